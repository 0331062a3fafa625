//! `modelDescription.xml` and `documentation/index.html`, generated from the variable table
//! ([`crate::variables`]), and the GUID that ties the binary to its description.

use crate::variables::{self, Causality, Kind, Settings, Variability, Variable, UNITS};
use std::fmt::Write;
use std::sync::OnceLock;

/// The FMI model identifier: the binary is `binaries/linux64/crane.so`.
pub const MODEL_IDENTIFIER: &str = "crane";

/// XML-escapes text for attribute values.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
    }
}

fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

/// The description with a placeholder GUID (what the GUID hashes).
fn body(guid: &str) -> String {
    let vars = variables::all();
    let settings = Settings::default();
    let mut x = String::with_capacity(32 * 1024);
    // `write!` to a String cannot fail.
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="crane" guid="{guid}" description="3-D overhead crane (INTECO 3D-Crane) with hybrid exact-sticking dry friction, fixed step" author="crane workspace" version="{}" generationTool="crane-fmu-pack {}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
        env!("CARGO_PKG_VERSION"),
        env!("CARGO_PKG_VERSION"),
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" needsExecutionTool="false" canHandleVariableCommunicationStepSize="false" canInterpolateInputs="false" maxOutputDerivativeOrder="0" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="false"/>"#
    );
    let _ = writeln!(x, "  <UnitDefinitions>");
    for (name, [kg, m, s, a, rad]) in UNITS {
        let mut attrs = String::new();
        for (k, e) in [("kg", kg), ("m", m), ("s", s), ("A", a), ("rad", rad)] {
            if *e != 0 {
                let _ = write!(attrs, r#" {k}="{e}""#);
            }
        }
        let _ = writeln!(
            x,
            r#"    <Unit name="{}"><BaseUnit{attrs}/></Unit>"#,
            esc(name)
        );
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
    let _ = writeln!(x, "  <LogCategories>");
    let _ = writeln!(
        x,
        r#"    <Category name="logStatusError" description="a call failed: why (always logged)"/>"#
    );
    let _ = writeln!(
        x,
        r#"    <Category name="logStatusFatal" description="an internal panic was caught (always logged)"/>"#
    );
    let _ = writeln!(x, "  </LogCategories>");
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="0" stopTime="20" stepSize="{}"/>"#,
        settings.h
    );
    let _ = writeln!(x, "  <ModelVariables>");
    for (i, v) in vars.iter().enumerate() {
        let _ = writeln!(x, "    <!-- index {} -->", i + 1);
        let _ = writeln!(x, "{}", scalar(v, &settings));
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let outputs: Vec<usize> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i + 1)
        .collect();
    let _ = writeln!(x, "    <Outputs>");
    for i in &outputs {
        let _ = writeln!(x, r#"      <Unknown index="{i}"/>"#);
    }
    let _ = writeln!(x, "    </Outputs>");
    let _ = writeln!(x, "    <InitialUnknowns>");
    for i in &outputs {
        let _ = writeln!(x, r#"      <Unknown index="{i}"/>"#);
    }
    let _ = writeln!(x, "    </InitialUnknowns>");
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

fn scalar(v: &Variable, s: &Settings) -> String {
    let mut head = format!(
        r#"    <ScalarVariable name="{}" valueReference="{}" description="{}" causality="{}" variability="{}""#,
        esc(v.name),
        v.vr,
        esc(v.description),
        causality(v.causality),
        variability(v.variability),
    );
    let start = variables::start(s, v.slot);
    match (v.causality, start) {
        (Causality::Output, _) => head.push_str(r#" initial="calculated""#),
        (Causality::Parameter, Some(_)) => head.push_str(r#" initial="exact""#),
        _ => {}
    }
    head.push('>');
    let start_attr = match (v.kind, start) {
        // Rust's `{}` for f64 is the shortest text that reads back to the same bits.
        (Kind::Real, Some(x)) => format!(r#" start="{x}""#),
        (Kind::Integer, Some(x)) => format!(r#" start="{}""#, x as i64),
        _ => String::new(),
    };
    let unit = v
        .unit
        .map(|u| format!(r#" unit="{}""#, esc(u)))
        .unwrap_or_default();
    let range = bounds(v);
    let ty = match v.kind {
        Kind::Real => format!("<Real{unit}{range}{start_attr}/>"),
        Kind::Integer => format!("<Integer{range}{start_attr}/>"),
    };
    format!("{head}{ty}</ScalarVariable>")
}

/// The `min` and `max` attributes of a variable's declared range (empty when unbounded).
/// Reals print as Rust's `{:?}`: the shortest text that reads back to the same bits, in
/// exponent form for tiny values (`5e-324`).
fn bounds(v: &Variable) -> String {
    let text = |x: f64| match v.kind {
        Kind::Real => format!("{x:?}"),
        Kind::Integer => format!("{}", x as i64),
    };
    let mut a = String::new();
    if let Some(x) = v.range.min {
        let _ = write!(a, r#" min="{}""#, text(x));
    }
    if let Some(x) = v.range.max {
        let _ = write!(a, r#" max="{}""#, text(x));
    }
    a
}

/// FNV-1a, 64 bit: a stable hash for the GUID and the checksum of a serialized FMU state
/// (no cryptographic need).
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The GUID: a hash of the description itself (with a placeholder GUID), so any change of
/// the variables gives a new GUID and an FMU whose binary and XML disagree is refused at
/// `fmi2Instantiate`.
pub fn guid() -> &'static str {
    static GUID: OnceLock<String> = OnceLock::new();
    GUID.get_or_init(|| {
        let text = body("GUID");
        let a = fnv1a(text.as_bytes());
        let b = fnv1a(&[text.as_bytes(), b"crane-fmu"].concat());
        format!(
            "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
            a >> 32,
            (a >> 16) & 0xffff,
            a & 0xffff,
            b >> 48,
            b & 0xffff_ffff_ffff
        )
    })
}

/// The complete `modelDescription.xml`.
pub fn model_description() -> String {
    body(guid())
}

/// `documentation/index.html`: what the FMU is, its variables with units and start values.
pub fn documentation() -> String {
    let vars = variables::all();
    let s = Settings::default();
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>crane FMU</title></head><body>"
    );
    let _ = writeln!(
        h,
        "<h1>crane: 3-D overhead crane with hybrid (exact-sticking) dry friction</h1>\n\
<p>FMI 2.0 co-simulation FMU of the crane model (<code>crane_model::Crane</code>). \
The model integrates with its own fixed step <code>config.h</code> (default 1 ms); every \
communication step must be a whole multiple of it (relative tolerance 1e-9), otherwise \
<code>fmi2DoStep</code> returns <code>fmi2Error</code> and logs why. Inputs are held over \
the communication step (zero-order hold) and saturated to &plusmn;12 V. Parameters are \
validated at <code>fmi2ExitInitializationMode</code>; an invalid one gives \
<code>fmi2Error</code> and a log message naming it. Tunable parameters may change between \
steps (checked at once). Bounded parameters declare <code>min</code>/<code>max</code>: the \
range the model checks (a strict <code>&gt; 0</code> is <code>min=\"5e-324\"</code>, the \
smallest positive double).</p>\n\
<p>Friction options, as the Python package <code>crane_twin</code> offers them: \
<code>config.law.kind</code> 0 is the hybrid automaton (exact sticking), 1 the smooth \
<code>tanh</code> law with slope <code>config.law.gamma</code>; \
<code>stiction[i].ratio</code> (breakaway over sliding friction, 1 = none) and \
<code>stiction[i].velocity</code> (Stribeck velocity) per drive axis (0 X, 1 Y, 2 rope). \
A large <code>config.law.gamma</code> makes the <code>tanh</code> law stiff at rest: the \
fixed-step RK4 is stable only while <code>config.h</code> stays below about \
2.785&nbsp;M&nbsp;/&nbsp;(Dbar&nbsp;+&nbsp;gamma&nbsp;Cbar) of the stiffest axis (the rope, \
with the default parameters: 5.59 ms at gamma = 1000, 1.96 ms at 3000, 0.599 ms at 1e4, \
0.060 ms at 1e5); above it the crane at rest creeps (13 &micro;m in 0.5 s at 1e4 and \
h = 1 ms) without an error. Use a smaller <code>config.h</code> or the hybrid law.</p>\n\
<p>FMU state: <code>fmi2GetFMUstate</code>/<code>fmi2SetFMUstate</code> and serialisation \
are supported; a state holds every parameter, the inputs, the time, the simulator's state \
and modes and the last applied input, so a simulation continued from it gives the same \
bits. A serialized state carries a header (magic, format version, length, GUID) and a \
checksum; a corrupt one is refused with <code>fmi2Error</code>. No directional \
derivatives.</p>\n\
<p>Positions: X rail, Y trolley, rope length L (positive velocity lowers the payload), swing \
angles alpha (pi/2 hanging straight down) and beta. Modes: -1 moving negative, 0 stopped \
(exact sticking, friction holds), 1 moving positive.</p>"
    );
    let _ = writeln!(
        h,
        "<table border=\"1\"><tr><th>name</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>min</th><th>max</th><th>description</th></tr>"
    );
    for v in &vars {
        let start = variables::start(&s, v.slot)
            .map(|x| format!("{x}"))
            .unwrap_or_default();
        let bound = |b: Option<f64>| b.map(|x| format!("{x:?}")).unwrap_or_default();
        let _ = writeln!(
            h,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(v.name),
            causality(v.causality),
            variability(v.variability),
            v.kind,
            esc(v.unit.unwrap_or("")),
            start,
            bound(v.range.min),
            bound(v.range.max),
            esc(v.description)
        );
    }
    let _ = writeln!(h, "</table></body></html>");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guid_is_stable_and_in_the_description() {
        assert_eq!(guid(), guid());
        assert_eq!(guid().len(), 38);
        let xml = model_description();
        assert!(xml.contains(&format!("guid=\"{}\"", guid())));
        // Start values read back to the defaults' bits.
        assert!(xml.contains(r#"name="x.viscous_neg""#));
        assert!(xml.contains(r#"<Real unit="N.s/m" min="0.0" start="101.44"/>"#));
        // Declared ranges: > 0 as the smallest positive double, integers as integers.
        assert!(xml.contains(r#"<Real unit="kg" min="5e-324" start="0.457"/>"#));
        assert!(xml.contains(r#"<Integer min="1" max="8" start="8"/>"#));
        assert!(xml.contains(r#"<Real unit="1" min="1.0" start="1"/>"#));
        assert!(xml.contains(r#"canGetAndSetFMUstate="true" canSerializeFMUstate="true""#));
        assert!(xml.contains(r#"start="1.5707963267948966""#));
    }
}
