use super::*;
use crate::ode::events::{hermite_root, locate, locate_from};
use crate::ode::test_systems::*;
use crate::ode::{NoObserver, Sampler};
use std::f64::consts::PI;

/// Records events and counts steps; stops after `stop_after` steps if set.
#[derive(Default)]
struct Rec<M> {
    events: Vec<(usize, f64, M, M)>,
    steps: u64,
    stop_after: Option<u64>,
    last_t1: f64,
    contiguous: bool,
}
impl<const N: usize, M: Copy> Observer<N, M> for Rec<M> {
    fn on_step(&mut self, s: &StepView<'_, N, M>) -> Control {
        // Steps must tile the time axis: each starts where the previous one ended.
        if self.steps > 0 && s.t0 != self.last_t1 {
            self.contiguous = false;
        }
        self.last_t1 = s.t1;
        self.steps += 1;
        if self.stop_after == Some(self.steps) {
            Control::Stop
        } else {
            Control::Continue
        }
    }
    fn on_event(&mut self, i: usize, t: f64, _y: &SVector<f64, N>, before: M, after: M) -> Control {
        self.events.push((i, t, before, after));
        Control::Continue
    }
}
fn rec<M>() -> Rec<M> {
    Rec { events: vec![], steps: 0, stop_after: None, last_t1: 0.0, contiguous: true }
}

#[test]
fn damped_oscillator_matches_analytic_solution() {
    let sys = Damped { w: 2.0 * PI, zeta: 0.05 };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    for m in Method::ALL {
        let opts = Options::<2>::new(1e-10, 1e-14);
        let sol = integrate(&sys, m, 0.0, y0, 5.0, &opts, &mut NoObserver);
        assert_eq!(sol.outcome, Outcome::Finished, "{m:?}");
        assert_eq!(sol.t, 5.0, "{m:?}: must land exactly on t_end");
        let err = (sol.y - sys.exact(5.0)).amax();
        // Rodas4 (order 4, error per unit step, not tolerance-proportional) is held to 1e-7.
        let tol = if m == Method::Rodas4 { 1e-7 } else { 1e-8 };
        println!("{m:?}: err {err:.2e}, {:?}", sol.stats);
        assert!(err < tol, "{m:?}: error {err:e}");
        assert!(sol.stats.n_accept > 10);
    }
}

#[test]
fn tolerance_proportionality() {
    // Tighter tolerance gives smaller error and more steps (the controller is alive).
    let sys = Damped { w: 2.0 * PI, zeta: 0.05 };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    for m in Method::ALL {
        let run = |rtol: f64| integrate(&sys, m, 0.0, y0, 5.0, &Options::<2>::new(rtol, rtol * 1e-3), &mut NoObserver);
        let (a, b) = (run(1e-5), run(1e-9));
        let (ea, eb) = ((a.y - sys.exact(5.0)).amax(), (b.y - sys.exact(5.0)).amax());
        assert!(eb < ea * 1e-2, "{m:?}: {ea:e} -> {eb:e}");
        assert!(b.stats.n_accept > a.stats.n_accept, "{m:?}");
    }
}

#[test]
fn sampler_sees_dense_output() {
    // Dense output through the public observer, all methods: samples match the exact solution.
    let sys = Damped { w: 2.0 * PI, zeta: 0.05 };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    let ts: Vec<f64> = (0..=100).map(|k| k as f64 * 0.03).collect();
    for m in Method::ALL {
        let mut s = Sampler::new(&ts);
        let sol = integrate(&sys, m, 0.0, y0, 3.0, &Options::<2>::new(1e-10, 1e-14), &mut s);
        assert_eq!(sol.outcome, Outcome::Finished);
        assert_eq!(s.out.len(), ts.len());
        let worst = ts.iter().zip(&s.out).map(|(&t, y)| (y - sys.exact(t)).amax()).fold(0.0, f64::max);
        let tol = if m == Method::Rodas4 { 1e-6 } else { 1e-8 };
        assert!(worst < tol, "{m:?}: dense error {worst:e}");
    }
}

#[test]
fn level_crossings_located_to_1e_10() {
    // x = cos t crosses 0.3 at acos(0.3) + 2 pi k and 2 pi - acos(0.3) + 2 pi k.
    let sys = Level { level: 0.3, stop: false };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    let a = 0.3f64.acos();
    let mut want = vec![];
    for k in 0..3 {
        want.push(a + 2.0 * PI * k as f64);
        want.push(2.0 * PI - a + 2.0 * PI * k as f64);
    }
    for m in Method::ALL {
        let mut r = rec();
        let rtol = if m == Method::Rodas4 { 1e-13 } else { 1e-12 };
        let sol = integrate(&sys, m, 0.0, y0, 6.0 * PI, &Options::<2>::new(rtol, 1e-15), &mut r);
        assert_eq!(sol.outcome, Outcome::Finished);
        assert_eq!(r.events.len(), want.len(), "{m:?}: {:?}", r.events);
        assert_eq!(sol.stats.n_events, want.len() as u64);
        for (e, w) in r.events.iter().zip(&want) {
            assert!((e.1 - w).abs() < 1e-10, "{m:?}: event at {} want {w} ({:e})", e.1, e.1 - w);
        }
        assert!(r.contiguous, "{m:?}: a Continue event must not truncate steps");
    }
}

#[test]
fn stop_event_ends_the_run_at_the_crossing() {
    let sys = Level { level: 0.3, stop: true };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    for m in Method::ALL {
        let mut r = rec();
        let sol = integrate(&sys, m, 0.0, y0, 10.0, &Options::<2>::new(1e-12, 1e-15), &mut r);
        assert_eq!(sol.outcome, Outcome::StoppedByEvent, "{m:?}");
        assert!((sol.t - 0.3f64.acos()).abs() < 1e-10, "{m:?}: {}", sol.t);
        assert!((sol.y[0] - 0.3).abs() < 1e-10);
        // The observer saw the truncated step, then the event.
        assert_eq!(r.last_t1, sol.t);
        assert_eq!(r.events.len(), 1);
        assert_eq!(sol.stats.n_events, 1);
    }
}

#[test]
fn bouncing_ball_switches_track_the_exact_solution() {
    let sys = Ball { g: 9.81, k: 1e4 };
    let h0 = 1.0;
    let (tf, _, tc) = sys.phases(h0);
    let period = 2.0 * tf + tc;
    // Three full bounces and a bit: ends in the air on the way up.
    let t_end = tf + 3.0 * period + 0.5 * tc + 0.1;
    let y0 = SVector::<f64, 2>::new(h0, 0.0);
    for m in Method::ALL {
        let mut r = rec();
        let sol = integrate(&sys, m, 0.0, y0, t_end, &Options::<2>::new(1e-12, 1e-14), &mut r);
        assert_eq!(sol.outcome, Outcome::Finished, "{m:?}");
        // Impacts at tf + j period, lift-offs tf + tc + j period; j = 0..3 (8 switches + last impact).
        let mut want = vec![];
        for j in 0..4 {
            want.push((tf + j as f64 * period, BallMode::Air, BallMode::Floor));
            want.push((tf + tc + j as f64 * period, BallMode::Floor, BallMode::Air));
        }
        want.retain(|w| w.0 < t_end);
        assert_eq!(r.events.len(), want.len(), "{m:?}: {:?}", r.events);
        for (e, w) in r.events.iter().zip(&want) {
            assert_eq!((e.2, e.3), (w.1, w.2), "{m:?}");
            assert!((e.1 - w.0).abs() < 1e-10, "{m:?}: switch at {} want {} ({:e})", e.1, w.0, e.1 - w.0);
        }
        let ex = sys.exact(h0, t_end);
        let err = (sol.y - ex).amax() / (2.0 * 9.81 * h0).sqrt();
        println!("{m:?}: state error {err:.2e} (rel. to impact speed), {:?}", sol.stats);
        assert!(err < 1e-8, "{m:?}: {} vs {}", sol.y, ex);
        assert_eq!(sol.mode, BallMode::Air);
    }
}

#[test]
fn observer_stop_and_max_steps() {
    let sys = Damped { w: 2.0 * PI, zeta: 0.05 };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    for m in Method::ALL {
        let mut r = rec();
        r.stop_after = Some(5);
        let sol = integrate(&sys, m, 0.0, y0, 5.0, &Options::<2>::new(1e-8, 1e-12), &mut r);
        assert_eq!(sol.outcome, Outcome::StoppedByObserver);
        assert_eq!(sol.stats.n_accept, 5);
        assert_eq!(sol.t, r.last_t1);
        assert!(sol.t < 5.0);

        let mut opts = Options::<2>::new(1e-10, 1e-14);
        opts.max_steps = 10;
        let sol = integrate(&sys, m, 0.0, y0, 5.0, &opts, &mut NoObserver);
        assert_eq!(sol.outcome, Outcome::MaxSteps);
        assert_eq!(sol.stats.n_accept + sol.stats.n_reject, 10);
    }
}

#[test]
fn h_max_and_h0_are_respected() {
    struct MaxStep(f64);
    impl<const N: usize> Observer<N, ()> for MaxStep {
        fn on_step(&mut self, s: &StepView<'_, N, ()>) -> Control {
            self.0 = self.0.max(s.t1 - s.t0);
            Control::Continue
        }
    }
    let sys = Damped { w: 1.0, zeta: 0.0 };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    for m in Method::ALL {
        let mut opts = Options::<2>::new(1e-6, 1e-9);
        opts.h_max = 0.01;
        opts.h0 = 1e-3;
        let mut o = MaxStep(0.0);
        let sol = integrate(&sys, m, 0.0, y0, 1.0, &opts, &mut o);
        assert_eq!(sol.outcome, Outcome::Finished);
        assert!(o.0 <= 0.01 * (1.0 + 1e-12), "{m:?}: {}", o.0);
        assert!(sol.stats.n_accept >= 100);
    }
}

#[test]
fn blow_up_is_never_finished() {
    let y0 = SVector::<f64, 1>::new(1.0);
    for m in Method::ALL {
        let sol = integrate(&BlowUp, m, 0.0, y0, 2.0, &Options::<1>::new(1e-8, 1e-10), &mut NoObserver);
        println!("{m:?}: {:?} at t = {} y = {:e}, {:?}", sol.outcome, sol.t, sol.y[0], sol.stats);
        assert!(matches!(sol.outcome, Outcome::NonFinite | Outcome::StepTooSmall), "{m:?}: {:?}", sol.outcome);
        // The blow-up time itself carries the integration error (about rtol).
        assert!((sol.t - 1.0).abs() < 1e-6, "{m:?}: stopped at {}", sol.t);
        assert!(sol.y[0].is_finite());
    }
    // A derivative that is NaN at once: NonFinite, not a panic.
    struct Nan;
    impl OdeSystem<1> for Nan {
        type Mode = ();
        fn rhs(&self, _t: f64, y: &SVector<f64, 1>, _m: ()) -> SVector<f64, 1> {
            SVector::<f64, 1>::new(if y[0] > 1.5 { f64::NAN } else { 1.0 })
        }
        fn initial_mode(&self, _t: f64, _y: &SVector<f64, 1>) {}
    }
    for m in Method::ALL {
        let sol = integrate(&Nan, m, 0.0, y0, 2.0, &Options::<1>::new(1e-8, 1e-10), &mut NoObserver);
        assert!(matches!(sol.outcome, Outcome::NonFinite | Outcome::StepTooSmall), "{m:?}: {:?}", sol.outcome);
        assert!(sol.y[0].is_finite() && sol.t <= 0.5 + 1e-9, "{m:?}: {} {}", sol.t, sol.y[0]);
    }
}

#[test]
fn stiff_problems_need_rodas() {
    // Prothero-Robinson with lambda = 1e6 on [0, 2]: Dopri5 is held to its stability limit
    // (h ~ 3.3 / lambda), Rodas4 follows the smooth solution.
    // Measured (release): Rodas4 8 steps (66 right-hand sides, 8 LU);
    // Dopri5 604 852 accepted steps (3.6e6 right-hand sides).
    let sys = Prothero { lambda: 1e6 };
    let y0 = SVector::<f64, 1>::new(1.0);
    let opts = Options::<1>::new(1e-6, 1e-9);
    let r = integrate(&sys, Method::Rodas4, 0.0, y0, 2.0, &opts, &mut NoObserver);
    let d = integrate(&sys, Method::Dopri5, 0.0, y0, 2.0, &opts, &mut NoObserver);
    println!("Prothero-Robinson: Rodas4 {:?}\n                   Dopri5 {:?}", r.stats, d.stats);
    assert_eq!(r.outcome, Outcome::Finished);
    assert_eq!(d.outcome, Outcome::Finished);
    assert!((r.y[0] - 2f64.cos()).abs() < 1e-6);
    assert!(r.stats.n_accept + r.stats.n_reject < 500);
    assert!(d.stats.n_accept > 100 * (r.stats.n_accept + r.stats.n_reject));

    // Van der Pol, mu = 1e3 (Hairer's scaled form, eps = 1e-6) on [0, 2]: two fast jumps.
    let v = VanDerPol { eps: 1e-6 };
    let y0 = SVector::<f64, 2>::new(2.0, -0.66);
    let opts = Options::<2>::new(1e-6, 1e-6);
    let r = integrate(&v, Method::Rodas4, 0.0, y0, 2.0, &opts, &mut NoObserver);
    println!("Van der Pol eps=1e-6, t in [0,2]: Rodas4 {:?}", r.stats);
    assert_eq!(r.outcome, Outcome::Finished);
    // Measured: 1039 accepted + 18 rejected (SciPy's Radau at the same tolerances: 860 steps).
    assert!(r.stats.n_accept + r.stats.n_reject < 1500);
    // Hairer's reference value (Solving ODEs II, IV.10): y1(2) = 1.7061677321...
    assert!((r.y[0] - 1.706_167_732_170_469).abs() < 1e-4, "{}", r.y[0]);
}

#[test]
fn non_autonomous_rodas_matches_dop853() {
    // The forced Duffing oscillator exercises Rodas4's df/dt term.
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    let reference =
        integrate(&DUFFING, Method::Dop853, 0.0, y0, 10.0, &Options::<2>::new(1e-13, 1e-15), &mut NoObserver);
    for m in Method::ALL {
        let sol = integrate(&DUFFING, m, 0.0, y0, 10.0, &Options::<2>::new(1e-10, 1e-12), &mut NoObserver);
        let err = (sol.y - reference.y).amax();
        assert!(err < 1e-7, "{m:?}: {err:e}");
    }
}

#[test]
fn the_root_finder_brackets_roots_in_few_evaluations() {
    // (g, [a, b], root, most evaluations; Illinois took 14, 32, 20 and 13): a cubic across a wide
    // bracket, a root next to the left end of a strongly curved function (the slider's lift-off
    // just after a touchdown looks like this), one next to the right end, and a nearly linear one
    // (most contact events).
    type Case = (fn(f64) -> f64, f64, f64, f64, usize);
    let cases: [Case; 4] = [
        (|t| t * t * t - 0.5, 0.0, 2.0, 0.5f64.cbrt(), 12),
        (|t| (t - 1e-6) * (1.0 + 1e4 * t), 0.0, 1e-3, 1e-6, 7),
        (|t| (t - 0.999) * (3.0 - t * t), 0.0, 1.0, 0.999, 6),
        (|t| 2.0 * (t - 0.3) + 0.1 * (t - 0.3) * (t - 0.3), 0.0, 1.0, 0.3, 5),
    ];
    for (k, (g, a, b, root, most)) in cases.into_iter().enumerate() {
        for tol in [1e-9, 1e-14] {
            let mut calls = 0;
            let t = locate(
                |t| {
                    calls += 1;
                    g(t)
                },
                a,
                g(a),
                b,
                g(b),
                tol,
            );
            // On the far side of the root, within tol of it (to rounding of g near the root).
            assert!(t >= root - 1e-15 && t - root <= tol + 1e-15, "case {k}, tol {tol:e}: {t} against {root}");
            assert!(g(t).signum() == g(b).signum() || g(t) == 0.0, "case {k}: the near side");
            assert!(calls <= most, "case {k}, tol {tol:e}: {calls} evaluations (at most {most})");
        }
    }
    // Exactly zero at the end: the end.
    assert_eq!(locate(|t| t - 1.0, 0.0, -1.0, 1.0, 0.0, 1e-12), 1.0);
}

#[test]
fn the_cubic_model_root_is_exact_for_a_cubic_and_close_for_a_smooth_function() {
    // A cubic is its own Hermite model: the root to rounding, and the slope there.
    let g = |t: f64| (t - 0.3) * (t * t + 1.0);
    let dg = |t: f64| 3.0 * t * t - 0.6 * t + 1.0;
    let (t, s) = hermite_root(0.0, 1.0, g(0.0), g(1.0), dg(0.0), dg(1.0)).expect("a root");
    assert!((t - 0.3).abs() < 1e-15, "{t}");
    assert!((s - dg(0.3)).abs() < 1e-14, "{s}");
    // On a step and away from zero: sin over a tenth of its period, error of order h^4.
    let (t0, h) = (3.0, 0.3);
    let (t, s) = hermite_root(t0, h, t0.sin(), (t0 + h).sin(), t0.cos(), (t0 + h).cos()).expect("a root");
    assert!((t - std::f64::consts::PI).abs() < 1e-5 * h, "{t}");
    assert!((s + 1.0).abs() < 1e-3, "{s}");
    // No model from non-finite input or a start on the root.
    assert!(hermite_root(0.0, 1.0, 1.0, -1.0, f64::NAN, 0.0).is_none());
    assert!(hermite_root(0.0, 1.0, 0.0, -1.0, 1.0, 1.0).is_none());
}

#[test]
fn the_root_finder_started_from_the_cubic_model_keeps_its_contract_in_fewer_evaluations() {
    // (g, g', [a, b], root): a nearly linear function, a strongly curved one, sin across a root.
    type Case = (fn(f64) -> f64, fn(f64) -> f64, f64, f64, f64);
    let cases: [Case; 3] = [
        (|t| 2.0 * (t - 0.3) + 0.1 * (t - 0.3) * (t - 0.3), |t| 2.0 + 0.2 * (t - 0.3), 0.0, 1.0, 0.3),
        (|t| (t - 0.999) * (3.0 - t * t), |t| 3.0 - 3.0 * t * t + 1.998 * t, 0.0, 1.0, 0.999),
        (f64::sin, f64::cos, 3.0, 3.3, std::f64::consts::PI),
    ];
    for (k, (g, dg, a, b, root)) in cases.into_iter().enumerate() {
        for tol in [1e-9, 1e-14] {
            let run = |guess: Option<(f64, f64)>| {
                let mut calls = 0;
                let counted = |t| {
                    calls += 1;
                    g(t)
                };
                let t = locate_from(counted, a, g(a), b, g(b), tol, guess);
                assert!(t >= root - 1e-15 && t - root <= tol + 1e-15, "case {k}, tol {tol:e}: {t} against {root}");
                assert!(g(t).signum() == g(b).signum() || g(t) == 0.0, "case {k}: the near side");
                (t, calls)
            };
            let (_, plain) = run(None);
            let guess = hermite_root(a, b - a, g(a), g(b), dg(a), dg(b));
            let (_, guided) = run(guess);
            assert!(guided <= 4 && guided <= plain, "case {k}, tol {tol:e}: {guided} evaluations against {plain}");
            // A useless guess (an end, a wrong or missing slope) costs evaluations, not the contract.
            for bad in [Some((a, 1.0)), Some((b, -1e300)), Some((0.5 * (a + b), f64::NAN)), Some((f64::NAN, 1.0))] {
                let (_, n) = run(bad);
                assert!(n <= plain + 2, "case {k}, tol {tol:e}, guess {bad:?}: {n} evaluations against {plain}");
            }
        }
    }
}

#[test]
fn restart_on_a_root_does_not_refire() {
    // Starting exactly on g = 0 (x = level) must not report an event at t0; the next real
    // crossing is reported once.
    let sys = Level { level: 1.0, stop: false };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0); // x = cos t touches 1 at t = 0, 2 pi, ...
    let mut r = rec();
    let sol = integrate(&sys, Method::Dopri5, 0.0, y0, 1.0, &Options::<2>::new(1e-10, 1e-13), &mut r);
    assert_eq!(sol.outcome, Outcome::Finished);
    assert!(r.events.is_empty(), "{:?}", r.events);
}

#[test]
fn event_chatter_is_reported() {
    let sys = Level { level: 0.3, stop: false };
    let y0 = SVector::<f64, 2>::new(1.0, 0.0);
    let mut opts = Options::<2>::new(1e-8, 1e-12);
    opts.max_events = 3;
    let sol = integrate(&sys, Method::Dopri5, 0.0, y0, 20.0, &opts, &mut NoObserver);
    assert_eq!(sol.outcome, Outcome::EventChatter);
    assert_eq!(sol.stats.n_events, 4);
}
