//! Candidate-list selection: the sort [`key`]s that pack a reduced cost and its
//! column into one `u64`, and the streaming selection of a row's `k` smallest keys
//! ([`select_k`]) that the sparse strategy builds its per-row candidate lists with.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Width of the blocks the streaming row scans test at once.
const LANES: usize = 8;
// `block_min` reduces exactly eight lanes.
const _: () = assert!(LANES == 8);

/// Order-preserving map of a finite or infinite `f64` (not NaN) to `u64`; `-0.0`
/// is folded into `0.0` so that the order agrees with `==`.
#[inline]
pub(super) fn ord_bits(w: f64) -> u64 {
    let b = (w + 0.0).to_bits();
    if b >> 63 == 0 {
        b | 1 << 63
    } else {
        !b
    }
}

/// Inverse of [`ord_bits`].
#[inline]
pub(super) fn from_ord_bits(o: u64) -> f64 {
    f64::from_bits(if o >> 63 == 1 { o & !(1 << 63) } else { !o })
}

/// Sort key of the pair `(w, col)`: the order bits of `w` with the low mantissa bits
/// (`mask`) replaced by the column. Keys are totally ordered, and a key bounds its
/// `w` from below: `w >= key_floor(key)`. Low-bit truncation costs about `mask / 2^52`
/// relative precision in the bounds only, never in the costs.
#[inline]
pub(super) fn key(w: f64, col: u32, mask: u64) -> u64 {
    (ord_bits(w) & !mask) | u64::from(col)
}

/// The largest `f64` not above any `w` whose [`key`] is at least `k`.
#[inline]
pub(super) fn key_floor(k: u64, mask: u64) -> f64 {
    if k & !mask == 0 {
        f64::NEG_INFINITY
    } else {
        from_ord_bits(k & !mask)
    }
}

/// The column of a [`key`].
#[inline]
pub(super) fn key_col(k: u64, mask: u64) -> u32 {
    (k & mask) as u32
}

/// Streaming selection of the `k` smallest [`key`]s `key(w, col)`, `w = row[col] -
/// v[col]` finite, that are at least `lo`. `thr0` is an inclusive upper bound on the
/// `k`-th smallest `w` when one is known (`+inf` otherwise). Columns enter the keys
/// XOR-ed with `salt` (ties between equal `w` break in a per-row order). The keys are left sorted
/// in `buf[..n]`; `buf.len() >= 2k` is the scratch. With `check` and `lo == 0`, also
/// returns the first column whose `w` is NaN or `-inf`. `BELOW` says whether `lo`
/// bounds anything (`false` requires `lo == 0`).
///
/// # Complexity
/// One pass over the row; blocks of [`LANES`] entries are tested against the current
/// threshold at once, admitted entries are appended to `buf`, and `buf` is cut back to
/// the best `k` (linear-time selection) when full, so the work beyond the streaming
/// compare is `O(admitted + k log k)`.
#[allow(clippy::too_many_arguments)]
pub(super) fn select_k<const BELOW: bool>(
    row: &[f64],
    v: &[f64],
    k: usize,
    mask: u64,
    lo: u64,
    thr0: f64,
    check: bool,
    salt: u32,
    buf: &mut [u64],
) -> (usize, Option<usize>) {
    let cap = buf.len();
    debug_assert!(k >= 1 && cap >= 2 * k);
    let lo_w = key_floor(lo, mask);
    let mut n = 0usize;
    // Keys above `thr_key` are rejected; `thr` is a float upper bound of the `w` of
    // any key up to `thr_key` (for the block prefilter).
    let (mut thr_key, mut thr) = if thr0 < f64::INFINITY {
        (ord_bits(thr0) | mask, thr0)
    } else {
        (u64::MAX, f64::INFINITY)
    };
    let mut bad = None;
    let mut admit = |w: f64, col: u32, n: &mut usize, thr_key: &mut u64, thr: &mut f64| {
        if !(w > f64::NEG_INFINITY) {
            // NaN or -inf (only reachable here when `lo` admits everything).
            if check && bad.is_none() {
                bad = Some(col as usize);
            }
        } else if w < f64::INFINITY && !(w > *thr) {
            // (`thr` here too, not only in the block filter: the row's tail skips it.)
            let kk = key(w, col ^ salt, mask);
            if kk >= lo && kk <= *thr_key {
                buf[*n] = kk;
                *n += 1;
                if *n == cap {
                    let (_, kth, _) = buf.select_nth_unstable(k - 1);
                    *thr_key = *kth;
                    *thr = from_ord_bits(*kth | mask).min(thr0);
                    *n = k;
                }
            }
        }
    };
    let mut sums = [0.0f64; LANES];
    let rch = row.chunks_exact(LANES);
    let vch = v.chunks_exact(LANES);
    let (rt, vt) = (rch.remainder(), vch.remainder());
    let mut base = 0u32;
    for (r, vv) in rch.zip(vch) {
        let mut hits = 0u32;
        if BELOW {
            for (l, (a, b)) in r.iter().zip(vv).enumerate() {
                let w = a - b;
                // Candidates, and also NaN (every comparison false).
                hits |= u32::from(!((w > thr) | (w < lo_w))) << l;
            }
        } else if let (Ok(r8), Ok(v8)) =
            (<&[f64; LANES]>::try_from(r), <&[f64; LANES]>::try_from(vv))
        {
            let w: [f64; LANES] = std::array::from_fn(|l| r8[l] - v8[l]);
            if check {
                for (s, x) in sums.iter_mut().zip(&w) {
                    *s += x;
                }
            }
            if block_min(&w) > thr {
                base += LANES as u32;
                continue;
            }
            for (l, x) in w.iter().enumerate() {
                hits |= u32::from(!(*x > thr)) << l;
            }
        }
        while hits != 0 {
            let l = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            admit(
                r[l] - vv[l],
                base + l as u32,
                &mut n,
                &mut thr_key,
                &mut thr,
            );
        }
        base += LANES as u32;
    }
    for (l, (a, b)) in rt.iter().zip(vt).enumerate() {
        admit(a - b, base + l as u32, &mut n, &mut thr_key, &mut thr);
    }
    // The block filter of the unbounded selection may skip NaN lanes: a NaN or `-inf`
    // cost makes the sum of the row's `c - v` NaN or `-inf` (prices are never NaN,
    // and a `-inf` price only comes with a `-inf` cost in its column).
    if !BELOW && check && bad.is_none() && !(sums.iter().sum::<f64>() > f64::NEG_INFINITY) {
        bad = row.iter().position(|&c| !(c > f64::NEG_INFINITY));
    }
    if n > k {
        buf[..n].select_nth_unstable(k - 1);
        n = k;
    }
    buf[..n].sort_unstable();
    (n, bad)
}

/// Smallest entry of a block of [`LANES`] reduced costs, as a branch-free reduction
/// tree (NaN lanes may be skipped: callers detect NaN separately).
#[inline(always)]
fn block_min(w: &[f64; LANES]) -> f64 {
    #[inline(always)]
    fn mn(a: f64, b: f64) -> f64 {
        if a < b {
            a
        } else {
            b
        }
    }
    let a: [f64; 4] = std::array::from_fn(|l| mn(w[l], w[l + 4]));
    let b = [mn(a[0], a[2]), mn(a[1], a[3])];
    mn(b[0], b[1])
}
