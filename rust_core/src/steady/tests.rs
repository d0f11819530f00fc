use super::*;
use crate::model::Params;

#[test]
fn amp_phase_convention() {
    // 2 sin(x + 0.3) = 2 sin 0.3 cos x + 2 cos 0.3 sin x
    let (a, b) = (2.0 * 0.3f64.sin(), 2.0 * 0.3f64.cos());
    let (amp, ph) = amp_phase(a, b);
    assert!((amp - 2.0).abs() < 1e-15 && (ph - 0.3).abs() < 1e-15);
    assert!((wrap(-0.1) - (std::f64::consts::TAU - 0.1)).abs() < 1e-15);
}

#[test]
fn characteristic_sizes_follow_static_point() {
    let s = Slider::seed();
    let c = characteristic_sizes(&s);
    assert!((c[0] - 16.5612e-6).abs() < 1e-10);
    assert!((c[4] - 16.5612e-6 / 0.065).abs() < 1e-8);
    let _ = Params::seed();
}

#[test]
fn x_is_left_out_of_the_settling_tests_only_where_it_is_slaved() {
    let off = SteadyOptions { watch_x: false, ..SteadyOptions::default() };
    let constant = Slider::seed();
    assert_eq!(SectionWatcher::new(&off, &constant).comps, &NOT_X[..]);
    assert_eq!(SectionWatcher::new(&SteadyOptions::default(), &constant).comps, &ALL[..]);
    // Speed-dependent friction: x acts back through the sliding velocity, so it is always watched.
    for law in [FrictionLaw::Coulomb, FrictionLaw::Switch] {
        let s = Slider::new(Params { friction_law: law, mu_static: 0.3, ..Params::seed() }).unwrap();
        assert_eq!(SectionWatcher::new(&off, &s).comps, &ALL[..], "{law:?}");
    }
}

#[test]
fn per_component_decay_thresholds_set_the_decay_test() {
    // A small torsion-mode motion of the seed (sliding stable, decaying at 0.33 1/s).
    let s = Slider::seed();
    let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 1e-4, 0.0);
    let sizes = characteristic_sizes(&s);
    let d = 1e-2 * s.z_st.abs();
    let base = SteadyOptions { t_max: 60.0, ..SteadyOptions::default() };
    let plain = run_to_steady(&s, &y0, &SteadyOptions { decay_amplitude: Some(d), ..base });
    // Thresholds in the shape of the characteristic sizes are the same test.
    let same = sizes.map(|c| c * d / sizes[0]);
    let shaped = run_to_steady(&s, &y0, &DecayTest::Thresholds(same).apply(&base));
    assert_eq!(plain.outcome, SteadyOutcome::Decayed);
    assert_eq!(shaped.outcome, SteadyOutcome::Decayed);
    assert_eq!(plain.t_end, shaped.t_end);
    // The torsion motion dominates the measure (phi is 1e-4 rad against |z_st|/L = 2.5e-4 rad for
    // z = 1e-6 m against 1.7e-5 m): thresholds 10x larger in phi and phid alone stop it earlier,
    // by about ln(10) / 0.33 = 7 s.
    let mut wide = same;
    wide[idx::PHI] *= 10.0;
    wide[idx::PHID] *= 10.0;
    let early = run_to_steady(&s, &y0, &DecayTest::Thresholds(wide).apply(&base));
    assert_eq!(early.outcome, SteadyOutcome::Decayed);
    assert!(early.t_end < plain.t_end - 5.0, "{} vs {}", early.t_end, plain.t_end);
    // An amplitude override replaces thresholds.
    let back = DecayTest::Amplitude(d).apply(&DecayTest::Thresholds(wide).apply(&base));
    assert_eq!(back.decay_thresholds, None);
    assert_eq!(run_to_steady(&s, &y0, &back).t_end, plain.t_end);
}
