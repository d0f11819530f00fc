//! The integration driver: step-size control, dense output, event location.
//!
//! [`integrate`] picks the method once (`match` at the top) and runs one generic loop,
//! monomorphised per method through the crate-private `Stepper` trait: no dynamic dispatch and
//! no heap allocation inside the loop; every state is an `SVector` on the stack.
//!
//! # One step
//! 1. The stepper attempts `h` from `(t, y)` with `f = f(t, y)` known, `h` capped by the system's
//!    `OdeSystem::step_limit` (a discontinuity of the mode's field ahead, which an event ends the
//!    mode before); the error norm is the weighted RMS of [`super::controller::error_norm`]
//!    (DOP853: Hairer's combination of two such sums). A non-finite error or state rejects the
//!    step and cuts `h` by the largest factor; the run ends with `NonFinite` only when that drives
//!    `h` below the floor `h_min_rel * max(|t|, 1)` (a finite error there gives `StepTooSmall`).
//! 2. On acceptance the event functions are evaluated once at the step end (and reused as the next
//!    step's start values). Every sign change `g(start) != 0`, `g(end)` of the other sign or exactly
//!    zero, in a direction the system counts (`OdeSystem::crossing_counts`; both by default), is located on the step's dense output by a bracketing root finder (`events::locate`, bracket shrunk to
//!    `event_tol`; the returned time is the bracket end on the far side of the crossing, so that a
//!    restarted run already sees the new sign).
//! 3. Located events are processed in time order: `sys.on_event` gives each one's action; the first
//!    `Switch` or `Stop` truncates the step there and later crossings in the step are discarded
//!    (they are found again in the new mode if real). Then `observer.on_step` sees the
//!    (truncated) step, then `observer.on_event` each processed event. A `Switch` restarts the
//!    integration at the event in the new mode with a fresh `f` (the FSAL stage is invalid) and a
//!    fresh controller history. If `on_step` stops the run, that step's events are neither
//!    processed nor counted; if `on_event` stops it, the run ends at the (truncated) step end, in
//!    the mode after that event.
//!
//! # Restart and grazing guard (the documented rule)
//! An event function is *pending* when the run (re)starts on its zero: the event that caused a
//! `Switch`, and any event whose value is exactly 0 at a step start. A pending event reports no
//! crossing until a step ends beyond the check time
//! `t_c = max(t_s + event_guard, t_step_start + 1e-6 * h)` (`t_s`: when it became pending). At that
//! step the departure sign is read on the dense output at `t_c`; crossings between `t_c` and the
//! step end are then located as usual (so a short flight that ends inside the first step after a
//! switch is still caught). If `g(t_c)` is exactly 0 too, the event stays quiet in that step and
//! takes the sign of the step end as its reference (it stays pending while that is 0 as well).
//! Consequences: a restart on a root never re-fires at once; a genuine crossing within
//! `max(event_guard, 1e-6 h)` after a switch is not seen (it is rounding-level, the grazing case the
//! guard exists for); two crossings of one function inside one step cancel at its ends (as in
//! every sign-based locator), which is why steps are also checked inside when `interior_checks` is
//! positive (at that many points, and at each event function's turning point where the system
//! gives the rates of its event functions: `OdeSystem::event_rates`, `events::turn_point`).
//! Crossings located after the truncating event in the same step are discarded and looked for
//! again in the new mode; one whose root lies within `event_tol` of the switch may by then be on
//! its far side and go unreported (simultaneous events are not merged).
//!
//! # Counting
//! `n_rhs` counts the right-hand-side calls the integrator makes, including the starting-step
//! estimate, restarts, Rodas4's finite-difference `df/dt`, and DOP853's three extra dense-output
//! stages (computed lazily, only when the dense output is evaluated). Locating an event evaluates
//! the dense output and the event functions only; a system's own finite-difference Jacobian is not
//! counted in `n_rhs` (it is one `n_jac`).

use super::controller::{initial_step, Controller, ModeSteps, FAC_MIN};
use super::dop853::Dop853;
use super::dopri5::Dopri5;
use super::events::{crosses, hidden_crossing, step_events, StepEnd};
use super::rodas::Rodas4;
use super::stepper::{StepDense, Stepper};
use super::{Control, Method, Observer, OdeSystem, Options, Outcome, Solution, Stats, StepView, MAX_EVENTS};
use crate::cancel;
use nalgebra::SVector;

/// Integrate `sys` from `(t0, y0)` to `t_end` (> t0) with `method`, starting in `sys.initial_mode(t0, y0)`.
///
/// The last step lands exactly on `t_end`. Events, observer and outcomes as described in the
/// module documentation; a failure is reported in [`Solution::outcome`], never by a panic.
/// Integration backwards in time is not supported: `t_end < t0` returns at once with
/// `Outcome::StepTooSmall`; `t_end == t0` returns `Finished` without a step. A non-positive
/// `opts.h_max` means no limit; only the first [`super::MAX_EVENTS`] event functions are watched.
pub fn integrate<const N: usize, S: OdeSystem<N>, O: Observer<N, S::Mode>>(
    sys: &S,
    method: Method,
    t0: f64,
    y0: SVector<f64, N>,
    t_end: f64,
    opts: &Options<N>,
    observer: &mut O,
) -> Solution<N, S::Mode> {
    match method {
        Method::Dopri5 => run::<N, S, O, Dopri5<N>>(sys, t0, y0, t_end, opts, observer),
        Method::Dop853 => run::<N, S, O, Dop853<N>>(sys, t0, y0, t_end, opts, observer),
        Method::Rodas4 => run::<N, S, O, Rodas4<N>>(sys, t0, y0, t_end, opts, observer),
    }
}

/// Fixed-step integration with `n_steps` equal steps from `t0` to `t_end`: no error control, no
/// events, in the initial mode throughout. For measuring the order of convergence.
pub fn integrate_fixed<const N: usize, S: OdeSystem<N>>(
    sys: &S,
    method: Method,
    t0: f64,
    y0: SVector<f64, N>,
    t_end: f64,
    n_steps: usize,
) -> SVector<f64, N> {
    match method {
        Method::Dopri5 => fixed::<N, S, Dopri5<N>>(sys, t0, y0, t_end, n_steps),
        Method::Dop853 => fixed::<N, S, Dop853<N>>(sys, t0, y0, t_end, n_steps),
        Method::Rodas4 => fixed::<N, S, Rodas4<N>>(sys, t0, y0, t_end, n_steps),
    }
}

fn fixed<const N: usize, S: OdeSystem<N>, St: Stepper<N, S>>(
    sys: &S,
    t0: f64,
    y0: SVector<f64, N>,
    t_end: f64,
    n_steps: usize,
) -> SVector<f64, N> {
    let mode = sys.initial_mode(t0, &y0);
    let n = n_steps.max(1);
    let h = (t_end - t0) / n as f64;
    let mut stats = Stats::default();
    let atol = SVector::<f64, N>::repeat(1.0);
    let mut st = St::new();
    let mut y = y0;
    let mut f = sys.rhs(t0, &y, mode);
    for k in 0..n {
        // Times from the index, not by accumulation, so that rounding does not drift.
        let t = t0 + k as f64 * h;
        st.begin(sys, mode, t, &y, &f, &mut stats);
        let (y_new, _) = st.try_step(sys, mode, t, &y, &f, h, &atol, 0.0, &mut stats);
        f = st.finish(sys, mode, t, h, &y_new, &mut stats);
        y = y_new;
    }
    y
}

#[inline]
fn all_finite<const N: usize>(v: &SVector<f64, N>) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn run<const N: usize, S, O, St>(
    sys: &S,
    t0: f64,
    y0: SVector<f64, N>,
    t_end: f64,
    opts: &Options<N>,
    obs: &mut O,
) -> Solution<N, S::Mode>
where
    S: OdeSystem<N>,
    O: Observer<N, S::Mode>,
    St: Stepper<N, S>,
{
    let mut stats = Stats::default();
    let mut mode = sys.initial_mode(t0, &y0);
    let mut t = t0;
    let mut y = y0;
    let mut h = f64::NAN;
    macro_rules! done {
        ($t:expr, $y:expr, $mode:expr, $outcome:expr) => {
            return Solution { t: $t, y: $y, mode: $mode, outcome: $outcome, stats, h }
        };
    }
    if !t0.is_finite() || !t_end.is_finite() || !all_finite(&y) {
        done!(t, y, mode, Outcome::NonFinite);
    }
    if t_end < t0 {
        done!(t, y, mode, Outcome::StepTooSmall);
    }
    if t_end == t0 {
        done!(t, y, mode, Outcome::Finished);
    }
    let mut f = sys.rhs(t, &y, mode);
    stats.n_rhs += 1;
    if !all_finite(&f) {
        done!(t, y, mode, Outcome::NonFinite);
    }

    let n_ev = sys.n_events().min(MAX_EVENTS);
    // Event values at the current step start; `pend[i] = Some(t_s)`: pending since t_s.
    let mut g0 = [0.0; MAX_EVENTS];
    let mut pend: [Option<f64>; MAX_EVENTS] = [None; MAX_EVENTS];
    if n_ev > 0 {
        sys.events(t, &y, mode, &mut g0);
        for i in 0..n_ev {
            if g0[i] == 0.0 {
                pend[i] = Some(t);
            }
        }
    }

    let mut st = St::new();
    let mut ctl = Controller::new(St::ERR_EXP, St::BETA, St::PREDICTIVE);
    st.begin(sys, mode, t, &y, &f, &mut stats);
    let h_max = if opts.h_max > 0.0 { opts.h_max } else { f64::INFINITY };
    h = if opts.h0 > 0.0 {
        opts.h0.min(h_max)
    } else {
        initial_step(sys, mode, t, &y, &f, t_end, St::ORDER, &opts.atol, opts.rtol, h_max, &mut stats.n_rhs)
    };
    let mut rejected = false;
    let mut mode_steps = ModeSteps::<S::Mode>::default();

    loop {
        let floor = opts.h_min_rel * t.abs().max(1.0);
        let remaining = t_end - t;
        h = h.min(sys.step_limit(&y, &f, mode));
        // Land exactly on t_end; stretch by up to 1 % rather than leave a sliver.
        let last = h >= remaining || (1.01 * h >= remaining && remaining <= h_max);
        if last {
            h = remaining;
        }
        if (h.is_nan() || h < floor) && !last {
            done!(t, y, mode, if h.is_finite() { Outcome::StepTooSmall } else { Outcome::NonFinite });
        }
        let steps = stats.n_accept + stats.n_reject;
        if steps >= opts.max_steps {
            done!(t, y, mode, Outcome::MaxSteps);
        }
        if cancel::requested_every(steps) {
            done!(t, y, mode, Outcome::Cancelled);
        }

        let (y_new, err) = st.try_step(sys, mode, t, &y, &f, h, &opts.atol, opts.rtol, &mut stats);
        let ok = err <= 1.0 && all_finite(&y_new);
        // f at the new point only for a step that passed the error test.
        let f_new = if ok { Some(st.finish(sys, mode, t, h, &y_new, &mut stats)) } else { None };
        let f_new = match f_new {
            Some(fv) if all_finite(&fv) => fv,
            _ => {
                stats.n_reject += 1;
                rejected = true;
                // A finite error above 1 is an ordinary rejection; anything non-finite (error,
                // state or derivative) cuts the step by the largest factor first.
                let ordinary = !ok && err.is_finite() && all_finite(&y_new);
                h *= if ordinary { ctl.reject(err) } else { FAC_MIN };
                if h.is_nan() || h < floor {
                    done!(t, y, mode, if ordinary { Outcome::StepTooSmall } else { Outcome::NonFinite });
                }
                continue;
            }
        };
        let t_new = if last { t_end } else { t + h };
        // One interpolant per step, shared by the hidden-crossing check and the events (its
        // extra stages, where a method has them, are built once and counted once).
        let dense = st.dense(sys, mode, t, h, &y, &y_new);
        let mut g1 = [0.0; MAX_EVENTS];
        if n_ev > 0 {
            sys.events(t_new, &y_new, mode, &mut g1);
            if opts.interior_checks > 0 {
                if let Some(t_in) = hidden_crossing(
                    sys,
                    &dense,
                    mode,
                    (t, &y, &f),
                    (t_new, &y_new, &f_new),
                    n_ev,
                    &g0,
                    &g1,
                    &pend,
                    opts,
                ) {
                    // A crossing and its return inside this step: redo it ending inside the excursion.
                    stats.n_rhs += dense.extra_rhs();
                    stats.n_reject += 1;
                    h = t_in - t;
                    continue;
                }
            }
        }
        stats.n_accept += 1;
        let mut ratio = ctl.accept(h, err);
        if rejected {
            ratio = ratio.min(1.0);
        }
        rejected = false;
        let mut h_next = (h * ratio).min(h_max);

        // ---- events on the accepted step ----
        let mut busy = false;
        for i in 0..n_ev {
            busy |= pend[i].is_some() || crosses(g0[i], g1[i]);
        }
        let ev = if busy {
            step_events(sys, obs, opts, &mut stats, &dense, mode, (t, &y), (t_new, &y_new), n_ev, &g0, &g1, &mut pend)
        } else {
            // The common step: no crossing, nothing pending.
            let view = StepView { t0: t, t1: t_new, y0: &y, y1: &y_new, mode, dense: &dense };
            let end = if obs.on_step(&view) == Control::Stop { Some(Outcome::StoppedByObserver) } else { None };
            StepEnd { t1: t_new, y1: y_new, new_mode: mode, end, switched: None }
        };
        stats.n_rhs += dense.extra_rhs();
        drop(dense);
        if let Some(outcome) = ev.end {
            done!(ev.t1, ev.y1, ev.new_mode, outcome);
        }

        if let Some(sw) = ev.switched {
            // Restart at the event in the new mode: fresh derivative, fresh event values.
            t = ev.t1;
            y = ev.y1;
            let mode_before = mode;
            mode = ev.new_mode;
            f = sys.rhs(t, &y, mode);
            stats.n_rhs += 1;
            if !all_finite(&f) {
                done!(t, y, mode, Outcome::NonFinite);
            }
            sys.events(t, &y, mode, &mut g0);
            for i in 0..n_ev {
                pend[i] = match sw.pend_before[i] {
                    // Still inside its own guard window: stays pending from the same origin.
                    Some(ts) if t <= sw.t_check[i] => Some(ts),
                    _ if i == sw.index || g0[i] == 0.0 => Some(t),
                    _ => None,
                };
            }
            ctl.reset();
            h_next = mode_steps.switch(mode_before, mode, h_next);
            // The first step in the new mode does not grow the next (as after a rejection).
            rejected = true;
        } else {
            t = t_new;
            y = y_new;
            f = f_new;
            g0 = g1;
            if last {
                done!(t, y, mode, Outcome::Finished);
            }
            for i in 0..n_ev {
                if pend[i].is_none() && g0[i] == 0.0 {
                    pend[i] = Some(t);
                }
            }
        }
        st.begin(sys, mode, t, &y, &f, &mut stats);
        h = h_next;
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod hidden_crossing_tests;
