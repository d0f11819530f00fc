//! Linear stability of steady sliding (MODEL.md §4).
//!
//! Steady sliding is the equilibrium `y = 0` of MODEL.md §2. Its stability is decided by the six
//! eigenvalues of the Jacobian `Slider::jacobian(0, Contact)`: three complex pairs at the seed, one
//! per mode (friction `x`, torsion `phi`, normal `z`). The modes are labelled by the energy
//! participation of their eigenvectors, so a label follows the physics when the frequencies cross.
//!
//! [`hopf_loads`] follows the report's load sweep: only the static point (`z_st`, `K_s`) follows
//! the normal load; `K_phi`, `C_zc`, `mu` stay fixed. It brackets the sign changes of the largest
//! real part on a log-spaced load grid and refines each with Brent's method.

use crate::model::{idx, Jacobian, ParamError, Params, Slider, State};
use crate::status::Status;
use crate::ContactMode;
use nalgebra::{Complex, Matrix3, SMatrix, SVector, Vector3};

type C64 = Complex<f64>;

/// Which degree of freedom dominates a mode of the linearised slider.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModeKind {
    /// Dominated by `x`, the friction direction (`-1.158 ± 306.30j` at the seed).
    Friction,
    /// Dominated by the twist `phi` (`-0.3285 ± 646.63j` at the seed); the mode that self-excites.
    Torsion,
    /// Dominated by the normal displacement `z` (`-50.03 ± 1440.27j` at the seed).
    Normal,
}

impl ModeKind {
    /// Every kind, in the order of [`LinearMode::participation`] (`[x, phi, z]`).
    pub const ALL: [ModeKind; 3] = [ModeKind::Friction, ModeKind::Torsion, ModeKind::Normal];

    /// Short name (`"friction"`, `"torsion"`, `"normal"`).
    pub fn name(self) -> &'static str {
        match self {
            ModeKind::Friction => "friction",
            ModeKind::Torsion => "torsion",
            ModeKind::Normal => "normal",
        }
    }
}

/// One mode of the linearised slider: a complex-conjugate pair of eigenvalues (or, when
/// overdamped, a pair of real ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearMode {
    /// Label, assigned by eigenvector participation (see [`LinearMode::participation`]).
    pub kind: ModeKind,
    /// The member with `Im >= 0` (for a real pair: the larger one) [1/s].
    pub eigenvalue: C64,
    /// The other member of the pair (the conjugate of `eigenvalue` for a complex pair) [1/s].
    pub partner: C64,
    /// Largest real part of the pair [1/s]: the growth rate (> 0: unstable).
    pub growth_rate: f64,
    /// `Im(eigenvalue)` [rad/s] (0 for a real pair).
    pub frequency: f64,
    /// Energy fractions of the eigenvector of `eigenvalue` in `[x, phi, z]` order (same order as
    /// [`ModeKind::ALL`]): `m |u_x|^2`, `I |u_phi|^2`, `m |u_z|^2`, normalised to sum 1, where `u`
    /// is the displacement part of the eigenvector.
    pub participation: [f64; 3],
}

/// Linear stability of steady sliding at one parameter point (MODEL.md §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearStability {
    /// The six eigenvalues in a deterministic order: mode by mode as in `modes`, each as
    /// `[eigenvalue, partner]`.
    pub eigenvalues: [C64; 6],
    /// The three modes, sorted by frequency (ascending; real pairs first).
    pub modes: [LinearMode; 3],
    /// Index into `modes` of the least stable mode (largest growth rate).
    pub least_stable: usize,
    /// Largest real part of all eigenvalues [1/s].
    pub max_growth_rate: f64,
    /// Frequency of the least stable mode [rad/s].
    pub least_stable_frequency: f64,
    /// True when every eigenvalue has a negative real part (steady sliding is asymptotically stable).
    pub stable: bool,
    /// `Im(lambda_normal) / 2 pi` [Hz]: the normal-mode frequency the wear model uses (MODEL.md §8).
    pub normal_mode_frequency_hz: f64,
    /// `Success`, `NonFinite` (a non-finite Jacobian) or `NotConverged` (the QR iteration failed);
    /// on failure every number is NaN.
    pub status: Status,
}

impl LinearStability {
    /// The mode labelled `kind`.
    pub fn mode(&self, kind: ModeKind) -> &LinearMode {
        // Labels are a permutation of ModeKind::ALL, so the search cannot fail.
        self.modes.iter().find(|m| m.kind == kind).unwrap_or(&self.modes[0])
    }

    fn failed(status: Status) -> Self {
        let nan = C64::new(f64::NAN, f64::NAN);
        let mode = |kind| LinearMode {
            kind,
            eigenvalue: nan,
            partner: nan,
            growth_rate: f64::NAN,
            frequency: f64::NAN,
            participation: [f64::NAN; 3],
        };
        LinearStability {
            eigenvalues: [nan; 6],
            modes: [mode(ModeKind::Friction), mode(ModeKind::Torsion), mode(ModeKind::Normal)],
            least_stable: 0,
            max_growth_rate: f64::NAN,
            least_stable_frequency: f64::NAN,
            stable: false,
            normal_mode_frequency_hz: f64::NAN,
            status,
        }
    }
}

/// Eigenvalues of a 6x6 real matrix (unordered), by nalgebra's Schur decomposition after a diagonal
/// balancing by powers of two (the slider's Jacobian mixes entries of order 1 and 1e6).
///
/// # Errors
/// `None` if the matrix is not finite or the QR iteration does not converge.
pub fn eigenvalues(j: &Jacobian) -> Option<[C64; 6]> {
    if !j.iter().all(|v| v.is_finite()) {
        return None;
    }
    let (b, _) = balance(j);
    let schur = b.try_schur(f64::EPSILON, 10_000)?;
    let ev = schur.complex_eigenvalues();
    let mut out = [C64::new(0.0, 0.0); 6];
    for (o, e) in out.iter_mut().zip(ev.iter()) {
        *o = *e;
    }
    Some(out)
}

/// Parlett-Reinsch balancing `D^-1 A D` with `D` a diagonal of powers of two (exact in floating point).
/// Returns the balanced matrix and the diagonal of `D`.
pub(crate) fn balance<const N: usize>(a: &SMatrix<f64, N, N>) -> (SMatrix<f64, N, N>, SVector<f64, N>) {
    let mut m = *a;
    let mut d = SVector::<f64, N>::repeat(1.0);
    for _sweep in 0..20 {
        let mut changed = false;
        for i in 0..N {
            let mut c = 0.0;
            let mut r = 0.0;
            for k in 0..N {
                if k != i {
                    c += m[(k, i)].abs();
                    r += m[(i, k)].abs();
                }
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0;
            let (mut cc, mut rr) = (c, r);
            while cc < rr / 2.0 {
                cc *= 2.0;
                rr /= 2.0;
                f *= 2.0;
            }
            while cc >= rr * 2.0 {
                cc /= 2.0;
                rr *= 2.0;
                f /= 2.0;
            }
            if (cc + rr) < 0.95 * s {
                changed = true;
                d[i] *= f;
                for k in 0..N {
                    m[(i, k)] /= f;
                    m[(k, i)] *= f;
                }
            }
        }
        if !changed {
            break;
        }
    }
    (m, d)
}

/// Energy participation `[x, phi, z]` of the eigenvector of `lambda`.
///
/// The slider's Jacobian has the kinematic rows `q' = v` (`q = [z, x, phi]`), so an eigenvector is
/// `[u, lambda u]` with `(lambda^2 - A_q - lambda A_v) u = 0`, `A_q`, `A_v` the acceleration rows'
/// position and velocity columns. `u` is the (bilinear) cross product of two rows of that rank-2
/// 3x3 matrix: exact, no inverse iteration.
pub(crate) fn participation(j: &Jacobian, p: &Params, lambda: C64) -> [f64; 3] {
    let pos = [idx::Z, idx::X, idx::PHI];
    let vel = [idx::ZD, idx::XD, idx::PHID];
    let mut a = Matrix3::<C64>::zeros();
    for r in 0..3 {
        for c in 0..3 {
            let diag = if r == c { lambda * lambda } else { C64::new(0.0, 0.0) };
            a[(r, c)] = diag - j[(vel[r], pos[c])] - lambda * j[(vel[r], vel[c])];
        }
    }
    let cross = |x: Vector3<C64>, y: Vector3<C64>| {
        Vector3::new(x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0])
    };
    let rows = [a.row(0).transpose(), a.row(1).transpose(), a.row(2).transpose()];
    let mut u = Vector3::<C64>::zeros();
    let mut best = -1.0;
    for (k, l) in [(0, 1), (0, 2), (1, 2)] {
        let v = cross(rows[k], rows[l]);
        let n: f64 = v.iter().map(|c| c.norm_sqr()).sum();
        if n > best {
            best = n;
            u = v;
        }
    }
    // u = [z, x, phi]; energy weights m, m, I.
    let e = [p.mass * u[1].norm_sqr(), p.inertia * u[2].norm_sqr(), p.mass * u[0].norm_sqr()];
    let s: f64 = e.iter().sum();
    if s > 0.0 && s.is_finite() {
        [e[0] / s, e[1] / s, e[2] / s]
    } else {
        // A decoupled (diagonal) block gives a null vector that is zero in the cross products of
        // the other rows only when two rows vanish; fall back to no information.
        [1.0 / 3.0; 3]
    }
}

/// Linear stability of steady sliding for a validated slider (MODEL.md §4).
///
/// Uses `Slider::jacobian(0, Contact)`, whatever the contact model: steady sliding is in contact.
///
/// # Errors
/// A failure is reported in [`LinearStability::status`] (non-finite Jacobian, QR not converged),
/// never as a panic.
pub fn linear_stability(slider: &Slider) -> LinearStability {
    let j = slider.jacobian(&State::zeros(), ContactMode::Contact);
    let Some(ev) = eigenvalues(&j) else {
        let finite = j.iter().all(|v| v.is_finite());
        return LinearStability::failed(if finite { Status::NotConverged } else { Status::NonFinite });
    };
    // Pair the eigenvalues: complex ones with Im > 0 carry their conjugate (the Schur form gives
    // exact conjugate pairs), real ones are paired in descending order.
    let mut upper: Vec<C64> = ev.iter().copied().filter(|e| e.im > 0.0).collect();
    let lower: Vec<C64> = ev.iter().copied().filter(|e| e.im < 0.0).collect();
    let mut real: Vec<C64> = ev.iter().copied().filter(|e| e.im == 0.0).collect();
    if upper.len() != lower.len() || !real.len().is_multiple_of(2) {
        return LinearStability::failed(Status::NotConverged);
    }
    upper.sort_by(|a, b| a.im.total_cmp(&b.im).then(a.re.total_cmp(&b.re)));
    real.sort_by(|a, b| b.re.total_cmp(&a.re));
    let mut pairs: Vec<(C64, C64)> = real.chunks(2).map(|c| (c[0], c[1])).collect();
    pairs.extend(upper.iter().map(|e| (*e, e.conj())));

    // Participation of each pair, then the label permutation with the largest total participation.
    let part: Vec<[f64; 3]> = pairs.iter().map(|(e, _)| participation(&j, &slider.p, *e)).collect();
    const PERMS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut best_perm = PERMS[0];
    let mut best = f64::NEG_INFINITY;
    for perm in PERMS {
        let score: f64 = (0..3).map(|m| part[m][perm[m]]).sum();
        if score > best {
            best = score;
            best_perm = perm;
        }
    }
    let modes: [LinearMode; 3] = std::array::from_fn(|m| {
        let (e, partner) = pairs[m];
        LinearMode {
            kind: ModeKind::ALL[best_perm[m]],
            eigenvalue: e,
            partner,
            growth_rate: e.re.max(partner.re),
            frequency: e.im,
            participation: part[m],
        }
    });
    let mut eigenvalues = [C64::new(0.0, 0.0); 6];
    for (m, mode) in modes.iter().enumerate() {
        eigenvalues[2 * m] = mode.eigenvalue;
        eigenvalues[2 * m + 1] = mode.partner;
    }
    let mut least_stable = 0;
    for m in 1..3 {
        if modes[m].growth_rate > modes[least_stable].growth_rate {
            least_stable = m;
        }
    }
    let max_growth_rate = modes[least_stable].growth_rate;
    let normal = modes.iter().find(|m| m.kind == ModeKind::Normal).map_or(f64::NAN, |m| m.frequency);
    LinearStability {
        eigenvalues,
        modes,
        least_stable,
        max_growth_rate,
        least_stable_frequency: modes[least_stable].frequency,
        stable: max_growth_rate < 0.0,
        normal_mode_frequency_hz: normal / (2.0 * std::f64::consts::PI),
        status: Status::Success,
    }
}

/// [`linear_stability`] from parameters.
///
/// # Errors
/// The first parameter out of range (see [`Params::validate`]).
pub fn linear_stability_of(p: &Params) -> Result<LinearStability, ParamError> {
    Ok(linear_stability(&Slider::new(*p)?))
}

/// Direction of a Hopf crossing as the normal load increases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HopfDirection {
    /// Stable below the load, unstable above it.
    StableToUnstable,
    /// Unstable below the load, stable above it (the seed configuration's torsion mode, MODEL.md §4).
    UnstableToStable,
}

/// A normal load where the largest real part of the eigenvalues changes sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HopfPoint {
    /// Normal load F_st at the crossing [N].
    pub normal_load: f64,
    /// Direction of the crossing as the load increases.
    pub direction: HopfDirection,
    /// Mode that crosses the imaginary axis.
    pub mode: ModeKind,
    /// Its frequency `Im(lambda)` at the crossing [rad/s].
    pub frequency: f64,
    /// Width of the final bracket [N].
    pub bracket: f64,
    /// Function evaluations spent on the refinement.
    pub evaluations: u32,
    /// `Success`, or `NotConverged` if the refinement ran out of iterations (the load is then the
    /// best estimate inside `bracket`), or the status of a failed eigenvalue computation.
    pub status: Status,
    /// True if the load is outside 22-93 N, the range of loads the contact law was identified from
    /// (report Table 1): the result is an extrapolation (MODEL.md §3).
    pub extrapolated: bool,
}

/// Range of loads the contact law was identified from (report Table 1) [N].
pub const IDENTIFIED_LOAD_RANGE: (f64, f64) = (22.0, 93.0);

/// Largest real part of the eigenvalues at normal load `load` (others from `p`), with its stability
/// analysis.
fn at_load(p: &Params, load: f64) -> Result<LinearStability, ParamError> {
    linear_stability_of(&Params { normal_load: load, ..*p })
}

/// Hopf loads of steady sliding in `[load_min, load_max]` (MODEL.md §4).
///
/// Only `z_st` and `K_s` follow the load (the slider is rebuilt with `normal_load` changed; `K_phi`,
/// `C_zc`, `mu` stay fixed). The largest real part is sampled on `n_grid` log-spaced loads; each
/// sign change is refined with Brent's method to a relative bracket of 1e-10. Crossings closer than
/// the grid spacing in pairs (an unstable window narrower than one grid cell) are missed: refine
/// the grid to find them. Points are returned in increasing load.
///
/// # Errors
/// [`ParamError::OutOfRange`] if `p` is invalid or the load range is not `0 < load_min < load_max`
/// (finite), or `n_grid < 2`. A numerical failure of one refinement is in that point's `status`.
pub fn hopf_loads(p: &Params, load_min: f64, load_max: f64, n_grid: usize) -> Result<Vec<HopfPoint>, ParamError> {
    if !(load_min.is_finite() && load_min > 0.0) {
        return Err(ParamError::OutOfRange { name: "load_min", value: load_min, range: "a finite number > 0" });
    }
    if !(load_max.is_finite() && load_max > load_min) {
        return Err(ParamError::OutOfRange { name: "load_max", value: load_max, range: "a finite number > load_min" });
    }
    if n_grid < 2 {
        return Err(ParamError::OutOfRange { name: "n_grid", value: n_grid as f64, range: ">= 2" });
    }
    p.validate()?;
    let ratio = (load_max / load_min).ln();
    let grid: Vec<f64> = (0..n_grid)
        .map(|i| if i + 1 == n_grid { load_max } else { load_min * (ratio * i as f64 / (n_grid - 1) as f64).exp() })
        .collect();
    let mut vals = Vec::with_capacity(n_grid);
    for &f in &grid {
        vals.push(at_load(p, f)?.max_growth_rate);
    }
    let mut out = Vec::new();
    for i in 0..n_grid - 1 {
        let (a, b) = (vals[i], vals[i + 1]);
        if !(a.is_finite() && b.is_finite()) || (a < 0.0) == (b < 0.0) {
            continue;
        }
        let f = |load: f64| at_load(p, load).map(|s| s.max_growth_rate).unwrap_or(f64::NAN);
        let r = brent(f, grid[i], grid[i + 1], a, b, 1e-10, 200);
        let st = at_load(p, r.x)?;
        let mode = st.modes[st.least_stable];
        out.push(HopfPoint {
            normal_load: r.x,
            direction: if a < 0.0 { HopfDirection::StableToUnstable } else { HopfDirection::UnstableToStable },
            mode: mode.kind,
            frequency: mode.frequency,
            bracket: r.bracket,
            evaluations: r.evaluations,
            status: if st.status != Status::Success {
                st.status
            } else if r.converged {
                Status::Success
            } else {
                Status::NotConverged
            },
            extrapolated: r.x < IDENTIFIED_LOAD_RANGE.0 || r.x > IDENTIFIED_LOAD_RANGE.1,
        });
    }
    Ok(out)
}

/// Result of [`brent`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct BrentResult {
    pub x: f64,
    pub bracket: f64,
    pub evaluations: u32,
    pub converged: bool,
}

/// Brent's root finder on a bracket `[a, b]` with `f(a) = fa`, `f(b) = fb` of opposite signs;
/// stops when the bracket is below `rtol * |x|` (plus a tiny absolute floor) or `f(x) = 0`.
pub(crate) fn brent<F: FnMut(f64) -> f64>(
    mut f: F,
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    rtol: f64,
    max_iter: u32,
) -> BrentResult {
    // Classic Brent (Numerical Recipes' zbrent layout).
    let (mut a, mut b, mut fa, mut fb) = (a, b, fa, fb);
    let (mut c, mut fc) = (b, fb);
    let (mut d, mut e) = (b - a, b - a);
    let mut evals = 0;
    for _ in 0..max_iter {
        if (fb > 0.0 && fc > 0.0) || (fb < 0.0 && fc < 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.5 * rtol * b.abs() + 1e-300;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            return BrentResult { x: b, bracket: (c - b).abs(), evaluations: evals, converged: true };
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            let min1 = 3.0 * xm * q - (tol1 * q).abs();
            let min2 = (e * q).abs();
            if 2.0 * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = f(b);
        evals += 1;
        if !fb.is_finite() {
            return BrentResult { x: b, bracket: (c - b).abs(), evaluations: evals, converged: false };
        }
    }
    BrentResult { x: b, bracket: (c - b).abs(), evaluations: evals, converged: false }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed() -> LinearStability {
        linear_stability(&Slider::seed())
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn seed_eigenvalues_match_model_md() {
        let s = seed();
        assert_eq!(s.status, Status::Success);
        // MODEL.md §4 / seed_values.json: (x) -1.1578 ± 306.303j, (torsion) -0.3285 ± 646.627j,
        // (normal) -50.0279 ± 1440.265j: 4 significant digits on each part.
        let expect = [
            (ModeKind::Friction, -1.1578, 306.303),
            (ModeKind::Torsion, -0.3285, 646.627),
            (ModeKind::Normal, -50.0279, 1440.265),
        ];
        for (m, (kind, re, im)) in s.modes.iter().zip(expect) {
            assert_eq!(m.kind, kind, "{m:?}");
            assert!(close(m.eigenvalue.re, re, 5e-4), "{kind:?}: {}", m.eigenvalue);
            assert!(close(m.eigenvalue.im, im, 5e-5), "{kind:?}: {}", m.eigenvalue);
            assert_eq!(m.partner, m.eigenvalue.conj());
            eprintln!("{:>8}: {:.6} participation {:?}", kind.name(), m.eigenvalue, m.participation);
        }
        assert!(s.stable);
        assert_eq!(s.modes[s.least_stable].kind, ModeKind::Torsion);
        assert!(close(s.max_growth_rate, -0.3285, 5e-4));
        // MODEL.md §8: 229.2 Hz.
        assert!((s.normal_mode_frequency_hz - 229.2).abs() < 0.05, "{}", s.normal_mode_frequency_hz);
        // Deterministic order: mode by mode, upper member first.
        for m in 0..3 {
            assert!(s.eigenvalues[2 * m].im > 0.0 && s.eigenvalues[2 * m + 1].im < 0.0);
        }
    }

    #[test]
    fn decoupled_limit_is_three_damped_oscillators() {
        let p = Params { contact_quadratic: 0.0, mu: 0.0, twist_coupling: 0.0, ..Params::seed() };
        let s = linear_stability_of(&p).unwrap();
        let osc = |k: f64, c: f64, m: f64| {
            // roots of m l^2 + c l + k = 0 (underdamped here)
            let re = -c / (2.0 * m);
            let im = (k / m - re * re).sqrt();
            C64::new(re, im)
        };
        let (wz, wx, wt) = (p.omega_normal, p.omega_friction, p.omega_torsion);
        let m = p.mass;
        let expect = [
            (ModeKind::Friction, osc(m * wx * wx, 2.0 * p.zeta_friction * m * wx, m)),
            (ModeKind::Torsion, osc(wt * wt, 2.0 * p.zeta_torsion * wt, 1.0)),
            (
                ModeKind::Normal,
                osc(m * wz * wz + p.contact_stiffness, 2.0 * p.zeta_normal * m * wz + p.contact_damping, m),
            ),
        ];
        for (kind, l) in expect {
            let got = s.mode(kind).eigenvalue;
            assert!((got - l).norm() <= 1e-10 * l.norm(), "{kind:?}: {got} vs {l}");
            let part = s.mode(kind).participation;
            let k = ModeKind::ALL.iter().position(|&x| x == kind).unwrap();
            assert!(part[k] > 1.0 - 1e-12, "{kind:?} {part:?}");
        }
    }

    #[test]
    fn hopf_loads_match_model_md() {
        // MODEL.md §4 / seed_values.json, to 0.1 %.
        for (mu, load) in [(0.20, 4.162), (0.215, 24.904), (0.25, 74.514), (0.30, 148.277), (0.35, 225.364)] {
            let p = Params { mu, ..Params::seed() };
            let h = hopf_loads(&p, 1.0, 250.0, 60).unwrap();
            assert_eq!(h.len(), 1, "mu = {mu}: {h:?}");
            let h = h[0];
            eprintln!(
                "mu = {mu}: Hopf load {:.6} N ({:?}, {:.3} rad/s, {} evals)",
                h.normal_load, h.direction, h.frequency, h.evaluations
            );
            assert!(close(h.normal_load, load, 1e-3), "mu = {mu}: {} vs {load}", h.normal_load);
            assert_eq!(h.status, Status::Success);
            assert!(h.bracket <= 2e-10 * h.normal_load);
            assert_eq!(h.direction, HopfDirection::UnstableToStable);
            assert_eq!(h.mode, ModeKind::Torsion);
            // At the crossing the torsion eigenvalue is on the imaginary axis.
            let s = at_load(&p, h.normal_load).unwrap();
            assert!(s.max_growth_rate.abs() < 1e-8, "{}", s.max_growth_rate);
        }
    }

    #[test]
    fn stable_or_unstable_at_every_load() {
        // MODEL.md §4: mu <= 0.15 stable at every load 1-250 N; mu >= 0.40 unstable at every load.
        let loads: Vec<f64> = (0..=100).map(|i| 1.0 * 250f64.powf(i as f64 / 100.0)).collect();
        for mu in [0.0, 0.05, 0.10, 0.15] {
            let p = Params { mu, ..Params::seed() };
            assert!(hopf_loads(&p, 1.0, 250.0, 200).unwrap().is_empty());
            for &f in &loads {
                assert!(at_load(&p, f).unwrap().stable, "mu = {mu}, load {f}");
            }
        }
        for mu in [0.40, 0.45, 0.5] {
            let p = Params { mu, ..Params::seed() };
            assert!(hopf_loads(&p, 1.0, 250.0, 200).unwrap().is_empty());
            for &f in &loads {
                assert!(!at_load(&p, f).unwrap().stable, "mu = {mu}, load {f}");
            }
        }
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let p = Params::seed();
        assert!(hopf_loads(&p, 0.0, 10.0, 10).is_err());
        assert!(hopf_loads(&p, 10.0, 5.0, 10).is_err());
        assert!(hopf_loads(&p, 1.0, 10.0, 1).is_err());
        assert!(hopf_loads(&Params { mass: -1.0, ..p }, 1.0, 10.0, 10).is_err());
        let mut j = Slider::seed().jacobian(&State::zeros(), ContactMode::Contact);
        j[(1, 0)] = f64::NAN;
        assert!(eigenvalues(&j).is_none());
    }

    #[test]
    fn brent_finds_a_simple_root() {
        let r = brent(|x| x * x - 2.0, 0.0, 2.0, -2.0, 2.0, 1e-14, 100);
        assert!(r.converged && (r.x - 2f64.sqrt()).abs() < 1e-13, "{r:?}");
    }
}
