//! Error of the FPU-only sine and cosine of `F32x` against the correctly rounded value
//! (libm's f64 `sin`/`cos`, rounded): measured over every f32 in the swing's range.

use crane_twin::logic::fastmath::sincosf;

/// Largest error [ulp of the result, and absolute] over all f32 in `[lo, hi]`, every `step`-th.
fn max_err(lo: f32, hi: f32, step: u32) -> (f64, f64, f32) {
    let (mut ulp_max, mut abs_max, mut at) = (0.0f64, 0.0f64, 0.0f32);
    let mut x = lo;
    while x <= hi {
        let (s, c) = sincosf(x);
        for (got, want) in [(s, libm::sin(f64::from(x))), (c, libm::cos(f64::from(x)))] {
            let e = (f64::from(got) - want).abs();
            let ulp = f64::from(f32::EPSILON) * want.abs().max(f64::from(f32::MIN_POSITIVE));
            let u = e / ulp;
            if u > ulp_max {
                ulp_max = u;
                at = x;
            }
            abs_max = abs_max.max(e);
        }
        let b = x.to_bits();
        x = if x >= 0.0 {
            f32::from_bits(b + step)
        } else if b - step > 0x8000_0000 {
            f32::from_bits(b - step)
        } else {
            0.0
        };
    }
    (ulp_max, abs_max, at)
}

#[test]
fn sincosf_error_is_bounded() {
    // The swing angles: alpha in (0, pi), beta in (-pi/2, pi/2); and a wider band.
    let (ulp, abs, at) = max_err(-4.0, 4.0, 97);
    println!("[-4, 4]: max error {ulp:.2} ulp (at {at}), {abs:.3e} absolute");
    assert!(abs < 2.4e-7, "absolute error {abs}");
    // Relative error away from the zeros of sin/cos (where ulps shrink to nothing).
    let (ulp, _, at) = max_err(0.1, 1.4, 13);
    println!("[0.1, 1.4]: max error {ulp:.2} ulp (at {at})");
    assert!(ulp < 2.0, "{ulp} ulp at {at}");
    let (_, abs, _) = max_err(-100.0, 100.0, 101);
    assert!(abs < 1e-6, "absolute error {abs} on [-100, 100]");
    assert!(sincosf(f32::NAN).0.is_nan() && sincosf(f32::INFINITY).1.is_nan());
}
