//! The travel's level: the median of a move's judged deviations, selected on their integer
//! keys ([`map::total_key`]) bit for bit as on the `f32`s.

use super::map::{self, BINS};

/// Median of the `f32` values whose [`map::total_key`]s are `keys[..below]` and
/// `keys[BINS - above..]` (reordered), 0 if there are none: the element at
/// `(below + above) / 2` in [`f32::total_cmp`]'s order. Every key of the first part is
/// below every key of the second
/// ([`SlidingMap::judged_bands`](map::SlidingMap::judged_bands) split them around a pivot),
/// so the element is selected in the one part that holds it: about half the keys when the
/// pivot is near the median (the travel's previous level). Any selection gives that element,
/// bit for bit, as `select_nth_unstable_by(n / 2, f32::total_cmp)` on the `f32`s did (the
/// keys have the same order); on the integer keys a comparison is one instruction.
pub(super) fn median_of_split_keys(keys: &mut [i32; BINS], below: usize, above: usize) -> f32 {
    let k = (below + above) / 2;
    let m = if k < below {
        keys.get_mut(..below).and_then(|a| select_key(a, k))
    } else {
        let from = BINS.saturating_sub(above);
        keys.get_mut(from..).and_then(|a| select_key(a, k - below))
    };
    m.map_or(0.0, map::from_total_key)
}

/// The `k`-th smallest of `a` (0-based; `a` is reordered), `None` unless `k < a.len()`:
/// `select_nth_unstable` (introselect, linear in the worst case), kept out of line (inlined
/// into [`Monitor::move_done`](super::Monitor::move_done) it measured twice the instructions).
#[inline(never)]
fn select_key(a: &mut [i32], k: usize) -> Option<i32> {
    if k >= a.len() {
        return None;
    }
    Some(*a.select_nth_unstable(k).1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The old median: `select_nth_unstable_by(n / 2, f32::total_cmp)` on the `f32`s.
    fn median_by_total_cmp(v: &mut [f32]) -> f32 {
        let n = v.len();
        if n == 0 {
            return 0.0;
        }
        *v.select_nth_unstable_by(n / 2, f32::total_cmp).1
    }

    #[test]
    fn the_median_of_the_keys_is_the_total_cmp_median_bit_for_bit() {
        let mut rng = crane_ident::rng::Rng::new(0x2545_f491_4f6c_dd1d);
        let mut next = || rng.next_u64();
        let specials = [0.0f32, -0.0, 1.0, -1.0, f32::MIN_POSITIVE, -f32::MAX, 1e-3];
        for round in 0..4000 {
            let n = (next() % (BINS as u64 + 1)) as usize;
            let mut v = [0.0f32; BINS];
            for x in v.iter_mut().take(n) {
                let r = next();
                *x = match round % 4 {
                    // few distinct values: many ties
                    0 => specials[(r % specials.len() as u64) as usize],
                    // sorted runs and reversed runs
                    1 => (r % 16) as f32 * 0.125 - 1.0,
                    _ => (r as i64 as f64 / 1e18) as f32,
                };
            }
            if round % 8 == 1 {
                v[..n].sort_by(f32::total_cmp);
            } else if round % 8 == 3 {
                v[..n].sort_by(|a, b| b.total_cmp(a));
            }
            // Split around a pivot as `SlidingMap::judged_bands` does: one of the values, or
            // a value of its own.
            let pivot = if n > 0 && round % 3 == 0 {
                map::total_key(v[(next() % n as u64) as usize])
            } else {
                map::total_key((next() as i64 as f64 / 4e18) as f32)
            };
            let mut keys = [0i32; BINS];
            let (mut below, mut above) = (0usize, 0usize);
            for x in &v[..n] {
                let key = map::total_key(*x);
                if key < pivot {
                    keys[below] = key;
                    below += 1;
                } else {
                    above += 1;
                    keys[BINS - above] = key;
                }
            }
            let got = median_of_split_keys(&mut keys, below, above);
            let want = median_by_total_cmp(&mut v[..n]);
            assert_eq!(got.to_bits(), want.to_bits(), "round {round}, n {n}");
            // Every rank, against a sort.
            if n > 0 && round % 16 == 0 {
                let mut sorted = v;
                sorted[..n].sort_by(f32::total_cmp);
                for (rank, want) in sorted.iter().enumerate().take(n) {
                    let mut keys = [0i32; BINS];
                    for (k, x) in keys.iter_mut().zip(&v[..n]) {
                        *k = map::total_key(*x);
                    }
                    let got = select_key(&mut keys[..n], rank).map(map::from_total_key);
                    assert_eq!(got.map(f32::to_bits), Some(want.to_bits()));
                }
            }
        }
        let mut keys = [0i32; BINS];
        assert_eq!(select_key(&mut keys[..3], 3), None);
        assert_eq!(median_of_split_keys(&mut keys, 0, 0), 0.0);
        for x in [0.0f32, -0.0, 1.5, -2.25, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(
                map::from_total_key(map::total_key(x)).to_bits(),
                x.to_bits()
            );
        }
    }
}
