//! Ensembles of slider trajectories: one entry point, [`run`], and the policy that routes an
//! ensemble to one of three paths.
//!
//! - [`Route::Batch`]: [`batch::run_bilateral_batch_sampled`], lane-batched Dormand–Prince 5(4) or DOP853 for
//!   the end state, or samples at `t_eval`, of the bilateral constant-`mu` slider (the fastest path;
//!   only the escape is located).
//! - [`Route::Lanes`]: [`lanes::run_lanes_threads`], lane-batched Dormand–Prince 5(4) and DOP853 for
//!   everything else the lanes support (unilateral contact, the tanh and switch Stribeck laws, samples at
//!   `t_eval`, runs to a steady state), with the scalar driver's event code on a cold path.
//! - [`Route::Scalar`]: the scalar driver through `steady` (`run`, `run_sampled`, `run_to_steady`,
//!   `run_observed`), one trajectory per work item of [`par_map`]: every method and model.
//!
//! Every route gives the result of the scalar driver with the same method and tolerances, to
//! integration accuracy (the lane paths use the same algebra with the dynamic law force used
//! directly, so states differ by rounding per step; tested per route). On one route a
//! trajectory's result is bitwise the same for any thread count: the lane paths compute each lane
//! from its own values only, whatever shares its batch, and the scalar route runs one pure
//! function per trajectory.
//!
//! This module is the home of every slider-specific batched integrator (`batch`, `lanes`); the
//! generic pieces they are built from (tableaux, the lane kit, event location) stay in
//! [`crate::ode`], which knows nothing of the slider.

pub mod batch;
pub mod lanes;

#[cfg(test)]
mod tests;

// The thread pools lived here before they moved to `parallel`; these names keep working.
pub use crate::parallel::{default_threads, panic_message, par_map, THREADS_ENV};

use crate::parallel::par_map_or;

use crate::model::{ContactMode, ContactModel, FrictionLaw, Slider, State};
use crate::ode::{Control, Method, Observer};
use crate::status::{Failure, Status};
use crate::steady::{self, DecayTest, Known, RunResult, SteadyOptions, Summary, Tolerances};

/// What each trajectory of an ensemble computes.
#[derive(Clone, Copy, Debug)]
pub enum Task<'a> {
    /// The end state at `t_end` (or where the run stopped).
    Final,
    /// The end state and the states at the increasing times `t_eval` (NaN past an early stop),
    /// as `steady::run_sampled`.
    Sampled(&'a [f64]),
    /// A run to a steady state and its summary, as `steady::run_to_steady`: `opts` carries the
    /// method, the tolerances and `t_max` (the settings' `t_end`, `method` and `tol` are not
    /// used). `decay`: a decay test per trajectory that overrides `opts`' (`DecayTest`);
    /// `known`: fingerprints of known irregular attractors per trajectory, overriding
    /// `opts.known_irregular`; `restart`: `t_max` and `hold` per trajectory, overriding `opts`'
    /// (runs that go on from where earlier ones stopped, each with its own time left).
    Steady {
        opts: &'a SteadyOptions,
        decay: Option<&'a [DecayTest]>,
        known: Option<&'a [Known]>,
        restart: Option<&'a [Restart]>,
    },
    /// The end state and every located event `(index, time)`: for tests and diagnostics.
    Events,
}

impl Task<'_> {
    /// Trajectory `i`'s options of a `Steady` task, with its own overrides (`None` for other tasks).
    pub fn steady_options(&self, i: usize) -> Option<SteadyOptions> {
        let Task::Steady { opts, decay, known, restart } = *self else { return None };
        let mut o = decay.map_or(*opts, |d| d[i].apply(opts));
        if let Some(k) = known {
            o.known_irregular = k[i];
        }
        if let Some(r) = restart {
            (o.t_max, o.hold) = (r[i].t_max, r[i].hold);
        }
        Some(o)
    }

    /// Panics unless the per-trajectory overrides of a `Steady` task have one entry per trajectory.
    pub(crate) fn check_overrides(&self, n: usize, caller: &str) {
        if let Task::Steady { decay, known, restart, .. } = self {
            assert!(decay.is_none_or(|d| d.len() == n), "{caller}: one decay test per slider");
            assert!(restart.is_none_or(|r| r.len() == n), "{caller}: one restart per slider");
            assert!(known.is_none_or(|k| k.len() == n), "{caller}: one set of known fingerprints per slider");
        }
    }
}

/// A run to steady state that goes on from where an earlier one stopped: its own longest
/// simulated time and hold (`SteadyOptions::t_max`, `SteadyOptions::hold`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Restart {
    /// Longest simulated time of this run [s].
    pub t_max: f64,
    /// No periodic state before this time [s].
    pub hold: f64,
}

/// The result of one trajectory.
#[derive(Clone, Debug)]
pub struct TrajectoryResult {
    /// The plain run. For `Steady`: on the lane route the run up to the end of detection; on the
    /// scalar route the summary's status, `t_end`, `y_end`, extremes and work.
    pub run: RunResult,
    /// States at `t_eval` (`Sampled` only).
    pub samples: Vec<State>,
    /// Summary (`Steady` only); boxed, so that a plain run's result stays small (an ensemble's
    /// results are moved several times on their way to Python, one thread for all of them).
    pub summary: Option<Box<Summary>>,
    /// Located events `(index, time)` (`Events` only).
    pub events: Vec<(usize, f64)>,
}

impl TrajectoryResult {
    /// A plain run's result, nothing else.
    pub fn from_run(run: RunResult) -> Self {
        TrajectoryResult { run, samples: Vec::new(), summary: None, events: Vec::new() }
    }

    /// The result of a trajectory that could not be computed: `status`, NaN state and time, no
    /// samples, a failed summary.
    pub fn failed(status: Status) -> Self {
        Self::failed_because(status, None)
    }

    /// [`TrajectoryResult::failed`] with the failure behind it.
    pub fn failed_because(status: Status, failure: Option<Failure>) -> Self {
        let run = RunResult::failed(status, failure);
        TrajectoryResult { summary: Some(Box::new(Summary::failed(status, failure))), ..Self::from_run(run) }
    }

    /// The result of a trajectory that a cancelled call never started (`NotComputed`), with no
    /// summary (`Summary::failed` of its status is what it would hold): a cancelled call of 10^6
    /// trajectories allocated and faulted in a boxed summary for each, 2 s of the reaction to
    /// Ctrl-C (1.5-2 us per trajectory, measured 2026-11-26).
    pub fn not_started() -> Self {
        Self::from_run(RunResult::failed(Status::NotComputed, Some(Failure::NotStarted)))
    }
}

/// Settings shared by every trajectory of an ensemble.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Simulated time of each trajectory from `t = 0` [s] (not used by `Task::Steady`).
    pub t_end: f64,
    /// Integrator (not used by `Task::Steady`: `opts.method`).
    pub method: Method,
    /// Tolerances and limits (not used by `Task::Steady`: `opts.tol`).
    pub tol: Tolerances,
    /// Worker threads; `None`: [`default_threads`].
    pub threads: Option<usize>,
}

/// The path an ensemble takes (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Route {
    /// [`batch::run_bilateral_batch`] on groups of [`group_size`] trajectories in parallel.
    Batch,
    /// [`lanes::run_lanes_threads`].
    Lanes,
    /// The scalar driver, one trajectory per work item.
    Scalar,
}

impl Route {
    /// Every route.
    pub const ALL: [Route; 3] = [Route::Batch, Route::Lanes, Route::Scalar];
}

/// The method and tolerances a task integrates with.
fn method_tol(settings: &Settings, task: &Task<'_>) -> (Method, Tolerances) {
    match task {
        Task::Steady { opts, .. } => (opts.method, opts.tol),
        _ => (settings.method, settings.tol),
    }
}

/// Whether `route` can compute `task` for these sliders with these settings: the batch only the
/// end state or samples (`t_end > 0`) of bilateral constant-`mu` sliders with DOPRI5 or DOP853 and the default step and event
/// budgets (it counts no events); the lanes only DOPRI5 or DOP853 and the friction laws they know,
/// with one contact model and one law for all sliders; the scalar route everything.
pub fn supports(route: Route, sliders: &[Slider], settings: &Settings, task: &Task<'_>) -> bool {
    let (method, tol) = method_tol(settings, task);
    let Some(first) = sliders.first() else { return route == Route::Scalar };
    let shared = sliders.iter().all(|s| s.p.contact == first.p.contact && s.p.friction_law == first.p.friction_law);
    match route {
        Route::Batch => {
            (matches!(task, Task::Final)
                || (matches!(task, Task::Sampled(_)) && settings.t_end.is_finite() && settings.t_end > 0.0))
                && !tol.has_limits()
                && batch::supports_method(method)
                && shared
                && first.p.contact == ContactModel::Bilateral
                && first.p.friction_law == FrictionLaw::Constant
        }
        Route::Lanes => lanes::supports_method(method) && shared && lanes::supports(&first.p),
        Route::Scalar => true,
    }
}

/// The routing policy: the batch where it applies (the fastest), else the lanes where they
/// apply, else the scalar driver.
pub fn route(sliders: &[Slider], settings: &Settings, task: &Task<'_>) -> Route {
    [Route::Batch, Route::Lanes].into_iter().find(|&r| supports(r, sliders, settings, task)).unwrap_or(Route::Scalar)
}

/// Trajectories per group of the batch route for `n` trajectories on `threads` threads (`None`:
/// [`default_threads`]): about four groups per thread, so that the threads stay busy to the end of
/// a call even when a few long runs dominate it, at least one full set of the batch's lanes
/// ([`batch::lane_count`]: 16 with AVX-512, else 8) and at most 1024.
///
/// A group runs on one set of lanes and refills them from its own trajectories only, so a group
/// smaller than the set leaves lanes idle to its end. The floor was 8 after the AVX-512 copy had
/// gone to 16 lanes: 16 trajectories on one thread ran as two groups of 8, each paying for 16
/// lanes (bilateral, 5 s, Zen 5: 5.1 ms, against 2.9 ms for 8 trajectories).
pub fn group_size(n: usize, threads: Option<usize>) -> usize {
    let nthreads = threads.unwrap_or_else(default_threads).max(1);
    n.div_ceil(4 * nthreads).clamp(batch::lane_count(), 1024)
}

/// Integrate each `sliders[i]` from `y0s[i]` at `t = 0` and compute `task` for it, on the route
/// that [`route`] picks; results in input order. `Err(message)` for a trajectory whose
/// computation panicked (on the batch route: every trajectory of its group). When the caller
/// cancels ([`crate::cancel`]), every route stops within [`crate::cancel::CHECK_EVERY`] steps of a
/// trajectory: the trajectories still running end with `NotComputed` (`Failure::Cancelled`), those
/// not started with [`TrajectoryResult::not_started`].
///
/// Preconditions (panics otherwise): `sliders.len() == y0s.len()`; for `Task::Steady` with
/// `decay` or `known`, one entry per slider.
pub fn run(
    sliders: &[Slider],
    y0s: &[State],
    settings: &Settings,
    task: Task<'_>,
) -> Vec<Result<TrajectoryResult, String>> {
    run_on(route(sliders, settings, &task), sliders, y0s, settings, task)
}

/// [`run`] on a given route (for tests and benchmarks). Panics if [`supports`] rejects the route.
pub fn run_on(
    route: Route,
    sliders: &[Slider],
    y0s: &[State],
    settings: &Settings,
    task: Task<'_>,
) -> Vec<Result<TrajectoryResult, String>> {
    assert_eq!(sliders.len(), y0s.len(), "ensemble: one initial state per slider");
    task.check_overrides(sliders.len(), "ensemble");
    assert!(supports(route, sliders, settings, &task), "ensemble: the {route:?} route cannot compute this task");
    let (method, tol) = method_tol(settings, &task);
    let threads = settings.threads;
    match route {
        Route::Batch => {
            let t_eval: &[f64] = if let Task::Sampled(te) = task { te } else { &[] };
            let stride = 6 * t_eval.len();
            let mut flat = vec![0.0; sliders.len() * stride];
            let mut out = run_batch(sliders, y0s, settings.t_end, method, &tol, threads, t_eval, &mut flat);
            if stride > 0 {
                for (o, row) in out.iter_mut().zip(flat.chunks_exact(stride)) {
                    if let Ok(x) = o {
                        x.samples = batch::states_of(row);
                    }
                }
            }
            out
        }
        Route::Lanes => lanes::run_lanes_threads(sliders, y0s, settings.t_end, method, &tol, task, threads),
        Route::Scalar => {
            let rows: Vec<usize> = (0..sliders.len()).collect();
            par_map_or(
                &rows,
                threads,
                |&i| Ok(scalar(&sliders[i], &y0s[i], i, settings.t_end, method, &tol, task)),
                Err,
                || Ok(TrajectoryResult::not_started()),
            )
        }
    }
}

/// [`run`] of `Task::Sampled(t_eval)` with every trajectory's samples written into `out`, a row
/// of `6 t_eval.len()` values per trajectory (state by state, in input order), instead of into the
/// results' `samples` (left empty): the samples each run reached, NaN after them and for a
/// trajectory that failed or was not started. The batched routes write into `out` as they
/// sample; the scalar route copies each result's samples into its row.
pub fn run_sampled_into(
    sliders: &[Slider],
    y0s: &[State],
    settings: &Settings,
    t_eval: &[f64],
    out: &mut [f64],
) -> Vec<Result<TrajectoryResult, String>> {
    let task = Task::Sampled(t_eval);
    let stride = 6 * t_eval.len();
    assert_eq!(out.len(), sliders.len() * stride, "ensemble: one row of samples per trajectory");
    let route = route(sliders, settings, &task);
    let (method, tol, threads) = (settings.method, settings.tol, settings.threads);
    match route {
        Route::Batch => {
            assert_eq!(sliders.len(), y0s.len(), "ensemble: one initial state per slider");
            return run_batch(sliders, y0s, settings.t_end, method, &tol, threads, t_eval, out);
        }
        Route::Lanes => return lanes::run_lanes_into(sliders, y0s, settings.t_end, method, &tol, t_eval, threads, out),
        Route::Scalar => {}
    }
    let mut res = run_on(route, sliders, y0s, settings, task);
    if stride > 0 {
        for (o, row) in res.iter_mut().zip(out.chunks_exact_mut(stride)) {
            let samples = o.as_mut().map(|x| std::mem::take(&mut x.samples)).unwrap_or_default();
            let k = samples.len().min(t_eval.len());
            for (dst, v) in row.chunks_exact_mut(6).zip(&samples[..k]) {
                dst.copy_from_slice(v.as_slice());
            }
            row[6 * k..].fill(f64::NAN);
        }
    }
    res
}

/// The bilateral batch on groups of [`group_size`] trajectories in parallel, the samples at
/// `t_eval` into `out` (rows of `6 t_eval.len()` values; NaN for a group that panicked or was not
/// started).
#[allow(clippy::too_many_arguments)]
fn run_batch(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    threads: Option<usize>,
    t_eval: &[f64],
    out: &mut [f64],
) -> Vec<Result<TrajectoryResult, String>> {
    let stride = 6 * t_eval.len();
    let group = group_size(sliders.len(), threads);
    let ranges: Vec<std::ops::Range<usize>> =
        (0..sliders.len()).step_by(group).map(|a| a..(a + group).min(sliders.len())).collect();
    // Each group's rows, handed to the worker that runs it (once).
    let rows: Vec<std::sync::Mutex<Option<&mut [f64]>>> = {
        let mut rest = &mut *out;
        ranges
            .iter()
            .map(|r| {
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(r.len() * stride);
                rest = tail;
                std::sync::Mutex::new(Some(head))
            })
            .collect()
    };
    let groups: Vec<usize> = (0..ranges.len()).collect();
    let parts = par_map_or(
        &groups,
        threads,
        |&g| {
            let r = ranges[g].clone();
            let buf = rows[g].lock().unwrap_or_else(|e| e.into_inner()).take().expect("each group runs once");
            Some(Ok(batch::run_bilateral_batch_into(&sliders[r.clone()], &y0s[r], t_end, method, tol, t_eval, buf)))
        },
        |msg| Some(Err(msg)),
        || None,
    );
    drop(rows);
    let mut res = Vec::with_capacity(sliders.len());
    for (p, r) in parts.into_iter().zip(&ranges) {
        match p {
            Some(Ok(v)) => res.extend(v.into_iter().map(|run| Ok(TrajectoryResult::from_run(run)))),
            failed => {
                out[r.start * stride..r.end * stride].fill(f64::NAN);
                match failed {
                    Some(Err(msg)) => res.extend(std::iter::repeat_n(Err(msg), r.len())),
                    _ => res.extend(std::iter::repeat_n(Ok(TrajectoryResult::not_started()), r.len())),
                }
            }
        }
    }
    res
}

/// One trajectory on the scalar driver.
fn scalar(
    s: &Slider,
    y0: &State,
    i: usize,
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
) -> TrajectoryResult {
    match task {
        Task::Final => TrajectoryResult::from_run(steady::run(s, y0, t_end, method, tol)),
        Task::Sampled(te) => {
            let (run, samples) = steady::run_sampled(s, y0, t_end, method, tol, te);
            TrajectoryResult { samples, ..TrajectoryResult::from_run(run) }
        }
        Task::Steady { .. } => {
            let o = task.steady_options(i).expect("a steady task");
            let sum = steady::run_to_steady(s, y0, &o);
            let run = RunResult {
                status: sum.status,
                t: sum.t_end,
                y: sum.y_end,
                extremes: sum.extremes,
                stats: sum.stats,
                failure: sum.failure,
            };
            TrajectoryResult { summary: Some(Box::new(sum)), ..TrajectoryResult::from_run(run) }
        }
        Task::Events => {
            let (run, log) = steady::run_observed(s, y0, t_end, method, tol, EventLog(Vec::new()));
            TrajectoryResult { events: log.0, ..TrajectoryResult::from_run(run) }
        }
    }
}

/// Records every located event `(index, time)`.
struct EventLog(Vec<(usize, f64)>);

impl Observer<6, ContactMode> for EventLog {
    fn on_event(&mut self, i: usize, t: f64, _y: &State, _before: ContactMode, _after: ContactMode) -> Control {
        self.0.push((i, t));
        Control::Continue
    }
}
