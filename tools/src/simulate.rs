//! `crane simulate`: a scenario file (TOML) to a CSV run and a plot (SVG beside the CSV, same
//! name with `.svg`: drive positions, velocities, voltages and mode bands).
//!
//! Scenario format (every field optional; the built-in default is the validation multisine of
//! `docs/MODEL.md` on the default crane with a 0.064 kg payload; an example file is
//! `examples/scenarios/step.toml`). Plausible ranges: `duration_s` in (0, 86400], `h` in
//! [1e-6, 0.1], at most 1e8 steps and 1e6 CSV rows, `payload_kg` in [1e-4, 100]:
//!
//! ```toml
//! duration_s = 20.0          # simulated time [s]
//! h = 0.001                  # model step [s]
//! sample_s = 0.002           # CSV sampling [s] (a multiple of h)
//! payload_kg = 0.064         # overrides the parameter file's payload
//! params = "params.toml"     # parameter file (as written by `crane identify`), relative to
//!                            # the scenario file; default: the built-in parameters
//! q0 = [0.25, 0.3, 0.35, 1.5707963267948966, 0.0]   # x, y, L [m], alpha, beta [rad]
//! qd0 = [0.0, 0.0, 0.0, 0.0, 0.0]
//! [[input]]                  # inputs are sums of these terms, per axis
//! axis = "x"                 # x, y or l
//! offset_v = 0.0             # constant part [V] (a step when start_s > 0)
//! amplitude_v = 2.0          # sine amplitude [V]
//! frequency_hz = 0.135
//! phase_rad = 0.0
//! start_s = 0.0              # the term acts on [start_s, stop_s)
//! stop_s = 1e9
//! ```
//!
//! The CSV is a crane run of the data format (`t,u_x,u_y,u_l,x,y,l,alpha,beta`) plus the
//! columns `mode_x, mode_y, mode_l` (-1, 0, 1), `friction_x, friction_y, friction_l` [N] and
//! `tension` [N] (friction and tension of the sample are those of the input of the step before
//! it); it loads back with `crane_ident::data`.

use anyhow::{bail, Context, Result};
use crane_ident::num::Num;
use crane_ident::params_file;
use crane_model::{Config, Crane, FrictionLaw, Mode, Params, State};
use crane_tools::output::{OutputError, Outputs};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// One input term.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Term {
    axis: String,
    #[serde(default)]
    offset_v: f64,
    #[serde(default)]
    amplitude_v: f64,
    #[serde(default)]
    frequency_hz: f64,
    #[serde(default)]
    phase_rad: f64,
    #[serde(default)]
    start_s: f64,
    #[serde(default = "far")]
    stop_s: f64,
}

fn far() -> f64 {
    1e9
}

/// A scenario.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct Scenario {
    duration_s: f64,
    h: f64,
    sample_s: f64,
    payload_kg: Option<f64>,
    params: Option<PathBuf>,
    q0: [f64; 5],
    qd0: [f64; 5],
    input: Vec<Term>,
}

impl Default for Scenario {
    /// The validation multisine of docs/MODEL.md (amplitudes chosen to move every axis).
    fn default() -> Self {
        let sines = |axis: &str, f: [f64; 4], a: f64| -> Vec<Term> {
            f.iter()
                .map(|&frequency_hz| Term {
                    axis: axis.into(),
                    offset_v: 0.0,
                    amplitude_v: a,
                    frequency_hz,
                    phase_rad: 0.0,
                    start_s: 0.0,
                    stop_s: far(),
                })
                .collect()
        };
        let mut input = sines("x", [0.135, 0.404, 0.673, 0.942], 1.5);
        input.extend(sines("y", [0.105, 0.314, 0.523, 0.942], 1.5));
        input.extend(sines("l", [0.135, 0.406, 0.219, 0.744], 0.5));
        Scenario {
            duration_s: 20.0,
            h: 1e-3,
            sample_s: 2e-3,
            payload_kg: Some(0.064),
            params: None,
            q0: [0.25, 0.3, 0.35, core::f64::consts::FRAC_PI_2, 0.0],
            qd0: [0.0; 5],
            input,
        }
    }
}

fn axis_index(name: &str) -> Option<usize> {
    match name {
        "x" => Some(0),
        "y" => Some(1),
        "l" => Some(2),
        _ => None,
    }
}

fn mode_code(m: Mode) -> i8 {
    match m {
        Mode::Negative => -1,
        Mode::Stopped => 0,
        Mode::Positive => 1,
    }
}

/// Plausible range of the model step `h` [s].
pub const H_RANGE: (f64, f64) = (1e-6, 0.1);
/// Longest simulated time [s] of a scenario (one day).
pub const MAX_DURATION_S: f64 = 86_400.0;
/// Most model steps of one scenario (`duration_s / h`): about a minute of work.
pub const MAX_STEPS: f64 = 1e8;
/// Most CSV samples of one scenario (`duration_s / sample_s`; about 200 MB of CSV).
pub const MAX_SAMPLES: f64 = 1e6;
/// Plausible range of `payload_kg` [kg].
pub const PAYLOAD_RANGE_KG: (f64, f64) = (1e-4, 100.0);
/// Largest initial rate `|qd0[i]|` [m/s or rad/s].
pub const MAX_RATE: f64 = 100.0;
/// Largest `|offset_v|`, `|amplitude_v|` of an input term [V] (the inputs saturate at 12 V).
pub const MAX_VOLTS: f64 = 1000.0;
/// Highest `frequency_hz` of an input term [Hz].
pub const MAX_FREQUENCY_HZ: f64 = 1e4;

/// What `crane simulate` wrote.
#[derive(Clone, Debug, Serialize)]
pub struct SimulateSummary {
    /// The CSV run.
    pub csv: PathBuf,
    /// Its plot.
    pub svg: PathBuf,
    /// Samples (rows) written.
    pub samples: usize,
}

/// Checks the scenario's numbers against their plausible ranges, before any work; errors
/// name the scenario (`label`: its file) and the key.
fn check_ranges(sc: &Scenario, label: &str) -> Result<()> {
    let d = sc.duration_s;
    if !(d.is_finite() && d > 0.0 && d <= MAX_DURATION_S) {
        bail!(
            "{label}: duration_s = {} is outside the plausible range (0, {MAX_DURATION_S}] s",
            Num(d)
        );
    }
    let (lo, hi) = H_RANGE;
    if !(sc.h.is_finite() && sc.h >= lo && sc.h <= hi) {
        bail!(
            "{label}: h = {} is outside the plausible range [{lo:e}, {hi}] s",
            Num(sc.h)
        );
    }
    if !(sc.sample_s.is_finite() && sc.sample_s > 0.0) {
        bail!("{label}: sample_s = {} must be > 0", Num(sc.sample_s));
    }
    let steps = d / sc.h;
    if steps > MAX_STEPS {
        bail!("{label}: duration_s / h = {steps:.3e} steps; at most {MAX_STEPS:e} (shorten duration_s or raise h)");
    }
    let samples = d / sc.sample_s;
    if samples > MAX_SAMPLES {
        bail!("{label}: duration_s / sample_s = {samples:.3e} CSV rows; at most {MAX_SAMPLES:e} (shorten duration_s or raise sample_s)");
    }
    for (i, v) in sc.qd0.iter().enumerate() {
        if !(v.is_finite() && v.abs() <= MAX_RATE) {
            bail!(
                "{label}: qd0[{i}] = {} is outside the plausible range [-{MAX_RATE}, {MAX_RATE}]",
                Num(*v)
            );
        }
    }
    for (k, t) in sc.input.iter().enumerate() {
        for (name, v, max) in [
            ("offset_v", t.offset_v, MAX_VOLTS),
            ("amplitude_v", t.amplitude_v, MAX_VOLTS),
            ("frequency_hz", t.frequency_hz, MAX_FREQUENCY_HZ),
        ] {
            if !(v.is_finite() && v.abs() <= max) {
                bail!(
                    "{label}: input[{k}].{name} = {} is outside the plausible range [-{max}, {max}]",
                    Num(v)
                );
            }
        }
    }
    if let Some(m) = sc.payload_kg {
        let (lo, hi) = PAYLOAD_RANGE_KG;
        if !(m.is_finite() && m >= lo && m <= hi) {
            bail!(
                "{label}: payload_kg = {} is outside the plausible range [{lo:e}, {hi}] kg",
                Num(m)
            );
        }
    }
    Ok(())
}

/// The model failed on a step of the scenario.
#[derive(Debug)]
struct StepFailed {
    /// Time of the step [s].
    t: f64,
    /// The model's message.
    error: String,
}

impl std::fmt::Display for StepFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "at t = {} s: {}", Num(self.t), self.error)
    }
}

impl std::error::Error for StepFailed {}

/// What the messages of a simulation call the scenario and its parameters.
struct Names {
    /// The scenario file, or "the built-in scenario".
    scenario: String,
    /// The parameter file, or "the built-in parameters".
    params: String,
}

/// The model's refusal of the scenario's first state or of its parameters, said in the
/// scenario's own keys (`q0[i]`, `qd0[i]`, `h`) or the parameter file's, with the file.
fn setup_error(e: &crane_model::Error, names: &Names, p: &Params) -> anyhow::Error {
    let axis = e
        .field
        .strip_prefix("state.q[")
        .and_then(|r| r.strip_suffix(']'))
        .and_then(|i| i.parse::<usize>().ok());
    if let (Some(i), crane_model::Problem::OutOfLimits) = (axis, e.problem) {
        if let Some((name, a)) = ["x", "y", "rope"].iter().zip(p.axes()).nth(i) {
            return anyhow::anyhow!(
                "{}: q0[{i}] = {} is outside the travel [{name}.min, {name}.max] = [{}, {}] of {}",
                names.scenario,
                Num(e.value),
                Num(a.min),
                Num(a.max),
                names.params
            );
        }
    }
    let text = e.to_string();
    if e.field.starts_with("state.") || e.field.starts_with("config.") {
        let text = text
            .replace("`state.qd[", "`qd0[")
            .replace("`state.q[", "`q0[")
            .replace("`config.h`", "`h`");
        return anyhow::anyhow!("{}: {text}", names.scenario);
    }
    anyhow::anyhow!("{}: {text}", names.params)
}

/// A hint for a step the model rejected: the axis whose `h * viscous / inertia` is largest,
/// when it is above 1 (the drive's own time constant shorter than the step: too stiff for
/// `h`).
fn stiffness_hint(p: &Params, h: f64) -> String {
    let worst = ["x", "y", "rope"]
        .iter()
        .zip(p.axes())
        .map(|(name, a)| (name, h * a.viscous_pos.max(a.viscous_neg) / a.inertia))
        .filter(|(_, r)| r.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1));
    match worst {
        Some((name, r)) if r > 1.0 => format!(
            " (too stiff for h: h * {name}.viscous / {name}.inertia = {}, above 1; lower h or \
             check {name}.viscous_pos, {name}.viscous_neg and {name}.inertia)",
            Num(r)
        ),
        _ => " (check the parameters, or lower h)".into(),
    }
}

/// The plot written beside a CSV: same path with the extension `svg`.
pub fn plot_path(csv: &Path) -> PathBuf {
    csv.with_extension("svg")
}

/// Runs a scenario file (or the default) and writes the CSV and its plot ([`plot_path`]),
/// atomically and together at the end, or neither (a failed plot leaves the earlier CSV as
/// it was); neither may replace the scenario, its parameter file or a data set's file unless
/// `force`.
pub fn simulate(
    scenario: Option<&Path>,
    out: &Path,
    force: bool,
    json: bool,
) -> Result<SimulateSummary> {
    let svg = plot_path(out);
    if svg == out {
        return Err(OutputError::Clash {
            out: out.to_path_buf(),
            why: "the plot goes beside the CSV with the extension .svg; the CSV cannot be named .svg (use --out NAME.csv)",
        }
        .into());
    }
    let label = scenario.map_or_else(
        || "the built-in scenario".to_string(),
        |p| p.display().to_string(),
    );
    let (sc, base) = match scenario {
        Some(p) => {
            let text = crane_ident::input::read_text(p)
                .with_context(|| format!("read {}", p.display()))?;
            let sc: Scenario =
                toml::from_str(&text).with_context(|| format!("scenario {}", p.display()))?;
            (sc, p.parent().map(Path::to_path_buf).unwrap_or_default())
        }
        None => (Scenario::default(), PathBuf::new()),
    };
    check_ranges(&sc, &label)?;
    let mut outputs = Outputs::new(force);
    if let Some(p) = scenario {
        outputs = outputs.input(p);
    }
    if let Some(p) = &sc.params {
        outputs = outputs.input(&base.join(p));
    }
    outputs.check(out)?;
    outputs.check(&svg)?;
    let (mut params, params_label) = match &sc.params {
        Some(p) => {
            let path = base.join(p);
            let read = params_file::read(&path).with_context(|| format!("{label}: params"))?;
            (read, path.display().to_string())
        }
        None => (Params::default(), "the built-in parameters".to_string()),
    };
    let names = Names {
        scenario: label.clone(),
        params: params_label,
    };
    if let Some(m) = sc.payload_kg {
        params.payload_mass = m;
    }
    let mut terms = Vec::new();
    for (k, t) in sc.input.iter().enumerate() {
        let Some(i) = axis_index(&t.axis) else {
            bail!(
                "{label}: input[{k}].axis = {:?}: expected \"x\", \"y\" or \"l\"",
                t.axis
            );
        };
        for (name, v) in [
            ("offset_v", t.offset_v),
            ("amplitude_v", t.amplitude_v),
            ("frequency_hz", t.frequency_hz),
            ("phase_rad", t.phase_rad),
            ("start_s", t.start_s),
            ("stop_s", t.stop_s),
        ] {
            if !v.is_finite() {
                bail!("{label}: input[{k}].{name} is not finite");
            }
        }
        terms.push((i, t.clone()));
    }
    let per = (sc.sample_s / sc.h).round();
    if !(per >= 1.0 && (per * sc.h - sc.sample_s).abs() <= 1e-9 * sc.sample_s.abs()) {
        bail!(
            "{label}: sample_s ({}) must be a whole multiple of h ({})",
            Num(sc.sample_s),
            Num(sc.h)
        );
    }
    let per = per as usize;
    let config = Config {
        h: sc.h,
        law: FrictionLaw::Hybrid,
    };
    let mut crane: Crane = Crane::new(
        &params,
        config,
        State {
            q: sc.q0,
            qd: sc.qd0,
        },
    )
    .map_err(|e| setup_error(&e, &names, &params))?;
    let mut w = outputs.create(out)?;
    let (samples, rec) = record(&sc, &terms, per, &mut crane, &mut w, out).map_err(|e| {
        match e.downcast::<StepFailed>() {
            Ok(step) => anyhow::anyhow!(
                "{}: the simulation with {} failed: {step}{}",
                names.scenario,
                names.params,
                stiffness_hint(&params, sc.h)
            ),
            Err(e) => e,
        }
    })?;
    outputs.stage_file(w)?;
    crate::plot::simulation(&rec, &svg, &mut outputs)?;
    // the CSV and its plot together, or neither
    outputs.commit()?;
    if !json {
        out!(
            "simulate: {samples} samples -> {}, plot {}",
            out.display(),
            svg.display()
        );
    }
    Ok(SimulateSummary {
        csv: out.to_path_buf(),
        svg,
        samples,
    })
}

/// Steps the scenario's inputs through `crane` to `duration_s`, writing every `per`-th state
/// to `w` (the CSV `out`, for messages) and recording it for the plot; returns the rows
/// written and the record.
fn record(
    sc: &Scenario,
    terms: &[(usize, Term)],
    per: usize,
    crane: &mut Crane,
    w: &mut impl Write,
    out: &Path,
) -> Result<(usize, crate::plot::SimulationRecord)> {
    let wrote = || format!("write {}", out.display());
    writeln!(w, "# crane simulate: hybrid model, h = {} s", sc.h).with_context(wrote)?;
    writeln!(
        w,
        "t,u_x,u_y,u_l,x,y,l,alpha,beta,mode_x,mode_y,mode_l,friction_x,friction_y,friction_l,tension"
    )
    .with_context(wrote)?;
    let steps = (sc.duration_s / sc.h).round() as usize;
    let mut samples = 0;
    let mut rec = crate::plot::SimulationRecord::default();
    for k in 0..=steps {
        let t = k as f64 * sc.h;
        let mut u = [0.0; 3];
        for (i, term) in terms {
            if t >= term.start_s && t < term.stop_s {
                let arg = 2.0 * std::f64::consts::PI * term.frequency_hz * (t - term.start_s)
                    + term.phase_rad;
                u[*i] += term.offset_v + term.amplitude_v * libm::sin(arg);
            }
        }
        let u = u.map(|v| v.clamp(-crane_model::U_MAX, crane_model::U_MAX));
        if k % per == 0 {
            let s = crane.state();
            let m = crane.modes().map(mode_code);
            let o = crane.output().map_err(|e| StepFailed {
                t,
                error: e.to_string(),
            })?;
            writeln!(
                w,
                "{t},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                u[0],
                u[1],
                u[2],
                s.q[0],
                s.q[1],
                s.q[2],
                s.q[3],
                s.q[4],
                m[0],
                m[1],
                m[2],
                o.friction[0],
                o.friction[1],
                o.friction[2],
                o.tension
            )
            .with_context(wrote)?;
            samples += 1;
            rec.t.push(t);
            rec.u.push(u);
            rec.q.push([s.q[0], s.q[1], s.q[2]]);
            rec.qd.push([s.qd[0], s.qd[1], s.qd[2]]);
            rec.modes.push(crane.modes());
        }
        if k < steps {
            crane.step(u).map_err(|e| StepFailed {
                t,
                error: e.to_string(),
            })?;
        }
    }
    Ok((samples, rec))
}
