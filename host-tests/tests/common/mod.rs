//! Helpers shared by the integration tests: building the model and the reference from the
//! same inputs, mapping modes, input programs, the host's seeded generator.
#![allow(dead_code, clippy::needless_range_loop)]

use crane_model::{Config, Crane, Extensions, FrictionLaw, Mode, Params, State};
use host_tests::reference::{RefCrane, RefExtensions, RefLaw, RefMode, RefParams};

pub const FRAC_PI_2: f64 = core::f64::consts::FRAC_PI_2;

/// The model's mode as the reference's.
pub fn ref_mode(m: Mode) -> RefMode {
    match m {
        Mode::Negative => RefMode::Negative,
        Mode::Stopped => RefMode::Stopped,
        Mode::Positive => RefMode::Positive,
    }
}

/// The model's law as the reference's.
pub fn ref_law(l: FrictionLaw) -> RefLaw {
    match l {
        FrictionLaw::Hybrid => RefLaw::Hybrid,
        FrictionLaw::Tanh { gamma } => RefLaw::Tanh { gamma },
    }
}

/// Builds the model and the reference from the same parameters and initial state.
pub fn pair(
    p: &Params,
    h: f64,
    law: FrictionLaw,
    q: [f64; 5],
    qd: [f64; 5],
) -> (Crane<f64>, RefCrane) {
    let model: Crane<f64> = Crane::new(p, Config { h, law }, State { q, qd }).expect("model new");
    let reference = RefCrane::new(RefParams::from(p), h, ref_law(law), q, qd).expect("ref new");
    (model, reference)
}

/// Builds the model (`Crane::new(..)?.with_extensions(ext)?`) and the reference with the
/// same extensions.
pub fn pair_ext(
    p: &Params,
    h: f64,
    law: FrictionLaw,
    q: [f64; 5],
    qd: [f64; 5],
    ext: &Extensions,
) -> (Crane<f64>, RefCrane) {
    let model = Crane::<f64>::new(p, Config { h, law }, State { q, qd })
        .and_then(|c| c.with_extensions(ext))
        .expect("model new + extensions");
    let reference = RefCrane::new(RefParams::from(p), h, ref_law(law), q, qd)
        .and_then(|r| r.with_extensions(&RefExtensions::from(ext)))
        .expect("ref new + extensions");
    (model, reference)
}

/// Builds only the model (panics on a rejected configuration).
pub fn model(p: &Params, h: f64, law: FrictionLaw, q: [f64; 5], qd: [f64; 5]) -> Crane<f64> {
    Crane::new(p, Config { h, law }, State { q, qd }).expect("model new")
}

/// `None` when model and reference agree to the bit on q, qd, modes and time; otherwise a
/// description of the first differing component.
pub fn compare(step: usize, m: &Crane<f64>, r: &RefCrane) -> Option<String> {
    let s = m.state();
    let names = ["x", "y", "L", "alpha", "beta"];
    for j in 0..5 {
        if s.q[j].to_bits() != r.q()[j].to_bits() {
            return Some(format!(
                "step {step}: q[{j}] ({}) model {:e} ({:#018x}) vs reference {:e} ({:#018x})",
                names[j],
                s.q[j],
                s.q[j].to_bits(),
                r.q()[j],
                r.q()[j].to_bits()
            ));
        }
        if s.qd[j].to_bits() != r.qd()[j].to_bits() {
            return Some(format!(
                "step {step}: qd[{j}] ({}) model {:e} ({:#018x}) vs reference {:e} ({:#018x})",
                names[j],
                s.qd[j],
                s.qd[j].to_bits(),
                r.qd()[j],
                r.qd()[j].to_bits()
            ));
        }
    }
    let mm = m.modes().map(ref_mode);
    if mm != r.modes() {
        return Some(format!(
            "step {step}: modes model {mm:?} vs reference {:?}",
            r.modes()
        ));
    }
    if m.time().to_bits() != r.time().to_bits() {
        return Some(format!(
            "step {step}: time model {:e} vs reference {:e}",
            m.time(),
            r.time()
        ));
    }
    None
}

/// Bitwise comparison of the two `output()`s.
pub fn compare_output(step: usize, m: &Crane<f64>, r: &RefCrane) -> Option<String> {
    let (mo, ro) = match (m.output(), r.output()) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(_), Err(_)) => return None,
        (a, b) => {
            return Some(format!(
                "step {step}: output() model {a:?} vs reference {b:?}"
            ))
        }
    };
    let mut pairs: Vec<(String, f64, f64)> = Vec::new();
    for j in 0..5 {
        pairs.push((format!("qdd[{j}]"), mo.qdd[j], ro.qdd[j]));
    }
    for j in 0..3 {
        pairs.push((format!("friction[{j}]"), mo.friction[j], ro.friction[j]));
        pairs.push((format!("payload[{j}]"), mo.payload[j], ro.payload[j]));
    }
    pairs.push(("tension".into(), mo.tension, ro.tension));
    for (name, a, b) in pairs {
        if a.to_bits() != b.to_bits() {
            return Some(format!(
                "step {step}: output {name} model {a:e} vs reference {b:e}"
            ));
        }
    }
    None
}

/// The host's one seeded generator, for long random input sequences.
pub use crane_ident::rng::Rng;

/// One piece of an input program for one axis [V]. Saturation happens in the model.
#[derive(Clone, Debug)]
pub enum Piece {
    /// Constant voltage.
    Hold(f64),
    /// Linear ramp from `.0` to `.1` over the piece.
    Ramp(f64, f64),
    /// Sum of sines: (amplitude V, frequency Hz, phase rad), the rig's validation input kind.
    Multisine([(f64, f64, f64); 4]),
    /// Square wave between `+a` and `-a` (|a| up to 20 V: saturates), period in seconds.
    Square(f64, f64),
}

/// A piecewise input program: pieces of `len` steps, cycled.
#[derive(Clone, Debug)]
pub struct Program {
    pub pieces: Vec<(Piece, usize)>,
}

impl Program {
    /// Input at step `k` with step size `h` [V].
    pub fn at(&self, k: usize, h: f64) -> f64 {
        let total: usize = self.pieces.iter().map(|p| p.1).sum();
        let mut k = k % total.max(1);
        for (piece, len) in &self.pieces {
            if k < *len {
                let t = k as f64 * h;
                let frac = k as f64 / *len as f64;
                return match piece {
                    Piece::Hold(v) => *v,
                    Piece::Ramp(a, b) => a + (b - a) * frac,
                    Piece::Multisine(c) => c
                        .iter()
                        .map(|(a, f, ph)| a * (2.0 * core::f64::consts::PI * f * t + ph).sin())
                        .sum(),
                    Piece::Square(a, period) => {
                        if (t / period).fract() < 0.5 {
                            *a
                        } else {
                            -*a
                        }
                    }
                };
            }
            k -= len;
        }
        0.0
    }
}

/// A random program from a seed (used by the long physics runs).
pub fn random_program(rng: &mut Rng, sat: f64) -> Program {
    let n = 3 + rng.below(6) as usize;
    let mut pieces = Vec::new();
    for _ in 0..n {
        let len = 200 + rng.below(3000) as usize;
        let piece = match rng.below(4) {
            0 => Piece::Hold(rng.range(-sat, sat)),
            1 => Piece::Ramp(rng.range(-sat, sat), rng.range(-sat, sat)),
            2 => {
                let mut c = [(0.0, 0.0, 0.0); 4];
                for ci in &mut c {
                    *ci = (
                        rng.range(0.0, sat / 2.0),
                        rng.range(0.1, 3.0),
                        rng.range(0.0, 6.3),
                    );
                }
                Piece::Multisine(c)
            }
            _ => Piece::Square(rng.range(-sat, sat), rng.range(0.1, 3.0)),
        };
        pieces.push((piece, len));
    }
    Program { pieces }
}

/// Mechanical energy `1/2 qd^T M qd + m_p g z_p` [J] of a model state, computed here from
/// docs/MODEL.md (independently of both implementations' evaluation order).
pub fn energy(p: &Params, s: &State<f64>) -> f64 {
    let m = mass_matrix(p, &s.q);
    let mut kin = 0.0;
    for i in 0..5 {
        for j in 0..5 {
            kin += s.qd[i] * m[i][j] * s.qd[j];
        }
    }
    let [_, _, l, a, b] = s.q;
    let zp = -l * a.sin() * b.cos();
    0.5 * kin + p.payload_mass * p.gravity * zp
}

/// `M(q)` of docs/MODEL.md.
pub fn mass_matrix(p: &Params, q: &[f64; 5]) -> [[f64; 5]; 5] {
    let mp = p.payload_mass;
    let [_, _, l, a, b] = *q;
    let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
    let mx = p.trolley_mass + p.rail_mass + p.x.inertia;
    let my = p.trolley_mass + p.y.inertia;
    [
        [
            mx + mp,
            0.0,
            mp * sa * sb,
            mp * l * ca * sb,
            mp * l * sa * cb,
        ],
        [0.0, my + mp, mp * ca, -mp * l * sa, 0.0],
        [mp * sa * sb, mp * ca, p.rope.inertia + mp, 0.0, 0.0],
        [mp * l * ca * sb, -mp * l * sa, 0.0, mp * l * l, 0.0],
        [mp * l * sa * cb, 0.0, 0.0, 0.0, mp * l * l * sa * sa],
    ]
}

/// Parameters with every friction and damping term zero (the conservative crane).
pub fn frictionless(mut p: Params) -> Params {
    for a in [&mut p.x, &mut p.y, &mut p.rope] {
        a.viscous_pos = 0.0;
        a.viscous_neg = 0.0;
        a.dry_pos = [0.0; 5];
        a.dry_neg = [0.0; 5];
    }
    p.damping_alpha = 0.0;
    p.damping_beta = 0.0;
    p
}
