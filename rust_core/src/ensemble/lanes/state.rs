//! The state of a lane driver: the vector side of the `N` lanes ([`Lanes`]), each lane's scalar
//! side ([`Side`]: the observers of its task, its events and options), and the set-up and teardown
//! of a trajectory in a lane (refill, finish, idle) with the copies between the two sides.

use super::slider::{Coef, Modes, NE};
use crate::ensemble::{Task, TrajectoryResult};
use crate::model::{idx, ContactMode, Slider, State};
use crate::ode::controller::{initial_step, ModeSteps};
use crate::ode::lanes::{lane_state, Lw, Row, Rows, Vw, LN_ERR_FLOOR};
use crate::ode::{Control, Observer, OdeSystem, Options, Outcome, SampleStore, Sampler, Stats, StepView, MAX_EVENTS};
use crate::steady::{
    end_status, options_for, run_failure, status_of, summarize, Extremes, ExtremesObserver, RunResult, SteadyObserver,
    SteadyOptions, Tolerances,
};
use std::sync::atomic::{AtomicUsize, Ordering};

/// What a lane's observer watches.
pub(super) enum Watch<'a> {
    Nothing,
    Sample(Sampler<'a, 6, Store<'a>>),
    Steady(Box<SteadyObserver>, Box<SteadyOptions>),
    Log(Vec<(usize, f64)>),
}

impl Observer<6, ContactMode> for Watch<'_> {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        match self {
            Watch::Sample(s) => s.on_step(st),
            Watch::Steady(o, _) => o.on_step(st),
            Watch::Nothing | Watch::Log(_) => Control::Continue,
        }
    }
    fn on_event(&mut self, i: usize, t: f64, y: &State, before: ContactMode, after: ContactMode) -> Control {
        match self {
            Watch::Log(v) => {
                v.push((i, t));
                Control::Continue
            }
            Watch::Steady(o, _) => o.on_event(i, t, y, before, after),
            _ => Control::Continue,
        }
    }
}

/// Where a lane's samples go: a vector for the result, or the trajectory's row of the caller's
/// buffer.
pub(super) enum Store<'a> {
    Own(Vec<State>),
    Row(Row<'a>),
}

impl SampleStore<6> for Store<'_> {
    #[inline]
    fn len(&self) -> usize {
        match self {
            Store::Own(v) => v.len(),
            Store::Row(r) => r.len(),
        }
    }
    #[inline]
    fn push(&mut self, v: State) {
        match self {
            Store::Own(o) => o.push(v),
            Store::Row(r) => r.push(v),
        }
    }
}

/// The trajectories of a call: the index of the next to start (shared by the workers of a
/// threaded call), and the rows their samples go to where the caller gave a buffer.
pub(crate) struct Feed<'r> {
    pub(crate) next: AtomicUsize,
    pub(crate) rows: Option<Rows<'r>>,
}

impl<'r> Feed<'r> {
    pub(crate) fn new(rows: Option<Rows<'r>>) -> Self {
        Feed { next: AtomicUsize::new(0), rows }
    }
}

/// The scalar side of a lane: what the cold paths need.
pub(super) struct Side<'a> {
    /// Input index of the trajectory.
    pub(super) i: usize,
    pub(super) s: &'a Slider,
    pub(super) opts: Options<6>,
    /// The end of the run [s] (`t_max` for a run to steady state).
    pub(super) t_end: f64,
    pub(super) mode: ContactMode,
    pub(super) pend: [Option<f64>; MAX_EVENTS],
    /// Right-hand sides outside the steps (start, starting step, restarts) and located events.
    pub(super) stats: Stats,
    pub(super) obs: ExtremesObserver<'a, Watch<'a>>,
    /// The first step after a mode switch, as the scalar driver takes it.
    pub(super) steps: ModeSteps<ContactMode>,
}

/// The vector side of the `N` lanes (state and stage first, on 64-byte boundaries, as
/// `ode::lanes::Al`).
#[repr(C, align(64))]
pub(super) struct Lanes<'a, const N: usize> {
    pub(super) y: Vw<N>,
    /// f(t, y) in the lane's mode: the FSAL stage.
    pub(super) f: Vw<N>,
    pub(super) c: Coef<N>,
    pub(super) t: Lw<N>,
    pub(super) h: Lw<N>,
    pub(super) ln_err_old: Lw<N>,
    pub(super) rejected: [bool; N],
    pub(super) n_acc: [u64; N],
    pub(super) n_rej: [u64; N],
    /// Right-hand sides of DOP853's interpolant built on the lanes (hidden-crossing checks).
    pub(super) n_extra: [u64; N],
    /// The method is DOP853 (else DP5).
    pub(super) m8: bool,
    pub(super) modes: Modes<N>,
    pub(super) g0: [Lw<N>; NE],
    pub(super) pend: [[bool; N]; NE],
    /// Where `pend` is set, the pending event's time (the side's `pend`), else NaN.
    pub(super) pend_t: [Lw<N>; NE],
    pub(super) min_n: Lw<N>,
    pub(super) max_gap: Lw<N>,
    pub(super) min_vr: Lw<N>,
    pub(super) max_z: Lw<N>,
    /// Steady watcher: largest |z| and |y_c| since the last section, the rest floor (-inf: none).
    pub(super) peak: Lw<N>,
    pub(super) peaks: Vw<N>,
    pub(super) rest: Lw<N>,
    /// Next `t_eval` time of each lane (+inf: none).
    pub(super) next_sample: Lw<N>,
    /// The end of each lane's run (its own `t_max` under a `restart`; `Side::t_end`).
    pub(super) t_end: Lw<N>,
    pub(super) side: [Option<Side<'a>>; N],
}

/// Everything the set-up and teardown of a lane needs.
pub(super) struct Input<'a, 'b> {
    pub(super) sliders: &'a [Slider],
    pub(super) y0s: &'b [State],
    pub(super) t_end: f64,
    pub(super) tol: Tolerances,
    pub(super) task: Task<'a>,
    /// The next trajectory to start and where samples go.
    pub(super) feed: &'b Feed<'a>,
}

impl<'a, 'b> Input<'a, 'b> {
    /// A call's input; a run to a steady state ends at its options' `t_max`, at their tolerances.
    pub(super) fn new(
        sliders: &'a [Slider],
        y0s: &'b [State],
        t_end: f64,
        tol: &Tolerances,
        task: Task<'a>,
        feed: &'b Feed<'a>,
    ) -> Self {
        let (t_end, tol) = match task {
            Task::Steady { opts, .. } => (opts.t_max, opts.tol),
            _ => (t_end, *tol),
        };
        Input { sliders, y0s, t_end, tol, task, feed }
    }
}

pub(super) fn sync_to_side<const N: usize>(
    min_n: &Lw<N>,
    max_gap: &Lw<N>,
    min_vr: &Lw<N>,
    max_z: &Lw<N>,
    l: usize,
    sd: &mut Side<'_>,
) {
    sd.obs.ext =
        Extremes { min_normal_force: min_n[l], max_gap: max_gap[l], min_slip_velocity: min_vr[l], max_abs_z: max_z[l] };
}

/// Copy what the scalar observers changed back onto the lanes.
pub(super) fn sync_from_side<const N: usize>(ln: &mut Lanes<'_, N>, l: usize, steady: bool, sampled: bool) {
    let sd = ln.side[l].as_ref().expect("live");
    let e = sd.obs.ext;
    ln.min_n[l] = e.min_normal_force;
    ln.max_gap[l] = e.max_gap;
    ln.min_vr[l] = e.min_slip_velocity;
    ln.max_z[l] = e.max_abs_z;
    if steady {
        if let Watch::Steady(o, _) = &sd.obs.inner {
            ln.peak[l] = o.w.peak_since;
            for i in 0..6 {
                ln.peaks[i][l] = o.w.peaks_since[i];
            }
        }
    }
    if sampled {
        if let Watch::Sample(s) = &sd.obs.inner {
            ln.next_sample[l] = s.t_eval.get(s.out.len()).copied().unwrap_or(f64::INFINITY);
        }
    }
}

/// Write lane `l`'s result (ended at `(t, y)` with step size `h` and `outcome`) and mark it idle.
#[cold]
pub(super) fn finish<const N: usize>(
    ln: &mut Lanes<'_, N>,
    l: usize,
    t: f64,
    y: State,
    h: f64,
    outcome: Outcome,
    out: &mut Vec<(usize, TrajectoryResult)>,
) {
    let mut sd = ln.side[l].take().expect("finish on a live lane");
    let ext = Extremes {
        min_normal_force: ln.min_n[l],
        max_gap: ln.max_gap[l],
        min_slip_velocity: ln.min_vr[l],
        max_abs_z: ln.max_z[l],
    };
    let steps = ln.n_acc[l] + ln.n_rej[l];
    let mut stats = sd.stats;
    // DP5: six new stages per attempt (FSAL); DOP853: eleven per attempt and the derivative at
    // each accepted step's end, plus its interpolants' extra stages.
    stats.n_rhs += if ln.m8 { 11 * steps + ln.n_acc[l] + ln.n_extra[l] } else { 6 * steps };
    stats.n_accept = ln.n_acc[l];
    stats.n_reject = ln.n_rej[l];
    let status = end_status(sd.s, outcome, &y, sd.mode);
    let failure = run_failure(status, sd.s, t, &y, h, steps, sd.t_end, &sd.opts);
    let run = RunResult { status, t, y, extremes: ext, stats, failure };
    out.push((sd.i, conclude(run, &mut sd)));
    idle(ln, l);
}

/// The task's result from a finished run and its observer.
fn conclude(run: RunResult, sd: &mut Side<'_>) -> TrajectoryResult {
    let mut res = TrajectoryResult { run, samples: Vec::new(), summary: None, events: Vec::new() };
    match std::mem::replace(&mut sd.obs.inner, Watch::Nothing) {
        Watch::Sample(s) => match s.out {
            Store::Own(mut v) => {
                v.resize(s.t_eval.len(), State::repeat(f64::NAN));
                res.samples = v;
            }
            Store::Row(r) => r.finish(),
        },
        Watch::Steady(o, opts) => res.summary = Some(Box::new(summarize(sd.s, &res.run, &o.w, &opts))),
        Watch::Log(v) => res.events = v,
        Watch::Nothing => {}
    }
    res
}

/// Harmless values in an idle lane: at rest, far from every end condition and event.
fn idle<const N: usize>(ln: &mut Lanes<'_, N>, l: usize) {
    for k in 0..6 {
        ln.y[k][l] = 0.0;
        ln.f[k][l] = 0.0;
    }
    ln.t[l] = 0.0;
    ln.h[l] = 0.0;
    ln.c.esc[l] = f64::INFINITY;
    ln.modes.set(l, ContactMode::Contact);
    for e in 0..NE {
        ln.g0[e][l] = 1.0;
        ln.pend[e][l] = false;
        ln.pend_t[e][l] = f64::NAN;
    }
    ln.rest[l] = f64::NEG_INFINITY;
    ln.next_sample[l] = f64::INFINITY;
    ln.side[l] = None;
}

/// The per-lane scalars of lane `l` that a [`Parked`] trajectory carries, in its `v`'s order: an
/// array to read, or to assign to.
macro_rules! scalars {
    ($ln:expr, $l:expr) => {
        [
            $ln.t[$l],
            $ln.t_end[$l],
            $ln.h[$l],
            $ln.ln_err_old[$l],
            $ln.min_n[$l],
            $ln.max_gap[$l],
            $ln.min_vr[$l],
            $ln.max_z[$l],
            $ln.peak[$l],
            $ln.rest[$l],
            $ln.next_sample[$l],
        ]
    };
}

/// A running trajectory taken off its lanes between two steps, with everything the lane held:
/// [`park`] on one set of lanes, [`unpark`] on a set of another width, where it goes on with the
/// same bits (a lane's arithmetic does not depend on the lane count; the coefficients and mode
/// masks are rebuilt from the side).
pub(super) struct Parked<'a> {
    y: State,
    f: State,
    /// `t, t_end, h, ln_err_old, min_n, max_gap, min_vr, max_z, peak, rest, next_sample`.
    v: [f64; 11],
    peaks: State,
    rejected: bool,
    counts: [u64; 3],
    g0: [f64; NE],
    pend: [bool; NE],
    pend_t: [f64; NE],
    side: Side<'a>,
}

/// Takes the trajectory of live lane `l` off the lanes (the lane is left idle).
pub(super) fn park<'a, const N: usize>(ln: &mut Lanes<'a, N>, l: usize) -> Parked<'a> {
    let side = ln.side[l].take().expect("park a live lane");
    let v = scalars!(ln, l);
    let p = Parked {
        y: lane_state(&ln.y, l),
        f: lane_state(&ln.f, l),
        v,
        peaks: lane_state(&ln.peaks, l),
        rejected: ln.rejected[l],
        counts: [ln.n_acc[l], ln.n_rej[l], ln.n_extra[l]],
        g0: std::array::from_fn(|e| ln.g0[e][l]),
        pend: std::array::from_fn(|e| ln.pend[e][l]),
        pend_t: std::array::from_fn(|e| ln.pend_t[e][l]),
        side,
    };
    idle(ln, l);
    p
}

/// Puts a parked trajectory on lane `l` (idle) of `ln`.
pub(super) fn unpark<'a, const N: usize>(ln: &mut Lanes<'a, N>, l: usize, p: Parked<'a>) {
    let atol: [f64; 6] = std::array::from_fn(|k| p.side.opts.atol[k]);
    ln.c.set(l, p.side.s, &atol);
    ln.modes.set(l, p.side.mode);
    for k in 0..6 {
        ln.y[k][l] = p.y[k];
        ln.f[k][l] = p.f[k];
        ln.peaks[k][l] = p.peaks[k];
    }
    scalars!(ln, l) = p.v;
    ln.rejected[l] = p.rejected;
    [ln.n_acc[l], ln.n_rej[l], ln.n_extra[l]] = p.counts;
    for e in 0..NE {
        ln.g0[e][l] = p.g0[e];
        ln.pend[e][l] = p.pend[e];
        ln.pend_t[e][l] = p.pend_t[e];
    }
    ln.side[l] = Some(p.side);
}

/// Load the next trajectory that needs a step into lane `l` (trajectories that end before their
/// first step get their result here); leave the lane idle when none is left.
#[cold]
pub(super) fn refill<'a, const N: usize>(
    ln: &mut Lanes<'a, N>,
    l: usize,
    inp: &Input<'a, '_>,
    out: &mut Vec<(usize, TrajectoryResult)>,
) {
    loop {
        // The next trajectory of the call, shared by every worker of it.
        let i = inp.feed.next.fetch_add(1, Ordering::Relaxed);
        if i >= inp.sliders.len() {
            break;
        }
        let s = &inp.sliders[i];
        let y0 = inp.y0s[i];
        let mut t_end = inp.t_end;
        let mode = s.mode_at(&y0);
        let watch = match inp.task {
            Task::Final => Watch::Nothing,
            Task::Sampled(te) => {
                let out = match &inp.feed.rows {
                    Some(rows) => Store::Row(rows.take(i)),
                    None => Store::Own(Vec::with_capacity(te.len())),
                };
                Watch::Sample(Sampler { t_eval: te, out })
            }
            Task::Steady { .. } => {
                let o = inp.task.steady_options(i).expect("a steady task");
                t_end = o.t_max;
                Watch::Steady(Box::new(SteadyObserver::new(s, &o)), Box::new(o))
            }
            Task::Events => Watch::Log(Vec::new()),
        };
        let mut obs = ExtremesObserver { s, ext: Extremes::default(), inner: watch };
        obs.ext.update(s, &y0, mode);
        let opts = options_for(s, &inp.tol);
        let mut sd = Side {
            i,
            s,
            opts,
            t_end,
            mode,
            pend: [None; MAX_EVENTS],
            stats: Stats::default(),
            obs,
            steps: ModeSteps::default(),
        };
        let early = |outcome: Outcome, n_rhs: u64, sd: &mut Side<'a>| {
            sd.stats.n_rhs = n_rhs;
            let status = status_of(outcome, y0[idx::Z].abs() >= s.p.escape_limit * (1.0 - 1e-9));
            let run = RunResult {
                status,
                t: 0.0,
                y: y0,
                extremes: sd.obs.ext,
                stats: sd.stats,
                failure: run_failure(status, s, 0.0, &y0, f64::NAN, 0, t_end, &sd.opts),
            };
            conclude(run, sd)
        };
        if !t_end.is_finite() || !y0.iter().all(|v| v.is_finite()) {
            out.push((i, early(Outcome::NonFinite, 0, &mut sd)));
            continue;
        }
        if t_end < 0.0 {
            out.push((i, early(Outcome::StepTooSmall, 0, &mut sd)));
            continue;
        }
        if t_end == 0.0 {
            out.push((i, early(Outcome::Finished, 0, &mut sd)));
            continue;
        }
        let f0 = s.rhs(&y0, mode);
        if !f0.iter().all(|v| v.is_finite()) {
            out.push((i, early(Outcome::NonFinite, 1, &mut sd)));
            continue;
        }
        let mut n_rhs = 1;
        let order = if ln.m8 { 8 } else { 5 };
        let h0 = initial_step(s, mode, 0.0, &y0, &f0, t_end, order, &opts.atol, opts.rtol, f64::INFINITY, &mut n_rhs);
        sd.stats.n_rhs = n_rhs;
        let mut g = [1.0; MAX_EVENTS];
        s.events(0.0, &y0, mode, &mut g);
        // Functions the law does not have stay 1 (never pending, never crossing).
        let ne = s.n_events();
        for e in 0..NE {
            g[e] = if e < ne { g[e] } else { 1.0 };
            if g[e] == 0.0 {
                sd.pend[e] = Some(0.0);
            }
            ln.g0[e][l] = g[e];
            ln.pend[e][l] = g[e] == 0.0;
            ln.pend_t[e][l] = if g[e] == 0.0 { 0.0 } else { f64::NAN };
        }
        let atol: [f64; 6] = std::array::from_fn(|k| opts.atol[k]);
        ln.c.set(l, s, &atol);
        for k in 0..6 {
            ln.y[k][l] = y0[k];
            ln.f[k][l] = f0[k];
        }
        ln.t[l] = 0.0;
        ln.t_end[l] = t_end;
        ln.h[l] = h0;
        ln.ln_err_old[l] = LN_ERR_FLOOR;
        ln.rejected[l] = false;
        ln.n_acc[l] = 0;
        ln.n_rej[l] = 0;
        ln.n_extra[l] = 0;
        ln.modes.set(l, mode);
        let e = sd.obs.ext;
        ln.min_n[l] = e.min_normal_force;
        ln.max_gap[l] = e.max_gap;
        ln.min_vr[l] = e.min_slip_velocity;
        ln.max_z[l] = e.max_abs_z;
        ln.rest[l] = f64::NEG_INFINITY;
        ln.next_sample[l] = f64::INFINITY;
        match &sd.obs.inner {
            Watch::Steady(o, _) => {
                ln.rest[l] = o.decay_floor;
                ln.peak[l] = o.w.peak_since;
                for k in 0..6 {
                    ln.peaks[k][l] = o.w.peaks_since[k];
                }
            }
            Watch::Sample(smp) => {
                ln.next_sample[l] = smp.t_eval.first().copied().unwrap_or(f64::INFINITY);
            }
            _ => {}
        }
        ln.side[l] = Some(sd);
        return;
    }
    idle(ln, l);
}
