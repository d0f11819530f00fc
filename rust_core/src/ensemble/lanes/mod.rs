//! Lane-batched Dormand–Prince 5(4) and DOP853 for the whole slider model: unilateral contact,
//! the regularised Coulomb/Stribeck law and the event-driven switch law (stick-slip), output at
//! `t_eval`, and runs to a steady state.
//!
//! [`run_lanes`] integrates many trajectories [`W`] = 8 at a time in structure-of-arrays form (the
//! generic lane kit `ode::lanes`; end states and samples 16 at a time in the AVX-512 copy,
//! [`W_FINAL_AVX512`]; calls too small to fill every thread's set on fewer, [`lane_width`]), as
//! [`super::batch`] does for the bilateral constant-`mu` end state, and refills a lane as soon as
//! its trajectory ends (on AVX-512, once the call's feed is dry, a thread's running trajectories
//! move to narrower sets as they end, down to one lane: `dispatch_cpu`). What it adds is everything the scalar driver
//! does around the step:
//!
//! - **Modes per lane.** Each lane knows whether its pin is on or off the disk and, under the
//!   switch law, whether it slips, sticks or is in transition across the stick band; the contact
//!   and friction forces are selected branch-free from per-lane masks, so lanes in different modes
//!   share the step.
//! - **Events per lane, never stepped across.** After every accepted step the event functions of
//!   the slider (gap, law normal force, sliding velocity, escape; the switch law's two band edges
//!   and stick bound) are evaluated on all lanes at once; for the unilateral model and the switch
//!   law they are also evaluated at the three interior points of
//!   each step's dense output and at the turning point of the function most likely to touch zero
//!   (the scalar driver's hidden-crossing check), and a lane with a
//!   crossing and its return inside its step redoes the step ending inside the excursion. A lane
//!   whose step shows a crossing (or has an event pending after a switch) goes to a cold path that
//!   builds that lane's Dormand–Prince interpolant and runs **the scalar driver's own event code**
//!   (`ode::events::step_events`: location, time order, actions, the re-trigger guard) on it,
//!   then restarts the lane in its new mode with a fresh derivative, as the scalar driver does.
//! - **Observers per lane.** Sampling at `t_eval` and the steady-state watcher (Poincare section
//!   `zd = 0` falling, decay, cycle detection) are the scalar path's observers, called on the cold
//!   path only for lanes that need them this step: a lane whose `t_eval` point falls inside its
//!   step (DOP853, or a step with an event or the run's end: DP5 samples on an otherwise plain
//!   step are taken on the lanes, by the sampler's rule and the same interpolant formula, so with
//!   the same bits), whose `zd` changes sign downwards, or whose motion fell below the rest floor.
//!   On all other steps the bookkeeping those observers do per step (extremes, the peaks since the
//!   last section) runs vectorised on the lanes.
//!
//! The result of a trajectory is that of `steady::run`, `steady::run_sampled` or
//! `steady::run_to_steady` with `Method::Dopri5` to integration accuracy (tested on every scene of
//! the work-precision bench and on the seed's bouncing cycle): the right-hand side is the same
//! algebra with the dynamic law force used directly, and `exp`/`tanh` of the Stribeck law are
//! branch-free lane polynomials, so states differ from the scalar path's by rounding per step.
//!
//! # Determinism
//! Every lane's arithmetic depends on that lane's values only, and the cold paths are scalar code
//! on one trajectory, so a trajectory's result is bitwise the same whatever trajectories share its
//!
//! # Files
//! - `mod.rs`: the entry points, their preconditions, the dispatch to a monomorphised,
//!   CPU-feature-specific copy of the loop;
//! - `slider.rs`: the slider on the lanes (coefficients, right-hand side, event functions,
//!   hidden-crossing check);
//! - `state.rs`: the lanes' vector side and each lane's scalar side (observers, events), loading
//!   and finishing trajectories;
//! - `run.rs`: the loop over steps of the lanes, with the cold path.

// Index loops over lanes and components are the point here: they are what LLVM vectorises.
#![allow(clippy::needless_range_loop)]

mod quick;
mod run;
mod slider;
mod state;

pub(crate) use slider::Coef;

use super::{Task, TrajectoryResult};
use crate::model::{ContactModel, FrictionLaw, Params, Slider, State};
use crate::ode::lanes::Rows;
use crate::ode::lanes::W;
use crate::ode::Method;
use crate::steady::Tolerances;
use run::run_impl;
use state::{Feed, Input, Parked};

/// Whether [`run_lanes`] integrates sliders with these parameters (the contact models and
/// friction laws it knows).
pub fn supports(p: &Params) -> bool {
    matches!(p.friction_law, FrictionLaw::Constant | FrictionLaw::Coulomb | FrictionLaw::Switch)
}

/// Whether [`run_lanes`] integrates with this method (the explicit Dormand–Prince pair and DOP853).
pub fn supports_method(m: Method) -> bool {
    matches!(m, Method::Dopri5 | Method::Dop853)
}

/// Integrate each `sliders[i]` from `y0s[i]` at `t = 0` with `method` (Dormand–Prince 5(4) or
/// DOP853), 4, 8 or (end states and samples on AVX-512) 16 trajectories at a time on this
/// thread ([`lane_width`]), and compute `task` for each; results in input order.
///
/// Precondition (the caller checks): all sliders share one contact model and one friction law,
/// which [`supports`] accepts; [`supports_method`] accepts `method`; `sliders.len() ==
/// y0s.len()`. Panics otherwise.
pub fn run_lanes(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
) -> Vec<TrajectoryResult> {
    check(sliders, y0s, method, &task);
    let feed = Feed::new(None);
    let width = lane_width(sliders.len(), 1, &task);
    // Only a cancelled call leaves trajectories without a result.
    let done = dispatch(sliders, y0s, t_end, method, tol, task, &feed, width);
    crate::parallel::scatter(sliders.len(), done, |_| TrajectoryResult::not_started())
}

/// [`run_lanes`] on `threads` threads (`None`: [`crate::parallel::default_threads`]): every
/// thread runs its own lanes and takes the next trajectory of the call whenever one of its
/// lanes ends, so the threads stay busy to the end however unequal the runs. A trajectory's
/// result does not depend on which lanes or thread ran it (bitwise; tested), so results are the
/// same for any thread count. A panic on a thread becomes `Err(message)` for the trajectories
/// that thread had not finished. On cancellation ([`crate::cancel`]) every thread stops within
/// [`crate::cancel::CHECK_EVERY`] steps: its running trajectories end with `NotComputed`, and those
/// not started get [`TrajectoryResult::not_started`].
pub fn run_lanes_threads(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
    threads: Option<usize>,
) -> Vec<Result<TrajectoryResult, String>> {
    run_lanes_fed(sliders, y0s, t_end, method, tol, task, threads, Feed::new(None))
}

/// [`run_lanes_threads`] of `Task::Sampled(t_eval)` with the samples written into `out`, a row of
/// `6 t_eval.len()` values per trajectory (the results' `samples` left empty): those the run
/// reached, NaN after them. Rows of trajectories that were not started or whose thread panicked
/// are NaN.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_lanes_into(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    t_eval: &[f64],
    threads: Option<usize>,
    out: &mut [f64],
) -> Vec<Result<TrajectoryResult, String>> {
    let stride = 6 * t_eval.len();
    assert_eq!(out.len(), sliders.len() * stride, "run_lanes: one row of samples per slider");
    if stride == 0 {
        return run_lanes_threads(sliders, y0s, t_end, method, tol, Task::Sampled(t_eval), threads);
    }
    let rows = Rows::new(out, stride);
    let feed = Feed::new(Some(rows));
    let res = run_lanes_fed(sliders, y0s, t_end, method, tol, Task::Sampled(t_eval), threads, feed);
    for (r, row) in res.iter().zip(out.chunks_exact_mut(stride)) {
        if r.is_err() || matches!(r, Ok(x) if x.run.failure == Some(crate::status::Failure::NotStarted)) {
            row.fill(f64::NAN);
        }
    }
    res
}

#[allow(clippy::too_many_arguments)]
fn run_lanes_fed(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
    threads: Option<usize>,
    feed: Feed<'_>,
) -> Vec<Result<TrajectoryResult, String>> {
    check(sliders, y0s, method, &task);
    let n = sliders.len();
    let threads = threads.unwrap_or_else(crate::parallel::default_threads).max(1);
    let width = lane_width(n, threads, &task);
    let nthreads = threads.min(n.div_ceil(width).max(1));
    let workers: Vec<usize> = (0..nthreads).collect();
    let parts = crate::parallel::par_map_or(
        &workers,
        Some(nthreads),
        |_| Ok(dispatch(sliders, y0s, t_end, method, tol, task, &feed, width)),
        Err,
        || Ok(Vec::new()),
    );
    let mut done = Vec::with_capacity(parts.len());
    let mut panic = None;
    for p in parts {
        match p {
            Ok(v) => done.push(v),
            Err(msg) => panic = Some(msg),
        }
    }
    // Each result moves once, on this one thread: the lanes' results are gathered serially, and
    // for short runs on many cores every pass over them counts (Amdahl).
    // Without a panic, only a cancelled call leaves trajectories without a result.
    crate::parallel::scatter(n, done.into_iter().flatten().map(|(i, r)| (i, Ok(r))), |_| match &panic {
        Some(msg) => Err(msg.clone()),
        None => Ok(TrajectoryResult::not_started()),
    })
}

fn check(sliders: &[Slider], y0s: &[State], method: Method, task: &Task<'_>) {
    assert_eq!(sliders.len(), y0s.len(), "run_lanes: one initial state per slider");
    assert!(supports_method(method), "run_lanes: method {method:?} is not lane-batched");
    if let Some(first) = sliders.first() {
        for s in sliders {
            assert!(supports(&s.p), "run_lanes: friction law {:?} is not lane-batched", s.p.friction_law);
            assert!(
                s.p.contact == first.p.contact && s.p.friction_law == first.p.friction_law,
                "run_lanes: every slider of one call shares the contact model and friction law"
            );
        }
    }
    task.check_overrides(sliders.len(), "run_lanes");
}

/// The narrowest lane set: one AVX2 register, half an AVX-512 one (see [`lane_width`]).
pub const W_NARROW: usize = 4;

/// The widest lane set of this CPU for `task`: [`W_FINAL_AVX512`] for end states and samples on
/// AVX-512, else [`W`].
fn full_width(task: &Task<'_>) -> usize {
    #[cfg(target_arch = "x86_64")]
    if matches!(task, Task::Final | Task::Sampled(_)) && std::is_x86_feature_detected!("avx512f") {
        return W_FINAL_AVX512;
    }
    W
}

/// The cost of one step of a set of `w` lanes, all running, relative to 16: the unilateral
/// issue-2 ensemble's DOP853 end state at rtol 1e-6, one thread, 1,000 trajectories, 70.0-71.0k
/// trajectories/s on 16 lanes, 48.9-49.0k on 8, 27.7-28.0k on 4 (Zen 5, AVX-512; DP5 and 501
/// samples in the same ratio or nearer 1). A run to a steady state alone on its lanes: 1.25 us a
/// step on 8, 1.11 on 4 (0.88, as 0.63 / 0.71).
fn step_cost(w: usize) -> f64 {
    match w {
        16 => 1.0,
        8 => 0.71,
        _ => 0.63,
    }
}

/// Lanes per worker for `n` trajectories on `threads` threads: of the widths up to the CPU's full
/// set (16, 8, [`W_NARROW`]), the one whose call takes the least time by [`step_cost`], the
/// workers being `min(threads, ceil(n / w))`, each running `ceil(n / (workers w))` rounds of
/// its set (runs of equal length); the wider on a tie. A wide set steps all its lanes whether
/// they run or not, and a call of fewer trajectories than threads times lanes left threads idle:
/// on 16 threads the 14 Lyapunov segments of a call of the Stribeck sweep took one worker of 16
/// lanes (now 4 of 4). On 2 threads 30 trajectories keep 2 workers of 16 (4 lanes would take 4
/// rounds at 0.63: 2.5x as long). A lane's bits do not depend on the lane count, so neither do
/// the results.
pub(crate) fn lane_width(n: usize, threads: usize, task: &Task<'_>) -> usize {
    let full = full_width(task);
    let wall = |w: usize| {
        let workers = threads.max(1).min(n.div_ceil(w)).max(1);
        n.div_ceil(workers * w).max(1) as f64 * step_cost(w)
    };
    let mut best = full;
    for w in [W_FINAL_AVX512, W, W_NARROW] {
        if w < full && wall(w) < wall(best) {
            best = w;
        }
    }
    best
}

/// The monomorphised, CPU-dispatched lane driver for the sliders' model and `method`, on `width`
/// lanes ([`lane_width`]: 16 only where the CPU's full set is 16).
#[allow(clippy::too_many_arguments)]
fn dispatch(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &Feed<'_>,
    width: usize,
) -> Vec<(usize, TrajectoryResult)> {
    let Some(first) = sliders.first() else { return Vec::new() };
    let uni = first.p.contact == ContactModel::Unilateral;
    let m8 = method == Method::Dop853;
    macro_rules! go {
        ($u:literal, $c:expr, $m:literal) => {
            dispatch_cpu::<$u, { $c as u8 }, $m>(sliders, y0s, t_end, tol, task, feed, width)
        };
    }
    use FrictionLaw::{Constant as C, Coulomb as T, Switch as S};
    match (uni, first.p.friction_law, m8) {
        (false, C, false) => go!(false, C, false),
        (false, T, false) => go!(false, T, false),
        (false, S, false) => go!(false, S, false),
        (true, C, false) => go!(true, C, false),
        (true, T, false) => go!(true, T, false),
        (true, S, false) => go!(true, S, false),
        (false, C, true) => go!(false, C, true),
        (false, T, true) => go!(false, T, true),
        (false, S, true) => go!(false, S, true),
        (true, C, true) => go!(true, C, true),
        (true, T, true) => go!(true, T, true),
        (true, S, true) => go!(true, S, true),
    }
}

/// Out of line, as each of the copies it picks from: inlined into [`dispatch`], the twelve
/// portable bodies made one function that LLVM's optimisation took minutes over.
///
/// On AVX-512 and on AVX2, once the call's feed is dry, a thread's running trajectories move to the
/// narrowest set of lanes that holds them whenever that is at most half the set ([`run_impl`]'s
/// `narrow`), down to one lane, with the same bits: a round costs about 0.72, 0.97, 1.09 and
/// 1.28 us on 1, 2, 4 and 8 lanes (the switch law's Stribeck transients forced onto each width,
/// one thread), and on two threads each thread ran one late long run alone for 18-26 ms of the
/// call's 233 (the longest run of the call alone: 80 ms on 8 lanes, 55 ms on 1). AVX2 parks the
/// same way since 2026-11-28: the sweep's two transient calls, replayed on two threads in one
/// process with both builds loaded and interleaved (Zen 3, AVX2, 12 rounds), took 0.905x as long
/// (median of the per-round ratios), on one thread the same within the noise, with the same bits.
#[inline(never)]
fn dispatch_cpu<const UNI: bool, const LAW: u8, const M8: bool>(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &Feed<'_>,
    width: usize,
) -> Vec<(usize, TrajectoryResult)> {
    let inp = Input::new(sliders, y0s, t_end, tol, task, feed);
    // `$run` on `width` lanes, then its parked runs on the narrowest set that holds them, until
    // every run has ended.
    #[cfg(target_arch = "x86_64")]
    macro_rules! run_parked {
        ($run:ident, $($w:pat => $n:expr),+) => {{
            let (mut out, mut parked) = match width {
                $($w => $run::<UNI, LAW, M8, { $n }>(&inp, Vec::new(), true),)+
            };
            while !parked.is_empty() {
                let (o, p) = match parked.len() {
                    1 => $run::<UNI, LAW, M8, 1>(&inp, parked, true),
                    2 => $run::<UNI, LAW, M8, 2>(&inp, parked, true),
                    3 | 4 => $run::<UNI, LAW, M8, W_NARROW>(&inp, parked, true),
                    _ => $run::<UNI, LAW, M8, W>(&inp, parked, true),
                };
                out.extend(o);
                parked = p;
            }
            out
        }};
    }
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { run_parked!(run_avx512, W_FINAL_AVX512 => W_FINAL_AVX512, W => W, _ => W_NARROW) };
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { run_parked!(run_avx2, W_NARROW => W_NARROW, _ => W) };
        }
    }
    if width == W_NARROW {
        run_portable::<UNI, LAW, M8, W_NARROW>(&inp, Vec::new(), false).0
    } else {
        run_portable::<UNI, LAW, M8, W>(&inp, Vec::new(), false).0
    }
}

/// The portable copy (no CPU features beyond the target's baseline).
#[inline(never)]
fn run_portable<'a, const UNI: bool, const LAW: u8, const M8: bool, const N: usize>(
    inp: &Input<'a, '_>,
    seed: Vec<Parked<'a>>,
    narrow: bool,
) -> (Vec<(usize, TrajectoryResult)>, Vec<Parked<'a>>) {
    run_impl::<UNI, LAW, M8, N>(inp, seed, narrow)
}

/// Lanes of the AVX-512 copy for end states (`Task::Final`) and samples (`Task::Sampled`): two
/// registers per operation, as in the bilateral batch (`batch::W_AVX512`). Runs to a steady state
/// keep `W` = 8: their any-lane work (the hidden-crossing check's extra stages and the cold
/// visits of sections) runs for every lane as soon as one lane needs it; 16 lanes made the census
/// 10 % slower. Measured on the unilateral issue-2 ensemble (Zen 4, one thread, 4,000
/// trajectories, builds alternating): DOP853 end state 27.9-29.9k -> 31.5-32.4k trajectories/s at
/// rtol 1e-6 and 12.4-13.3k -> 15.0-15.3k at 1e-9, DP5 14.7k -> 15.4-15.8k. The price is on end
/// states of bouncing motion, where a contact event is in some lane almost every step: 512
/// trajectories at 120 N, 11 cm, 1 s (438 events each), DOP853 at 1e-6, 1,852-1,905 ->
/// 1,720-1,784 per second (6 % slower). Runs mostly in contact, like the issue-2 ensemble, gain
/// 20 %. Samples ran 8 lanes beyond 16 output times until they were taken on all lanes at once
/// (`lanes::sample_lanes`); since then 16 win (Zen 5, 1,000 trajectories, rtol 1e-6, one thread):
/// DOP853 with 501 samples 25-26k -> 28-29k, DP5 19.2k -> 21.4k; 512 trajectories on the seed's
/// bouncing cycle (406 events each in 1 s) with 1,001 samples, DOP853 2,570-2,610 -> 2,780-2,840
/// per second, DP5 1,820 -> 2,510-2,540.
pub const W_FINAL_AVX512: usize = 16;

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn run_avx512<'a, const UNI: bool, const LAW: u8, const M8: bool, const N: usize>(
    inp: &Input<'a, '_>,
    seed: Vec<Parked<'a>>,
    narrow: bool,
) -> (Vec<(usize, TrajectoryResult)>, Vec<Parked<'a>>) {
    run_impl::<UNI, LAW, M8, N>(inp, seed, narrow)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<'a, const UNI: bool, const LAW: u8, const M8: bool, const N: usize>(
    inp: &Input<'a, '_>,
    seed: Vec<Parked<'a>>,
    narrow: bool,
) -> (Vec<(usize, TrajectoryResult)>, Vec<Parked<'a>>) {
    run_impl::<UNI, LAW, M8, N>(inp, seed, narrow)
}

#[cfg(test)]
mod tests;
