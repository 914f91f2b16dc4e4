//! Observed order of convergence from a refinement study, in the style of the
//! convergence tests of GeometricIntegrators.jl: a least-squares fit of
//! `log(error)` against `log(h)`, with the round-off plateau masked out.
//!
//! `h` is whatever measure of resolution the caller uses (a step size, or `1/N`); it is
//! taken as given. Refinement means decreasing `h`.
//!
//! **Place in the flow.** The first stage, beside the operators: numbers only, it uses
//! nothing else of this crate (the operators' tests fit their orders with it).

/// Result of [`fit_order`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OrderFit {
    /// Least-squares slope of `log(error)` vs `log(h)`.
    pub order: f64,
    /// Number of points the fit used.
    pub points_used: usize,
    /// Number of points left out (non-finite or non-positive data, errors below the
    /// floor, points on the round-off plateau).
    pub masked: usize,
}

/// Error ratio between successive refinements below which the error counts as having
/// stopped decreasing (round-off plateau).
pub const PLATEAU_RATIO: f64 = 1.5;

/// Least-squares slope of `log(error)` vs `log(h)`, masking the round-off plateau.
///
/// Points are ordered from coarse to fine (decreasing `h`). Left out are: pairs with a
/// non-finite or non-positive `h` or error; points whose error is below `floor` (e.g.
/// `1e-11`); and, walking from coarse to fine, every point from the first one whose error
/// is less than [`PLATEAU_RATIO`] times smaller than the previous kept point's error on
/// (the error has stopped decreasing). Once three points are kept, a point whose pairwise
/// observed order (against the previous kept point) is below half of the slope fitted so
/// far also ends the fit (a noisy plateau can show a single ratio above 1.5). Refinements should therefore shrink `h` by a
/// factor large enough that the expected error ratio exceeds 1.5 (e.g. a factor ≥ 1.5 for
/// first-order methods).
///
/// Returns `None` if fewer than two points are left or the lengths of `h` and `errors`
/// differ.
pub fn fit_order(h: &[f64], errors: &[f64], floor: f64) -> Option<OrderFit> {
    if h.len() != errors.len() {
        return None;
    }
    let total = h.len();
    let mut pts: Vec<(f64, f64)> = h
        .iter()
        .zip(errors)
        .filter(|(&x, &e)| x.is_finite() && x > 0.0 && e.is_finite() && e > 0.0 && e >= floor)
        .map(|(&x, &e)| (x, e))
        .collect();
    // Coarse to fine.
    pts.sort_by(|a, b| b.0.total_cmp(&a.0));

    let mut kept: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
    for &(x, e) in &pts {
        if let Some(&(xp, ep)) = kept.last() {
            if x >= xp || ep / e < PLATEAU_RATIO {
                break;
            }
            // A noisy plateau can still show one ratio above 1.5: once three points set a
            // trend, a pair whose observed order falls below half of it ends the fit too.
            if kept.len() >= 3 {
                if let Some(trend) = least_squares_slope(&kept) {
                    let pair = (ep / e).ln() / (xp / x).ln();
                    if trend > 0.0 && pair < 0.5 * trend {
                        break;
                    }
                }
            }
        }
        kept.push((x, e));
    }
    if kept.len() < 2 {
        return None;
    }
    let order = least_squares_slope(&kept)?;
    Some(OrderFit { order, points_used: kept.len(), masked: total - kept.len() })
}

/// Slope of the least-squares line through `(ln h, ln e)`; `None` if all `h` are equal.
fn least_squares_slope(pts: &[(f64, f64)]) -> Option<f64> {
    let m = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(sx, sy), &(x, e)| (sx + x.ln(), sy + e.ln()));
    let (mx, my) = (sx / m, sy / m);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for &(x, e) in pts {
        let dx = x.ln() - mx;
        sxy += dx * (e.ln() - my);
        sxx += dx * dx;
    }
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Pairwise observed orders `log(e_i/e_{i+1}) / log(h_i/h_{i+1})`, one per successive
/// pair (`min(len) − 1` values; NaN where a pair has non-positive data or equal `h`).
pub fn pairwise_orders(h: &[f64], errors: &[f64]) -> Vec<f64> {
    let n = h.len().min(errors.len());
    (1..n)
        .map(|i| {
            let (h0, h1, e0, e1) = (h[i - 1], h[i], errors[i - 1], errors[i]);
            if h0 > 0.0 && h1 > 0.0 && e0 > 0.0 && e1 > 0.0 && h0 != h1 {
                (e0 / e1).ln() / (h0 / h1).ln()
            } else {
                f64::NAN
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<f64> {
        (0..21).map(|k| 0.5f64.powi(k)).collect()
    }

    #[test]
    fn cubic_with_roundoff_plateau() {
        let h = grid();
        // e = 3 h³ until it reaches a plateau of 1e-14 with some wobble.
        let e: Vec<f64> =
            h.iter().enumerate().map(|(k, x)| (3.0 * x.powi(3)).max(1e-14 * (1.0 + 0.3 * ((k as f64) * 1.7).sin()))).collect();
        let fit = fit_order(&h, &e, 1e-16).unwrap();
        assert!((fit.order - 3.0).abs() < 0.01, "{fit:?}");
        assert!(fit.masked > 0);
        assert_eq!(fit.points_used + fit.masked, h.len());
        // With a floor above the plateau the same points are used.
        let fit2 = fit_order(&h, &e, 1e-11).unwrap();
        assert!((fit2.order - 3.0).abs() < 0.01, "{fit2:?}");
        // Unordered input gives the same answer.
        let (mut hr, mut er) = (h.clone(), e.clone());
        hr.reverse();
        er.reverse();
        assert_eq!(fit_order(&hr, &er, 1e-16), Some(fit));
    }

    #[test]
    fn noisy_second_order() {
        let h: Vec<f64> = (0..8).map(|k| 0.1 / 1.8f64.powi(k)).collect();
        let e: Vec<f64> = h.iter().enumerate().map(|(k, x)| 5.0 * x * x * (1.0 + 0.05 * ((k as f64) * 2.3).sin())).collect();
        let fit = fit_order(&h, &e, 1e-11).unwrap();
        assert_eq!(fit.points_used, h.len());
        assert!((fit.order - 2.0).abs() < 0.05, "{fit:?}");
        let pw = pairwise_orders(&h, &e);
        assert_eq!(pw.len(), h.len() - 1);
        assert!(pw.iter().all(|o| (o - 2.0).abs() < 0.3), "{pw:?}");
    }

    #[test]
    fn too_few_points() {
        assert_eq!(fit_order(&[], &[], 1e-11), None);
        assert_eq!(fit_order(&[0.1], &[1e-3], 1e-11), None);
        assert_eq!(fit_order(&[0.1, 0.05], &[1e-3], 1e-11), None);
        // All but one below the floor.
        assert_eq!(fit_order(&[0.1, 0.05, 0.025], &[1e-3, 1e-13, 1e-14], 1e-11), None);
        // Plateau right away.
        assert_eq!(fit_order(&[0.1, 0.05, 0.025], &[1e-3, 0.9e-3, 1e-3], 1e-11), None);
        // Bad data is masked, not fatal.
        let fit = fit_order(&[0.1, f64::NAN, 0.05, 0.025], &[1e-2, 1.0, 2.5e-3, 6.25e-4], 1e-11).unwrap();
        assert!((fit.order - 2.0).abs() < 1e-12);
        assert_eq!((fit.points_used, fit.masked), (3, 1));
        assert!(pairwise_orders(&[0.1], &[1.0]).is_empty());
        assert!(pairwise_orders(&[0.1, 0.1], &[1.0, 0.5])[0].is_nan());
    }
}
