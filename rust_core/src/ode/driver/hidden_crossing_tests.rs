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
