use crate::ode::test_systems::Level;
use crate::ode::{integrate, Method, NoObserver, OdeSystem, Options, MAX_EVENTS};
use nalgebra::SVector;

/// Harmonic oscillator x = cos t with the event x = 0.99: each peak pokes above the level for
/// 2 acos(0.99) = 0.283 s, shorter than the steps a loose tolerance takes (about 0.5 s) but
/// longer than the spacing of three interior checks: the situation of a short hop off the disk.
const PEAK: Level = Level { level: 0.99, stop: false };

#[test]
fn interior_checks_find_excursions_inside_one_step() {
    // Start at t = 0.1, above the level (cos 0.1 > 0.99): one crossing down at acos(0.99), then
    // the peaks at 2 pi k, k = 1..=5, each entered and left: 11 crossings in (0.1, 33).
    let y0 = SVector::<f64, 2>::new(0.1f64.cos(), -0.1f64.sin());
    for method in [Method::Dopri5, Method::Dop853] {
        let mut o = Options::<2>::new(1e-4, 1e-6);
        let ends_only = integrate(&PEAK, method, 0.1, y0, 33.0, &o, &mut NoObserver);
        // DOP853 steps about 1.3 s here: 7 checks space 0.16 s, inside the 0.28 s excursion.
        o.interior_checks = 7;
        let inside = integrate(&PEAK, method, 0.1, y0, 33.0, &o, &mut NoObserver);
        assert_eq!(inside.stats.n_events, 11, "{method:?}: {:?}", inside.stats);
        // Without the interior checks the loose steps jump over some of the excursions.
        assert!(ends_only.stats.n_events < 11, "{method:?}: the test does not exercise hidden crossings");
    }
}

/// `PEAK` with a counter of its right-hand-side calls.
struct Counted(std::cell::Cell<u64>);
impl OdeSystem<2> for Counted {
    type Mode = ();
    fn rhs(&self, t: f64, y: &SVector<f64, 2>, m: ()) -> SVector<f64, 2> {
        self.0.set(self.0.get() + 1);
        PEAK.rhs(t, y, m)
    }
    // Analytic, as the slider's (a finite-difference Jacobian is one n_jac, not n_rhs).
    fn jacobian(&self, _t: f64, _y: &SVector<f64, 2>, _m: ()) -> nalgebra::SMatrix<f64, 2, 2> {
        nalgebra::SMatrix::<f64, 2, 2>::new(0.0, 1.0, -1.0, 0.0)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, t: f64, y: &SVector<f64, 2>, m: (), g: &mut [f64; MAX_EVENTS]) {
        PEAK.events(t, y, m, g)
    }
}

#[test]
fn n_rhs_counts_every_evaluation_with_events_and_interior_checks() {
    // The reported cost is the true one: rejected steps, the steps redone after a hidden
    // crossing, event location and DOP853's extra dense-output stages included.
    let y0 = SVector::<f64, 2>::new(0.1f64.cos(), -0.1f64.sin());
    for method in [Method::Dopri5, Method::Dop853, Method::Rodas4] {
        for checks in [0, 7] {
            let mut o = Options::<2>::new(1e-4, 1e-6);
            o.interior_checks = checks;
            let sys = Counted(std::cell::Cell::new(0));
            let sol = integrate(&sys, method, 0.1, y0, 33.0, &o, &mut NoObserver);
            assert!(sol.stats.n_events > 0);
            assert_eq!(sol.stats.n_rhs, sys.0.get(), "{method:?}, {checks} checks: {:?}", sol.stats);
        }
    }
}

/// `PEAK` with the exact rate of its event function, `d(x - level)/dt = x'`.
struct WithRates;
impl OdeSystem<2> for WithRates {
    type Mode = ();
    fn rhs(&self, t: f64, y: &SVector<f64, 2>, m: ()) -> SVector<f64, 2> {
        PEAK.rhs(t, y, m)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, t: f64, y: &SVector<f64, 2>, m: (), g: &mut [f64; MAX_EVENTS]) {
        PEAK.events(t, y, m, g)
    }
    fn event_rates(
        &self,
        _t: f64,
        _y: &SVector<f64, 2>,
        f: &SVector<f64, 2>,
        _m: (),
        d: &mut [f64; MAX_EVENTS],
    ) -> bool {
        d[0] = f[0];
        true
    }
}

#[test]
fn turning_points_find_excursions_that_evenly_spaced_checks_miss() {
    // The loose steps jump over some of the 0.28 s excursions; the turning point of g's cubic
    // model (from g and its rate at both step ends) lands on each peak; one midpoint check does not.
    let y0 = SVector::<f64, 2>::new(0.1f64.cos(), -0.1f64.sin());
    for method in [Method::Dopri5, Method::Dop853] {
        let mut o = Options::<2>::new(1e-4, 1e-6);
        o.interior_checks = 1;
        let without = integrate(&PEAK, method, 0.1, y0, 33.0, &o, &mut NoObserver);
        let with = integrate(&WithRates, method, 0.1, y0, 33.0, &o, &mut NoObserver);
        // DP5's shorter steps put the midpoint inside every excursion; DOP853's do not.
        let missed = without.stats.n_events < 11;
        assert!(
            missed || method == Method::Dopri5,
            "{method:?}: the test does not exercise hidden crossings: {:?}",
            without.stats
        );
        assert_eq!(with.stats.n_events, 11, "{method:?}: {:?}", with.stats);
    }
}

#[test]
fn turning_point_of_a_parabola_is_its_vertex() {
    // g(t) = -1 + 4 (t - 0.3)^2 ... a parabola through g(0) = -0.64, peaking at t = 0.7 below zero:
    // g = -(t - 0.7)^2 - 0.01 on [0, 1] (h = 1): g0 = -0.5, g1 = -0.1, d0 = 1.4, d1 = -0.6.
    let (x, p) = super::super::events::turn_point(-0.5, -0.1, 1.4, -0.6, 1.0).unwrap();
    assert!((x - 0.7).abs() < 1e-9, "{x}");
    assert!((p + 0.01).abs() < 1e-9, "{p}"); // the vertex's value
                                             // The same on a step of 2 s: x is the fraction of the step.
    let (x, _) = super::super::events::turn_point(-0.5, -0.1, 0.7, -0.3, 2.0).unwrap();
    assert!((x - 0.7).abs() < 1e-9, "{x}");
    // Heading away at the start, or a sign change at the ends: none.
    assert!(super::super::events::turn_point(-0.5, -0.1, -1.0, -0.6, 1.0).is_none());
    assert!(super::super::events::turn_point(-0.5, 0.1, 1.4, 0.6, 1.0).is_none());
}

#[test]
fn turning_point_of_a_cubic_is_the_root_of_its_slope() {
    use super::super::events::{turn_point, turn_x};
    // p(x) = -0.5 x^3 - 0.6 x^2 + x - 0.5 on a step of 1 s: heads up towards zero at the start
    // (p'(0) = 1), away from it at the end (p(1) = -0.6, p'(1) = -1.7), and turns below zero where
    // p'(x) = -1.5 x^2 - 1.2 x + 1 = 0 (the quadratic branch: a is not negligible).
    let want = (-1.2 + 7.44f64.sqrt()) / 3.0;
    let p = |x: f64| ((-0.5 * x - 0.6) * x + 1.0) * x - 0.5;
    let (x, px) = turn_point(-0.5, -0.6, 1.0, -1.7, 1.0).unwrap();
    assert!((x - want).abs() < 1e-14, "{x} against {want}");
    assert!((px - p(want)).abs() < 1e-14 && px < 0.0, "{px}");
    // The same on a step of 0.25 s (rates 4x): x is the fraction of the step.
    let (x, _) = turn_point(-0.5, -0.6, 4.0, -6.8, 0.25).unwrap();
    assert!((x - want).abs() < 1e-14, "{x}");
    // The branch-free x is NaN exactly where turn_point gives none: heading away at the start, a
    // sign change, a non-finite input.
    for (g0, g1, d0, d1) in
        [(-0.5, -0.6, -1.0, -1.7), (-0.5, 0.6, 1.0, 1.7), (f64::NAN, -0.6, 1.0, -1.7), (-0.5, -0.6, 1.0, f64::NAN)]
    {
        assert!(turn_x(g0, g1, d0, d1, 1.0).is_nan() && turn_point(g0, g1, d0, d1, 1.0).is_none());
    }
    assert_eq!(
        turn_x(-0.5, -0.6, 1.0, -1.7, 1.0).to_bits(),
        turn_point(-0.5, -0.6, 1.0, -1.7, 1.0).unwrap().0.to_bits()
    );
}
