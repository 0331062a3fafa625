//! The verdict: the first finding's cause, else `unexplained` or `none` by how many noise
//! floors the baseline's held-out error is.

use super::{SUPPORT_RATIO, UNEXPLAINED_FLOORS};
use crate::{Finding, Verdict};

/// The verdict and its reason, from the findings (best first), the baseline's held-out NMAE
/// per axis [%] and the noise floors [%].
pub(super) fn verdict(
    findings: &[Finding],
    before_h: &[f64; 3],
    floor: &[f64; 3],
) -> (Verdict, String) {
    let worst = (0..3)
        .map(|i| before_h[i] / floor[i])
        .fold(0.0_f64, f64::max);
    if let Some(f) = findings.first() {
        (
            Verdict::Found(f.cause),
            format!(
                "{} on {} cuts the held-out NMAE from {:.4} % to {:.4} %",
                f.cause, f.axis, f.nmae_before, f.nmae_after
            ),
        )
    } else if worst > UNEXPLAINED_FLOORS {
        (
            Verdict::Unexplained,
            format!("the held-out simulation error is {worst:.1} noise floors but no candidate cuts it by {:.0} %", 100.0 * (1.0 - SUPPORT_RATIO)),
        )
    } else {
        (
            Verdict::None,
            format!("the held-out simulation error is within {worst:.1} noise floors and no candidate is supported"),
        )
    }
}
