//! The common event of an accepted step, handled on the lane's own values: one event function
//! changes sign, nothing is pending, the steady watcher sees no section, and the event switches
//! the mode or changes nothing (and shows no second crossing after it).
//!
//! The cold path (`run::cold_step`, the scalar driver's `step_events` behind the lane's observers)
//! builds the step's scalar interpolant, copies the lane's extremes and peaks to its observers and
//! back, and goes through the general event machinery (pending functions, several crossings in
//! time order, observers that stop the run). [`quick_event`] does what that machinery does in the
//! common case, with the same scalar functions on the same values in the same order, so a lane's
//! results are the cold path's bits (`tests::the_quick_event_path_gives_the_cold_paths_bits`);
//! anything else it hands to the cold path untouched.

use super::slider::{n_events, NE};
use super::state::{Lanes, Watch};
use crate::model::{idx, ContactMode, State};
use crate::ode::events::{crosses, hermite_root, locate_from};
use crate::ode::lanes::{cross, lane_state, LaneDense, Lw, Vw, LN_ERR_FLOOR};
use crate::ode::{EventAction, OdeSystem, Outcome, MAX_EVENTS};
use crate::steady::Extremes;

/// How [`quick_event`] left a lane.
pub(super) enum Quick {
    /// Not the common case: nothing changed, the lane takes the cold path.
    Cold,
    /// Handled: the lane goes on from the event (or the step's end).
    Done,
    /// Handled, and the run ends here (at `t`, `y`): the step was its last, or the restart's
    /// right-hand side is not finite.
    End(f64, State, Outcome),
}

// The tests' switch (off: every event takes the cold path) and count of events handled here, on
// the thread that runs the lanes.
#[cfg(test)]
thread_local! {
    pub(super) static QUICK: std::cell::Cell<bool> = const { std::cell::Cell::new(true) };
    pub(super) static HANDLED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Lane `l`'s event in the accepted step `[t0, t_new]` of size `h` (`yn`, `fnew`, `g1`: the
/// state, derivative and event functions at its end), located on `dense` (the lane's DOP853
/// interpolant of every component, built and counted this step), acted on and reported as
/// `step_events` and the run's restart would; [`Quick::Cold`] where the step is not the common
/// case (see the module documentation), before anything changed.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub(super) fn quick_event<const LAW: u8, const N: usize>(
    ln: &mut Lanes<'_, N>,
    l: usize,
    dense: &LaneDense<6, N>,
    (yn, fnew, g1): (&Vw<N>, &Vw<N>, &[Lw<N>; NE]),
    (t0, t_new, h): (f64, f64, f64),
    last: bool,
) -> Quick {
    #[cfg(test)]
    if !QUICK.with(|q| q.get()) {
        return Quick::Cold;
    }
    let ne = n_events(LAW);
    // One function changes sign, none is pending (a pending function's check and the crossings
    // after it are the cold path's: handled here, they cost more than they saved).
    let mut e = NE;
    for j in 0..ne {
        let crossed = cross(ln.g0[j][l], g1[j][l]);
        if ln.pend[j][l] || (crossed && e < NE) {
            return Quick::Cold;
        }
        e = if crossed { j } else { e };
    }
    let sd = ln.side[l].as_mut().expect("events only on live lanes");
    if e == NE || matches!(sd.obs.inner, Watch::Sample(_)) || sd.stats.n_events >= sd.opts.max_events {
        return Quick::Cold;
    }
    let (s, mode) = (sd.s, sd.mode);
    let ga = ln.g0[e][l];
    if !s.crossing_counts(mode, e, ga < 0.0) {
        return Quick::Cold;
    }
    let eval = |t: f64| State::from(dense.eval_lane(l, (t - t0) / h));
    // The function alone, on the components it reads (as `step_events`'s `Dense::eval_some`).
    let reads = s.event_reads(e);
    let g_at = |t: f64| {
        let x = (t - t0) / h;
        let y = State::from_fn(|j, _| if reads & (1 << j) != 0 { dense.at(j, l, x, 1.0 - x) } else { 0.0 });
        s.event(t, &y, mode, e)
    };
    let gb = g1[e][l];
    let (y0, y1) = (lane_state(&ln.y, l), lane_state(yn, l));
    // From the start of the step, the search starts at the root of the function's cubic model.
    let (mut d0, mut d1) = ([f64::NAN; MAX_EVENTS], [f64::NAN; MAX_EVENTS]);
    let guess = (s.event_rates(t0, &y0, &lane_state(&ln.f, l), mode, &mut d0)
        && s.event_rates(t_new, &y1, &lane_state(fnew, l), mode, &mut d1))
    .then(|| hermite_root(t0, t_new - t0, ga, gb, d0[e], d1[e]))
    .flatten();
    let te = locate_from(g_at, t0, ga, t_new, gb, sd.opts.event_tol, guess);
    let mut g = [0.0; MAX_EVENTS];
    let ye = if te < t_new { eval(te) } else { y1 };
    let (t1, y_end, after) = match s.on_event(te, &ye, mode, e) {
        EventAction::Switch(m) => (te, ye, m),
        EventAction::Continue => {
            // A point inside the step where every function is read: a second crossing after it
            // is the cold path's to locate.
            if te < t_new {
                s.events(te, &ye, mode, &mut g);
                for j in (0..ne).filter(|&j| j != e) {
                    let fresh = g[j] != 0.0 && !g[j].is_nan();
                    if fresh && crosses(g[j], g1[j][l]) && s.crossing_counts(mode, j, g[j] < 0.0) {
                        return Quick::Cold;
                    }
                }
            }
            (t_new, y1, mode)
        }
        EventAction::Stop => return Quick::Cold,
    };
    // The observers' look at the (truncated) step: extremes, and the steady watcher's peaks where
    // it sees no section and no rest.
    if let Watch::Steady(o, _) = &sd.obs.inner {
        let peak = ln.peak[l].max(y_end[idx::Z].abs());
        let section = y0[idx::ZD] > 0.0 && y_end[idx::ZD] <= 0.0;
        if section || y_end.norm() == 0.0 || peak < o.decay_floor {
            return Quick::Cold;
        }
        ln.peak[l] = peak;
        let peaks = lane_state(&ln.peaks, l).sup(&y_end.abs());
        for i in 0..6 {
            ln.peaks[i][l] = peaks[i];
        }
    }
    let mut ext = Extremes {
        min_normal_force: ln.min_n[l],
        max_gap: ln.max_gap[l],
        min_slip_velocity: ln.min_vr[l],
        max_abs_z: ln.max_z[l],
    };
    ext.update(s, &y_end, mode);
    sd.stats.n_events += 1;
    // At a switch the step ends at the event: its state is the step end's, already seen.
    if t1 != te {
        ext.update(s, &ye, mode);
    }
    ext.update(s, &ye, after);
    if let Watch::Log(v) = &mut sd.obs.inner {
        v.push((e, te));
    }
    (ln.min_n[l], ln.max_gap[l], ln.min_vr[l], ln.max_z[l]) =
        (ext.min_normal_force, ext.max_gap, ext.min_slip_velocity, ext.max_abs_z);
    #[cfg(test)]
    HANDLED.with(|h| h.set(h.get() + 1));
    if after != mode {
        return match restart(ln, l, t1, &y_end, after, e, &[None; MAX_EVENTS], &[f64::NEG_INFINITY; MAX_EVENTS]) {
            true => Quick::Done,
            false => Quick::End(t1, y_end, Outcome::NonFinite),
        };
    }
    go_on(ln, l, &y1, fnew, g1, t_new);
    if last {
        Quick::End(t_new, y1, Outcome::Finished)
    } else {
        Quick::Done
    }
}

/// Lane `l` restarts at `(t, y)` in `mode` after its event `index` switched the mode: the step
/// from the mode's memory, a fresh derivative and fresh event values, the pending events as the
/// scalar driver sets them (`pend_before` and `t_check`: the truncated step's). `false` where the
/// derivative is not finite (the run ends there).
#[allow(clippy::too_many_arguments)]
pub(super) fn restart<const N: usize>(
    ln: &mut Lanes<'_, N>,
    l: usize,
    t: f64,
    y: &State,
    mode: ContactMode,
    index: usize,
    pend_before: &[Option<f64>; MAX_EVENTS],
    t_check: &[f64; MAX_EVENTS],
) -> bool {
    let sd = ln.side[l].as_mut().expect("live");
    ln.h[l] = sd.steps.switch(sd.mode, mode, ln.h[l]);
    ln.rejected[l] = true;
    sd.mode = mode;
    let f = sd.s.rhs(y, mode);
    sd.stats.n_rhs += 1;
    if !f.iter().all(|v| v.is_finite()) {
        return false;
    }
    let mut g = [0.0; MAX_EVENTS];
    sd.s.events(t, y, mode, &mut g);
    let ne = sd.s.n_events();
    for e in 0..ne {
        sd.pend[e] = match pend_before[e] {
            Some(ts) if t <= t_check[e] => Some(ts),
            _ if e == index || g[e] == 0.0 => Some(t),
            _ => None,
        };
    }
    let pend = sd.pend;
    for i in 0..6 {
        ln.y[i][l] = y[i];
        ln.f[i][l] = f[i];
    }
    for e in 0..ne {
        ln.g0[e][l] = g[e];
        ln.pend[e][l] = pend[e].is_some();
        ln.pend_t[e][l] = pend[e].unwrap_or(f64::NAN);
    }
    ln.t[l] = t;
    ln.modes.set(l, mode);
    ln.ln_err_old[l] = LN_ERR_FLOOR;
    true
}

/// Lane `l` goes on from the end `(t_new, y1)` of its accepted step (derivative `fnew`, event
/// values `g1`), a function that reads exactly zero there pending from `t_new`.
pub(super) fn go_on<const N: usize>(
    ln: &mut Lanes<'_, N>,
    l: usize,
    y1: &State,
    fnew: &Vw<N>,
    g1: &[Lw<N>; NE],
    t_new: f64,
) {
    for i in 0..6 {
        ln.y[i][l] = y1[i];
        ln.f[i][l] = fnew[i][l];
    }
    ln.t[l] = t_new;
    let sd = ln.side[l].as_mut().expect("live");
    for e in 0..sd.s.n_events() {
        ln.g0[e][l] = g1[e][l];
        if sd.pend[e].is_none() && g1[e][l] == 0.0 {
            sd.pend[e] = Some(t_new);
        }
        ln.pend[e][l] = sd.pend[e].is_some();
        ln.pend_t[e][l] = sd.pend[e].unwrap_or(f64::NAN);
    }
}
