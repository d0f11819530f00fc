//! The scalar integrators on the real slider (MODEL.md §2): the three methods agree through the
//! contact switches. An integration test: it crosses the layers (`ode` is generic and knows nothing
//! of the slider), through the public API only.

use tribosweep_core::model::{ContactMode, ContactModel, Params, Slider, State};
use tribosweep_core::ode::{
    integrate, Control, Method, NoObserver, Observer, OdeSystem, Options, Outcome, StepView, MAX_EVENTS,
};

/// Largest |z| at step ends and the number of events by index.
#[derive(Default)]
struct Watch {
    z_max: f64,
    events: [u64; MAX_EVENTS],
    switches: u64,
}
impl Observer<6, ContactMode> for Watch {
    fn on_step(&mut self, s: &StepView<'_, 6, ContactMode>) -> Control {
        self.z_max = self.z_max.max(s.y1[0].abs());
        Control::Continue
    }
    fn on_event(&mut self, i: usize, _t: f64, _y: &State, before: ContactMode, after: ContactMode) -> Control {
        self.events[i] += 1;
        if before != after {
            self.switches += 1;
        }
        Control::Continue
    }
}

#[test]
fn seed_bilateral_methods_agree() {
    let s = Slider::seed();
    let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut w = Watch::default();
    let reference = integrate(&s, Method::Dop853, 0.0, y0, 0.5, &Options::<6>::new(1e-13, 1e-18), &mut w);
    assert_eq!(reference.outcome, Outcome::Finished);
    println!("reference Dop853 rtol 1e-13: {:?}, max|z| = {:.3e}", reference.stats, w.z_max);
    for m in Method::ALL {
        let sol = integrate(&s, m, 0.0, y0, 0.5, &Options::<6>::new(1e-10, 1e-16), &mut NoObserver);
        assert_eq!(sol.outcome, Outcome::Finished, "{m:?}");
        let dz = (sol.y[0] - reference.y[0]).abs() / w.z_max;
        println!("{m:?} rtol 1e-10: |dz|/max|z| = {dz:.2e}, {:?}", sol.stats);
        assert!(dz < 1e-7, "{m:?}: {dz:e}");
        // All components, each on its own scale along the reference.
        let rel = (sol.y - reference.y).component_div(&reference.y.map(|v| v.abs().max(1e-300))).amax();
        assert!(rel < 1e-5, "{m:?}: componentwise {rel:e}");
    }
}

#[test]
fn unilateral_growth_runs_without_chatter() {
    let s = Slider::new(Params { contact: ContactModel::Unilateral, mu: 0.30, ..Params::seed() }).unwrap();
    let y0 = State::new(0.1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    for m in Method::ALL {
        let mut w = Watch::default();
        let sol = integrate(&s, m, 0.0, y0, 2.0, &Options::<6>::new(1e-8, 1e-14), &mut w);
        println!(
            "{m:?} unilateral mu=0.30, 2 s: {:?} at t={} z_max={:.3e} events {:?} switches {} {:?}",
            sol.outcome, sol.t, w.z_max, w.events, w.switches, sol.stats
        );
        assert!(matches!(sol.outcome, Outcome::Finished | Outcome::StoppedByEvent), "{m:?}: {:?}", sol.outcome);
        assert!(sol.stats.n_accept < 200_000, "{m:?}: {:?}", sol.stats);
    }
}

#[test]
fn unilateral_bouncing_methods_agree() {
    // Start off the disk (z = 30 um > |z_st| = 16.6 um): the pin flies, lands, and the contact
    // opens and closes repeatedly; the three methods must agree through the switches.
    let s = Slider::new(Params { contact: ContactModel::Unilateral, ..Params::seed() }).unwrap();
    let y0 = State::new(30e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut w = Watch::default();
    let reference = integrate(&s, Method::Dop853, 0.0, y0, 0.1, &Options::<6>::new(1e-13, 1e-18), &mut w);
    println!("reference: {:?} switches {} events {:?} {:?}", reference.outcome, w.switches, w.events, reference.stats);
    assert_eq!(reference.outcome, Outcome::Finished);
    assert!(w.switches >= 4, "the contact should open and close: {}", w.switches);
    for m in Method::ALL {
        let mut wm = Watch::default();
        let sol = integrate(&s, m, 0.0, y0, 0.1, &Options::<6>::new(1e-10, 1e-16), &mut wm);
        let dz = (sol.y[0] - reference.y[0]).abs() / w.z_max;
        println!("{m:?}: {:?} switches {} |dz|/max|z| = {dz:.2e} {:?}", sol.outcome, wm.switches, sol.stats);
        assert_eq!(sol.outcome, Outcome::Finished, "{m:?}");
        assert_eq!(wm.switches, w.switches, "{m:?}");
        assert!(dz < 1e-6, "{m:?}: {dz:e}");
    }
}

/// MODEL.md §6: at mu = 0.30 from z = 0.1 um the unilateral slider grows into a bouncing
/// cycle (pin off the disk part of each period) within about 22 s. A long run through
/// thousands of contact switches: no chatter, and the fraction of time off the disk.
/// `cargo test --release -p tribosweep-core --test slider_integrators unilateral_reaches -- --ignored --nocapture`
#[test]
#[ignore]
fn unilateral_reaches_bouncing_cycle() {
    struct OffDisk {
        w: Watch,
        t_free: f64,
        t_from: f64,
    }
    impl Observer<6, ContactMode> for OffDisk {
        fn on_step(&mut self, s: &StepView<'_, 6, ContactMode>) -> Control {
            if s.mode == ContactMode::Free && s.t0 >= self.t_from {
                self.t_free += s.t1 - s.t0;
            }
            self.w.on_step(s)
        }
        fn on_event(&mut self, i: usize, t: f64, y: &State, b: ContactMode, a: ContactMode) -> Control {
            self.w.on_event(i, t, y, b, a)
        }
    }
    let s = Slider::new(Params { contact: ContactModel::Unilateral, mu: 0.30, ..Params::seed() }).unwrap();
    let y0 = State::new(0.1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    for m in [Method::Dopri5, Method::Dop853] {
        let mut o = OffDisk { w: Watch::default(), t_free: 0.0, t_from: 20.0 };
        let t0 = std::time::Instant::now();
        let sol = integrate(&s, m, 0.0, y0, 24.0, &Options::<6>::new(1e-8, 1e-14), &mut o);
        println!(
            "{m:?}: {:?} in {:.0} ms, z_max {:.2} um, events {:?}, switches {}, off the disk {:.1} % of [20, 24] s, {:?}",
            sol.outcome,
            t0.elapsed().as_secs_f64() * 1e3,
            o.w.z_max * 1e6,
            o.w.events,
            o.w.switches,
            100.0 * o.t_free / 4.0,
            sol.stats
        );
        assert_eq!(sol.outcome, Outcome::Finished);
    }
}

/// Time per seed trajectory (Dopri5, rtol 1e-6, 0.5 s). Run with
/// `cargo test --release -p tribosweep-core --test slider_integrators seed_trajectory_timing -- --ignored --nocapture`.
#[test]
#[ignore]
fn seed_trajectory_timing() {
    let s = Slider::seed();
    let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
    // Absolute tolerances of the Python benchmark: rtol * STATE_SCALE.
    let mut opts = Options::<6>::new(1e-6, 1e-12);
    opts.atol = State::new(1e-6, 1e-3, 1e-7, 1e-4, 1e-5, 1e-2) * 1e-6;
    // The right-hand side alone, for scale.
    let mut acc = State::zeros();
    let t0 = std::time::Instant::now();
    for k in 0..1_000_000 {
        acc += OdeSystem::rhs(&s, 0.0, &std::hint::black_box(y0 * (k as f64)), ContactMode::Contact);
    }
    println!("rhs: {:.1} ns ({})", t0.elapsed().as_secs_f64() * 1e3, acc[0]);
    for m in Method::ALL {
        let reps = if m == Method::Rodas4 { 200 } else { 2000 };
        let mut sol = integrate(&s, m, 0.0, y0, 0.5, &opts, &mut NoObserver);
        let t0 = std::time::Instant::now();
        for _ in 0..reps {
            sol = integrate(&s, m, 0.0, std::hint::black_box(y0), 0.5, &opts, &mut NoObserver);
        }
        let dt = t0.elapsed().as_secs_f64() / reps as f64;
        println!("{m:?} seed 0.5 s rtol 1e-6: {:.1} us per trajectory, {:?}", dt * 1e6, sol.stats);
    }
    // The same without event functions, to see what event detection costs.
    struct NoEvents(Slider);
    impl OdeSystem<6> for NoEvents {
        type Mode = ContactMode;
        #[inline]
        fn rhs(&self, t: f64, y: &State, m: ContactMode) -> State {
            OdeSystem::rhs(&self.0, t, y, m)
        }
        fn initial_mode(&self, _t: f64, _y: &State) -> ContactMode {
            ContactMode::Contact
        }
    }
    let ne = NoEvents(s);
    let reps = 2000;
    let t0 = std::time::Instant::now();
    for _ in 0..reps {
        integrate(&ne, Method::Dopri5, 0.0, std::hint::black_box(y0), 0.5, &opts, &mut NoObserver);
    }
    println!("Dopri5 without events: {:.1} us per trajectory", t0.elapsed().as_secs_f64() / reps as f64 * 1e6);
}
