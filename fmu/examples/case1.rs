//! Case 1 of the paper's study (`crane_tools::cases::Case::one`, 30 s, h = 1 ms) run natively
//! with the model, for the FMU timing comparison (`fmu/tests/bench_case1.py`).
//!
//! Prints one JSON object: `start_values` (every FMU parameter of the case, by FMU variable
//! name), `native_s` (fastest of 5 runs of the whole case including storing every 1 ms sample
//! of `q` and `qd`), and `final` (the final `q`, `qd` as f64 bit patterns in hex).
//!
//! `cargo run --release -p crane-fmu --example case1`

use crane_fmu::variables::params;
use crane_model::{Config, Crane, State};
use crane_tools::cases::Case;
use std::time::Instant;

fn run(case: &Case) -> (Vec<State>, f64) {
    let start = Instant::now();
    let mut crane: Crane = Crane::new(&case.params, Config::default(), case.init).unwrap();
    let n = (case.duration / 1e-3).round() as usize;
    let mut out = Vec::with_capacity(n + 1);
    out.push(crane.state());
    for _ in 0..n {
        crane.step([0.0; 3]).unwrap();
        out.push(crane.state());
    }
    (out, start.elapsed().as_secs_f64())
}

fn main() {
    let case = Case::one();
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..5 {
        let (states, t) = run(&case);
        best = best.min(t);
        last = states.last().copied();
    }
    let s = last.unwrap();
    let mut values: Vec<String> = params()
        .map(|f| format!("\"{}\": {:?}", f.name, (f.get)(&case.params)))
        .collect();
    for i in 0..5 {
        values.push(format!("\"state.q[{i}]\": {:?}", case.init.q[i]));
        values.push(format!("\"state.qd[{i}]\": {:?}", case.init.qd[i]));
    }
    let hex: Vec<String> =
        s.q.iter()
            .chain(&s.qd)
            .map(|v| format!("\"{:016x}\"", v.to_bits()))
            .collect();
    println!(
        "{{\"start_values\": {{{}}}, \"duration\": {:?}, \"native_s\": {best:e}, \"final\": [{}]}}",
        values.join(", "),
        case.duration,
        hex.join(", ")
    );
}
