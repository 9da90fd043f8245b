//! Envelope (skyline, profile) storage of the lower triangle of a symmetric matrix,
//! factorised in place into its Cholesky factor `L` (`A = L Lᵀ`): the sparse
//! factorisation of the ARAP systems ([`super::Arap`]).

/// Dot product with four accumulators (lets the compiler vectorise).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        acc[0] += x[0] * y[0];
        acc[1] += x[1] * y[1];
        acc[2] += x[2] * y[2];
        acc[3] += x[3] * y[3];
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        s += x * y;
    }
    s
}

/// Row `i` stores columns `first[i]..=i` contiguously at `vals[start[i]..start[i+1]]`.
#[derive(Clone, Debug)]
pub(super) struct Envelope {
    first: Vec<usize>,
    start: Vec<usize>,
    pub(super) vals: Vec<f64>,
    /// `1 / L[i][i]` after a successful [`Envelope::factor`].
    inv_diag: Vec<f64>,
}

impl Envelope {
    /// Zero matrix with the given first stored column per row (`first[i] <= i`).
    pub(super) fn new(first: Vec<usize>) -> Envelope {
        let n = first.len();
        let first: Vec<usize> = first.iter().enumerate().map(|(i, &f)| f.min(i)).collect();
        let mut start = Vec::with_capacity(n + 1);
        start.push(0);
        for (i, &f) in first.iter().enumerate() {
            start.push(start[i] + (i - f + 1));
        }
        let vals = vec![0.0; start[n]];
        Envelope {
            first,
            start,
            vals,
            inv_diag: vec![0.0; n],
        }
    }

    /// Matrix order.
    pub(super) fn dim(&self) -> usize {
        self.first.len()
    }

    /// Number of stored entries (the profile, diagonal included).
    pub(super) fn stored(&self) -> usize {
        self.vals.len()
    }

    /// Whether entry `(i, j)` (or its mirror) is stored.
    pub(super) fn contains(&self, i: usize, j: usize) -> bool {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        i < self.dim() && j >= self.first[i]
    }

    /// Adds `v` to entry `(i, j)` and its mirror; `false` if outside the envelope.
    pub(super) fn add(&mut self, i: usize, j: usize, v: f64) -> bool {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i >= self.dim() || j < self.first[i] {
            return false;
        }
        self.vals[self.start[i] + j - self.first[i]] += v;
        true
    }

    /// Entry `(i, j)` of the stored lower triangle (0 outside the envelope).
    #[cfg(test)]
    pub(super) fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i >= self.dim() || j < self.first[i] {
            return 0.0;
        }
        self.vals[self.start[i] + j - self.first[i]]
    }

    /// In-place Cholesky factorisation (row-oriented envelope algorithm; the fill
    /// stays inside the envelope). `Err(row)` at the first non-positive or
    /// non-finite pivot.
    pub(super) fn factor(&mut self) -> Result<(), usize> {
        for i in 0..self.dim() {
            let fi = self.first[i];
            let (done, rest) = self.vals.split_at_mut(self.start[i]);
            let row_i = &mut rest[..i - fi + 1];
            for j in fi..i {
                let fj = self.first[j];
                let k0 = fi.max(fj);
                let row_j = &done[self.start[j]..self.start[j + 1]];
                let s = row_i[j - fi] - dot(&row_i[k0 - fi..j - fi], &row_j[k0 - fj..j - fj]);
                row_i[j - fi] = s / row_j[j - fj];
            }
            let off = &row_i[..i - fi];
            let d = row_i[i - fi] - dot(off, off);
            if !(d > 0.0 && d.is_finite()) {
                return Err(i);
            }
            row_i[i - fi] = d.sqrt();
            self.inv_diag[i] = 1.0 / row_i[i - fi];
        }
        Ok(())
    }

    /// Solves `L Lᵀ x = b` in place (after [`Envelope::factor`]).
    ///
    /// The forward pass adds the entry next to the diagonal last and both passes
    /// multiply by the stored reciprocal pivots, which keeps the row-to-row
    /// dependency chain short (it bounds the speed of a triangular solve).
    pub(super) fn solve(&self, b: &mut [f64]) {
        let n = self.dim().min(b.len());
        for i in 0..n {
            let fi = self.first[i];
            let m = i - fi;
            let row = &self.vals[self.start[i]..self.start[i + 1]];
            let s = if m > 0 {
                let head = dot(&row[..m - 1], &b[fi..i - 1]);
                (b[i] - head) - row[m - 1] * b[i - 1]
            } else {
                b[i]
            };
            b[i] = s * self.inv_diag[i];
        }
        for i in (0..n).rev() {
            let fi = self.first[i];
            let row = &self.vals[self.start[i]..self.start[i + 1]];
            let xi = b[i] * self.inv_diag[i];
            b[i] = xi;
            for (bk, l) in b[fi..i].iter_mut().zip(&row[..i - fi]) {
                *bk -= l * xi;
            }
        }
    }

    /// Solves `L Lᵀ X = B` in place for two right-hand sides stored as pairs.
    pub(super) fn solve2(&self, b: &mut [[f64; 2]]) {
        let n = self.dim().min(b.len());
        for i in 0..n {
            let fi = self.first[i];
            let m = i - fi;
            let row = &self.vals[self.start[i]..self.start[i + 1]];
            let (done, rest) = b.split_at_mut(i);
            let mut s = rest[0];
            if m > 0 {
                // Two accumulator pairs: four independent dependency chains.
                let mut acc = [0.0; 4];
                let mut rows = row[..m - 1].chunks_exact(2);
                let mut xs = done[fi..i - 1].chunks_exact(2);
                for (l, x) in (&mut rows).zip(&mut xs) {
                    acc[0] += l[0] * x[0][0];
                    acc[1] += l[0] * x[0][1];
                    acc[2] += l[1] * x[1][0];
                    acc[3] += l[1] * x[1][1];
                }
                for (l, x) in rows.remainder().iter().zip(xs.remainder()) {
                    acc[0] += l * x[0];
                    acc[1] += l * x[1];
                }
                let (l, x) = (row[m - 1], done[i - 1]);
                s = [
                    (s[0] - (acc[0] + acc[2])) - l * x[0],
                    (s[1] - (acc[1] + acc[3])) - l * x[1],
                ];
            }
            let r = self.inv_diag[i];
            rest[0] = [s[0] * r, s[1] * r];
        }
        for i in (0..n).rev() {
            let fi = self.first[i];
            let row = &self.vals[self.start[i]..self.start[i + 1]];
            let r = self.inv_diag[i];
            let x = [b[i][0] * r, b[i][1] * r];
            b[i] = x;
            for (bk, l) in b[fi..i].iter_mut().zip(&row[..i - fi]) {
                bk[0] -= l * x[0];
                bk[1] -= l * x[1];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn envelope_cholesky_matches_dense() {
        let n = 9;
        let first: Vec<usize> = (0..n).map(|i: usize| i.saturating_sub(1 + i % 3)).collect();
        let mut env = Envelope::new(first.clone());
        let mut dense = DMatrix::<f64>::zeros(n, n);
        let mut rng = SplitMix64::new(7);
        for i in 0..n {
            for j in first[i]..i {
                let v = rng.unit() - 0.5;
                assert!(env.add(i, j, v));
                dense[(i, j)] += v;
                dense[(j, i)] += v;
            }
            env.add(i, i, 4.0);
            dense[(i, i)] += 4.0;
        }
        assert!(!env.add(n - 1, 0, 1.0), "outside the envelope");
        assert_eq!(env.get(3, 1), dense[(3, 1)]);
        let b: Vec<f64> = (0..n).map(|_| rng.unit()).collect();
        let expect = dense
            .clone()
            .cholesky()
            .expect("spd")
            .solve(&DVector::from_vec(b.clone()));
        env.factor().expect("spd");
        let mut x = b.clone();
        env.solve(&mut x);
        let mut x2: Vec<[f64; 2]> = b.iter().map(|&v| [v, -2.0 * v]).collect();
        env.solve2(&mut x2);
        for i in 0..n {
            assert!((x[i] - expect[i]).abs() < 1e-12);
            assert!((x2[i][0] - expect[i]).abs() < 1e-12);
            assert!((x2[i][1] + 2.0 * expect[i]).abs() < 1e-12);
        }
        let mut bad = Envelope::new(vec![0, 0]);
        bad.add(0, 0, 1.0);
        bad.add(1, 0, 2.0);
        bad.add(1, 1, 1.0);
        assert_eq!(bad.factor(), Err(1));
    }
}
