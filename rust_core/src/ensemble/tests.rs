//! The routing policy and the entry point: which route each ensemble takes, every route against
//! the scalar driver (with the tolerances of the lane and batch tests), and bitwise equality where
//! results must not change (thread counts, the batch's grouping, the entry point against the paths
//! it calls).

use super::*;
use crate::model::Params;
use crate::steady::SteadyOutcome;

fn tol(rtol: f64) -> Tolerances {
    Tolerances::new(rtol)
}

fn settings(t_end: f64, method: Method, rtol: f64, threads: Option<usize>) -> Settings {
    Settings { t_end, method, tol: tol(rtol), threads }
}

fn sliders(base: Params, mus: &[f64]) -> Vec<Slider> {
    mus.iter().map(|&mu| Slider::new(Params { mu, ..base }).unwrap()).collect()
}

fn starts(n: usize, z0: f64) -> Vec<State> {
    vec![State::new(z0, 0.0, 0.0, 0.0, 0.0, 0.0); n]
}

fn unwrap(v: Vec<Result<TrajectoryResult, String>>) -> Vec<TrajectoryResult> {
    v.into_iter().map(|r| r.expect("no panic")).collect()
}

/// Every number of a result, as bits.
fn bits(r: &TrajectoryResult) -> Vec<u64> {
    let mut v: Vec<u64> = r.run.y.iter().map(|x| x.to_bits()).collect();
    v.push(r.run.t.to_bits());
    let e = r.run.extremes;
    v.extend([e.min_normal_force, e.max_gap, e.min_slip_velocity, e.max_abs_z].map(f64::to_bits));
    let s = r.run.stats;
    v.extend([s.n_rhs, s.n_jac, s.n_lu, s.n_accept, s.n_reject, s.n_events, r.run.status.code() as u64]);
    for y in &r.samples {
        v.extend(y.iter().map(|x| x.to_bits()));
    }
    if let Some(m) = &r.summary {
        v.extend([m.omega, m.period, m.t_end, m.z0, m.z_amp[0], m.z_amp[1], m.fraction_off_disk].map(f64::to_bits));
        v.extend(m.y_end.iter().map(|x| x.to_bits()));
        v.extend([m.outcome as u64, m.multiplicity as u64, m.stats.n_rhs]);
    }
    for (i, t) in &r.events {
        v.extend([*i as u64, t.to_bits()]);
    }
    v
}

fn seed_bilateral() -> Params {
    Params::seed()
}

fn unilateral() -> Params {
    Params { contact: ContactModel::Unilateral, ..Params::seed() }
}

#[test]
fn the_policy_picks_the_fastest_route_that_applies() {
    let bil = sliders(seed_bilateral(), &[0.21, 0.22]);
    let uni = sliders(unilateral(), &[0.21, 0.22]);
    let sw = sliders(Params { friction_law: FrictionLaw::Switch, ..seed_bilateral() }, &[0.21]);
    let mixed = vec![bil[0], uni[0]];
    let te = [0.0, 0.1];
    let opts = SteadyOptions::default();
    let steady = Task::Steady { opts: &opts, decay: None, known: None, restart: None };
    let dp5 = settings(0.5, Method::Dopri5, 1e-8, None);
    let limited = Settings { tol: Tolerances { max_steps: Some(1000), ..tol(1e-8) }, ..dp5 };
    let cases: [(&str, &[Slider], Settings, Task<'_>, Route); 13] = [
        ("bilateral constant end state", &bil, dp5, Task::Final, Route::Batch),
        ("with a step budget (the batch keeps the default)", &bil, limited, Task::Final, Route::Lanes),
        ("samples", &bil, dp5, Task::Sampled(&te), Route::Batch),
        (
            "samples of a run that ends at 0",
            &bil,
            settings(0.0, Method::Dopri5, 1e-8, None),
            Task::Sampled(&[0.0]),
            Route::Lanes,
        ),
        ("steady state", &bil, dp5, steady, Route::Lanes),
        ("events", &bil, dp5, Task::Events, Route::Lanes),
        ("DOP853", &bil, Settings { method: Method::Dop853, ..dp5 }, Task::Final, Route::Batch),
        ("Rodas4", &bil, Settings { method: Method::Rodas4, ..dp5 }, Task::Final, Route::Scalar),
        ("unilateral", &uni, dp5, Task::Final, Route::Lanes),
        ("switch law", &sw, dp5, Task::Final, Route::Lanes),
        ("mixed contact models", &mixed, dp5, Task::Final, Route::Scalar),
        ("no trajectory", &[], dp5, Task::Final, Route::Scalar),
        (
            "steady with Rodas4 in its options",
            &bil,
            dp5,
            Task::Steady {
                opts: &SteadyOptions { method: Method::Rodas4, ..opts },
                decay: None,
                known: None,
                restart: None,
            },
            Route::Scalar,
        ),
    ];
    for (name, s, set, task, want) in cases {
        assert_eq!(route(s, &set, &task), want, "{name}");
        // The scalar route takes everything; a route is only picked where it applies.
        assert!(supports(Route::Scalar, s, &set, &task), "{name}");
        assert!(supports(want, s, &set, &task), "{name}");
    }
}

#[test]
fn batch_groups_keep_the_threads_and_the_lanes_busy() {
    // About four groups per thread...
    assert_eq!(group_size(1000, Some(2)), 125);
    assert_eq!(group_size(1001, Some(2)), 126);
    // ...but never less than one set of the batch's lanes (16 with AVX-512, else 8), never more
    // than 1024 trajectories.
    let lanes = batch::lane_count();
    assert!(lanes == crate::ode::lanes::W || lanes == batch::W_AVX512);
    assert_eq!(group_size(10, Some(4)), lanes);
    assert_eq!(group_size(0, Some(4)), lanes);
    assert_eq!(group_size(16, Some(1)), lanes);
    assert_eq!(group_size(100, Some(2)), 13.max(lanes));
    assert_eq!(group_size(10_000_000, Some(1)), 1024);
    // Zero threads means one.
    assert_eq!(group_size(100, Some(0)), group_size(100, Some(1)));
}

/// Distance of each trajectory's `z(t_end)` from a tight DOP853 reference, relative to the
/// reference's largest `|z|`.
fn z_errors(s: &[Slider], y0: &[State], t_end: f64, r: &[TrajectoryResult]) -> Vec<f64> {
    (0..s.len())
        .map(|i| {
            let rf = steady::run(&s[i], &y0[i], t_end, Method::Dop853, &tol(1e-13));
            (r[i].run.y[0] - rf.y[0]).abs() / rf.extremes.max_abs_z
        })
        .collect()
}

/// The end state on every route that applies, against the scalar route: same status and end
/// time, an error from the tight reference of the scalar error's size (the lane and batch tests'
/// bound: the paths are the same method and differ by rounding per step, so 10 times the scalar
/// error plus 10 rtol covers the accumulated rounding), step counts within a few per cent.
#[test]
fn every_route_gives_the_scalar_drivers_end_state() {
    let mus = [0.19, 0.2, 0.205, 0.21, 0.215, 0.22, 0.23, 0.25, 0.27, 0.3];
    let scenes =
        [("seed", sliders(seed_bilateral(), &mus), 1e-6, 0.5), ("unilateral", sliders(unilateral(), &mus), 30e-6, 0.2)];
    for (name, s, z0, t_end) in scenes {
        let y0 = starts(s.len(), z0);
        for method in [Method::Dopri5, Method::Dop853] {
            for rtol in [1e-6, 1e-9] {
                let set = settings(t_end, method, rtol, Some(2));
                let scalar = unwrap(run_on(Route::Scalar, &s, &y0, &set, Task::Final));
                let e_s = z_errors(&s, &y0, t_end, &scalar);
                let mut checked = 0;
                for r in [Route::Batch, Route::Lanes] {
                    if !supports(r, &s, &set, &Task::Final) {
                        continue;
                    }
                    checked += 1;
                    let out = unwrap(run_on(r, &s, &y0, &set, Task::Final));
                    let e_r = z_errors(&s, &y0, t_end, &out);
                    for i in 0..s.len() {
                        let (a, b) = (&out[i].run, &scalar[i].run);
                        assert_eq!(a.status, b.status, "{name} {method:?} {r:?} #{i}");
                        assert_eq!(a.t, b.t, "{name} {method:?} {r:?} #{i}");
                        assert!(
                            e_r[i] <= 10.0 * e_s[i] + 10.0 * rtol,
                            "{name} {method:?} {r:?} rtol {rtol} #{i}: {:e} vs scalar {:e}",
                            e_r[i],
                            e_s[i]
                        );
                        let (na, nb) = (a.stats.n_accept + a.stats.n_reject, b.stats.n_accept + b.stats.n_reject);
                        assert!(
                            (na as f64 - nb as f64).abs() <= 0.05 * nb as f64 + 3.0,
                            "{name} {r:?} #{i}: {na} vs {nb} steps"
                        );
                    }
                }
                // The seed's bilateral ensemble has both lane routes, the others the lanes.
                let want = if name == "seed" { 2 } else { 1 };
                assert_eq!(checked, want, "{name} {method:?}");
            }
        }
    }
}

/// Samples and runs to steady state on the lane route against the scalar route (the lane tests'
/// bounds: samples within 10 times the scalar error from a tight reference plus 10 rtol of the
/// motion's size; the same outcome, and a periodic state's frequency to 1e-5 and amplitude to 1e-4
/// relative, the accuracy the cycle detection promises at rtol 1e-8).
#[test]
fn samples_and_steady_states_agree_across_routes() {
    let te: Vec<f64> = (0..=100).map(|k| k as f64 * 2e-3).collect();
    let s = sliders(unilateral(), &[0.2, 0.25, 0.3, 0.35]);
    let y0 = starts(s.len(), 30e-6);
    let rtol = 1e-8;
    let set = settings(0.2, Method::Dopri5, rtol, Some(2));
    let lanes = unwrap(run_on(Route::Lanes, &s, &y0, &set, Task::Sampled(&te)));
    let scalar = unwrap(run_on(Route::Scalar, &s, &y0, &set, Task::Sampled(&te)));
    for i in 0..s.len() {
        let (_, yr) = steady::run_sampled(&s[i], &y0[i], 0.2, Method::Dop853, &tol(1e-13), &te);
        let scale = yr.iter().map(|y| y[0].abs()).fold(0.0, f64::max);
        let worst = |v: &[State]| v.iter().zip(&yr).map(|(a, b)| (a[0] - b[0]).abs()).fold(0.0, f64::max);
        assert_eq!(lanes[i].samples.len(), te.len());
        let (wl, ws) = (worst(&lanes[i].samples), worst(&scalar[i].samples));
        assert!(wl <= 10.0 * ws + 10.0 * rtol * scale, "#{i}: {wl:e} vs {ws:e}");
    }

    let mut outcomes = Vec::new();
    for base in [seed_bilateral(), unilateral()] {
        let mus = [0.15, 0.18, 0.25, 0.30, 0.35];
        let s = sliders(base, &mus);
        let y0: Vec<State> =
            (0..mus.len()).map(|k| State::new(1e-6 * (1 + k) as f64, 0.0, 0.0, 0.0, 0.0, 0.0)).collect();
        let opts = SteadyOptions { t_max: 10.0, tol: tol(1e-8), ..SteadyOptions::default() };
        let task = Task::Steady { opts: &opts, decay: None, known: None, restart: None };
        let lanes = unwrap(run_on(Route::Lanes, &s, &y0, &set, task));
        let scalar = unwrap(run_on(Route::Scalar, &s, &y0, &set, task));
        for i in 0..s.len() {
            let (m, sc) =
                (*lanes[i].summary.as_deref().expect("steady"), *scalar[i].summary.as_deref().expect("steady"));
            assert_eq!(m.outcome, sc.outcome, "{:?} #{i}", base.contact);
            assert_eq!(m.status, sc.status, "{:?} #{i}", base.contact);
            if m.outcome == SteadyOutcome::Periodic {
                assert!((m.omega - sc.omega).abs() < 1e-5 * sc.omega, "{:?} #{i}", base.contact);
                assert!((m.z_amp[0] - sc.z_amp[0]).abs() < 1e-4 * sc.z_amp[0], "{:?} #{i}", base.contact);
            }
            outcomes.push(m.outcome);
        }
    }
    // The set covers every way a run ends (the scenes of the lane tests).
    for o in [SteadyOutcome::Decayed, SteadyOutcome::Periodic, SteadyOutcome::Diverged] {
        assert!(outcomes.contains(&o), "{o:?} missing: {outcomes:?}");
    }
}

/// On each route, every task gives bitwise the same results on 1, 2 and 3 threads (on the batch
/// route that also changes the grouping: 40 trajectories in groups of 10 or 8), and the entry
/// point gives bitwise what the path it routes to gives when called directly.
#[test]
fn results_are_bitwise_the_same_for_any_thread_count_and_through_the_entry_point() {
    let mus: Vec<f64> = (0..40).map(|k| 0.18 + 0.004 * k as f64).collect();
    let te: Vec<f64> = (0..=20).map(|k| k as f64 * 5e-3).collect();
    let opts = SteadyOptions { t_max: 0.3, tol: tol(1e-7), ..SteadyOptions::default() };
    let decay: Vec<DecayTest> = (0..40).map(|k| DecayTest::Amplitude(1e-8 * (1 + k % 3) as f64)).collect();
    let tasks = [
        Task::Final,
        Task::Sampled(&te),
        Task::Steady { opts: &opts, decay: Some(&decay), known: None, restart: None },
        Task::Events,
    ];
    for (base, z0) in [(seed_bilateral(), 1e-6), (unilateral(), 30e-6)] {
        let s = sliders(base, &mus);
        let y0 = starts(s.len(), z0);
        for task in tasks {
            for r in Route::ALL {
                let set = settings(0.1, Method::Dopri5, 1e-7, Some(1));
                if !supports(r, &s, &set, &task) {
                    continue;
                }
                let one: Vec<Vec<u64>> = unwrap(run_on(r, &s, &y0, &set, task)).iter().map(bits).collect();
                for th in [2, 3] {
                    let set = Settings { threads: Some(th), ..set };
                    let many: Vec<Vec<u64>> = unwrap(run_on(r, &s, &y0, &set, task)).iter().map(bits).collect();
                    assert!(one == many, "{:?} {task:?} {r:?}: {th} threads differ from 1", base.contact);
                }
                // The entry point adds nothing to the lane paths' arithmetic (the batch route's
                // grouping included).
                let direct: Option<Vec<Vec<u64>>> = match r {
                    Route::Batch => {
                        let t_eval: &[f64] = if let Task::Sampled(te) = task { te } else { &[] };
                        Some(
                            batch::run_bilateral_batch_sampled(&s, &y0, 0.1, Method::Dopri5, &set.tol, t_eval)
                                .into_iter()
                                .map(|(run, samples)| {
                                    bits(&TrajectoryResult { samples, ..TrajectoryResult::from_run(run) })
                                })
                                .collect(),
                        )
                    }
                    Route::Lanes => {
                        Some(lanes::run_lanes(&s, &y0, 0.1, Method::Dopri5, &set.tol, task).iter().map(bits).collect())
                    }
                    Route::Scalar => None,
                };
                if let Some(direct) = direct {
                    assert!(one == direct, "{:?} {task:?} {r:?}: the entry point differs from the path", base.contact);
                }
                if route(&s, &set, &task) == r {
                    let auto: Vec<Vec<u64>> = unwrap(run(&s, &y0, &set, task)).iter().map(bits).collect();
                    assert!(auto == one, "{:?} {task:?}: run differs from run_on({r:?})", base.contact);
                }
            }
        }
    }
}

#[test]
fn failed_results_carry_the_status_and_no_numbers() {
    let f = TrajectoryResult::failed(Status::Panic);
    assert_eq!(f.run.status, Status::Panic);
    assert!(f.run.t.is_nan() && f.run.y.iter().all(|v| v.is_nan()));
    assert_eq!(f.summary.as_deref().map(|s| (s.status, s.outcome)), Some((Status::Panic, SteadyOutcome::Failed)));
}

#[test]
fn failures_carry_the_same_reason_on_every_route() {
    use crate::status::Failure;
    // Past the bilateral law's saddle z blows up in finite time (t = 2.93 ms from 300 um at rest,
    // tests/test_detectors.py): with the escape limit lifted the step size collapses onto the
    // singularity (StepTooSmall); with the default 1 mm limit the escape is located (Diverged,
    // about 2.04 ms); a budget of 10 steps runs out first (MaxSteps).
    let blow = Params { escape_limit: 1e100, ..seed_bilateral() };
    let cases = [
        (blow, None, Status::StepTooSmall),
        (seed_bilateral(), None, Status::Diverged),
        (seed_bilateral(), Some(10), Status::MaxSteps),
    ];
    for (p, max_steps, want) in cases {
        let s = vec![Slider::new(p).unwrap()];
        let y0 = starts(1, 300e-6);
        let mut set = settings(1.0, Method::Dopri5, 1e-8, Some(1));
        set.tol.max_steps = max_steps;
        let mut seen = 0;
        for r in Route::ALL {
            if !supports(r, &s, &set, &Task::Final) {
                continue;
            }
            seen += 1;
            let run = unwrap(run_on(r, &s, &y0, &set, Task::Final))[0].run;
            assert_eq!(run.status, want, "{r:?}");
            let f = run.failure.unwrap_or_else(|| panic!("{r:?}: {want:?} without a reason"));
            assert_eq!(f.status(), want, "{r:?}: {f:?}");
            match f {
                Failure::StepTooSmall { t, h, floor, rtol } => {
                    assert!(t == run.t && h < floor && rtol == 1e-8, "{r:?}: {f:?}");
                    assert!(t > 2.90e-3 && t < 2.95e-3, "{r:?}: {f:?}");
                }
                Failure::Escaped { t, z, limit } => {
                    assert!(t == run.t && limit == 1e-3 && z.abs() >= limit * (1.0 - 1e-9), "{r:?}: {f:?}");
                }
                Failure::MaxSteps { max_steps, t, t_end } => {
                    assert!(max_steps == 10 && t_end == 1.0 && t == run.t, "{r:?}: {f:?}");
                    assert_eq!(run.stats.n_accept + run.stats.n_reject, 10);
                }
                other => panic!("{r:?}: unexpected {other:?}"),
            }
        }
        // The batch takes no step budget; the other two routes always apply.
        assert!(seen >= 2, "{want:?}: {seen} routes");
    }
}

#[test]
fn a_call_cancelled_before_it_starts_computes_nothing() {
    let s = sliders(seed_bilateral(), &[0.215; 20]);
    let y0 = starts(20, 1e-6);
    let so = SteadyOptions { t_max: 1.0, ..SteadyOptions::default() };
    let token = crate::cancel::Token::new();
    token.cancel();
    for threads in [Some(1), Some(2)] {
        let set = settings(1.0, Method::Dopri5, 1e-8, threads);
        for task in [Task::Final, Task::Steady { opts: &so, decay: None, known: None, restart: None }] {
            for r in Route::ALL {
                if !supports(r, &s, &set, &task) {
                    continue;
                }
                let out = token.scope(|| unwrap(run_on(r, &s, &y0, &set, task)));
                for o in &out {
                    assert_eq!(o.run.status, Status::NotComputed, "{r:?} {task:?}");
                    let f = o.run.failure.expect("a reason");
                    assert_eq!(f.status(), Status::NotComputed);
                    assert!(o.run.stats.n_accept + o.run.stats.n_reject <= crate::cancel::CHECK_EVERY);
                }
            }
        }
    }
}

/// `run_on(route)` with `token` cancelled from another thread after `after`.
fn cancelled_after(
    after: std::time::Duration,
    route: Route,
    s: &[Slider],
    y0: &[State],
    set: &Settings,
    task: Task<'_>,
) -> Vec<TrajectoryResult> {
    let token = crate::cancel::Token::new();
    std::thread::scope(|sc| {
        let t2 = token.clone();
        sc.spawn(move || {
            std::thread::sleep(after);
            t2.cancel();
        });
        token.scope(|| unwrap(run_on(route, s, y0, set, task)))
    })
}

#[test]
fn a_call_cancelled_while_it_runs_stops_and_keeps_what_finished() {
    // 20,000 trajectories of 1 s (about 10 s of work per route on one thread), cancelled after
    // 0.1 s: some finished, the rest are not computed; the finished ones are bitwise those of an
    // uncancelled call (the cancel checks change no numbers).
    let n = 20_000;
    for (base, r) in [(seed_bilateral(), Route::Batch), (unilateral(), Route::Lanes), (seed_bilateral(), Route::Scalar)]
    {
        let s = sliders(base, &vec![0.215; n]);
        let y0 = starts(n, 1e-6);
        let set = settings(1.0, Method::Dopri5, 1e-8, Some(1));
        let out = cancelled_after(std::time::Duration::from_millis(100), r, &s, &y0, &set, Task::Final);
        let done: Vec<usize> = (0..n).filter(|&i| out[i].run.status == Status::Success).collect();
        let stopped = out.iter().filter(|o| o.run.status == Status::NotComputed).count();
        assert_eq!(done.len() + stopped, n, "{r:?}: only finished and not-computed trajectories");
        assert!(stopped > 0, "{r:?}: the cancel was not seen");
        if let Some(&i) = done.first() {
            let alone = unwrap(run_on(r, &s[i..=i], &y0[i..=i], &set, Task::Final));
            assert_eq!(bits(&out[i]), bits(&alone[0]), "{r:?}: a finished trajectory changed");
        }
    }
}

#[test]
fn a_long_trajectory_is_cancelled_inside_its_run() {
    // The seed's unilateral bouncing cycle at mu = 0.3 never repeats to periodic_tol = 1e-15, so a
    // run to steady state would go on to t_max = 1e4 s (minutes): the cancel after 0.1 s ends it
    // partway, on the lanes and on the scalar driver.
    let s = sliders(unilateral(), &[0.30, 0.30]);
    let y0 = starts(2, 0.1e-6);
    let so = SteadyOptions { t_max: 1e4, periodic_tol: 1e-15, ..SteadyOptions::default() };
    let set = settings(1e4, Method::Dopri5, 1e-8, Some(1));
    for r in [Route::Lanes, Route::Scalar] {
        let task = Task::Steady { opts: &so, decay: None, known: None, restart: None };
        let out = cancelled_after(std::time::Duration::from_millis(100), r, &s, &y0, &set, task);
        let sum = *out[0].summary.as_deref().expect("a summary");
        assert_eq!(sum.status, Status::NotComputed, "{r:?}");
        match sum.failure {
            Some(crate::status::Failure::Cancelled { t }) => assert!(t > 0.0 && t < 1e4, "{r:?}: t = {t}"),
            other => panic!("{r:?}: {other:?}"),
        }
    }
}

/// `run_sampled_into` writes, row by row, bitwise the samples `run` returns (NaN where a run
/// stopped early), on each route it takes (the bilateral batch, the unilateral lanes, the scalar
/// driver for Rodas4) and on 1 or 3 threads; the results are the same but carry no samples.
#[test]
fn samples_written_into_a_buffer_are_those_the_results_carry() {
    let mus: Vec<f64> = (0..24).map(|k| 0.18 + 0.006 * k as f64).collect();
    let te: Vec<f64> = (0..=40).map(|k| k as f64 * 2.5e-3).collect();
    // Large starts on both models: some bilateral runs escape inside the span (NaN tails).
    let cases = [
        (seed_bilateral(), 300e-6, Method::Dopri5, Route::Batch),
        (seed_bilateral(), 300e-6, Method::Dop853, Route::Batch),
        (unilateral(), 30e-6, Method::Dop853, Route::Lanes),
        (unilateral(), 30e-6, Method::Rodas4, Route::Scalar),
    ];
    let mut nan_tails = 0;
    for (base, z0, m, want) in cases {
        let s = sliders(base, &mus);
        let y0 = starts(s.len(), z0);
        for th in [1, 3] {
            let set = settings(0.1, m, 1e-7, Some(th));
            assert_eq!(route(&s, &set, &Task::Sampled(&te)), want);
            let reference = unwrap(run(&s, &y0, &set, Task::Sampled(&te)));
            let mut flat = vec![0.0; s.len() * te.len() * 6];
            let res = unwrap(run_sampled_into(&s, &y0, &set, &te, &mut flat));
            for (i, (a, b)) in reference.iter().zip(&res).enumerate() {
                assert!(b.samples.is_empty(), "{want:?}: samples left in the result");
                let row: Vec<u64> =
                    flat[i * te.len() * 6..(i + 1) * te.len() * 6].iter().map(|x| x.to_bits()).collect();
                let want_row: Vec<u64> = a.samples.iter().flat_map(|y| y.iter().map(|x| x.to_bits())).collect();
                assert_eq!(row, want_row, "{want:?}, {th} threads: trajectory {i}'s samples");
                assert_eq!(bits(a), [bits(b), want_row].concat(), "{want:?}, {th} threads: trajectory {i}'s result");
                nan_tails += (a.samples.last().is_some_and(|y| y[0].is_nan())) as usize;
            }
        }
    }
    assert!(nan_tails > 0, "no run stopped early: the NaN tails are not tested");
}

/// A restart's `t_max` and `hold` per trajectory give, on the lanes and on the scalar driver,
/// bitwise what a call whose options carry them gives; a hold lets no cycle be declared before it.
#[test]
fn restarts_override_t_max_and_hold_per_trajectory() {
    let (s, y) = crate::shooting::tests::bouncing_cycle_start();
    let sliders = vec![s; 4];
    let y0 = vec![y; 4];
    let opts = SteadyOptions { t_max: 10.0, method: Method::Dop853, tol: tol(1e-9), ..SteadyOptions::default() };
    let rs = [(10.0, 0.0), (10.0, 0.5), (0.3, 1.0), (10.0, 2.0)].map(|(t_max, hold)| Restart { t_max, hold });
    let set = settings(0.0, Method::Dop853, 1e-9, Some(2));
    for route in [Route::Lanes, Route::Scalar] {
        let task = Task::Steady { opts: &opts, decay: None, known: None, restart: Some(&rs) };
        let got = unwrap(run_on(route, &sliders, &y0, &set, task));
        for (k, r) in rs.iter().enumerate() {
            let own = SteadyOptions { t_max: r.t_max, hold: r.hold, ..opts };
            let one = Task::Steady { opts: &own, decay: None, known: None, restart: None };
            let alone = unwrap(run_on(route, &sliders[..1], &y0[..1], &set, one));
            assert_eq!(bits(&got[k]), bits(&alone[0]), "{route:?} #{k}");
        }
        let m: Vec<Summary> = got.iter().map(|x| *x.summary.as_deref().expect("steady")).collect();
        // Started on the bouncing cycle: it repeats at once, unless held; t_max 0.3 s is enough.
        assert_eq!(m[0].outcome, SteadyOutcome::Periodic);
        assert!(m[0].t_end < 0.2, "{}", m[0].t_end);
        for k in [1, 3] {
            assert_eq!(m[k].outcome, SteadyOutcome::Periodic);
            assert!(m[k].t_end >= rs[k].hold && m[k].t_end < rs[k].hold + 0.1, "#{k}: {}", m[k].t_end);
            assert!((m[k].omega / m[0].omega - 1.0).abs() < 1e-6);
        }
        // Held past its own t_max: unsettled, at that t_max exactly (the other runs' is 10 s).
        assert_eq!(m[2].outcome, SteadyOutcome::Unsettled);
        assert_eq!(m[2].t_end, 0.3);
    }
}

/// A pin that meets the disk while the contact law is in tension (the twist term outweighs the
/// damping) does not land at the gap event; it lands a few microseconds later, where the law
/// turns compressive (`NORMAL`). At rtol 1e-6 one free-flight step is 2.4 ms long and the law
/// force's dip below zero (about 20 us) lies inside it, unseen at the step's ends and its interior
/// checks: before 2026-11-29 the pin fell on through the disk in free flight until `|z|` reached
/// the escape limit (`EventMissed`; one point of the Stribeck sweep at 103.3 N, 12.7 cm, 0.2 m/s).
/// The gap event changes nothing, but every function is read there, and the law's crossing
/// between it and the step's end is located. Every route, against a run at rtol 1e-12.
#[test]
fn a_pin_meeting_the_disk_in_tension_lands_where_the_law_turns_compressive() {
    use crate::model::{event, FrictionLaw};
    let p = Params {
        contact: ContactModel::Unilateral,
        friction_law: FrictionLaw::Switch,
        mu_static: 0.3,
        normal_load: 103.33333333333333,
        moment_arm: 0.065,
        omega_normal: 234.4899326505231,
        omega_friction: 192.31907889927868,
        omega_torsion: 487.1928411561178,
        sliding_speed: 0.2,
        ..Params::seed()
    };
    let s = vec![Slider::new(p).unwrap()];
    let y0 = vec![State::from([
        2.7447089544736738e-05,
        -0.026216725687439157,
        4.162653500135582e-05,
        0.01921713066954986,
        -0.0007180072792502996,
        3.6619434962791955,
    ])];
    let landing = |r: &TrajectoryResult| {
        let gap = r.events.iter().position(|&(i, _)| i == event::GAP).expect("the gap event");
        let (i, t) = r.events[gap + 1];
        assert_eq!(i, event::NORMAL, "{:?}", r.events);
        (r.events[gap].1, t)
    };
    let reference =
        unwrap(run_on(Route::Scalar, &s, &y0, &settings(0.003, Method::Dop853, 1e-12, Some(1)), Task::Events));
    let (t_gap, t_land) = landing(&reference[0]);
    assert!(t_land - t_gap > 1e-5 && t_land < 3e-4, "{t_gap:e} {t_land:e}");
    for rtol in [1e-6, 1e-8] {
        let set = settings(0.003, Method::Dop853, rtol, Some(1));
        for route in [Route::Scalar, Route::Lanes] {
            let r = unwrap(run_on(route, &s, &y0, &set, Task::Events));
            assert_eq!(r[0].run.status, crate::status::Status::Success, "{route:?} {rtol}");
            let (g, l) = landing(&r[0]);
            assert!((g - t_gap).abs() < 1e-8 && (l - t_land).abs() < 1e-8, "{route:?} {rtol}: {g:e} {l:e}");
            // In contact from there: pressed in by tens of micrometres, not falling through.
            assert!(r[0].run.y[0] > -1e-4, "{route:?} {rtol}: z = {:e}", r[0].run.y[0]);
        }
    }
}
