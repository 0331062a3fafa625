//! The report as the few lines a person reads first (the `crane diagnose` output).

use crate::report::nmae_or_diverged::text as pct;
use crate::Report;
use std::fmt::Write;

impl Report {
    /// Verdict, findings, and the measures present: held-out simulation and final model
    /// (single-axis open-loop data), inverse-model and closed-loop force errors with the
    /// published figures (EMPS only).
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "verdict: {} ({})", self.verdict, self.verdict_reason);
        for f in &self.findings {
            let _ = writeln!(
                s,
                "  {} on {}: held-out NMAE {} -> {}, parameters {}",
                f.cause,
                f.axis,
                pct(f.nmae_before, 3),
                pct(f.nmae_after, 3),
                serde_json::to_string(&f.parameters).unwrap_or_default()
            );
        }
        if let Some(h) = self
            .heldout_simulation
            .as_ref()
            .filter(|h| !h.runs.is_empty() && h.runs.iter().all(|r| !r.moves))
        {
            let _ = writeln!(
                s,
                "held-out runs simulated from the recorded input: the axis moves in none of them ({}), so none tests the motion (every model that sticks predicts a resting run)",
                h.runs.iter().map(|r| r.file.as_str()).collect::<Vec<_>>().join(", ")
            );
        } else if let Some(h) = &self.heldout_simulation {
            let _ = writeln!(
                s,
                "held-out runs simulated from the recorded input, position NMAE: baseline {}, final model {}, no motion {:.2} % (runs that move: {} / {} / {:.2} %)",
                pct(h.nmae_before, 2),
                pct(h.nmae_after, 2),
                h.nmae_no_motion,
                pct(h.moving_nmae_before, 2),
                pct(h.moving_nmae_after, 2),
                h.moving_nmae_no_motion
            );
            for r in &h.runs {
                if !r.moves {
                    // a resting run is predicted by every model that sticks: no figure
                    let _ = writeln!(
                        s,
                        "  {}: at rest (the axis never moves: it tests only that a model sticks, not the motion)",
                        r.file
                    );
                    continue;
                }
                let _ = writeln!(
                    s,
                    "  {}: {} -> {} (no motion {:.2} %)",
                    r.file,
                    pct(r.nmae_before, 2),
                    pct(r.nmae_after, 2),
                    r.nmae_no_motion
                );
            }
        }
        if let Some(m) = &self.final_model {
            let (pu, fu) = (&m.position_unit, &m.force_unit);
            let _ = writeln!(
                s,
                "final model: inertia {:.4}, breakaway +{:.4} / -{:.4} {fu}, kinetic +{:.4} / -{:.4} {fu}, viscous +{:.4} / -{:.4} {fu} s/{pu}, stiffness {:.4} {fu}/{pu}, offset {:.4} {fu}",
                m.inertia,
                m.breakaway_pos,
                m.breakaway_neg,
                m.kinetic_pos,
                m.kinetic_neg,
                m.viscous_pos,
                m.viscous_neg,
                m.stiffness,
                m.offset
            );
            for f in &m.flags {
                let _ = writeln!(s, "  note: {f}");
            }
        }
        let m = &self.measures;
        let published = m.contains_key("published_direction_dependent_fit_pct");
        if let (Some(b), Some(h)) = (
            m.get("force_rel_err_fit_pct"),
            m.get("force_rel_err_held_out_pct"),
        ) {
            let _ = write!(
                s,
                "relative force error, inverse model (fitting / held-out): baseline {b:.2} % / {h:.2} %"
            );
            if published {
                let _ = write!(s, " (published symmetric with offset: 4.08 % / 5.98 %)");
            }
            let _ = writeln!(s);
            if let (Some(a), Some(c)) = (
                m.get("force_rel_err_fit_after_pct"),
                m.get("force_rel_err_held_out_after_pct"),
            ) {
                let _ = write!(s, "  extended {a:.2} % / {c:.2} %");
                if published {
                    let _ = write!(s, " (published direction-dependent fit: 3.11 %)");
                }
                let _ = writeln!(s);
            }
        }
        for (name, label) in [
            ("symmetric", "symmetric"),
            ("direction_dependent", "direction-dependent"),
        ] {
            if let (Some(f), Some(h)) = (
                m.get(&format!("closed_loop_force_err_fit_{name}_pct")),
                m.get(&format!("closed_loop_force_err_held_out_{name}_pct")),
            ) {
                let _ = write!(
                    s,
                    "closed-loop simulated force error (fitting / held-out), {label}: {f:.2} % / {h:.2} %"
                );
                if published {
                    let _ = write!(s, " (published symmetric: 5.85 % / 8.94 %)");
                }
                let _ = writeln!(s);
            }
        }
        s
    }
}
