//! A fast initial layer: a motion whose initial velocity is not the one its slow motion
//! has, so that the velocity relaxes within a small fraction of the grid's first step (an
//! overdamped spring released at rest: its velocity reaches the slow creep in `m/c`
//! seconds). A strong initial-velocity condition imposes the velocity from before the
//! layer at the first node, an error of about the slow velocity times the grid step that
//! falls only as `1/N`; the natural condition (docs/mathematics.md §5) lets the first
//! node's velocity be solved for, and is accurate at once. The solve chooses it when the
//! scene names no condition and [`initial_layer`] finds a layer.
//!
//! The test: the velocity's change over the grid's first step, `Δv`, measured by time
//! stepping, against the initial acceleration `a₀`: the time scale `τ = |Δv| / |a₀|` of the
//! change is about the step on a motion the grid follows (free fall: `τ = Δt`), and a
//! small fraction of it when the velocity relaxes fast and then creeps. A layer must also
//! be over early: the change after [`LAYER_FRACTION`] of the step is already within half
//! of `Δv` (a bounce inside the first step, whose velocity comes back to nearly what it
//! was, has a small `Δv` too, but not reached early and kept), and be seen at all (a
//! change below the velocity's rounding is none).

use crate::model::Model;
use crate::scene::{rounded_number, Scene};
use crate::stepping::equations::integrate_states;
use crate::stepping::ode::OdeOptions;

/// A layer is one whose time scale is below this fraction of the grid's first step.
pub const LAYER_FRACTION: f64 = 0.1;

/// A fast initial layer ([`initial_layer`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialLayer {
    /// The time scale of the velocity's change, `|Δv| / |a₀|`, seconds.
    pub relaxation: f64,
    /// The grid's first step, seconds.
    pub step: f64,
}

impl std::fmt::Display for InitialLayer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "a fast initial layer: the velocity relaxes within {} s of the start, where the grid's first step is {} s",
            rounded_number(self.relaxation),
            rounded_number(self.step)
        )
    }
}

/// The fast initial layer of `scene` (with its model `model`) on a grid whose first step
/// is `step`, if it has one (module docs). `None` also when the time stepping over the
/// first step fails (the verification will say why) or nothing accelerates at the start.
pub fn initial_layer(scene: &Scene, model: &Model, step: f64) -> Option<InitialLayer> {
    let (q0, v0) = (&scene.initial_q, &scene.initial_v);
    let (a0, _) = model.accelerations(scene.t_start, q0, v0, &mut model.workspace()).ok()?;
    let initial = max_abs(&a0);
    if !(initial > 0.0 && initial.is_finite()) {
        return None;
    }
    let opts = OdeOptions { rtol: 1e-8, atol: 1e-10, ..OdeOptions::default() };
    let times = [scene.t_start, scene.t_start + LAYER_FRACTION * step, scene.t_start + step];
    let stepped = integrate_states(model, q0, v0, &times, &opts).ok()?;
    let d = q0.len();
    let change = |k: usize| -> Vec<f64> { stepped.states[k][d..].iter().zip(v0).map(|(v1, v0)| v1 - v0).collect() };
    let (early, whole) = (change(1), change(2));
    let relaxation = max_abs(&whole) / initial;
    let early_gap: Vec<f64> = early.iter().zip(&whole).map(|(e, w)| e - w).collect();
    let over_early = max_abs(&early_gap) <= 0.5 * max_abs(&whole);
    // A change lost in the velocity's rounding is no layer (a force of 1e-80 at the start).
    let seen = max_abs(&whole) > 100.0 * f64::EPSILON * (max_abs(v0) + initial * step);
    (relaxation < LAYER_FRACTION * step && over_early && seen).then_some(InitialLayer { relaxation, step })
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Overrides, SceneFile};

    fn scene(lagrangian: &str, force: &str, v0: f64) -> (Scene, Model) {
        let text = format!(
            "[scene]\nname = \"s\"\nlagrangian = \"{lagrangian}\"\n[[coordinates]]\nname = \"x\"\ninitial = 1\nvelocity = {v0}\n\
             [forces]\nx = \"{force}\"\n[time]\nstart = 0\nend = 100\nnodes = 64\n"
        );
        let s = SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
        let m = Model::build(&s).unwrap();
        (s, m)
    }

    /// An overdamped spring released at rest (`c = 10⁴`): its velocity reaches the creep
    /// `−x/c` within `1/c` s; a step of 1.6 s does not see it. Released at its creep
    /// velocity, it has no layer; neither has free fall.
    #[test]
    fn an_overdamped_release_has_a_layer_and_a_smooth_motion_has_none() {
        let step = 100.0 / 63.0;
        let (s, m) = scene("x_dot^2/2 - x^2/2", "-1e4*x_dot", 0.0);
        let layer = initial_layer(&s, &m, step).expect("a layer");
        assert!((layer.relaxation - 1e-4).abs() < 1e-5, "{layer:?}");
        let (s, m) = scene("x_dot^2/2 - x^2/2", "-1e4*x_dot", -1e-4);
        assert_eq!(initial_layer(&s, &m, step), None);
        let (s, m) = scene("x_dot^2/2 - 9.8*x", "0", 0.0);
        assert_eq!(initial_layer(&s, &m, step), None);
        // A fast undamped oscillation (period 0.1 s) whose velocity is back near its start
        // after the step: a small change, not reached early.
        let step = 0.1 * (1.0 + 1e-3);
        let (s, m) = scene("x_dot^2/2 - 2*pi^2*100*x^2", "0", 0.0);
        assert_eq!(initial_layer(&s, &m, step), None);
        // A force far below the velocity's rounding at the start (a particle at 1 m/s
        // far from a Gaussian wall): no change of the velocity is seen.
        let (s, m) = scene("x_dot^2/2", "exp(-200*(x - 2)^2)", 1.0);
        assert_eq!(initial_layer(&s, &m, 0.03), None);
    }
}
