//! Gaussian elimination with partial pivoting for banded systems: the predictor's proxy
//! systems ([`predict`](crate::solve::choice::predict)), one per operator and grid.
//!
//! Written by hand because no crate of the stack solves banded systems: faer's and
//! sprs' sparse LUs analyse each pattern first (sorting, symbolic factorization), which
//! took most of a refinement's prediction time for systems of a few thousand rows and a
//! band of a few dozen (measured with `perf` on the tumbler at tolerance 1e-8: sorting
//! 21 %, faer's symbolic LU 10 %), and nalgebra's dense LU would be quadratic in memory.
//! The rows live in one flat buffer, each in a window of `p + q + 1` columns for a
//! lower bandwidth `p` and an upper `q`: partial pivoting widens the upper band to
//! `p + q` (Golub and Van Loan, *Matrix Computations*, 4th ed., Sec. 4.3.5), and a row
//! whose window would overflow is moved to start at the current column, left of which
//! its entries are already eliminated. No allocation per row or per step (a `Vec` per
//! row, grown as it filled, made the allocator a third of the solve's time).

/// Solves `A X = B` for `columns` right-hand sides stored column by column in `rhs`
/// (`n` values each), overwriting them with the solution. `A` is given by its entries
/// `(row, column, value)`, repeated entries summed; rows whose first nonzero lies far
/// left of the diagonal make the elimination slower, not wrong. Returns `false` when
/// `A` is singular to working precision or the solution is not finite.
pub fn solve_banded(n: usize, entries: &[(usize, usize, f64)], rhs: &mut [f64], columns: usize) -> bool {
    assert_eq!(rhs.len(), n * columns, "solve_banded: rhs holds `columns` vectors of n values");
    let mut a = Band::new(n, entries);
    // The right-hand sides row by row, moved with their rows.
    let mut b: Vec<f64> = (0..n).flat_map(|r| (0..columns).map(move |j| (r, j))).map(|(r, j)| rhs[j * n + r]).collect();
    for k in 0..n {
        let end = (k + a.reach).min(n - 1);
        // The last of the largest, as `Iterator::max_by` picks it.
        let mut p = k;
        for i in k..=end {
            if a.at(i, k).abs() >= a.at(p, k).abs() {
                p = i;
            }
        }
        let pivot = a.at(p, k);
        if pivot == 0.0 || !pivot.is_finite() {
            return false;
        }
        a.swap(k, p);
        for j in 0..columns {
            b.swap(k * columns + j, p * columns + j);
        }
        let (first_k, last_k) = (a.first[k], a.last[k]);
        for i in k + 1..=end {
            let l = a.at(i, k) / pivot;
            if l == 0.0 {
                continue;
            }
            // row i −= l · row k over the columns k.. of row k; row i's first column is ≤ k.
            a.make_room(i, k, last_k);
            let (offset_k, offset_i) = (k - first_k, k - a.first[i]);
            let (pivot_row, row) = a.two_rows(k, i);
            for (x, y) in row[offset_i..offset_i + (last_k - k)].iter_mut().zip(&pivot_row[offset_k..last_k - first_k]) {
                *x -= l * y;
            }
            for j in 0..columns {
                b[i * columns + j] -= l * b[k * columns + j];
            }
        }
    }
    // Back substitution, row k holding the diagonal at column k.
    for k in (0..n).rev() {
        let (first, values) = (a.first[k], a.row(k));
        let diagonal = values[k - first];
        for j in 0..columns {
            let mut s = b[k * columns + j];
            for (offset, &v) in values.iter().enumerate().skip(k + 1 - first) {
                s -= v * rhs[j * n + first + offset];
            }
            rhs[j * n + k] = s / diagonal;
        }
    }
    rhs.iter().all(|v| v.is_finite())
}

/// The rows of a banded matrix under elimination: row `r`'s values for the columns
/// `first[r]..last[r]` at the start of its window in `values`, the rows reached through
/// `slot` (a row exchange swaps two slots, not their values).
struct Band {
    values: Vec<f64>,
    width: usize,
    slot: Vec<usize>,
    first: Vec<usize>,
    last: Vec<usize>,
    /// How far below the diagonal a row reaches: the pivot's search window.
    reach: usize,
}

impl Band {
    fn new(n: usize, entries: &[(usize, usize, f64)]) -> Band {
        let (mut first, mut last) = (vec![usize::MAX; n], vec![0; n]);
        for &(r, c, _) in entries {
            first[r] = first[r].min(c);
            last[r] = last[r].max(c + 1);
        }
        // An empty row (a singular matrix) starts at column 0.
        first.iter_mut().filter(|f| **f == usize::MAX).for_each(|f| *f = 0);
        let reach = first.iter().enumerate().map(|(r, &f)| r.saturating_sub(f)).max().unwrap_or(0);
        let upper = last.iter().enumerate().map(|(r, &l)| l.saturating_sub(r + 1)).max().unwrap_or(0);
        // Wide enough for any row as given, and for any row from the current column on.
        let width = first.iter().zip(&last).map(|(&f, &l)| l.saturating_sub(f)).max().unwrap_or(0).max(reach + upper + 1);
        let mut values = vec![0.0; n * width];
        for &(r, c, v) in entries {
            values[r * width + c - first[r]] += v;
        }
        Band { values, width, slot: (0..n).collect(), first, last, reach }
    }

    /// Entry `(r, c)` (zero outside the row's columns).
    fn at(&self, r: usize, c: usize) -> f64 {
        if c >= self.first[r] && c < self.last[r] {
            self.values[self.slot[r] * self.width + c - self.first[r]]
        } else {
            0.0
        }
    }

    /// Row `r`'s values from its first column to its last.
    fn row(&self, r: usize) -> &[f64] {
        let start = self.slot[r] * self.width;
        &self.values[start..start + self.last[r] - self.first[r]]
    }

    /// Rows `k` and `i` (`k ≠ i`): the first to read, the second (its whole window) to
    /// change.
    fn two_rows(&mut self, k: usize, i: usize) -> (&[f64], &mut [f64]) {
        let w = self.width;
        let (sk, si) = (self.slot[k], self.slot[i]);
        let len_k = self.last[k] - self.first[k];
        if sk < si {
            let (lo, hi) = self.values.split_at_mut(si * w);
            (&lo[sk * w..sk * w + len_k], &mut hi[..w])
        } else {
            let (lo, hi) = self.values.split_at_mut(sk * w);
            (&hi[..len_k], &mut lo[si * w..si * w + w])
        }
    }

    fn swap(&mut self, k: usize, p: usize) {
        self.slot.swap(k, p);
        self.first.swap(k, p);
        self.last.swap(k, p);
    }

    /// Let row `i` reach column `last` (exclusive), its first column ≤ `k`: when its window
    /// is too short, it is moved to start at column `k` (the ones before are eliminated).
    fn make_room(&mut self, i: usize, k: usize, last: usize) {
        if last <= self.last[i] {
            return;
        }
        let start = self.slot[i] * self.width;
        if last - self.first[i] > self.width {
            let shift = k - self.first[i];
            let len = self.last[i] - self.first[i];
            self.values.copy_within(start + shift..start + len, start);
            self.values[start + len - shift..start + len].fill(0.0);
            self.first[i] = k;
        }
        self.last[i] = last;
    }
}

#[cfg(test)]
mod tests {
    use super::solve_banded;

    /// A tridiagonal system with a row far left of the diagonal and a zero leading
    /// entry (which forces a row exchange) against its known solution.
    #[test]
    fn solves_a_pivoted_band_with_a_wide_row_exactly() {
        let n = 7;
        let x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.5).collect();
        let mut entries = vec![(0, 0, 0.0), (0, 1, 2.0), (1, 0, 3.0), (1, 1, 1.0)];
        for i in 2..n {
            entries.extend([(i, i - 1, -1.0), (i, i, 4.0)]);
            if i + 1 < n {
                entries.push((i, i + 1, 1.0));
            }
        }
        entries.push((n - 1, 0, 2.0)); // the wide row
        entries.push((3, 3, 0.5)); // a repeated entry, summed
        let mut rhs = vec![0.0; 2 * n];
        for &(r, c, v) in &entries {
            rhs[r] += v * x[c];
            rhs[n + r] += 2.0 * v * x[c];
        }
        assert!(solve_banded(n, &entries, &mut rhs, 2));
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-14, "{i}: {} vs {}", rhs[i], x[i]);
            assert!((rhs[n + i] - 2.0 * x[i]).abs() < 1e-14);
        }
    }

    /// Banded systems whose small diagonals force row exchanges (and so the fill that
    /// moves rows in their windows): the solution leaves a residual at the rounding
    /// level of the matrix and the solution (the backward stability of partial
    /// pivoting), checked with the matrix held densely.
    #[test]
    fn pivoted_bands_with_fill_are_solved_to_the_rounding_level() {
        let mut seed = 12345u64;
        let mut random = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for trial in 0..60usize {
            let n = 8 + trial * 3;
            let (lower, upper) = (1 + trial % 5, 1 + trial % 4);
            let mut entries = Vec::new();
            let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
            for r in 0..n {
                for c in r.saturating_sub(lower)..(r + upper + 1).min(n) {
                    let v = if c == r { 1e-3 * random() } else { random() };
                    entries.push((r, c, v));
                    dense[(r, c)] += v;
                }
            }
            let columns = 1 + trial % 3;
            let b: Vec<f64> = (0..n * columns).map(|_| random()).collect();
            let mut x = b.clone();
            assert!(solve_banded(n, &entries, &mut x, columns), "trial {trial}");
            let (x, b) = (nalgebra::DMatrix::from_column_slice(n, columns, &x), nalgebra::DMatrix::from_column_slice(n, columns, &b));
            let residual = (&dense * &x - &b).amax();
            let level = 1e3 * f64::EPSILON * dense.amax() * x.amax() * (lower + upper + 1) as f64;
            assert!(residual < level, "trial {trial}: residual {residual:e} above {level:e}");
        }
    }

    #[test]
    fn a_singular_system_is_refused() {
        let entries = [(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 4.0)];
        let mut rhs = vec![1.0, 1.0];
        assert!(!solve_banded(2, &entries, &mut rhs, 1));
    }
}
