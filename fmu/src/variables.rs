//! The FMU's variables: one table, read by the FMU (get/set by value reference) and by the
//! packer (`modelDescription.xml`, `documentation/index.html`), so the two cannot disagree.
//!
//! Names of parameters are the model's own field paths (`payload_mass`, `x.viscous_pos`,
//! `rope.dry_neg[0]`, `config.h`, `state.q[3]`), so a validation error of the model
//! (`crane_model::Error::field`) names the FMU variable to fix. Names follow FMI 2.0's
//! `structured` naming convention. The model parameters' names, units, descriptions and
//! ranges are the model's table ([`crane_model::params::PARAM_FIELDS`]); this module adds
//! what is the FMU's own: their order, value references, causality and variability.

use crane_model::params::{ParamField, Rule, PARAM_FIELDS};
use crane_model::{Axis, Params, State};

pub use crane_model::params::LimitEnd;

/// FMI 2.0 causality of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// Set by the importer before (fixed) or during (tunable) the simulation.
    Parameter,
    /// Set by the importer before every step (held over the step, zero-order hold).
    Input,
    /// Computed by the FMU.
    Output,
}

/// FMI 2.0 variability of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// Set before initialisation only.
    Fixed,
    /// May also change between steps.
    Tunable,
    /// Changes only at communication points (integer outputs).
    Discrete,
    /// A real signal.
    Continuous,
}

/// FMI 2.0 base type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `fmi2Real` (f64).
    Real,
    /// `fmi2Integer` (i32).
    Integer,
}

/// What a value reference stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// Input voltage of axis 0 (X), 1 (Y), 2 (rope) [V].
    Input(usize),
    /// Model parameter number `i` in [`params`] order.
    Param(usize),
    /// The model's fixed step `h` [s].
    Step,
    /// Initial position `q[i]`.
    InitQ(usize),
    /// Initial velocity `qd[i]`.
    InitQd(usize),
    /// Segment budget of a step (integer, `1..=8`).
    SegmentBudget,
    /// Friction law (integer: 0 hybrid, 1 `tanh`).
    Law,
    /// Slope factor `gamma` [s/m] of the `tanh` law.
    Gamma,
    /// Stiction ratio (breakaway over sliding friction, >= 1) of drive axis `i`.
    StictionRatio(usize),
    /// Stribeck velocity [m/s] of drive axis `i`.
    StribeckVelocity(usize),
    /// Position `q[i]`.
    Q(usize),
    /// Velocity `qd[i]`.
    Qd(usize),
    /// Friction force of drive axis `i` [N].
    Friction(usize),
    /// Rope tension [N].
    Tension,
    /// Payload position component `i` (x, y, z) [m].
    Payload(usize),
    /// Mode of drive axis `i` (integer: -1 negative, 0 stopped, 1 positive).
    Mode(usize),
}

/// One variable of `modelDescription.xml`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variable {
    /// Name (FMI structured naming).
    pub name: &'static str,
    /// Value reference (unique over all variables).
    pub vr: u32,
    /// Base type.
    pub kind: Kind,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// Unit (declared in [`UNITS`]), if any.
    pub unit: Option<&'static str>,
    /// Human description.
    pub description: &'static str,
    /// What it stands for.
    pub slot: Slot,
    /// The range the FMU checks a set value against (`min`/`max` of `modelDescription.xml`).
    pub range: Range,
}

/// The smallest positive f64 (`5e-324`): the `min` of a parameter that must be `> 0`, since
/// FMI's `min` is inclusive and every f64 `>= 5e-324` is `> 0`.
pub const SMALLEST_POSITIVE: f64 = 5e-324;

/// The closed range `[min, max]` a variable's value must lie in, as `modelDescription.xml`
/// declares it (`None`: unbounded on that side). The same range the model (or the FMU)
/// checks when the value is used; every value must also be finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Smallest accepted value, in the variable's unit.
    pub min: Option<f64>,
    /// Largest accepted value, in the variable's unit.
    pub max: Option<f64>,
}

impl Range {
    /// Any finite value.
    pub const ANY: Range = Range {
        min: None,
        max: None,
    };
    /// `>= 0`.
    pub const NON_NEGATIVE: Range = Range {
        min: Some(0.0),
        max: None,
    };
    /// `> 0` (declared as `min = 5e-324`, see [`SMALLEST_POSITIVE`]).
    pub const POSITIVE: Range = Range {
        min: Some(SMALLEST_POSITIVE),
        max: None,
    };

    /// `>= min`.
    pub const fn at_least(min: f64) -> Range {
        Range {
            min: Some(min),
            max: None,
        }
    }

    /// `min <= value <= max`.
    pub const fn between(min: f64, max: f64) -> Range {
        Range {
            min: Some(min),
            max: Some(max),
        }
    }
}

/// Names of the drive axes as the parameter names spell them (X, Y, rope).
pub const AXES: [&str; 3] = [Axis::X.name(), Axis::Y.name(), Axis::Rope.name()];

/// For model parameter `i` ([`params`] order) that is a position limit: its axis (0 X, 1 Y,
/// 2 rope) and end.
pub fn limit_of(i: usize) -> Option<(usize, LimitEnd)> {
    let f = param_field(i)?;
    Some((f.axis?.index(), f.limit?))
}

/// The range `crane_model::Params::validate` checks model parameter `i` ([`params`] order)
/// against, taken alone (its [`ParamField::rule`]): masses `payload_mass`, `trolley_mass` and
/// the gains `> 0`; the other masses, gravity, inertias, viscous and swing damping
/// coefficients `>= 0`; `rope.min > 0`; polynomial coefficients and the other limits any
/// finite value (`min < max` of one axis is a condition on the pair, checked at
/// `fmi2ExitInitializationMode`).
pub fn param_range(i: usize) -> Range {
    param_field(i).map_or(Range::ANY, |f| rule_range(f.rule))
}

/// The declared range of a parameter with model rule `rule`.
fn rule_range(rule: Rule) -> Range {
    match rule {
        Rule::Finite => Range::ANY,
        Rule::NonNegative => Range::NON_NEGATIVE,
        Rule::Positive => Range::POSITIVE,
    }
}

/// Units used by the variables, with their SI base-unit exponents
/// `(name, [kg, m, s, A, rad])`.
pub const UNITS: &[(&str, [i8; 5])] = &[
    ("V", [1, 2, -3, -1, 0]),
    ("m", [0, 1, 0, 0, 0]),
    ("m/s", [0, 1, -1, 0, 0]),
    ("rad", [0, 0, 0, 0, 1]),
    ("rad/s", [0, 0, -1, 0, 1]),
    ("s", [0, 0, 1, 0, 0]),
    ("kg", [1, 0, 0, 0, 0]),
    ("m/s2", [0, 1, -2, 0, 0]),
    ("kg.m2/s", [1, 2, -1, 0, 0]),
    ("N", [1, 1, -2, 0, 0]),
    ("N/V", [0, -1, 1, 1, 0]),
    ("N.s/m", [1, 0, -1, 0, 0]),
    ("N/m", [1, 0, -2, 0, 0]),
    ("N/m2", [1, -1, -2, 0, 0]),
    ("N/m3", [1, -2, -2, 0, 0]),
    ("N/m4", [1, -3, -2, 0, 0]),
    ("s/m", [0, -1, 1, 0, 0]),
    ("1", [0, 0, 0, 0, 0]),
];

/// Number of model parameters (the numbers of [`Params`]).
pub const N_PARAMS: usize = crane_model::params::N_PARAMS;

/// The model parameters in the FMU's order, [`Slot::Param`] index `i` at value reference
/// [`VR_PARAM`] + `i`: first the scalars of [`Params`] itself, then the axes' numbers (X, Y,
/// rope), each in the order of the model's table ([`PARAM_FIELDS`]).
pub fn params() -> impl Iterator<Item = &'static ParamField> {
    let own = PARAM_FIELDS.iter().filter(|f| f.axis.is_none());
    own.chain(PARAM_FIELDS.iter().filter(|f| f.axis.is_some()))
}

/// Model parameter `i` ([`params`] order): its entry of the model's table, `None` past the
/// end.
pub fn param_field(i: usize) -> Option<&'static ParamField> {
    params().nth(i)
}

/// Mutable reference to model parameter `i` ([`params`] order), `None` past the end.
pub fn param_mut(p: &mut Params, i: usize) -> Option<&mut f64> {
    param_field(i).map(|f| (f.get_mut)(p))
}

/// Model parameter `i` ([`params`] order), `None` past the end.
pub fn param(p: &Params, i: usize) -> Option<f64> {
    param_field(i).map(|f| (f.get)(p))
}

/// Everything the importer can set before initialisation: model parameters, step, initial
/// state, segment budget and friction options. `Default` gives the start values of
/// `modelDescription.xml`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Model parameters (start values: `Params::default()`).
    pub params: Params,
    /// Model step `h` [s] (start 1 ms).
    pub h: f64,
    /// Initial state (start: `q = [0.25, 0.3, 0.35, pi/2, 0]`, at rest; the default of
    /// `crane simulate`).
    pub init: State<f64>,
    /// Segment budget of a step (start 8 = `crane_model::MAX_SEGMENTS`).
    pub segment_budget: i32,
    /// Friction law: 0 the hybrid automaton (exact sticking, start), 1 the smooth
    /// `Dbar qd + Cbar(q) tanh(gamma qd)` law (`crane_model::FrictionLaw`).
    pub law: i32,
    /// Slope factor `gamma` [s/m] of the `tanh` law (start 1000, the Python package's
    /// default; checked `> 0` whatever the law).
    pub gamma: f64,
    /// Stiction ratio per drive axis (X, Y, rope): breakaway over sliding dry friction
    /// (`crane_model::Stiction::ratio`, >= 1; start 1, no stiction).
    pub stiction_ratio: [f64; 3],
    /// Stribeck velocity [m/s] per drive axis (`crane_model::Stiction::velocity`, > 0;
    /// start 0.005, the Python environment's).
    pub stribeck_velocity: [f64; 3],
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            params: Params::default(),
            h: crane_model::Config::default().h,
            init: State {
                q: [0.25, 0.3, 0.35, core::f64::consts::FRAC_PI_2, 0.0],
                qd: [0.0; 5],
            },
            segment_budget: crane_model::MAX_SEGMENTS as i32,
            law: 0,
            gamma: 1000.0,
            stiction_ratio: [1.0; 3],
            stribeck_velocity: [0.005; 3],
        }
    }
}

/// Value references: inputs 0..3, outputs from 100, integer outputs from 200, model
/// parameters from 1000, step 1100, initial state 1101..1110, `tanh` slope 1111, segment
/// budget 1200, friction law 1201, stiction 1300..1305 (ratio, Stribeck velocity per axis).
pub const VR_PARAM: u32 = 1000;

const STICTION_RATIO: [&str; 3] = [
    "stiction[0].ratio",
    "stiction[1].ratio",
    "stiction[2].ratio",
];
const STRIBECK_VELOCITY: [&str; 3] = [
    "stiction[0].velocity",
    "stiction[1].velocity",
    "stiction[2].velocity",
];
const STICTION_DESC: [&str; 3] = [
    "stiction ratio of X: breakaway over sliding dry friction (>= 1; 1 is no stiction)",
    "stiction ratio of Y: breakaway over sliding dry friction (>= 1; 1 is no stiction)",
    "stiction ratio of the rope: breakaway over sliding dry friction (>= 1; 1 is no stiction)",
];
const STRIBECK_DESC: [&str; 3] = [
    "Stribeck velocity of X: sliding dry friction Cbar (1 + (ratio - 1) exp(-(v / velocity)^2)) (> 0)",
    "Stribeck velocity of Y: sliding dry friction Cbar (1 + (ratio - 1) exp(-(v / velocity)^2)) (> 0)",
    "Stribeck velocity of the rope: sliding dry friction Cbar (1 + (ratio - 1) exp(-(v / velocity)^2)) (> 0)",
];

const Q_NAMES: [&str; 5] = ["q.x", "q.y", "q.l", "q.alpha", "q.beta"];
const QD_NAMES: [&str; 5] = ["qd.x", "qd.y", "qd.l", "qd.alpha", "qd.beta"];
const Q_UNITS: [&str; 5] = ["m", "m", "m", "rad", "rad"];
const QD_UNITS: [&str; 5] = ["m/s", "m/s", "m/s", "rad/s", "rad/s"];
const Q_DESC: [&str; 5] = [
    "rail position X",
    "trolley position Y",
    "rope length L",
    "swing angle alpha (pi/2 hanging straight down)",
    "swing angle beta (0 hanging straight down)",
];
const QD_DESC: [&str; 5] = [
    "rail velocity dX/dt",
    "trolley velocity dY/dt",
    "rope velocity dL/dt (positive lowers the payload)",
    "swing rate dalpha/dt",
    "swing rate dbeta/dt",
];
const INIT_Q: [&str; 5] = [
    "state.q[0]",
    "state.q[1]",
    "state.q[2]",
    "state.q[3]",
    "state.q[4]",
];
const INIT_QD: [&str; 5] = [
    "state.qd[0]",
    "state.qd[1]",
    "state.qd[2]",
    "state.qd[3]",
    "state.qd[4]",
];
const INIT_Q_DESC: [&str; 5] = [
    "initial rail position X",
    "initial trolley position Y",
    "initial rope length L",
    "initial swing angle alpha",
    "initial swing angle beta",
];
const INIT_QD_DESC: [&str; 5] = [
    "initial rail velocity",
    "initial trolley velocity",
    "initial rope velocity",
    "initial swing rate alpha",
    "initial swing rate beta",
];

/// The input voltages `(name, description)` of axis 0 (X), 1 (Y), 2 (rope), value references
/// 0..3.
const INPUTS: [(&str, &str); 3] = [
    ("u_x", "input voltage of the X drive (saturated to +-12 V)"),
    ("u_y", "input voltage of the Y drive (saturated to +-12 V)"),
    (
        "u_l",
        "input voltage of the rope drive (saturated to +-12 V)",
    ),
];
/// The friction force outputs `(name, description)` of axis 0 (X), 1 (Y), 2 (rope) [N].
const FRICTION_OUT: [(&str, &str); 3] = [
    (
        "friction.x",
        "friction force of X: opposing motion when moving, the holding force when stopped",
    ),
    (
        "friction.y",
        "friction force of Y: opposing motion when moving, the holding force when stopped",
    ),
    (
        "friction.l",
        "friction force of the rope: opposing motion when moving, the holding force when stopped",
    ),
];
/// The payload position outputs `(name, description)` x, y, z [m].
const PAYLOAD_OUT: [(&str, &str); 3] = [
    ("payload.x", "payload position x"),
    ("payload.y", "payload position y"),
    (
        "payload.z",
        "payload position z (up; hanging payloads have z < 0)",
    ),
];
const MODE_NAMES: [&str; 3] = ["mode.x", "mode.y", "mode.l"];

/// A real variable with unit `unit` and no declared range.
fn real(
    name: &'static str,
    vr: u32,
    causality: Causality,
    variability: Variability,
    unit: &'static str,
    description: &'static str,
    slot: Slot,
) -> Variable {
    Variable {
        name,
        vr,
        kind: Kind::Real,
        causality,
        variability,
        unit: Some(unit),
        description,
        slot,
        range: Range::ANY,
    }
}

/// All variables, in `modelDescription.xml` order (its 1-based `index` is position + 1):
/// inputs, outputs, model parameters, initial state and step settings, friction options.
pub fn all() -> Vec<Variable> {
    let mut v = Vec::with_capacity(100);
    inputs(&mut v);
    outputs(&mut v);
    model_parameters(&mut v);
    initial_state(&mut v);
    friction_options(&mut v);
    v
}

/// The input voltages (value references 0..3).
fn inputs(v: &mut Vec<Variable>) {
    for (i, (name, desc)) in INPUTS.into_iter().enumerate() {
        v.push(real(
            name,
            i as u32,
            Causality::Input,
            Variability::Continuous,
            "V",
            desc,
            Slot::Input(i),
        ));
    }
}

/// The outputs: state `q`, `qd` (from 100), friction forces, tension, payload position, and
/// the integer modes (from 200).
fn outputs(v: &mut Vec<Variable>) {
    let out = |name, vr, unit, desc, slot| {
        real(
            name,
            vr,
            Causality::Output,
            Variability::Continuous,
            unit,
            desc,
            slot,
        )
    };
    for i in 0..5 {
        v.push(out(
            Q_NAMES[i],
            100 + i as u32,
            Q_UNITS[i],
            Q_DESC[i],
            Slot::Q(i),
        ));
    }
    for i in 0..5 {
        v.push(out(
            QD_NAMES[i],
            105 + i as u32,
            QD_UNITS[i],
            QD_DESC[i],
            Slot::Qd(i),
        ));
    }
    for (i, (name, desc)) in FRICTION_OUT.into_iter().enumerate() {
        v.push(out(name, 110 + i as u32, "N", desc, Slot::Friction(i)));
    }
    v.push(out(
        "tension",
        113,
        "N",
        "rope tension (positive pulls)",
        Slot::Tension,
    ));
    for (i, (name, desc)) in PAYLOAD_OUT.into_iter().enumerate() {
        v.push(out(name, 114 + i as u32, "m", desc, Slot::Payload(i)));
    }
    for (i, name) in MODE_NAMES.into_iter().enumerate() {
        v.push(Variable {
            name,
            vr: 200 + i as u32,
            kind: Kind::Integer,
            causality: Causality::Output,
            variability: Variability::Discrete,
            unit: None,
            description: "mode of the drive axis: -1 moving negative, 0 stopped (exact sticking), 1 moving positive",
            slot: Slot::Mode(i),
            range: Range::ANY,
        });
    }
}

/// The model parameters ([`params`], from [`VR_PARAM`]) and the model step `config.h`.
fn model_parameters(v: &mut Vec<Variable>) {
    for (i, f) in params().enumerate() {
        v.push(Variable {
            range: rule_range(f.rule),
            ..real(
                f.name,
                VR_PARAM + i as u32,
                Causality::Parameter,
                Variability::Tunable,
                f.unit,
                f.description,
                Slot::Param(i),
            )
        });
    }
    v.push(Variable {
        range: Range::POSITIVE,
        ..real(
            "config.h",
            1100,
            Causality::Parameter,
            Variability::Fixed,
            "s",
            "fixed model step h (> 0); every communication step must be a whole multiple of it",
            Slot::Step,
        )
    });
}

/// The initial state `state.q`, `state.qd` (1101..1110) and the segment budget (1200).
fn initial_state(v: &mut Vec<Variable>) {
    // The swing angles' own domain (the swing stops, `crane_model::SWING_STOP`); the
    // drive positions must lie within their axis limits, which are parameters themselves.
    let (half_pi, stop) = (core::f64::consts::FRAC_PI_2, crane_model::SWING_STOP);
    let angle_range = [
        Range::between(half_pi - stop, half_pi + stop),
        Range::between(-stop, stop),
    ];
    for i in 0..5 {
        let range = if i >= 3 {
            angle_range[i - 3]
        } else {
            Range::ANY
        };
        v.push(Variable {
            range,
            ..real(
                INIT_Q[i],
                1101 + i as u32,
                Causality::Parameter,
                Variability::Fixed,
                Q_UNITS[i],
                INIT_Q_DESC[i],
                Slot::InitQ(i),
            )
        });
    }
    for i in 0..5 {
        v.push(real(
            INIT_QD[i],
            1106 + i as u32,
            Causality::Parameter,
            Variability::Fixed,
            QD_UNITS[i],
            INIT_QD_DESC[i],
            Slot::InitQd(i),
        ));
    }
    v.push(Variable {
        name: "config.segment_budget",
        vr: 1200,
        kind: Kind::Integer,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        unit: None,
        description: "integration segments one step may use (1..=8): a real-time bound on the work of a step",
        slot: Slot::SegmentBudget,
        range: Range::between(1.0, crane_model::MAX_SEGMENTS as f64),
    });
}

/// The friction options of the Python package (`crane_twin.Crane(law=..., gamma=...,
/// stiction=...)`): the law, the `tanh` slope and stiction per drive axis.
fn friction_options(v: &mut Vec<Variable>) {
    v.push(Variable {
        name: "config.law.kind",
        vr: 1201,
        kind: Kind::Integer,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        unit: None,
        description: "friction law of the drive axes: 0 hybrid automaton (exact sticking), 1 smooth Dbar qd + Cbar(q) tanh(gamma qd) (no modes: mode outputs follow the sign of the velocity)",
        slot: Slot::Law,
        range: Range::between(0.0, 1.0),
    });
    v.push(Variable {
        name: "config.law.gamma",
        vr: 1111,
        kind: Kind::Real,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        unit: Some("s/m"),
        description: "slope factor gamma of the tanh law (> 0; used when config.law.kind = 1)",
        slot: Slot::Gamma,
        range: Range::POSITIVE,
    });
    for i in 0..3 {
        for (name, vr, unit, description, slot, range) in [
            (
                STICTION_RATIO[i],
                1300 + 2 * i as u32,
                "1",
                STICTION_DESC[i],
                Slot::StictionRatio(i),
                Range::at_least(1.0),
            ),
            (
                STRIBECK_VELOCITY[i],
                1301 + 2 * i as u32,
                "m/s",
                STRIBECK_DESC[i],
                Slot::StribeckVelocity(i),
                Range::POSITIVE,
            ),
        ] {
            v.push(Variable {
                name,
                vr,
                kind: Kind::Real,
                causality: Causality::Parameter,
                variability: Variability::Tunable,
                unit: Some(unit),
                description,
                slot,
                range,
            });
        }
    }
}

/// The variable table, built once per process and shared by every instance.
pub fn table() -> &'static [Variable] {
    static TABLE: std::sync::OnceLock<Vec<Variable>> = std::sync::OnceLock::new();
    TABLE.get_or_init(all)
}

/// The variable with value reference `vr` and base type `kind`, if any.
pub fn lookup(vars: &[Variable], kind: Kind, vr: u32) -> Option<&Variable> {
    vars.iter().find(|v| v.vr == vr && v.kind == kind)
}

/// Start value of a parameter or input as `modelDescription.xml` declares it (`None` for
/// outputs, which are calculated).
pub fn start(s: &Settings, slot: Slot) -> Option<f64> {
    match slot {
        Slot::Input(_) => Some(0.0),
        _ => setting(s, slot),
    }
}

/// The value of a parameter slot in `s` (integers as f64, exactly); `None` for inputs and
/// outputs.
pub fn setting(s: &Settings, slot: Slot) -> Option<f64> {
    match slot {
        Slot::Param(i) => param(&s.params, i),
        Slot::Step => Some(s.h),
        Slot::InitQ(i) => s.init.q.get(i).copied(),
        Slot::InitQd(i) => s.init.qd.get(i).copied(),
        Slot::SegmentBudget => Some(f64::from(s.segment_budget)),
        Slot::Law => Some(f64::from(s.law)),
        Slot::Gamma => Some(s.gamma),
        Slot::StictionRatio(i) => s.stiction_ratio.get(i).copied(),
        Slot::StribeckVelocity(i) => s.stribeck_velocity.get(i).copied(),
        _ => None,
    }
}

/// Sets a parameter slot of `s` to `value` (integer slots take a whole f64 in `i32` range);
/// `false`, and nothing changed, for inputs, outputs and integers that are not whole.
pub fn set_setting(s: &mut Settings, slot: Slot, value: f64) -> bool {
    let whole =
        value.fract() == 0.0 && value >= f64::from(i32::MIN) && value <= f64::from(i32::MAX);
    let dst = match slot {
        Slot::SegmentBudget | Slot::Law if !whole => return false,
        Slot::SegmentBudget => {
            s.segment_budget = value as i32;
            return true;
        }
        Slot::Law => {
            s.law = value as i32;
            return true;
        }
        Slot::Param(i) => param_mut(&mut s.params, i),
        Slot::Step => Some(&mut s.h),
        Slot::InitQ(i) => s.init.q.get_mut(i),
        Slot::InitQd(i) => s.init.qd.get_mut(i),
        Slot::Gamma => Some(&mut s.gamma),
        Slot::StictionRatio(i) => s.stiction_ratio.get_mut(i),
        Slot::StribeckVelocity(i) => s.stribeck_velocity.get_mut(i),
        _ => None,
    };
    match dst {
        Some(d) => {
            *d = value;
            true
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_value_references_are_unique() {
        let v = all();
        for (i, a) in v.iter().enumerate() {
            for b in &v[i + 1..] {
                assert_ne!(a.name, b.name);
                assert_ne!(a.vr, b.vr, "{} and {}", a.name, b.name);
            }
            if let Some(u) = a.unit {
                assert!(UNITS.iter().any(|(n, _)| *n == u), "unit {u} of {}", a.name);
            }
        }
    }

    #[test]
    fn every_param_slot_is_a_distinct_field() {
        // Setting parameter i to a marker changes exactly one field: the slots cover all
        // 54 fields once.
        let base = Params::default();
        for i in 0..N_PARAMS {
            let mut p = base;
            *param_mut(&mut p, i).unwrap() = 12345.5;
            for j in 0..N_PARAMS {
                let v = param(&p, j).unwrap();
                assert_eq!(v == 12345.5, i == j, "param {i} vs {j}");
            }
        }
        assert!(param(&base, N_PARAMS).is_none());
        // Field names match the model's own error paths.
        let mut p = base;
        p.x.viscous_pos = -1.0;
        assert_eq!(
            p.validate().unwrap_err().field,
            param_field(6 + 2).unwrap().name
        );
        let mut p = base;
        p.rope.dry_neg[0] = f64::NAN;
        assert_eq!(
            p.validate().unwrap_err().field,
            param_field(38 + 9).unwrap().name
        );
    }

    #[test]
    fn parameters_keep_their_value_references_and_ranges() {
        // The FMU's own order: the scalars of `Params`, then X, Y, rope (16 each).
        let vr = |name: &str| {
            let v = all();
            v.iter()
                .find(|v| v.name == name)
                .map(|v| (v.vr, v.unit, v.range))
        };
        let r = |vr, unit, range| Some((vr, Some(unit), range));
        assert_eq!(vr("payload_mass"), r(1000, "kg", Range::POSITIVE));
        assert_eq!(vr("gravity"), r(1003, "m/s2", Range::NON_NEGATIVE));
        assert_eq!(vr("damping_alpha"), r(1004, "kg.m2/s", Range::NON_NEGATIVE));
        assert_eq!(vr("damping_beta"), r(1005, "kg.m2/s", Range::NON_NEGATIVE));
        assert_eq!(vr("x.inertia"), r(1006, "kg", Range::NON_NEGATIVE));
        assert_eq!(vr("x.gain"), r(1007, "N/V", Range::POSITIVE));
        assert_eq!(vr("x.dry_pos[2]"), r(1012, "N/m2", Range::ANY));
        assert_eq!(vr("x.min"), r(1020, "m", Range::ANY));
        assert_eq!(vr("y.inertia"), r(1022, "kg", Range::NON_NEGATIVE));
        assert_eq!(vr("rope.dry_neg[4]"), r(1051, "N/m4", Range::ANY));
        assert_eq!(vr("rope.min"), r(1052, "m", Range::POSITIVE));
        assert_eq!(vr("rope.max"), r(1053, "m", Range::ANY));
        assert_eq!(vr("config.h").map(|v| v.0), Some(1100));
        assert_eq!(params().count(), N_PARAMS);
        assert_eq!(limit_of(6 + 14), Some((0, LimitEnd::Min)));
        assert_eq!(limit_of(38 + 15), Some((2, LimitEnd::Max)));
        assert_eq!(limit_of(5), None);
        assert_eq!(limit_of(N_PARAMS), None);
        assert_eq!(param_range(38 + 14), Range::POSITIVE);
        assert_eq!(param_range(N_PARAMS), Range::ANY);
    }
}
