use super::*;
use crate::model::{ContactModel, Params};
use crate::tidf::{SearchOptions, Tidf, Variant};

fn seed_root(s: &Slider) -> Root {
    Tidf::new(s, Variant::Consistent)
        .find_roots(s, &SearchOptions::default())
        .roots
        .into_iter()
        .find(|r| r.physical)
        .unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn saltation_is_identity_without_a_jump() {
    let s = Slider::seed();
    let y = State::new(-s.z_st, 0.01, 0.0, 0.0, 0.0, 0.0);
    assert_eq!(saltation(&s, &y, ContactMode::Contact, ContactMode::Contact, event::GAP), Jacobian::identity());
    let sm = saltation(&s, &y, ContactMode::Contact, ContactMode::Free, event::GAP);
    // Only the velocity rows change, and the z column carries the jump.
    assert!(sm[(0, 0)] == 1.0 && sm[(1, 0)] != 0.0);
}

#[test]
fn saltation_into_stick_projects_onto_the_band_edge() {
    use crate::model::{FrictionLaw, Params};
    let s = Slider::new(Params {
        friction_law: FrictionLaw::Switch,
        mu_static: 0.3,
        stribeck_velocity: 0.02,
        sliding_speed: 0.01,
        ..Params::seed()
    })
    .unwrap();
    // On the upper band edge, slipping inwards.
    let eta = s.p.stick_band;
    let phid = 0.01;
    let xd = s.p.sliding_speed - eta - s.p.torsion_sign * s.p.moment_arm * phid;
    let y = State::new(1e-6, 0.0, 2e-5, xd, 1e-4, phid);
    assert!((s.slip_velocity(&y) - eta).abs() < 1e-15);
    let sm = saltation(&s, &y, ContactMode::Contact, ContactMode::Stick, event::BAND_HI);
    // Every perturbation leaves v_r on the edge: n^T S = 0 (a zero Floquet multiplier).
    let n = s.slip_velocity_gradient();
    let row = n.transpose() * sm;
    assert!(row.amax() < 1e-12, "{row}");
    // Leaving stick for slip at the bound: S maps the stick field onto the slip field.
    let sm = saltation(&s, &y, ContactMode::Stick, ContactMode::Contact, event::STICK);
    let (fm, fp) = (s.rhs(&y, ContactMode::Stick), s.rhs(&y, ContactMode::Contact));
    assert!((sm * fm - fp).amax() <= 1e-9 * fp.amax());
}

#[test]
fn monodromy_matches_finite_differences() {
    // Bilateral (smooth): Phi(T) against central differences of the flow.
    let s = Slider::seed();
    let root = seed_root(&s);
    let (y0, t) = guess_from_root(&root);
    let opts = ShootingOptions::default();
    let o42 = options_42(&s, opts.rtol);
    let mut st = Stats::default();
    let fl = flow(&s, &y0, ContactMode::Contact, t, &opts, &o42, &mut st).unwrap();
    let sz = scales(&s);
    for j in 0..6 {
        let h = 1e-5 * sz[j];
        let mut yp = y0;
        let mut ym = y0;
        yp[j] += h;
        ym[j] -= h;
        let fp = flow(&s, &yp, ContactMode::Contact, t, &opts, &o42, &mut st).unwrap().y;
        let fm = flow(&s, &ym, ContactMode::Contact, t, &opts, &o42, &mut st).unwrap().y;
        for i in 0..6 {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            let scale = sz[i] / sz[j];
            assert!((fd - fl.phi[(i, j)]).abs() < 1e-5 * scale, "Phi[{i},{j}] = {} fd {fd}", fl.phi[(i, j)]);
        }
    }
}

#[test]
fn unilateral_monodromy_with_saltation_matches_finite_differences() {
    // A state that leaves the disk and lands again within the horizon: the saltation matrices
    // must make Phi the derivative of the non-smooth flow.
    let s = Slider::new(Params { contact: ContactModel::Unilateral, ..Params::seed() }).unwrap();
    let y0 = State::new(30e-6, 0.0, 1e-6, 0.0, 1e-3, 0.5);
    let t = 0.012;
    let opts = ShootingOptions::default();
    let o42 = options_42(&s, opts.rtol);
    let mut st = Stats::default();
    let mode0 = s.mode_at(&y0);
    let fl = flow(&s, &y0, mode0, t, &opts, &o42, &mut st).unwrap();
    assert!(fl.n_switches >= 2, "{}", fl.n_switches);
    let sz = scales(&s);
    // A relative step of 3e-4: the flow is smooth between switches, and a smaller step is
    // dominated by the event-location noise divided by h (worst scaled error 1.8e-4 at h = 1e-6,
    // 1.8e-5 at 1e-5, 6e-7 at 3e-4, 3e-6 at 1e-3 where truncation takes over).
    for j in 0..6 {
        let h = 3e-4 * sz[j];
        let mut yp = y0;
        let mut ym = y0;
        yp[j] += h;
        ym[j] -= h;
        let fp = flow(&s, &yp, s.mode_at(&yp), t, &opts, &o42, &mut st).unwrap();
        let fm = flow(&s, &ym, s.mode_at(&ym), t, &opts, &o42, &mut st).unwrap();
        assert_eq!(fp.n_switches, fl.n_switches);
        for i in 0..6 {
            let fd = (fp.y[i] - fm.y[i]) / (2.0 * h);
            let scale = sz[i] / sz[j];
            assert!((fd - fl.phi[(i, j)]).abs() < 1e-5 * scale, "Phi[{i},{j}] = {} fd {fd}", fl.phi[(i, j)]);
        }
    }
}

#[test]
fn seed_bilateral_orbit_matches_model_md() {
    let s = Slider::seed();
    let root = seed_root(&s);
    let o = shoot_from_root(&s, &root, &ShootingOptions::default());
    eprintln!(
        "bilateral: T {:.9e} w {:.4} moduli {:?} stable {} A0 {:.4e} A1 {:.5e} A2 {:.4e} A3 {:.4e} theta {:.2} deg z_max {:.4e} open {:.4} minN {:.2} res {:.1e} newton {} trivial err {:.1e} stats {:?}",
        o.period, o.omega, o.moduli, o.stable, o.harmonics.a0, o.harmonics.a1, o.harmonics.a2, o.harmonics.a3,
        o.harmonics.theta * 180.0 / PI, o.z_max, o.open_fraction, o.min_normal_force, o.residual_norm, o.newton_iterations, o.trivial_error, o.stats
    );
    assert_eq!(o.status, Status::Success);
    // MODEL.md §6 / seed_values.json bilateral_periodic_orbit_seed.
    assert!(rel(o.period, 9.702674e-3) < 1e-6, "T = {}", o.period);
    let expect = [1.00762, 1.0, 0.98883, 0.98883, 0.61117, 0.61117];
    for (m, e) in o.moduli.iter().zip(expect) {
        assert!((m - e).abs() < 1e-4, "{:?}", o.moduli);
    }
    assert!(!o.stable);
    // The subcritical Hopf's saddle cycle: one real multiplier just above 1.
    assert_eq!(o.instability, Instability::Fold);
    assert!(o.flip_multiplier.is_nan());
    assert!(o.trivial_error < 1e-6);
    assert!((o.harmonics.a1 - 22.27e-6).abs() < 0.01e-6, "A1 {}", o.harmonics.a1);
    assert!((o.harmonics.a2 - 5.26e-6).abs() < 0.01e-6, "A2 {}", o.harmonics.a2);
    assert!((o.z_max - 27.8e-6).abs() < 0.05e-6, "z_max {}", o.z_max);
    assert!(o.contact_opens);
    assert!((o.open_fraction - 0.26).abs() < 0.01, "open {}", o.open_fraction);
}

/// Integrates `s` from `y` over `[0, t_end]` in chunks; a chunk in which a step hides a contact
/// switch ([`missed_crossing`]) is integrated again with the step size capped (the driver's
/// sign test at step ends misses a hop shorter than a step).
fn run_watched(s: &Slider, y: &State, t_end: f64, rtol: f64) -> (State, usize) {
    struct Watch<'a> {
        s: &'a Slider,
        missed: Option<f64>,
    }
    impl Observer<6, ContactMode> for Watch<'_> {
        fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
            self.missed = missed_crossing(self.s, st, false);
            if self.missed.is_some() {
                Control::Stop
            } else {
                Control::Continue
            }
        }
    }
    let o = crate::steady::options_for(s, &crate::steady::Tolerances::new(rtol));
    let mut y = *y;
    let mut retries = 0;
    let chunk = 0.25;
    let mut t = 0.0;
    while t < t_end {
        let t1 = (t + chunk).min(t_end);
        let mut oc = o;
        loop {
            let mut w = Watch { s, missed: None };
            let sol = integrate(s, Method::Dop853, t, y, t1, &oc, &mut w);
            match w.missed {
                Some(h) => {
                    oc.h_max = oc.h_max.min(h / 8.0);
                    retries += 1;
                }
                None => {
                    assert_eq!(sol.outcome, Outcome::Finished);
                    y = sol.y;
                    break;
                }
            }
        }
        t = t1;
    }
    (y, retries)
}

/// MODEL.md §6 recipe: the unilateral model at mu = 0.30 from z = 0.1 um for 22 s, then at
/// mu = 0.215 for 6 s; the end state lies on the stable bouncing cycle.
/// A state on the seed's unilateral bouncing cycle, found robustly: at mu = 0.30 sliding is
/// unstable and the bouncing cycle is the attractor a small disturbance grows into; shooting
/// there, then following the cycle down to mu = 0.215 in steps of 0.005 (natural-parameter
/// continuation, each solve started from the last orbit). A single transient continued at
/// 0.215 (MODEL.md §6's recipe) lands near a basin boundary: moved by one ulp, it can decay.
pub(crate) fn bouncing_cycle_start() -> (Slider, State) {
    let p = Params { contact: ContactModel::Unilateral, mu: 0.30, ..Params::seed() };
    let hot = Slider::new(p).unwrap();
    let (y1, r1) = run_watched(&hot, &State::new(0.1e-6, 0.0, 0.0, 0.0, 0.0, 0.0), 22.0, 1e-9);
    eprintln!("mu = 0.30 transient: {r1} chunks integrated again for a hidden switch");
    let tors = crate::linear::linear_stability(&hot).mode(crate::linear::ModeKind::Torsion).frequency;
    let opts = ShootingOptions::default();
    let mut o = shoot(&hot, &y1, 2.0 * PI / tors, &opts);
    assert_eq!(o.status, Status::Success, "mu = 0.30");
    for k in 1..=17 {
        let mu = 0.30 - 0.005 * k as f64;
        let s = Slider::new(Params { mu, ..p }).unwrap();
        o = shoot(&s, &o.state0, o.period, &opts);
        assert!(o.status == Status::Success && o.stable, "mu = {mu}: {:?}", o.status);
    }
    (Slider::new(Params { mu: 0.215, ..p }).unwrap(), o.state0)
}

#[test]
fn seed_unilateral_bouncing_cycle_is_stable() {
    let (s, y) = bouncing_cycle_start();
    // Period guess: the torsion mode's (1.5 % off the cycle's).
    let tors = crate::linear::linear_stability(&s).mode(crate::linear::ModeKind::Torsion).frequency;
    let o = shoot(&s, &y, 2.0 * PI / tors, &ShootingOptions::default());
    eprintln!(
        "unilateral: T {:.9e} w {:.4} moduli {:?} stable {} A0 {:.4e} A1 {:.5e} A2 {:.4e} A3 {:.4e} theta {:.2} deg z_max {:.4e} open {:.4} minN {:.2} minLaw {:.2} switches {} res {:.1e} newton {} trivial err {:.1e}",
        o.period, o.omega, o.moduli, o.stable, o.harmonics.a0, o.harmonics.a1, o.harmonics.a2, o.harmonics.a3,
        o.harmonics.theta * 180.0 / PI, o.z_max, o.open_fraction, o.min_normal_force, o.min_law_force, o.n_switches, o.residual_norm, o.newton_iterations, o.trivial_error
    );
    assert_eq!(o.status, Status::Success);
    // MODEL.md §6 / seed_values.json unilateral_bouncing_cycle_seed.
    assert!((o.omega - 640.371).abs() < 0.01, "w = {}", o.omega);
    assert!((o.harmonics.a1 - 23.646e-6).abs() < 0.01e-6, "A1 {}", o.harmonics.a1);
    assert!((o.harmonics.a2 - 11.009e-6).abs() < 0.01e-6, "A2 {}", o.harmonics.a2);
    assert!((o.open_fraction - 0.115).abs() < 0.001, "open {}", o.open_fraction);
    assert!(o.stable);
    assert_eq!(o.instability, Instability::Stable);
    assert!(o.contact_opens && o.min_normal_force == 0.0);
    assert!(o.trivial_error < 1e-6);
}

#[test]
fn instability_is_the_kind_of_the_largest_nontrivial_multiplier() {
    let c = C64::new;
    // Sorted by modulus, descending, as `analyse` leaves them; the trivial one is 1.
    let judge = |ev: [C64; 6]| {
        let trivial = trivial_index(&ev);
        let stable = (0..6).filter(|&k| k != trivial).all(|k| ev[k].norm() < 1.0 - 1e-6);
        classify(&ev, trivial, stable)
    };
    let tail = [c(0.3, 0.0), c(0.1, 0.0)];
    let (k, f) = judge([c(1.0, 0.0), c(-0.5, 0.2), c(-0.5, -0.2), c(-0.4, 0.0), tail[0], tail[1]]);
    assert_eq!((k, f), (Instability::Stable, -0.4));
    let (k, f) = judge([c(1.2, 0.0), c(1.0, 0.0), c(0.5, 0.0), c(0.4, 0.0), tail[0], tail[1]]);
    assert!(k == Instability::Fold && f.is_nan());
    let (k, f) = judge([c(-1.3, 0.0), c(1.0, 0.0), c(-0.9, 0.0), c(0.4, 0.0), tail[0], tail[1]]);
    assert_eq!((k, f), (Instability::Flip, -1.3));
    let (k, f) = judge([c(-0.2, 1.1), c(-0.2, -1.1), c(1.0, 0.0), c(0.4, 0.0), tail[0], tail[1]]);
    assert!(k == Instability::Torus && f.is_nan());
    // A real multiplier's rounding-level imaginary part does not make it complex.
    let (k, f) = judge([c(-1.1, 1e-12), c(1.0, 0.0), c(0.5, 0.0), c(0.4, 0.0), tail[0], tail[1]]);
    assert_eq!((k, f), (Instability::Flip, -1.1));
}

#[test]
fn shooting_from_a_transients_section_state_converges() {
    // Unilateral, 76 N, mu 0.36: the transient's section state is within 3e-6 (scaled) of the
    // stable bouncing cycle. Judged at the graded first accuracy its residual looked smaller
    // than any Newton step could make it, and the solve gave up after one iteration; it is
    // now judged again at full accuracy.
    use crate::steady::{run_to_steady, SteadyOptions, SteadyOutcome, Tolerances};
    let s = Slider::new(Params { contact: ContactModel::Unilateral, normal_load: 76.0, mu: 0.36, ..Params::seed() })
        .unwrap();
    let y0 = State::new(s.z_st.abs(), 0.0, 0.0, 0.0, 0.0, 0.0);
    let so = SteadyOptions { t_max: 40.0, tol: Tolerances::new(1e-9), periodic_tol: 1e-6, ..Default::default() };
    let sum = run_to_steady(&s, &y0, &so);
    assert_eq!(sum.outcome, SteadyOutcome::Periodic);
    let o = shoot(&s, &sum.y_end, sum.period, &ShootingOptions::default());
    assert_eq!(o.status, Status::Success, "after {} iterations, residual {:e}", o.newton_iterations, o.residual_norm);
    assert!(o.stable && o.residual_norm < 1e-9);
    assert!((o.period / sum.period - 1.0).abs() < 1e-5, "{} vs {}", o.period, sum.period);
}

#[test]
fn period_doubling_is_flagged_by_the_flip_multiplier() {
    // Unilateral, 80 N: the bouncing cycle's real multiplier crosses -1 near mu = 0.4206 and a
    // stable cycle of twice the period takes over. Shooting the period-1 orbit still converges
    // past the crossing (M - I is regular at rho = -1); only the multipliers tell.
    use crate::steady::{run_to_steady, SteadyOptions, SteadyOutcome, Tolerances};
    let at = |mu| Slider::new(Params { contact: ContactModel::Unilateral, normal_load: 80.0, mu, ..Params::seed() });
    let steady = |s: &Slider| {
        let y0 = State::new(s.z_st.abs(), 0.0, 0.0, 0.0, 0.0, 0.0);
        let so = SteadyOptions { t_max: 40.0, tol: Tolerances::new(1e-9), periodic_tol: 1e-6, ..Default::default() };
        let sum = run_to_steady(s, &y0, &so);
        assert_eq!(sum.outcome, SteadyOutcome::Periodic, "{:?}", sum.status);
        assert!(sum.y_end[idx::ZD].abs() < 1e-9, "y_end is on the section: {}", sum.y_end);
        sum
    };
    let opts = ShootingOptions::default();
    let before = at(0.415).unwrap();
    let sum = steady(&before);
    let o1 = shoot(&before, &sum.y_end, sum.period, &opts);
    assert_eq!(o1.status, Status::Success);
    assert!((o1.period / sum.period - 1.0).abs() < 1e-5, "{} vs {}", o1.period, sum.period);
    assert!(o1.stable && o1.instability == Instability::Stable);
    assert!(o1.flip_multiplier.is_nan() || o1.flip_multiplier > -0.95, "{:?}", o1.multipliers);
    // Continue the branch past the crossing.
    let past = at(0.4225).unwrap();
    let o2 = shoot(&past, &o1.state0, o1.period, &opts);
    eprintln!("period-1 at 0.4225: T {:.6e} multipliers {:?}", o2.period, o2.multipliers);
    assert_eq!(o2.status, Status::Success);
    assert!(!o2.stable && o2.instability == Instability::Flip, "{:?}", o2.multipliers);
    assert!(o2.flip_multiplier < -1.05 && o2.flip_multiplier > -1.2, "{}", o2.flip_multiplier);
    // The attractor there has twice the period; shooting with that period finds it stable.
    let sum2 = steady(&past);
    assert!((sum2.period / o2.period - 2.0).abs() < 0.01, "{} vs {}", sum2.period, o2.period);
    let o3 = shoot(&past, &sum2.y_end, sum2.period, &opts);
    assert_eq!(o3.status, Status::Success);
    assert!((o3.period / sum2.period - 1.0).abs() < 1e-5, "{} vs {}", o3.period, sum2.period);
    assert!(o3.stable, "{:?}", o3.moduli);
}

#[test]
fn describing_function_error_grows_with_amplitude() {
    // MODEL.md §6: at mu = 0.1 the describing function's A1 is 10.4 % below the exact orbit's
    // at 15 N and 18.5 % below at 200 N.
    for (load, gap) in [(15.0, 0.104), (200.0, 0.185)] {
        let s = Slider::new(Params { mu: 0.1, normal_load: load, ..Params::seed() }).unwrap();
        let search = Tidf::new(&s, Variant::Consistent).find_roots(&s, &SearchOptions::default());
        // The torsion-branch root (at 15 N it is flagged non-physical: A0 = 3.7 um > |z_st| = 3.1 um).
        let dist = |r: &&Root| (r.omega - search.torsion_frequency).abs();
        let root = *search.roots.iter().min_by(|a, b| dist(a).total_cmp(&dist(b))).unwrap();
        let o = shoot_from_root(&s, &root, &ShootingOptions::default());

        assert_eq!(o.status, Status::Success);
        let err = 1.0 - root.a1 / o.harmonics.a1;
        eprintln!(
            "mu 0.1, {load} N: DF A1 {:.4e}, orbit A1 {:.4e} ({:.1} % below), orbit stable {}",
            root.a1,
            o.harmonics.a1,
            100.0 * err,
            o.stable
        );
        assert!((err - gap).abs() < 0.002, "{err}");
        assert!(!o.stable);
    }
}

#[test]
#[ignore = "timing; run with --ignored --nocapture in release"]
fn timing() {
    let s = Slider::seed();
    let root = seed_root(&s);
    let (y0, t) = guess_from_root(&root);
    let opts = ShootingOptions::default();
    let n = 100;
    // Best of 5 batches: the machine is shared.
    let mut best = f64::INFINITY;
    let mut it = 0;
    let mut rhs = 0;
    for _ in 0..5 {
        let t0 = std::time::Instant::now();
        for _ in 0..n {
            let o = std::hint::black_box(shoot_from_root(&s, &root, &opts));
            it = o.newton_iterations;
            rhs = o.stats.n_rhs;
        }
        best = best.min(t0.elapsed().as_secs_f64() / n as f64);
    }
    eprintln!("shooting from the DF root (bilateral seed): {:.0} us per solve (best of 5 x {n}), {it} Newton iterations, {rhs} rhs", best * 1e6);
    let (_, y1) = bouncing_cycle_start();
    let su = Slider::new(Params { contact: ContactModel::Unilateral, ..Params::seed() }).unwrap();
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = std::time::Instant::now();
        for _ in 0..20 {
            let o = std::hint::black_box(shoot(&su, &y1, 9.8e-3, &opts));
            it = o.newton_iterations;
            rhs = o.stats.n_rhs;
        }
        best = best.min(t0.elapsed().as_secs_f64() / 20.0);
    }
    eprintln!("shooting the unilateral bouncing cycle from the recipe state: {:.0} us per solve, {it} Newton iterations, {rhs} rhs", best * 1e6);
    let o42 = options_42(&s, opts.rtol);
    let t0 = std::time::Instant::now();
    let mut st = Stats::default();
    for _ in 0..n {
        std::hint::black_box(flow(&s, &y0, ContactMode::Contact, t, &opts, &o42, &mut st).ok());
    }
    let dt = t0.elapsed().as_secs_f64() / n as f64;
    eprintln!(
        "one variational period: {:.0} us, {} rhs, {} steps",
        dt * 1e6,
        st.n_rhs / n as u64,
        st.n_accept / n as u64
    );
    let o6 = crate::steady::options_for(&s, &crate::steady::Tolerances::new(opts.rtol));
    let t0 = std::time::Instant::now();
    let mut st = Stats::default();
    for _ in 0..n {
        st += std::hint::black_box(integrate(&s, opts.method, 0.0, y0, t, &o6, &mut crate::ode::NoObserver)).stats;
    }
    let dt = t0.elapsed().as_secs_f64() / n as f64;
    eprintln!("one plain period: {:.0} us, {} rhs, {} steps", dt * 1e6, st.n_rhs / n as u64, st.n_accept / n as u64);
    let sys = Variational { slider: &s, start: ContactMode::Contact };
    let mut ya = join(&y0, &Jacobian::identity());
    let t0 = std::time::Instant::now();
    for _ in 0..100_000 {
        let d = sys.rhs(0.0, std::hint::black_box(&ya), ContactMode::Contact);
        ya += d * 1e-12;
    }
    eprintln!("variational rhs: {:.0} ns", t0.elapsed().as_secs_f64() / 1e5 * 1e9);
}

#[test]
fn an_unconverged_orbit_has_no_values_and_says_why() {
    // max_iter = 0: Newton may not take a step from the describing function's guess, whose scaled
    // residual is far above tol; no orbit, and nothing of the guess is reported as one.
    let s = Slider::seed();
    let root = seed_root(&s);
    let o = shoot_from_root(&s, &root, &ShootingOptions { max_iter: 0, ..ShootingOptions::default() });
    assert_eq!(o.status, Status::NewtonNotConverged);
    assert!(o.period.is_nan() && o.omega.is_nan() && o.state0.iter().all(|v| v.is_nan()));
    assert!(o.harmonics.a1.is_nan() && o.z_max.is_nan() && o.moduli.iter().all(|v| v.is_nan()));
    assert!(!o.stable && o.instability == Instability::Unknown && !o.contact_opens);
    assert!(o.residual_norm > 1e-9 && o.newton_iterations == 0);
    match o.failure {
        Some(Failure::Newton { iterations: 0, max_iter: 0, residual, tol }) => {
            assert!(residual == o.residual_norm && tol == 1e-9);
        }
        other => panic!("{other:?}"),
    }
    // A converged orbit has no failure.
    let ok = shoot_from_root(&s, &root, &ShootingOptions::default());
    assert!(ok.status == Status::Success && ok.failure.is_none() && ok.period.is_finite());
    // A bad start is refused with its reason.
    let bad = shoot(&s, &State::zeros(), -1.0, &ShootingOptions::default());
    assert_eq!((bad.status, bad.failure), (Status::InvalidInput, Some(Failure::InvalidStart { period: -1.0 })));
    // A cancelled solve stops with no values.
    let token = crate::cancel::Token::new();
    token.cancel();
    let c = token.scope(|| shoot_from_root(&s, &root, &ShootingOptions::default()));
    assert_eq!(c.status, Status::NotComputed);
    assert!(c.period.is_nan() && c.failure.is_some_and(|f| f.status() == Status::NotComputed));
}

#[test]
fn the_chord_finds_the_orbit_and_the_verdict_of_newton() {
    // A transient's slow-approach stop is within APPROACH_TOL = 1e-3 (scaled) of its orbit; the
    // chord (one monodromy matrix, then flows of the state alone) must end where Newton ends,
    // with the same stability (its cost is measured by the Stribeck bench). Two orbits: the issue-10 model's cycle with stick
    // and contact loss under the switch law (72 N, 0.2 m/s; its friction mode's multiplier is
    // near 1, where a kept matrix is least accurate against the Newton matrix's smallest
    // singular value), stable; and the seed's period-1 bouncing orbit past its flip (80 N,
    // mu = 0.4225, continued from 0.415 as in `period_doubling_is_flagged_by_the_flip_multiplier`),
    // unstable.
    use crate::model::FrictionLaw;
    use crate::steady::{run_to_steady, SteadyOptions, SteadyOutcome, Tolerances};
    let opts = ShootingOptions { rtol: 1e-9, tol: 1e-8, max_iter: 20, n_samples: 256, ..ShootingOptions::default() };
    let on_cycle = |p: Params| {
        let s = Slider::new(p).unwrap();
        let y0 = State::new(s.z_st.abs(), 0.0, 0.0, 0.0, 0.0, 0.0);
        let so = SteadyOptions { t_max: 40.0, tol: Tolerances::new(1e-9), periodic_tol: 1e-6, ..Default::default() };
        let sum = run_to_steady(&s, &y0, &so);
        assert_eq!(sum.outcome, SteadyOutcome::Periodic, "{:?}", sum.status);
        let o = shoot(&s, &sum.y_end, sum.period, &opts);
        assert_eq!(o.status, Status::Success);
        (s, o)
    };
    let stribeck = Params {
        contact: ContactModel::Unilateral,
        friction_law: FrictionLaw::Switch,
        mu_static: 0.3,
        normal_load: 72.2,
        omega_normal: 443.358,
        omega_friction: 413.074,
        omega_torsion: 724.756,
        sliding_speed: 0.2,
        ..Params::seed()
    };
    let bounce = Params { contact: ContactModel::Unilateral, normal_load: 80.0, mu: 0.415, ..Params::seed() };
    let (_, before) = on_cycle(bounce);
    let past = Slider::new(Params { mu: 0.4225, ..bounce }).unwrap();
    let flip = shoot(&past, &before.state0, before.period, &opts);
    assert!(flip.status == Status::Success && !flip.stable);
    for ((s, on), stable) in [(on_cycle(stribeck), true), ((past, flip), false)] {
        let sz = scales(&s);
        let start = State::from_fn(|k, _| if k == idx::ZD { 0.0 } else { on.state0[k] + [1e-3, -1e-3][k % 2] * sz[k] });
        let full = shoot_impl(&s, &start, on.period, &opts, false, Newton::Full);
        let chord = shoot_impl(&s, &start, on.period, &opts, false, Newton::Chord);
        eprintln!(
            "{:?}: full {} iterations, {} rhs; chord {} iterations, {} rhs; moduli {:?} / {:?}",
            s.p.friction_law,
            full.newton_iterations,
            full.stats.n_rhs,
            chord.newton_iterations,
            chord.stats.n_rhs,
            full.moduli,
            chord.moduli
        );
        assert_eq!((full.status, chord.status), (Status::Success, Status::Success));
        assert_eq!((full.stable, chord.stable), (stable, stable));
        // Against a solve to tol 1e-11 at rtol 1e-11: the chord stops once its step is below
        // tol = 1e-8 as well as the residual, so its end is within about tol of the orbit. Full
        // Newton's end is as good as its flows: 8.9e-7 here, 1.7e-5 when the flow with the
        // variational equations let `Phi` into its error norm (`options_42`); along the orbit's
        // 0.998 multiplier a flow's error is amplified about 430x.
        let fine = ShootingOptions { rtol: 1e-11, tol: 1e-11, ..opts };
        let refo = shoot_impl(&s, &start, on.period, &fine, false, Newton::Full);
        assert_eq!(refo.status, Status::Success);
        let dyf = (full.state0 - refo.state0).component_div(&sz).amax();
        assert!(dyf < 1e-5, "full Newton's state {dyf:e} from the reference");
        let dy = (chord.state0 - refo.state0).component_div(&sz).amax();
        let dt = chord.period / refo.period - 1.0;
        eprintln!("chord: period {dt:e} relative, state {dy:e} (scaled) from the reference");
        assert!(dt.abs() < 1e-8 && dy < 1e-6, "period {dt:e}, state {dy:e}");
        let largest = |o: &PeriodicOrbit| o.moduli[(0..6).find(|&k| k != o.trivial).unwrap()];
        assert!((largest(&chord) - largest(&refo)).abs() < 1e-4, "{} vs {}", largest(&chord), largest(&refo));
    }
}

#[test]
fn a_pin_landing_under_tension_does_not_fly_through_the_disk() {
    // The end of a chaotic run of the issue-10 switch-law sweep (150 N, 12.7 cm arm, 0.4 m/s; its
    // frequencies as the sweep sets them): the pin is in flight, lands at 1.0 ms while the law's
    // normal force is tensile (it stays in flight at the gap event), and that force turns
    // compressive again inside the same step. Without checks inside the steps the shooting's flows
    // missed both crossings and flew on through the disk to the 1 mm escape limit at 6.2 ms
    // (`Diverged`). Each flow (the state alone, and with its variational equations) must follow
    // the transients' own driver instead: within 1e-5 of the characteristic sizes after 10 ms.
    let mut p = Params::seed();
    p.contact = ContactModel::Unilateral;
    p.friction_law = crate::model::FrictionLaw::Switch;
    for (k, v) in [
        ("omega_normal", 234.4899326505231),
        ("omega_friction", 192.31907889927868),
        ("omega_torsion", 487.1928411561178),
        ("normal_load", 150.0),
        ("sliding_speed", 0.4),
        ("mu_static", 0.3),
    ] {
        p.set(k, v).unwrap();
    }
    let s = Slider::new(p).unwrap();
    let y0 = State::from_column_slice(&[
        7.214338537441294e-05,
        -0.011065934757032178,
        2.7619381516037394e-05,
        0.0046263753049569055,
        -0.004903329338366977,
        4.511541282276206,
    ]);
    assert_eq!(s.mode_at(&y0), ContactMode::Free);
    let (t, rtol) = (0.01, 1e-8);
    let o = crate::steady::options_for(&s, &crate::steady::Tolerances::new(1e-11));
    let reference = integrate(&s, Method::Dop853, 0.0, y0, t, &o, &mut crate::ode::NoObserver);
    assert_eq!(reference.outcome, Outcome::Finished);
    let sz = scales(&s);
    let off = |y: &State| (y - reference.y).component_div(&sz).amax();
    let opts = ShootingOptions { rtol, ..ShootingOptions::default() };
    let mut st = Stats::default();
    let alone = newton::flow_state(&s, &y0, s.mode_at(&y0), t, &opts, rtol, &mut st).expect("the state's flow");
    let with_phi =
        flow(&s, &y0, s.mode_at(&y0), t, &opts, &options_42(&s, rtol), &mut st).expect("the variational flow");
    assert!(off(&alone.y) < 1e-5, "{:e}", off(&alone.y));
    assert!(off(&with_phi.y) < 1e-5, "{:e}", off(&with_phi.y));
    assert!(reference.y[idx::Z].abs() < 2e-4);
}
