//! The coefficients of the operators, as exact fractions.
//!
//! Each operator is given by
//! * `H_*`: the first diagonal entries of `H/Δt` at the left boundary (the remaining
//!   interior entries are 1, the right boundary mirrors the left one);
//! * `D_*`: the rows of the left boundary block of `Δt·D`, each starting in column 1;
//!   the right boundary block follows by antisymmetry,
//!   `D[N+1−i, N+1−j] = −D[i, j]` (1-based);
//! * `INTERIOR_*`: the central difference stencil `Δt·D[i, i−r..=i+r]` of interior rows.
//!
//! All values were verified with exact rational arithmetic (a throwaway Python script
//! with `fractions.Fraction`) for N = 2·(boundary rows) … 20: `HD + (HD)ᵀ = B` exactly,
//! `D tʲ = j tʲ⁻¹` exactly for `j ≤` boundary order in every row and for `j ≤` interior
//! order in interior rows, and `1ᵀ H tʲ = ∫ tʲ` exactly for `j ≤ 2·(boundary order) − 1`
//! (but not for `j = 2·(boundary order)`). The unit tests repeat these checks in floating point.

use super::Frac;

/// SBP121: trapezoid-rule norm, central differences inside, one-sided first
/// differences in the two boundary rows. (The classic second-order SBP operator,
/// e.g. Strand (1994), Mattsson & Nordström (2004).)
pub const H_121: [Frac; 1] = [(1, 2)];
/// Left boundary row of `Δt·D` for SBP121.
pub const D_121: [&[Frac]; 1] = [&[(-1, 1), (1, 1)]];
/// Interior stencil of `Δt·D` for SBP121.
pub const INTERIOR_121: [Frac; 3] = [(-1, 2), (0, 1), (1, 2)];

/// SBP242: diagonal norm, fourth order inside, second order at the boundary.
///
/// Source: B. Strand, *Summation by parts for finite difference approximations for
/// d/dx*, J. Comput. Phys. 110 (1994) 47–67; K. Mattsson & J. Nordström, *Summation by
/// parts operators for finite difference approximations of second derivatives*,
/// J. Comput. Phys. 199 (2004) 503–540 (same coefficients as
/// SummationByPartsOperators.jl's `MattssonNordström2004()`, order 4).
pub const H_242: [Frac; 4] = [(17, 48), (59, 48), (43, 48), (49, 48)];
/// Left 4×6 boundary block of `Δt·D` for SBP242 (trailing zeros omitted).
pub const D_242: [&[Frac]; 4] = [
    &[(-24, 17), (59, 34), (-4, 17), (-3, 34)],
    &[(-1, 2), (0, 1), (1, 2)],
    &[(4, 43), (-59, 86), (0, 1), (59, 86), (-4, 43)],
    &[(3, 98), (0, 1), (-59, 98), (0, 1), (32, 49), (-4, 49)],
];
/// Interior stencil of `Δt·D` for SBP242.
pub const INTERIOR_242: [Frac; 5] = [(1, 12), (-2, 3), (0, 1), (2, 3), (-1, 12)];

/// SBP363: diagonal norm, sixth order inside, third order at the boundary.
///
/// Source: K. Mattsson & J. Nordström, *Summation by parts operators for finite
/// difference approximations of second derivatives*, J. Comput. Phys. 199 (2004)
/// 503–540 (the diagonal-norm operator of Strand (1994) with the free parameter of the
/// boundary closure fixed at the rational value used there, which puts
/// `D[5,6] = 342523/472620`); the exact fractions are those tabulated by
/// SummationByPartsOperators.jl (`MattssonNordström2004()`, order 6), whose decimal
/// expansions agree with other public SBP codes (e.g. the `ConservationLaws` OpenCL code).
/// Verified exactly as described in the module documentation.
pub const H_363: [Frac; 6] = [(13649, 43200), (12013, 8640), (2711, 4320), (5359, 4320), (7877, 8640), (43801, 43200)];
/// Left 6×9 boundary block of `Δt·D` for SBP363 (trailing zeros omitted).
pub const D_363: [&[Frac]; 6] = [
    &[(-21600, 13649), (104009, 54596), (30443, 81894), (-33311, 27298), (16863, 27298), (-15025, 163788)],
    &[(-104009, 240260), (0, 1), (-311, 72078), (20229, 24026), (-24337, 48052), (36661, 360390)],
    &[(-30443, 162660), (311, 32532), (0, 1), (-11155, 16266), (41287, 32532), (-21999, 54220)],
    &[(33311, 107180), (-20229, 21436), (485, 1398), (0, 1), (4147, 21436), (25427, 321540), (72, 5359)],
    &[(-16863, 78770), (24337, 31508), (-41287, 47262), (-4147, 15754), (0, 1), (342523, 472620), (-1296, 7877), (144, 7877)],
    &[
        (15025, 525612),
        (-36661, 262806),
        (21999, 87602),
        (-25427, 262806),
        (-342523, 525612),
        (0, 1),
        (32400, 43801),
        (-6480, 43801),
        (720, 43801),
    ],
];
/// Interior stencil of `Δt·D` for SBP363.
pub const INTERIOR_363: [Frac; 7] = [(-1, 60), (3, 20), (-3, 4), (0, 1), (3, 4), (-3, 20), (1, 60)];

/// SBP484: diagonal norm, eighth order inside, fourth order at the boundary.
///
/// Source: K. Mattsson & J. Nordström, *Summation by parts operators for finite
/// difference approximations of second derivatives*, J. Comput. Phys. 199 (2004)
/// 503–540, the eighth-order diagonal-norm first-derivative operator; the exact
/// fractions are those tabulated by SummationByPartsOperators.jl
/// (`MattssonNordström2004()`, order 8). Verified exactly as described in the module
/// documentation (N = 16 … 39). Its boundary closure has large coefficients (up to
/// about 130 in `Δt·D`), as the diagonal-norm operators of this order do.
pub const H_484: [Frac; 8] = [
    (1498139, 5080320),
    (1107307, 725760),
    (20761, 80640),
    (1304999, 725760),
    (299527, 725760),
    (103097, 80640),
    (670091, 725760),
    (5127739, 5080320),
];
/// Left 8×12 boundary block of `Δt·D` for SBP484 (trailing zeros omitted).
pub const D_484: [&[Frac]; 8] = [
    &[
        (-2540160, 1498139),
        (5544277, 5992556),
        (198794991, 29962780),
        (-256916579, 17977668),
        (20708767, 1498139),
        (-41004357, 5992556),
        (27390659, 17977668),
        (-2323531, 29962780),
    ],
    &[
        (-5544277, 31004596),
        (0, 1),
        (-85002381, 22146140),
        (49607267, 4429228),
        (-165990199, 13287684),
        (7655859, 1107307),
        (-7568311, 4429228),
        (48319961, 465068940),
    ],
    &[
        (-66264997, 8719620),
        (9444709, 415220),
        (0, 1),
        (-20335981, 249132),
        (32320879, 249132),
        (-35518713, 415220),
        (2502774, 103805),
        (-3177073, 1743924),
    ],
    &[
        (256916579, 109619916),
        (-49607267, 5219996),
        (61007943, 5219996),
        (0, 1),
        (-68748371, 5219996),
        (65088123, 5219996),
        (-66558305, 15659988),
        (3870214, 9134993),
    ],
    &[
        (-20708767, 2096689),
        (165990199, 3594324),
        (-96962637, 1198108),
        (68748371, 1198108),
        (0, 1),
        (-27294549, 1198108),
        (14054993, 1198108),
        (-42678199, 25160268),
        (-2592, 299527),
    ],
    &[
        (13668119, 8660148),
        (-850651, 103097),
        (35518713, 2061940),
        (-21696041, 1237164),
        (9098183, 1237164),
        (0, 1),
        (-231661, 412388),
        (7120007, 43300740),
        (3072, 103097),
        (-288, 103097),
    ],
    &[
        (-27390659, 56287644),
        (7568311, 2680364),
        (-22524966, 3350455),
        (66558305, 8041092),
        (-14054993, 2680364),
        (2084949, 2680364),
        (0, 1),
        (70710683, 93812740),
        (-145152, 670091),
        (27648, 670091),
        (-2592, 670091),
    ],
    &[
        (2323531, 102554780),
        (-48319961, 307664340),
        (9531219, 20510956),
        (-3870214, 5127739),
        (2246221, 3238572),
        (-21360021, 102554780),
        (-70710683, 102554780),
        (0, 1),
        (4064256, 5127739),
        (-1016064, 5127739),
        (193536, 5127739),
        (-18144, 5127739),
    ],
];
/// Interior stencil of `Δt·D` for SBP484.
pub const INTERIOR_484: [Frac; 9] = [(1, 280), (-4, 105), (1, 5), (-4, 5), (0, 1), (4, 5), (-1, 5), (4, 105), (-1, 280)];
