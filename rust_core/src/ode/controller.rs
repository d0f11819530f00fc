//! Step-size control: the error norm, the PI controller and the starting step.
//!
//! - [`error_norm`] is Hairer's weighted RMS norm; a step is accepted when it is `<= 1`.
//! - [`Controller`] is the PI (Gustafsson/Hairer) controller of DOPRI5/DOP853,
//!   `h_new = h * safety * err^-alpha * err_old^beta`, clipped to `[facmin, facmax] * h`, with no
//!   growth right after a rejection. For Rodas4 it adds Gustafsson's predictive factor (as in
//!   Hairer's `rodas.f`), which copes better with the error behaviour of stiff problems.
//! - [`initial_step`] is Hairer's starting-step algorithm (`hinit` of `dopri5.f`), in RMS norms.
//! - [`ModeSteps`] is the first step after a mode switch: no larger than the step the run had
//!   when it last left the mode it enters.

use super::OdeSystem;
use nalgebra::SVector;

/// Weighted RMS norm of an error estimate:
/// `sqrt(mean_i (err_i / (atol_i + rtol * max(|y0_i|, |y1_i|)))^2)`.
/// NaN or infinity in any input propagates to the result (the driver then rejects the step).
#[inline]
pub fn error_norm<const N: usize>(
    err: &SVector<f64, N>,
    y0: &SVector<f64, N>,
    y1: &SVector<f64, N>,
    atol: &SVector<f64, N>,
    rtol: f64,
) -> f64 {
    let mut s = 0.0;
    for i in 0..N {
        let sk = atol[i] + rtol * y0[i].abs().max(y1[i].abs());
        let q = err[i] / sk;
        s += q * q;
    }
    (s / N as f64).sqrt()
}

/// Safety factor on the optimal step.
pub const SAFETY: f64 = 0.9;
/// `ln SAFETY`.
const LN_SAFETY: f64 = -0.105_360_515_657_826_3;
/// Smallest step ratio `h_new / h` in one adjustment.
pub const FAC_MIN: f64 = 0.2;
/// Largest step ratio `h_new / h` in one adjustment.
pub const FAC_MAX: f64 = 10.0;

/// PI step-size controller (Hairer's DOPRI5/DOP853 form) with optional Gustafsson prediction.
///
/// Works on logarithms: one `ln` and one `exp` per step instead of Hairer's two `pow` calls
/// (which cost as much as a right-hand side of the slider); the results agree to rounding.
#[derive(Clone, Copy, Debug)]
pub struct Controller {
    /// Exponent on the current error, `1/k - 0.75 beta` with `k` the error estimate's order + 1.
    alpha: f64,
    /// Exponent on the previous accepted error (0: a plain I controller).
    beta: f64,
    /// Use Gustafsson's predictive factor (stiff methods).
    predictive: bool,
    /// `ln` of the previous accepted error (floored at 1e-4 as in Hairer's codes).
    ln_err_old: f64,
    /// Previous accepted step and `ln` of its error, for the predictive factor (`h_acc <= 0`: none).
    h_acc: f64,
    ln_err_acc: f64,
}

/// `ln 1e-4`: Hairer's floor on the remembered error.
const LN_ERR_FLOOR: f64 = -9.210_340_371_976_184;
/// `ln 1e-2`: `rodas.f`'s floor on the error remembered for the predictive factor.
const LN_ERR_ACC_FLOOR: f64 = -4.605_170_185_988_091;

impl Controller {
    /// A controller for an error estimate that scales as `h^k` (`k = 5` for Dopri5, 8 for
    /// DOP853's combined estimate, 4 for Rodas4) with PI weight `beta`.
    pub fn new(k: u32, beta: f64, predictive: bool) -> Self {
        Controller {
            alpha: 1.0 / k as f64 - 0.75 * beta,
            beta,
            predictive,
            ln_err_old: LN_ERR_FLOOR,
            h_acc: 0.0,
            ln_err_acc: LN_ERR_ACC_FLOOR,
        }
    }

    /// Forget the step history (at a restart after a mode switch the error behaviour changes).
    pub fn reset(&mut self) {
        self.ln_err_old = LN_ERR_FLOOR;
        self.h_acc = 0.0;
        self.ln_err_acc = LN_ERR_ACC_FLOOR;
    }

    /// Step ratio `h_new / h` after accepting a step of size `h` with error `err <= 1`.
    #[inline]
    pub fn accept(&mut self, h: f64, err: f64) -> f64 {
        if err <= 0.0 {
            // A zero error estimate: the largest growth (ln would be -inf).
            self.ln_err_old = LN_ERR_FLOOR;
            if self.predictive {
                self.h_acc = h;
                self.ln_err_acc = LN_ERR_ACC_FLOOR;
            }
            return FAC_MAX;
        }
        let ln_err = err.ln();
        // ln(1/ratio) = alpha ln err - beta ln err_old - ln safety, as in Hairer's codes
        // (fac = err^alpha / err_old^beta / safety, h_new = h / fac).
        let mut ln_fac = self.alpha * ln_err - self.beta * self.ln_err_old - LN_SAFETY;
        if self.predictive && self.h_acc > 0.0 {
            // Gustafsson: use the error trend of the last two accepted steps; never let it
            // increase the step more than the plain estimate does.
            let gus = (self.h_acc / h).ln() + self.alpha * (2.0 * ln_err - self.ln_err_acc) - LN_SAFETY;
            ln_fac = ln_fac.max(gus);
        }
        if self.predictive {
            self.h_acc = h;
            self.ln_err_acc = ln_err.max(LN_ERR_ACC_FLOOR);
        }
        self.ln_err_old = ln_err.max(LN_ERR_FLOOR);
        (-ln_fac).exp().clamp(FAC_MIN, FAC_MAX)
    }

    /// Step ratio `h_new / h` after rejecting a step with error `err > 1` (finite).
    #[inline]
    pub fn reject(&self, err: f64) -> f64 {
        (SAFETY * (-self.alpha * err.ln()).exp()).clamp(FAC_MIN, 1.0)
    }
}

/// Modes whose exit steps [`ModeSteps`] remembers (the slider has five; the least recently left
/// is forgotten first).
const MODE_SLOTS: usize = 5;

/// The first step after a mode switch: the step the run proposed when it last left the mode it
/// now enters; on the first entry into a mode, the controller's proposal. The drivers also treat
/// that step as one after a rejection (its acceptance does not grow the next).
///
/// At a switch the proposal comes from the step that crossed the event, in the old mode. Where
/// the new mode's dynamics are faster that step is far too long. The slider's pin landing on the
/// disk is the case that matters: its steps in free flight are several times those the stiff
/// contact allows. On the default grid's census (361 points, K = 16, rtol 1e-6) about half of
/// the first steps after a landing were rejected: 2.43 million of all 3.21 million rejections,
/// each a whole step of right-hand sides. A run that switches back and forth (a bouncing cycle,
/// stick-slip) meets the same mode again and again, and the step it took on leaving a mode is the
/// step that mode allows.
///
/// Measured on that census: rejections 3.21 -> 0.61 million, steps per simulated second 1,608 ->
/// 1,567. Without the no-growth rule 1,528, but the labels then agreed less well with runs to
/// `t_max` and with rtol 1e-10 (86-94 labels against 66-83, and 98.3 % against 98.7 %); with it
/// 72 and 98.3 %, within the spread of unchanged builds under rtol moved by 1 %. Caps of 0.6-0.9x
/// or 1.5-3x the exit step did worse (1,544-1,629 steps per second).
///
/// Until 2026-11-29 the exit step only capped the proposal (never lengthened it). But a phase
/// that ends within a small part of its first step (a stick phase of 0.01 us that a rising
/// normal force ends, a bounce of a few us) leaves a proposal of that scale, and the mode that
/// follows grew it back by at most 10x a step: 4-5 steps after every such phase, a quarter of all
/// steps of an irregular point of the Stribeck sweep. Its exit step restores the mode's own.
/// Right-hand sides, the same builds otherwise: the issue-10 Stribeck sweep 22.6 -> 20.3 million
/// (switch law) and 40.1 -> 32.7 million (tanh law); that grid with `friction_law="constant"`
/// and the census 414 -> 384 million.
#[derive(Clone, Copy, Debug)]
pub struct ModeSteps<M> {
    /// Each mode's exit step, the most recently left first.
    slots: [Option<(M, f64)>; MODE_SLOTS],
}

impl<M: Copy + PartialEq> Default for ModeSteps<M> {
    fn default() -> Self {
        ModeSteps { slots: [None; MODE_SLOTS] }
    }
}

impl<M: Copy + PartialEq> ModeSteps<M> {
    /// At a switch from mode `from` to mode `to`, with the controller's proposal `h`: remembers
    /// `h` as `from`'s exit step and returns the step to take in `to`.
    pub fn switch(&mut self, from: M, to: M, h: f64) -> f64 {
        let entered = self.slots.iter().flatten().find(|(m, _)| *m == to).map(|&(_, hm)| hm);
        // `from` moves to the front (the most recently left); the least recently left falls off.
        let at = self.slots.iter().position(|s| matches!(s, Some((m, _)) if *m == from)).unwrap_or(MODE_SLOTS - 1);
        self.slots.copy_within(0..at, 1);
        self.slots[0] = Some((from, h));
        match entered {
            Some(hm) => hm,
            _ => h,
        }
    }
}

/// Hairer's starting step for a method of order `order`, in the RMS norms of [`error_norm`].
/// Costs one right-hand-side evaluation (counted in `n_rhs`). The result is in `(0, h_max]` and
/// never beyond `t_end - t0`.
#[allow(clippy::too_many_arguments)]
pub fn initial_step<const N: usize, S: OdeSystem<N>>(
    sys: &S,
    mode: S::Mode,
    t0: f64,
    y0: &SVector<f64, N>,
    f0: &SVector<f64, N>,
    t_end: f64,
    order: u32,
    atol: &SVector<f64, N>,
    rtol: f64,
    h_max: f64,
    n_rhs: &mut u64,
) -> f64 {
    let span = (t_end - t0).abs();
    let h_cap = h_max.min(span);
    let zero = SVector::<f64, N>::zeros();
    let d0 = error_norm(y0, &zero, &zero, atol, rtol);
    let d1 = error_norm(f0, y0, y0, atol, rtol);
    let mut h = if d0 < 1e-5 || d1 < 1e-5 || !d1.is_finite() { 1e-6 } else { 0.01 * d0 / d1 };
    h = h.min(h_cap);
    let y1 = y0 + f0 * h;
    let f1 = sys.rhs(t0 + h, &y1, mode);
    *n_rhs += 1;
    let d2 = error_norm(&(f1 - f0), y0, y0, atol, rtol) / h;
    let d12 = d1.max(d2);
    let h1 = if !d12.is_finite() {
        // The derivative blows up next to y0: start tiny and let the controller find out.
        h * 1e-3
    } else if d12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        (0.01 / d12).powf(1.0 / order as f64)
    };
    (100.0 * h).min(h1).min(h_cap)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_norm_is_weighted_rms() {
        let e = SVector::<f64, 2>::new(1e-6, 0.0);
        let y0 = SVector::<f64, 2>::new(1.0, 0.0);
        let y1 = SVector::<f64, 2>::new(-2.0, 0.0);
        let atol = SVector::<f64, 2>::repeat(1e-8);
        // sk_0 = 1e-8 + 1e-6 * 2; only the first component contributes.
        let want = (1e-6 / (1e-8 + 2e-6)) / 2f64.sqrt();
        assert!((error_norm(&e, &y0, &y1, &atol, 1e-6) - want).abs() < 1e-15);
        let nan = SVector::<f64, 2>::new(f64::NAN, 0.0);
        assert!(error_norm(&nan, &y0, &y1, &atol, 1e-6).is_nan());
    }

    #[test]
    fn controller_limits() {
        let mut c = Controller::new(5, 0.04, false);
        // Zero error: the largest growth.
        assert_eq!(c.accept(1.0, 0.0), FAC_MAX);
        // Huge error: the largest cut, never growth on rejection.
        assert_eq!(c.reject(1e30), FAC_MIN);
        assert!(c.reject(1.0 + 1e-12) <= 1.0);
        // err = 1 on accept shrinks a little (safety) — roughly 0.9.
        let mut c = Controller::new(5, 0.0, false);
        assert!((c.accept(1.0, 1.0) - SAFETY).abs() < 1e-12);
    }

    #[test]
    fn mode_steps_start_a_mode_with_its_last_exit_step() {
        let mut m = ModeSteps::<u8>::default();
        // First entry into 1: the proposal as it is.
        assert_eq!(m.switch(0, 1, 1e-3), 1e-3);
        // Back into 0 with a short proposal from mode 1: 0's exit step, longer.
        assert_eq!(m.switch(1, 0, 2e-5), 1e-3);
        // Back into 1 with a long proposal from mode 0: 1's exit step, shorter...
        assert_eq!(m.switch(0, 1, 5e-3), 2e-5);
        // ...and into 0 with a proposal from a short phase of 1: 0's exit step (5e-3).
        assert_eq!(m.switch(1, 0, 1e-6), 5e-3);
        assert_eq!(m.switch(0, 1, 5e-3), 1e-6);
        // Five modes remembered; a sixth pushes out the least recently left (mode 0 here).
        for (from, to) in [(1, 2), (2, 3), (3, 4), (4, 5), (5, 6)] {
            m.switch(from, to, 1.0);
        }
        assert_eq!(m.switch(6, 0, 7.0), 7.0);
        assert_eq!(m.switch(0, 4, 7.0), 1.0);
    }
}
