//! Hopf curves in two parameters by pseudo-arclength continuation.
//!
//! The equilibrium is known at every parameter, so a Hopf curve is the zero set of one smooth
//! function of the two parameters, `g(s) = Re lambda(s)`, `lambda` the critical eigenvalue followed
//! by continuity and `grad g = Re <p, dA/ds q>` exact up to the difference of `A` in the
//! parameters. Coordinates `s` are box units (`[0, 1]^2`), so a step means the same on both axes.
//!
//! - **Seeds.** The critical pairs' real parts on a coarse grid of nodes; along each grid edge the
//!   eigenvalues at its ends are matched, and each sign change of a complex pair's real part is
//!   located on the edge. A seed within reach of a curve already traced (same frequency) is a
//!   duplicate.
//! - **Continuation.** Tangent predictor `s + h t`, then Newton on `g(s) = 0`,
//!   `t . (s - s_pred) = 0`. A step is rejected (and halved) when Newton fails or the tracked
//!   eigenvalue is ambiguous, and shortened when the tangent turns by more than `max_angle` or the
//!   chord bulges from the arc by more than `chord_tol`; it grows by 1.5 after an easy step. Below
//!   `step_min` the direction ends with `StepFloor` and the reason.
//! - **Special points** between two accepted points are located on the curve (a root in the
//!   arclength `sigma` of the corrected point, by the Illinois method): a sign change of `l1`
//!   (Bautin), of another pair's real part (double Hopf) or of a real eigenvalue (zero-Hopf),
//!   a requested axis value (`marks`). A predictor leaving the box is replaced by the point of the
//!   curve on the box face, found with the face coordinate fixed. A curve that returns to its seed
//!   (the seed's tangent hyperplane crossed from behind within two steps of the seed, same
//!   eigenvalue) is closed.

use super::{normal_form_at, track, Counters, Criticality, Family, C64, H_BILINEAR};
use crate::status::Status;

mod events;
mod seeds;

use seeds::{seeds, segment_distance};

/// Settings of [`hopf_curves`].
#[derive(Clone, Debug, PartialEq)]
pub struct CurveOptions {
    /// Seeding grid: nodes on each axis (>= 2).
    pub grid: [usize; 2],
    /// First step [box units].
    pub step: f64,
    /// Smallest step before a direction ends [box units].
    pub step_min: f64,
    /// Largest step [box units].
    pub step_max: f64,
    /// Newton tolerance on the correction [box units].
    pub tol: f64,
    /// Largest number of points per curve.
    pub max_points: usize,
    /// Largest turn of the tangent per step [rad].
    pub max_angle: f64,
    /// Largest deviation of the polyline from the curve [box units], estimated per step as
    /// `h * angle / 8` (a circular arc of length `h` turning by `angle` bulges `h angle / 8` from
    /// its chord).
    pub chord_tol: f64,
    /// Axis values to mark on the curves (physical units), per axis.
    pub marks: [Vec<f64>; 2],
}

impl Default for CurveOptions {
    fn default() -> Self {
        CurveOptions {
            grid: [16, 16],
            step: 0.01,
            step_min: 1e-7,
            step_max: 0.05,
            tol: 1e-10,
            max_points: 5000,
            max_angle: 0.1,
            chord_tol: 1e-5,
            marks: [Vec::new(), Vec::new()],
        }
    }
}

/// What a curve point is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum PointType {
    /// An ordinary continuation point.
    Regular = 0,
    /// The seed the curve was started from.
    Seed = 1,
    /// `l1 = 0`: the criticality changes (generalised Hopf).
    Bautin = 2,
    /// Another complex pair crosses the imaginary axis (double Hopf).
    DoubleHopf = 3,
    /// The curve leaves the box here.
    BoxExit = 4,
    /// The closing point of a closed curve (the seed again).
    Closure = 5,
    /// The last point of a direction that ended without reaching the box or its start.
    End = 6,
    /// A requested axis value.
    Mark = 7,
    /// A real eigenvalue crosses zero on the curve (fold-Hopf, or zero-Hopf).
    ZeroHopf = 8,
}

impl PointType {
    /// Every value, in code order.
    pub const ALL: [PointType; 9] = [
        PointType::Regular,
        PointType::Seed,
        PointType::Bautin,
        PointType::DoubleHopf,
        PointType::BoxExit,
        PointType::Closure,
        PointType::End,
        PointType::Mark,
        PointType::ZeroHopf,
    ];

    /// CF flag name.
    pub fn name(self) -> &'static str {
        match self {
            PointType::Regular => "regular",
            PointType::Seed => "seed",
            PointType::Bautin => "bautin",
            PointType::DoubleHopf => "double_hopf",
            PointType::BoxExit => "box_exit",
            PointType::Closure => "closure",
            PointType::End => "end",
            PointType::Mark => "mark",
            PointType::ZeroHopf => "zero_hopf",
        }
    }
}

/// How one end of a curve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum EndStatus {
    /// The curve is closed (both ends).
    Closed = 0,
    /// It leaves the box.
    LeftBox = 1,
    /// The step was halved to `step_min` without an acceptable point.
    StepFloor = 2,
    /// `max_points` was reached.
    MaxPoints = 3,
    /// The pair's frequency went to zero (Bogdanov-Takens, or the pair turned real).
    FrequencyVanished = 4,
}

impl EndStatus {
    /// Every value, in code order.
    pub const ALL: [EndStatus; 5] = [
        EndStatus::Closed,
        EndStatus::LeftBox,
        EndStatus::StepFloor,
        EndStatus::MaxPoints,
        EndStatus::FrequencyVanished,
    ];

    /// CF flag name.
    pub fn name(self) -> &'static str {
        match self {
            EndStatus::Closed => "closed",
            EndStatus::LeftBox => "left_box",
            EndStatus::StepFloor => "step_floor",
            EndStatus::MaxPoints => "max_points",
            EndStatus::FrequencyVanished => "frequency_vanished",
        }
    }
}

/// One point of a Hopf curve.
#[derive(Clone, Debug)]
pub struct CurvePoint {
    /// Parameters (physical units).
    pub u: [f64; 2],
    /// The critical eigenvalue (real part zero to the tolerance).
    pub lambda: C64,
    /// First Lyapunov coefficient (NaN if not computed).
    pub l1: f64,
    /// Its sign.
    pub criticality: Criticality,
    /// What the point is.
    pub kind: PointType,
    /// Mode label of the critical pair.
    pub mode: u8,
    /// Other eigenvalues with positive real part.
    pub other_unstable: usize,
    /// `Success`, or `NotConverged` for a special point located only to its bracket.
    pub status: Status,
}

/// One Hopf curve, in order along it.
#[derive(Clone, Debug)]
pub struct Curve {
    /// Points; a closed curve repeats its first point at the end.
    pub points: Vec<CurvePoint>,
    /// How the first and the last point ended the curve, with a reason.
    pub ends: [(EndStatus, String); 2],
}

/// Result of [`hopf_curves`].
#[derive(Clone, Debug)]
pub struct Curves {
    /// Distinct curves.
    pub curves: Vec<Curve>,
    /// Seeds found on the grid edges (duplicates included).
    pub n_seeds: usize,
    /// Work done.
    pub counters: Counters,
}

/// The tracked eigenvalue at one point, with its gradient in box units.
#[derive(Clone, Debug)]
struct Eval {
    lambda: C64,
    /// Gradient of `Re lambda`.
    g: [f64; 2],
    /// Gradient of `lambda`.
    gc: [C64; 2],
    /// Every other eigenvalue with `Im >= 0`.
    others: Vec<C64>,
}

/// An accepted point with its unit tangent (in the direction of travel).
#[derive(Clone, Debug)]
struct Node {
    s: [f64; 2],
    e: Eval,
    t: [f64; 2],
    l1: f64,
    crit: Criticality,
    mode: u8,
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn axpy(a: [f64; 2], h: f64, t: [f64; 2]) -> [f64; 2] {
    [a[0] + h * t[0], a[1] + h * t[1]]
}

fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

/// Unit tangent of the zero set of `Re lambda` (orthogonal to its gradient), oriented along `prev`.
fn tangent(g: [f64; 2], prev: [f64; 2]) -> Option<[f64; 2]> {
    let n = norm(g);
    if !(n > 0.0 && n.is_finite()) {
        return None;
    }
    let t = [-g[1] / n, g[0] / n];
    Some(if dot(t, prev) < 0.0 { [-t[0], -t[1]] } else { t })
}

struct Ctx<'a, Fam> {
    fam: &'a Fam,
    lo: [f64; 2],
    width: [f64; 2],
    h: [f64; 2],
    opts: &'a CurveOptions,
    cnt: Counters,
}

impl<'a, Fam> Ctx<'a, Fam> {
    fn phys(&self, s: [f64; 2]) -> [f64; 2] {
        [self.lo[0] + s[0] * self.width[0], self.lo[1] + s[1] * self.width[1]]
    }

    fn eval<const N: usize>(&mut self, s: [f64; 2], guess: C64) -> Result<Eval, String>
    where
        Fam: Family<N>,
    {
        let t = track(self.fam, &self.phys(s), guess, &self.h, &mut self.cnt)?;
        if t.ambiguity >= 0.5 {
            return Err(format!(
                "the critical eigenvalue is ambiguous at {:?} (ratio {:.2})",
                self.phys(s),
                t.ambiguity
            ));
        }
        let gc = [t.grad[0] * self.width[0], t.grad[1] * self.width[1]];
        Ok(Eval { lambda: t.lambda, g: [gc[0].re, gc[1].re], gc, others: t.others })
    }

    /// Newton on `Re lambda = 0`, `t . (s - pred) = 0`; rejects a correction longer than `reach`.
    fn correct<const N: usize>(
        &mut self,
        pred: [f64; 2],
        t: [f64; 2],
        guess: C64,
        reach: f64,
    ) -> Result<([f64; 2], Eval), String>
    where
        Fam: Family<N>,
    {
        let (mut s, mut guess) = (pred, guess);
        for _ in 0..10 {
            let e = self.eval(s, guess)?;
            let (r0, r1) = (e.lambda.re, dot(t, sub(s, pred)));
            let det = e.g[0] * t[1] - e.g[1] * t[0];
            if !(det.abs() > 0.0 && det.is_finite()) {
                return Err(format!("the corrector is singular at {:?}", self.phys(s)));
            }
            let d = [(-r0 * t[1] + e.g[1] * r1) / det, (-e.g[0] * r1 + t[0] * r0) / det];
            s = axpy(s, 1.0, d);
            guess = e.lambda + e.gc[0] * d[0] + e.gc[1] * d[1];
            if norm(sub(s, pred)) > reach + self.opts.tol {
                return Err(format!("the corrector left the step's reach at {:?}", self.phys(s)));
            }
            if norm(d) <= self.opts.tol {
                let e = self.eval(s, guess)?;
                return Ok((s, e));
            }
        }
        Err(format!("Newton did not converge to {} in 10 iterations near {:?}", self.opts.tol, self.phys(pred)))
    }

    fn node<const N: usize>(&mut self, s: [f64; 2], e: Eval, prev: [f64; 2]) -> Result<Node, String>
    where
        Fam: Family<N>,
    {
        let t =
            tangent(e.g, prev).ok_or_else(|| format!("the gradient of Re lambda vanishes at {:?}", self.phys(s)))?;
        let (l1, crit, mode) = match normal_form_at(self.fam, &self.phys(s), e.lambda) {
            Ok((nf, m)) => (nf.l1, Criticality::of(nf.l1, nf.l1_scale), m),
            Err(_) => (f64::NAN, Criticality::Undetermined, 0),
        };
        Ok(Node { s, e, t, l1, crit, mode })
    }

    fn point(&self, n: &Node, kind: PointType, status: Status) -> CurvePoint {
        let other_unstable = n.e.others.iter().filter(|e| e.re > 0.0).map(|e| if e.im > 0.0 { 2 } else { 1 }).sum();
        CurvePoint {
            u: self.phys(n.s),
            lambda: n.e.lambda,
            l1: n.l1,
            criticality: n.crit,
            kind,
            mode: n.mode,
            other_unstable,
            status,
        }
    }

    /// The point where the curve through `a` meets the box face that `a + sigma t` reaches first,
    /// with the face coordinate fixed (Newton on the other one). `None` if it is not within
    /// `reach` of `a` or not on the same eigenvalue.
    fn exit<const N: usize>(&mut self, a: &Node, reach: f64) -> Option<(f64, Node)>
    where
        Fam: Family<N>,
    {
        let mut faces: Vec<(f64, usize, f64)> = Vec::new();
        for k in 0..2 {
            if a.t[k] > 0.0 {
                faces.push(((1.0 - a.s[k]) / a.t[k], k, 1.0));
            } else if a.t[k] < 0.0 {
                faces.push((-a.s[k] / a.t[k], k, 0.0));
            }
        }
        faces.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (sigma, k, bound) in faces {
            let j = 1 - k;
            let mut s = axpy(a.s, sigma, a.t);
            s[k] = bound;
            s[j] = s[j].clamp(0.0, 1.0);
            let mut guess = a.e.lambda + (a.e.gc[0] * a.t[0] + a.e.gc[1] * a.t[1]) * sigma;
            for _ in 0..20 {
                let Ok(e) = self.eval(s, guess) else { break };
                let d = -e.lambda.re / e.g[j];
                if !d.is_finite() {
                    break;
                }
                s[j] += d;
                guess = e.lambda + e.gc[j] * d;
                if d.abs() <= self.opts.tol {
                    let inside = s[j] >= -self.opts.tol && s[j] <= 1.0 + self.opts.tol;
                    let along = dot(sub(s, a.s), a.t);
                    if !inside || norm(sub(s, a.s)) > reach || along <= 0.0 {
                        break;
                    }
                    let e = self.eval(s, guess).ok()?;
                    let n = self.node(s, e, a.t).ok()?;
                    return Some((along, n));
                }
            }
        }
        None
    }

    /// Follow the curve from `start` along `start.t` until it ends; push its points (not `start`).
    /// With `closable`, a return to `start` closes it.
    fn trace<const N: usize>(
        &mut self,
        start: &Node,
        closable: bool,
        pts: &mut Vec<CurvePoint>,
        budget: usize,
    ) -> (EndStatus, String)
    where
        Fam: Family<N>,
    {
        let opts = self.opts;
        let omega_floor = 1e-6 * start.e.lambda.norm();
        let mut a = start.clone();
        let mut h = opts.step.clamp(opts.step_min, opts.step_max);
        let mut travelled = 0.0;
        let mut last_err = String::new();
        loop {
            // On a face of the box and heading out (a seed on a face, or a point that landed on
            // one): the curve leaves here.
            if (0..2).any(|k| (a.s[k] <= opts.tol && a.t[k] < 0.0) || (a.s[k] >= 1.0 - opts.tol && a.t[k] > 0.0)) {
                if let Some(p) = pts.last_mut() {
                    p.kind = PointType::BoxExit;
                }
                return (EndStatus::LeftBox, format!("leaves the box at {:?}", self.phys(a.s)));
            }
            if pts.len() >= budget {
                if let Some(p) = pts.last_mut() {
                    p.kind = PointType::End;
                }
                return (EndStatus::MaxPoints, format!("reached max_points = {}", opts.max_points));
            }
            if h < opts.step_min {
                if let Some(p) = pts.last_mut() {
                    p.kind = PointType::End;
                }
                return (EndStatus::StepFloor, format!("step halved below step_min = {:e}: {last_err}", opts.step_min));
            }
            // Where the frequency falls, no step may halve it more than once: the pair must not
            // pass through the real axis unseen (the tracked eigenvalue would jump to its mirror).
            let dim = (a.e.gc[0] * a.t[0] + a.e.gc[1] * a.t[1]).im;
            if dim < 0.0 && a.e.lambda.im + h * dim < 0.5 * a.e.lambda.im {
                h = 0.5 * a.e.lambda.im / -dim;
                if h < opts.step_min {
                    last_err = format!("the pair's frequency {:e} heads to zero", a.e.lambda.im);
                    continue;
                }
            }
            let pred = axpy(a.s, h, a.t);
            if pred.iter().any(|&x| !(0.0..=1.0).contains(&x)) {
                if let Some((along, e)) = self.exit(&a, h * 1.5) {
                    for (_, p) in self.locate_events(&a, &e, along) {
                        pts.push(p);
                    }
                    pts.push(self.point(&e, PointType::BoxExit, Status::Success));
                    return (EndStatus::LeftBox, format!("leaves the box at {:?}", self.phys(e.s)));
                }
                last_err = "the curve turns before the box face but no step inside it converged".into();
                h *= 0.5;
                continue;
            }
            let guess = a.e.lambda + (a.e.gc[0] * a.t[0] + a.e.gc[1] * a.t[1]) * h;
            let b = match self.correct(pred, a.t, guess, h).and_then(|(s, e)| self.node(s, e, a.t)) {
                Ok(b) => b,
                Err(e) => {
                    last_err = e;
                    h *= 0.5;
                    continue;
                }
            };
            let angle = dot(a.t, b.t).clamp(-1.0, 1.0).acos();
            let bulge = h * angle / 8.0;
            if (angle > opts.max_angle || bulge > opts.chord_tol) && h > 2.0 * opts.step_min {
                last_err = format!(
                    "the tangent turned by {angle:.3} rad (max_angle {}, chord_tol {:e})",
                    opts.max_angle, opts.chord_tol
                );
                // The bulge grows as h^2: aim at 80 % of the tolerance.
                h *= (0.8 * opts.chord_tol / bulge).sqrt().clamp(0.2, 0.5);
                continue;
            }
            if b.e.lambda.im <= omega_floor {
                pts.push(self.point(&b, PointType::End, Status::Success));
                return (EndStatus::FrequencyVanished, format!("the pair's frequency fell to {:e}", b.e.lambda.im));
            }
            // Closure: crossing the seed's normal hyperplane from behind, close to the seed.
            let (ca, cb) = (dot(sub(a.s, start.s), start.t), dot(sub(b.s, start.s), start.t));
            travelled += h;
            if closable
                && travelled > 3.0 * h
                && ca < 0.0
                && cb >= 0.0
                && norm(sub(b.s, start.s)) <= 2.0 * h
                && (b.e.lambda - start.e.lambda).norm()
                    <= 1e-3 * start.e.lambda.norm() + (b.e.gc[0].norm() + b.e.gc[1].norm()) * 2.0 * h
            {
                let to_start = dot(sub(start.s, a.s), a.t);
                for (_, p) in self.locate_events(&a, start, to_start) {
                    pts.push(p);
                }
                pts.push(self.point(start, PointType::Closure, Status::Success));
                return (EndStatus::Closed, "returned to its seed".into());
            }
            for (_, p) in self.locate_events(&a, &b, h) {
                pts.push(p);
            }
            pts.push(self.point(&b, PointType::Regular, Status::Success));
            if angle < opts.max_angle / 3.0 && bulge < opts.chord_tol / 3.0 {
                h = (h * 1.5).min(opts.step_max);
            }
            a = b;
        }
    }
}

/// Every Hopf curve of `fam` in the box `[lo_k, hi_k]` (physical units), seeded from the grid.
///
/// # Errors
/// A message for an empty or non-finite box or a grid below 2 x 2. Numerical trouble on a curve
/// ends that curve with a status and a reason instead.
pub fn hopf_curves<Fam: Family<N>, const N: usize>(
    fam: &Fam,
    bx: [[f64; 2]; 2],
    opts: &CurveOptions,
) -> Result<Curves, String> {
    for (k, [lo, hi]) in bx.iter().enumerate() {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(format!("axis {k}: the range [{lo}, {hi}] must be finite with lo < hi"));
        }
    }
    if opts.grid.iter().any(|&n| n < 2) {
        return Err(format!("grid = {:?}: must have at least 2 nodes per axis", opts.grid));
    }
    let width = [bx[0][1] - bx[0][0], bx[1][1] - bx[1][0]];
    let mut ctx = Ctx {
        fam,
        lo: [bx[0][0], bx[1][0]],
        width,
        h: [H_BILINEAR * width[0], H_BILINEAR * width[1]],
        opts,
        cnt: Counters::default(),
    };
    let seeds = seeds(&mut ctx);
    let n_seeds = seeds.len();
    let mut curves: Vec<Curve> = Vec::new();
    let mut traced: Vec<Vec<([f64; 2], C64)>> = Vec::new();
    // A chord deviates from its arc by at most min(h max_angle / 8, chord_tol): twice that is
    // "on the curve".
    let reach = (0.25 * opts.step_max * opts.max_angle).min(2.0 * opts.chord_tol).max(100.0 * opts.tol);
    for (s0, e0) in seeds {
        let covered = traced.iter().any(|c| {
            c.windows(2).any(|w| {
                let (d, t) = segment_distance(s0, w[0].0, w[1].0);
                let lam = w[0].1 + (w[1].1 - w[0].1) * t;
                d <= reach && (lam - e0.lambda).norm() <= 1e-3 * e0.lambda.norm()
            })
        });
        if covered {
            continue;
        }
        let Ok(start) = ctx.node(s0, e0, [1.0, 0.0]) else { continue };
        let mut seed_pt = ctx.point(&start, PointType::Seed, Status::Success);
        let mut fwd = Vec::new();
        let end_f = ctx.trace(&start, true, &mut fwd, opts.max_points.saturating_sub(1));
        if end_f.0 == EndStatus::LeftBox && fwd.is_empty() {
            seed_pt.kind = PointType::BoxExit;
        }
        let mut points: Vec<CurvePoint>;
        let ends;
        if end_f.0 == EndStatus::Closed {
            points = vec![seed_pt];
            points.extend(fwd);
            ends = [end_f.clone(), end_f];
        } else {
            let back_start = Node { t: [-start.t[0], -start.t[1]], ..start.clone() };
            let mut bwd = Vec::new();
            let end_b = ctx.trace(&back_start, false, &mut bwd, opts.max_points.saturating_sub(1 + fwd.len()));
            if end_b.0 == EndStatus::LeftBox && bwd.is_empty() {
                seed_pt.kind = PointType::BoxExit;
            }
            bwd.reverse();
            points = bwd;
            points.push(seed_pt);
            points.extend(fwd);
            ends = [end_b, end_f];
        }
        let boxed: Vec<([f64; 2], C64)> = points
            .iter()
            .map(|p| ([(p.u[0] - ctx.lo[0]) / width[0], (p.u[1] - ctx.lo[1]) / width[1]], p.lambda))
            .collect();
        traced.push(boxed);
        curves.push(Curve { points, ends });
    }
    Ok(Curves { curves, n_seeds, counters: ctx.cnt })
}
