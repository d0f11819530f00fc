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
    /// Smallest dynamic `z` over a period of the two-harmonic waveform [m].
    pub z_min: f64,
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
    /// `Success`, `InvalidInput` (bad box or `K_a = 0`: no describing function), `NonFinite`, or
    /// `NotComputed` (cancelled by the caller during the scan).
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
}

mod search;
pub use search::{canonical, find_roots, two_harmonic_argmax, two_harmonic_max};

#[cfg(test)]
mod tests;
