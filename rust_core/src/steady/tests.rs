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
