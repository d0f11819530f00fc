//! # tribosweep-core
//!
//! Numerics of tribosweep, free of Python types so that `cargo test` covers them alone.
//!
//! A tour, in the order a computation flows:
//! - [`model`]: the 3-DOF pin-on-disk slider of the 1985 report (MODEL.md §2-3): parameters with
//!   their valid ranges, the static point, the right-hand side for bilateral and unilateral contact,
//!   constant or regularised Coulomb/Stribeck friction, its analytic Jacobian and contact events.
//! - [`ode`]: adaptive integrators on stack states (Dormand-Prince 5(4), DOP853, Rodas4) with dense
//!   output and event location, so that contact switches are integrated through, never stepped
//!   across; and the kit of lane-batched (SIMD) integration. Generic: it knows nothing of the slider.
//! - [`steady`]: run a trajectory to its steady state (decay to sliding, periodic cycle, escape) and
//!   summarise it: frequency, harmonics of `z`, `phi`, `x`, minimum normal force, time off the disk.
//! - [`parallel`]: many independent computations on a thread pool (rayon), deterministic for any
//!   thread count, one panic caught per point.
//! - [`ensemble`]: many slider trajectories at once: the routing policy between the lane-batched
//!   paths (`ensemble::batch`, `ensemble::lanes`) and the scalar driver, one entry point.
//! - [`linear`], [`tidf`], [`shooting`]: linear stability of steady sliding, the triple-input
//!   describing function with all its roots, periodic orbits with Floquet multipliers.
//! - [`branch`]: branches of periodic orbits by pseudo-arclength continuation, with folds, period
//!   doublings, torus and grazing points located on them, and two-parameter curves of folds and grazing.
//! - [`status`]: the per-point status codes and the failures behind them, defined in one place.
//! - [`cancel`]: the caller's stop request, looked at by every long loop (a leaf module).

pub mod branch;
pub mod cancel;
pub mod ensemble;
pub mod hopf;
pub mod linear;
pub mod model;
pub mod ode;
pub mod parallel;
pub mod shooting;
pub mod status;
pub mod steady;
pub mod tidf;

pub use model::{ContactMode, ContactModel, FrictionLaw, ParamError, Params, Slider, State};
pub use status::{Failure, Status};
