//! The model computes `sin` and `cos` of one angle with `libm::sincos` (one argument
//! reduction instead of two) where NUMERICS.md writes `libm::sin` and `libm::cos`, and the
//! reference calls those two. That is only allowed because `sincos` returns the very same
//! bits; this test checks it over the angles the model meets and well beyond.

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

/// xorshift64* (deterministic).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
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
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for _ in 0..2_000_000 {
        check(f64::from_bits(rng.next()));
        let u = (rng.next() >> 11) as f64 / (1u64 << 53) as f64;
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
