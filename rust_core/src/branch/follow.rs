//! The walk along a branch: starts, steps, special points, changes of the mode sequence
//! (grazing), the end.

use super::flow::switches;
use super::locate::{locate, on_plane, unit, Search};
use super::solve::{fail, node, valid, Ctx, Failure, Node, Seq};
use super::{flags, BranchPoint, PointType, C64, POINT_TYPE_NAMES};
use crate::linear::eigenvalues;
use crate::model::{idx, ContactMode, ContactModel, FrictionLaw, Slider, State};
use crate::status::Status;
use nalgebra::{SMatrix, SVector};
use std::f64::consts::PI;

/// The first point from an orbit: shoot at fixed parameter, read its mode sequence off one run
/// that locates its switches, correct as segments, then the tangent towards `direction`.
pub(super) fn first_from_orbit(ctx: &mut Ctx<'_>, y: &State, t: f64, direction: f64) -> Result<Node, Failure> {
    let p = ctx.base.get(ctx.name).unwrap_or(f64::NAN);
    let s = Slider::new(ctx.base).map_err(|e| fail(Status::InvalidInput, e.to_string()))?;
    let so = crate::shooting::ShootingOptions { rtol: ctx.opts.rtol, tol: ctx.opts.tol, ..Default::default() };
    let o = crate::shooting::shoot(&s, y, t, &so);
    if o.status != Status::Success {
        return Err(fail(o.status, format!("shooting from the given orbit ended with {}", o.status.name())));
    }
    let model = ctx.model(p)?;
    let fs = super::flow::FlowSettings {
        method: ctx.opts.method,
        rtol: ctx.opts.rtol,
        sizes: ctx.sizes,
        p_ref: ctx.p_ref,
        max_switches: ctx.opts.max_switches,
    };
    let list = switches(&model, &o.state0, o.period, &fs, &mut ctx.stats)
        .map_err(|st| fail(st, format!("the orbit's run failed ({})", st.name())))?;
    let mut modes = vec![s.mode_at(&o.state0)];
    let mut events = Vec::new();
    let mut taus = Vec::new();
    let mut t0 = 0.0;
    for sw in &list {
        modes.push(sw.after);
        events.push(sw.index);
        taus.push(sw.t - t0);
        t0 = sw.t;
    }
    taus.push(o.period - t0);
    let seq = Seq { modes, events };
    let xi = ctx.pack(&o.state0, &taus, p);
    let ip = seq.ip();
    let ep = unit(seq.n(), ip);
    let e = ctx.correct(&xi, &seq, &ep, &xi)?;
    let guess = ep * direction.signum();
    let tangent =
        ctx.tangent(&e.jac, &guess).ok_or_else(|| fail(Status::NotConverged, "no tangent at the start".into()))?;
    Ok(node(ctx, e, tangent, 0.0))
}

/// Tries of the first orbit from a Hopf point, each at a tenth of the amplitude before.
///
/// Where the branch bends hard away from the Hopf point (with Stribeck friction at low speed, at
/// 5 cm arm, 0.2 m/s: the load moves 0.025 N by A1 = 2.3e-8 m, and a Newton step from the first
/// guess at `hopf_amplitude = 0.02` was 1.2 scaled units), the guess on the critical eigenvector
/// at the Hopf parameter is too far from the orbit for Newton. A smaller amplitude moves the
/// parameter quadratically less (the Hopf normal form), so the guess comes within Newton's reach.
pub(super) const HOPF_TRIES: usize = 3;

/// The Hopf point as a branch point, and the first orbit: amplitude `hopf_amplitude |z_st|`
/// along the critical eigenvector, corrected with its projection on that direction fixed; where
/// that does not converge, a tenth of it, up to [`HOPF_TRIES`] tries (`ctx.opts.hopf_amplitude`
/// is left at the amplitude that converged, which is also the branch's "back at steady
/// sliding" threshold).
pub(super) fn first_from_hopf(
    ctx: &mut Ctx<'_>,
    s: &Slider,
    omega: f64,
    mode_scales: bool,
    points: &mut Vec<BranchPoint>,
) -> Result<Node, Failure> {
    let j = s.jacobian(&State::zeros(), ContactMode::Contact);
    let v = critical_vector(&j, omega).ok_or_else(|| fail(Status::NotConverged, "no critical eigenvector".into()))?;
    if mode_scales {
        ctx.sizes = hopf_sizes(&ctx.sizes, &v, s.z_st.abs());
    }
    let seq = Seq::contact();
    let t = 2.0 * PI / omega;
    let p = ctx.base.get(ctx.name).unwrap_or(f64::NAN);
    let xi_h = ctx.pack(&State::zeros(), &[t], p);
    let mut tried = Vec::new();
    let e = loop {
        let amp = ctx.opts.hopf_amplitude * s.z_st.abs();
        let mut y = State::from_fn(|i, _| amp * v[i].re);
        y[idx::ZD] = 0.0;
        let xi = ctx.pack(&y, &[t], p);
        let c = (&xi - &xi_h).normalize();
        match ctx.correct(&xi, &seq, &c, &xi) {
            Ok(e) => break e,
            Err(f) => {
                tried.push(format!("at hopf_amplitude = {:.0e}: {}", ctx.opts.hopf_amplitude, f.reason));
                if tried.len() == HOPF_TRIES {
                    return Err(fail(f.status, tried.join("; ")));
                }
                ctx.opts.hopf_amplitude *= 0.1;
            }
        }
    };
    // The Hopf point: the equilibrium as a zero-amplitude orbit, multipliers exp(lambda T).
    let lam = eigenvalues(&j).unwrap_or([C64::new(f64::NAN, f64::NAN); 6]);
    let mut rho = lam.map(|l| (l * t).exp());
    rho.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    let trivial = (0..6).min_by(|&a, &b| (rho[a] - 1.0).norm().total_cmp(&(rho[b] - 1.0).norm())).unwrap_or(0);
    let dxi = &e.xi - &xi_h;
    let tangent =
        ctx.tangent(&e.jac, &dxi).ok_or_else(|| fail(Status::NotConverged, "no tangent at the start".into()))?;
    let first = node(ctx, e, tangent, dxi.norm());
    points.push(BranchPoint {
        parameter: p,
        period: t,
        state0: State::zeros(),
        multipliers: rho,
        trivial,
        trivial_error: (rho[trivial] - 1.0).norm(),
        stable: false,
        n_unstable: (0..6).filter(|&k| k != trivial && rho[k].norm() > 1.0).count() as u8,
        a0: 0.0,
        a1: 0.0,
        z_max: 0.0,
        z_min: 0.0,
        min_gap: -s.z_st,
        min_law_force: s.p.normal_load,
        open_fraction: 0.0,
        min_slip_velocity: s.p.sliding_speed.abs(),
        n_switches: 0,
        dp_ds: 0.0,
        arclength: 0.0,
        point_type: PointType::Hopf,
        contact: ctx.base.contact,
        newton_iterations: 0,
        residual: 0.0,
        flags: 0,
    });
    Ok(first)
}

/// The scales of a branch from a Hopf point: the friction-direction components (`x`, `phi` and
/// their rates) at least as large as the critical mode's own when `z` moves by `|z_st|` (`v`
/// scaled to `v_z = 1`); `z` and `zd` keep theirs.
///
/// The characteristic sizes scale `x` by `|z_st|`, as `z`. On a mode whose friction-direction
/// motion is larger than its normal motion the scaled orbit, and with it the arclength, was then
/// that many times longer, and the steps sat at `ds_max`: a Stribeck branch of the friction mode
/// took 400-1000 orbits to its stick point. The absolute tolerances of the flows and the Newton
/// tolerance follow the same scales: each component is held to the same accuracy relative to its
/// motion on the mode. Longer steps alone stepped over close special points; the steps are held
/// back by the test functions they move ([`step_cap`], [`too_far`]).
fn hopf_sizes(sizes: &State, v: &SVector<C64, 6>, z_st: f64) -> State {
    let mut out = *sizes;
    for i in [idx::X, idx::XD, idx::PHI, idx::PHID] {
        out[i] = out[i].max(v[i].norm() * z_st);
    }
    out
}

/// Eigenvector of `j` for the eigenvalue nearest `i omega`, scaled so that `v_z = 1` (inverse
/// iteration on the complex 6x6 system, shifted by a relative 1e-9 off the eigenvalue).
fn critical_vector(j: &crate::model::Jacobian, omega: f64) -> Option<SVector<C64, 6>> {
    let target = C64::new(0.0, omega);
    let lam = eigenvalues(j)?;
    let l = *lam.iter().min_by(|a, b| (*a - target).norm().total_cmp(&(*b - target).norm()))?;
    let shift = l * (1.0 + 1e-9);
    let zero = C64::new(0.0, 0.0);
    let a = SMatrix::<C64, 6, 6>::from_fn(|r, c| C64::new(j[(r, c)], 0.0) - if r == c { shift } else { zero });
    let lu = a.lu();
    let mut v = SVector::<C64, 6>::repeat(C64::new(1.0, 0.0));
    for _ in 0..3 {
        v = lu.solve(&v)?;
        let n = v.norm();
        v /= C64::new(n, 0.0);
    }
    let vz = v[idx::Z];
    (vz.norm() > 1e-12).then(|| v / vz)
}

/// Follow the branch from `cur` (see [`super::branch`]); pushes the points, returns how it ended.
pub(super) fn follow(
    ctx: &mut Ctx<'_>,
    mut cur: Node,
    (lo, hi): (f64, f64),
    points: &mut Vec<BranchPoint>,
) -> (Status, String) {
    let o = ctx.opts;
    let name = ctx.name.to_string();
    let inside = |p: f64| p >= lo && p <= hi;
    let p0 = cur.point.parameter;
    points.push(cur.point);
    if !inside(p0) {
        return (Status::Success, format!("the first orbit is at {name} = {p0:.10e}, outside [{lo}, {hi}]"));
    }
    let small = o.hopf_amplitude * ctx.sizes[idx::Z];
    let mut ds = o.ds;
    loop {
        if crate::cancel::requested() {
            let p = cur.point.parameter;
            return (Status::NotComputed, format!("cancelled by the caller at {name} = {p:.10e}"));
        }
        if points.len() >= o.max_points {
            let p = cur.point.parameter;
            return (Status::Success, format!("max_points = {} reached at {name} = {p:.10e}", o.max_points));
        }
        let seq = cur.e.seq.clone();
        let pred = &cur.e.xi + &cur.tangent * ds;
        let attempt = ctx.correct(&pred, &seq, &cur.tangent, &pred).and_then(|e| {
            let t = ctx.tangent(&e.jac, &cur.tangent);
            t.map(|t| (e, t)).ok_or_else(|| fail(Status::NotConverged, "singular Jacobian: no tangent".into()))
        });
        let (e, tangent) = match attempt {
            Ok(v) => v,
            Err(f) => {
                ds *= 0.5;
                if ds < o.ds_min {
                    let p = cur.point.parameter;
                    let why = format!("the step was halved below ds_min = {:e} after {name} = {p:.10e}", o.ds_min);
                    return (f.status, format!("{why}: {}", f.reason));
                }
                continue;
            }
        };
        let mut next = node(ctx, e, tangent, cur.point.arclength + ds);
        let turn = cur.tangent.dot(&next.tangent).clamp(-1.0, 1.0).acos();
        let jump = (&next.e.xi - &pred).norm();
        let rough = turn > o.max_turn || jump > 0.5 * ds;
        let steep = !rough && ds * 0.5 >= o.ds_min && valid(ctx, &next.e) && too_far(ctx, &cur, &next);
        if rough || steep {
            if ds * 0.5 >= o.ds_min {
                ds *= 0.5;
                continue;
            }
            next.point.flags |= flags::SWITCH_SUSPECTED;
        }
        if !valid(ctx, &next.e) {
            // The mode sequence changes between `cur` and `next` (a grazing): locate it, change
            // the sequence, and go on along the physical piece.
            match super::sequence::change_sequence(ctx, &cur, &next).map_err(|f| {
                let p = cur.point.parameter;
                let why = format!("the mode sequence changes after {name} = {p:.10e}, and the change failed");
                fail(f.status, format!("{why}: {}", f.reason))
            }) {
                Ok((g, n)) => {
                    if !inside(g.point.parameter) {
                        let p = g.point.parameter;
                        return (
                            Status::Success,
                            format!("the branch grazes at {name} = {p:.10e}, outside [{lo}, {hi}]"),
                        );
                    }
                    points.push(g.point);
                    let turns = g.point.flags & flags::PARAMETER_TURNS != 0;
                    let stop = match o.stop_at {
                        Some(PointType::Grazing) => true,
                        Some(PointType::Fold) => turns,
                        _ => false,
                    };
                    if stop {
                        let p = g.point.parameter;
                        let kind = if turns { "non-smooth fold (grazing)" } else { "grazing" };
                        return (Status::Success, format!("stopped at the first {kind} point, {name} = {p:.10e}"));
                    }
                    points.push(n.point);
                    let arc = n.point.arclength - g.point.arclength;
                    ds = o.ds.min(step_cap(ctx, &g, &n, arc)).max(o.ds_min);
                    cur = n;
                    continue;
                }
                Err(f) => {
                    // A smaller step reaches the grazing closer, where the change may succeed.
                    if ds * 0.5 >= o.ds_min {
                        ds *= 0.5;
                        continue;
                    }
                    return (f.status, f.reason);
                }
            }
        }
        let amp = next.point.z_max - next.point.z_min;
        if amp < small && inside(next.point.parameter) {
            let p = next.point.parameter;
            next.point.point_type = PointType::End;
            points.push(next.point);
            let why = "the branch is back at steady sliding (a Hopf point nearby)";
            return (Status::Success, format!("the amplitude fell to {amp:.3e} m at {name} = {p:.10e}: {why}"));
        }
        let mut specials = locate_all(ctx, &cur, &next, ds);
        specials.retain(|n| inside(n.point.parameter));
        specials.sort_by(|a, b| a.point.arclength.total_cmp(&b.point.arclength));
        // (Stopping at a stick point is the branch's own end below, with its reason: the same
        // branch and words whatever `stop_at`, so a fold's branch can be read off a stick's.)
        let stop_at = o.stop_at.filter(|&k| k != PointType::Stick);
        if let Some(i) = stop_at.and_then(|k| specials.iter().position(|n| n.point.point_type == k)) {
            points.extend(specials.iter().take(i + 1).map(|n| n.point));
            let k = POINT_TYPE_NAMES[specials[i].point.point_type as usize];
            let p = specials[i].point.parameter;
            return (Status::Success, format!("stopped at the first {k} point, {name} = {p:.10e}"));
        }
        // The cycle reaches the stick band: past it the orbit of this mode sequence is not the
        // switch law's (it would stick), and stick phases are not followed.
        if let Some(i) = specials.iter().position(|n| n.point.point_type == PointType::Stick) {
            points.extend(specials.iter().take(i + 1).map(|n| n.point));
            let p = specials[i].point.parameter;
            return (
                Status::Success,
                format!(
                    "the cycle reaches the stick band at {name} = {p:.10e}: it gains a stick phase there (a sliding \
                     bifurcation, which continuation does not follow)"
                ),
            );
        }
        points.extend(specials.iter().map(|n| n.point));
        if !inside(next.point.parameter) {
            let bound = if next.point.parameter > hi { hi } else { lo };
            return land(ctx, &cur, &next, bound, points);
        }
        let (p, period) = (next.point.parameter, next.point.period);
        points.push(next.point);
        if period > o.max_period_ratio * ctx.t_ref {
            let why = "a homoclinic orbit or a switch to another branch nearby";
            return (Status::Success, format!("the period grew to {period:.6e} s at {name} = {p:.10e}: {why}"));
        }
        let it = next.e.iterations;
        let factor = if it <= 2 {
            1.5
        } else if it >= 5 {
            0.5
        } else {
            1.0
        };
        let cap = step_cap(ctx, &cur, &next, ds);
        ds = (ds * factor).min(cap).clamp(o.ds_min, o.ds_max);
        cur = next;
    }
}

/// The test functions a step may move only by [`STEP_THETA`] times their distance from zero, plus
/// a floor: `dp/ds` (folds), `ln |rho|` of the non-trivial multipliers by modulus, descending
/// (period doublings, Neimark-Sacker and branch points), the stick margin `(min |v_r| - eta) /
/// eta`, the bilateral gap and the unilateral validity margin in their scales (grazing), and the
/// amplitude in `|z_st|` (the end at steady sliding). Special points are detected between
/// consecutive orbits, so two of them inside one step (a test function out and back across zero)
/// are not seen: a test function that must cross zero and come back within a step must change
/// there by more than its distance from zero, and these bounds keep each step's change below
/// that, at the rate the last step saw ([`step_cap`]) and, where a step proves steeper, by
/// halving it ([`too_far`]). Against the static scales' short steps on 33 branches (the issue-10
/// switch law at 0.2 and 0.5 m/s, the constant and tanh laws): the same special points on 30,
/// further on two that those steps ended at `max_points`, and in one cascade of some 40 special
/// points (6.25 cm) a period doubling 1e-4 N from a fold that they missed and another way
/// through its grazings to the same stick point.
const NW: usize = 10;
/// See [`NW`].
const STEP_THETA: f64 = 0.5;

/// The watched test functions of a node (see [`NW`]); NaN where one does not apply.
fn watched(ctx: &Ctx<'_>, n: &Node) -> [f64; NW] {
    let ip = n.e.seq.ip();
    let mut out = [f64::NAN; NW];
    out[0] = n.tangent[ip];
    if let Some(sp) = n.spec {
        let mut l: Vec<f64> = (0..6).filter(|&k| k != sp.trivial).map(|k| sp.rho[k].norm().ln()).collect();
        l.sort_by(|a, b| b.total_cmp(a));
        out[1..6].copy_from_slice(&l);
    }
    let band = n.e.model.s.p.stick_band;
    if ctx.base.friction_law == FrictionLaw::Switch {
        out[6] = (n.point.min_slip_velocity - band) / band;
    }
    if ctx.base.contact == ContactModel::Bilateral {
        out[7] = n.point.min_gap / ctx.sizes[idx::Z];
    } else {
        out[8] = -ctx.violations(&n.e).iter().filter(|v| v.is_finite()).fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    }
    out[9] = (n.point.z_max - n.point.z_min) / ctx.sizes[idx::Z];
    out
}

/// The floors of the watched functions' allowed change (the amplitude's: half the first orbit's).
fn floors(ctx: &Ctx<'_>) -> [f64; NW] {
    let m = 0.005;
    [0.02, m, m, m, m, m, 0.05, 0.01, 0.01, 0.5 * ctx.opts.hopf_amplitude]
}

/// Each watched test function's change over the step from `cur` to `next`, its distances from
/// zero at both ends, and its floor (NaN changes where one does not apply).
fn changes(ctx: &Ctx<'_>, cur: &Node, next: &Node) -> [(f64, f64, f64, f64); NW] {
    let (a, b, f) = (watched(ctx, cur), watched(ctx, next), floors(ctx));
    std::array::from_fn(|i| ((b[i] - a[i]).abs(), a[i].abs(), b[i].abs(), f[i]))
}

/// Whether the step from `cur` to `next` moved a watched test function by more than
/// [`STEP_THETA`] times its smaller distance from zero at the two ends, plus its floor.
fn too_far(ctx: &Ctx<'_>, cur: &Node, next: &Node) -> bool {
    changes(ctx, cur, next).iter().any(|&(d, a, b, f)| d.is_finite() && d > STEP_THETA * a.min(b) + f)
}

/// The largest next step that moves no watched test function by more than [`STEP_THETA`] times
/// its distance from zero (plus its floor), at its rate over the last step (`ds` long).
fn step_cap(ctx: &Ctx<'_>, cur: &Node, next: &Node, ds: f64) -> f64 {
    changes(ctx, cur, next)
        .iter()
        .filter(|&&(d, ..)| d.is_finite() && d > 0.0)
        .fold(f64::INFINITY, |cap, &(d, _, b, f)| cap.min(ds * (STEP_THETA * b + f) / d))
}

/// The last point, exactly on `bound`.
fn land(ctx: &mut Ctx<'_>, cur: &Node, next: &Node, bound: f64, points: &mut Vec<BranchPoint>) -> (Status, String) {
    let name = ctx.name.to_string();
    match on_plane(ctx, cur, next, cur.e.seq.ip(), bound / ctx.p_ref) {
        Ok(mut n) => {
            n.point.point_type = PointType::End;
            n.point.parameter = bound;
            points.push(n.point);
            (Status::Success, format!("reached the bound {name} = {bound}"))
        }
        Err(f) => {
            let why = format!("the branch crosses the bound {name} = {bound}, but the orbit there did not converge");
            (f.status, format!("{why}: {}", f.reason))
        }
    }
}

/// A test function and how it is searched.
type Test<'a> = (PointType, Box<dyn Fn(&Node) -> f64 + 'a>, Search);

/// Every special point between `cur` and `next` (`ds` apart), located.
fn locate_all(ctx: &mut Ctx<'_>, cur: &Node, next: &Node, ds: f64) -> Vec<Node> {
    let mut tests: Vec<Test<'_>> = Vec::new();
    let ip = cur.e.seq.ip();
    let fold = cur.tangent[ip] * next.tangent[ip] < 0.0;
    if fold {
        tests.push((PointType::Fold, Box::new(move |n: &Node| n.tangent[ip]), Search::Secant));
    }
    if let (Some(a), Some(b)) = (cur.spec, next.spec) {
        // A count change, located on the smooth test function when that changes sign too.
        type Pick = fn(&super::solve::Spectrum) -> (u8, f64);
        let count = |kind, ca: u8, cb: u8, fa: f64, fb: f64, f: Pick| -> Test<'_> {
            if fa * fb < 0.0 {
                (kind, Box::new(move |n: &Node| n.spec.map_or(f64::NAN, |s| f(&s).1)), Search::Secant)
            } else {
                let mid = 0.5 * (ca as f64 + cb as f64);
                (kind, Box::new(move |n: &Node| n.spec.map_or(f64::NAN, |s| f(&s).0 as f64 - mid)), Search::Bisect)
            }
        };
        // Only crossings of the unit circle count: a collision of two real multipliers into a
        // complex pair (or back) off the circle changes the kinds, not the number outside.
        let crosses = a.n_out != b.n_out;
        if crosses && a.n_real_neg != b.n_real_neg {
            tests.push(count(PointType::PeriodDoubling, a.n_real_neg, b.n_real_neg, a.pd, b.pd, |s| {
                (s.n_real_neg, s.pd)
            }));
        }
        if crosses && a.n_complex != b.n_complex {
            tests.push(count(PointType::NeimarkSacker, a.n_complex, b.n_complex, a.ns, b.ns, |s| (s.n_complex, s.ns)));
        }
        if crosses && a.n_real_pos != b.n_real_pos && !fold {
            tests.push(count(PointType::BranchPoint, a.n_real_pos, b.n_real_pos, 0.0, 0.0, |s| (s.n_real_pos, 0.0)));
        }
    }
    // The switch law's slip reaching the stick band (`min_slip_velocity` down to its half-width).
    // Each node's own band (the continued parameter may be the band itself).
    if ctx.base.friction_law == FrictionLaw::Switch {
        let margin = |n: &Node| n.point.min_slip_velocity - n.e.model.s.p.stick_band;
        if margin(cur) >= 0.0 && margin(next) < 0.0 {
            tests.push((PointType::Stick, Box::new(margin), Search::Secant));
        }
    }
    // Grazing of the bilateral law (the unilateral law changes its mode sequence there instead).
    if ctx.base.contact == ContactModel::Bilateral && (cur.point.min_gap > 0.0) != (next.point.min_gap > 0.0) {
        tests.push((PointType::Grazing, Box::new(|n: &Node| n.point.min_gap), Search::Secant));
    }
    let mut out = Vec::new();
    for (kind, f, search) in tests {
        match locate(ctx, cur, next, ds, kind, &*f, search) {
            Ok(n) => out.push(n),
            Err(_) => {
                // Not located: reported at the bracket's far end, flagged.
                let mut n = node(ctx, next.e.clone(), next.tangent.clone(), next.point.arclength);
                n.point.point_type = kind;
                n.point.flags |= flags::NOT_LOCATED;
                out.push(n);
            }
        }
    }
    out
}
