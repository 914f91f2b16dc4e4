//! Time stepping: the scene's equations of motion integrated in time, independently of
//! the SBP discretization, and what is made from it.
//!
//! * [`ode`]: the adaptive DOP853 integrator with dense output and event location (its
//!   coefficients in `ode/tableau.rs`, its tests in `ode/tests.rs`).
//! * [`radau`]: the implicit Radau IIA integrator of order 5 for stiff equations, with
//!   the same contract (its coefficients in `radau/coefficients.rs`).
//! * [`integrate`](mod@integrate): the stepper the options name, or the automatic choice:
//!   DOP853 until the equation is found stiff, then Radau IIA.
//! * [`layer`]: whether a motion starts with a fast layer the grid does not resolve
//!   (then the natural initial-velocity condition is the accurate one).
//! * [`equations`]: the index-reduced Lagrange–d'Alembert equations of a model
//!   integrated by it and sampled at given times ([`integrate_model`]).
//! * [`verify`]: a trajectory compared with time stepping of the same scene at its nodes,
//!   the odd-even amplitude, non-finite numbers ([`Verification`]).
//! * [`reference`](mod@reference): reference solutions, regularized or with hard walls, with their
//!   provenance ([`Reference`]).
//!
//! **Place in the flow.** After the discretization: it uses [`scene`](crate::scene),
//! [`memory`](crate::memory), [`model`](crate::model) and [`discrete`](crate::discrete)
//! (the trajectory type and contact), nothing after it. The verification solves
//! nothing itself, so it sits here, below its callers, which also make initial guesses
//! with [`integrate_model`].

pub mod equations;
pub mod integrate;
pub mod layer;
pub mod ode;
pub mod radau;
pub mod reference;
pub mod verify;

pub use equations::integrate_model;
pub use reference::{Reference, ReferenceError, ReferenceOptions};
pub use verify::{Verification, VerifyStatus};
