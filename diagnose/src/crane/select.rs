//! Selection: every candidate reported with whether it is supported, and the findings kept,
//! best score first and at most one per drive.

use super::baseline::BaselineScore;
use super::candidate::Cand;
use super::heldout::Scored;
use super::{Ext, AXIS_NAMES, FORCE_BIC_MAX, SUPPORT_RATIO};
use crate::{Candidate, Cause, Evidence, Finding};
use std::collections::BTreeMap;

/// The report's candidates and findings.
pub(super) struct Selection {
    /// The findings, best first.
    pub(super) findings: Vec<Finding>,
    /// Every candidate tried, in score order, then the causes not tried.
    pub(super) candidates: Vec<Candidate>,
}

/// Selects from `scored` (sorted by score, best first): a candidate is supported when its
/// score is below `ln(SUPPORT_RATIO)`, its force BIC below `FORCE_BIC_MAX` (stiction
/// excepted: stick-slip leaves too little in the force residual), it is not a direction
/// asymmetry that an offset on the same drive matches or beats by force BIC, and it cuts its
/// own drive's held-out NMAE (the payload mass excepted); a supported candidate
/// becomes a finding unless a better one has taken one of its drives. The causes in
/// `not_identifiable` (drive, cause) are listed last, unsupported.
pub(super) fn select(
    scored: &[Scored],
    base: &BaselineScore,
    not_identifiable: Vec<(usize, Cause)>,
) -> Selection {
    let before_h = base.before_h;
    let supported = |fb: f64, s: f64, st: bool| -> bool {
        s < SUPPORT_RATIO.ln() && (st || fb < FORCE_BIC_MAX)
    };
    // Nested candidates: `force_offset` is `direction_asymmetry` restricted to opposite dry
    // shifts and no viscous change (exactly the same model while the bias stays below the dry
    // magnitudes), so their simulated errors differ only by noise; the held-out force BIC,
    // which charges the three extra parameters, decides between them.
    let offset_bic: [f64; 3] = std::array::from_fn(|i| {
        scored
            .iter()
            .filter(|sc| sc.cand.axis == i && matches!(sc.cand.ext, Ext::Offset(_)))
            .map(|sc| sc.force_bic)
            .fold(f64::INFINITY, f64::min)
    });
    let nested_loses = |c: &Cand, fb: f64| -> bool {
        matches!(c.ext, Ext::Asymmetry { .. }) && c.axis < 3 && offset_bic[c.axis] <= fb
    };
    let mut findings = Vec::new();
    let mut used = [false; 3];
    let mut candidates = Vec::new();
    for sc in scored {
        let (c, fb, s, after) = (&sc.cand, sc.force_bic, sc.score, &sc.after);
        let st = matches!(c.ext, Ext::Stiction { .. });
        // a finding on one drive must cut that drive's own held-out NMAE (a gain on the
        // coupled axes alone is not evidence for it)
        let own_cut = c.axis == 3 || after[c.axis] < before_h[c.axis];
        let ok = supported(fb, s, st) && !nested_loses(c, fb) && own_cut;
        let axis_name = if c.axis == 3 { "l" } else { AXIS_NAMES[c.axis] };
        candidates.push(Candidate {
            cause: c.ext.cause(),
            axis: axis_name.into(),
            parameters: c.ext.parameters(),
            score: s,
            force_delta_bic: fb,
            supported: ok,
        });
        let axes: Vec<usize> = if c.axis == 3 {
            vec![0, 1, 2]
        } else {
            vec![c.axis]
        };
        if !ok || axes.iter().any(|&i| used[i]) {
            continue;
        }
        for &i in &axes {
            used[i] = true;
        }
        findings.push(finding(sc, axis_name, base));
    }
    for (i, cause) in not_identifiable {
        candidates.push(Candidate {
            cause,
            axis: AXIS_NAMES[i].into(),
            parameters: BTreeMap::new(),
            score: 0.0,
            force_delta_bic: 0.0,
            supported: false,
        });
    }
    Selection {
        findings,
        candidates,
    }
}

/// Whether the extension is identifiable against the alternatives, and a note saying why
/// (empty when nothing needs saying). Forces in [N].
fn identifiability(ext: &Ext) -> (bool, String) {
    match *ext {
        Ext::Offset(b) => (
            true,
            format!(
                "a constant bias of {b:.3} N is exactly a shift of the dry magnitudes (dry_pos by {:.3} N, dry_neg by {:.3} N) while it stays below them; named force_offset against this fixed baseline because one parameter explains what direction_asymmetry needs two for",
                -b, b
            ),
        ),
        Ext::Asymmetry {
            dry_pos, dry_neg, ..
        } if (dry_pos + dry_neg).abs() < 0.2 * (dry_pos.abs() + dry_neg.abs()) => (
            false,
            "the dry shifts are nearly opposite: indistinguishable from a force_offset of the same size".into(),
        ),
        Ext::Payload(_) => (
            true,
            "payload mass changes the three drive rows together; reported on the rope, which carries its weight".into(),
        ),
        _ => (true, String::new()),
    }
}

/// The finding of a selected candidate, reported on `axis_name` (the payload mass on the
/// rope): its held-out NMAE [%] before and after, and the force evidence (RMS residuals [N]).
fn finding(sc: &Scored, axis_name: &str, base: &BaselineScore) -> Finding {
    let (c, fb, s, after) = (&sc.cand, sc.force_bic, sc.score, &sc.after);
    let (before_h, held_g, sse_b) = (base.before_h, &base.held_g, base.sse_b);
    let ai = if c.axis == 3 { 2 } else { c.axis };
    let n_h = held_g[ai].r.len();
    let (identifiable, note) = identifiability(&c.ext);
    Finding {
        cause: c.ext.cause(),
        axis: axis_name.into(),
        parameters: c.ext.parameters(),
        nmae_before: before_h[ai],
        nmae_after: after[ai],
        evidence: Evidence {
            force_delta_bic: fb,
            force_rms_before_n: (sse_b[ai] / n_h.max(1) as f64).sqrt(),
            force_rms_after_n: (c.sse_after[ai] / n_h.max(1) as f64).sqrt(),
            score: s,
            extra_parameters: c.ext.k(),
            held_out_samples: n_h,
            identifiable,
            note,
        },
    }
}
