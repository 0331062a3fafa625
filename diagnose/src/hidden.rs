//! Hidden effects for the tests: a virtual rig (the crane model, as `crane-ident` records it)
//! with one seeded random effect among the candidate causes, at a random axis, size and
//! place within realistic ranges.

use crate::crane::Ext;
use crane_ident::data::{Dataset, DatasetSpec, Run, RunKind, Samples};
use crane_ident::rig::{signals, Effect, Experiment, Input, PlantConfig, Rig, VirtualRig};
use crane_ident::rng::Rng;
use crane_model::{Direction, Extensions, Params};

/// Declared payload of the generated runs [kg].
pub const PAYLOAD_KG: f64 = 0.457;

/// A hidden effect: `None` is clean data.
#[derive(Clone, Debug, PartialEq)]
pub struct Hidden {
    /// Drive (0 X, 1 Y, 2 rope).
    pub axis: usize,
    /// The effect, in the workbench's own terms.
    pub ext: Option<Ext>,
}

impl Hidden {
    /// Cause name (`none` for clean data).
    pub fn cause(&self) -> &'static str {
        self.ext
            .as_ref()
            .map(|e| e.cause().as_str())
            .unwrap_or("none")
    }
    /// Axis name as reported (`l` for the payload mass).
    pub fn axis_name(&self) -> &'static str {
        crate::crane::AXIS_NAMES[self.axis]
    }
}

struct HiddenEffect(Hidden);

impl Effect for HiddenEffect {
    fn plant(&self, _kind: RunKind, params: &mut Params, ext: &mut Extensions) {
        if let Some(e) = &self.0.ext {
            e.apply(self.0.axis, params, ext);
        }
    }
}

/// Draws a hidden effect of `cause` (the name of one of [`crate::crane::CRANE_CAUSES`], or `none`) from `seed`.
pub fn draw(cause: &str, seed: u64) -> Hidden {
    let mut rng = Rng::new(seed ^ 0x9e37_79b9_7f4a_7c15);
    let sign = |rng: &mut Rng| if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    let mut axis = (rng.uniform() * 3.0).floor().min(2.0) as usize;
    // rope forces are about 7 times those of X and Y (its dry friction is 8.6 N)
    let scale = if axis == 2 { 7.0 } else { 1.0 };
    let ext = match cause {
        "localized_friction" => {
            let (lo, hi) = [(0.18, 0.32), (0.23, 0.37), (0.31, 0.39)][axis];
            let amp = if rng.uniform() < 0.7 {
                rng.range(0.6, 1.5)
            } else {
                -rng.range(0.4, 0.8)
            };
            let direction = match (rng.uniform() * 4.0) as usize {
                0 => Direction::Positive,
                1 => Direction::Negative,
                _ => Direction::Both,
            };
            Some(Ext::Bump {
                center: rng.range(lo, hi),
                width: rng.range(0.015, 0.04) * if axis == 2 { 0.5 } else { 1.0 },
                amplitude: amp * scale,
                direction,
            })
        }
        "stiction" => Some(Ext::Stiction {
            ratio: rng.range(1.6, 3.0),
            velocity: rng.range(0.005, 0.02) * if axis == 2 { 0.3 } else { 1.0 },
        }),
        "direction_asymmetry" => {
            let d = rng.range(0.4, 1.0) * scale;
            let dv = rng.range(20.0, 40.0) * scale;
            Some(if rng.uniform() < 0.5 {
                Ext::Asymmetry {
                    dry_pos: d,
                    dry_neg: 0.0,
                    viscous_pos: dv,
                    viscous_neg: 0.0,
                }
            } else {
                Ext::Asymmetry {
                    dry_pos: 0.0,
                    dry_neg: d,
                    viscous_pos: 0.0,
                    viscous_neg: dv,
                }
            })
        }
        "force_offset" => Some(Ext::Offset(sign(&mut rng) * rng.range(0.4, 1.0) * scale)),
        "input_deadzone" => Some(Ext::Deadzone(rng.range(0.2, 0.6))),
        "input_delay" => Some(Ext::Delay(rng.range(4.0, 40.0).round() * 1e-3)),
        "payload_mass" => {
            axis = 2;
            let f = if rng.uniform() < 0.5 {
                rng.range(0.4, 0.7)
            } else {
                rng.range(1.5, 2.2)
            };
            Some(Ext::Payload(PAYLOAD_KG * (f - 1.0)))
        }
        _ => None,
    };
    Hidden { axis, ext }
}

/// Centring feedback gains of the generated runs (X, Y, rope) [V/m].
pub const GAIN: [f64; 3] = [15.0, 15.0, 40.0];
/// Amplitude of the reference sweep of the generated runs (X, Y, rope) [m]: with the
/// feedback's lag the drives then cross the whole stretch where a hidden bump may sit.
pub const SWEEP_M: [f64; 3] = [0.15, 0.15, 0.08];

/// Records `runs` runs of `seconds` each on the virtual rig with the hidden effect: steps of
/// random level and duration on every drive, with a weak feedback towards a reference that
/// sweeps each drive's stretch once per run.
pub fn dataset(hidden: &Hidden, seed: u64, runs: usize, seconds: f64) -> Result<Dataset, String> {
    let cfg = PlantConfig {
        seed,
        ..PlantConfig::default()
    };
    let dt = cfg.sample_time;
    let mut rig =
        VirtualRig::new(Params::default(), cfg).with_effect(Box::new(HiddenEffect(hidden.clone())));
    let mut rng = Rng::new(seed.wrapping_mul(7919).wrapping_add(13));
    let n = (seconds / dt).round() as usize;
    let mut out = Vec::new();
    for r in 0..runs {
        let parts: Vec<Vec<[f64; 3]>> = (0..3)
            .map(|a| {
                let lv = if a == 2 { (1.5, 5.0) } else { (0.8, 4.0) };
                signals::multistep(&mut rng, n, dt, a, lv, (0.3, 1.0))
            })
            .collect();
        let center = [0.25, 0.30, 0.35];
        // the reference sweeps the stretch where effects may sit, once per run and in both
        // directions (the feedback towards a moving reference `center + sweep(t)` is the
        // fixed-centre feedback plus `gain * sweep(t)`, added to the signal)
        let phase = rng.range(0.0, std::f64::consts::TAU);
        let signal: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let w = (std::f64::consts::TAU * k as f64 / n as f64 + phase).sin();
                std::array::from_fn(|a| parts[a][k][a] + GAIN[a] * SWEEP_M[a] * w)
            })
            .collect();
        let exp = Experiment {
            name: format!("run{r}"),
            kind: RunKind::Other,
            payload_kg: PAYLOAD_KG,
            init: [
                center[0],
                center[1],
                center[2],
                std::f64::consts::FRAC_PI_2,
                0.0,
            ],
            input: Input::Centred {
                signal,
                center,
                gain: GAIN,
            },
        };
        let rec = rig.run(&exp).map_err(|e| e.to_string())?;
        out.push(Run {
            name: exp.name.clone(),
            kind: RunKind::Other,
            payload_kg: PAYLOAD_KG,
            samples: Samples::Crane(rec),
        });
    }
    Ok(Dataset {
        dir: "virtual-rig".into(),
        spec: DatasetSpec::minimal(PAYLOAD_KG),
        runs: out,
    })
}
