//! Gaussian elimination with partial pivoting for banded systems: the predictor's proxy
//! systems ([`predict`](crate::solve::choice::predict)), one per operator and grid.
//!
//! Written by hand because no crate of the stack solves banded systems: faer's and
//! sprs' sparse LUs analyse each pattern first (sorting, symbolic factorization), which
//! took most of a refinement's prediction time for systems of a few thousand rows and a
//! band of a few dozen (measured with `perf` on the tumbler at tolerance 1e-8: sorting
//! 21 %, faer's symbolic LU 10 %), and nalgebra's dense LU would be quadratic in memory.
//! Each row is stored from its first nonzero column on and grows to the right as the
//! elimination fills it: the fill of a row stays within the pivot rows' reach.

/// Solves `A X = B` for `columns` right-hand sides stored column by column in `rhs`
/// (`n` values each), overwriting them with the solution. `A` is given by its entries
/// `(row, column, value)`, repeated entries summed; rows whose first nonzero lies far
/// left of the diagonal make the elimination slower, not wrong. Returns `false` when
/// `A` is singular to working precision or the solution is not finite.
pub fn solve_banded(n: usize, entries: &[(usize, usize, f64)], rhs: &mut [f64], columns: usize) -> bool {
    assert_eq!(rhs.len(), n * columns, "solve_banded: rhs holds `columns` vectors of n values");
    // Each row as (its first column, the values from there on).
    let mut span = vec![(usize::MAX, 0usize); n];
    for &(r, c, _) in entries {
        span[r] = (span[r].0.min(c), span[r].1.max(c));
    }
    let mut rows: Vec<(usize, Vec<f64>)> = span
        .iter()
        .map(|&(first, last)| if first == usize::MAX { (0, Vec::new()) } else { (first, vec![0.0; last - first + 1]) })
        .collect();
    for &(r, c, v) in entries {
        let (first, values) = &mut rows[r];
        values[c - *first] += v;
    }
    // How far below the diagonal a row reaches: the pivot's search window.
    let reach = rows.iter().enumerate().map(|(r, (first, _))| r.saturating_sub(*first)).max().unwrap_or(0);
    let mut b: Vec<Vec<f64>> = (0..n).map(|r| (0..columns).map(|j| rhs[j * n + r]).collect()).collect();
    let at = |row: &(usize, Vec<f64>), c: usize| if c >= row.0 { row.1.get(c - row.0).copied().unwrap_or(0.0) } else { 0.0 };
    for k in 0..n {
        let end = (k + reach).min(n - 1);
        let p = (k..=end).max_by(|&i, &j| at(&rows[i], k).abs().total_cmp(&at(&rows[j], k).abs())).unwrap_or(k);
        let pivot = at(&rows[p], k);
        if pivot == 0.0 || !pivot.is_finite() {
            return false;
        }
        rows.swap(k, p);
        b.swap(k, p);
        let (done, below) = rows.split_at_mut(k + 1);
        let (bk, b_below) = b.split_at_mut(k + 1);
        let (first_k, values_k) = (&done[k].0, &done[k].1);
        let last_k = first_k + values_k.len();
        for (row, bi) in below.iter_mut().zip(b_below.iter_mut()).take(end - k) {
            let l = at(row, k) / pivot;
            if l == 0.0 {
                continue;
            }
            // row −= l · row k over the columns k.. of row k; row's first column is ≤ k.
            if row.0 + row.1.len() < last_k {
                row.1.resize(last_k - row.0, 0.0);
            }
            for c in k..last_k {
                row.1[c - row.0] -= l * values_k[c - first_k];
            }
            for (x, y) in bi.iter_mut().zip(&bk[k]) {
                *x -= l * y;
            }
        }
    }
    // Back substitution, row k holding the diagonal at column k.
    for k in (0..n).rev() {
        let (first, values) = &rows[k];
        let diagonal = values[k - first];
        for j in 0..columns {
            let mut s = b[k][j];
            for (offset, &a) in values.iter().enumerate().skip(k + 1 - first) {
                s -= a * rhs[j * n + first + offset];
            }
            rhs[j * n + k] = s / diagonal;
        }
    }
    rhs.iter().all(|v| v.is_finite())
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

    #[test]
    fn a_singular_system_is_refused() {
        let entries = [(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 4.0)];
        let mut rhs = vec![1.0, 1.0];
        assert!(!solve_banded(2, &entries, &mut rhs, 1));
    }
}
