//! The model computes `sin` and `cos` of one angle with `libm::sincos` (one argument
//! reduction instead of two) where NUMERICS.md writes `libm::sin` and `libm::cos`, and the
//! reference calls those two. That is only allowed because `sincos` returns the very same
//! bits; this test checks it over the angles the model meets and well beyond.

use crane_ident::rng::Rng;

/// `None` if `sincos(x)` equals `(sin(x), cos(x))` bit for bit, else a description.
fn mismatch(x: f64) -> Option<String> {
    let (s, c) = libm::sincos(x);
    let (s0, c0) = (libm::sin(x), libm::cos(x));
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    if same(s, s0) && same(c, c0) {
        None
    } else {
        Some(format!(
            "x = {x:e} ({:#018x}): sincos ({s:e}, {c:e}) vs sin, cos ({s0:e}, {c0:e})",
            x.to_bits()
        ))
    }
}

#[test]
fn sincos_gives_the_bits_of_sin_and_cos() {
    let mut checked = 0usize;
    let mut check = |x: f64| {
        checked += 1;
        if let Some(m) = mismatch(x) {
            panic!("{m}");
        }
    };
    // Dense over the swing domain (alpha in pi/2 +- 1.4, beta in +-1.4) and beyond: [-8, 8].
    let n = 2_000_000;
    for k in 0..=n {
        check(-8.0 + 16.0 * f64::from(k) / f64::from(n));
    }
    // Near the thresholds where sin and sincos take different early exits
    // (|x| < 2^-26 in sin, |x| < 2^-27 sqrt 2 in sincos and cos), both signs.
    let mut x = 2f64.powi(-30);
    while x < 2f64.powi(-20) {
        check(x);
        check(-x);
        x = f64::from_bits(x.to_bits() + 0x0000_0010_0000_0001);
    }
    // Random bit patterns (every exponent, subnormals, huge arguments), and random angles
    // near pi/2, the hanging position.
    let mut rng = Rng::new(1);
    for _ in 0..2_000_000 {
        check(f64::from_bits(rng.next_u64()));
        let u = rng.uniform();
        check(core::f64::consts::FRAC_PI_2 + 2.8 * (u - 0.5));
    }
    for x in [
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        1e300,
    ] {
        check(x);
    }
    for x in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
        check(x);
    }
    assert!(checked > 6_000_000);
}

/// `crane_model::hangs` answers `true` inside the swing stops without computing
/// `sin(alpha) cos(beta) >= MIN_HANG`; the formula gives the same answer everywhere (f64 and
/// f32), so the model's domain checks keep the reference's decisions.
#[test]
fn hangs_shortcut_gives_the_formulas_answer() {
    use crane_model::{hangs, MIN_HANG, SWING_STOP};
    let half_pi = core::f64::consts::FRAC_PI_2;
    let mut rng = Rng::new(2);
    let (mut in_box, mut out_of_domain) = (0usize, 0usize);
    for k in 0..2_000_000u32 {
        let u = |r: &mut Rng| r.uniform();
        // alpha over (0, pi), beta over (-pi/2, pi/2), denser near the box edges.
        let (a, b) = if k % 2 == 0 {
            (
                core::f64::consts::PI * u(&mut rng),
                3.1 * (u(&mut rng) - 0.5),
            )
        } else {
            let ea = (half_pi + SWING_STOP) + 1e-3 * (u(&mut rng) - 0.5);
            let eb = SWING_STOP + 1e-3 * (u(&mut rng) - 0.5);
            (
                if k % 4 == 1 {
                    ea
                } else {
                    half_pi - (ea - half_pi)
                },
                eb,
            )
        };
        let formula = libm::sin(a) * libm::cos(b) >= MIN_HANG;
        assert_eq!(hangs(a, b), formula, "f64 alpha {a} beta {b}");
        let (af, bf) = (a as f32, b as f32);
        let formula32 = libm::sinf(af) * libm::cosf(bf) >= MIN_HANG as f32;
        assert_eq!(hangs(af, bf), formula32, "f32 alpha {af} beta {bf}");
        let boxed = a >= half_pi - SWING_STOP && a <= half_pi + SWING_STOP && b.abs() <= SWING_STOP;
        in_box += usize::from(boxed);
        out_of_domain += usize::from(!formula);
    }
    assert!(hangs(half_pi, 0.0) && !hangs(f64::NAN, 0.0) && !hangs(0.01, 1.55));
    // Both answers, and both sides of the box edges, were exercised.
    assert!(
        in_box > 500_000 && out_of_domain > 10_000,
        "{in_box} {out_of_domain}"
    );
}
