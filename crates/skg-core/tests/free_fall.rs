//! Free fall x'' = -g against its closed form x = x0 + v0 t - g t²/2.

mod common;

use common::G;

use skg_core::scene::{Formulation, Overrides};

const X0: f64 = 10.0;
const V0: f64 = 3.0;

fn exact(t: f64) -> Vec<f64> {
    vec![X0 + V0 * t - 0.5 * G * t * t]
}

#[test]
fn sbp242_is_exact_for_free_fall() {
    for formulation in [Formulation::Reduced, Formulation::Full] {
        let o = common::solve("free_fall", &Overrides { formulation: Some(formulation), ..Default::default() });
        let err = common::max_error(&o, &[0], 0, exact);
        assert!(err < 1e-10, "{formulation}: max error {err:e}");
        // Velocity Dq is exact too, and the energy is conserved to round-off at every node.
        for (k, t) in o.trajectory.t.iter().enumerate() {
            assert!((o.trajectory.v[k][0] - (V0 - G * t)).abs() < 1e-9, "velocity at t={t}");
        }
        assert!(o.diagnostics.energy_drift_all < 1e-9, "energy drift {:e}", o.diagnostics.energy_drift_all);
    }
}

#[test]
fn sbp121_converges_at_second_order_on_free_fall() {
    let ns = [16, 32, 64, 128];
    let errors: Vec<f64> =
        ns.iter().map(|&n| common::max_error(&common::solve("free_fall", &common::grid(n, "SBP121")), &[0], 0, exact)).collect();
    let h: Vec<f64> = ns.iter().map(|&n| 2.0 / (n as f64 - 1.0)).collect();
    let fit = skg_core::convergence::fit_order(&h, &errors, 1e-12).expect("enough points");
    assert!((fit.order - 2.0).abs() < 0.15, "SBP121 order {} from errors {errors:?}", fit.order);
}

#[test]
fn sbp363_is_exact_for_free_fall() {
    let o = common::solve("free_fall", &common::grid(24, "SBP363"));
    let err = common::max_error(&o, &[0], 0, exact);
    assert!(err < 1e-10, "max error {err:e}");
}
