//! Dormand–Prince 5(4) (Hairer's DOPRI5): 7 stages, first same as last (6 new right-hand sides
//! per step), local extrapolation (the 5th-order solution is propagated), and Shampine's
//! 4th-order continuous extension as coded in Hairer's `dopri5.f` (`contd5`), which needs no
//! extra evaluation.
//!
//! Coefficients: Dormand & Prince (1980), dense output Shampine (1986), as published in
//! Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5–II.6.

use super::controller::error_norm;
use super::stepper::{combine, weighted, StepDense, Stepper};
use super::{Dense, OdeSystem, Stats};
use nalgebra::SVector;

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
pub(crate) const A21: f64 = 1.0 / 5.0;
pub(crate) const A31: f64 = 3.0 / 40.0;
pub(crate) const A32: f64 = 9.0 / 40.0;
pub(crate) const A41: f64 = 44.0 / 45.0;
pub(crate) const A42: f64 = -56.0 / 15.0;
pub(crate) const A43: f64 = 32.0 / 9.0;
pub(crate) const A51: f64 = 19372.0 / 6561.0;
pub(crate) const A52: f64 = -25360.0 / 2187.0;
pub(crate) const A53: f64 = 64448.0 / 6561.0;
pub(crate) const A54: f64 = -212.0 / 729.0;
pub(crate) const A61: f64 = 9017.0 / 3168.0;
pub(crate) const A62: f64 = -355.0 / 33.0;
pub(crate) const A63: f64 = 46732.0 / 5247.0;
pub(crate) const A64: f64 = 49.0 / 176.0;
pub(crate) const A65: f64 = -5103.0 / 18656.0;
pub(crate) const B1: f64 = 35.0 / 384.0;
pub(crate) const B3: f64 = 500.0 / 1113.0;
pub(crate) const B4: f64 = 125.0 / 192.0;
pub(crate) const B5: f64 = -2187.0 / 6784.0;
pub(crate) const B6: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order minus embedded 4th-order weights.
pub(crate) const E1: f64 = 71.0 / 57600.0;
pub(crate) const E3: f64 = -71.0 / 16695.0;
pub(crate) const E4: f64 = 71.0 / 1920.0;
pub(crate) const E5: f64 = -17253.0 / 339200.0;
pub(crate) const E6: f64 = 22.0 / 525.0;
pub(crate) const E7: f64 = -1.0 / 40.0;
// Shampine's dense-output coefficients.
pub(crate) const D1: f64 = -12715105075.0 / 11282082432.0;
pub(crate) const D3: f64 = 87487479700.0 / 32700410799.0;
pub(crate) const D4: f64 = -10690763975.0 / 1880347072.0;
pub(crate) const D5: f64 = 701980252875.0 / 199316789632.0;
pub(crate) const D6: f64 = -1453857185.0 / 822651844.0;
pub(crate) const D7: f64 = 69997945.0 / 29380423.0;

/// The Dopri5 stepper: the seven stages of the last attempted step.
pub(crate) struct Dopri5<const N: usize> {
    k: [SVector<f64, N>; 7],
}

/// Dopri5's interpolant on one step; evaluated straight from the stages (no per-step set-up
/// cost when nobody asks for it).
pub(crate) struct Dopri5Dense<'a, const N: usize> {
    k: &'a [SVector<f64, N>; 7],
    y0: &'a SVector<f64, N>,
    y1: &'a SVector<f64, N>,
    t0: f64,
    h: f64,
}

impl<'a, const N: usize> Dopri5Dense<'a, N> {
    /// The interpolant of a step `[t0, t0 + h]` from `y0` to `y1` with stages `k` (for callers
    /// that keep the stages themselves, as the lane-batched stepper does).
    pub(crate) fn from_stages(
        k: &'a [SVector<f64, N>; 7],
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
        t0: f64,
        h: f64,
    ) -> Self {
        Dopri5Dense { k, y0, y1, t0, h }
    }
}

impl<const N: usize> Dense<N> for Dopri5Dense<'_, N> {
    #[inline]
    fn eval(&self, t: f64) -> SVector<f64, N> {
        let k = self.k;
        let h = self.h;
        let th = (t - self.t0) / h;
        let th1 = 1.0 - th;
        let dy = self.y1 - self.y0;
        let bspl = k[0] * h - dy;
        let r4 = dy - k[6] * h - bspl;
        let r5 = weighted([D1 * h, D3 * h, D4 * h, D5 * h, D6 * h, D7 * h], [&k[0], &k[2], &k[3], &k[4], &k[5], &k[6]]);
        self.y0 + (dy + (bspl + (r4 + r5 * th1) * th) * th1) * th
    }

    fn end_rates(&self) -> Option<super::EndRates<N>> {
        // First same as last: k7 is f(t0 + h, y1).
        Some(((self.t0, self.t0 + self.h), (self.k[0], self.k[6])))
    }
}

impl<const N: usize> StepDense<N> for Dopri5Dense<'_, N> {}

impl<const N: usize, S: OdeSystem<N>> Stepper<N, S> for Dopri5<N> {
    const ORDER: u32 = 5;
    const ERR_EXP: u32 = 5;
    const BETA: f64 = 0.04;
    const PREDICTIVE: bool = false;

    type Dense<'a>
        = Dopri5Dense<'a, N>
    where
        Self: 'a,
        S: 'a;

    fn new() -> Self {
        Dopri5 { k: [SVector::zeros(); 7] }
    }

    #[inline]
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
    ) -> (SVector<f64, N>, f64) {
        let k1 = *f;
        let k2 = sys.rhs(t + C2 * h, &combine(y, h, [A21], [&k1]), mode);
        let k3 = sys.rhs(t + C3 * h, &combine(y, h, [A31, A32], [&k1, &k2]), mode);
        let k4 = sys.rhs(t + C4 * h, &combine(y, h, [A41, A42, A43], [&k1, &k2, &k3]), mode);
        let k5 = sys.rhs(t + C5 * h, &combine(y, h, [A51, A52, A53, A54], [&k1, &k2, &k3, &k4]), mode);
        let k6 = sys.rhs(t + h, &combine(y, h, [A61, A62, A63, A64, A65], [&k1, &k2, &k3, &k4, &k5]), mode);
        let y_new = combine(y, h, [B1, B3, B4, B5, B6], [&k1, &k3, &k4, &k5, &k6]);
        let k7 = sys.rhs(t + h, &y_new, mode);
        stats.n_rhs += 6;
        let err = weighted([E1 * h, E3 * h, E4 * h, E5 * h, E6 * h, E7 * h], [&k1, &k3, &k4, &k5, &k6, &k7]);
        self.k = [k1, k2, k3, k4, k5, k6, k7];
        (y_new, error_norm(&err, y, &y_new, atol, rtol))
    }

    #[inline]
    fn finish(
        &mut self,
        _sys: &S,
        _mode: S::Mode,
        _t: f64,
        _h: f64,
        _y_new: &SVector<f64, N>,
        _stats: &mut Stats,
    ) -> SVector<f64, N> {
        // First same as last: the 7th stage is f(t + h, y_new).
        self.k[6]
    }

    #[inline]
    fn dense<'a>(
        &'a self,
        _sys: &'a S,
        _mode: S::Mode,
        t: f64,
        h: f64,
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
    ) -> Dopri5Dense<'a, N> {
        Dopri5Dense { k: &self.k, y0, y1, t0: t, h }
    }
}
