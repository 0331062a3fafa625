//! The `min`/`max` that `modelDescription.xml` declares for every parameter are the ranges
//! the FMU checks (issue 23): for each parameter, set alone on the start values, a declared
//! bound is accepted and the next f64 beyond it is refused with a message naming the
//! parameter; a side without a declared bound accepts +-1e300. The parameters whose range
//! depends on other parameters (the travel limits, checked as a pair, and the initial drive
//! positions, within them) are listed and checked for that dependence instead.

use crane_fmu::description::model_description;
use crane_fmu::instance::Instance;
use crane_fmu::variables::{table, Causality, Kind, Variable};

/// The next f64 after `x` towards +inf (`up`) or -inf.
fn next(x: f64, up: bool) -> f64 {
    if x == 0.0 {
        return if up { 5e-324 } else { -5e-324 };
    }
    let b = x.to_bits();
    f64::from_bits(if (x > 0.0) == up { b + 1 } else { b - 1 })
}

/// `Ok` if an instance with `v` set to `x` (everything else at its start value) passes
/// `fmi2ExitInitializationMode`, else the logged message.
fn try_value(v: &Variable, x: f64) -> Result<(), String> {
    let mut i = Instance::new();
    i.enter_initialization().map_err(|f| f.message)?;
    let set = match v.kind {
        Kind::Real => i.set_real(&[v.vr], &[x]),
        Kind::Integer => i.set_integer(&[v.vr], &[x as i32]),
    };
    set.map_err(|f| f.message)?;
    i.exit_initialization().map_err(|f| f.message)
}

/// Parameters without a fixed range of their own: the travel limits (`min < max` of an axis)
/// and the initial drive positions (within their axis' limits).
fn depends_on_others(name: &str) -> bool {
    name.ends_with(".min")
        || name.ends_with(".max")
        || name.starts_with("state.q[") && {
            let k = name.as_bytes()[8];
            (b'0'..=b'2').contains(&k)
        }
}

#[test]
fn every_parameter_declares_the_range_the_fmu_checks() {
    let mut checked = 0;
    for v in table()
        .iter()
        .filter(|v| v.causality == Causality::Parameter)
    {
        let name = v.name;
        for (bound, up) in [(v.range.min, false), (v.range.max, true)] {
            match bound {
                Some(b) => {
                    assert_eq!(try_value(v, b), Ok(()), "{name} = {b:?} (its bound)");
                    let beyond = match v.kind {
                        Kind::Real => next(b, up),
                        Kind::Integer => b + if up { 1.0 } else { -1.0 },
                    };
                    let e = try_value(v, beyond).unwrap_err();
                    assert!(e.contains(&format!("`{name}`")), "{name} = {beyond:?}: {e}");
                    checked += 1;
                }
                None if depends_on_others(name) => {}
                None => {
                    let far = if up { 1e300 } else { -1e300 };
                    assert_eq!(try_value(v, far), Ok(()), "{name} = {far:e} (unbounded)");
                }
            }
        }
    }
    // > 0 (min 5e-324): 2 masses, 3 gains, rope.min, config.h, gamma, 3 Stribeck velocities;
    // >= 0: rail mass, gravity, 2 dampings, 3 x (inertia and 2 viscous coefficients);
    // between: alpha and beta of the initial state, the segment budget, the law (2 each);
    // >= 1: 3 stiction ratios.
    assert_eq!(checked, 11 + 13 + 4 * 2 + 3, "bounds checked");
}

#[test]
fn the_parameters_without_a_range_of_their_own_depend_on_others() {
    let var = |name: &str| *table().iter().find(|v| v.name == name).unwrap();
    // The travel: any finite value as long as min < max.
    for (lo, hi) in [
        ("x.min", "x.max"),
        ("y.min", "y.max"),
        ("rope.min", "rope.max"),
    ] {
        assert_eq!(try_value(&var(hi), 1e300), Ok(()));
        assert!(try_value(&var(hi), -1e300)
            .unwrap_err()
            .contains(&format!("`{hi}`")));
        if lo != "rope.min" {
            assert_eq!(try_value(&var(lo), -1e300), Ok(()));
        }
        assert!(try_value(&var(lo), 1e300)
            .unwrap_err()
            .contains(&format!("`{lo}`")));
    }
    // The initial drive positions: within the axis' limits (start values [0, 0.505],
    // [0, 0.625], [0.13, 0.57]).
    for (k, lo, hi) in [(0, 0.0, 0.505), (1, 0.0, 0.625), (2, 0.13, 0.57)] {
        let v = var(&format!("state.q[{k}]"));
        assert!(v.range.min.is_none() && v.range.max.is_none());
        assert_eq!(try_value(&v, lo), Ok(()));
        assert_eq!(try_value(&v, hi), Ok(()));
        assert!(try_value(&v, next(lo, false)).is_err());
        assert!(try_value(&v, next(hi, true)).is_err());
    }
}

#[test]
fn the_description_declares_each_range() {
    let xml = model_description();
    for v in table() {
        let line = xml
            .lines()
            .find(|l| l.contains(&format!(r#"name="{}""#, v.name)))
            .unwrap();
        for (attr, bound) in [("min", v.range.min), ("max", v.range.max)] {
            match bound {
                Some(b) => {
                    let text = line
                        .split(&format!(r#" {attr}=""#))
                        .nth(1)
                        .and_then(|rest| rest.split('"').next())
                        .unwrap_or_else(|| panic!("{}: no {attr}", v.name));
                    // The declared text reads back to the bound's bits.
                    let read: f64 = text.parse().unwrap();
                    assert_eq!(read.to_bits(), b.to_bits(), "{} {attr}", v.name);
                }
                None => assert!(!line.contains(&format!(" {attr}=")), "{}", v.name),
            }
        }
    }
}
