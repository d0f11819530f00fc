//! The contract between the driver and an integration method: the crate-private [`Stepper`]
//! trait every method implements, the [`StepDense`] interpolant it hands back, and the stage
//! combinations the explicit methods share.

use super::{Dense, OdeSystem, Stats};
use nalgebra::SVector;

/// The dense output of one step, as the driver needs it.
pub(crate) trait StepDense<const N: usize>: Dense<N> {
    /// Right-hand-side evaluations made so far by lazy evaluation of this interpolant.
    fn extra_rhs(&self) -> u64 {
        0
    }
}

/// One integration method, as a value that holds its stages between calls.
pub(crate) trait Stepper<const N: usize, S: OdeSystem<N>> {
    /// Classical order of the propagated solution (for the starting step).
    const ORDER: u32;
    /// The error estimate scales as `h^ERR_EXP` (the controller's exponent is its inverse).
    const ERR_EXP: u32;
    /// PI weight of the previous error.
    const BETA: f64;
    /// Gustafsson's predictive step control (stiff methods).
    const PREDICTIVE: bool;

    /// The interpolant of the last attempted step.
    type Dense<'a>: StepDense<N>
    where
        Self: 'a,
        S: 'a;

    /// A fresh stepper.
    fn new() -> Self;

    /// A step is about to start at `(t, y)` with `f = f(t, y)` (first attempt from this point).
    #[inline]
    fn begin(
        &mut self,
        _sys: &S,
        _mode: S::Mode,
        _t: f64,
        _y: &SVector<f64, N>,
        _f: &SVector<f64, N>,
        _stats: &mut Stats,
    ) {
    }

    /// Attempt a step of size `h`: the new state and the error norm (`<= 1` accepts; NaN or
    /// infinite when the step failed).
    #[allow(clippy::too_many_arguments)]
    fn try_step(
        &mut self,
        sys: &S,
        mode: S::Mode,
        t: f64,
        y: &SVector<f64, N>,
        f: &SVector<f64, N>,
        h: f64,
        atol: &SVector<f64, N>,
        rtol: f64,
        stats: &mut Stats,
    ) -> (SVector<f64, N>, f64);

    /// The attempted step is accepted: `f(t + h, y_new)` (FSAL stage or a new evaluation).
    fn finish(
        &mut self,
        sys: &S,
        mode: S::Mode,
        t: f64,
        h: f64,
        y_new: &SVector<f64, N>,
        stats: &mut Stats,
    ) -> SVector<f64, N>;

    /// The interpolant of the accepted step `[t, t + h]` from `y0` to `y1`.
    fn dense<'a>(
        &'a self,
        sys: &'a S,
        mode: S::Mode,
        t: f64,
        h: f64,
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
    ) -> Self::Dense<'a>;
}

/// `y + h * sum_j a[j] k[j]`, component by component: one pass, no temporaries (the stage
/// combinations of the explicit methods are the hot loop next to the right-hand side).
#[inline(always)]
pub(crate) fn combine<const N: usize, const K: usize>(
    y: &SVector<f64, N>,
    h: f64,
    a: [f64; K],
    k: [&SVector<f64, N>; K],
) -> SVector<f64, N> {
    let mut out = *y;
    for i in 0..N {
        let mut s = 0.0;
        for j in 0..K {
            s += a[j] * k[j][i];
        }
        out[i] += h * s;
    }
    out
}

/// `sum_j a[j] k[j]` (an error estimate or an interpolation coefficient).
#[inline(always)]
pub(crate) fn weighted<const N: usize, const K: usize>(a: [f64; K], k: [&SVector<f64, N>; K]) -> SVector<f64, N> {
    let mut out = SVector::<f64, N>::zeros();
    for i in 0..N {
        let mut s = 0.0;
        for j in 0..K {
            s += a[j] * k[j][i];
        }
        out[i] = s;
    }
    out
}
