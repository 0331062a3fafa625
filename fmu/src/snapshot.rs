//! The FMU state (`fmi2FMUstate`): everything that determines an instance's future, as plain
//! data ([`Snapshot`]), and its serialized form (`fmi2SerializeFMUstate`), in safe Rust.
//!
//! What determines the future: every parameter and option the importer can set (model
//! parameters, step, initial state, segment budget, friction law, stiction), the inputs, the
//! phase, the start time and the step count (the FMU's time), the simulator's state and
//! modes, and the input the last step applied (the friction and tension outputs use it). The
//! model has no other memory: the integrator is one-step, and the input delay line of
//! `crane_model::Extensions` is not used by the FMU.
//!
//! Serialized form (all numbers little-endian; f64 as their IEEE bits, so a round trip is
//! exact, NaN payloads and `-0.0` included):
//!
//! | bytes | what |
//! |---|---|
//! | 8 | magic `CRANEFMU` |
//! | 4 | format version ([`FORMAT_VERSION`], u32) |
//! | 8 | total length in bytes (u64) |
//! | 38 | GUID of the FMU (`modelDescription.xml`): a state of another build is refused |
//! | 1 | phase (0 instantiated, 1 initialization, 2 step complete, 3 terminated, 4 failed) |
//! | 8 | accepted steps (u64) |
//! | 8 | start time [s] |
//! | 24 + 24 | inputs `u_x, u_y, u_l` [V]; the last applied (saturated) input [V] |
//! | 8 per parameter | every parameter variable, in `modelDescription.xml` order (integers as f64) |
//! | 3 | per drive axis, the travel limit set last (0 none, 1 `min`, 2 `max`) |
//! | 1 | 1 if a simulator runs, else 0 (and the next 83 bytes are 0) |
//! | 80 + 3 | state `q`, `qd`; modes of X, Y, rope (0 negative, 1 stopped, 2 positive) |
//! | 8 | FNV-1a 64 of every byte before |

use crate::description::{fnv1a, guid};
use crate::status::{Failure, Phase};
use crate::variables::{self, Causality, LimitEnd, Settings, Slot};
use crane_model::{Mode, State};

/// First bytes of a serialized FMU state.
pub const MAGIC: [u8; 8] = *b"CRANEFMU";

/// Version of the serialized form; a state of another version is refused.
pub const FORMAT_VERSION: u32 = 1;

/// The running simulator's part of an FMU state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sim {
    /// Positions [m, m, m, rad, rad] and velocities [m/s, m/s, m/s, rad/s, rad/s].
    pub state: State<f64>,
    /// Modes of X, Y, rope.
    pub modes: [Mode; 3],
}

/// Everything that determines an FMU instance's future (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Snapshot {
    /// Parameters and options.
    pub settings: Settings,
    /// Per drive axis, the travel limit the importer set last (for error messages).
    pub limit_set: [Option<LimitEnd>; 3],
    /// Inputs [V] as set (held over the next step).
    pub inputs: [f64; 3],
    /// Input [V] the last accepted step applied (saturated to +-12 V).
    pub applied: [f64; 3],
    /// Start time [s].
    pub start_time: f64,
    /// Accepted model steps since the start.
    pub steps: u64,
    /// Phase of the FMI state machine.
    pub phase: Phase,
    /// The simulator's state and modes, if one runs.
    pub sim: Option<Sim>,
}

const PHASES: [Phase; 5] = [
    Phase::Instantiated,
    Phase::Initialization,
    Phase::StepComplete,
    Phase::Terminated,
    Phase::Failed,
];
const MODES: [Mode; 3] = [Mode::Negative, Mode::Stopped, Mode::Positive];
const LIMITS: [Option<LimitEnd>; 3] = [None, Some(LimitEnd::Min), Some(LimitEnd::Max)];
/// Bytes before the body: magic, version, length, GUID.
const HEADER: usize = 8 + 4 + 8 + 38;

/// The parameter slots in `modelDescription.xml` order: the settings part of the state.
fn setting_slots() -> impl Iterator<Item = (&'static str, Slot)> {
    variables::table()
        .iter()
        .filter(|v| v.causality == Causality::Parameter)
        .map(|v| (v.name, v.slot))
}

fn code<T: PartialEq>(table: &[T], x: &T) -> u8 {
    table.iter().position(|t| t == x).unwrap_or(0) as u8
}

impl Snapshot {
    /// The serialized form (see the module documentation); its length is the same for every
    /// state of one FMU build.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(1024);
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        b.extend_from_slice(&0u64.to_le_bytes()); // the length, written last
        b.extend_from_slice(guid().as_bytes());
        b.push(code(&PHASES, &self.phase));
        b.extend_from_slice(&self.steps.to_le_bytes());
        let mut reals = vec![self.start_time];
        reals.extend(self.inputs);
        reals.extend(self.applied);
        for (_, slot) in setting_slots() {
            reals.push(variables::setting(&self.settings, slot).unwrap_or(f64::NAN));
        }
        for x in reals {
            b.extend_from_slice(&x.to_bits().to_le_bytes());
        }
        b.extend(self.limit_set.iter().map(|l| code(&LIMITS, l)));
        let (flag, sim) = match self.sim {
            Some(s) => (1, s),
            None => (
                0,
                Sim {
                    state: State {
                        q: [0.0; 5],
                        qd: [0.0; 5],
                    },
                    modes: [Mode::Negative; 3],
                },
            ),
        };
        b.push(flag);
        for x in sim.state.q.iter().chain(&sim.state.qd) {
            b.extend_from_slice(&x.to_bits().to_le_bytes());
        }
        b.extend(sim.modes.iter().map(|m| code(&MODES, m)));
        let len = (b.len() + 8) as u64;
        b[12..20].copy_from_slice(&len.to_le_bytes());
        let sum = fnv1a(&b);
        b.extend_from_slice(&sum.to_le_bytes());
        b
    }

    /// Reads a serialized state: magic, version, length, GUID and checksum are checked, then
    /// every field (codes in range, integer parameters whole). The values themselves are
    /// checked by the model when the state is set (`Instance::restore`).
    pub fn from_bytes(bytes: &[u8]) -> Result<Snapshot, Failure> {
        let bad = |what: String| Failure::error(format!("serialized FMU state: {what}"));
        if bytes.len() < HEADER + 8 || bytes[..8] != MAGIC {
            return Err(bad(format!(
                "not a crane FMU state ({} bytes, no `CRANEFMU` header)",
                bytes.len()
            )));
        }
        let mut r = Reader { bytes, at: 8 };
        let version = u32::from_le_bytes(r.array()?);
        if version != FORMAT_VERSION {
            return Err(bad(format!(
                "format version {version}, this FMU reads version {FORMAT_VERSION}"
            )));
        }
        let len = u64::from_le_bytes(r.array()?);
        if len != bytes.len() as u64 {
            return Err(bad(format!(
                "{} bytes, but its header says {len}",
                bytes.len()
            )));
        }
        let g = r.take(38)?;
        if g != guid().as_bytes() {
            return Err(bad(format!(
                "made by an FMU with GUID {}, this one is {}",
                String::from_utf8_lossy(g),
                guid()
            )));
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if fnv1a(body).to_le_bytes() != sum {
            return Err(bad("checksum mismatch (corrupt bytes)".into()));
        }
        let snap = read_body(&mut r)?;
        if r.at != body.len() {
            return Err(bad(format!(
                "{} bytes, {} expected by this FMU's variables",
                bytes.len(),
                r.at + 8
            )));
        }
        Ok(snap)
    }
}

/// The fields after the header.
fn read_body(r: &mut Reader<'_>) -> Result<Snapshot, Failure> {
    let phase = r.code(&PHASES, "phase")?;
    let steps = u64::from_le_bytes(r.array()?);
    let start_time = r.f64()?;
    let inputs = [r.f64()?, r.f64()?, r.f64()?];
    let applied = [r.f64()?, r.f64()?, r.f64()?];
    let mut settings = Settings::default();
    for (name, slot) in setting_slots() {
        let x = r.f64()?;
        if !variables::set_setting(&mut settings, slot, x) {
            return Err(Failure::error(format!(
                "serialized FMU state: `{name}` = {x} is not a value of its type"
            )));
        }
    }
    let limit_set = [
        r.code(&LIMITS, "limit")?,
        r.code(&LIMITS, "limit")?,
        r.code(&LIMITS, "limit")?,
    ];
    let running = r.code(&[false, true], "simulator flag")?;
    let mut state = State {
        q: [0.0; 5],
        qd: [0.0; 5],
    };
    for x in state.q.iter_mut().chain(state.qd.iter_mut()) {
        *x = r.f64()?;
    }
    let modes = [
        r.code(&MODES, "mode")?,
        r.code(&MODES, "mode")?,
        r.code(&MODES, "mode")?,
    ];
    Ok(Snapshot {
        settings,
        limit_set,
        inputs,
        applied,
        start_time,
        steps,
        phase,
        sim: running.then_some(Sim { state, modes }),
    })
}

/// Reads a byte buffer front to back; reading past the end is an error, never a panic.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], Failure> {
        let end = self.at.saturating_add(n);
        let s = self.bytes.get(self.at..end).ok_or_else(|| {
            Failure::error(format!(
                "serialized FMU state: ends at byte {} (field at {} of {n} bytes)",
                self.bytes.len(),
                self.at
            ))
        })?;
        self.at = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], Failure> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    fn f64(&mut self) -> Result<f64, Failure> {
        Ok(f64::from_bits(u64::from_le_bytes(self.array()?)))
    }

    /// One byte, an index into `table`.
    fn code<T: Copy>(&mut self, table: &[T], what: &str) -> Result<T, Failure> {
        let [c] = self.array()?;
        table.get(usize::from(c)).copied().ok_or_else(|| {
            Failure::error(format!(
                "serialized FMU state: {what} code {c} at byte {} is not one of 0..{}",
                self.at - 1,
                table.len()
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A snapshot with every field away from its default (a NaN input and a `-0.0`
    /// velocity included).
    fn unusual() -> Snapshot {
        let mut settings = Settings::default();
        for (i, (_, slot)) in setting_slots().enumerate() {
            let x = variables::setting(&settings, slot).unwrap();
            assert!(variables::set_setting(
                &mut settings,
                slot,
                x + 1.0 + i as f64
            ));
        }
        Snapshot {
            settings,
            limit_set: [None, Some(LimitEnd::Min), Some(LimitEnd::Max)],
            inputs: [f64::NAN, -0.0, 13.0],
            applied: [1.5, -12.0, 0.25],
            start_time: -3.5,
            steps: u64::MAX - 7,
            phase: Phase::Failed,
            sim: Some(Sim {
                state: State {
                    q: [0.1, 0.2, 0.3, 1.4, -0.1],
                    qd: [-0.0, 0.5, -0.25, 1e-300, 7.0],
                },
                modes: [Mode::Stopped, Mode::Positive, Mode::Negative],
            }),
        }
    }

    #[test]
    fn a_round_trip_keeps_every_bit() {
        let s = unusual();
        let bytes = s.to_bytes();
        let back = Snapshot::from_bytes(&bytes).unwrap();
        // (NaN != NaN, so the bytes are compared; they hold every field's bits.)
        assert_eq!(back.to_bytes(), bytes);
        assert!(back.inputs[0].is_nan());
        assert_eq!(back.inputs[1].to_bits(), (-0.0f64).to_bits());
        assert_eq!(back.settings, s.settings);
        assert_eq!(
            (back.limit_set, back.steps, back.phase),
            (s.limit_set, s.steps, s.phase)
        );
        assert_eq!(back.sim.unwrap().modes, s.sim.unwrap().modes);
        // The size does not depend on the state.
        let plain = Snapshot {
            sim: None,
            ..unusual()
        };
        assert_eq!(plain.to_bytes().len(), bytes.len());
        assert_eq!(Snapshot::from_bytes(&plain.to_bytes()).unwrap().sim, None);
    }

    #[test]
    fn every_truncation_and_every_flipped_bit_is_refused() {
        let bytes = unusual().to_bytes();
        for n in 0..bytes.len() {
            assert!(Snapshot::from_bytes(&bytes[..n]).is_err(), "{n} bytes");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(Snapshot::from_bytes(&longer).is_err());
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                assert!(Snapshot::from_bytes(&b).is_err(), "byte {i} bit {bit}");
            }
        }
    }

    #[test]
    fn the_message_says_what_is_wrong() {
        let bytes = unusual().to_bytes();
        let msg = |b: &[u8]| Snapshot::from_bytes(b).unwrap_err().message;
        assert_eq!(
            msg(b"hello"),
            "serialized FMU state: not a crane FMU state (5 bytes, no `CRANEFMU` header)"
        );
        let short = &bytes[..bytes.len() - 1];
        assert_eq!(
            msg(short),
            format!(
                "serialized FMU state: {} bytes, but its header says {}",
                short.len(),
                bytes.len()
            )
        );
        let mut v = bytes.clone();
        v[8] = 2;
        assert_eq!(
            msg(&v),
            "serialized FMU state: format version 2, this FMU reads version 1"
        );
        let mut g = bytes.clone();
        g[21] ^= 1;
        assert!(msg(&g).contains("made by an FMU with GUID"), "{}", msg(&g));
        let mut c = bytes.clone();
        c[HEADER + 3] ^= 1;
        assert_eq!(
            msg(&c),
            "serialized FMU state: checksum mismatch (corrupt bytes)"
        );
        // A field out of range behind a valid checksum (as a buggy writer would make it).
        let mut p = bytes[..bytes.len() - 8].to_vec();
        p[HEADER] = 9;
        let sum = fnv1a(&p);
        p.extend_from_slice(&sum.to_le_bytes());
        assert_eq!(
            msg(&p),
            format!("serialized FMU state: phase code 9 at byte {HEADER} is not one of 0..5")
        );
    }
}
