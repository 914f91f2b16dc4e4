//! The coefficients of the three-stage Radau IIA method (order 5, stiffly accurate,
//! L-stable) and of the transformation that decouples its simplified Newton iteration.
//!
//! Derived here, not copied: the nodes are the Radau right points `c = ((4 − √6)/10,
//! (4 + √6)/10, 1)`, `A` collocates at them (`a_ij = ∫₀^{c_i} ℓ_j`), and the inverse `A⁻¹`
//! has one real eigenvalue `γ` and a complex pair `α ± iβ`. `T` holds the eigenvector of
//! `γ` and the real and imaginary parts of the eigenvector of `α + iβ` (each scaled to a
//! last component of 1), so that `T⁻¹ A⁻¹ T = [γ 0 0; 0 α β; 0 −β α]`. The values were
//! computed with 40 digits (mpmath: the quadrature of the Lagrange polynomials and the
//! eigen-decomposition); the tests below check every identity they must satisfy. They
//! are written with 20 digits, more than a double holds, so that they read as derived;
//! the compiler rounds each to the nearest double.
#![allow(clippy::excessive_precision)]

/// The nodes `c_i`.
pub const C: [f64; 3] = [0.155_051_025_721_682_190_18, 0.644_948_974_278_317_809_82, 1.0];

/// The Butcher matrix `A` (used only by the tests: the iteration works on `T⁻¹ A⁻¹ T`).
#[cfg(test)]
pub const A: [[f64; 3]; 3] = [
    [0.196_815_477_223_660_425_87, -0.065_535_425_850_198_388_109, 0.023_770_974_348_220_152_42],
    [0.394_424_314_739_087_277, 0.292_073_411_665_228_463_02, -0.041_548_752_125_997_930_198],
    [0.376_403_062_700_467_275_05, 0.512_485_826_188_421_613_84, 0.111_111_111_111_111_111_11],
];

/// The real eigenvalue of `A⁻¹`.
pub const GAMMA: f64 = 3.637_834_252_744_495_732_2;
/// The real part of the complex eigenvalues of `A⁻¹`.
pub const ALPHA: f64 = 2.681_082_873_627_752_133_9;
/// The imaginary part of the complex eigenvalues of `A⁻¹`.
pub const BETA: f64 = 3.050_430_199_247_410_569_4;

/// `T`: the columns are the eigenvector of `γ`, and the real and imaginary parts of the
/// eigenvector of `α + iβ`.
pub const T: [[f64; 3]; 3] = [
    [0.094_438_762_488_975_241_487, -0.141_255_295_020_954_208_43, 0.030_029_194_105_147_424_492],
    [0.250_213_122_965_333_311_38, 0.204_129_352_293_799_932, -0.382_942_112_757_261_937_8],
    [1.0, 1.0, 0.0],
];

/// `T⁻¹`.
pub const T_INV: [[f64; 3]; 3] = [
    [4.178_718_591_551_904_727_3, 0.327_682_820_761_062_387_08, 0.523_376_445_499_449_548_04],
    [-4.178_718_591_551_904_727_3, -0.327_682_820_761_062_387_08, 0.476_623_554_500_550_451_96],
    [0.502_872_634_945_786_875_95, -2.571_926_949_855_605_429_2, 0.596_039_204_828_224_924_97],
];

/// The error estimate's weights of the stages, divided by `1/γ` (Hairer and Wanner,
/// *Solving ODEs II*, IV.8, the embedded formula of order 3 with its `γ₀ = 1/γ`):
/// `((−13 − 7√6)/3, (−13 + 7√6)/3, −1/3)`.
pub const ERROR_WEIGHTS: [f64; 3] = [-10.048_809_399_827_415_562, 1.382_142_733_160_748_895_8, -1.0 / 3.0];

#[cfg(test)]
mod tests {
    use super::*;

    fn product(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let mut p = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        p
    }

    fn assert_close(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], tol: f64) {
        for i in 0..3 {
            for j in 0..3 {
                assert!((a[i][j] - b[i][j]).abs() < tol, "({i}, {j}): {} vs {}", a[i][j], b[i][j]);
            }
        }
    }

    /// The nodes and `A`: `A` integrates polynomials of degree ≤ 2 exactly on `[0, c_i]`
    /// (`Σ_j a_ij c_j^k = c_i^{k+1}/(k+1)`), and the last row is the weights `b`
    /// (stiff accuracy), which integrate degree ≤ 4 exactly on `[0, 1]`.
    #[test]
    fn the_tableau_is_the_radau_iia_collocation() {
        assert!((C[0] - (4.0 - 6f64.sqrt()) / 10.0).abs() < 1e-16 && (C[1] - (4.0 + 6f64.sqrt()) / 10.0).abs() < 1e-16);
        for i in 0..3 {
            for k in 0..3 {
                let sum: f64 = (0..3).map(|j| A[i][j] * C[j].powi(k)).sum();
                assert!((sum - C[i].powi(k + 1) / (k + 1) as f64).abs() < 1e-15, "row {i}, degree {k}");
            }
        }
        for k in 0..5 {
            let sum: f64 = (0..3).map(|j| A[2][j] * C[j].powi(k)).sum();
            assert!((sum - 1.0 / (k + 1) as f64).abs() < 1e-15, "quadrature of degree {k}");
        }
    }

    /// `T⁻¹ T = I` and `T⁻¹ A⁻¹ T = [γ 0 0; 0 α β; 0 −β α]`, i.e. `A T Λ = T`.
    #[test]
    fn the_transformation_decouples_the_inverse() {
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_close(&product(&T_INV, &T), &identity, 1e-15);
        let lambda = [[GAMMA, 0.0, 0.0], [0.0, ALPHA, BETA], [0.0, -BETA, ALPHA]];
        assert_close(&product(&A, &product(&T, &lambda)), &T, 1e-14);
    }

    /// The error weights: `(−13 ∓ 7√6)/3` and `−1/3`.
    #[test]
    fn the_error_weights_are_the_embedded_formulas() {
        let s6 = 6f64.sqrt();
        assert!((ERROR_WEIGHTS[0] - (-13.0 - 7.0 * s6) / 3.0).abs() < 1e-14);
        assert!((ERROR_WEIGHTS[1] - (-13.0 + 7.0 * s6) / 3.0).abs() < 1e-14);
    }
}
