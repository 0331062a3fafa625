//! Digital filters as MATLAB's Signal Processing Toolbox defines them: `butter`, `cheby1`
//! (bilinear transform with pre-warping, cut-off normalised to the Nyquist frequency),
//! `filter` (direct form II transposed), `filtfilt` (odd reflection of `3 (n - 1)` samples at
//! each end, initial conditions scaled to the first sample), `decimate` (order-8 Chebyshev
//! type I at `0.8 / r`, zero-phase, every `r`-th sample ending on the last one), and central
//! differences.
//!
//! These are the operations of the EMPS benchmark's IDIM-LS script and of the crane paper's
//! data processing; reproducing their conventions is what makes the published numbers come
//! out.
//!
//! Nothing here panics on short signals or slow sampling: the `try_` constructors return a
//! [`SignalError`]; [`butter`] and [`cheby1`] return the identity filter when the cut-off is
//! at or above the Nyquist frequency (a low-pass there removes nothing). Runs are decimated
//! one by one ([`decimate_each`]), never after concatenation, so that the columns of a
//! regression built from several runs stay aligned sample by sample.

/// Highest filter order accepted by the `try_` constructors (the bilinear transform of a
/// higher-order prototype is ill-conditioned in double precision).
pub const MAX_ORDER: usize = 16;

/// Why a filter cannot be built or a signal processed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SignalError {
    /// The normalised cut-off (relative to Nyquist) is not in (0, 1): for a sampling period
    /// `dt` and a cut-off `f` [Hz], `wn = 2 f dt`; `wn >= 1` means the data are sampled too
    /// slowly for that cut-off.
    #[error("cut-off {wn} of Nyquist is outside (0, 1) (sampled too slowly for the cut-off, or a non-positive cut-off)")]
    Cutoff {
        /// The normalised cut-off.
        wn: f64,
    },
    /// Filter order 0 or above [`MAX_ORDER`].
    #[error("filter order {order} is outside 1..={MAX_ORDER}")]
    Order {
        /// The order asked for.
        order: usize,
    },
    /// Decimation factor 0.
    #[error("decimation factor must be >= 1")]
    Factor,
}

/// A transfer function `B(z) / A(z)` in powers of `z^-1`, `a[0] = 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Filter {
    /// Numerator coefficients.
    pub b: Vec<f64>,
    /// Denominator coefficients (`a[0] = 1`).
    pub a: Vec<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct C64 {
    re: f64,
    im: f64,
}

impl C64 {
    fn new(re: f64, im: f64) -> Self {
        C64 { re, im }
    }
    fn mul(self, o: C64) -> C64 {
        C64::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn div(self, o: C64) -> C64 {
        let d = o.re * o.re + o.im * o.im;
        C64::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    fn add(self, o: C64) -> C64 {
        C64::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C64) -> C64 {
        C64::new(self.re - o.re, self.im - o.im)
    }
    fn scale(self, s: f64) -> C64 {
        C64::new(self.re * s, self.im * s)
    }
}

/// Monic polynomial with the given roots (complex roots in conjugate pairs): real
/// coefficients, highest power first.
fn poly(roots: &[C64]) -> Vec<f64> {
    let mut c = vec![C64::new(1.0, 0.0)];
    for &r in roots {
        let mut next = vec![C64::new(0.0, 0.0); c.len() + 1];
        for (k, &ck) in c.iter().enumerate() {
            next[k] = next[k].add(ck);
            next[k + 1] = next[k + 1].sub(ck.mul(r));
        }
        c = next;
    }
    c.into_iter().map(|z| z.re).collect()
}

fn check_design(n: usize, wn: f64) -> Result<(), SignalError> {
    if n == 0 || n > MAX_ORDER {
        return Err(SignalError::Order { order: n });
    }
    if !(wn > 0.0 && wn < 1.0) {
        return Err(SignalError::Cutoff { wn });
    }
    Ok(())
}

/// Low-pass digital filter from an analog prototype's poles and gain (no finite zeros),
/// cut-off `wn` in (0, 1) relative to Nyquist (checked by the callers), by the bilinear
/// transform with pre-warping.
fn lowpass_from_prototype(poles: &[C64], gain: f64, wn: f64) -> Filter {
    let fs = 2.0;
    let warped = 2.0 * fs * libm::tan(core::f64::consts::PI * wn / fs);
    let n = poles.len();
    let pa: Vec<C64> = poles.iter().map(|p| p.scale(warped)).collect();
    let ka = (0..n).fold(gain, |a, _| a * warped);
    let fs2 = C64::new(2.0 * fs, 0.0);
    let pd: Vec<C64> = pa.iter().map(|&p| fs2.add(p).div(fs2.sub(p))).collect();
    let mut den = C64::new(1.0, 0.0);
    for &p in &pa {
        den = den.mul(fs2.sub(p));
    }
    let kd = C64::new(ka, 0.0).div(den).re;
    let zd = vec![C64::new(-1.0, 0.0); n];
    let b = poly(&zd).into_iter().map(|c| c * kd).collect();
    let a = poly(&pd);
    Filter { b, a }
}

/// Butterworth low-pass of order `n`, cut-off `wn` relative to Nyquist (MATLAB `butter(n, wn)`).
///
/// Never panics: a cut-off at or above Nyquist (`wn >= 1`, slow sampling) removes nothing and
/// gives the identity filter, and so does a degenerate request (order 0 or above
/// [`MAX_ORDER`], `wn <= 0` or NaN). Use [`try_butter`] to reject those.
pub fn butter(n: usize, wn: f64) -> Filter {
    try_butter(n, wn).unwrap_or_else(|_| Filter::identity())
}

/// Butterworth low-pass of order `n` in 1..=[`MAX_ORDER`], cut-off `wn` in (0, 1) relative to
/// Nyquist, or the reason it cannot be built.
pub fn try_butter(n: usize, wn: f64) -> Result<Filter, SignalError> {
    check_design(n, wn)?;
    let poles: Vec<C64> = (0..n)
        .map(|k| {
            let th = core::f64::consts::PI * (2 * k + n + 1) as f64 / (2 * n) as f64;
            C64::new(libm::cos(th), libm::sin(th))
        })
        .collect();
    Ok(lowpass_from_prototype(&poles, 1.0, wn))
}

/// Chebyshev type I low-pass of order `n`, pass-band ripple `rp` dB, pass-band edge `wn`
/// relative to Nyquist (MATLAB `cheby1(n, rp, wn)`). Never panics: identity filter where
/// [`try_cheby1`] fails (as [`butter`]).
pub fn cheby1(n: usize, rp: f64, wn: f64) -> Filter {
    try_cheby1(n, rp, wn).unwrap_or_else(|_| Filter::identity())
}

/// Chebyshev type I low-pass (as [`cheby1`]), or the reason it cannot be built; the ripple
/// `rp` must be positive and finite (reported as a bad cut-off otherwise).
pub fn try_cheby1(n: usize, rp: f64, wn: f64) -> Result<Filter, SignalError> {
    check_design(n, wn)?;
    if !(rp > 0.0 && rp.is_finite()) {
        return Err(SignalError::Cutoff { wn: rp });
    }
    let eps = libm::sqrt(libm::pow(10.0, 0.1 * rp) - 1.0);
    let mu = libm::asinh(1.0 / eps) / n as f64;
    let poles: Vec<C64> = (1..=n)
        .map(|k| {
            let th = core::f64::consts::PI * (2 * k - 1) as f64 / (2 * n) as f64;
            C64::new(
                -libm::sinh(mu) * libm::sin(th),
                libm::cosh(mu) * libm::cos(th),
            )
        })
        .collect();
    let mut prod = C64::new(1.0, 0.0);
    for &p in &poles {
        prod = prod.mul(p.scale(-1.0));
    }
    let mut gain = prod.re;
    if n & 1 == 0 {
        gain /= libm::sqrt(1.0 + eps * eps);
    }
    Ok(lowpass_from_prototype(&poles, gain, wn))
}

impl Filter {
    /// The identity `B = A = 1` (what a low-pass above Nyquist amounts to).
    pub fn identity() -> Filter {
        Filter {
            b: vec![1.0],
            a: vec![1.0],
        }
    }

    fn order(&self) -> usize {
        self.a.len().max(self.b.len()).saturating_sub(1)
    }

    fn padded(&self) -> (Vec<f64>, Vec<f64>) {
        let n = self.order() + 1;
        let a0 = self.a.first().copied().unwrap_or(1.0);
        let mut b: Vec<f64> = self.b.iter().map(|v| v / a0).collect();
        let mut a: Vec<f64> = self.a.iter().map(|v| v / a0).collect();
        b.resize(n, 0.0);
        a.resize(n, 0.0);
        (b, a)
    }

    /// Direct form II transposed with initial state `zi` (MATLAB `filter(b, a, x, zi)`).
    pub fn lfilter(&self, x: &[f64], zi: Option<&[f64]>) -> Vec<f64> {
        let (b, a) = self.padded();
        let m = b.len() - 1;
        let mut z = match zi {
            Some(z) => z.to_vec(),
            None => vec![0.0; m],
        };
        z.resize(m, 0.0);
        let mut y = Vec::with_capacity(x.len());
        for &xi in x {
            let yi = b[0] * xi + if m > 0 { z[0] } else { 0.0 };
            for k in 0..m {
                let next = if k + 1 < m { z[k + 1] } else { 0.0 };
                z[k] = b[k + 1] * xi + next - a[k + 1] * yi;
            }
            y.push(yi);
        }
        y
    }

    /// Steady-state initial conditions for a unit step (as MATLAB's `filtfilt` computes them).
    pub fn zi(&self) -> Vec<f64> {
        let (b, a) = self.padded();
        let m = b.len() - 1;
        if m == 0 {
            return Vec::new();
        }
        // (I - A^T) zi = b[1..] - a[1..] b[0], A the companion form of DF-II transposed.
        let mut mat = vec![vec![0.0; m]; m];
        for (i, row) in mat.iter_mut().enumerate() {
            row[i] = 1.0;
            row[0] += a[i + 1];
            if i + 1 < m {
                row[i + 1] -= 1.0;
            }
        }
        let rhs: Vec<f64> = (0..m).map(|i| b[i + 1] - a[i + 1] * b[0]).collect();
        crate::linalg::solve_dense(mat, rhs).unwrap_or_else(|| vec![0.0; m])
    }

    /// Zero-phase forward-backward filtering (MATLAB `filtfilt(b, a, x)`): the signal is
    /// extended at both ends by odd reflection of `3 (n - 1)` samples (`n` the filter length),
    /// each pass starts from the steady state of its first sample. Signals shorter than the
    /// extension are reflected as far as they go.
    pub fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        let len = x.len();
        if len < 2 {
            return x.to_vec();
        }
        let nfact = (3 * self.order()).min(len - 1);
        let mut ext = Vec::with_capacity(len + 2 * nfact);
        for i in (1..=nfact).rev() {
            ext.push(2.0 * x[0] - x[i]);
        }
        ext.extend_from_slice(x);
        for i in 1..=nfact {
            ext.push(2.0 * x[len - 1] - x[len - 1 - i]);
        }
        let zi = self.zi();
        let z0: Vec<f64> = zi.iter().map(|z| z * ext[0]).collect();
        let mut y = self.lfilter(&ext, Some(&z0));
        y.reverse();
        let z1: Vec<f64> = zi.iter().map(|z| z * y[0]).collect();
        let mut y2 = self.lfilter(&y, Some(&z1));
        y2.reverse();
        y2[nfact..nfact + len].to_vec()
    }

    /// Gain at normalised frequency `w` (relative to Nyquist).
    pub fn gain(&self, w: f64) -> f64 {
        let th = core::f64::consts::PI * w;
        let eval = |c: &[f64]| {
            let mut s = C64::new(0.0, 0.0);
            for (k, &ck) in c.iter().enumerate() {
                let ang = -th * k as f64;
                s = s.add(C64::new(libm::cos(ang), libm::sin(ang)).scale(ck));
            }
            libm::sqrt(s.re * s.re + s.im * s.im)
        };
        eval(&self.b) / eval(&self.a)
    }
}

/// Zero-phase low-pass: Butterworth of `order` at `cutoff_hz` for sampling period `dt`,
/// applied forwards and backwards.
pub fn lowpass_zero_phase(x: &[f64], order: usize, cutoff_hz: f64, dt: f64) -> Vec<f64> {
    let wn = cutoff_hz * 2.0 * dt;
    butter(order, wn).filtfilt(x)
}

/// MATLAB `decimate(x, r)` with its default IIR filter: Chebyshev type I of order 8, 0.05 dB
/// ripple, pass-band edge `0.8 / r`, applied with `filtfilt`; then every `r`-th sample, the
/// last one included. If the order-8 filter has lost its pass-band (as MATLAB checks), the
/// order is lowered.
pub fn decimate(x: &[f64], r: usize) -> Vec<f64> {
    if r <= 1 {
        return x.to_vec();
    }
    let wn = 0.8 / r as f64;
    let mut order = 8;
    let mut f = cheby1(order, 0.05, wn);
    // MATLAB: reduce the order while the gain at the edge is not -rip dB (ill-conditioned).
    while order > 1 && (20.0 * libm::log10(f.gain(wn)) + 0.05).abs() > 1e-6 {
        order -= 1;
        f = cheby1(order, 0.05, wn);
    }
    let y = f.filtfilt(x);
    let nd = y.len();
    let nout = nd.div_ceil(r);
    // MATLAB 1-based nbeg = r - (r*nout - nd); 0-based start = nbeg - 1.
    let nbeg = r + nd - r * nout;
    y.iter().skip(nbeg - 1).step_by(r).copied().collect()
}

/// Length of [`decimate`]`(x, r)` for a signal of `n` samples: `ceil(n / r)` (`n` for
/// `r <= 1`).
pub fn decimated_len(n: usize, r: usize) -> usize {
    if r <= 1 {
        n
    } else {
        n.div_ceil(r)
    }
}

/// Decimates every run on its own ([`decimate`], same factor) and concatenates the results.
///
/// This is the only correct way to decimate data made of several runs: decimating the
/// concatenation keeps samples at other places (the kept samples end on the *last* sample of
/// the whole signal) and filters across the joints between runs, so a force decimated run by
/// run and regressors decimated after concatenation end up shifted against each other. With
/// this helper every column built from the same runs has the same length, `sum of
/// ceil(n_i / r)`, and sample `j` of every column comes from the same instant.
pub fn decimate_each<S: AsRef<[f64]>>(runs: &[S], r: usize) -> Result<Vec<f64>, SignalError> {
    if r == 0 {
        return Err(SignalError::Factor);
    }
    let total = runs
        .iter()
        .map(|x| decimated_len(x.as_ref().len(), r))
        .sum();
    let mut out = Vec::with_capacity(total);
    for x in runs {
        out.extend(decimate(x.as_ref(), r));
    }
    Ok(out)
}

/// Central differences `(x[k+1] - x[k-1]) / (2 dt)`, one-sided at the ends.
pub fn diff_central(x: &[f64], dt: f64) -> Vec<f64> {
    let n = x.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let mut d = vec![0.0; n];
    d[0] = (x[1] - x[0]) / dt;
    d[n - 1] = (x[n - 1] - x[n - 2]) / dt;
    for k in 1..n - 1 {
        d[k] = (x[k + 1] - x[k - 1]) / (2.0 * dt);
    }
    d
}

/// Second central differences `(x[k+1] - 2 x[k] + x[k-1]) / dt^2`, copied at the ends.
pub fn diff2_central(x: &[f64], dt: f64) -> Vec<f64> {
    let n = x.len();
    if n < 3 {
        return vec![0.0; n];
    }
    let mut d = vec![0.0; n];
    for k in 1..n - 1 {
        d[k] = (x[k + 1] - 2.0 * x[k] + x[k - 1]) / (dt * dt);
    }
    d[0] = d[1];
    d[n - 1] = d[n - 2];
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slow_sampling_and_short_runs_do_not_panic() {
        // 200 Hz data with a 100 Hz cut-off: wn = 1, nothing to filter
        let x: Vec<f64> = (0..5).map(|k| k as f64).collect();
        assert_eq!(butter(4, 1.0), Filter::identity());
        assert_eq!(butter(4, 1.0).filtfilt(&x), x);
        assert_eq!(
            try_butter(4, 1.0),
            Err(SignalError::Cutoff { wn: 1.0 }),
            "the fallible constructor says why"
        );
        assert!(matches!(
            try_butter(4, f64::NAN),
            Err(SignalError::Cutoff { .. })
        ));
        assert_eq!(try_butter(0, 0.5), Err(SignalError::Order { order: 0 }));
        assert!(try_cheby1(8, 0.05, 0.2).is_ok());
        assert!(try_cheby1(8, -1.0, 0.2).is_err());
        for n in 0..4 {
            let y: Vec<f64> = (0..n).map(|k| k as f64).collect();
            assert_eq!(decimate(&y, 10).len(), decimated_len(n, 10));
            assert_eq!(butter(4, 0.2).filtfilt(&y).len(), n);
            assert_eq!(diff_central(&y, 0.01).len(), n);
            assert_eq!(diff2_central(&y, 0.01).len(), n);
        }
        // a hand-made degenerate filter does not index out of bounds
        let empty = Filter {
            b: vec![],
            a: vec![],
        };
        assert_eq!(empty.filtfilt(&x).len(), x.len());
    }

    #[test]
    fn decimate_each_keeps_runs_aligned() {
        // two runs of different lengths: a ramp (time index) and its double, decimated per
        // run, stay in the ratio 2 sample by sample; decimating the concatenation would not
        // even give the same length
        let runs: Vec<Vec<f64>> = vec![
            (0..1005).map(|k| k as f64).collect(),
            (0..998).map(|k| 1000.0 + k as f64).collect(),
        ];
        let doubled: Vec<Vec<f64>> = runs
            .iter()
            .map(|r| r.iter().map(|v| 2.0 * v).collect())
            .collect();
        let a = decimate_each(&runs, 10).unwrap();
        let b = decimate_each(&doubled, 10).unwrap();
        assert_eq!(a.len(), decimated_len(1005, 10) + decimated_len(998, 10));
        assert_eq!(a.len(), 101 + 100);
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!((2.0 * x - y).abs() < 1e-6 * y.abs().max(1.0), "{x} {y}");
        }
        let concat: Vec<f64> = runs.concat();
        // decimating the concatenation keeps other instants (here 2 samples earlier)
        let c = decimate(&concat, 10);
        assert!((a[50] - c[50]).abs() > 1.0, "{} {}", a[50], c[50]);
        assert_eq!(decimate_each(&runs, 0), Err(SignalError::Factor));
        assert_eq!(decimate_each(&runs, 1).unwrap(), concat);
    }

    #[test]
    fn butter_matches_matlab_coefficients() {
        // MATLAB: [b,a] = butter(4, 0.2)
        let f = butter(4, 0.2);
        let b = [
            0.0048243433,
            0.0192973731,
            0.0289460597,
            0.0192973731,
            0.0048243433,
        ];
        let a = [
            1.0,
            -2.3695130072,
            2.3139884144,
            -1.0546654058,
            0.1873794924,
        ];
        for (x, y) in f.b.iter().zip(b) {
            assert!((x - y).abs() < 1e-9, "{:?}", f.b);
        }
        for (x, y) in f.a.iter().zip(a) {
            assert!((x - y).abs() < 1e-9, "{:?}", f.a);
        }
        assert!((f.gain(0.2) - libm::sqrt(0.5)).abs() < 1e-9);
    }

    #[test]
    fn cheby1_has_its_ripple_at_the_edge_and_unit_gain_ripple_band() {
        let f = cheby1(8, 0.05, 0.08);
        let db = 20.0 * libm::log10(f.gain(0.08));
        assert!((db + 0.05).abs() < 1e-6, "{db}");
        // even order: DC gain is the bottom of the ripple
        let dc = 20.0 * libm::log10(f.gain(0.0));
        assert!((dc + 0.05).abs() < 1e-6, "{dc}");
        assert!(f.gain(0.2) < 1e-3);
    }

    #[test]
    fn filtfilt_keeps_a_ramp_and_kills_high_frequency() {
        let n = 2000;
        let dt = 0.002;
        let x: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                0.3 * t + 0.01 * libm::sin(2.0 * core::f64::consts::PI * 60.0 * t)
            })
            .collect();
        let y = lowpass_zero_phase(&x, 4, 3.0, dt);
        // (the end transients of MATLAB's short padding last a few time constants)
        for (k, v) in y.iter().enumerate().skip(500).take(n - 1000) {
            let t = k as f64 * dt;
            assert!((v - 0.3 * t).abs() < 1e-5, "{k} {v}");
        }
    }

    #[test]
    fn decimate_picks_every_rth_ending_on_last() {
        let w = 2.0 * core::f64::consts::PI / 400.0;
        let x: Vec<f64> = (0..1005).map(|k| 3.0 + libm::sin(w * k as f64)).collect();
        let y = decimate(&x, 10);
        assert_eq!(y.len(), 101);
        // a slow sine passes the anti-aliasing filter (times its squared pass-band gain, the
        // bottom of the 0.05 dB ripple at DC, as in MATLAB); samples 4, 14, ..., 1004 are kept
        let g2 = libm::pow(10.0, -0.05 / 10.0);
        for (j, v) in y.iter().enumerate().skip(20).take(60) {
            let k = 4 + 10 * j;
            assert!((v - g2 * x[k]).abs() < 5e-3, "{j} {v} {}", x[k]);
        }
        let c = decimate(&[2.5; 57], 4);
        assert_eq!(c.len(), 15);
        assert!(c.iter().all(|v| (v - 2.5 * g2).abs() < 1e-9), "{c:?}");
    }
}
