//! Stage 3 of a closed-loop diagnosis: the candidate extensions searched, in their order
//! (the causes' searches live in `friction` and `input`).

use super::baseline::BaselineFit;
use super::candidates::Candidates;
use super::prepare::Prepared;
use super::{friction, input};
use crate::Cause;

/// Stage 3: localized friction, stiction, direction asymmetry (symmetric baseline only),
/// input delay and input dead band, in this order; the payload mass is never fitted here.
pub(super) fn search(prep: &Prepared, base: &BaselineFit) -> Candidates {
    let mut out = Candidates::default();
    friction::localized_friction(prep, base, &mut out);
    friction::stiction(prep, base, &mut out);
    friction::direction_asymmetry(prep, base, &mut out);
    input::input_delay(prep, base, &mut out);
    input::input_deadzone(prep, base, &mut out);
    out.not_ident.push(Cause::PayloadMass);
    out
}
