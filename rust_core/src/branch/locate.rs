//! Locating a point on the branch: on a plane of one unknown, or at a zero of a test function
//! (bracketed secant or bisection along the tangent). Shared by the follower and the mode-sequence
//! changes, which therefore do not depend on each other.

use super::solve::{fail, node, Ctx, Failure, Node, Xi};
use super::PointType;
use crate::status::Status;

pub(super) fn unit(n: usize, i: usize) -> Xi {
    let mut v = Xi::zeros(n);
    v[i] = 1.0;
    v
}

/// How a test function is searched: on its value (secant), or on a count (bisection).
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Search {
    Secant,
    Bisect,
}

/// The point where the linear unknown `i` of `cur`'s sequence reaches `value` between `cur` and
/// `next`: interpolated, then corrected with that unknown fixed.
pub(super) fn on_plane(ctx: &mut Ctx<'_>, cur: &Node, next: &Node, i: usize, value: f64) -> Result<Node, Failure> {
    let (a, b) = (cur.e.xi[i], next.e.xi[i]);
    let th = ((value - a) / (b - a)).clamp(0.0, 1.0);
    let mut xi = &cur.e.xi + (&next.e.xi - &cur.e.xi) * th;
    xi[i] = value;
    let e = ctx.correct(&xi, &cur.e.seq, &unit(xi.len(), i), &xi)?;
    let t = ctx.tangent(&e.jac, &cur.tangent).unwrap_or_else(|| cur.tangent.clone());
    let s = cur.point.arclength + th * (next.point.arclength - cur.point.arclength);
    Ok(node(ctx, e, t, s))
}

/// Locate a zero of `test` between `cur` and `next` by pseudo-arclength corrections from `cur`
/// along its tangent: a bracketed secant (Illinois), or bisection for a count, to `locate_tol`.
pub(super) fn locate(
    ctx: &mut Ctx<'_>,
    cur: &Node,
    next: &Node,
    ds: f64,
    kind: PointType,
    test: &dyn Fn(&Node) -> f64,
    search: Search,
) -> Result<Node, Failure> {
    let seq = cur.e.seq.clone();
    let (mut a, mut fa, mut b, mut fb) = (0.0, test(cur), ds, test(next));
    let mut side = 0;
    let mut best: Option<Node> = None;
    for _ in 0..100 {
        if b - a <= ctx.opts.locate_tol && best.is_some() {
            break;
        }
        let mut x = 0.5 * (a + b);
        if search == Search::Secant && fa.is_finite() && fb.is_finite() && fb != fa {
            let s = a - fa * (b - a) / (fb - fa);
            let margin = 0.01 * (b - a);
            if s > a + margin && s < b - margin {
                x = s;
            }
        }
        let pred = &cur.e.xi + &cur.tangent * x;
        let e = ctx.correct(&pred, &seq, &cur.tangent, &pred)?;
        let t = ctx.tangent(&e.jac, &cur.tangent).ok_or_else(|| fail(Status::NotConverged, "no tangent".into()))?;
        let n = node(ctx, e, t, cur.point.arclength + x);
        let fx = test(&n);
        if !fx.is_finite() {
            return Err(fail(Status::NonFinite, "non-finite test function".into()));
        }
        let stop = fx == 0.0;
        if (fx > 0.0) == (fa > 0.0) {
            a = x;
            fa = fx;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            b = x;
            fb = fx;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
        best = Some(n);
        if stop {
            break;
        }
    }
    let mut node = best.ok_or_else(|| fail(Status::NotConverged, "nothing to locate".into()))?;
    node.point.point_type = kind;
    Ok(node)
}
