//! Changes of the mode sequence along a unilateral branch: where an orbit stops being a physical
//! orbit of its sequence (a segment vanishes, the pin lifts off or detaches in contact, touches
//! down in flight, or a landing changes its event), the grazing point is located and the branch
//! goes on in the new sequence along its physical piece.

use super::locate::{locate, on_plane, unit, Search};
use super::solve::{fail, node, valid, Ctx, Failure, Node, Seq, Xi};
use super::{flags, PointType};
use crate::model::{event, ContactMode};
use crate::status::Status;
use nalgebra::DMatrix;

/// How the mode sequence changes at a grazing point.
enum Change {
    /// Segment `i` vanishes (its duration reaches 0).
    Remove(usize),
    /// A new segment of mode `mode`, entered and left on event `event`, appears inside segment
    /// `i`, `t` after its start (`i = 0, t = 0`: around the phase point).
    Insert { i: usize, t: f64, mode: ContactMode, event: usize },
}

/// `next` is not a physical orbit of `cur`'s sequence: locate where it stops being one (the
/// grazing point: the first violated condition, by a secant search on it), build the new sequence
/// there, and take the first step along the physical piece of the branch. Returns the grazing
/// point and that first point.
pub(super) fn change_sequence(ctx: &mut Ctx<'_>, cur: &Node, next: &Node) -> Result<(Node, Node), Failure> {
    let name = ctx.name.to_string();
    let seq = &cur.e.seq;
    let (va, vb) = (ctx.violations(&cur.e), ctx.violations(&next.e));
    // The condition violated first along the segment (linear interpolation of each).
    let which = (0..5)
        .filter(|&c| vb[c] > 0.0)
        .min_by(|&a, &b| {
            let th = |c: usize| {
                if !va[c].is_finite() {
                    1.0
                } else if va[c] < 0.0 {
                    va[c] / (va[c] - vb[c])
                } else {
                    0.0
                }
            };
            th(a).total_cmp(&th(b))
        })
        .ok_or_else(|| fail(Status::NotConverged, "no violated condition".into()))?;
    let ds = next.point.arclength - cur.point.arclength;
    let inner = which == 0 && {
        let i = next.e.monitors.tau_min.1;
        !(seq.phase_in_flight() && (i == 0 || i == seq.k() - 1)) && i > 0 && i + 1 < seq.k()
    };
    if inner {
        return remove_inner(ctx, cur, next);
    }
    if which == 4 {
        return swap_landing(ctx, cur, next);
    }
    let g = if which == 0 {
        let i = next.e.monitors.tau_min.1;
        on_plane(ctx, cur, next, 5 + i, 0.0)?
    } else {
        let f = move |n: &Node| ctx_free_violation(n, which);
        let mut g = locate(ctx, cur, next, ds, PointType::Grazing, &f, Search::Secant)?;
        // `f` reads scaled violations computed with the node's model; nothing else to do.
        g.point.point_type = PointType::Grazing;
        g
    };
    let m = g.e.monitors;
    let (_, taus, p) = ctx.unpack(&g.e.xi);
    let k = seq.k();
    let eps = 1e-6 * ctx.t_ref;
    let phase = |i: usize, t: f64| {
        (i == 0 && t < eps && seq.modes[0] != ContactMode::Free)
            || (i == k - 1 && taus[i] - t < eps && seq.modes[k - 1] != ContactMode::Free)
    };
    let change = match which {
        0 => Change::Remove(m.tau_min.1),
        1 | 2 => {
            let (_, i, t) = if which == 1 { m.contact_gap } else { m.contact_law };
            let event = if which == 1 { event::GAP } else { event::NORMAL };
            let (i, t) = if phase(i, t) { (0, 0.0) } else { (i, t) };
            Change::Insert { i, t, mode: ContactMode::Free, event }
        }
        _ => {
            let (_, i, t) = m.free_margin;
            Change::Insert { i, t, mode: ContactMode::Contact, event: m.free_margin_event }
        }
    };
    if let Change::Insert { i, t, .. } = change {
        if !(t == 0.0 && i == 0) && (t <= 0.0 || t >= taus[i]) {
            let why = format!("a mode change at the end of segment {i} near {name} = {p:.10e} is not supported");
            return Err(fail(Status::NotConverged, why));
        }
    }
    let (y0, _, _) = ctx.unpack(&g.e.xi);
    let (new, taus) = rebuild(seq, &taus, &change);

    let xi = ctx.pack(&y0, &taus, p);
    let first = leave(ctx, &g, &xi, &new, &change).map_err(|f| {
        let why =
            format!("the branch grazes at {name} = {p:.10e}, but no physical orbit follows in the new mode sequence");
        fail(f.status, format!("{why}: {}", f.reason))
    })?;
    // The grazing point as an orbit of the sequence with fewer switches (its multipliers are
    // that side's: on the other, a segment of zero length has an unbounded saltation matrix).
    let mut g = if let Change::Remove(_) = change {
        let (e, _) = ctx.evaluate(&xi, &new, ctx.opts.rtol)?;
        node(ctx, e, first.tangent.clone(), g.point.arclength)
    } else {
        g
    };
    g.point.point_type = PointType::Grazing;
    if g.tangent[g.tangent.len() - 1] * first.tangent[first.tangent.len() - 1] < 0.0 {
        g.point.flags |= flags::PARAMETER_TURNS;
    }
    Ok((g, first))
}

/// An inner segment's duration reaches zero between `cur` and `next`. In `cur`'s sequence that
/// point is where two switching conditions coincide (singular); in the merged sequence it is a
/// regular orbit whose merged segment just touches its mode's limit. So: merge at the
/// interpolated crossing, then locate the touch in the merged sequence by a secant in the
/// parameter (corrections at fixed parameter) on the merged segment's condition.
fn remove_inner(ctx: &mut Ctx<'_>, cur: &Node, next: &Node) -> Result<(Node, Node), Failure> {
    let name = ctx.name.to_string();
    let seq = &cur.e.seq;
    let i = next.e.monitors.tau_min.1;
    let (a, b) = (cur.e.xi[5 + i], next.e.xi[5 + i]);
    let th = (a / (a - b)).clamp(0.0, 1.0);
    let xi = &cur.e.xi + (&next.e.xi - &cur.e.xi) * th;
    let (y0, taus, p) = ctx.unpack(&xi);
    let change = Change::Remove(i);
    let (new, taus) = rebuild(seq, &taus, &change);
    // The merged segment's condition: a free segment left by `ev` merges into a contact one
    // (watch the gap or the law force there); a contact segment into a free one (its margin).
    let which = match (seq.modes[i], seq.events[i - 1]) {
        (ContactMode::Free, event::GAP) => 1,
        (ContactMode::Free, _) => 2,
        _ => 3,
    };
    let ip = new.ip();
    let ep = unit(new.n(), ip);
    let at = |ctx: &mut Ctx<'_>, xi: &Xi| -> Result<(super::solve::Eval, f64), Failure> {
        let e = ctx.correct(xi, &new, &ep, xi)?;
        let v = ctx.violations(&e)[which];
        Ok((e, v))
    };
    let x0 = ctx.pack(&y0, &taus, p);
    let (mut ea, mut fa) = at(ctx, &x0)?;
    // A second point a little further along the old branch's parameter direction.
    let dp = (next.point.parameter - cur.point.parameter) * 0.25;
    let mut x1 = ea.xi.clone();
    x1[ip] += dp / ctx.p_ref;
    let (mut eb, mut fb) = at(ctx, &x1)?;
    for _ in 0..40 {
        if !(fa.is_finite() && fb.is_finite()) || fb == fa || fb.abs() <= 1e-3 * ctx.opts.tol {
            break;
        }
        let pa = ea.xi[ip];
        let pb = eb.xi[ip];
        let pn = pb - fb * (pb - pa) / (fb - fa);
        if !pn.is_finite() || (pn - pb).abs() <= ctx.opts.locate_tol {
            break;
        }
        let mut xn = eb.xi.clone();
        xn[ip] = pn;
        let (en, fnew) = at(ctx, &xn)?;
        (ea, fa) = (eb, fb);
        (eb, fb) = (en, fnew);
    }
    let xg = eb.xi.clone();
    let t = ctx.tangent(&eb.jac, &unit(new.n(), ip)).unwrap_or_else(|| unit(new.n(), ip));
    let mut g = node(ctx, eb, t, cur.point.arclength + th * (next.point.arclength - cur.point.arclength));
    g.point.point_type = PointType::Grazing;
    let first = leave(ctx, &g, &xg, &new, &change).map_err(|f| {
        let p = g.point.parameter;
        let why = format!("a segment vanishes at {name} = {p:.10e}, but no physical orbit follows without it");
        fail(f.status, format!("{why}: {}", f.reason))
    })?;
    if cur.tangent[cur.tangent.len() - 1] * first.tangent[first.tangent.len() - 1] < 0.0 {
        g.point.flags |= flags::PARAMETER_TURNS;
    }
    g.tangent = first.tangent.clone();
    g.point.dp_ds = first.point.dp_ds;
    Ok((g, first))
}

/// A landing's other condition fails between `cur` and `next`: where both conditions hold at
/// once (located on it), the landing switches to the other event. The unknowns keep their
/// meaning, so the branch goes on with the same tangent orientation.
fn swap_landing(ctx: &mut Ctx<'_>, cur: &Node, next: &Node) -> Result<(Node, Node), Failure> {
    let f = |n: &Node| n.e.monitors.landing.0;
    let ds = next.point.arclength - cur.point.arclength;
    let mut g = locate(ctx, cur, next, ds, PointType::Grazing, &f, Search::Secant)?;
    let k = g.e.monitors.landing.1;
    let mut seq = g.e.seq.clone();
    seq.events[k] = if seq.events[k] == event::GAP { event::NORMAL } else { event::GAP };
    let xi = g.e.xi.clone();
    let (e, _) = ctx.evaluate(&xi, &seq, ctx.opts.rtol)?;
    let t = ctx.tangent(&e.jac, &cur.tangent).ok_or_else(|| fail(Status::NotConverged, "no tangent".into()))?;
    let pred = &xi + &t * ctx.opts.ds;
    let e1 = ctx.correct(&pred, &seq, &t, &pred)?;
    let t1 = ctx.tangent(&e1.jac, &t).unwrap_or_else(|| t.clone());
    let first = node(ctx, e1, t1, g.point.arclength + ctx.opts.ds);
    g.point.point_type = PointType::Grazing;
    Ok((g, first))
}

/// Violation `which` (> 0 violated) of a node, scaled as in [`Ctx::violations`].
fn ctx_free_violation(n: &Node, which: usize) -> f64 {
    let m = &n.e.monitors;
    let ks = n.e.model.s.k_s;
    match which {
        1 => m.contact_gap.0,
        2 => -m.contact_law.0 / ks,
        _ => m.free_margin.0 / ks,
    }
}

/// The new sequence and durations after `change`.
fn rebuild(seq: &Seq, taus: &[f64], change: &Change) -> (Seq, Vec<f64>) {
    let (mut modes, mut events, mut taus) = (seq.modes.clone(), seq.events.clone(), taus.to_vec());
    match *change {
        Change::Remove(i) => {
            let k = modes.len();
            if seq.phase_in_flight() && (i == 0 || i == k - 1) {
                // The flight around the phase point vanishes: both halves go.
                modes = modes[1..k - 1].to_vec();
                events = events[1..k - 2].to_vec();
                taus = taus[1..k - 1].to_vec();
            } else if i > 0 && i + 1 < k {
                // An inner segment vanishes: its neighbours (same mode) merge.
                let merged = taus[i - 1] + taus[i] + taus[i + 1];
                modes.drain(i..i + 2);
                events.drain(i - 1..i + 1);
                taus.splice(i - 1..i + 2, [merged]);
            } else {
                taus[i] = 0.0;
            }
        }
        Change::Insert { i, t, mode, event } => {
            let old = modes[i];
            if t == 0.0 && i == 0 {
                // Around the phase point: a half of the new segment at each end.
                modes.insert(0, mode);
                modes.push(mode);
                events.insert(0, event);
                events.push(event);
                taus.insert(0, 0.0);
                taus.push(0.0);
            } else {
                let rest = taus[i] - t;
                modes.splice(i..i + 1, [old, mode, old]);
                events.splice(i..i, [event, event]);
                taus.splice(i..i + 1, [t, 0.0, rest]);
            }
        }
    }
    (Seq { modes, events }, taus)
}

/// The first physical point after a change of sequence at `g`.
///
/// A new segment: the orbit whose new segment lasts `eps` (scaled by the period; at the phase
/// point the two halves together), corrected with that duration fixed from `g` with the segment
/// inserted, centred on the touch. Near `g` the physical piece is parametrised by that duration,
/// while the virtual piece through `g` keeps it at zero: the condition picks the physical one
/// whichever way the parameter goes (if that fails, as for a removed segment:
/// [`leave_along_null`]).
fn leave(ctx: &mut Ctx<'_>, g: &Node, xi: &Xi, seq: &Seq, change: &Change) -> Result<Node, Failure> {
    if let Change::Insert { i, t, .. } = *change {
        let k = seq.k();
        // (new segments, their neighbours that give up the time)
        let (new, give): (Vec<usize>, Vec<usize>) = if t == 0.0 && i == 0 {
            (vec![5, 5 + k - 1], vec![5 + 1, 5 + k - 2])
        } else {
            (vec![5 + i + 1], vec![5 + i, 5 + i + 2])
        };
        let mut c = Xi::zeros(xi.len());
        for &n in &new {
            c[n] = 1.0;
        }
        let cn = c.normalize();
        let mut last = fail(Status::NotConverged, "no step".into());
        let ip = seq.ip();
        // Smallest first, from a thousandth of `ds`: a fold can follow a grazing within 4e-4 N
        // (at 6.66 cm on the issue-10 switch-law box), and a first step past it hides both the
        // turn and the fold. A first orbit whose tangent points back against the step it took in
        // the parameter has passed a fold: smaller steps, down to ds / 1024.
        let mut tries = vec![0.001 * ctx.opts.ds, 0.0625 * ctx.opts.ds, 0.25 * ctx.opts.ds, ctx.opts.ds];
        let mut k = 0;
        while k < tries.len() {
            let eps = tries[k];
            k += 1;
            let mut guess = xi.clone();
            for &n in &new {
                guess[n] += eps / new.len() as f64;
            }
            for &n in &give {
                guess[n] -= eps / give.len() as f64;
            }
            let anchor = xi + &c * (eps / c.norm_squared());
            match ctx.correct(&guess, seq, &cn, &anchor) {
                Ok(e) if valid(ctx, &e) && e.monitors.tau_min.0 > 0.0 => {
                    let tan = ctx.tangent(&e.jac, &cn).unwrap_or_else(|| cn.clone());
                    if (e.xi[ip] - xi[ip]) * tan[ip] < 0.0 && eps > ctx.opts.ds / 1024.0 {
                        tries.insert(k, 0.25 * eps);
                        continue;
                    }
                    let s = g.point.arclength + (&e.xi - xi).norm();
                    return Ok(node(ctx, e, tan, s));
                }
                Ok(_) => last = fail(Status::NotConverged, "the orbit with the new segment is not physical".into()),
                Err(f) => last = f,
            }
        }
        if let Ok(n) = leave_along_null(ctx, g, xi, seq) {
            return Ok(n);
        }
        return Err(last);
    }
    leave_along_null(ctx, g, xi, seq)
}

/// One step from `g` along each null direction of the new system, both ways; the first that lands
/// on a physical orbit with every duration positive wins.
fn leave_along_null(ctx: &mut Ctx<'_>, g: &Node, xi: &Xi, seq: &Seq) -> Result<Node, Failure> {
    let (e, _) = ctx.evaluate(xi, seq, ctx.opts.rtol)?;
    let j = &e.jac;
    let jtj: DMatrix<f64> = j.transpose() * j;
    let eig = jtj.symmetric_eigen();
    let top = eig.eigenvalues.amax();
    let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let null: Vec<Xi> = order
        .iter()
        .take(2)
        .filter(|&&k| eig.eigenvalues[k] <= 1e-6 * top || k == order[0])
        .map(|&k| eig.eigenvectors.column(k).into_owned())
        .collect();
    let mut tries: Vec<Xi> = Vec::new();
    for v in &null {
        tries.push(v.clone());
        tries.push(-v.clone());
    }
    let mut last = fail(Status::NotConverged, "no null direction".into());
    for ds in [ctx.opts.ds, 0.25 * ctx.opts.ds, 0.0625 * ctx.opts.ds] {
        for d in &tries {
            let pred = xi + d * ds;
            match ctx.correct(&pred, seq, d, &pred) {
                Ok(e) if valid(ctx, &e) && e.monitors.tau_min.0 > 0.0 => {
                    let t = ctx.tangent(&e.jac, &(&e.xi - xi)).unwrap_or_else(|| d.clone());
                    return Ok(node(ctx, e, t, g.point.arclength + ds));
                }
                Ok(_) => last = fail(Status::NotConverged, "the step lands on a non-physical orbit".into()),
                Err(f) => last = f,
            }
        }
    }
    Err(last)
}
