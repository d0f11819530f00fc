//! Hopf bifurcations of an equilibrium: where a complex pair crosses the imaginary axis, and on
//! which side the small cycle is born.
//!
//! A tour:
//! - this file, the generic part: a [`VectorField`] `f: R^N -> R^N` with its Jacobian and the
//!   multilinear forms `B`, `C` of its Taylor expansion; the critical eigenpair; the first
//!   Lyapunov coefficient [`first_lyapunov`] by Kuznetsov's invariant formula; a [`Family`] of
//!   fields over one or two parameters and the tracked critical eigenvalue with its parameter
//!   gradient ([`track`]).
//! - [`slider`]: steady sliding of the slider as a vector field (analytic `B`, `C` for every
//!   friction law) and the parameter axes (a model field, or the apparatus' arm length).
//! - [`scan`]: steady sliding along one parameter, every Hopf point located and classified.
//! - [`curve`]: Hopf curves in two parameters by pseudo-arclength continuation.
//!
//! **The formula** (Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed., §3.5 and §5.4).
//! At an equilibrium `x0` with Jacobian `A`, `f(x0 + u) = A u + B(u,u)/2 + C(u,u,u)/6 + O(|u|^4)`.
//! With `A q = i w q`, `A^T p = -i w p`, `<p, q> = conj(p)^T q = 1`:
//!
//! ```text
//!   h11 = -A^-1 B(q, conj q),   h20 = (2 i w I - A)^-1 B(q, q),
//!   c1  = 1/2 <p, C(q, q, conj q) + B(conj q, h20) + 2 B(q, h11)>,   l1 = Re(c1) / w.
//! ```
//!
//! Near the Hopf point `x(t) = x0 + 2 Re(v q) + O(|v|^2)` with `v' = lambda v + c1 v |v|^2 + O(|v|^4)`,
//! `lambda = a + i w` the critical eigenvalue. `l1 < 0`: supercritical (a stable cycle is born on
//! the unstable side); `l1 > 0`: subcritical (an unstable cycle surrounds the stable equilibrium).
//! The cycle has `|v|^2 = -a / (w l1)`. `l1` scales with the square of the size of `q`: only its
//! sign is invariant. [`first_lyapunov`] normalises `q` in a weighted norm given by the caller
//! (unit weights: Kuznetsov's `<q, q> = 1`).
//!
//! **Derivatives.** `B` and `C` are the field's own (the slider's are analytic). The default
//! methods of [`VectorField`] difference the analytic Jacobian instead: one central difference
//! for `B` (step `eps^(1/3)`, truncation `O(h^2)` against rounding `O(eps/h)`: error about
//! `eps^(2/3)` = 4e-11 relative) and a second one for `C` (step `eps^(1/4)`, truncation `O(h^2)`
//! against rounding `O(eps/h^2)`: about `eps^(1/2)` = 1.5e-8). Differencing `f` itself would lose
//! one more order each (errors `eps^(1/2)` and `eps^(2/5)`).

use nalgebra::{Complex, DMatrix, SMatrix, SVector};
use thiserror::Error;

pub mod curve;
pub mod scan;
pub mod slider;

/// Complex double.
pub type C64 = Complex<f64>;
/// Complex vector of length `N`.
pub type CVector<const N: usize> = SVector<C64, N>;
/// Complex `N x N` matrix.
pub type CMatrix<const N: usize> = SMatrix<C64, N, N>;

/// `eps^(1/3)`: the step of the central difference of the Jacobian that gives `B`.
pub const H_BILINEAR: f64 = 6.055454452393343e-6;
/// `eps^(1/4)` (exactly `2^-13`): the step of the second difference of the Jacobian that gives `C`.
pub const H_TRILINEAR: f64 = 1.220703125e-4;
/// `|l1|` below this fraction of the size of the terms summed into it is zero to their accuracy
/// (finite-difference `C` is good to 1.5e-8): criticality undetermined there.
pub const DEGENERATE_RTOL: f64 = 1e-7;
/// Smallest ratio of the second-smallest to the largest pivot of `A - lambda I` (complete
/// pivoting, balanced `A`) for `lambda` to count as a simple eigenvalue.
pub const SIMPLE_PIVOT_RTOL: f64 = 1e-9;

/// Why a Hopf normal form could not be computed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum HopfError {
    /// The Jacobian has a NaN or infinite entry.
    #[error("the Jacobian is not finite")]
    NonFinite,
    /// The eigenvalue is not part of a complex pair with positive imaginary part.
    #[error("lambda = {re} + {im}i is not oscillatory: a Hopf pair needs Im(lambda) > 0")]
    NotOscillatory { re: f64, im: f64 },
    /// `A - lambda I` has (numerically) rank below `N - 1`: lambda is not a simple eigenvalue.
    #[error("lambda = {re} + {im}i is not a simple eigenvalue (pivot ratio {ratio:e})")]
    NotSimple { re: f64, im: f64, ratio: f64 },
    /// `A` is singular: a zero eigenvalue beside the pair (fold-Hopf); `h11` is undefined.
    #[error("the Jacobian is singular (a zero eigenvalue beside the Hopf pair: fold-Hopf)")]
    SingularJacobian,
    /// `2 i w` is an eigenvalue (1:2 resonance); `h20` is undefined.
    #[error("2iw = {0}i is an eigenvalue (1:2 resonance)")]
    Resonance(f64),
    /// The QR iteration of the eigenvalue computation did not converge.
    #[error("the eigenvalue computation did not converge")]
    Eigen,
}

/// A smooth vector field `f: R^N -> R^N` with its derivatives.
pub trait VectorField<const N: usize> {
    /// `f(x)`.
    fn rhs(&self, x: &SVector<f64, N>) -> SVector<f64, N>;
    /// `Df(x)`.
    fn jacobian(&self, x: &SVector<f64, N>) -> SMatrix<f64, N, N>;
    /// Per component, the length over which `f` changes by its own size: the default difference
    /// steps perturb `x` by `H` times these in the scaled maximum norm.
    fn fd_scale(&self) -> SVector<f64, N> {
        SVector::repeat(1.0)
    }
    /// `B(u, v) = D^2 f(x)[u, v]`. Default: central difference of the Jacobian along `v`.
    fn bilinear(&self, x: &SVector<f64, N>, u: &SVector<f64, N>, v: &SVector<f64, N>) -> SVector<f64, N> {
        let size = scaled_size(v, &self.fd_scale());
        if size == 0.0 {
            return SVector::zeros();
        }
        fd_bilinear(self, x, u, v, H_BILINEAR / size)
    }
    /// `C(u, v, w) = D^3 f(x)[u, v, w]`. Default: second difference of the Jacobian along `v`, `w`.
    fn trilinear(
        &self,
        x: &SVector<f64, N>,
        u: &SVector<f64, N>,
        v: &SVector<f64, N>,
        w: &SVector<f64, N>,
    ) -> SVector<f64, N> {
        let scale = self.fd_scale();
        let size = scaled_size(v, &scale).max(scaled_size(w, &scale));
        if size == 0.0 {
            return SVector::zeros();
        }
        fd_trilinear(self, x, u, v, w, H_TRILINEAR / size)
    }
}

/// `max_i |v_i| / scale_i`.
fn scaled_size<const N: usize>(v: &SVector<f64, N>, scale: &SVector<f64, N>) -> f64 {
    v.iter().zip(scale.iter()).map(|(a, s)| a.abs() / s).fold(0.0, f64::max)
}

/// `B(u, v) ~ (J(x + h v) - J(x - h v)) u / 2h`: error `O(h^2)` plus rounding `O(eps/h)`.
pub fn fd_bilinear<F: VectorField<N> + ?Sized, const N: usize>(
    f: &F,
    x: &SVector<f64, N>,
    u: &SVector<f64, N>,
    v: &SVector<f64, N>,
    h: f64,
) -> SVector<f64, N> {
    (f.jacobian(&(x + v * h)) - f.jacobian(&(x - v * h))) * u / (2.0 * h)
}

/// `C(u, v, w) ~ (J(x+h(v+w)) - J(x+h(v-w)) - J(x-h(v-w)) + J(x-h(v+w))) u / 4h^2`: the first-
/// and third-order terms cancel by symmetry, so the error is `O(h^2)` plus rounding `O(eps/h^2)`.
pub fn fd_trilinear<F: VectorField<N> + ?Sized, const N: usize>(
    f: &F,
    x: &SVector<f64, N>,
    u: &SVector<f64, N>,
    v: &SVector<f64, N>,
    w: &SVector<f64, N>,
    h: f64,
) -> SVector<f64, N> {
    let (s, d) = ((v + w) * h, (v - w) * h);
    (f.jacobian(&(x + s)) - f.jacobian(&(x + d)) - f.jacobian(&(x - d)) + f.jacobian(&(x - s))) * u / (4.0 * h * h)
}

fn split<const N: usize>(z: &CVector<N>) -> (SVector<f64, N>, SVector<f64, N>) {
    (z.map(|c| c.re), z.map(|c| c.im))
}

fn join<const N: usize>(re: SVector<f64, N>, im: SVector<f64, N>) -> CVector<N> {
    CVector::<N>::from_fn(|i, _| C64::new(re[i], im[i]))
}

/// `B(u, v)` for complex arguments, by bilinearity from four real evaluations.
pub fn bilinear_c<F: VectorField<N> + ?Sized, const N: usize>(
    f: &F,
    x: &SVector<f64, N>,
    u: &CVector<N>,
    v: &CVector<N>,
) -> CVector<N> {
    let ((ur, ui), (vr, vi)) = (split(u), split(v));
    let b = |a: &SVector<f64, N>, c: &SVector<f64, N>| f.bilinear(x, a, c);
    join(b(&ur, &vr) - b(&ui, &vi), b(&ur, &vi) + b(&ui, &vr))
}

/// `C(u, v, w)` for complex arguments, by trilinearity from eight real evaluations.
pub fn trilinear_c<F: VectorField<N> + ?Sized, const N: usize>(
    f: &F,
    x: &SVector<f64, N>,
    u: &CVector<N>,
    v: &CVector<N>,
    w: &CVector<N>,
) -> CVector<N> {
    let ((ur, ui), (vr, vi), (wr, wi)) = (split(u), split(v), split(w));
    let c = |a: &SVector<f64, N>, b: &SVector<f64, N>, d: &SVector<f64, N>| f.trilinear(x, a, b, d);
    let re = c(&ur, &vr, &wr) - c(&ur, &vi, &wi) - c(&ui, &vr, &wi) - c(&ui, &vi, &wr);
    let im = c(&ur, &vr, &wi) + c(&ur, &vi, &wr) + c(&ui, &vr, &wr) - c(&ui, &vi, &wi);
    join(re, im)
}

/// `<p, q> = conj(p)^T q`.
pub fn inner<const N: usize>(p: &CVector<N>, q: &CVector<N>) -> C64 {
    p.iter().zip(q.iter()).map(|(a, b)| a.conj() * b).sum()
}

fn complexify<const N: usize>(a: &SMatrix<f64, N, N>) -> CMatrix<N> {
    a.map(|v| C64::new(v, 0.0))
}

/// Gaussian elimination with complete pivoting on `a` (and the same row operations on `b`), for
/// `steps` columns. Returns the column permutation: unknown `k` of the reduced system is `perm[k]`.
fn eliminate<const N: usize>(a: &mut CMatrix<N>, b: &mut CVector<N>, steps: usize) -> [usize; N] {
    let mut perm: [usize; N] = std::array::from_fn(|i| i);
    for k in 0..steps {
        let (mut pi, mut pj, mut best) = (k, k, -1.0);
        for j in k..N {
            for i in k..N {
                let m = a[(i, j)].norm_sqr();
                if m > best {
                    (pi, pj, best) = (i, j, m);
                }
            }
        }
        a.swap_rows(k, pi);
        b.swap_rows(k, pi);
        a.swap_columns(k, pj);
        perm.swap(k, pj);
        let piv = a[(k, k)];
        if piv.norm_sqr() == 0.0 {
            break;
        }
        for i in k + 1..N {
            let f = a[(i, k)] / piv;
            if f.norm_sqr() != 0.0 {
                for j in k..N {
                    let akj = a[(k, j)];
                    a[(i, j)] -= f * akj;
                }
                let bk = b[k];
                b[i] -= f * bk;
            }
        }
    }
    perm
}

/// Back substitution on the upper triangle of `a` for the first `n` unknowns, with the unknowns
/// from `n` on already set in `y`.
fn back_substitute<const N: usize>(a: &CMatrix<N>, b: &CVector<N>, y: &mut CVector<N>, n: usize) {
    for k in (0..n).rev() {
        let mut s = b[k];
        for j in k + 1..N {
            s -= a[(k, j)] * y[j];
        }
        y[k] = s / a[(k, k)];
    }
}

/// Solve `m x = b` (complete pivoting); `None` if `m` is singular to working precision.
pub fn solve<const N: usize>(m: &CMatrix<N>, b: &CVector<N>) -> Option<CVector<N>> {
    let (mut a, mut rhs) = (*m, *b);
    let scale = m.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let perm = eliminate(&mut a, &mut rhs, N);
    // NaN pivots fail this too.
    let last = a[(N - 1, N - 1)].norm();
    if last.is_nan() || last <= (N as f64) * f64::EPSILON * scale {
        return None;
    }
    let mut y = CVector::<N>::zeros();
    back_substitute(&a, &rhs, &mut y, N);
    let mut x = CVector::<N>::zeros();
    for k in 0..N {
        x[perm[k]] = y[k];
    }
    x.iter().all(|c| c.re.is_finite() && c.im.is_finite()).then_some(x)
}

/// Null vector of a matrix of rank `N - 1` (complete pivoting; the last pivot is dropped), and the
/// ratio of its second-smallest to its largest pivot (small: rank below `N - 1`).
fn null_vector<const N: usize>(m: &CMatrix<N>) -> (CVector<N>, f64) {
    let (mut a, mut rhs) = (*m, CVector::<N>::zeros());
    let perm = eliminate(&mut a, &mut rhs, N - 1);
    let ratio = if N >= 2 { a[(N - 2, N - 2)].norm() / a[(0, 0)].norm() } else { 1.0 };
    let mut y = CVector::<N>::zeros();
    y[N - 1] = C64::new(1.0, 0.0);
    back_substitute(&a, &rhs, &mut y, N - 1);
    let mut x = CVector::<N>::zeros();
    for k in 0..N {
        x[perm[k]] = y[k];
    }
    (x, ratio)
}

/// All eigenvalues of a real matrix (balanced, then the real Schur form), unordered.
///
/// # Errors
/// `None` if `a` is not finite or the QR iteration does not converge.
pub fn spectrum<const N: usize>(a: &SMatrix<f64, N, N>) -> Option<Vec<C64>> {
    if !a.iter().all(|v| v.is_finite()) {
        return None;
    }
    let (b, _) = crate::linear::balance(a);
    let d = DMatrix::from_column_slice(N, N, b.as_slice());
    let schur = d.try_schur(f64::EPSILON, 10_000)?;
    Some(schur.complex_eigenvalues().iter().copied().collect())
}

/// A simple eigenvalue with its right and left eigenvectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EigenPair<const N: usize> {
    /// The eigenvalue.
    pub lambda: C64,
    /// `A q = lambda q`, normalised to `sum_i w_i |q_i|^2 = 1` (weights of [`eigenpair`]), with the
    /// phase that makes its largest weighted component real and positive.
    pub q: CVector<N>,
    /// `A^T p = conj(lambda) p`, normalised to `<p, q> = 1`.
    pub p: CVector<N>,
}

impl<const N: usize> EigenPair<N> {
    /// `d lambda` for a change `da` of the matrix: `<p, dA q>` (first-order perturbation theory).
    pub fn derivative(&self, da: &SMatrix<f64, N, N>) -> C64 {
        inner(&self.p, &(complexify(da) * self.q))
    }
}

/// Right and left eigenvectors of the simple eigenvalue `lambda` of `a`, computed as null vectors
/// of the balanced `A - lambda I` and its transpose.
///
/// # Errors
/// [`HopfError::NotSimple`] if `A - lambda I` has rank below `N - 1` (or `<p, q> = 0`), and
/// [`HopfError::NonFinite`] for a non-finite matrix.
pub fn eigenpair<const N: usize>(
    a: &SMatrix<f64, N, N>,
    lambda: C64,
    weights: &SVector<f64, N>,
) -> Result<EigenPair<N>, HopfError> {
    if !a.iter().all(|v| v.is_finite()) {
        return Err(HopfError::NonFinite);
    }
    // B = D^-1 A D: A q = lambda q <=> B (D^-1 q) = lambda D^-1 q; A^T p = mu p <=> B^T (D p) = mu D p.
    let (b, d) = crate::linear::balance(a);
    let bc = complexify(&b);
    let id = CMatrix::<N>::identity();
    let (qb, r1) = null_vector(&(bc - id * lambda));
    let (pb, r2) = null_vector(&(bc.transpose() - id * lambda.conj()));
    let not_simple = HopfError::NotSimple { re: lambda.re, im: lambda.im, ratio: r1.min(r2) };
    if !(r1 > SIMPLE_PIVOT_RTOL && r2 > SIMPLE_PIVOT_RTOL) {
        return Err(not_simple);
    }
    let mut q = CVector::<N>::from_fn(|i, _| qb[i] * d[i]);
    let mut p = CVector::<N>::from_fn(|i, _| pb[i] / d[i]);
    let norm = q.iter().zip(weights.iter()).map(|(c, w)| w * c.norm_sqr()).sum::<f64>().sqrt();
    let k =
        (0..N).max_by(|&i, &j| (weights[i] * q[i].norm_sqr()).total_cmp(&(weights[j] * q[j].norm_sqr()))).unwrap_or(0);
    let phase = q[k].conj() / q[k].norm();
    q *= phase / norm;
    let pq = inner(&p, &q);
    if !(pq.norm() > 0.0 && pq.re.is_finite() && pq.im.is_finite()) {
        return Err(not_simple);
    }
    p /= pq.conj();
    Ok(EigenPair { lambda, q, p })
}

/// The normal form of a Hopf point to third order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HopfNormalForm<const N: usize> {
    /// The critical eigenvalue (real part zero at an exact Hopf point).
    pub lambda: C64,
    /// Its imaginary part `w` [rad per time unit].
    pub omega: f64,
    /// Eigenvectors (see [`EigenPair`]).
    pub pair: EigenPair<N>,
    /// Cubic coefficient `c1` of `v' = lambda v + c1 v |v|^2`.
    pub c1: C64,
    /// First Lyapunov coefficient `Re(c1) / w`.
    pub l1: f64,
    /// `(|<p,C(q,q,conj q)>| + |<p,B(conj q,h20)>| + 2|<p,B(q,h11)>|) / 2w`: the size of the terms
    /// summed into `l1`, the scale of its rounding error.
    pub l1_scale: f64,
    /// `h20 = (2iw I - A)^-1 B(q, q)` and `h11 = -A^-1 B(q, conj q)`: the centre manifold to second
    /// order, `x = x0 + 2 Re(v q) + Re(h20 v^2) + h11 |v|^2 + O(|v|^3)`.
    pub h20: CVector<N>,
    /// See `h20` (real up to rounding).
    pub h11: CVector<N>,
}

/// Sign of the first Lyapunov coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Criticality {
    /// `l1 < 0`: a stable cycle is born where the equilibrium is unstable.
    Supercritical = 0,
    /// `l1 > 0`: an unstable cycle surrounds the stable equilibrium (bistability).
    Subcritical = 1,
    /// `|l1|` below [`DEGENERATE_RTOL`] of its terms: at or next to a Bautin point.
    Degenerate = 2,
    /// `l1` could not be computed.
    Undetermined = 3,
}

impl Criticality {
    /// Every value, in code order.
    pub const ALL: [Criticality; 4] =
        [Criticality::Supercritical, Criticality::Subcritical, Criticality::Degenerate, Criticality::Undetermined];

    /// CF flag name.
    pub fn name(self) -> &'static str {
        match self {
            Criticality::Supercritical => "supercritical",
            Criticality::Subcritical => "subcritical",
            Criticality::Degenerate => "degenerate",
            Criticality::Undetermined => "undetermined",
        }
    }

    /// Classify `l1` against the size of its terms.
    pub fn of(l1: f64, scale: f64) -> Criticality {
        if !l1.is_finite() {
            Criticality::Undetermined
        } else if l1.abs() <= DEGENERATE_RTOL * scale {
            Criticality::Degenerate
        } else if l1 > 0.0 {
            Criticality::Subcritical
        } else {
            Criticality::Supercritical
        }
    }
}

/// First Lyapunov coefficient of `f` at the equilibrium `x0`, whose Jacobian has the simple
/// eigenvalue `lambda` (Kuznetsov's invariant formula, see the module docs). `q` is normalised to
/// `sum_i weights_i |q_i|^2 = 1`.
///
/// # Errors
/// A non-finite Jacobian, `Im(lambda) <= 0`, a non-simple eigenvalue, a singular `A` (fold-Hopf)
/// or a 1:2 resonance.
pub fn first_lyapunov<F: VectorField<N> + ?Sized, const N: usize>(
    f: &F,
    x0: &SVector<f64, N>,
    lambda: C64,
    weights: &SVector<f64, N>,
) -> Result<HopfNormalForm<N>, HopfError> {
    let a = f.jacobian(x0);
    let omega = lambda.im;
    if omega.is_nan() || omega <= 0.0 {
        return Err(HopfError::NotOscillatory { re: lambda.re, im: lambda.im });
    }
    let pair = eigenpair(&a, lambda, weights)?;
    let (q, p) = (pair.q, pair.p);
    let qb = q.conjugate();
    let ac = complexify(&a);
    let h11 = solve(&ac, &-bilinear_c(f, x0, &q, &qb)).ok_or(HopfError::SingularJacobian)?;
    let shifted = CMatrix::<N>::identity() * C64::new(0.0, 2.0 * omega) - ac;
    let h20 = solve(&shifted, &bilinear_c(f, x0, &q, &q)).ok_or(HopfError::Resonance(2.0 * omega))?;
    let t1 = inner(&p, &trilinear_c(f, x0, &q, &q, &qb));
    let t2 = inner(&p, &bilinear_c(f, x0, &qb, &h20));
    let t3 = inner(&p, &bilinear_c(f, x0, &q, &h11));
    let c1 = (t1 + t2 + t3 * 2.0) * 0.5;
    if !(c1.re.is_finite() && c1.im.is_finite()) {
        return Err(HopfError::NonFinite);
    }
    Ok(HopfNormalForm {
        lambda,
        omega,
        pair,
        c1,
        l1: c1.re / omega,
        l1_scale: (t1.norm() + t2.norm() + 2.0 * t3.norm()) / (2.0 * omega),
        h20,
        h11,
    })
}

/// A family of vector fields over one or two real parameters, each with an equilibrium known in
/// closed form (steady sliding is `y = 0` at every parameter).
pub trait Family<const N: usize>: Sync {
    /// The vector field at one parameter point.
    type Field: VectorField<N>;
    /// The field at parameters `p` (physical units), or why it cannot be built (out of range).
    ///
    /// # Errors
    /// A message naming the parameter that is out of range.
    fn field(&self, p: &[f64]) -> Result<Self::Field, String>;
    /// The equilibrium of `f`.
    fn equilibrium(&self, _f: &Self::Field) -> SVector<f64, N> {
        SVector::zeros()
    }
    /// Weights of the norm in which the critical eigenvector is normalised, at frequency `omega`.
    fn weights(&self, _f: &Self::Field, _omega: f64) -> SVector<f64, N> {
        SVector::repeat(1.0)
    }
    /// A label of the mode of eigenvalue `lambda` (the slider: friction, torsion, normal).
    fn mode_label(&self, _f: &Self::Field, _lambda: C64) -> u8 {
        0
    }
}

/// Work done, for benchmarks and the output's cost record.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Eigenvalue computations (the cost of one linear-stability evaluation).
    pub n_eig: u64,
    /// Jacobian evaluations (including those of the parameter derivatives).
    pub n_jac: u64,
}

/// The Jacobian at the equilibrium of the field at `p`.
pub fn jacobian_at<Fam: Family<N>, const N: usize>(
    fam: &Fam,
    p: &[f64],
    cnt: &mut Counters,
) -> Result<(Fam::Field, SMatrix<f64, N, N>), String> {
    let f = fam.field(p)?;
    let a = f.jacobian(&fam.equilibrium(&f));
    cnt.n_jac += 1;
    if a.iter().all(|v| v.is_finite()) {
        Ok((f, a))
    } else {
        Err(format!("the Jacobian at {p:?} is not finite"))
    }
}

/// `dA/dp_k` by a central difference of step `h` (`eps^(1/3)` of the parameter's scale), or a
/// one-sided second-order one where one side is outside the valid range.
pub fn jacobian_derivative<Fam: Family<N>, const N: usize>(
    fam: &Fam,
    p: &[f64],
    k: usize,
    h: f64,
    cnt: &mut Counters,
) -> Result<SMatrix<f64, N, N>, String> {
    let at = |dk: f64, cnt: &mut Counters| {
        let mut q = p.to_vec();
        q[k] += dk;
        jacobian_at(fam, &q, cnt).map(|(_, a)| a)
    };
    match (at(h, cnt), at(-h, cnt)) {
        (Ok(ap), Ok(am)) => Ok((ap - am) / (2.0 * h)),
        (Ok(ap), Err(_)) => {
            let a0 = at(0.0, cnt)?;
            let a2 = at(2.0 * h, cnt)?;
            Ok((ap * 4.0 - a0 * 3.0 - a2) / (2.0 * h))
        }
        (Err(_), Ok(am)) => {
            let a0 = at(0.0, cnt)?;
            let a2 = at(-2.0 * h, cnt)?;
            Ok((a0 * 3.0 - am * 4.0 + a2) / (2.0 * h))
        }
        (Err(e), Err(_)) => Err(e),
    }
}

/// The eigenvalue of a family followed from a guess, with its parameter gradient.
#[derive(Clone, Debug)]
pub struct Tracked<const N: usize> {
    /// The eigenvalue nearest the guess (upper half plane, or real).
    pub lambda: C64,
    /// `d lambda / d p_k` for each parameter [per parameter unit].
    pub grad: Vec<C64>,
    /// Distance from the guess to `lambda` over the distance to the next nearest eigenvalue: near 1,
    /// the choice is ambiguous.
    pub ambiguity: f64,
    /// Every other eigenvalue with `Im >= 0` (one per complex pair, every real one).
    pub others: Vec<C64>,
    /// Eigenvectors of `lambda`, normalised with the family's weights.
    pub pair: EigenPair<N>,
}

/// The eigenvalue of the family at `p` nearest `guess`, with `d lambda/dp` (steps `h[k]`).
///
/// # Errors
/// A message: invalid parameters, a non-finite Jacobian, a failed eigenvalue computation or a
/// non-simple eigenvalue.
pub fn track<Fam: Family<N>, const N: usize>(
    fam: &Fam,
    p: &[f64],
    guess: C64,
    h: &[f64],
    cnt: &mut Counters,
) -> Result<Tracked<N>, String> {
    let (f, a) = jacobian_at(fam, p, cnt)?;
    cnt.n_eig += 1;
    let ev = spectrum(&a).ok_or_else(|| format!("the eigenvalue computation failed at {p:?}"))?;
    let upper: Vec<C64> = ev.into_iter().filter(|e| e.im >= 0.0).collect();
    let mut order: Vec<usize> = (0..upper.len()).collect();
    order.sort_by(|&i, &j| (upper[i] - guess).norm().total_cmp(&(upper[j] - guess).norm()));
    let lambda = upper[order[0]];
    let d1 = (lambda - guess).norm();
    let ambiguity = order.get(1).map_or(0.0, |&j| d1 / (upper[j] - guess).norm().max(f64::MIN_POSITIVE));
    let others = order[1..].iter().map(|&j| upper[j]).collect();
    let pair = eigenpair(&a, lambda, &fam.weights(&f, lambda.im)).map_err(|e| format!("{e} at {p:?}"))?;
    let mut grad = Vec::with_capacity(p.len());
    for (k, hk) in h.iter().enumerate().take(p.len()) {
        grad.push(pair.derivative(&jacobian_derivative(fam, p, k, *hk, cnt)?));
    }
    Ok(Tracked { lambda, grad, ambiguity, others, pair })
}

/// The normal form at a point of the family where `lambda` is critical.
///
/// # Errors
/// See [`first_lyapunov`]; invalid parameters.
pub fn normal_form_at<Fam: Family<N>, const N: usize>(
    fam: &Fam,
    p: &[f64],
    lambda: C64,
) -> Result<(HopfNormalForm<N>, u8), String> {
    let f = fam.field(p)?;
    let x0 = fam.equilibrium(&f);
    let nf = first_lyapunov(&f, &x0, lambda, &fam.weights(&f, lambda.im)).map_err(|e| e.to_string())?;
    Ok((nf, fam.mode_label(&f, lambda)))
}

#[cfg(test)]
mod tests;
