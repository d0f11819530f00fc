use super::*;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn static_point_matches_model_md() {
    let s = Slider::seed();
    // MODEL.md §3: z_st = -16.5612 um, K_s = 5.4607e6 N/m.
    assert!(close(s.z_st, -16.5612e-6, 1e-5), "z_st = {}", s.z_st);
    assert!(close(s.k_s, 5.4607e6, 1e-4), "K_s = {}", s.k_s);
    // The law reproduces the load at the static point.
    let p = s.p;
    let f = -p.contact_stiffness * s.z_st + p.contact_quadratic * s.z_st * s.z_st;
    assert!(close(f, p.normal_load, 1e-13));
}

#[test]
fn static_point_without_quadratic_term() {
    let p = Params { contact_quadratic: 0.0, ..Params::seed() };
    assert!(close(p.static_penetration(), -p.normal_load / p.contact_stiffness, 1e-15));
    assert_eq!(p.dynamic_contact_stiffness(), p.contact_stiffness);
}

#[test]
fn sliding_is_an_equilibrium_for_every_law() {
    for contact in [ContactModel::Bilateral, ContactModel::Unilateral] {
        for law in [FrictionLaw::Constant, FrictionLaw::Coulomb, FrictionLaw::Switch] {
            let s = Slider::new(Params { contact, friction_law: law, mu_static: 0.3, ..Params::seed() }).unwrap();
            let y = State::zeros();
            assert_eq!(s.mode_at(&y), ContactMode::Contact);
            let f = s.rhs(&y, ContactMode::Contact);
            assert!(f.norm() < 1e-12, "{contact:?} {law:?}: {f}");
        }
    }
}

#[test]
fn bilateral_force_equals_total_law() {
    let s = Slider::seed();
    let y = State::new(3e-6, -0.01, 1e-6, 0.002, 1e-4, 0.05);
    let zc = s.gap(&y);
    let p = s.p;
    let total =
        -p.contact_stiffness * zc + p.contact_quadratic * zc * zc - p.contact_damping * y[1] + p.twist_coupling * y[4];
    let f = s.forces(&y, ContactMode::Contact);
    assert!((f.normal - total).abs() < 1e-9 * p.normal_load);
}

/// The analytic Jacobian against central differences (steps `h_rel` times each component's
/// scale), element by element to 1e-6 (1 + |J|).
fn assert_jacobian_matches_fd(s: &Slider, y: &State, mode: ContactMode, h_rel: f64, label: &str) {
    let j = s.jacobian(y, mode);
    let scale = [1e-6, 1e-3, 1e-6, 1e-3, 1e-4, 1e-2];
    for c in 0..6 {
        let h = scale[c] * h_rel;
        let (mut yp, mut ym) = (*y, *y);
        yp[c] += h;
        ym[c] -= h;
        let col = (s.rhs(&yp, mode) - s.rhs(&ym, mode)) / (2.0 * h);
        for r in 0..6 {
            let tol = 1e-6 * (1.0 + j[(r, c)].abs());
            assert!((col[r] - j[(r, c)]).abs() < tol, "{label} {mode:?} J[{r},{c}] = {} vs fd {}", j[(r, c)], col[r]);
        }
    }
}

#[test]
fn jacobian_matches_finite_differences() {
    for law in [FrictionLaw::Constant, FrictionLaw::Coulomb] {
        for mode in [ContactMode::Contact, ContactMode::Free] {
            let s = Slider::new(Params {
                friction_law: law,
                mu_static: 0.3,
                friction_regularization: 0.05,
                ..Params::seed()
            })
            .unwrap();
            let y = State::new(2e-6, 1e-3, -1e-6, 0.01, 2e-4, 0.3);
            assert_jacobian_matches_fd(&s, &y, mode, 1e-4, &format!("{law:?}"));
        }
    }
}

/// A slider with the switch law and a state inside the stick band, in contact.
fn switch_slider() -> Slider {
    Slider::new(Params {
        friction_law: FrictionLaw::Switch,
        mu_static: 0.3,
        stribeck_velocity: 0.02,
        sliding_speed: 0.01,
        stick_band: 1e-4,
        ..Params::seed()
    })
    .unwrap()
}

/// State with `v_r = v` and some spring and twist deflection.
fn state_with_slip(s: &Slider, v: f64, x: f64, phi: f64) -> State {
    let p = s.p;
    // v_r = V - (xd + s L phid): put the rest in xd.
    let phid = 0.02;
    let xd = p.sliding_speed - v - p.torsion_sign * p.moment_arm * phid;
    State::new(1e-6, 1e-3, x, xd, phi, phid)
}

#[test]
fn switch_jacobian_matches_finite_differences_in_every_mode() {
    let s = switch_slider();
    for (mode, v) in [
        (ContactMode::Contact, 3e-3),
        (ContactMode::Contact, -2e-3),
        (ContactMode::Free, 3e-3),
        (ContactMode::Stick, 5e-5),
        (ContactMode::Transition, -5e-5),
    ] {
        for (x, phi) in [(2e-6, 1e-4), (-3e-5, -2e-4)] {
            let y = state_with_slip(&s, v, x, phi);
            assert_jacobian_matches_fd(&s, &y, mode, 1e-5, &format!("v_r = {v}"));
        }
    }
}

#[test]
fn stick_force_holds_the_sliding_velocity() {
    let s = switch_slider();
    let n = s.slip_velocity_gradient();
    for (x, phi) in [(2e-6, 1e-4), (-3e-5, -2e-4), (0.0, 0.0), (1e-4, 3e-3)] {
        let y = state_with_slip(&s, 3e-5, x, phi);
        let f = s.rhs(&y, ContactMode::Stick);
        // d v_r/dt = grad(v_r) . f; the accelerations are O(1e2) m/s^2, so 1e-12 is rounding.
        let acc = f[idx::XD].abs() + s.p.moment_arm * f[idx::PHID].abs();
        assert!(n.dot(&f).abs() <= 1e-13 * acc.max(1.0), "dv_r/dt = {} (scale {acc})", n.dot(&f));
        assert_eq!(s.forces(&y, ContactMode::Stick).friction, s.stick_force(&y));
        // The total force is the required one, and the margin is the bound less its size.
        let req = s.required_friction(&y);
        assert!(close(req, s.stick_force(&y) + s.mu_of(s.p.sliding_speed) * s.p.normal_load, 1e-15));
        let nf = s.forces(&y, ContactMode::Stick).normal;
        assert!(close(s.stick_margin(&y), s.p.mu_static * nf - req.abs(), 1e-12));
    }
    // Steady sliding needs exactly the static sliding force.
    let y0 = State::zeros();
    assert_eq!(s.stick_force(&y0), 0.0);
    assert!(close(s.required_friction(&y0), s.p.mu * s.p.normal_load, 1e-14));
}

#[test]
fn switch_modes_and_slip_friction() {
    let s = switch_slider();
    let eta = s.p.stick_band;
    // Outside the band: slip with the Stribeck force in the direction of v_r, a mode per direction.
    for (v, mode) in [(3e-3, ContactMode::Contact), (-3e-3, ContactMode::SlipBack)] {
        let y = state_with_slip(&s, v, 0.0, 0.0);
        assert_eq!(s.mode_at(&y), mode);
        let f = s.forces(&y, mode);
        let total = f.friction + s.mu_of(s.p.sliding_speed) * s.p.normal_load;
        assert!(close(total, s.mu_of(v) * f.normal * v.signum(), 1e-14), "{total}");
    }
    // Inside the band near the static point: stick (mu_s N = 25 N > the 18 N needed).
    let y = state_with_slip(&s, 0.5 * eta, 0.0, 0.0);
    assert_eq!(s.mode_at(&y), ContactMode::Stick);
    // A large spring deflection needs more than mu_s N: transition, at the static bound.
    let y = state_with_slip(&s, 0.5 * eta, -1e-3, 0.0);
    assert!(s.stick_margin(&y) < 0.0);
    assert_eq!(s.mode_at(&y), ContactMode::Transition);
    let f = s.forces(&y, ContactMode::Transition);
    let total = f.friction + s.mu_of(s.p.sliding_speed) * s.p.normal_load;
    assert!(close(total.abs(), s.p.mu_static * f.normal, 1e-14));
    assert_eq!(total.signum(), s.required_friction(&y).signum());
    // The transition drives v_r towards the edge sign(F_req) eta.
    let rate = s.slip_velocity_gradient().dot(&s.rhs(&y, ContactMode::Transition));
    assert_eq!(rate.signum(), s.required_friction(&y).signum());
    // Stick ends at the bound with v_r on the edge the force drives it to: slip at once.
    let req_sign = s.required_friction(&y).signum();
    let y_edge = state_with_slip(&s, req_sign * eta, -1e-3, 0.0);
    let slip = if req_sign > 0.0 { ContactMode::Contact } else { ContactMode::SlipBack };
    assert_eq!(s.band_regime(&y_edge), slip);
    assert_eq!(s.band_exit(&y_edge), slip);
    let y_far = state_with_slip(&s, -req_sign * eta, -1e-3, 0.0);
    assert_eq!(s.band_exit(&y_far), ContactMode::Transition);
}

#[test]
fn switch_slip_field_of_one_direction_is_the_law_on_its_side_and_smooth_across_zero() {
    let s = switch_slider();
    for sign in [1.0, -1.0] {
        let f = s.with_slip_sign(sign);
        // The law's slip mode of that direction (`Contact` forwards, `SlipBack` backwards).
        let own = if sign > 0.0 { ContactMode::Contact } else { ContactMode::SlipBack };
        // On its own side, and past zero, the law's field and Jacobian of that mode bit for bit.
        for v in [3e-3, 1e-7, -1e-7] {
            let y = state_with_slip(&s, sign * v, 2e-6, 1e-3);
            assert_eq!(f.rhs(&y, ContactMode::Contact), s.rhs(&y, own), "v = {v}");
            assert_eq!(f.jacobian(&y, ContactMode::Contact), s.jacobian(&y, own));
        }
        // Across zero (+-1e-9 m/s): the law's force (its mode following the sign of v_r) jumps by
        // 2 mu_s N; each slip mode's field is continued, with no jump, and its Jacobian is the
        // central difference of its field on both sides (analytic, 1e-6 relative).
        let force = |sl: &Slider, v: f64, m: ContactMode| sl.forces(&state_with_slip(&s, v, 0.0, 0.0), m).friction;
        let h = 1e-9;
        let law_jump = (force(&s, h, ContactMode::Contact) - force(&s, -h, ContactMode::SlipBack)).abs();
        let jump = |sl: &Slider, m: ContactMode| (force(sl, h, m) - force(sl, -h, m)).abs();
        let normal = s.forces(&state_with_slip(&s, h, 0.0, 0.0), ContactMode::Contact).normal;
        assert!(close(law_jump, 2.0 * s.p.mu_static * normal, 1e-6), "{law_jump} {normal}");
        assert!(jump(&f, ContactMode::Contact) < 1e-6 * law_jump, "{}", jump(&f, ContactMode::Contact)); // O(h)
        assert!(jump(&s, own) < 1e-6 * law_jump, "{}", jump(&s, own));
        for v in [-2e-4, 2e-4] {
            let y = state_with_slip(&s, sign * v, 0.0, 0.0);
            let j = f.jacobian(&y, ContactMode::Contact);
            let mut dy = State::zeros();
            dy[idx::XD] = 1e-7;
            let fd = (f.rhs(&(y + dy), ContactMode::Contact) - f.rhs(&(y - dy), ContactMode::Contact)) / 2e-7;
            assert!(close(fd[idx::XD], j[(idx::XD, idx::XD)], 1e-6), "{} {}", fd[idx::XD], j[(idx::XD, idx::XD)]);
        }
    }
}

#[test]
fn switch_events_fire_at_the_band_edges() {
    use crate::ode::{integrate, Control, Method, Observer, Options};
    // Free stick-slip from a pre-loaded spring: record every event with its v_r and modes.
    struct Log(Vec<(usize, f64, ContactMode, ContactMode)>, Slider);
    impl Observer<6, ContactMode> for Log {
        fn on_event(&mut self, i: usize, _t: f64, y: &State, b: ContactMode, a: ContactMode) -> Control {
            self.0.push((i, self.1.slip_velocity(y), b, a));
            Control::Continue
        }
    }
    let s = Slider::new(Params { stick_band: 1e-5, ..switch_slider().p }).unwrap();
    let eta = s.p.stick_band;
    let mut y0 = State::zeros();
    // Start stuck: v_r = 0 inside the band (xd = V), spring unloaded.
    y0[idx::XD] = s.p.sliding_speed;
    assert_eq!(s.mode_at(&y0), ContactMode::Stick);
    let mut log = Log(Vec::new(), s);
    let o = Options::<6>::new(1e-10, 1e-14);
    let sol = integrate(&s, Method::Dop853, 0.0, y0, 0.05, &o, &mut log);
    assert_eq!(sol.outcome, crate::ode::Outcome::Finished);
    let switches: Vec<_> = log.0.iter().filter(|e| e.2 != e.3).collect();
    assert!(switches.len() >= 4, "{switches:?}");
    // A located edge is inside the band by |dv_r/dt| x event_tol (1e-13 s): about 1e-11 m/s,
    // 1e-6 of this eta; 1e-4 of eta says "on the edge" with a hundredfold margin.
    for &&(i, v, b, a) in &switches {
        match i {
            event::BAND_HI => assert!((v - eta).abs() <= 1e-4 * eta, "{v}"),
            event::BAND_LO => assert!((v + eta).abs() <= 1e-4 * eta, "{v}"),
            event::STICK => assert!(b == ContactMode::Stick || a == ContactMode::Stick, "{b:?} -> {a:?}"),
            _ => {}
        }
        assert!(b.in_contact() && a.in_contact());
    }
    // It sticks, slips, and sticks again.
    assert!(switches.iter().any(|e| e.2 == ContactMode::Stick && e.3 != ContactMode::Stick));
    assert!(switches.iter().filter(|e| e.3 == ContactMode::Stick).count() >= 1);
}

#[test]
fn switch_law_validation() {
    let p = Params { friction_law: FrictionLaw::Switch, mu_static: 0.2, ..Params::seed() };
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("mu_static") && e.contains(">= mu"), "{e}");
    let p = Params { friction_law: FrictionLaw::Switch, stick_band: 0.5, ..Params::seed() };
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("stick_band") && e.contains("0.5") && e.contains("sliding_speed"), "{e}");
    let p = Params { stick_band: -1.0, ..Params::seed() };
    assert!(p.validate().unwrap_err().to_string().contains("stick_band"));
}

#[test]
fn validation_names_the_argument() {
    let bad = Params { mass: -1.0, ..Params::seed() };
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("mass") && e.contains("-1") && e.contains("> 0"), "{e}");
    let bad = Params { normal_load: f64::NAN, ..Params::seed() };
    assert!(bad.validate().unwrap_err().to_string().contains("normal_load"));
    let bad = Params { torsion_sign: 0.5, ..Params::seed() };
    assert!(bad.validate().unwrap_err().to_string().contains("-1 or +1"));
    let mut p = Params::seed();
    assert!(p.set("no_such", 1.0).is_err());
    p.set("mu", 0.3).unwrap();
    assert_eq!(p.get("mu").unwrap(), 0.3);
    for name in PARAM_NAMES {
        let v = p.get(name).unwrap();
        p.set(name, v).unwrap();
    }
    assert_eq!(p, Params { mu: 0.3, ..Params::seed() });
}

#[test]
fn stribeck_curve_passes_through_mu_at_operating_speed() {
    let s = Slider::new(Params { friction_law: FrictionLaw::Coulomb, mu_static: 0.3, ..Params::seed() }).unwrap();
    assert!(close(s.mu_of(s.p.sliding_speed), s.p.mu, 1e-14));
    assert!(s.mu_of(0.0) > s.mu_of(0.1));
    assert!(close(s.mu_of(0.0), 0.3, 1e-14));
}

/// `event` (one function, as root finding reads it) gives `events`'s bits for every law, contact
/// model, mode and function, at states on and off the disk, in and out of the stick band, from
/// the components `event_reads` names alone.
#[test]
fn one_event_function_is_the_events_bits() {
    use crate::ode::OdeSystem;
    let modes =
        [ContactMode::Contact, ContactMode::SlipBack, ContactMode::Free, ContactMode::Stick, ContactMode::Transition];
    for law in [FrictionLaw::Constant, FrictionLaw::Coulomb, FrictionLaw::Switch] {
        for contact in [ContactModel::Bilateral, ContactModel::Unilateral] {
            let p = Params { contact, friction_law: law, mu_static: 0.3, stick_band: 1e-4, ..Params::seed() };
            let s = Slider::new(p).unwrap();
            for k in 0..40 {
                let u = |j: u32| ((k as f64 + 1.0) * (0.37 + 0.11 * j as f64)).sin();
                let y = State::new(
                    30e-6 * u(0),
                    0.02 * u(1),
                    1e-5 * u(2),
                    p.sliding_speed * (1.0 + u(3)),
                    1e-4 * u(4),
                    0.5 * u(5),
                );
                for mode in modes {
                    let mut g = [f64::NAN; MAX_EVENTS];
                    s.events(0.3, &y, mode, &mut g);
                    for (i, gi) in g.iter().enumerate().take(s.n_events()) {
                        let one = s.event(0.3, &y, mode, i);
                        assert_eq!(one.to_bits(), gi.to_bits(), "{law:?} {contact:?} {mode:?} #{i}: {one} vs {gi}");
                        // It reads only the components `event_reads` names.
                        let reads = s.event_reads(i);
                        let only = State::from_fn(|j, _| if reads & (1 << j) != 0 { y[j] } else { f64::NAN });
                        let masked = s.event(0.3, &only, mode, i);
                        assert_eq!(masked.to_bits(), gi.to_bits(), "{law:?} {contact:?} {mode:?} #{i} reads {reads:b}");
                    }
                }
            }
        }
    }
}
