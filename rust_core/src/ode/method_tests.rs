//! Orders of convergence of every method and of its dense output, measured on smooth problems
//! with known behaviour: fixed steps (`driver::integrate_fixed`) against a tight adaptive DOP853
//! reference. Kept apart from the steppers because they need the driver: the steppers are below
//! it, this module is above both (the layering test in `tests/architecture.rs` checks it).

use crate::ode::dop853::Dop853;
use crate::ode::dopri5::Dopri5;
use crate::ode::rodas::Rodas4;
use crate::ode::test_systems::*;
use crate::ode::{Method, OdeSystem};
use nalgebra::SVector;

/// Observed order of convergence of `integrate_fixed` with `method` at step counts `ns`
/// against a tight adaptive DOP853 reference; prints the errors.
fn observed_order<S: OdeSystem<N>, const N: usize>(
    sys: &S,
    method: crate::ode::Method,
    y0: SVector<f64, N>,
    t_end: f64,
    ns: &[usize],
) -> f64 {
    use crate::ode::{driver::integrate_fixed, integrate, Method, NoObserver, Options};
    let reference = integrate(sys, Method::Dop853, 0.0, y0, t_end, &Options::<N>::new(1e-15, 1e-18), &mut NoObserver).y;
    let errs: Vec<f64> =
        ns.iter().map(|&n| (integrate_fixed(sys, method, 0.0, y0, t_end, n) - reference).amax()).collect();
    let p = slope(ns, &errs);
    println!("{method:?}: n {ns:?} errors {} -> order {p:.3}", sci(&errs));
    p
}

/// Error of the dense output at the middle of one step of size `h` from `y0` at `t = 0`
/// against a tight adaptive DOP853 reference.
fn midpoint_error<St, S, const N: usize>(sys: &S, y0: SVector<f64, N>, h: f64) -> f64
where
    S: OdeSystem<N>,
    St: crate::ode::stepper::Stepper<N, S>,
{
    use crate::ode::{integrate, Dense, Method, NoObserver, Options, Stats};
    let mode = sys.initial_mode(0.0, &y0);
    let mut stats = Stats::default();
    let f0 = sys.rhs(0.0, &y0, mode);
    let mut st = St::new();
    st.begin(sys, mode, 0.0, &y0, &f0, &mut stats);
    let atol = SVector::<f64, N>::repeat(1.0);
    let (y1, _) = st.try_step(sys, mode, 0.0, &y0, &f0, h, &atol, 0.0, &mut stats);
    st.finish(sys, mode, 0.0, h, &y1, &mut stats);
    let mid = st.dense(sys, mode, 0.0, h, &y0, &y1).eval(0.5 * h);
    let reference =
        integrate(sys, Method::Dop853, 0.0, y0, 0.5 * h, &Options::<N>::new(1e-15, 1e-18), &mut NoObserver).y;
    (mid - reference).amax()
}

#[test]
fn order_five_on_forced_duffing() {
    // Measured: errors 2.1e-8 .. 6.4e-13 for n = 200 .. 1600, order 4.98.
    let p = observed_order(&DUFFING, Method::Dopri5, SVector::<f64, 2>::new(1.0, 0.0), 10.0, &[200, 400, 800, 1600]);
    assert!((p - 5.0).abs() < 0.3, "observed order {p}");
}

#[test]
fn order_five_on_two_body_problem() {
    // Kepler, e = 0.5, one orbit. Measured: errors 6.1e-7 .. 1.3e-11, order 5.18 (approached
    // from above; at n = 3200 the error, 3e-13, is near the reference's rounding).
    let p =
        observed_order(&Kepler, Method::Dopri5, Kepler::y0(0.5), 2.0 * std::f64::consts::PI, &[200, 400, 800, 1600]);
    assert!((p - 5.0).abs() < 0.3, "observed order {p}");
}

#[test]
fn dense_output_is_fourth_order() {
    // Local interpolation error at mid-step ~ h^5. Measured pairwise orders 4.90, 4.96, 4.98.
    let y0 = SVector::<f64, 2>::new(1.0, 3.0);
    let hs = [0.1, 0.05, 0.025, 0.0125];
    let errs: Vec<f64> = hs.iter().map(|&h| midpoint_error::<Dopri5<2>, _, 2>(&LotkaVolterra, y0, h)).collect();
    assert_dense_order("Dopri5", &errs, 5.0);
}

#[test]
fn order_eight_on_lotka_volterra() {
    // DOP853 reaches rounding fast: few steps over a long interval (t = 20, about 3 cycles),
    // step counts in ratios of sqrt(2). Measured: errors 5e-7 .. 4e-13, order about 8.2.
    let p = observed_order(
        &LotkaVolterra,
        Method::Dop853,
        SVector::<f64, 2>::new(1.0, 3.0),
        20.0,
        &[40, 56, 80, 113, 160, 226],
    );
    assert!((p - 8.0).abs() < 0.3, "observed order {p}");
}

#[test]
fn dense_output_is_seventh_order() {
    // A 7th-order interpolant: local error at mid-step ~ h^8. Measured pairwise orders 7.44, 7.86, 7.97;
    // the finest error (1.3e-14) is still 30 ulps of |y|.
    let y0 = SVector::<f64, 2>::new(1.0, 3.0);
    let hs = [0.4, 0.2, 0.1, 0.05];
    let errs: Vec<f64> = hs.iter().map(|&h| midpoint_error::<Dop853<2>, _, 2>(&LotkaVolterra, y0, h)).collect();
    assert_dense_order("Dop853", &errs, 8.0);
}

#[test]
fn order_four_on_forced_duffing() {
    // Non-autonomous (exercises the df/dt term) with an analytic Jacobian.
    // Measured: errors 1.5e-8 .. 3.4e-12 for n = 200 .. 1600, order 4.03.
    let p = observed_order(&DUFFING, Method::Rodas4, SVector::<f64, 2>::new(1.0, 0.0), 10.0, &[200, 400, 800, 1600]);
    assert!((p - 4.0).abs() < 0.3, "observed order {p}");
}

#[test]
fn dense_output_is_third_order() {
    // Local interpolation error at mid-step ~ h^4. Measured pairwise orders 3.84, 3.93, 3.97.
    let y0 = SVector::<f64, 2>::new(1.0, 3.0);
    let hs = [0.1, 0.05, 0.025, 0.0125];
    let errs: Vec<f64> = hs.iter().map(|&h| midpoint_error::<Rodas4<2>, _, 2>(&LotkaVolterra, y0, h)).collect();
    assert_dense_order("Rodas4", &errs, 4.0);
}
