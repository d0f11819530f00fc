//! Two-parameter curves of folds of cycles, of grazing and of the onset of sticking, slice by slice.
//!
//! For each value `y_j` of the second parameter the special point is located in the first
//! parameter `x` by the one-parameter continuation itself ([`super::branch`] with `stop_at`), from
//! an anchor orbit on the branch a little before the previous slice's special point; the anchor is
//! carried from `y_{j-1}` to `y_j` by a short branch in `y` at fixed `x`. Why not an augmented
//! system (periodicity plus a fold or grazing condition, continued in `(x, y)`): the fold condition
//! needs second derivatives of the flow, which on this model are finite differences of the
//! monodromy across contact switches (noisy at the level the shooting test of the unilateral
//! monodromy shows, 1e-5 relative), and grazing is a corner of the unilateral branch. The slices
//! reuse only first derivatives, the same detection and the same location tolerance as the
//! one-parameter branch, so each curve point is what a branch at that `y` reports. The price:
//! the curve must be a graph over `y` (one point per slice; a curve that turns back in `y` ends
//! there with its reason), and a slice costs a short branch.

use super::{branch, Branch, BranchError, BranchOptions, BranchPoint, PointType, Start};
use crate::model::{FrictionLaw, Params};
use crate::ode::Stats;
use crate::status::Status;

/// Which special point a curve follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// Fold of cycles (the edge of the bistable region).
    Fold,
    /// Grazing (the orbit first touches contact loss).
    Grazing,
    /// Switch law: the cycle's slip first reaches the stick band (the onset of stick-slip).
    Stick,
}

impl CurveKind {
    fn point_type(self) -> PointType {
        match self {
            CurveKind::Fold => PointType::Fold,
            CurveKind::Grazing => PointType::Grazing,
            CurveKind::Stick => PointType::Stick,
        }
    }
}

/// One point of a two-parameter curve: the special point of the slice `y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint {
    /// Value of the second parameter.
    pub y: f64,
    /// The located point of the branch in `x` at `y` (`point.parameter` is `x`).
    pub point: BranchPoint,
}

/// A two-parameter curve.
#[derive(Clone, Debug)]
pub struct Curve {
    /// The points, one per slice reached, in the order of the `y` values.
    pub points: Vec<CurvePoint>,
    /// `Success` if every slice has its point, else the status of the failure that ended it.
    pub status: Status,
    /// Why it ended (never empty).
    pub reason: String,
    /// Integrator work.
    pub stats: Stats,
    /// Flow integrations.
    pub n_flows: u32,
}

/// Anchors are taken at least this far before the special point (scaled arclength).
const ANCHOR_GAP: f64 = 0.3;

/// Regular points before the special point, nearest last.
fn trail(b: &Branch) -> Vec<BranchPoint> {
    let k = b.points.len().saturating_sub(1);
    b.points[..k].iter().filter(|p| p.point_type == PointType::Regular).copied().collect()
}

/// Anchors for the next slice: the points at least `ANCHOR_GAP` before the special one, nearest first.
fn anchors(trail: &[BranchPoint], special: &BranchPoint) -> Vec<BranchPoint> {
    let mut v: Vec<BranchPoint> =
        trail.iter().rev().filter(|p| (special.arclength - p.arclength).abs() >= ANCHOR_GAP).copied().collect();
    if v.is_empty() {
        v.extend(trail.first().copied());
    }
    v.truncate(3);
    v
}

/// Follow the special point `kind` of the branch of `p` in `x` over the values `ys` of `y`.
///
/// A grazing curve is that of the contact side's grazing (the pin first leaves the disk), followed
/// with the bilateral law, on which that orbit is the same; a fold curve follows smooth folds and
/// grazing points where the branch turns back.
///
/// The first slice, at `y = ys[0]`, is a branch in `x` from `start` at `x = x_value` until its first
/// `kind` point (within `x_bounds`). Each further slice moves an anchor orbit of the previous one to
/// the new `y` and locates the point there. The curve ends early, with its status and reason, when a
/// slice finds no such point inside `x_bounds` or cannot be reached.
///
/// # Errors
/// Bad input before any work (see [`branch`]); `ys` empty or not finite.
#[allow(clippy::too_many_arguments)]
pub fn special_curve(
    p: &Params,
    kind: CurveKind,
    x: &str,
    x_value: f64,
    x_bounds: (f64, f64),
    start: Start,
    y: &str,
    ys: &[f64],
    opts: &BranchOptions,
) -> Result<Curve, BranchError> {
    let Some(&y0) = ys.first() else {
        return Err(BranchError::OutOfRange { name: "ys", value: f64::NAN, range: "at least one value".into() });
    };
    if let Some(bad) = ys.iter().find(|v| !v.is_finite()) {
        return Err(BranchError::OutOfRange { name: "ys", value: *bad, range: "finite values".into() });
    }
    if y == x {
        return Err(BranchError::Parameter(y.to_string(), "the two parameters must differ".into()));
    }
    if kind == CurveKind::Stick && p.friction_law != FrictionLaw::Switch {
        let law = p.friction_law;
        return Err(BranchError::Kind(format!(
            "kind = Stick needs friction_law = Switch, not {law:?}: only the switch law has a stick band"
        )));
    }
    let mut q = *p;
    q.set(y, y0)?;
    if kind == CurveKind::Grazing {
        // The grazing orbit is on the contact side, where the unilateral orbit is the bilateral
        // one: the bilateral law follows it, smoothly on both sides of the grazing point.
        q.contact = crate::model::ContactModel::Bilateral;
    }
    let target = kind.point_type();
    let ox = BranchOptions { stop_at: Some(target), ..*opts };
    let mut curve = Curve {
        points: Vec::new(),
        status: Status::Success,
        reason: String::new(),
        stats: Stats::default(),
        n_flows: 0,
    };
    let add = |c: &mut Curve, b: &Branch| {
        c.stats += b.stats;
        c.n_flows += b.n_flows;
    };
    let first = branch(&q, x, x_value, start, x_bounds, &ox)?;
    add(&mut curve, &first);
    // A fold curve follows smooth folds and the non-smooth ones, where a grazing turns the branch
    // back: both end a family of cycles in the parameter.
    let is_target = move |p: &BranchPoint| {
        p.point_type == target
            || (kind == CurveKind::Fold
                && p.point_type == PointType::Grazing
                && p.flags & super::flags::PARAMETER_TURNS != 0)
    };
    let found = |b: &Branch| b.points.last().filter(|p| is_target(p)).copied();
    let Some(sp) = found(&first) else {
        curve.status = first.status;
        curve.reason = format!("no {:?} point on the first slice ({y} = {y0}): {}", kind, first.reason);
        return Ok(curve);
    };
    curve.points.push(CurvePoint { y: y0, point: sp });
    let mut tr = trail(&first);
    let mut special = sp;
    for w in ys.windows(2) {
        let (ya, yb) = (w[0], w[1]);
        let mut reached: Option<Branch> = None;
        let mut why = String::from("no anchor orbit before the special point");
        for a in anchors(&tr, &special) {
            // Carry the anchor to y_b at fixed x.
            let mut qa = q;
            qa.set(x, a.parameter)?;
            qa.set(y, ya)?;
            let oy = BranchOptions { stop_at: None, ..*opts };
            let dir = if yb > ya { 1.0 } else { -1.0 };
            let (lo, hi) = if yb > ya { (ya, yb) } else { (yb, ya) };
            let start = Start::Orbit { state0: a.state0, period: a.period, direction: dir };
            let by = branch(&qa, y, ya, start, (lo, hi), &oy)?;
            add(&mut curve, &by);
            let Some(end) = by.points.last().filter(|p| p.point_type == PointType::End && p.parameter == yb).copied()
            else {
                why = format!("the anchor at {x} = {} did not reach {y} = {yb}: {}", a.parameter, by.reason);
                continue;
            };
            // Locate the special point in x at y_b, heading the way the previous slice did.
            let mut qb = q;
            qb.set(y, yb)?;
            let mut dir = if a.dp_ds >= 0.0 { 1.0 } else { -1.0 };
            // An anchor already past the grazing (stick) point at the new y: head back to it.
            let band = q.stick_band;
            let past = match kind {
                CurveKind::Grazing => (end.min_gap > 0.0) != (a.min_gap > 0.0),
                CurveKind::Stick => (end.min_slip_velocity < band) != (a.min_slip_velocity < band),
                CurveKind::Fold => false,
            };
            if past {
                dir = -dir;
            }
            let start = Start::Orbit { state0: end.state0, period: end.period, direction: dir };
            let bx = branch(&qb, x, a.parameter, start, x_bounds, &ox)?;
            add(&mut curve, &bx);
            if found(&bx).is_some() {
                reached = Some(bx);
                break;
            }
            why = format!(
                "no {kind:?} point in {x} within {x_bounds:?} from {x} = {} at {y} = {yb}: {}",
                a.parameter, bx.reason
            );
        }
        let Some(bx) = reached else {
            curve.status = Status::NotConverged;
            curve.reason = format!("the curve ends after {y} = {ya}: {why}");
            return Ok(curve);
        };
        special = found(&bx).expect("checked above");
        curve.points.push(CurvePoint { y: yb, point: special });
        tr = trail(&bx);
    }
    curve.reason = format!("every slice located its {kind:?} point ({} values of {y})", ys.len());
    Ok(curve)
}
