//! One step of DOP853: the work space of the stepper ([`Dop853`]), the stages, the
//! error estimate, an attempt of a step and why it is rejected, the dense output and
//! the first crossing of an event on it, and the initial step guess.
//!
//! The step-size control around the attempts and the requested times are the module
//! above's ([`integrate`](super::integrate)); the coefficients are in
//! [`tableau`](super::tableau).

use super::{tableau, EventHit, OdeOptions, OdeStats, RhsError};

/// Interior points (fractions of a step) where the event function is sampled.
pub(super) const EVENT_SAMPLES: [f64; 4] = [0.25, 0.5, 0.75, 1.0];

/// Why an attempt of a step was rejected ([`Dop853::attempt`]).
pub(super) enum Rejection {
    /// The right-hand side failed in a stage, at the time given.
    Failed((f64, RhsError)),
    /// The caller's test refused the step ([`integrate_checked`]).
    Refused,
    /// The error estimate is too large.
    TooLarge {
        /// `err^(1/8)`, which sets how much the step shrinks.
        fac11: f64,
    },
}

/// Which state a stage evaluation reads.
#[derive(Clone, Copy)]
pub(super) enum Stage {
    /// The current accepted state `y`.
    Y,
    /// The new solution `y_new`.
    YNew,
    /// The scratch stage state.
    Tmp,
}

/// Work space of the DOP853 stepper.
pub(super) struct Dop853<F> {
    f: F,
    n: usize,
    rtol: f64,
    atol: f64,
    /// Stage derivatives `k_0..k_15`.
    k: Vec<Vec<f64>>,
    y: Vec<f64>,
    pub(super) ynew: Vec<f64>,
    tmp: Vec<f64>,
    /// `Σ b_j k_j` of the current step.
    bk: Vec<f64>,
    /// Coefficients of the dense output polynomial of the current step.
    rcont: Vec<Vec<f64>>,
    pub(super) stats: OdeStats,
    /// `h·λ` of the last accepted step: the step times an estimate of the Jacobian's
    /// largest eigenvalue along the step's end, from the two stages at `t + h`
    /// (Hairer and Wanner, *Solving ODEs II*, IV.2). DOP853 is stable up to about 6.1.
    pub(super) h_lambda: f64,
}

impl<F> Dop853<F>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
{
    pub(super) fn new(f: F, y0: &[f64], opts: &OdeOptions) -> Self {
        let n = y0.len();
        Dop853 {
            f,
            n,
            rtol: opts.rtol,
            atol: opts.atol,
            k: vec![vec![0.0; n]; 16],
            y: y0.to_vec(),
            ynew: vec![0.0; n],
            tmp: vec![0.0; n],
            bk: vec![0.0; n],
            rcont: vec![vec![0.0; n]; 8],
            stats: OdeStats::default(),
            h_lambda: 0.0,
        }
    }

    /// `k[stage] = f(t, state)`; a non-finite derivative counts as a failure.
    pub(super) fn eval(&mut self, t: f64, state: Stage, stage: usize) -> Result<(), RhsError> {
        self.stats.rhs_evals += 1;
        let y = match state {
            Stage::Y => &self.y,
            Stage::YNew => &self.ynew,
            Stage::Tmp => &self.tmp,
        };
        let dy = &mut self.k[stage];
        dy.fill(0.0);
        (self.f)(t, y, dy)?;
        if let Some(i) = dy.iter().position(|v| !v.is_finite()) {
            return Err(RhsError(format!("the right-hand side returned a non-finite value in component {i}")));
        }
        Ok(())
    }

    /// Stage `i`: `tmp = y + h Σ_j a_ij k_j`, `k_i = f(t + c_i h, tmp)`.
    fn stage(&mut self, t: f64, h: f64, i: usize) -> Result<(), (f64, RhsError)> {
        self.tmp.copy_from_slice(&self.y);
        for (j, &a) in tableau::A[i].iter().enumerate() {
            if a != 0.0 {
                let ha = h * a;
                for (o, kj) in self.tmp.iter_mut().zip(&self.k[j]) {
                    *o += ha * kj;
                }
            }
        }
        let ti = t + tableau::C[i] * h;
        self.eval(ti, Stage::Tmp, i).map_err(|error| (ti, error))
    }

    /// Stages 1..=11 and the new solution `ynew = y + h Σ b_j k_j`.
    fn main_stages(&mut self, t: f64, h: f64) -> Result<(), (f64, RhsError)> {
        for i in 1..12 {
            self.stage(t, h, i)?;
        }
        self.bk.fill(0.0);
        for (j, &b) in tableau::A[12].iter().enumerate() {
            if b != 0.0 {
                for (o, kj) in self.bk.iter_mut().zip(&self.k[j]) {
                    *o += b * kj;
                }
            }
        }
        for ((yn, y), bk) in self.ynew.iter_mut().zip(&self.y).zip(&self.bk) {
            *yn = y + h * bk;
        }
        Ok(())
    }

    /// One attempt of the step from `(t, y)` of size `h` to `t_new`: the stages, the
    /// error estimate, the caller's test `accept`, then the first stage of the next step
    /// and, if `dense_wanted`, the dense output's stages. Accepted, it gives `err^(1/8)`
    /// (which sets the next step's size) with `ynew` the new state and `k[12]` its
    /// derivative.
    pub(super) fn attempt<C>(&mut self, t: f64, h: f64, t_new: f64, dense_wanted: bool, accept: &mut C) -> Result<f64, Rejection>
    where
        C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
    {
        self.main_stages(t, h).map_err(Rejection::Failed)?;
        let err = self.error_norm(h);
        let fac11 = err.powf(0.125);
        if err <= 1.0 {
            if !accept(t, &self.y, t_new, &self.ynew) {
                return Err(Rejection::Refused);
            }
            self.eval(t_new, Stage::YNew, 12).map_err(|error| Rejection::Failed((t_new, error)))?;
            self.h_lambda = self.h_lambda(h);
            if dense_wanted {
                self.dense_stages(t, h).map_err(Rejection::Failed)?;
            }
            Ok(fac11)
        } else {
            Err(Rejection::TooLarge { fac11 })
        }
    }

    /// `h·λ` of the step just taken: `h ‖f(t+h, y_new) − f(t+h, Y₁₁)‖ / ‖y_new − Y₁₁‖` with
    /// `Y₁₁` the last main stage's state, also at `t + h` (in `tmp` until the dense
    /// output's stages overwrite it).
    fn h_lambda(&self, h: f64) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..self.n {
            num += (self.k[12][i] - self.k[11][i]).powi(2);
            den += (self.ynew[i] - self.tmp[i]).powi(2);
        }
        if den > 0.0 {
            h.abs() * (num / den).sqrt()
        } else {
            0.0
        }
    }

    /// The current accepted state.
    pub(super) fn state(&self) -> &[f64] {
        &self.y
    }

    /// The first upward zero crossing of `event` in the accepted step from `(t, y)` of
    /// size `h` to `t_new` (before [`commit`](Self::commit)): sampled at
    /// [`EVENT_SAMPLES`], a sign change bracketed and bisected on the dense output down
    /// to round-off.
    pub(super) fn first_crossing<E>(&self, event: &mut E, t: f64, h: f64, t_new: f64) -> Option<EventHit>
    where
        E: FnMut(f64, &[f64]) -> f64,
    {
        let mut e_prev = event(t, &self.y);
        let mut th_prev = 0.0;
        for &th in &EVENT_SAMPLES {
            let y_th = if th == 1.0 { self.ynew.clone() } else { self.dense(th) };
            let e_th = event(t + th * h, &y_th);
            if e_prev < 0.0 && e_th >= 0.0 {
                let (mut a, mut b) = (th_prev, th);
                for _ in 0..200 {
                    let m = 0.5 * (a + b);
                    if m <= a || m >= b || (b - a) * h.abs() <= 4.0 * f64::EPSILON * t.abs().max(t_new.abs()) {
                        break;
                    }
                    if event(t + m * h, &self.dense(m)) < 0.0 {
                        a = m;
                    } else {
                        b = m;
                    }
                }
                let te = if b == 1.0 { t_new } else { t + b * h };
                let ye = if b == 1.0 { self.ynew.clone() } else { self.dense(b) };
                return Some(EventHit { t: te, y: ye });
            }
            e_prev = e_th;
            th_prev = th;
        }
        None
    }

    /// Scaled error of the step (≤ 1: accept), Hairer's combination of the 5th- and
    /// 3rd-order estimators. Non-finite values map to `+∞` (reject).
    fn error_norm(&self, h: f64) -> f64 {
        let (mut err, mut err2) = (0.0, 0.0);
        for i in 0..self.n {
            let sk = (self.atol + self.rtol * self.y[i].abs().max(self.ynew[i].abs())).max(f64::MIN_POSITIVE);
            let k = |j: usize| self.k[j][i];
            let e3 = self.bk[i] - tableau::BHH[0] * k(0) - tableau::BHH[1] * k(8) - tableau::BHH[2] * k(11);
            let e5: f64 = tableau::ER.iter().enumerate().map(|(j, &e)| e * k(j)).sum();
            err2 += (e3 / sk).powi(2);
            err += (e5 / sk).powi(2);
        }
        let mut deno = err + 0.01 * err2;
        if deno <= 0.0 {
            deno = 1.0;
        }
        let e = h.abs() * err / (self.n as f64 * deno).sqrt();
        if e.is_finite() {
            e
        } else {
            f64::INFINITY
        }
    }

    /// The three extra stages of the dense output and the interpolation coefficients
    /// (needs `k[12] = f(t + h, ynew)`).
    fn dense_stages(&mut self, t: f64, h: f64) -> Result<(), (f64, RhsError)> {
        for i in 13..16 {
            self.stage(t, h, i)?;
        }
        for i in 0..self.n {
            let ydiff = self.ynew[i] - self.y[i];
            let bspl = h * self.k[0][i] - ydiff;
            self.rcont[0][i] = self.y[i];
            self.rcont[1][i] = ydiff;
            self.rcont[2][i] = bspl;
            self.rcont[3][i] = ydiff - h * self.k[12][i] - bspl;
            for (r, d) in tableau::DENSE.iter().enumerate() {
                let mut acc = 0.0;
                for (j, &dj) in d.iter().enumerate() {
                    if dj != 0.0 {
                        acc += dj * self.k[j][i];
                    }
                }
                self.rcont[4 + r][i] = h * acc;
            }
        }
        Ok(())
    }

    /// Dense output at `θ = (t − t_old)/h ∈ [0, 1]` (Hairer's `contd8`).
    pub(super) fn dense(&self, theta: f64) -> Vec<f64> {
        let s = theta;
        let s1 = 1.0 - s;
        let r = &self.rcont;
        (0..self.n)
            .map(|i| {
                let conpar = r[4][i] + s * (r[5][i] + s1 * (r[6][i] + s * r[7][i]));
                r[0][i] + s * (r[1][i] + s1 * (r[2][i] + s * (r[3][i] + s1 * conpar)))
            })
            .collect()
    }

    /// Accept the step: `y ← ynew`, `k_0 ← k_12`.
    pub(super) fn commit(&mut self) {
        std::mem::swap(&mut self.y, &mut self.ynew);
        self.k.swap(0, 12);
    }

    /// Initial step size guess (Hairer's `hinit` for order 8); needs `k[0] = f(t, y)`.
    pub(super) fn hinit(&mut self, t: f64, hmax: f64) -> f64 {
        let sk: Vec<f64> = self.y.iter().map(|y| (self.atol + self.rtol * y.abs()).max(f64::MIN_POSITIVE)).collect();
        let dnf: f64 = self.k[0].iter().zip(&sk).map(|(f, s)| (f / s).powi(2)).sum();
        let dny: f64 = self.y.iter().zip(&sk).map(|(y, s)| (y / s).powi(2)).sum();
        let mut h = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
        if !(h.is_finite() && h > 0.0) {
            h = 1e-6;
        }
        h = h.min(hmax);
        // One explicit Euler step to estimate the second derivative.
        for i in 0..self.n {
            self.tmp[i] = self.y[i] + h * self.k[0][i];
        }
        if self.eval(t + h, Stage::Tmp, 1).is_err() {
            return h;
        }
        let der2 = self.k[1].iter().zip(&self.k[0]).zip(&sk).map(|((f1, f0), s)| ((f1 - f0) / s).powi(2)).sum::<f64>().sqrt() / h;
        let der12 = der2.max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 { (h * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / 8.0) };
        let h_new = (100.0 * h).min(h1).min(hmax);
        if h_new.is_finite() && h_new > 0.0 {
            h_new
        } else {
            h
        }
    }
}
