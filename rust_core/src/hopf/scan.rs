//! An equilibrium followed along one parameter: every eigenvalue tracked by continuity, every
//! crossing of the imaginary axis located and, for a complex pair, classified by its first
//! Lyapunov coefficient.
//!
//! The equilibrium is known at every parameter (steady sliding is `y = 0`), so following it is
//! following its spectrum. The samples start on a uniform grid; an interval is halved while
//! (a) the eigenvalues at its ends cannot be matched unambiguously (a step larger than a quarter
//! of the gap between eigenvalues), or (b) a real part keeps its sign at both ends but its cubic
//! Hermite interpolant (values and the exact derivatives `<p, A' q>`) changes sign inside: two
//! crossings in one cell, which a sign test alone misses. Each sign change is then refined by
//! Newton's method on `Re lambda(p)` (exact derivative), safeguarded by bisection.

use super::{normal_form_at, track, Counters, Criticality, Family, HopfNormalForm, Tracked, C64, H_BILINEAR};
use crate::status::Status;

/// Settings of [`scan`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanOptions {
    /// Uniform samples before refinement (>= 2).
    pub n_points: usize,
    /// Tolerance on the located parameter, relative to the range.
    pub xtol: f64,
    /// Smallest interval the refinement halves to, relative to the range.
    pub min_width: f64,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions { n_points: 201, xtol: 1e-13, min_width: 1e-9 }
    }
}

/// The spectrum at one parameter value, in the tracked order.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Parameter value.
    pub value: f64,
    /// Eigenvalues with `Im >= 0` (one per complex pair, every real one), in the order of the first
    /// sample, followed by continuity.
    pub eigenvalues: Vec<C64>,
    /// `d lambda / dp` of each.
    pub grad: Vec<C64>,
    /// Mode label of each (see [`Family::mode_label`]).
    pub labels: Vec<u8>,
}

/// A crossing of the imaginary axis.
#[derive(Clone, Debug)]
pub struct Crossing<const N: usize> {
    /// Parameter value.
    pub value: f64,
    /// Index of the tracked eigenvalue (into [`Sample::eigenvalues`]).
    pub branch: usize,
    /// The eigenvalue at the crossing (real part zero to the tolerance).
    pub lambda: C64,
    /// `d lambda / dp` there; `Re > 0`: the eigenvalue moves to the right as `p` increases.
    pub dlambda: C64,
    /// True for a complex pair (a Hopf point); false for a real eigenvalue through zero.
    pub hopf: bool,
    /// Normal form (Hopf points whose `l1` could be computed).
    pub normal_form: Option<HopfNormalForm<N>>,
    /// Sign of `l1`.
    pub criticality: Criticality,
    /// Mode label.
    pub mode: u8,
    /// Eigenvalues with positive real part other than the crossing ones (0: the point bounds the
    /// region where the equilibrium is stable).
    pub other_unstable: usize,
    /// Final bracket width [parameter units].
    pub bracket: f64,
    /// `Success`, `NewtonNotConverged` (bracket not closed to the tolerance) or `NonFinite`.
    pub status: Status,
    /// Why the status is not success, or why `l1` is missing (empty otherwise).
    pub reason: String,
}

/// Result of [`scan`].
#[derive(Clone, Debug)]
pub struct Scan<const N: usize> {
    /// Samples in increasing parameter.
    pub samples: Vec<Sample>,
    /// Crossings in increasing parameter.
    pub crossings: Vec<Crossing<N>>,
    /// Work done.
    pub counters: Counters,
}

struct Ctx<'a, Fam> {
    fam: &'a Fam,
    h: f64,
    min_width: f64,
    xtol: f64,
    cnt: Counters,
}

impl<Fam> Ctx<'_, Fam> {
    fn sample<const N: usize>(&mut self, v: f64) -> Result<Sample, String>
    where
        Fam: Family<N>,
    {
        let (f, a) = super::jacobian_at(self.fam, &[v], &mut self.cnt)?;
        self.cnt.n_eig += 1;
        let ev: Vec<C64> = super::spectrum(&a)
            .ok_or_else(|| format!("the eigenvalue computation failed at {v}"))?
            .into_iter()
            .filter(|e| e.im >= 0.0)
            .collect();
        let da = super::jacobian_derivative(self.fam, &[v], 0, self.h, &mut self.cnt)?;
        let mut grad = Vec::with_capacity(ev.len());
        let mut labels = Vec::with_capacity(ev.len());
        for e in &ev {
            let w = self.fam.weights(&f, e.im);
            grad.push(super::eigenpair(&a, *e, &w).map(|p| p.derivative(&da)).unwrap_or(C64::new(f64::NAN, f64::NAN)));
            labels.push(self.fam.mode_label(&f, *e));
        }
        Ok(Sample { value: v, eigenvalues: ev, grad, labels })
    }
}

/// Reorder `b` to follow `a` (greedy nearest pairs). Returns the largest move relative to the
/// smallest gap between `a`'s eigenvalues, or infinity when the counts differ.
fn match_to(a: &Sample, b: &mut Sample) -> f64 {
    let n = a.eigenvalues.len();
    if b.eigenvalues.len() != n {
        return f64::INFINITY;
    }
    let mut dist: Vec<(f64, usize, usize)> = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            dist.push(((a.eigenvalues[i] - b.eigenvalues[j]).norm(), i, j));
        }
    }
    dist.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (mut used_a, mut used_b, mut perm) = (vec![false; n], vec![false; n], vec![0; n]);
    let mut worst: f64 = 0.0;
    for (d, i, j) in dist {
        if !used_a[i] && !used_b[j] {
            (used_a[i], used_b[j], perm[i]) = (true, true, j);
            worst = worst.max(d);
        }
    }
    let mut gap = f64::INFINITY;
    for i in 0..n {
        // A complex eigenvalue's conjugate is a neighbour too.
        if a.eigenvalues[i].im > 0.0 {
            gap = gap.min(2.0 * a.eigenvalues[i].im);
        }
        for j in i + 1..n {
            gap = gap.min((a.eigenvalues[i] - a.eigenvalues[j]).norm());
        }
    }
    let reorder = |v: &Vec<C64>| perm.iter().map(|&j| v[j]).collect::<Vec<_>>();
    b.eigenvalues = reorder(&b.eigenvalues);
    b.grad = reorder(&b.grad);
    b.labels = perm.iter().map(|&j| b.labels[j]).collect();
    if n == 0 {
        0.0
    } else {
        worst / gap
    }
}

/// True if the cubic Hermite interpolant of `(g0, d0)`, `(g1, d1)` on `[0, 1]` (derivatives already
/// scaled by the width) takes the sign opposite to `g0` inside while `g0`, `g1` share theirs.
fn hermite_dips(g0: f64, g1: f64, d0: f64, d1: f64) -> bool {
    if !(g0 * g1 > 0.0 && d0.is_finite() && d1.is_finite()) {
        return false;
    }
    // h(t) = g0 H00 + d0 H10 + g1 H01 + d1 H11; h'(t) = 3 a t^2 + 2 b t + c
    let a = 2.0 * g0 + d0 - 2.0 * g1 + d1;
    let b = -3.0 * g0 - 2.0 * d0 + 3.0 * g1 - d1;
    let c = d0;
    let h = |t: f64| ((a * t + b) * t + c) * t + g0;
    let (qa, qb, qc) = (3.0 * a, 2.0 * b, c);
    let mut ts = Vec::new();
    if qa.abs() < 1e-300 {
        if qb != 0.0 {
            ts.push(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let s = disc.sqrt();
            ts.push((-qb - s) / (2.0 * qa));
            ts.push((-qb + s) / (2.0 * qa));
        }
    }
    ts.into_iter().any(|t| t > 0.0 && t < 1.0 && h(t) * g0 < 0.0)
}

/// Follow the equilibrium of `fam` (one parameter) over `[lo, hi]`.
///
/// # Errors
/// A message if a sample cannot be computed (invalid parameters inside the range, a failed
/// eigenvalue computation). A crossing whose refinement or normal form fails is returned with its
/// status and reason.
pub fn scan<Fam: Family<N>, const N: usize>(
    fam: &Fam,
    lo: f64,
    hi: f64,
    opts: &ScanOptions,
) -> Result<Scan<N>, String> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(format!("the range [{lo}, {hi}] must be finite with lo < hi"));
    }
    let n = opts.n_points.max(2);
    let range = hi - lo;
    let mut ctx = Ctx {
        fam,
        h: H_BILINEAR * range,
        min_width: opts.min_width * range,
        xtol: opts.xtol * range,
        cnt: Counters::default(),
    };
    let grid: Vec<f64> = (0..n).map(|i| if i + 1 == n { hi } else { lo + range * i as f64 / (n - 1) as f64 }).collect();
    let mut samples = vec![ctx.sample(grid[0])?];
    let mut crossings = Vec::new();
    for &v in &grid[1..] {
        let b = ctx.sample(v)?;
        let a = samples.last().cloned().expect("non-empty");
        refine(&mut ctx, a, b, &mut samples, &mut crossings)?;
    }
    crossings.sort_by(|a: &Crossing<N>, b| a.value.total_cmp(&b.value));
    Ok(Scan { samples, crossings, counters: ctx.cnt })
}

/// Process the interval `[a, b]` (`a` already in `out`): halve it while it needs it, then push `b`
/// and locate its crossings.
fn refine<Fam: Family<N>, const N: usize>(
    ctx: &mut Ctx<'_, Fam>,
    a: Sample,
    mut b: Sample,
    out: &mut Vec<Sample>,
    crossings: &mut Vec<Crossing<N>>,
) -> Result<(), String> {
    let quality = match_to(&a, &mut b);
    let width = b.value - a.value;
    let dips = (0..a.eigenvalues.len().min(b.eigenvalues.len()))
        .any(|i| hermite_dips(a.eigenvalues[i].re, b.eigenvalues[i].re, a.grad[i].re * width, b.grad[i].re * width));
    if (quality > 0.25 || dips) && width > ctx.min_width {
        let m = ctx.sample(0.5 * (a.value + b.value))?;
        refine(ctx, a, m, out, crossings)?;
        let m = out.last().cloned().expect("pushed");
        return refine(ctx, m, b, out, crossings);
    }
    if quality.is_finite() {
        for i in 0..a.eigenvalues.len() {
            let (ga, gb) = (a.eigenvalues[i].re, b.eigenvalues[i].re);
            if ga.is_finite() && gb.is_finite() && (ga < 0.0) != (gb < 0.0) {
                crossings.push(locate(ctx, &a, &b, i));
            }
        }
    }
    out.push(b);
    Ok(())
}

/// Newton's method on `Re lambda(p) = 0` in the bracket `[a, b]`, safeguarded by bisection.
fn locate<Fam: Family<N>, const N: usize>(ctx: &mut Ctx<'_, Fam>, a: &Sample, b: &Sample, i: usize) -> Crossing<N> {
    let (la, lb) = (a.eigenvalues[i], b.eigenvalues[i]);
    let (mut xa, mut xb, mut fa) = (a.value, b.value, la.re);
    let guess_at = |x: f64| la + (lb - la) * ((x - a.value) / (b.value - a.value));
    let mut x = xa - fa * (xb - xa) / (lb.re - fa);
    let mut status = Status::NewtonNotConverged;
    let mut reason = String::new();
    let mut last: Option<Tracked<N>> = None;
    for _ in 0..100 {
        let t = match track(ctx.fam, &[x], guess_at(x), &[ctx.h], &mut ctx.cnt) {
            Ok(t) if t.ambiguity < 0.5 => t,
            Ok(t) => {
                reason = format!("eigenvalue tracking ambiguous at {x} (ratio {:.2})", t.ambiguity);
                break;
            }
            Err(e) => {
                status = Status::NonFinite;
                reason = e;
                break;
            }
        };
        let (f, df) = (t.lambda.re, t.grad[0].re);
        last = Some(t);
        if f == 0.0 {
            (xa, xb, status) = (x, x, Status::Success);
            break;
        }
        if (f < 0.0) == (fa < 0.0) {
            (xa, fa) = (x, f);
        } else {
            xb = x;
        }
        let newton = x - f / df;
        let step_ok = df.is_finite() && df != 0.0 && newton > xa.min(xb) && newton < xa.max(xb);
        let next = if step_ok { newton } else { 0.5 * (xa + xb) };
        let done = (next - x).abs() <= ctx.xtol || (xb - xa).abs() <= ctx.xtol;
        x = next;
        if done {
            status = Status::Success;
            break;
        }
    }
    // The last evaluation belongs to the previous x; evaluate once more at the final x.
    let fin = track(ctx.fam, &[x], last.as_ref().map_or(guess_at(x), |t| t.lambda), &[ctx.h], &mut ctx.cnt);
    let (lambda, dlambda, others) = match &fin {
        Ok(t) => (t.lambda, t.grad[0], t.others.clone()),
        Err(e) => {
            status = Status::NonFinite;
            reason = e.clone();
            (C64::new(f64::NAN, f64::NAN), C64::new(f64::NAN, f64::NAN), Vec::new())
        }
    };
    let other_unstable = others.iter().filter(|e| e.re > 0.0).map(|e| if e.im > 0.0 { 2 } else { 1 }).sum();
    let hopf = lambda.im > 0.0;
    let (normal_form, mode) = if hopf && status != Status::NonFinite {
        match normal_form_at(ctx.fam, &[x], lambda) {
            Ok((nf, m)) => (Some(nf), m),
            Err(e) => {
                reason = format!("first Lyapunov coefficient not computed: {e}");
                (None, 0)
            }
        }
    } else {
        (None, 0)
    };
    let criticality = normal_form.map_or(Criticality::Undetermined, |nf| Criticality::of(nf.l1, nf.l1_scale));
    if status == Status::NewtonNotConverged && reason.is_empty() {
        reason = format!("the bracket [{xa}, {xb}] did not close to {} in 100 iterations", ctx.xtol);
    }
    Crossing {
        value: x,
        branch: i,
        lambda,
        dlambda,
        hopf,
        normal_form,
        criticality,
        mode,
        other_unstable,
        bracket: (xb - xa).abs(),
        status,
        reason,
    }
}
