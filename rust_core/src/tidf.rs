//! Triple-input describing function of the report's chapter IV (MODEL.md §5, report eqs 34-49).
//!
//! Ansatz `z = A0 + A1 sin(psi) + A2 sin(2 psi + theta)`, `psi = w t`. With the describing functions
//! of `K_a z^2`
//!
//! ```text
//! N1 = K_a [(2 A0 - A2 sin theta) + j A2 cos theta]
//! N2 = K_a [(2 A0 - A1^2/(2 A2) sin theta) - j A1^2/(2 A2) cos theta]
//! ```
//!
//! and the linear part `l_k(w) = m L_z(jkw) [1 - s mu L K_phi / (I L_t(jkw))] + K_s + j k w C_zc`,
//! the harmonic balance is `l_k(w) = N_k` for `k = 1, 2` (two complex equations, MODEL.md §5 in
//! consistent units) plus one real mean (DC) balance: five real equations in
//! `(w, A0, A1, A2, theta)`.
//!
//! Readings of the DC balance ([`Variant`]):
//! - `Consistent` (default): the mean of the equations of MODEL.md §2 with the arm spring carrying
//!   the mean dynamic force, `-K_s A0 + K_a (A0^2 + (A1^2+A2^2)/2) + K_phi phi0 - m w_z^2 A0 = 0`,
//!   `phi0 = s (L/I) mu m w_z^2 A0 / w_t^2`; it is `l_0 A0 = N0 A0`, the `k = 0` member of the family.
//! - `DeadLoad`: the report's eq 46 (mean dynamic contact force zero; the block free to creep),
//!   `-K_s A0 + K_a (A0^2 + (A1^2+A2^2)/2) = 0`.
//!
//! The printed ("literal") reading is not offered: eqs 44-45 as printed add `K_s`, `N_k` [N/m] to
//! `L_z` [1/s^2] and carry an extra factor `m` on `K_phi`, so their roots move with the unit system
//! (in grams instead of kilograms every root changes): they have no unit-independent solution set.
//! Its `N2` (`A1^2/(2 A0) cos theta`) also breaks the invariance `(A2, theta) -> (-A2, theta + pi)`,
//! so it is not even a function of the waveform `z(t)`. MODEL.md §5 also shows that the report's
//! printed solution is not a root of the printed equations in any reading.
//!
//! **All roots** ([`Tidf::find_roots`]). MODEL.md §5 suggests a grid over `(w, theta)`: per cell,
//! eq k=1 gives `A2`, `A0` in closed form, Re of eq k=2 gives `A1^2`, and the two remaining residuals
//! are scanned for sign changes. The `theta` direction of that scan can be done exactly: with
//! `l_k = R_k + j I_k`, `c = cos theta`, `s = sin theta`, the remaining Im of eq k=2 times `sin theta`
//! is *linear* in `(c, s)`,
//!
//! ```text
//! s (I_1 + I_2) + c (R_1 - R_2) = 0   =>   (c, s) = +-(I_1 + I_2, R_2 - R_1) / |.|
//! ```
//!
//! (the sign is the symmetry `(A2, theta) -> (-A2, theta + pi)`), and then
//!
//! ```text
//! K_a A2 = I_1 / c,   2 K_a A0 = U / c,   K_a^2 A1^2 = -2 I_1 I_2 / c^2,   U = R_1 c + I_1 s,
//! g(w) = 4 c^2 K_a (DC residual) = 2 alpha U c + U^2 - 4 I_1 I_2 + 2 I_1^2
//! ```
//!
//! with `alpha` the DC coefficient of `A0`. So the `(w, theta)` grid collapses to a grid in `w`
//! alone: every root is a zero of the smooth function `g(w)` with `I_1 I_2 < 0` (`A1^2 > 0`).
//! `g` is sampled on a log-spaced grid refined around the torsional resonances `w = w_t` and
//! `w = w_t / 2` (where `l_1`, `l_2` vary fastest), each sign change is refined by Brent's method,
//! and the closed-form point is polished by Newton on all five equations, canonicalised,
//! deduplicated and checked. A zero of `g` whose `|A1^2|` is below `amp_resolution^2` is a root
//! that the describing function cannot resolve (the small-amplitude branch at a Hopf point, where
//! `A1^2` changes sign): it is reported as "below resolution", not as a root and not as "none".

use crate::linear::{brent, linear_stability, ModeKind};
use crate::model::{ParamError, Params, Slider};
use crate::status::Status;
use nalgebra::{Complex, SMatrix, SVector};
use std::f64::consts::PI;

type C64 = Complex<f64>;
/// The unknowns `[w, A0, A1, A2, theta]` (rad/s, m, m, m, rad).
pub type Unknowns = SVector<f64, 5>;
/// Five residuals (see [`Tidf::residual`]).
pub type Residual = SVector<f64, 5>;
/// Jacobian of the residuals with respect to [`Unknowns`].
pub type TidfJacobian = SMatrix<f64, 5, 5>;

/// Indices into [`Unknowns`].
pub mod var {
    /// w [rad/s]
    pub const W: usize = 0;
    /// A0 [m]
    pub const A0: usize = 1;
    /// A1 [m]
    pub const A1: usize = 2;
    /// A2 [m]
    pub const A2: usize = 3;
    /// theta [rad]
    pub const THETA: usize = 4;
}

/// Reading of the mean (DC) balance (MODEL.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Variant {
    /// Fixed block: the arm spring carries the mean dynamic force (what the ODE of MODEL.md §2 implies).
    #[default]
    Consistent,
    /// Report eq 46: mean dynamic contact force zero (dead load, block free to creep).
    DeadLoad,
}

impl Variant {
    /// Name as used in the Python API.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Consistent => "consistent",
            Variant::DeadLoad => "dead_load",
        }
    }
}

/// The describing-function equations of one slider, with its constants precomputed.
#[derive(Clone, Copy, Debug)]
pub struct Tidf {
    /// Reading of the DC balance.
    pub variant: Variant,
    /// m [kg]
    m: f64,
    /// K_s [N/m]
    pub k_s: f64,
    /// K_a [N/m^2]
    pub k_a: f64,
    /// C_zc [N s/m]
    c_zc: f64,
    /// gamma = s mu L K_phi / I [1/s^2]
    gamma: f64,
    /// s mu (L/I) m [1/m] (phi phasor gain)
    phi_gain: f64,
    mu: f64,
    wz: f64,
    zz: f64,
    wt: f64,
    zt: f64,
    wx: f64,
    zx: f64,
    /// Coefficient of A0 in the DC balance [N/m].
    alpha: f64,
    /// z_st [m] (< 0)
    pub z_st: f64,
    /// Residual scales: eqs k=1,2 are divided by K_s, the DC balance by K_s |z_st|.
    inv_ks: f64,
    inv_ks_a: f64,
    /// Scales of the unknowns used by Newton: w_t for w, |z_st| for amplitudes.
    w_ref: f64,
    a_ref: f64,
}

/// Options of the damped Newton solver [`Tidf::solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    /// Most iterations.
    pub max_iter: u32,
    /// Converged when a full step is below this in the scaled unknowns (`w / w_t`, `A / |z_st|`,
    /// `theta`), infinity norm.
    pub xtol: f64,
    /// Converged when the scaled residual (see [`Tidf::residual`]) is below this, infinity norm.
    pub ftol: f64,
    /// Largest scaled step (infinity norm) before damping; larger Newton steps are shortened.
    pub max_step: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions { max_iter: 40, xtol: 1e-12, ftol: 1e-14, max_step: 0.5 }
    }
}

/// Result of a Newton solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonResult {
    /// Last iterate (the root on success), not canonicalised.
    pub x: Unknowns,
    /// Infinity norm of the scaled residual at `x`.
    pub residual_norm: f64,
    /// Iterations (Jacobian evaluations) spent.
    pub iterations: u32,
    /// `Success`, `NewtonNotConverged` (no progress, singular Jacobian or `max_iter` reached) or
    /// `NonFinite`.
    pub status: Status,
}

/// One describing-function root with its derived quantities (MODEL.md §5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Root {
    /// Unknowns in canonical form: `w > 0`, `A1 > 0`, `A2 > 0`, `theta` in `[0, 2 pi)`.
    pub x: Unknowns,
    /// w [rad/s]
    pub omega: f64,
    /// A0 [m]
    pub a0: f64,
    /// A1 [m]
    pub a1: f64,
    /// A2 [m]
    pub a2: f64,
    /// theta [rad], phase of the second harmonic relative to `z1`.
    pub theta: f64,
    /// Mean twist [rad]: `s mu (L/I) F_z0 / w_t^2` with the mean dynamic contact force `F_z0`
    /// (`m w_z^2 A0` in the consistent reading, 0 in the dead-load reading).
    pub phi0: f64,
    /// Mean of `x` [m]: `mu F_z0 / (m w_x^2)`.
    pub x0: f64,
    /// Fundamental of `phi` as a phasor relative to `z1`: `s mu (L/I) m L_z(jw) A1 / L_t(jw)` [rad].
    pub phi1: C64,
    /// Second harmonic of `phi`: `s mu (L/I) m L_z(2jw) A2 e^{j theta} / L_t(2jw)` [rad].
    pub phi2: C64,
    /// Fundamental of `x`: `mu L_z(jw) A1 / L_x(jw)` [m].
    pub x1: C64,
    /// Second harmonic of `x`: `mu L_z(2jw) A2 e^{j theta} / L_x(2jw)` [m].
    pub x2: C64,
    /// `|phi1|` [rad] and its phase in `(-pi, pi]` [rad] (`|phi1| sin(psi + phase)`).
    pub phi1_amp: f64,
    /// Phase of `phi1` [rad].
    pub phi1_phase: f64,
    /// `|x1|` [m].
    pub x_amp: f64,
    /// Phase of `x1` [rad].
    pub x_phase: f64,
    /// Largest dynamic `z` over a period of the two-harmonic waveform [m].
    pub z_max: f64,
    /// True if `z_st + z_max > 0`: the pin would leave the disk (the bilateral law, and this
    /// describing function, are then outside their validity).
    pub contact_opens: bool,
    /// `|A0| < |z_st|` and `w` within `physical_band` of the torsion mode's `Im(lambda)`.
    pub physical: bool,
    /// Amplitudes of the first three harmonics of `F_z` [N]: `|m L_z(jw) A1|`, `|m L_z(2jw) A2|`,
    /// and the third harmonic the describing function drops, `K_a A1 A2` (from `K_a z^2`).
    pub fz_harmonics: [f64; 3],
    /// Truncation check: `fz_harmonics[2] / hypot(fz_harmonics[0], fz_harmonics[1])`.
    pub third_harmonic_ratio: f64,
    /// Infinity norm of the scaled residual at the root.
    pub residual_norm: f64,
    /// Newton iterations of the final polish.
    pub newton_iterations: u32,
    /// `Success`, or the Newton status if the polish failed (the root is then kept only if its
    /// residual still passes the check).
    pub status: Status,
}

/// A zero of the reduced function whose amplitude is below what the search resolves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unresolved {
    /// Frequency of the zero [rad/s].
    pub omega: f64,
    /// `A1^2` there [m^2] (either sign: a real root if positive).
    pub a1_squared: f64,
}

/// What an all-roots search found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SearchOutcome {
    /// At least one resolved root.
    Roots,
    /// No root in the box, and nothing below resolution.
    NoRoot,
    /// No resolved root, but a zero of the reduced function with `A1` below `amp_resolution`, or
    /// the linearised system is marginal: a root may exist at amplitudes the search cannot resolve.
    BelowResolution,
}

impl SearchOutcome {
    /// Short machine name.
    pub fn name(self) -> &'static str {
        match self {
            SearchOutcome::Roots => "roots",
            SearchOutcome::NoRoot => "no_root",
            SearchOutcome::BelowResolution => "below_resolution",
        }
    }
}

/// Options of [`Tidf::find_roots`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchOptions {
    /// Lower end of the frequency box [rad/s].
    pub w_min: f64,
    /// Upper end of the frequency box [rad/s].
    pub w_max: f64,
    /// Log-spaced base grid: this many points over `[w_min, w_max]`.
    pub n_base: usize,
    /// Near the torsional resonances the step is at most `kappa |L_t| / |dL_t/dw|` (`k = 1, 2`).
    pub kappa: f64,
    /// Zeros with `|A1| < amp_resolution` are reported as below resolution [m].
    pub amp_resolution: f64,
    /// The linearised system counts as marginal when `|max Re(lambda)| < marginal_tol * Im(lambda)`.
    pub marginal_tol: f64,
    /// Two roots are the same when their scaled unknowns differ by less than this.
    pub dedup_tol: f64,
    /// A root is kept when its scaled residual is below this after the Newton polish.
    pub residual_tol: f64,
    /// Relative band around the torsion mode's frequency for the `physical` flag (MODEL.md §5: 5 %).
    pub physical_band: f64,
    /// Newton options of the polish.
    pub newton: NewtonOptions,
}

impl Default for SearchOptions {
    fn default() -> Self {
        SearchOptions {
            w_min: 150.0,
            w_max: 3000.0,
            n_base: 1000,
            kappa: 0.25,
            amp_resolution: 1e-9,
            marginal_tol: 1e-6,
            dedup_tol: 1e-7,
            residual_tol: 1e-10,
            physical_band: 0.05,
            newton: NewtonOptions::default(),
        }
    }
}

impl SearchOptions {
    /// The same options on a grid `factor` times finer (more base points, smaller `kappa`).
    pub fn refined(&self, factor: f64) -> Self {
        SearchOptions { n_base: (self.n_base as f64 * factor).ceil() as usize, kappa: self.kappa / factor, ..*self }
    }
}

/// Result of an all-roots search.
#[derive(Clone, Debug, PartialEq)]
pub struct RootSearch {
    /// Resolved roots, canonical, sorted by `w`.
    pub roots: Vec<Root>,
    /// Zeros below the amplitude resolution (see [`SearchOutcome::BelowResolution`]), sorted by `w`.
    pub unresolved: Vec<Unresolved>,
    /// Summary.
    pub outcome: SearchOutcome,
    /// Largest real part of the linearised system's eigenvalues [1/s] (> 0: sliding unstable).
    pub max_growth_rate: f64,
    /// Frequency of the torsion mode `Im(lambda)` [rad/s] (reference of the `physical` flag).
    pub torsion_frequency: f64,
    /// True when the linearised system is marginal (see [`SearchOptions::marginal_tol`]).
    pub near_marginal: bool,
    /// Zeros of the reduced function that were discarded because `A1^2 < 0` (no real root; on
    /// the unstable side of a Hopf point the torsion branch ends up here), sorted by `w`.
    pub complex_amplitude: Vec<Unresolved>,
    /// Grid points sampled.
    pub n_grid: usize,
    /// `Success`, `InvalidInput` (bad box or `K_a = 0`: no describing function), or `NonFinite`.
    pub status: Status,
}

/// The theta-eliminated closed form at one frequency (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reduced {
    /// `g(w) = 4 c^2 K_a (DC residual)` [(N/m)^2]: its zeros are the roots.
    pub g: f64,
    /// Unknowns at this `w` (theta canonical, `A2 >= 0`); `A1` is `sqrt(max(A1^2, 0))`.
    pub x: Unknowns,
    /// `A1^2` [m^2], possibly negative.
    pub a1_squared: f64,
}

#[inline]
fn osc(k: f64, w: f64, wn: f64, zeta: f64) -> (C64, C64) {
    // L(jkw) = -(kw)^2 + wn^2 + 2j zeta wn kw and its derivative with respect to w.
    let kw = k * w;
    (C64::new(wn * wn - kw * kw, 2.0 * zeta * wn * kw), C64::new(-2.0 * k * kw, 2.0 * zeta * wn * k))
}

/// Wrap an angle into `[0, 2 pi)`.
#[inline]
fn wrap_2pi(a: f64) -> f64 {
    let r = a.rem_euclid(2.0 * PI);
    if r >= 2.0 * PI {
        0.0
    } else {
        r
    }
}

impl Tidf {
    /// The equations of `slider` in reading `variant`.
    pub fn new(slider: &Slider, variant: Variant) -> Self {
        let p = &slider.p;
        let gamma = p.torsion_sign * p.mu * p.moment_arm * p.twist_coupling / p.inertia;
        let wz = p.omega_normal;
        let wt = p.omega_torsion;
        let alpha = match variant {
            // -K_s - m w_z^2 + K_phi phi0 / A0, phi0 = s (L/I) mu m w_z^2 A0 / w_t^2 (MODEL.md §5)
            Variant::Consistent => -slider.k_s - p.mass * wz * wz * (1.0 - gamma / (wt * wt)),
            // report eq 46 (times A0)
            Variant::DeadLoad => -slider.k_s,
        };
        let a_ref = slider.z_st.abs();
        Tidf {
            variant,
            m: p.mass,
            k_s: slider.k_s,
            k_a: p.contact_quadratic,
            c_zc: p.contact_damping,
            gamma,
            phi_gain: p.torsion_sign * p.mu * p.moment_arm / p.inertia * p.mass,
            mu: p.mu,
            wz,
            zz: p.zeta_normal,
            wt,
            zt: p.zeta_torsion,
            wx: p.omega_friction,
            zx: p.zeta_friction,
            alpha,
            z_st: slider.z_st,
            inv_ks: 1.0 / slider.k_s,
            inv_ks_a: 1.0 / (slider.k_s * a_ref),
            w_ref: wt,
            a_ref,
        }
    }

    /// Linear part `l_k(w) = m L_z(jkw) [1 - gamma / L_t(jkw)] + K_s + j k w C_zc` [N/m] and its
    /// derivative with respect to `w` (MODEL.md §5, report eqs 44-45 in consistent units).
    #[inline]
    pub fn linear_part(&self, k: f64, w: f64) -> (C64, C64) {
        let (lz, dlz) = osc(k, w, self.wz, self.zz);
        let (lt, dlt) = osc(k, w, self.wt, self.zt);
        let inv_lt = lt.inv();
        let coup = C64::new(1.0, 0.0) - self.gamma * inv_lt;
        let l = self.m * lz * coup + C64::new(self.k_s, k * w * self.c_zc);
        // d/dw [lz (1 - gamma/lt)] = dlz (1 - gamma/lt) + lz gamma dlt / lt^2
        let dl = self.m * (dlz * coup + lz * self.gamma * dlt * inv_lt * inv_lt) + C64::new(0.0, k * self.c_zc);
        (l, dl)
    }

    /// The five scaled residuals at `x = [w, A0, A1, A2, theta]`:
    /// `[Re e1, Im e1, Re e2, Im e2] / K_s` with `e_k = l_k(w) - N_k`, and the DC balance divided by
    /// `K_s |z_st|` (dimensionless; 0 at a root). Singular at `A2 = 0` (as `N2` is).
    pub fn residual(&self, x: &Unknowns) -> Residual {
        self.eval(x, false).0
    }

    /// Residuals and their analytic Jacobian with respect to `x` (physical units of `x`).
    pub fn residual_jacobian(&self, x: &Unknowns) -> (Residual, TidfJacobian) {
        self.eval(x, true)
    }

    #[inline]
    fn eval(&self, x: &Unknowns, with_jac: bool) -> (Residual, TidfJacobian) {
        let (w, a0, a1, a2, th) = (x[0], x[1], x[2], x[3], x[4]);
        let ka = self.k_a;
        let (s, c) = th.sin_cos();
        let (l1, dl1) = self.linear_part(1.0, w);
        let (l2, dl2) = self.linear_part(2.0, w);
        // N1 = K_a [(2 A0 - A2 s) + j A2 c]
        let n1 = ka * C64::new(2.0 * a0 - a2 * s, a2 * c);
        // N2 = K_a [2 A0 - q (s + j c)], q = A1^2 / (2 A2)
        let q = a1 * a1 / (2.0 * a2);
        let n2 = ka * C64::new(2.0 * a0 - q * s, -q * c);
        let e1 = (l1 - n1) * self.inv_ks;
        let e2 = (l2 - n2) * self.inv_ks;
        // DC balance: alpha A0 + K_a (A0^2 + (A1^2 + A2^2)/2)
        let e0 = (self.alpha * a0 + ka * (a0 * a0 + 0.5 * (a1 * a1 + a2 * a2))) * self.inv_ks_a;
        let r = Residual::new(e1.re, e1.im, e2.re, e2.im, e0);
        let mut j = TidfJacobian::zeros();
        if with_jac {
            let k = self.inv_ks;
            let cols1 =
                [dl1, C64::new(-2.0 * ka, 0.0), C64::new(0.0, 0.0), ka * C64::new(s, -c), ka * a2 * C64::new(c, s)];
            let sc = C64::new(s, c);
            let cols2 = [
                dl2,
                C64::new(-2.0 * ka, 0.0),
                ka * (a1 / a2) * sc,
                -ka * (a1 * a1 / (2.0 * a2 * a2)) * sc,
                ka * q * C64::new(c, -s),
            ];
            for col in 0..5 {
                j[(0, col)] = cols1[col].re * k;
                j[(1, col)] = cols1[col].im * k;
                j[(2, col)] = cols2[col].re * k;
                j[(3, col)] = cols2[col].im * k;
            }
            let k0 = self.inv_ks_a;
            j[(4, 1)] = (self.alpha + 2.0 * ka * a0) * k0;
            j[(4, 2)] = ka * a1 * k0;
            j[(4, 3)] = ka * a2 * k0;
        }
        (r, j)
    }

    /// Damped Newton from `guess` (no heap allocation: fixed-size LU).
    ///
    /// Newton steps are computed in scaled unknowns (`w / w_t`, `A / |z_st|`, `theta`), shortened
    /// to `max_step`, and damped by backtracking on `|r|^2` (Armijo). The result is not
    /// canonicalised (see [`canonical`]).
    ///
    /// # Errors
    /// `status` is `NewtonNotConverged` when the iteration stalls (the line search fails, the
    /// Jacobian is singular) or `max_iter` runs out, `NonFinite` for a non-finite iterate.
    pub fn solve(&self, guess: &Unknowns, opts: &NewtonOptions) -> NewtonResult {
        let d = Unknowns::new(self.w_ref, self.a_ref, self.a_ref, self.a_ref, 1.0);
        let mut x = *guess;
        let (mut r, mut jac) = self.eval(&x, true);
        let mut iterations = 0;
        let done = |x, r: Residual, it, status| NewtonResult { x, residual_norm: r.amax(), iterations: it, status };
        loop {
            if !(r.iter().all(|v| v.is_finite()) && x.iter().all(|v| v.is_finite())) {
                return done(x, r, iterations, Status::NonFinite);
            }
            if r.amax() <= opts.ftol {
                return done(x, r, iterations, Status::Success);
            }
            if iterations >= opts.max_iter {
                return done(x, r, iterations, Status::NewtonNotConverged);
            }
            iterations += 1;
            // Scaled system (J D) du = -r.
            let mut js = jac;
            for col in 0..5 {
                for row in 0..5 {
                    js[(row, col)] *= d[col];
                }
            }
            let Some(mut du) = js.lu().solve(&(-r)) else {
                return done(x, r, iterations, Status::NewtonNotConverged);
            };
            if !du.iter().all(|v| v.is_finite()) {
                return done(x, r, iterations, Status::NewtonNotConverged);
            }
            let size = du.amax();
            if size <= opts.xtol {
                // At roundoff level: take the step without a line search and stop.
                x += du.component_mul(&d);
                let (r1, _) = self.eval(&x, false);
                let st = if r1.amax() <= opts.ftol.max(1e-9) { Status::Success } else { Status::NewtonNotConverged };
                return done(x, r1, iterations, st);
            }
            if size > opts.max_step {
                du *= opts.max_step / size;
            }
            let phi0 = r.norm_squared();
            let mut lambda = 1.0;
            let accepted = loop {
                let xt = x + du.component_mul(&d) * lambda;
                let (rt, jt) = self.eval(&xt, true);
                let phit = rt.norm_squared();
                if phit.is_finite() && phit <= (1.0 - 1e-4 * lambda) * phi0 {
                    x = xt;
                    r = rt;
                    jac = jt;
                    break true;
                }
                // Quadratic backtracking, kept within [0.1, 0.5] of the last lambda.
                let lq = if phit.is_finite() {
                    phi0 * lambda * lambda / (phit + phi0 * (2.0 * lambda - 1.0))
                } else {
                    0.1 * lambda
                };
                lambda = lq.clamp(0.1 * lambda, 0.5 * lambda);
                if lambda < 1e-6 {
                    break false;
                }
            };
            if !accepted {
                return done(x, r, iterations, Status::NewtonNotConverged);
            }
        }
    }

    /// The theta-eliminated closed form at frequency `w` (see the module docs).
    pub fn reduced(&self, w: f64) -> Reduced {
        let (l1, _) = self.linear_part(1.0, w);
        let (l2, _) = self.linear_part(2.0, w);
        self.reduced_from(w, l1, l2)
    }

    #[inline]
    fn reduced_from(&self, w: f64, l1: C64, l2: C64) -> Reduced {
        let (r1, i1, r2, i2) = (l1.re, l1.im, l2.re, l2.im);
        let (vx, vy) = (i1 + i2, r2 - r1);
        let nv = vx.hypot(vy);
        let (mut c, mut s) = (vx / nv, vy / nv);
        // Orientation with A2 = I_1 / (K_a c) >= 0 (the g below does not depend on it).
        if c * i1 < 0.0 {
            c = -c;
            s = -s;
        }
        let u = r1 * c + i1 * s;
        let g = 2.0 * self.alpha * u * c + u * u - 4.0 * i1 * i2 + 2.0 * i1 * i1;
        let ka = self.k_a;
        let a2 = i1 / (ka * c);
        let a0 = u / (2.0 * ka * c);
        let a1sq = -2.0 * i1 * i2 / (ka * c * ka * c);
        Reduced { g, x: Unknowns::new(w, a0, a1sq.max(0.0).sqrt(), a2, wrap_2pi(s.atan2(c))), a1_squared: a1sq }
    }

    /// Derived quantities of a root `x` (canonicalised first); `torsion_frequency` is the torsion
    /// mode's `Im(lambda)` for the `physical` flag, `band` its relative width (MODEL.md §5: 0.05).
    pub fn describe(&self, x: &Unknowns, torsion_frequency: f64, band: f64) -> Root {
        let x = canonical(x);
        let (w, a0, a1, a2, th) = (x[0], x[1], x[2], x[3], x[4]);
        let z2 = C64::from_polar(a2, th);
        let (lz1, _) = osc(1.0, w, self.wz, self.zz);
        let (lz2, _) = osc(2.0, w, self.wz, self.zz);
        let (lt1, _) = osc(1.0, w, self.wt, self.zt);
        let (lt2, _) = osc(2.0, w, self.wt, self.zt);
        let (lx1, _) = osc(1.0, w, self.wx, self.zx);
        let (lx2, _) = osc(2.0, w, self.wx, self.zx);
        // phi_k = s mu (L/I) m L_z(jkw) z_k / L_t(jkw); x_k = mu L_z(jkw) z_k / L_x(jkw) (MODEL.md §5)
        let phi1 = self.phi_gain * lz1 * a1 / lt1;
        let phi2 = self.phi_gain * lz2 * z2 / lt2;
        let x1 = self.mu * lz1 * a1 / lx1;
        let x2 = self.mu * lz2 * z2 / lx2;
        let z_max = two_harmonic_max(a0, a1, a2, th);
        // Mean dynamic contact force per unit mass: w_z^2 A0 with the block fixed, 0 for a dead load.
        let fz0_m = match self.variant {
            Variant::Consistent => self.wz * self.wz * a0,
            Variant::DeadLoad => 0.0,
        };
        let f1 = (self.m * lz1 * a1).norm();
        let f2 = (self.m * lz2 * a2).norm();
        let f3 = self.k_a * a1 * a2;
        let residual_norm = self.residual(&x).amax();
        Root {
            x,
            omega: w,
            a0,
            a1,
            a2,
            theta: th,
            phi0: self.phi_gain * fz0_m / (self.wt * self.wt),
            x0: self.mu * fz0_m / (self.wx * self.wx),
            phi1,
            phi2,
            x1,
            x2,
            phi1_amp: phi1.norm(),
            phi1_phase: phi1.arg(),
            x_amp: x1.norm(),
            x_phase: x1.arg(),
            z_max,
            contact_opens: self.z_st + z_max > 0.0,
            physical: a0.abs() < self.z_st.abs() && (w - torsion_frequency).abs() <= band * torsion_frequency,
            fz_harmonics: [f1, f2, f3],
            third_harmonic_ratio: f3 / f1.hypot(f2),
            residual_norm,
            newton_iterations: 0,
            status: Status::Success,
        }
    }

    /// The search grid: log-spaced, refined near `w_t` and `w_t / 2` (see [`SearchOptions::kappa`]).
    fn grid_step(&self, w: f64, h_log: f64, kappa: f64) -> f64 {
        let mut h = h_log * w;
        for k in [1.0, 2.0] {
            let (lt, dlt) = osc(k, w, self.wt, self.zt);
            h = h.min(kappa * lt.norm() / dlt.norm());
        }
        h
    }

    /// All roots in the box `[w_min, w_max]` (MODEL.md §5 "Roots"; method in the module docs).
    ///
    /// # Errors
    /// `status` is `InvalidInput` for a bad box or `K_a = 0` (a linear contact has no describing
    /// function: only Hopf points), `NonFinite` if the reduced function is not finite on the grid.
    pub fn find_roots(&self, slider: &Slider, opts: &SearchOptions) -> RootSearch {
        let lin = linear_stability(slider);
        let torsion_frequency = lin.mode(ModeKind::Torsion).frequency;
        let near_marginal = lin.max_growth_rate.abs() < opts.marginal_tol * lin.least_stable_frequency.abs();
        let mut out = RootSearch {
            roots: Vec::new(),
            unresolved: Vec::new(),
            outcome: SearchOutcome::NoRoot,
            max_growth_rate: lin.max_growth_rate,
            torsion_frequency,
            near_marginal,
            complex_amplitude: Vec::new(),
            n_grid: 0,
            status: Status::Success,
        };
        let ok_box = opts.w_min.is_finite() && opts.w_min > 0.0 && opts.w_max.is_finite() && opts.w_max > opts.w_min;
        if !ok_box || self.k_a <= 0.0 || opts.n_base < 2 || opts.kappa.is_nan() || opts.kappa <= 0.0 {
            out.status = Status::InvalidInput;
            out.outcome = if near_marginal { SearchOutcome::BelowResolution } else { SearchOutcome::NoRoot };
            return out;
        }
        let h_log = (opts.w_max / opts.w_min).ln() / (opts.n_base - 1) as f64;
        let g_at = |w: f64| self.reduced(w).g;
        let mut candidates: Vec<(f64, Reduced)> = Vec::new();
        let mut w0 = opts.w_min;
        let mut g0 = g_at(w0);
        let mut n = 1;
        if g0 == 0.0 {
            candidates.push((w0, self.reduced(w0)));
        }
        while w0 < opts.w_max {
            let w1 = (w0 + self.grid_step(w0, h_log, opts.kappa)).min(opts.w_max);
            let g1 = g_at(w1);
            n += 1;
            if !g1.is_finite() {
                out.status = Status::NonFinite;
            } else if g1 == 0.0 {
                candidates.push((w1, self.reduced(w1)));
            } else if g0 != 0.0 && g0.is_finite() && (g0 < 0.0) != (g1 < 0.0) {
                let b = brent(g_at, w0, w1, g0, g1, 4.0 * f64::EPSILON, 200);
                candidates.push((b.x, self.reduced(b.x)));
            }
            w0 = w1;
            g0 = g1;
        }
        out.n_grid = n;
        for (_, red) in candidates {
            if red.a1_squared.abs().sqrt() < opts.amp_resolution || red.x[var::A2].is_nan() || red.x[var::A2] <= 0.0 {
                out.unresolved.push(Unresolved { omega: red.x[0], a1_squared: red.a1_squared });
                continue;
            }
            if red.a1_squared < 0.0 {
                out.complex_amplitude.push(Unresolved { omega: red.x[0], a1_squared: red.a1_squared });
                continue;
            }
            let nr = self.solve(&red.x, &opts.newton);
            let xr = if nr.status == Status::Success { nr.x } else { red.x };
            let mut root = self.describe(&xr, torsion_frequency, opts.physical_band);
            root.newton_iterations = nr.iterations;
            root.status = nr.status;
            if root.residual_norm.is_nan() || root.residual_norm > opts.residual_tol {
                continue;
            }
            if root.omega < opts.w_min || root.omega > opts.w_max {
                continue;
            }
            let scale = Unknowns::new(self.w_ref, self.a_ref, self.a_ref, self.a_ref, 1.0);
            let dup = out.roots.iter().any(|r: &Root| {
                let mut d = (r.x - root.x).component_div(&scale);
                // theta is periodic
                d[var::THETA] = (d[var::THETA] + PI).rem_euclid(2.0 * PI) - PI;
                d.amax() < opts.dedup_tol
            });
            if !dup {
                out.roots.push(root);
            }
        }
        out.roots.sort_by(|a, b| a.omega.total_cmp(&b.omega));
        out.outcome = if !out.roots.is_empty() {
            SearchOutcome::Roots
        } else if !out.unresolved.is_empty() || near_marginal {
            SearchOutcome::BelowResolution
        } else {
            SearchOutcome::NoRoot
        };
        out
    }
}

/// Canonical form of a root: `w > 0`, `A1 > 0`, `A2 > 0`, `theta` in `[0, 2 pi)`, using the
/// invariances `w -> -w` (with `A2 -> -A2`, `theta -> -theta`), `A1 -> -A1` and
/// `(A2, theta) -> (-A2, theta + pi)`.
pub fn canonical(x: &Unknowns) -> Unknowns {
    let mut y = *x;
    if y[var::W] < 0.0 {
        y[var::W] = -y[var::W];
        y[var::A2] = -y[var::A2];
        y[var::THETA] = -y[var::THETA];
    }
    y[var::A1] = y[var::A1].abs();
    if y[var::A2] < 0.0 {
        y[var::A2] = -y[var::A2];
        y[var::THETA] += PI;
    }
    y[var::THETA] = wrap_2pi(y[var::THETA]);
    y
}

/// Largest value over `psi` of `A0 + A1 sin psi + A2 sin(2 psi + theta)`: see [`two_harmonic_argmax`].
pub fn two_harmonic_max(a0: f64, a1: f64, a2: f64, theta: f64) -> f64 {
    two_harmonic_argmax(a0, a1, a2, theta).1
}

/// Where `A0 + A1 sin psi + A2 sin(2 psi + theta)` is largest, and that value: 64 samples, then
/// Newton on the derivative from the best one (converges to rounding: the maximum is a simple one
/// unless two maxima tie, where either is the maximum value). `psi` in `[0, 2 pi)`.
pub fn two_harmonic_argmax(a0: f64, a1: f64, a2: f64, theta: f64) -> (f64, f64) {
    let f = |p: f64| a0 + a1 * p.sin() + a2 * (2.0 * p + theta).sin();
    const N: usize = 64;
    let mut best = (f64::NEG_INFINITY, 0.0);
    for i in 0..N {
        let p = 2.0 * PI * i as f64 / N as f64;
        let v = f(p);
        if v > best.0 {
            best = (v, p);
        }
    }
    let mut p = best.1;
    for _ in 0..8 {
        let d1 = a1 * p.cos() + 2.0 * a2 * (2.0 * p + theta).cos();
        let d2 = -a1 * p.sin() - 4.0 * a2 * (2.0 * p + theta).sin();
        if d2 >= 0.0 {
            break;
        }
        let step = d1 / d2;
        p -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    let v = f(p);
    if v >= best.0 {
        (wrap_2pi(p), v)
    } else {
        (best.1, best.0)
    }
}

/// All describing-function roots of the slider with parameters `p` (see [`Tidf::find_roots`]).
///
/// # Errors
/// The first parameter out of range.
pub fn find_roots(p: &Params, variant: Variant, opts: &SearchOptions) -> Result<RootSearch, ParamError> {
    let s = Slider::new(*p)?;
    Ok(Tidf::new(&s, variant).find_roots(&s, opts))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deg(a: f64) -> f64 {
        wrap_2pi(a) * 180.0 / PI
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    fn seed_search(variant: Variant) -> RootSearch {
        let s = Slider::seed();
        Tidf::new(&s, variant).find_roots(&s, &SearchOptions::default())
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let s = Slider::seed();
        for variant in [Variant::Consistent, Variant::DeadLoad] {
            let t = Tidf::new(&s, variant);
            let x = Unknowns::new(640.0, 1.3e-6, 2.0e-5, 6.0e-6, 4.2);
            let (_, j) = t.residual_jacobian(&x);
            let h = [1e-4, 1e-12, 1e-11, 1e-12, 1e-7];
            for c in 0..5 {
                let mut xp = x;
                let mut xm = x;
                xp[c] += h[c];
                xm[c] -= h[c];
                let fd = (t.residual(&xp) - t.residual(&xm)) / (2.0 * h[c]);
                for r in 0..5 {
                    let scale = j.row(r).iter().zip(h.iter()).map(|(v, h)| (v * h).abs()).fold(0.0, f64::max) / h[c];
                    assert!(
                        (fd[r] - j[(r, c)]).abs() <= 1e-6 * scale.max(j[(r, c)].abs()) + 1e-12,
                        "{variant:?} J[{r},{c}] = {} fd {}",
                        j[(r, c)],
                        fd[r]
                    );
                }
            }
        }
    }

    #[test]
    fn seed_physical_root_matches_model_md() {
        let search = seed_search(Variant::Consistent);
        assert_eq!(search.status, Status::Success);
        assert_eq!(search.outcome, SearchOutcome::Roots);
        let phys: Vec<&Root> = search.roots.iter().filter(|r| r.physical).collect();
        assert_eq!(phys.len(), 1, "{:#?}", search.roots);
        let r = phys[0];
        eprintln!(
            "seed root: w {:.9} A0 {:.6e} A1 {:.6e} A2 {:.6e} theta {:.4} deg, phi1 {:.5e} at {:.3} deg, x {:.5e} at {:.3} deg, \
             z_max {:.4e}, Fz harmonics {:?}, res {:.1e}, newton {}",
            r.omega,
            r.a0,
            r.a1,
            r.a2,
            deg(r.theta),
            r.phi1_amp,
            deg(r.phi1_phase),
            r.x_amp,
            r.x_phase * 180.0 / PI,
            r.z_max,
            r.fz_harmonics,
            r.residual_norm,
            r.newton_iterations
        );
        // MODEL.md §5 "this reading" (seed_values.json tidf_root_seed), to the printed digits.
        assert!((r.omega - 647.559).abs() < 7e-4, "w = {}", r.omega);
        assert!((r.a0 - 0.958e-6).abs() < 0.6e-9, "A0 = {}", r.a0);
        assert!((r.a1 - 21.524e-6).abs() < 0.6e-9, "A1 = {}", r.a1);
        assert!((r.a2 - 5.175e-6).abs() < 0.6e-9, "A2 = {}", r.a2);
        assert!((deg(r.theta) - 251.13).abs() < 6e-3, "theta = {}", deg(r.theta));
        assert!((r.phi1_amp - 2.066e-3).abs() < 0.6e-6, "phi1 = {}", r.phi1_amp);
        assert!((deg(r.phi1_phase) - 182.42).abs() < 6e-3, "phi1 phase = {}", deg(r.phi1_phase));
        assert!((r.x_amp - 4.264e-6).abs() < 0.6e-9, "x = {}", r.x_amp);
        assert!((r.x_phase * 180.0 / PI + 0.70).abs() < 6e-3, "x phase = {}", r.x_phase * 180.0 / PI);
        // Third harmonic of K_a z^2: 2.4 N against 16.0 and 20.0 N (MODEL.md §5), to 2 %.
        assert!(rel(r.fz_harmonics[0], 16.0) < 0.02 && rel(r.fz_harmonics[1], 20.0) < 0.02, "{:?}", r.fz_harmonics);
        assert!(rel(r.fz_harmonics[2], 2.4) < 0.02, "{:?}", r.fz_harmonics);
        // The two-harmonic waveform already reaches 27.5 um > |z_st| = 16.56 um: the describing
        // function's own solution leaves the disk (the exact orbit reaches 27.8 um, MODEL.md §6).
        assert!(r.contact_opens && (r.z_max - 27.51e-6).abs() < 0.01e-6, "z_max = {}", r.z_max);
        assert!(r.residual_norm < 1e-13);
    }

    #[test]
    fn dead_load_root_matches_model_md() {
        let search = seed_search(Variant::DeadLoad);
        let phys: Vec<&Root> = search.roots.iter().filter(|r| r.physical).collect();
        assert_eq!(phys.len(), 1);
        let r = phys[0];
        eprintln!(
            "dead load: w {:.6} A0 {:.4e} A1 {:.5e} A2 {:.4e} theta {:.3}",
            r.omega,
            r.a0,
            r.a1,
            r.a2,
            deg(r.theta)
        );
        assert!((r.omega - 647.563).abs() < 7e-4, "w = {}", r.omega);
        assert!((r.a0 - 0.978e-6).abs() < 0.6e-9, "A0 = {}", r.a0);
        assert!((r.a1 - 21.486e-6).abs() < 0.6e-9, "A1 = {}", r.a1);
        assert!((r.a2 - 5.162e-6).abs() < 0.6e-9, "A2 = {}", r.a2);
        assert!((deg(r.theta) - 251.11).abs() < 6e-3, "theta = {}", deg(r.theta));
    }

    #[test]
    fn finer_grid_finds_the_same_roots() {
        let s = Slider::seed();
        for p in [
            Params::seed(),
            Params { normal_load: 30.0, ..Params::seed() },
            Params { mu: 0.1, normal_load: 200.0, ..Params::seed() },
        ] {
            let s2 = Slider::new(p).unwrap();
            let t = Tidf::new(&s2, Variant::Consistent);
            let base = t.find_roots(&s2, &SearchOptions::default());
            let fine = t.find_roots(&s2, &SearchOptions::default().refined(2.0));
            let finer = t.find_roots(&s2, &SearchOptions::default().refined(8.0));
            eprintln!(
                "load {} mu {}: {} roots ({} / {} / {} grid points)",
                p.normal_load,
                p.mu,
                base.roots.len(),
                base.n_grid,
                fine.n_grid,
                finer.n_grid
            );
            for r in &base.roots {
                eprintln!(
                    "  w {:.4} A0 {:.3e} A1 {:.3e} A2 {:.3e} theta {:.2} physical {} opens {}",
                    r.omega,
                    r.a0,
                    r.a1,
                    r.a2,
                    deg(r.theta),
                    r.physical,
                    r.contact_opens
                );
            }
            for other in [&fine, &finer] {
                assert_eq!(base.roots.len(), other.roots.len());
                for (a, b) in base.roots.iter().zip(other.roots.iter()) {
                    assert!(rel(a.omega, b.omega) < 1e-12 && (a.a1 - b.a1).abs() < 1e-12 * s.z_st.abs(), "{a:?} {b:?}");
                }
            }
        }
    }

    #[test]
    fn seed_has_non_physical_roots_far_from_torsion() {
        let search = seed_search(Variant::Consistent);
        let others: Vec<&Root> = search.roots.iter().filter(|r| !r.physical).collect();
        assert!(!others.is_empty());
        for r in &others {
            eprintln!("non-physical: w {:.3} A0 {:.3e} A1 {:.3e} A2 {:.3e}", r.omega, r.a0, r.a1, r.a2);
        }
        // MODEL.md §5: w about 290-600 rad/s, A0 of 100-200 um.
        assert!(others.iter().any(|r| (280.0..610.0).contains(&r.omega) && (90e-6..210e-6).contains(&r.a0.abs())));
    }

    #[test]
    fn no_physical_root_where_sliding_is_unstable() {
        // mu = 0.215 at 15 N: below the Hopf load 24.904 N, sliding unstable (MODEL.md §4, §6).
        // MODEL.md §6 says the describing function has no root at all there. Found: no root on
        // the torsion branch (its zero has A1^2 < 0: complex amplitude), but the four far,
        // non-physical roots (w 291-585 rad/s, A0 91-176 um) exist here as at the seed.
        let p = Params { normal_load: 15.0, ..Params::seed() };
        let r = find_roots(&p, Variant::Consistent, &SearchOptions::default()).unwrap();
        assert!(r.max_growth_rate > 0.0);
        for x in &r.roots {
            eprintln!("15 N root: w {:.3} A0 {:.3e} A1 {:.3e} physical {}", x.omega, x.a0, x.a1, x.physical);
        }
        eprintln!(
            "15 N: outcome {:?}, complex-amplitude zeros {:?}, unresolved {:?}",
            r.outcome, r.complex_amplitude, r.unresolved
        );
        assert!(r.roots.iter().all(|x| !x.physical && (280.0..610.0).contains(&x.omega)));
        assert!(r.unresolved.is_empty());
        let branch: Vec<&Unresolved> = r
            .complex_amplitude
            .iter()
            .filter(|z| (z.omega - r.torsion_frequency).abs() < 0.05 * r.torsion_frequency)
            .collect();
        assert_eq!(branch.len(), 1, "{:?}", r.complex_amplitude);
        // The same holds on a load grid below the Hopf load.
        for load in [2.0, 5.0, 10.0, 20.0, 24.0] {
            let r = find_roots(
                &Params { normal_load: load, ..Params::seed() },
                Variant::Consistent,
                &SearchOptions::default(),
            )
            .unwrap();
            assert!(r.max_growth_rate > 0.0 && r.roots.iter().all(|x| !x.physical), "load {load}");
        }
    }

    #[test]
    fn at_the_hopf_load_the_root_is_below_resolution() {
        let p0 = Params::seed();
        let h = crate::linear::hopf_loads(&p0, 10.0, 50.0, 20).unwrap()[0];
        let p = Params { normal_load: h.normal_load, ..p0 };
        let r = find_roots(&p, Variant::Consistent, &SearchOptions::default()).unwrap();
        eprintln!(
            "at the Hopf load {}: unresolved {:?}, marginal {}, growth {:e}",
            h.normal_load, r.unresolved, r.near_marginal, r.max_growth_rate
        );
        assert!(r.near_marginal);
        assert!(r.roots.iter().all(|x| !x.physical));
        assert_eq!(r.unresolved.len(), 1);
        assert!((r.unresolved[0].omega - r.torsion_frequency).abs() < 0.01 * r.torsion_frequency);
        // Just above it, the small root is resolved and physical (subcritical: it exists on the
        // stable side); just below, the zero has A1^2 < 0 (no root).
        let above = find_roots(
            &Params { normal_load: h.normal_load * 1.01, ..p0 },
            Variant::Consistent,
            &SearchOptions::default(),
        )
        .unwrap();
        let small: Vec<&Root> = above.roots.iter().filter(|x| x.physical).collect();
        assert_eq!(small.len(), 1);
        eprintln!("1 % above the Hopf load: A1 = {:e}", small[0].a1);
        let below = find_roots(
            &Params { normal_load: h.normal_load * 0.99, ..p0 },
            Variant::Consistent,
            &SearchOptions::default(),
        )
        .unwrap();
        assert!(below.roots.iter().all(|x| !x.physical) && below.unresolved.is_empty());
    }

    #[test]
    fn newton_recovers_the_root_from_a_perturbed_guess() {
        let s = Slider::seed();
        let t = Tidf::new(&s, Variant::Consistent);
        let root = seed_search(Variant::Consistent).roots.into_iter().find(|r| r.physical).unwrap();
        let guess = Unknowns::new(root.omega * 1.01, root.a0 * 1.5, root.a1 * 0.8, root.a2 * 1.2, root.theta + 0.2);
        let r = t.solve(&guess, &NewtonOptions::default());
        assert_eq!(r.status, Status::Success, "{r:?}");
        let x = canonical(&r.x);
        assert!(rel(x[0], root.omega) < 1e-13 && rel(x[2], root.a1) < 1e-10, "{x} vs {:?}", root.x);
        // A hopeless guess fails as data.
        let bad = t
            .solve(&Unknowns::new(2900.0, 1e-3, 1e-9, 1e-3, 0.0), &NewtonOptions { max_iter: 5, ..Default::default() });
        assert_ne!(bad.status, Status::Success);
    }

    #[test]
    fn canonical_form_is_invariant() {
        let s = Slider::seed();
        let t = Tidf::new(&s, Variant::Consistent);
        let x = Unknowns::new(640.0, 1.3e-6, 2.0e-5, 6.0e-6, 4.2);
        let r0 = t.residual(&x);
        for y in [
            Unknowns::new(640.0, 1.3e-6, -2.0e-5, 6.0e-6, 4.2),
            Unknowns::new(640.0, 1.3e-6, 2.0e-5, -6.0e-6, 4.2 - PI),
            Unknowns::new(-640.0, 1.3e-6, 2.0e-5, -6.0e-6, -4.2),
        ] {
            // Re parts equal, Im parts flip with w -> -w.
            let r = t.residual(&y);
            let sign = if y[0] < 0.0 { -1.0 } else { 1.0 };
            let flip = Residual::new(r0[0], sign * r0[1], r0[2], sign * r0[3], r0[4]);
            assert!((r - flip).amax() < 1e-14, "{r} vs {flip}");
            assert!((canonical(&y) - x).amax() < 1e-14);
        }
    }

    #[test]
    fn two_harmonic_max_is_accurate() {
        let (a0, a1, a2, th) = (1e-6, 2e-5, 6e-6, 4.2);
        let brute = (0..200_000)
            .map(|i| {
                let p = 2.0 * PI * i as f64 / 200_000.0;
                a0 + a1 * p.sin() + a2 * (2.0 * p + th).sin()
            })
            .fold(f64::NEG_INFINITY, f64::max);
        let m = two_harmonic_max(a0, a1, a2, th);
        // the sampled maximum is below the true one by up to f'' h^2 / 8 ~ 5e-15 here
        assert!(m >= brute && m - brute < 1e-14, "{m} vs {brute}");
    }

    #[test]
    fn cross_check_against_a_two_dimensional_grid() {
        // Independent of the theta elimination: Newton from every node of a coarse (w, theta) grid,
        // with A0, A2 from eq k=1 and A1^2 from Re eq k=2 in closed form (MODEL.md §5's recipe).
        // Every root it converges to inside the box must be one the 1-D search found.
        for p in [Params::seed(), Params { normal_load: 30.0, ..Params::seed() }] {
            let s = Slider::new(p).unwrap();
            let t = Tidf::new(&s, Variant::Consistent);
            let search = t.find_roots(&s, &SearchOptions::default());
            let mut found = 0;
            for iw in 0..120 {
                let w = 150.0 * (20f64).powf(iw as f64 / 119.0);
                let (l1, _) = t.linear_part(1.0, w);
                let (l2, _) = t.linear_part(2.0, w);
                for it in 0..24 {
                    let th = 2.0 * PI * (it as f64 + 0.5) / 24.0;
                    let (sn, cs) = th.sin_cos();
                    let a2 = l1.im / (t.k_a * cs);
                    let a0 = (l1.re + t.k_a * a2 * sn) / (2.0 * t.k_a);
                    let a1sq = 2.0 * a2 * (2.0 * t.k_a * a0 - l2.re) / (t.k_a * sn);
                    if a1sq.is_nan() || a1sq <= 0.0 || a1sq.sqrt() > 1e-3 || a0.abs() > 1e-3 {
                        continue;
                    }
                    let r = t.solve(&Unknowns::new(w, a0, a1sq.sqrt(), a2, th), &NewtonOptions::default());
                    if r.status != Status::Success {
                        continue;
                    }
                    let x = canonical(&r.x);
                    if x[0] < 150.0 || x[0] > 3000.0 || x[2] < 1e-9 {
                        continue;
                    }
                    found += 1;
                    assert!(
                        search
                            .roots
                            .iter()
                            .any(|q| rel(q.omega, x[0]) < 1e-9 && (q.a1 - x[2]).abs() < 1e-9 * s.z_st.abs()),
                        "load {}: 2-D grid root {x} not in the 1-D set",
                        p.normal_load
                    );
                }
            }
            assert!(found > 0);
        }
    }

    #[test]
    #[ignore = "timing; run with --ignored --nocapture in release"]
    fn timing() {
        let s = Slider::seed();
        let t = Tidf::new(&s, Variant::Consistent);
        let opts = SearchOptions::default();
        let n = 2000;
        let t0 = std::time::Instant::now();
        let mut k = 0;
        for _ in 0..n {
            k += std::hint::black_box(t.find_roots(&s, &opts)).roots.len();
        }
        let dt = t0.elapsed().as_secs_f64() / n as f64;
        eprintln!("all-roots search: {:.1} us per point ({} roots)", dt * 1e6, k / n);
        let root = t.find_roots(&s, &opts).roots.into_iter().find(|r| r.physical).unwrap();
        let guess =
            Unknowns::new(root.omega * 1.001, root.a0 * 1.05, root.a1 * 0.98, root.a2 * 1.02, root.theta + 0.01);
        let m = 200_000;
        let t0 = std::time::Instant::now();
        let mut it = 0;
        for i in 0..m {
            let g = guess * (1.0 + 1e-9 * (i % 7) as f64);
            it += std::hint::black_box(t.solve(std::hint::black_box(&g), &NewtonOptions::default())).iterations;
        }
        let dt = t0.elapsed().as_secs_f64() / m as f64;
        eprintln!(
            "warm-start Newton: {:.2} us per solve, {:.0} solves/s, {:.1} iterations",
            dt * 1e6,
            1.0 / dt,
            it as f64 / m as f64
        );
    }
}
