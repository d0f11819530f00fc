//! Tests of the Hopf analysis: textbook systems with known first Lyapunov coefficients, the
//! difference schemes' orders, the slider's analytic forms, the one-parameter scan and the curves.

use super::curve::{hopf_curves, CurveOptions, EndStatus, PointType};
use super::scan::{scan, ScanOptions};
use super::slider::{Axis, SliderFamily, SliderField};
use super::*;
use crate::linear::hopf_loads;
use crate::model::{FrictionLaw, Params, Slider, State};
use crate::status::Status;
use nalgebra::{Matrix2, Matrix3, Matrix4, Vector2, Vector3, Vector4};

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// `x' = a x - w y + s x r^2`, `y' = w x + a y + s y r^2` (the Hopf normal form in Cartesian
/// form), at `a = 0`. In `z = x + iy`: `z' = (a + iw) z + s z|z|^2`. With `q = (1, -i)/sqrt 2`
/// (`<q, q> = 1`), `x = 2 Re(v q)` gives `z = sqrt(2) v`, so `v' = (a + iw) v + 2 s v|v|^2`:
/// `c1 = 2 s`, `l1 = 2 s / w`.
struct NormalForm {
    w: f64,
    s: f64,
}

impl VectorField<2> for NormalForm {
    fn rhs(&self, x: &Vector2<f64>) -> Vector2<f64> {
        let r2 = x.norm_squared();
        Vector2::new(-self.w * x[1] + self.s * x[0] * r2, self.w * x[0] + self.s * x[1] * r2)
    }
    fn jacobian(&self, x: &Vector2<f64>) -> Matrix2<f64> {
        let (a, b, s) = (x[0], x[1], self.s);
        let r2 = a * a + b * b;
        Matrix2::new(
            s * (r2 + 2.0 * a * a),
            -self.w + 2.0 * s * a * b,
            self.w + 2.0 * s * a * b,
            s * (r2 + 2.0 * b * b),
        )
    }
    fn bilinear(&self, x: &Vector2<f64>, u: &Vector2<f64>, v: &Vector2<f64>) -> Vector2<f64> {
        // F(x) = s (x.x) x: D^2F[u, v] = 2 s ((x.u) v + (x.v) u + (u.v) x)
        (v * x.dot(u) + u * x.dot(v) + x * u.dot(v)) * (2.0 * self.s)
    }
    fn trilinear(&self, _x: &Vector2<f64>, u: &Vector2<f64>, v: &Vector2<f64>, w: &Vector2<f64>) -> Vector2<f64> {
        // D^3F[u, v, w] = 2 s ((u.v) w + (u.w) v + (v.w) u)
        (w * u.dot(v) + v * u.dot(w) + u * v.dot(w)) * (2.0 * self.s)
    }
}

/// Any field with its forms replaced by the default differences of its Jacobian.
struct Differenced<F>(F);

impl<F: VectorField<N>, const N: usize> VectorField<N> for Differenced<F> {
    fn rhs(&self, x: &SVector<f64, N>) -> SVector<f64, N> {
        self.0.rhs(x)
    }
    fn jacobian(&self, x: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        self.0.jacobian(x)
    }
    fn fd_scale(&self) -> SVector<f64, N> {
        self.0.fd_scale()
    }
}

/// Tolerance of `l1` computed with the default differences: `C` carries a relative error of
/// about `eps^(1/2)` = 1.5e-8 (see the module docs); 1e-7 is that with a factor 7 of margin.
const FD_RTOL: f64 = 1e-7;

#[test]
fn normal_form_l1_is_two_sigma_over_omega() {
    for (s, w) in [(-1.0, 2.0), (1.0, 2.0), (-0.3, 0.5)] {
        for analytic in [true, false] {
            let (f, x0, one) = (NormalForm { w, s }, Vector2::zeros(), Vector2::repeat(1.0));
            let lam = C64::new(0.0, w);
            let nf = if analytic {
                first_lyapunov(&f, &x0, lam, &one)
            } else {
                first_lyapunov(&Differenced(f), &x0, lam, &one)
            };
            let nf = nf.unwrap();
            let expect = 2.0 * s / w;
            // Analytic forms: the formula's own rounding (a few eps on O(1) terms).
            let tol = if analytic { 1e-13 } else { FD_RTOL };
            assert!(rel(nf.l1, expect) < tol, "s = {s}, w = {w}, analytic {analytic}: l1 = {} vs {expect}", nf.l1);
            // c1 = 2 s is real: no frequency shift for this normal form.
            assert!(nf.c1.im.abs() < tol * 2.0 * s.abs(), "{}", nf.c1);
            let crit = if s < 0.0 { Criticality::Supercritical } else { Criticality::Subcritical };
            assert_eq!(Criticality::of(nf.l1, nf.l1_scale), crit);
        }
    }
}

/// Van der Pol `x'' - (mu -+ x^2) x' + x = 0` as `x1' = x2`, `x2' = -x1 + mu x2 + sgn x1^2 x2`, at
/// `mu = 0`. Averaging `x1 = r cos t`: `r' = mu r / 2 + sgn r^3 / 8`. With `q = (1, i)/sqrt 2`,
/// `r = sqrt(2) |v|`, so `|v|' = ... + sgn |v|^3 / 4`: `l1 = sgn / 4` (`w = 1`).
struct VanDerPol {
    sgn: f64,
}

impl VectorField<2> for VanDerPol {
    fn rhs(&self, x: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(x[1], -x[0] + self.sgn * x[0] * x[0] * x[1])
    }
    fn jacobian(&self, x: &Vector2<f64>) -> Matrix2<f64> {
        Matrix2::new(0.0, 1.0, -1.0 + 2.0 * self.sgn * x[0] * x[1], self.sgn * x[0] * x[0])
    }
}

#[test]
fn van_der_pol_is_supercritical_and_its_mirror_subcritical() {
    for (sgn, crit) in [(-1.0, Criticality::Supercritical), (1.0, Criticality::Subcritical)] {
        let nf =
            first_lyapunov(&VanDerPol { sgn }, &Vector2::zeros(), C64::new(0.0, 1.0), &Vector2::repeat(1.0)).unwrap();
        assert!(rel(nf.l1, sgn / 4.0) < FD_RTOL, "sgn {sgn}: l1 = {}", nf.l1);
        assert_eq!(Criticality::of(nf.l1, nf.l1_scale), crit);
    }
}

/// `x' = -w y + f(x, y)`, `y' = w x + g(x, y)` with quadratic and cubic `f`, `g`, against the
/// closed form of Guckenheimer & Holmes (1983, eq. 3.4.11) for `a` in `r' = a r^3`:
/// `a = [f_xxx + f_xyy + g_xxy + g_yyy]/16 + [f_xy (f_xx + f_yy) - g_xy (g_xx + g_yy) - f_xx g_xx
/// + f_yy g_yy] / (16 w)`; `r = sqrt(2)|v|` gives `l1 = 2 a / w`. The quadratic terms exercise the
/// `h11`, `h20` parts of the formula (the slider's nonlinearity is quadratic).
struct Planar {
    w: f64,
    f: [f64; 5], // x^2, xy, y^2, x^3, x y^2
    g: [f64; 5], // x^2, xy, y^2, x^2 y, y^3
}

impl VectorField<2> for Planar {
    fn rhs(&self, v: &Vector2<f64>) -> Vector2<f64> {
        let (x, y, f, g) = (v[0], v[1], &self.f, &self.g);
        Vector2::new(
            -self.w * y + f[0] * x * x + f[1] * x * y + f[2] * y * y + f[3] * x * x * x + f[4] * x * y * y,
            self.w * x + g[0] * x * x + g[1] * x * y + g[2] * y * y + g[3] * x * x * y + g[4] * y * y * y,
        )
    }
    fn jacobian(&self, v: &Vector2<f64>) -> Matrix2<f64> {
        let (x, y, f, g) = (v[0], v[1], &self.f, &self.g);
        Matrix2::new(
            2.0 * f[0] * x + f[1] * y + 3.0 * f[3] * x * x + f[4] * y * y,
            -self.w + f[1] * x + 2.0 * f[2] * y + 2.0 * f[4] * x * y,
            self.w + 2.0 * g[0] * x + g[1] * y + 2.0 * g[3] * x * y,
            g[1] * x + 2.0 * g[2] * y + g[3] * x * x + 3.0 * g[4] * y * y,
        )
    }
}

#[test]
fn planar_quadratic_cubic_matches_guckenheimer_holmes() {
    let cases = [
        (1.0, [0.7, -0.4, 0.3, -0.2, 0.5], [-0.6, 0.25, 0.8, 0.1, -0.3]),
        (2.5, [1.5, 0.0, -1.0, 0.0, 0.0], [0.0, 2.0, 0.5, 0.0, 0.0]),
        (0.8, [0.0, 0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0, -1.0]),
    ];
    for (w, f, g) in cases {
        let (fxx, fxy, fyy, fxxx, fxyy) = (2.0 * f[0], f[1], 2.0 * f[2], 6.0 * f[3], 2.0 * f[4]);
        let (gxx, gxy, gyy, gxxy, gyyy) = (2.0 * g[0], g[1], 2.0 * g[2], 2.0 * g[3], 6.0 * g[4]);
        let a = (fxxx + fxyy + gxxy + gyyy) / 16.0
            + (fxy * (fxx + fyy) - gxy * (gxx + gyy) - fxx * gxx + fyy * gyy) / (16.0 * w);
        let sys = Planar { w, f, g };
        let nf = first_lyapunov(&sys, &Vector2::zeros(), C64::new(0.0, w), &Vector2::repeat(1.0)).unwrap();
        // Terms of size 1: the FD tolerance applies to the scale of the terms, not to l1 itself.
        assert!(
            (nf.l1 - 2.0 * a / w).abs() < FD_RTOL * nf.l1_scale.max(1.0),
            "w {w}: l1 = {} vs {}",
            nf.l1,
            2.0 * a / w
        );
    }
}

/// A pair with a slaved third direction: `x1' = -x2 + x1 x3`, `x2' = x1 + x2 x3`,
/// `x3' = -k x3 + s (x1^2 + x2^2)`. On the centre manifold `x3 = s r^2 / k + O(r^4)`, so
/// `r' = s r^3 / k` and `l1 = 2 s / k` (`w = 1`): all of it comes through `h11 = -A^-1 B(q, conj q)`.
struct Slaved {
    k: f64,
    s: f64,
}

impl VectorField<3> for Slaved {
    fn rhs(&self, x: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(-x[1] + x[0] * x[2], x[0] + x[1] * x[2], -self.k * x[2] + self.s * (x[0] * x[0] + x[1] * x[1]))
    }
    fn jacobian(&self, x: &Vector3<f64>) -> Matrix3<f64> {
        Matrix3::new(x[2], -1.0, x[0], 1.0, x[2], x[1], 2.0 * self.s * x[0], 2.0 * self.s * x[1], -self.k)
    }
}

#[test]
fn slaved_direction_enters_through_the_centre_manifold() {
    for (k, s) in [(3.0, 1.0), (0.5, -1.0)] {
        let nf =
            first_lyapunov(&Slaved { k, s }, &Vector3::zeros(), C64::new(0.0, 1.0), &Vector3::repeat(1.0)).unwrap();
        assert!(rel(nf.l1, 2.0 * s / k) < FD_RTOL, "k {k}: l1 = {}", nf.l1);
    }
}

/// `f(x) = exp(c.x) v + sin(d.x) w`: derivatives of every order in closed form.
struct Smooth;

const CV: [f64; 2] = [0.7, -0.4];
const DV: [f64; 2] = [0.3, 1.1];

impl VectorField<2> for Smooth {
    fn rhs(&self, x: &Vector2<f64>) -> Vector2<f64> {
        let (c, d) = (Vector2::from(CV), Vector2::from(DV));
        Vector2::new(1.0, 2.0) * c.dot(x).exp() + Vector2::new(-1.5, 0.5) * d.dot(x).sin()
    }
    fn jacobian(&self, x: &Vector2<f64>) -> Matrix2<f64> {
        let (c, d) = (Vector2::from(CV), Vector2::from(DV));
        Vector2::new(1.0, 2.0) * c.transpose() * c.dot(x).exp()
            + Vector2::new(-1.5, 0.5) * d.transpose() * d.dot(x).cos()
    }
}

fn smooth_b(x: &Vector2<f64>, u: &Vector2<f64>, v: &Vector2<f64>) -> Vector2<f64> {
    let (c, d) = (Vector2::from(CV), Vector2::from(DV));
    Vector2::new(1.0, 2.0) * (c.dot(x).exp() * c.dot(u) * c.dot(v))
        - Vector2::new(-1.5, 0.5) * (d.dot(x).sin() * d.dot(u) * d.dot(v))
}

fn smooth_c(x: &Vector2<f64>, u: &Vector2<f64>, v: &Vector2<f64>, w: &Vector2<f64>) -> Vector2<f64> {
    let (c, d) = (Vector2::from(CV), Vector2::from(DV));
    Vector2::new(1.0, 2.0) * (c.dot(x).exp() * c.dot(u) * c.dot(v) * c.dot(w))
        - Vector2::new(-1.5, 0.5) * (d.dot(x).cos() * d.dot(u) * d.dot(v) * d.dot(w))
}

#[test]
fn difference_schemes_converge_at_second_order() {
    let (x, u, v, w) =
        (Vector2::new(0.3, -0.2), Vector2::new(0.6, 0.8), Vector2::new(-0.5, 1.0), Vector2::new(1.0, 0.2));
    let (b, c) = (smooth_b(&x, &u, &v), smooth_c(&x, &u, &v, &w));
    // Steps well above the rounding floor (eps/h^2 < 1e-11 at h >= 1e-2.5), so truncation rules.
    let hs = [0.08, 0.04, 0.02, 0.01];
    let eb: Vec<f64> = hs.iter().map(|&h| (fd_bilinear(&Smooth, &x, &u, &v, h) - b).norm()).collect();
    let ec: Vec<f64> = hs.iter().map(|&h| (fd_trilinear(&Smooth, &x, &u, &v, &w, h) - c).norm()).collect();
    for k in 0..3 {
        let (ob, oc) = ((eb[k] / eb[k + 1]).log2(), (ec[k] / ec[k + 1]).log2());
        eprintln!("h = {}: B error {:.3e} (order {ob:.3}), C error {:.3e} (order {oc:.3})", hs[k], eb[k], ec[k]);
        // Order 2, with O(h^2) corrections to the ratio at these steps (h |c|, h |d| <= 0.1).
        assert!((ob - 2.0).abs() < 0.1 && (oc - 2.0).abs() < 0.1, "orders {ob}, {oc}");
    }
    // At the default steps the errors sit at the predicted levels eps^(2/3) and eps^(1/2).
    let eb0 = (Smooth.bilinear(&x, &u, &v) - b).norm() / b.norm();
    let ec0 = (Smooth.trilinear(&x, &u, &v, &w) - c).norm() / c.norm();
    eprintln!("default steps: B {eb0:.2e}, C {ec0:.2e}");
    assert!(eb0 < 10.0 * f64::EPSILON.powf(2.0 / 3.0) && ec0 < 10.0 * f64::EPSILON.sqrt(), "{eb0:e} {ec0:e}");
}

fn law_slider(law: FrictionLaw) -> Slider {
    Slider::new(Params {
        friction_law: law,
        mu_static: 0.3,
        // v_r / eps near 1.5 at the test state: the tanh's curvature terms are alive.
        friction_regularization: 0.3,
        stribeck_velocity: 0.2,
        stick_band: 1e-4,
        ..Params::seed()
    })
    .unwrap()
}

#[test]
fn slider_forms_match_differences_of_its_jacobian() {
    // A state off equilibrium (every term of B and C alive), and directions of the state's scales.
    let y = State::new(2e-6, 1e-3, -1e-6, 0.01, 2e-4, 0.3);
    let dirs = [
        State::new(1e-6, 2e-3, 3e-6, -1e-2, 1e-4, 5e-2),
        State::new(-2e-6, 1e-3, 1e-6, 2e-2, -3e-4, 1e-1),
        State::new(3e-6, -1e-3, -2e-6, 1e-2, 2e-4, -2e-2),
    ];
    for law in [FrictionLaw::Constant, FrictionLaw::Coulomb, FrictionLaw::Switch] {
        let f = SliderField(law_slider(law));
        let d = Differenced(f);
        let (b, bd) = (f.bilinear(&y, &dirs[0], &dirs[1]), d.bilinear(&y, &dirs[0], &dirs[1]));
        let (c, cd) = (f.trilinear(&y, &dirs[0], &dirs[1], &dirs[2]), d.trilinear(&y, &dirs[0], &dirs[1], &dirs[2]));
        // Differences at the default steps, to their rounding floors (a factor 10 above the
        // estimate): the difference of J u loses eps |J u| over the step h = H / (scaled size),
        // so B is good to eps^(2/3) |J u| size_v and C (a second difference) to
        // eps^(1/2) |J u| size_v size_w. |J u| holds the large linear terms (K_s/m u_z ~ 2), so
        // these floors exceed eps^(2/3) |B| and eps^(1/2) |C|; C = 0 for the constant law.
        let sc = f.fd_scale();
        let size = |v: &State| v.iter().zip(sc.iter()).map(|(a, s)| a.abs() / s).fold(0.0, f64::max);
        let ju = (f.jacobian(&y) * dirs[0]).norm();
        let floor_b = 10.0 * f64::EPSILON.powf(2.0 / 3.0) * ju * size(&dirs[1]);
        assert!((b - bd).norm() <= floor_b, "{law:?} B: {b} vs {bd} (floor {floor_b:e})");
        let floor = 10.0 * f64::EPSILON.sqrt() * ju * size(&dirs[1]) * size(&dirs[2]);
        assert!((c - cd).norm() <= floor, "{law:?} C: {c} vs {cd} (floor {floor:e})");
        eprintln!(
            "{law:?}: |B - B_fd| = {:.2e} (floor {floor_b:.2e}), |C - C_fd| = {:.2e} (floor {floor:.2e}), |C| = {:.2e}",
            (b - bd).norm(),
            (c - cd).norm(),
            c.norm()
        );
        assert_eq!(c.norm() == 0.0, law == FrictionLaw::Constant, "{law:?}: C = 0 only for the constant law");
        // Tighter: C against the central difference of the analytic B along w, whose floor is
        // eps^(2/3) |B| size_w (no large linear terms) and truncation O(h^2) below it.
        let hw = H_BILINEAR / size(&dirs[2]);
        let cb = (f.bilinear(&(y + dirs[2] * hw), &dirs[0], &dirs[1])
            - f.bilinear(&(y - dirs[2] * hw), &dirs[0], &dirs[1]))
            / (2.0 * hw);
        let floor_c = 10.0 * f64::EPSILON.powf(2.0 / 3.0) * b.norm() * size(&dirs[2]);
        eprintln!("{law:?}: |C - dB/dw| = {:.2e} (floor {floor_c:.2e})", (c - cb).norm());
        assert!((c - cb).norm() <= floor_c, "{law:?} C: {c} vs dB {cb}");
        // B is symmetric.
        let bt = f.bilinear(&y, &dirs[1], &dirs[0]);
        assert!((b - bt).norm() <= 1e-14 * b.norm());
    }
}

fn seed_family(mu: f64) -> SliderFamily {
    SliderFamily { base: Params { mu, ..Params::seed() }, axes: vec![Axis::field("normal_load")] }
}

#[test]
fn seed_hopf_point_is_subcritical_and_agrees_with_hopf_loads() {
    let fam = seed_family(0.215);
    let sc = scan(&fam, 1.0, 250.0, &ScanOptions::default()).unwrap();
    let hopf: Vec<_> = sc.crossings.iter().filter(|c| c.hopf).collect();
    assert_eq!(hopf.len(), 1, "{:?}", sc.crossings);
    let h = hopf[0];
    let reference = hopf_loads(&fam.base, 1.0, 250.0, 60).unwrap()[0].normal_load;
    eprintln!(
        "Hopf at {:.9} N (hopf_loads {reference:.9}), w = {:.4}, l1 = {:.6e} m^-2, dlambda/dF = {:.4e}, {} eigen, {} jac",
        h.value,
        h.lambda.im,
        h.normal_form.unwrap().l1,
        h.dlambda,
        sc.counters.n_eig,
        sc.counters.n_jac
    );
    // Brent in hopf_loads closes to 1e-10 relative; the scan to 1e-13 of the range.
    assert!(rel(h.value, reference) < 1e-9);
    assert!(rel(h.value, 24.904) < 1e-4, "MODEL.md §4: 24.904 N");
    assert_eq!(h.status, Status::Success);
    assert_eq!(h.criticality, Criticality::Subcritical, "MODEL.md §6: subcritical");
    assert_eq!(h.mode, crate::linear::ModeKind::Torsion as u8);
    assert!(h.dlambda.re < 0.0, "unstable below the load, stable above");
    assert_eq!(h.other_unstable, 0);
    // The same l1 with differenced forms: the analytic ones are right.
    let f = fam.field(&[h.value]).unwrap();
    let w = fam.weights(&f, h.lambda.im);
    let fd = first_lyapunov(&Differenced(f), &State::zeros(), h.lambda, &w).unwrap();
    assert!(rel(fd.l1, h.normal_form.unwrap().l1) < 1e-6, "{} vs {}", fd.l1, h.normal_form.unwrap().l1);
}

#[test]
fn coulomb_friction_changes_l1_smoothly() {
    // With a flat Stribeck curve (mu_s = mu) and V >> eps, the Coulomb law's G is mu tanh(V/eps):
    // its slope at V vanishes to exp(-2 V/eps), so l1 is the constant law's times tanh(V/eps).
    let fam_c = seed_family(0.215);
    let fam_t = SliderFamily {
        base: Params { friction_law: FrictionLaw::Coulomb, friction_regularization: 1e-3, ..fam_c.base },
        axes: fam_c.axes.clone(),
    };
    let (a, b) = (
        scan(&fam_c, 10.0, 40.0, &ScanOptions::default()).unwrap(),
        scan(&fam_t, 10.0, 40.0, &ScanOptions::default()).unwrap(),
    );
    let (ha, hb) = (&a.crossings[0], &b.crossings[0]);
    let th = (0.46f64 / 1e-3).tanh();
    // tanh(460) = 1 to rounding: the two fields are the same function to 1e-15.
    assert!(rel(hb.value, ha.value) < 1e-10 && rel(hb.normal_form.unwrap().l1, ha.normal_form.unwrap().l1 * th) < 1e-8);
}

/// Two decoupled oscillators over parameters `(a, b)`: pair 1 with `mu1 = 1 - a^2 - b^2`,
/// `w1 = 1 + a/4` and cubic coefficient `s1 = b` (Hopf curve: the unit circle; `l1 = 2b/w1`, Bautin
/// at `(+-1, 0)`); pair 2 with `mu2 = a - 1/2`, `w2 = 3`, `s2 = -1` (Hopf line `a = 1/2`,
/// `l1 = -2/3`). They meet (double Hopf) at `(1/2, +-sqrt(3)/2)`.
struct TwoOsc {
    a: f64,
    b: f64,
}

impl TwoOsc {
    fn coef(&self) -> [(f64, f64, f64); 2] {
        let (a, b) = (self.a, self.b);
        [(1.0 - a * a - b * b, 1.0 + 0.25 * a, b), (a - 0.5, 3.0, -1.0)]
    }
}

impl VectorField<4> for TwoOsc {
    fn rhs(&self, x: &Vector4<f64>) -> Vector4<f64> {
        let mut out = Vector4::zeros();
        for (k, (m, w, s)) in self.coef().into_iter().enumerate() {
            let (p, q) = (x[2 * k], x[2 * k + 1]);
            let r2 = p * p + q * q;
            out[2 * k] = m * p - w * q + s * p * r2;
            out[2 * k + 1] = w * p + m * q + s * q * r2;
        }
        out
    }
    fn jacobian(&self, x: &Vector4<f64>) -> Matrix4<f64> {
        let mut j = Matrix4::zeros();
        for (k, (m, w, s)) in self.coef().into_iter().enumerate() {
            let (p, q, i) = (x[2 * k], x[2 * k + 1], 2 * k);
            let r2 = p * p + q * q;
            j[(i, i)] = m + s * (r2 + 2.0 * p * p);
            j[(i, i + 1)] = -w + 2.0 * s * p * q;
            j[(i + 1, i)] = w + 2.0 * s * p * q;
            j[(i + 1, i + 1)] = m + s * (r2 + 2.0 * q * q);
        }
        j
    }
}

struct TwoOscFamily {
    fixed_b: f64,
}

impl Family<4> for TwoOscFamily {
    type Field = TwoOsc;
    fn field(&self, p: &[f64]) -> Result<TwoOsc, String> {
        Ok(TwoOsc { a: p[0], b: p.get(1).copied().unwrap_or(self.fixed_b) })
    }
}

#[test]
fn scan_finds_every_crossing_and_a_pair_inside_one_cell() {
    // b = 0.3: pair 1 crosses at a = -+sqrt(0.91), pair 2 at a = 1/2.
    let sc = scan(&TwoOscFamily { fixed_b: 0.3 }, -1.5, 1.5, &ScanOptions::default()).unwrap();
    let r = 0.91f64.sqrt();
    let want = [(-r, 2.0 * 0.3 / (1.0 - 0.25 * r)), (0.5, -2.0 / 3.0), (r, 2.0 * 0.3 / (1.0 + 0.25 * r))];
    assert_eq!(sc.crossings.len(), 3, "{:?}", sc.crossings);
    for (c, (a, l1)) in sc.crossings.iter().zip(want) {
        // The located value to the 1e-13 relative bracket (times the range 3), l1 to the FD tolerance.
        assert!((c.value - a).abs() < 1e-12, "{} vs {a}", c.value);
        assert!(rel(c.normal_form.unwrap().l1, l1) < FD_RTOL, "{} vs {l1}", c.normal_form.unwrap().l1);
        assert_eq!(c.status, Status::Success);
    }
    // b = 0.999 on a 4-point grid: both crossings of pair 1 (a = +-0.0447) lie in the cell
    // [-0.5, 0.5], where mu1 is negative at both ends. The Hermite test must split it.
    let opts = ScanOptions { n_points: 4, ..ScanOptions::default() };
    let sc = scan(&TwoOscFamily { fixed_b: 0.999 }, -1.5, 1.5, &opts).unwrap();
    let r = (1.0f64 - 0.999 * 0.999).sqrt();
    let pair1: Vec<f64> = sc.crossings.iter().filter(|c| (c.lambda.im - 3.0).abs() > 0.5).map(|c| c.value).collect();
    assert_eq!(pair1.len(), 2, "{:?}", sc.crossings);
    assert!((pair1[0] + r).abs() < 1e-12 && (pair1[1] - r).abs() < 1e-12, "{pair1:?}");
}

#[test]
fn circle_is_closed_with_its_bautin_and_double_hopf_points() {
    let opts = CurveOptions { grid: [8, 8], marks: [vec![0.0], vec![]], ..CurveOptions::default() };
    let res = hopf_curves(&TwoOscFamily { fixed_b: 0.0 }, [[-1.5, 1.5], [-1.5, 1.5]], &opts).unwrap();
    assert_eq!(
        res.curves.len(),
        2,
        "{} seeds -> {:?}",
        res.n_seeds,
        res.curves.iter().map(|c| &c.ends).collect::<Vec<_>>()
    );
    assert!(res.n_seeds > 2, "several seeds per curve were deduplicated");
    let (circle, line): (Vec<_>, Vec<_>) = res.curves.iter().partition(|c| (c.points[0].lambda.im - 3.0).abs() > 0.5);
    let (circle, line) = (circle[0], line[0]);
    // The circle: closed, every point on it to the corrector tolerance (1e-10 box units = 3e-10).
    assert_eq!(circle.ends[0].0, EndStatus::Closed);
    assert_eq!(circle.points.last().unwrap().kind, PointType::Closure);
    for p in &circle.points {
        let [a, b] = p.u;
        assert!((a.hypot(b) - 1.0).abs() < 1e-9, "{:?}", p.u);
        assert!(p.lambda.re.abs() < 1e-9 && (p.lambda.im - (1.0 + 0.25 * a)).abs() < 1e-9);
        if p.criticality != Criticality::Degenerate {
            assert!(rel(p.l1, 2.0 * b / (1.0 + 0.25 * a)) < FD_RTOL * 10.0 || p.l1.abs() < 1e-7, "{:?}", p);
        }
    }
    // The polyline keeps within chord_tol of the circle (box units: radius 1/3 about the centre);
    // h angle / 8 is the exact bulge of a circular arc to second order in the angle.
    let boxed = |u: [f64; 2]| [(u[0] + 1.5) / 3.0 - 0.5, (u[1] + 1.5) / 3.0 - 0.5];
    let worst = circle
        .points
        .windows(2)
        .map(|w| {
            let (a, b) = (boxed(w[0].u), boxed(w[1].u));
            1.0 / 3.0 - (0.5 * (a[0] + b[0])).hypot(0.5 * (a[1] + b[1]))
        })
        .fold(0.0, f64::max);
    assert!(worst <= 1.01 * opts.chord_tol, "bulge {worst:e} > chord_tol {:e}", opts.chord_tol);
    let kinds = |c: &super::curve::Curve, k: PointType| {
        c.points.iter().filter(|p| p.kind == k).map(|p| p.u).collect::<Vec<_>>()
    };
    let bautin = kinds(circle, PointType::Bautin);
    assert_eq!(bautin.len(), 2, "{bautin:?}");
    for u in &bautin {
        // Located by the Illinois method to 1e-10 in arclength: b = 0 to that.
        assert!(u[1].abs() < 1e-9 && (u[0].abs() - 1.0).abs() < 1e-9, "{u:?}");
    }
    let dh = kinds(circle, PointType::DoubleHopf);
    assert_eq!(dh.len(), 2, "{dh:?}");
    for u in &dh {
        assert!((u[0] - 0.5).abs() < 1e-9 && (u[1].abs() - 0.75f64.sqrt()).abs() < 1e-9, "{u:?}");
    }
    let marks = kinds(circle, PointType::Mark);
    assert_eq!(marks.len(), 2);
    assert!(marks.iter().all(|u| u[0].abs() < 1e-9 && (u[1].abs() - 1.0).abs() < 1e-9), "{marks:?}");
    // The line a = 1/2 leaves through the top and the bottom faces, supercritical all along.
    assert_eq!((line.ends[0].0, line.ends[1].0), (EndStatus::LeftBox, EndStatus::LeftBox));
    let exits = kinds(line, PointType::BoxExit);
    assert_eq!(exits.len(), 2);
    assert!(exits.iter().all(|u| (u[0] - 0.5).abs() < 1e-9 && (u[1].abs() - 1.5).abs() < 1e-12), "{exits:?}");
    assert!(line.points.iter().all(|p| p.criticality == Criticality::Supercritical && rel(p.l1, -2.0 / 3.0) < FD_RTOL));
    assert_eq!(kinds(line, PointType::DoubleHopf).len(), 2);
}

#[test]
fn arc_leaving_the_box_ends_on_its_faces() {
    // The right half of the circle in [0, 1.5] x [-1.5, 1.5]: it leaves through the face a = 0 at
    // b = +-1 (the line a = 1/2 is the other curve).
    let opts = CurveOptions { grid: [6, 6], ..CurveOptions::default() };
    let res = hopf_curves(&TwoOscFamily { fixed_b: 0.0 }, [[0.0, 1.5], [-1.5, 1.5]], &opts).unwrap();
    let arc = res.curves.iter().find(|c| (c.points[0].lambda.im - 3.0).abs() > 0.5).unwrap();
    assert_eq!((arc.ends[0].0, arc.ends[1].0), (EndStatus::LeftBox, EndStatus::LeftBox), "{:?}", arc.ends);
    let (first, last) = (arc.points.first().unwrap(), arc.points.last().unwrap());
    for p in [first, last] {
        assert_eq!(p.kind, PointType::BoxExit);
        assert!(p.u[0].abs() < 1e-12 && (p.u[1].abs() - 1.0).abs() < 1e-9, "{:?}", p.u);
    }
    assert!(first.u[1] * last.u[1] < 0.0, "one exit at b = -1, one at b = +1");
    assert!(!arc.ends[0].1.is_empty() && !arc.ends[1].1.is_empty());
}

#[test]
fn seed_hopf_curve_in_load_and_mu_passes_through_model_md() {
    let fam = SliderFamily { base: Params::seed(), axes: vec![Axis::field("normal_load"), Axis::field("mu")] };
    let mus = vec![0.2, 0.215, 0.25, 0.3, 0.35];
    let opts = CurveOptions { grid: [8, 8], marks: [vec![], mus.clone()], ..CurveOptions::default() };
    let res = hopf_curves(&fam, [[1.0, 250.0], [0.15, 0.4]], &opts).unwrap();
    assert_eq!(res.curves.len(), 1, "{:?}", res.curves.iter().map(|c| &c.ends).collect::<Vec<_>>());
    let c = &res.curves[0];
    let marks: Vec<_> = c.points.iter().filter(|p| p.kind == PointType::Mark).collect();
    assert_eq!(marks.len(), 5);
    for (p, load) in marks.iter().zip([4.162, 24.904, 74.514, 148.277, 225.364]) {
        // MODEL.md's loads carry 3 decimals: half a unit of the last digit relative to 4.162 N is 1.2e-4.
        assert!((p.u[0] - load).abs() <= 5e-4, "{:?} vs {load}", p.u);
        assert_eq!(p.criticality, Criticality::Subcritical);
    }
    eprintln!("{} points, {} eigen, ends {:?}", c.points.len(), res.counters.n_eig, c.ends);
}

/// `x' = b x - a y - x r^2`, `y' = a x + b y - y r^2`: a Hopf line `b = 0` whose frequency `a` falls
/// to zero at `a = 0`, inside the box (there the pair turns into a double real eigenvalue).
struct Slowing {
    a: f64,
    b: f64,
}

impl VectorField<2> for Slowing {
    fn rhs(&self, x: &Vector2<f64>) -> Vector2<f64> {
        let r2 = x.norm_squared();
        Vector2::new(self.b * x[0] - self.a * x[1] - x[0] * r2, self.a * x[0] + self.b * x[1] - x[1] * r2)
    }
    fn jacobian(&self, x: &Vector2<f64>) -> Matrix2<f64> {
        let (p, q) = (x[0], x[1]);
        let r2 = p * p + q * q;
        Matrix2::new(self.b - r2 - 2.0 * p * p, -self.a - 2.0 * p * q, self.a - 2.0 * p * q, self.b - r2 - 2.0 * q * q)
    }
}

struct SlowingFamily;

impl Family<2> for SlowingFamily {
    type Field = Slowing;
    fn field(&self, p: &[f64]) -> Result<Slowing, String> {
        Ok(Slowing { a: p[0], b: p[1] })
    }
}

#[test]
fn a_vanishing_frequency_ends_the_curve_with_a_status_and_a_reason() {
    let opts = CurveOptions { grid: [5, 5], ..CurveOptions::default() };
    let res = hopf_curves(&SlowingFamily, [[-0.5, 1.0], [-1.0, 1.0]], &opts).unwrap();
    // The upper half (a > 0) and its mirror (a < 0, where the pair's upper member is b - ia).
    let right = res.curves.iter().find(|c| c.points.iter().all(|p| p.u[0] > 0.0)).expect("the a > 0 half");
    let (start, end) = (&right.ends[0], &right.ends[1]);
    let (near_zero, far) = if right.points[0].u[0] < 0.5 { (start, end) } else { (end, start) };
    assert_eq!(far.0, EndStatus::LeftBox);
    // At a = 0 the tracked eigenvalue either falls below the frequency floor or stops being simple
    // (the step then halves to its floor): both end the curve with a status and a reason.
    assert!(matches!(near_zero.0, EndStatus::FrequencyVanished | EndStatus::StepFloor), "{near_zero:?}");
    assert!(!near_zero.1.is_empty());
    let tip = if right.points[0].u[0] < 0.5 { &right.points[0] } else { right.points.last().unwrap() };
    assert_eq!(tip.kind, PointType::End);
    // It got within a step floor's reach of a = 0 (box units 1.5 wide; the floor is 1e-7).
    assert!(tip.u[0] < 1e-3 && tip.u[1].abs() < 1e-9, "{:?}", tip.u);
    assert!(right.points.iter().all(|p| p.criticality == Criticality::Supercritical || p.kind == PointType::End));
}
