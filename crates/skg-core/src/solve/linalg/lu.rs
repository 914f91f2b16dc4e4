//! The sparse LU of one sparsity structure, with faer: the symbolic analysis (a COLAMD
//! fill-reducing column order and the elimination structure) made once, then any number
//! of numeric factorizations (threshold partial pivoting by rows, into the stored
//! buffers) and triangular solves. faer was chosen over SuiteSparse's KLU/UMFPACK by
//! measurement (docs/benchmarks.md#the-sparse-lu): it is fast enough on these matrices
//! and needs no system library or FFI.
//!
//! **Mixed precision.** Asked for single precision, the matrix is factored in `f32` on
//! the same analysis, and each linear system `A x = b` is solved by iterative refinement
//! in double precision: `x ← x + M⁻¹ r`, `r = b − A x` computed with the double-precision
//! `A`, until `max |r|` meets the caller's target. Each refinement step contracts `r` by
//! about `κ(A) · 2⁻²⁴`; when one contracts by less than one half (single precision no
//! longer resolves the matrix), or an entry is beyond single precision's range, the
//! matrix is factored again in double precision, and the structure stays in double
//! precision for the rest of this LU's life. This is the scheme of LAPACK's `DSGESV`
//! (Langou et al., *Exploiting the performance of 32 bit floating point arithmetic in
//! obtaining 64 bit accuracy*, 2006). A single-precision LU moves half the bytes and fits
//! twice the numbers in a SIMD register: on the chain of 16 rods at N = 1024 it takes
//! 0.17 s against 0.24 s, and the process's peak memory falls from 273 to 182 MB.

use std::sync::Arc;
use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par};
use serde::Serialize;

use super::max_abs;
use super::pattern::CompressedPattern;

/// A refinement step must reduce `max |A x − b|` at least by this factor, or the
/// refinement is abandoned for a factorization in double precision. With `κ(A)` the
/// condition number, a step contracts by about `κ(A) · 2⁻²⁴`; at 0.5 the refinement
/// stops where single precision no longer resolves the matrix.
const REFINEMENT_CONTRACTION: f64 = 0.5;

/// The most triangular solves of one refinement (the first solve included).
const MAX_REFINEMENT_SOLVES: usize = 10;

/// Supernode amalgamation of the supernodal LU: two adjacent supernodes of `n` columns
/// in all are merged when the merged block's explicit zeros are at most the given
/// fraction of its entries, for the first `n` bound they are within. faer's default is
/// `(4, 1.0), (16, 0.8), (48, 0.1), (∞, 0.05)`; these admit about twice the zeros in
/// larger blocks, which makes fewer, larger dense blocks for the blocked kernels. A chain
/// of 16 rods at N = 1024 (n = 49 216, the Jacobian's time blocks of 48 unknowns):
/// numeric LU 0.33 → 0.23 s, 375 → 267 MB peak (fewer supernodes, less bookkeeping);
/// 32 rods at N = 512: 0.42 → 0.37 s, 456 → 383 MB. The band-like systems of the other
/// shipped scenes (rolling disk, tumbler at N = 65536) keep faer's simplicial LU, which
/// this does not touch, and do not change beyond the noise of the measurement.
const SUPERNODE_RELAX: &[(usize, f64)] = &[(8, 1.0), (32, 0.8), (96, 0.2), (usize::MAX, 0.1)];

/// The choice between faer's simplicial (column by column) and supernodal (dense
/// blocks) numeric LU: supernodal when the analysis's estimate of flops per factor
/// nonzero exceeds `40 · SUPERNODAL_THRESHOLD`, i.e. 10 (faer's default threshold is 1,
/// i.e. 40). Measured per numeric LU, best of 20, simplicial → supernodal, with the
/// estimate in brackets: chain4 at N = 1024 (13.7) 21.4 → 9.4 ms and at N = 8192
/// 167 → 101 ms; the rolling disk with `SBP484` at N = 512 (17.1; the fit's example)
/// 4.3 → 2.5 ms, with `SBP363` at N = 2048 (13.5) 15.2 → 13.1 ms; the tumbler with
/// `SBP484` (10.6) 4.4 → 2.7 ms. Below 10 the simplicial LU is as fast or faster: the
/// knife edge (8.3) 13.9 against 16.8 ms at N = 8192, the rolling disk with `SBP242`
/// (6.4) 20.1 against 24.1 ms, the pendulum (4.6) 5.9 against 7.4 ms, the damped
/// oscillator (3.1) 0.9 against 1.9 ms. The supernodal factors take more memory: peak
/// 197 → 245 MB for chain4 at N = 8192, 244 → 306 MB for the `SBP484` disk at 16384
/// (within the memory estimate, `tests/memory.rs`). The chain of 8 rods (24 unknowns per node) was
/// the reason for the first lowering from 1 to 0.5: 0.13 s simplicial per numeric LU at
/// N = 1024, 0.06 s supernodal.
const SUPERNODAL_THRESHOLD: f64 = 0.25;

/// Counts and wall times of an LU's factorizations and solves, in seconds.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct LuStats {
    /// Numeric LU factorizations in single precision (module documentation, "Mixed
    /// precision"); the others are in double precision.
    pub single_precision_factorizations: usize,
    /// Triangular solves with a single-precision factorization, each followed by the
    /// residual of the linear system in double precision (the refinement steps).
    pub refinement_solves: usize,
    /// Times the refinement did not converge and the matrix was factored again in double
    /// precision (the structure then stays in double precision).
    pub single_precision_fallbacks: usize,
    /// Time in numeric LU factorizations.
    pub factorization_s: f64,
    /// Time in the triangular solves (and the refinement's residuals).
    pub triangular_solve_s: f64,
}

/// The precision of the factorization in hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Factored {
    None,
    Double,
    Single,
}

/// A numeric LU in single precision on the same symbolic analysis, with its buffers.
#[derive(Default)]
struct SingleLu {
    numeric: NumericLu<u32, f32>,
    values: Vec<f32>,
    rhs: Vec<f32>,
    factor_work: Option<MemBuffer>,
    solve_work: Option<MemBuffer>,
}

/// The analysis of one structure: its compressed pattern and symbolic LU.
struct Analysis {
    pattern: CompressedPattern,
    symbolic: SymbolicLu<u32>,
}

impl Analysis {
    /// The analysis of the `n × n` `structure`.
    fn of(n: usize, structure: &[(u32, u32)]) -> Result<Analysis, String> {
        let pattern = CompressedPattern::new(n, structure);
        let symbolic = factorize_symbolic_lu(pattern.symbolic(), lu_params()).map_err(|e| format!("{e:?}"))?;
        Ok(Analysis { pattern, symbolic })
    }
}

/// The sparse LU of one structure: its analysis (which other LUs of the structure may
/// share, [`SparseLu::sharing`]), numeric factorizations and work buffers.
pub(super) struct SparseLu {
    analysis: Arc<Analysis>,
    numeric: NumericLu<u32, f64>,
    factor_work: MemBuffer,
    solve_work: MemBuffer,
    /// The single-precision factorization and its buffers (empty until used).
    single: SingleLu,
    /// The precision of the last successful factorization.
    factored: Factored,
    /// Whether a single-precision factorization of this structure failed or did not
    /// refine: later factorizations are in double precision.
    single_failed: bool,
}

impl SparseLu {
    /// The symbolic analysis of the `n × n` `structure` (entries inside the matrix,
    /// checked by the caller); the error is faer's.
    pub(super) fn analyse(n: usize, structure: &[(u32, u32)]) -> Result<SparseLu, String> {
        Ok(SparseLu::on(Arc::new(Analysis::of(n, structure)?)))
    }

    /// Another LU of this one's structure, on the same analysis (nothing factored yet).
    pub(super) fn sharing(&self) -> SparseLu {
        SparseLu::on(Arc::clone(&self.analysis))
    }

    /// An LU on `analysis`, with its buffers.
    fn on(analysis: Arc<Analysis>) -> SparseLu {
        let factor_req = analysis.symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default());
        let solve_req: StackReq = analysis.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        SparseLu {
            analysis,
            numeric: NumericLu::new(),
            factor_work: MemBuffer::new(factor_req),
            solve_work: MemBuffer::new(solve_req),
            single: SingleLu::default(),
            factored: Factored::None,
            single_failed: false,
        }
    }

    /// The compressed pattern.
    pub(super) fn pattern(&self) -> &CompressedPattern {
        &self.analysis.pattern
    }

    /// Factor the compressed matrix with `values`: in single precision when `single` and
    /// single precision has not failed on this structure (falling back to double
    /// precision when its LU fails, e.g. on an entry beyond single precision's range);
    /// `false` when the matrix is singular.
    pub(super) fn factor(&mut self, values: &[f64], single: bool, stats: &mut LuStats) -> bool {
        if single && !self.single_failed {
            if self.factor_single(values, stats) {
                return true;
            }
            self.give_up_single(stats);
        }
        self.factor_double(values, stats)
    }

    /// Overwrite `rhs` with the solution of the system of the last factorization, which
    /// was of the compressed matrix with `values` (the caller knows that it succeeded):
    /// directly in double precision; in single precision refined until
    /// `max |A x − rhs| ≤ target`, and when the refinement does not converge, factored
    /// again in double precision and solved directly. `false` when the solution is not
    /// finite or the matrix singular.
    pub(super) fn solve(&mut self, values: &[f64], rhs: &mut [f64], target: f64, stats: &mut LuStats) -> bool {
        if self.factored == Factored::Single {
            if self.refine(values, rhs, target, stats) {
                return true;
            }
            self.give_up_single(stats);
            if !self.factor_double(values, stats) {
                return false;
            }
        }
        self.solve_double(rhs, false, stats)
    }

    /// The numeric LU in double precision.
    fn factor_double(&mut self, values: &[f64], stats: &mut LuStats) -> bool {
        let t = Instant::now();
        let Analysis { pattern, symbolic } = &*self.analysis;
        let factored = symbolic.factorize_numeric_lu(
            &mut self.numeric,
            SparseColMatRef::new(pattern.symbolic(), values),
            Par::Seq,
            MemStack::new(&mut self.factor_work),
            Default::default(),
        );
        stats.factorization_s += t.elapsed().as_secs_f64();
        self.factored = if factored.is_ok() { Factored::Double } else { Factored::None };
        factored.is_ok()
    }

    /// The numeric LU in single precision; `false` when an entry is beyond its range or
    /// the LU finds no pivot.
    fn factor_single(&mut self, values: &[f64], stats: &mut LuStats) -> bool {
        let t = Instant::now();
        let single = &mut self.single;
        single.values.clear();
        single.values.extend(values.iter().map(|&v| v as f32));
        if single.values.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let Analysis { pattern, symbolic } = &*self.analysis;
        let work = single
            .factor_work
            .get_or_insert_with(|| MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f32>(Par::Seq, Default::default())));
        let factored = symbolic.factorize_numeric_lu(
            &mut single.numeric,
            SparseColMatRef::new(pattern.symbolic(), &single.values),
            Par::Seq,
            MemStack::new(work),
            Default::default(),
        );
        stats.factorization_s += t.elapsed().as_secs_f64();
        stats.single_precision_factorizations += 1;
        self.factored = if factored.is_ok() { Factored::Single } else { Factored::None };
        factored.is_ok()
    }

    /// Stop using single precision on this structure, and free its factorization.
    fn give_up_single(&mut self, stats: &mut LuStats) {
        stats.single_precision_fallbacks += 1;
        self.single_failed = true;
        self.single = SingleLu::default();
    }

    /// The direct solve with the double-precision factorization, of `A x = rhs` or, when
    /// `transposed`, of `Aᵀ x = rhs`.
    fn solve_double(&mut self, rhs: &mut [f64], transposed: bool, stats: &mut LuStats) -> bool {
        let t = Instant::now();
        let n = rhs.len();
        let lu = LuRef::new_unchecked(&self.analysis.symbolic, &self.numeric);
        let (rhs_mat, stack) = (MatMut::from_column_major_slice_mut(rhs, n, 1), MemStack::new(&mut self.solve_work));
        if transposed {
            lu.solve_transpose_in_place_with_conj(Conj::No, rhs_mat, Par::Seq, stack);
        } else {
            lu.solve_in_place_with_conj(Conj::No, rhs_mat, Par::Seq, stack);
        }
        stats.triangular_solve_s += t.elapsed().as_secs_f64();
        rhs.iter().all(|v| v.is_finite())
    }

    /// The direct solve of the transposed system, when the caller factored in double
    /// precision.
    fn solve_transposed(&mut self, rhs: &mut [f64], stats: &mut LuStats) -> bool {
        self.factored == Factored::Double && self.solve_double(rhs, true, stats)
    }

    /// Iterative refinement with the single-precision factorization `M ≈ A`:
    /// `x ← x + M⁻¹ r`, `r = b − A x` in double precision, from `x = 0`, until
    /// `max |r| ≤ target` after at least one solve; each correction is solved for
    /// `r / max |r|`, which keeps the right-hand side within single precision's range.
    /// Fails (`false`, `rhs` unchanged) when a step does not reduce `max |r|` by
    /// [`REFINEMENT_CONTRACTION`], after [`MAX_REFINEMENT_SOLVES`] solves, or when `x` is
    /// not finite; on success `rhs` holds `x`.
    fn refine(&mut self, values: &[f64], rhs: &mut [f64], target: f64, stats: &mut LuStats) -> bool {
        let t = Instant::now();
        let n = rhs.len();
        let single = &mut self.single;
        let Analysis { pattern, symbolic } = &*self.analysis;
        let work = single.solve_work.get_or_insert_with(|| MemBuffer::new(symbolic.solve_in_place_scratch::<f32>(1, Par::Seq)));
        let mut x = vec![0.0; n];
        let mut r = rhs.to_vec();
        let mut last = max_abs(&r);
        // At least one solve, even when the right-hand side is already below the target.
        let mut converged = last == 0.0;
        for _ in 0..MAX_REFINEMENT_SOLVES {
            if converged || !last.is_finite() {
                break;
            }
            single.rhs.clear();
            single.rhs.extend(r.iter().map(|&ri| (ri / last) as f32));
            LuRef::new_unchecked(symbolic, &single.numeric).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut single.rhs, n, 1),
                Par::Seq,
                MemStack::new(work),
            );
            stats.refinement_solves += 1;
            x.iter_mut().zip(&single.rhs).for_each(|(xi, di)| *xi += last * f64::from(*di));
            r.copy_from_slice(rhs);
            pattern.subtract_product(values, &x, &mut r);
            let now = max_abs(&r);
            if now.is_nan() || now > REFINEMENT_CONTRACTION * last {
                break;
            }
            last = now;
            converged = now <= target;
        }
        stats.triangular_solve_s += t.elapsed().as_secs_f64();
        // A solution with a non-finite entry fails too (`max_abs` can miss a NaN of `r`).
        let solved = converged && x.iter().all(|v| v.is_finite());
        if solved {
            rhs.copy_from_slice(&x);
        }
        solved
    }
}

/// The symbolic LU's parameters: faer's defaults (COLAMD) with [`SUPERNODAL_THRESHOLD`]
/// and [`SUPERNODE_RELAX`].
fn lu_params() -> LuSymbolicParams<'static> {
    LuSymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold(SUPERNODAL_THRESHOLD),
        supernodal_params: SymbolicSupernodalParams { relax: Some(SUPERNODE_RELAX) },
        ..Default::default()
    }
}

/// One LU factorization of a square sparse matrix in double precision, kept for solving
/// any number of right-hand sides: the sensitivities of a fit's trajectory to its
/// parameters, one column per parameter.
pub struct SparseFactorization {
    n: usize,
    lu: SparseLu,
    /// The compressed values of the matrix factored last.
    values: Vec<f64>,
    /// The compressed values asked for by `refactor`, compared with `values`.
    incoming: Vec<f64>,
    factorizations: usize,
    stats: LuStats,
}

impl SparseFactorization {
    /// The analysis and the factorization of the `n × n` matrix with the entries
    /// `structure` (row, column; duplicates summed) and their `entries`. `None` when
    /// the structure cannot be analysed (an entry outside the matrix) or the matrix is
    /// singular.
    pub fn new(n: usize, structure: &[(u32, u32)], entries: &[f64]) -> Option<SparseFactorization> {
        if structure.iter().any(|&(r, c)| r as usize >= n || c as usize >= n) || structure.len() != entries.len() {
            return None;
        }
        SparseFactorization::factor_on(n, SparseLu::analyse(n, structure).ok()?, entries)
    }

    /// The factorization of the matrix with `entries` on `lu`'s analysis (their number
    /// checked); `None` when it is singular.
    pub(super) fn factor_on(n: usize, mut lu: SparseLu, entries: &[f64]) -> Option<SparseFactorization> {
        if entries.len() != lu.pattern().entries_len() {
            return None;
        }
        let mut values = vec![0.0; lu.pattern().nonzeros()];
        lu.pattern().gather(entries, &mut values);
        let mut stats = LuStats::default();
        let incoming = values.clone();
        lu.factor(&values, false, &mut stats).then_some(SparseFactorization { n, lu, values, incoming, factorizations: 1, stats })
    }

    /// Factor the matrix of the same structure with other `entries`, on the analysis
    /// already made (a fit factors `∂R/∂P` at several points: its COLAMD ordering cost as
    /// much as the numeric factorization); nothing to do when they are the entries of
    /// the factorization in hand (a fit's start, its first derivatives and its last
    /// statistics each factor at a point factored before). `false` when the matrix is
    /// singular or `entries` has another length.
    pub fn refactor(&mut self, entries: &[f64]) -> bool {
        if entries.len() != self.lu.pattern().entries_len() {
            return false;
        }
        self.lu.pattern().gather(entries, &mut self.incoming);
        if self.incoming == self.values && self.lu.factored == Factored::Double {
            return true;
        }
        std::mem::swap(&mut self.incoming, &mut self.values);
        self.factorizations += 1;
        self.lu.factor(&self.values, false, &mut self.stats)
    }

    /// A new LU on this factorization's analysis (nothing factored yet), for the
    /// `n × n` matrices of `structure`; `None` unless the analysis is of that structure
    /// (the same entries in the same order).
    pub(super) fn sharing_analysis(&self, n: usize, structure: &[(u32, u32)]) -> Option<SparseLu> {
        (n == self.n
            && structure.iter().all(|&(r, c)| (r as usize) < n && (c as usize) < n)
            && *self.lu.pattern() == CompressedPattern::new(n, structure))
        .then(|| self.lu.sharing())
    }

    /// The numeric factorizations made, the first included.
    pub fn factorizations(&self) -> usize {
        self.factorizations
    }

    /// Overwrite `rhs` (of length `n`) with the solution of `A x = rhs`; `false` when it
    /// is not finite or `rhs` has another length.
    pub fn solve(&mut self, rhs: &mut [f64]) -> bool {
        rhs.len() == self.n && self.lu.solve(&self.values, rhs, 0.0, &mut self.stats)
    }

    /// Overwrite `rhs` (of length `n`) with the solution of `Aᵀ x = rhs` (a fit's
    /// starting multipliers); `false` when it is not finite or `rhs` has another length.
    pub fn solve_transposed(&mut self, rhs: &mut [f64]) -> bool {
        rhs.len() == self.n && self.lu.solve_transposed(rhs, &mut self.stats)
    }
}

#[cfg(test)]
mod tests {
    use super::SparseFactorization;

    /// A nonsymmetric tridiagonal system with a duplicated entry, against its solution
    /// built first: `A x = b` with `b = A x*`.
    #[test]
    fn a_factorization_solves_several_right_hand_sides() {
        let n = 50;
        let mut structure = Vec::new();
        let mut entries = Vec::new();
        for i in 0..n {
            structure.push((i as u32, i as u32));
            entries.push(4.0 + i as f64 * 0.01);
            if i + 1 < n {
                structure.extend([(i as u32, i as u32 + 1), (i as u32 + 1, i as u32)]);
                entries.extend([-1.0, -2.0]);
            }
        }
        structure.push((0, 0)); // summed with the diagonal entry
        entries.push(1.0);
        // `A x` for the matrix with `values` on `structure`.
        let a = |values: &[f64], x: &[f64]| -> Vec<f64> {
            let mut b = vec![0.0; n];
            for (&(r, c), v) in structure.iter().zip(values) {
                b[r as usize] += v * x[c as usize];
            }
            b
        };
        let max_error = |x: &[f64], exact: &[f64]| x.iter().zip(exact).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        let mut lu = SparseFactorization::new(n, &structure, &entries).expect("nonsingular");
        for shift in [0.0, 1.5] {
            let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3 + shift).sin()).collect();
            let mut x = a(&entries, &exact);
            assert!(lu.solve(&mut x));
            let err = max_error(&x, &exact);
            // Diagonally dominant: measured 2.2e-16; margin 50x.
            assert!(err < 1e-14, "{err:e}");
        }
        assert!(!lu.solve(&mut [0.0; 3]), "a right-hand side of another length");
        // Aᵀ x = b with b = Aᵀ x*.
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        let mut x = vec![0.0; n];
        for (&(r, c), v) in structure.iter().zip(&entries) {
            x[c as usize] += v * exact[r as usize];
        }
        assert!(lu.solve_transposed(&mut x));
        let err = max_error(&x, &exact);
        assert!(err < 1e-14, "transposed: {err:e}");
        // Other values of the same structure on the same analysis: the matrix with its
        // off-diagonal entries halved (still diagonally dominant), against a solution
        // built with it.
        let halved: Vec<f64> = structure.iter().zip(&entries).map(|(&(r, c), v)| if r == c { *v } else { 0.5 * v }).collect();
        assert!(lu.refactor(&halved));
        assert_eq!(lu.factorizations(), 2);
        assert!(lu.refactor(&halved));
        assert_eq!(lu.factorizations(), 2, "the same entries are not factored again");
        let exact: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 0.2).cos()).collect();
        let mut x = a(&halved, &exact);
        assert!(lu.solve(&mut x));
        let err = max_error(&x, &exact);
        assert!(err < 1e-14, "refactored: {err:e}");
        assert!(!lu.refactor(&halved[1..]), "values of another structure");
        // Singular (a zero column) and malformed inputs are refused, not a panic.
        assert!(SparseFactorization::new(2, &[(0, 0), (1, 0)], &[1.0, 1.0]).is_none());
        assert!(SparseFactorization::new(2, &[(0, 5)], &[1.0]).is_none());
    }
}
