use crane_tools::{adaptive_run, cases::Case, reference};
fn main() {
    for case in Case::all() {
        let t0 = std::time::Instant::now();
        let refr = reference::reference(&case, 1e-3, 100).unwrap();
        eprintln!("ref {:?}", t0.elapsed());
        for h in [1e-3, 1e-2] {
            let tr = reference::hybrid(&case, h, false).unwrap();
            println!(
                "{} fixed h {h}: rmse {:.3e}",
                case.name,
                reference::rmse(&case, &tr, &refr)
            );
        }
        for rtol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10] {
            let tol = adaptive_run::tolerances(&case, rtol);
            let t0 = std::time::Instant::now();
            let (tr, st) = adaptive_run::hybrid_adaptive(&case, &tol).unwrap();
            let el = t0.elapsed();
            println!(
                "{} rtol {rtol:e}: rmse {:.3e} steps {} rej {} evals {} events {} time {:?}",
                case.name,
                reference::rmse(&case, &tr, &refr),
                st.accepted,
                st.rejected,
                st.evals,
                st.events,
                el
            );
        }
    }
}
