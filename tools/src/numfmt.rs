//! Numbers in the study's and work-precision tables.

/// Compact number: 4 significant digits, scientific when small or large.
pub fn fmt_g(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if !(1e-3..1e4).contains(&v.abs()) {
        format!("{v:.3e}")
    } else {
        let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.digits$}")
    }
}
