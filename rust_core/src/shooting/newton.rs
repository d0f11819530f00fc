//! Newton's iteration on the periodic orbit's shooting equations (MODEL.md §6): the full method,
//! with every iterate's monodromy matrix, and the chord method of the slow-approach checks.

use super::*;

/// How [`shoot_impl`]'s Newton iteration gets its matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Newton {
    /// Every iterate's flow with its variational equations: the monodromy matrix of the iterate.
    Full,
    /// The chord method: a monodromy matrix kept for later steps, whose flows integrate the state
    /// alone (six equations instead of 42). From a start within `APPROACH_TOL` = 1e-3 of the orbit
    /// the kept matrix is near the orbit's and most steps shrink the residual many times over; a
    /// step that shrinks it less than [`CHORD_CONTRACTION`] computes the iterate's own matrix and
    /// keeps that (near a multiplier of 1 the Newton matrix has a small singular value, and a
    /// matrix 1e-3 off may not contract). The iteration stops on its step as well as its residual
    /// (its convergence is linear: the residual alone can be small while the iterate is still off
    /// along that singular direction). A stable orbit is told on the kept matrix where its own
    /// trivial multiplier (1 on the orbit) says it is accurate enough ([`CHORD_MARGIN`]); any
    /// other (an unstable orbit's multipliers are reported) takes one more flow with the
    /// variational equations at the converged orbit. On
    /// the issue-10 Stribeck sweep the transients' 68 slow-approach checks took 47.5 ms instead of
    /// 77 (one thread; Newton's own matrix: 3.3 flows with the variational equations a check),
    /// with the same verdicts.
    Chord,
}

/// The chord's kept monodromy matrix ([`Newton::Chord`]) tells a stable orbit when every
/// non-trivial multiplier is inside the unit circle by at least this many times the matrix's
/// error, gauged by its trivial multiplier's distance from 1.
const CHORD_MARGIN: f64 = 10.0;

/// A chord step ([`Newton::Chord`]) is taken where it shrinks the residual at least this much;
/// otherwise the iterate's own monodromy matrix is computed and kept from there.
const CHORD_CONTRACTION: f64 = 0.3;

/// The end of one period of the flow of the state alone (no variational equations), for the
/// chord steps of [`Newton::Chord`]: `phi` is left NaN for the caller to fill.
pub(super) fn flow_state(
    s: &Slider,
    y0: &State,
    mode0: ContactMode,
    t_end: f64,
    opts: &ShootingOptions,
    rtol: f64,
    stats: &mut Stats,
) -> Result<Flow, Status> {
    let sz = scales(s);
    let mut o = Options::<6>::new(rtol, 1.0);
    o.max_steps = ORBIT_FLOW_MAX_STEPS;
    for i in 0..6 {
        o.atol[i] = rtol * sz[i];
    }
    let make = |m| Forced { slider: s, start: m };
    let mut cap = Cap::NONE;
    let mut obs = crate::ode::NoObserver;
    let sol = run_watched(make, s, opts.method, 0.0, *y0, mode0, t_end, &o, false, &mut cap, &mut obs, stats);
    match sol.outcome {
        Outcome::Finished => Ok(Flow {
            y: sol.y,
            phi: Jacobian::repeat(f64::NAN),
            mode: sol.mode,
            n_switches: 0,
            refinements: cap.refinements,
        }),
        Outcome::StoppedByEvent => Err(Status::Diverged),
        other => Err(other.status()),
    }
}

pub(super) fn shoot_impl(
    s: &Slider,
    y0: &State,
    period: f64,
    opts: &ShootingOptions,
    refine_period: bool,
    newton: Newton,
) -> PeriodicOrbit {
    let mut stats = Stats::default();
    let sz = scales(s);
    let mut y = *y0;
    if !period.is_finite() || period <= 0.0 || !y.iter().all(|v| v.is_finite()) {
        return unconverged(Failure::InvalidStart { period }, f64::NAN, 0, stats);
    }
    if y[idx::ZD] != 0.0 {
        match to_section(s, &y, 2.0 * period, opts, &mut stats) {
            Some(v) => y = v,
            None if crate::cancel::requested() => {
                return unconverged(Failure::Cancelled { t: f64::NAN }, f64::NAN, 0, stats)
            }
            None => return unconverged(Failure::NoSection { horizon: 2.0 * period }, f64::NAN, 0, stats),
        }
    }
    y[idx::ZD] = 0.0;
    let mut t = if refine_period { first_return(s, &y, period, opts, &mut stats) } else { period };
    let mut iterations = 0;
    // The monodromy matrix of the chord (`Newton::Chord`): that of the first flow.
    let mut kept: Option<(Jacobian, u32)> = None;
    // Whether `kept` is the monodromy matrix of the current iterate.
    let mut kept_here = true;
    let eval = |y: &State,
                t: f64,
                rtol: f64,
                kept: &mut Option<(Jacobian, u32)>,
                stats: &mut Stats|
     -> Result<(Flow, State, f64), Status> {
        let mode0 = s.mode_at(y);
        let fl = match *kept {
            Some((phi, n_switches)) => Flow { phi, n_switches, ..flow_state(s, y, mode0, t, opts, rtol, stats)? },
            None => {
                let fl = flow(s, y, mode0, t, opts, &options_42(s, rtol), stats)?;
                if newton == Newton::Chord {
                    *kept = Some((fl.phi, fl.n_switches));
                }
                fl
            }
        };
        let r = fl.y - y;
        let rn = r.component_div(&sz).amax();
        Ok((fl, r, rn))
    };
    // Graded accuracy: while far from the orbit the flow is integrated only as accurately as the
    // next Newton iterate can use (1e-3 of the residual expected after a quadratic step, at most
    // 1e-6; the first evaluation at 1e-7); convergence is only declared, and the monodromy matrix
    // only kept, from an integration at `opts.rtol` (on the seed orbit: 4 integrations at 1e-7,
    // 1e-6, 5e-10, 1e-11 instead of 4 at 1e-11).
    let graded = |rn_prev: f64| (1e-3 * rn_prev * rn_prev).clamp(opts.rtol, 1e-6);
    let mut rtol = opts.rtol.max(1e-7);
    let (mut fl, mut r, mut rn) = match eval(&y, t, rtol, &mut kept, &mut stats) {
        Ok(v) => v,
        Err(st) => return unconverged(Failure::OrbitFlow { status: st, period: t }, f64::NAN, 0, stats),
    };
    let mut status = Status::NewtonNotConverged;
    let mut stalled = false;
    // The scaled size of the last accepted step (the chord's convergence test).
    let mut last_step = f64::INFINITY;
    let mut prev_step = f64::INFINITY;
    // The current iterate's flow again (at `rtol`, with `kept` as it now is), then the next round;
    // a failed flow ends the solve.
    macro_rules! reeval {
        () => {
            match eval(&y, t, rtol, &mut kept, &mut stats) {
                Ok(v) => (fl, r, rn) = v,
                Err(st) => {
                    status = st;
                    break;
                }
            }
            continue
        };
    }
    loop {
        if crate::cancel::requested() {
            status = Status::NotComputed;
            break;
        }
        if !rn.is_finite() {
            status = Status::NonFinite;
            break;
        }
        // The chord converges linearly: its iterate is within about its last step of the orbit, which
        // (through the Newton matrix's smallest singular value, small near a multiplier of 1)
        // can be far above the residual; it stops once that step is below `tol` too, or no longer
        // shrinks (the integration's noise, amplified by that singular value).
        let settled = last_step <= opts.tol || last_step > CHORD_CONTRACTION * prev_step;
        let converged = rn <= opts.tol && (newton == Newton::Full || settled);
        if converged || stalled {
            if rtol > opts.rtol {
                // Judge again at full accuracy before deciding. (After a failed line search: the
                // residual was judged at a graded, lower accuracy; from a start already close to
                // the orbit, such as a transient's section state, the accurate residual can be
                // above the coarse one, so no step could beat it.)
                rtol = opts.rtol;
                stalled = false;
                reeval!();
            }
            // At full accuracy: converged; or no step reduces the residual, which is then at the
            // integration's noise floor, and within the small-step acceptance (100 tol) that is
            // convergence too.
            if converged || rn <= opts.tol * 100.0 {
                status = Status::Success;
            }
            break;
        }
        if iterations >= opts.max_iter {
            break;
        }
        iterations += 1;
        // Scaled Newton matrix: rows by sizes, columns by sizes (state) and T (period).
        let f_end = s.rhs(&fl.y, fl.mode);
        let mut a = SMatrix::<f64, 6, 6>::zeros();
        for (col, &j) in FREE.iter().enumerate() {
            for i in 0..6 {
                let m = fl.phi[(i, j)] - if i == j { 1.0 } else { 0.0 };
                a[(i, col)] = m * sz[j] / sz[i];
            }
        }
        for i in 0..6 {
            a[(i, 5)] = f_end[i] * t / sz[i];
        }
        let rhs = -r.component_div(&sz);
        let Some(du) = a.lu().solve(&rhs) else { break };
        if !du.iter().all(|v| v.is_finite()) {
            break;
        }
        let small_step = du.amax() <= opts.tol * 1e-2;
        let rtol_next = graded(rn);
        // A chord step: the kept matrix is another iterate's (the first step from a fresh matrix
        // is Newton's own, taken by Newton's rule).
        let chord = kept.is_some() && !kept_here;
        let mut lambda = 1.0;
        let mut accepted = false;
        let mut refresh = false;
        for _ in 0..8 {
            let mut yt = y;
            for (col, &j) in FREE.iter().enumerate() {
                yt[j] += lambda * du[col] * sz[j];
            }
            let tt = t * (1.0 + lambda * du[5]);
            let trial = eval(&yt, tt, rtol_next, &mut kept, &mut stats);
            if chord && !small_step && !matches!(trial, Ok((_, _, rnt)) if rnt <= CHORD_CONTRACTION * rn) {
                // The kept matrix is too far from this iterate's: a new one here; or, within the
                // small-step acceptance, the residual is at the integration's noise floor, judged
                // as a stalled Newton iteration is.
                refresh = rn > 100.0 * opts.tol;
                break;
            }
            if let Ok((flt, rt, rnt)) = trial {
                if rnt < rn || small_step {
                    kept_here = false;
                    prev_step = last_step;
                    last_step = lambda * du.amax();
                    y = yt;
                    t = tt;
                    fl = flt;
                    r = rt;
                    rn = rnt;
                    rtol = rtol_next;
                    accepted = true;
                    break;
                }
            }
            lambda *= 0.5;
        }
        if refresh {
            kept = None;
            kept_here = true;
            reeval!();
        }
        if !accepted {
            stalled = true;
            continue;
        }
        if small_step && rtol <= opts.rtol {
            status = if rn <= opts.tol * 100.0 { Status::Success } else { Status::NewtonNotConverged };
            break;
        }
    }
    if status != Status::Success {
        let failure = match status {
            Status::NewtonNotConverged => {
                Failure::Newton { iterations, max_iter: opts.max_iter, residual: rn, tol: opts.tol }
            }
            Status::NotComputed => Failure::Cancelled { t: f64::NAN },
            other => Failure::OrbitFlow { status: other, period: t },
        };
        return unconverged(failure, rn, iterations, stats);
    }
    if newton == Newton::Chord && !chord_says_stable(&fl.phi, opts.stability_tol) {
        // The kept matrix cannot tell, or tells an unstable orbit, whose multipliers are reported
        // (the intermittent cycle's): the monodromy matrix of the converged orbit.
        match flow(s, &y, s.mode_at(&y), t, opts, &options_42(s, opts.rtol), &mut stats) {
            Ok(f) => fl.phi = f.phi,
            Err(st) => return unconverged(Failure::OrbitFlow { status: st, period: t }, rn, iterations, stats),
        }
    }
    let mut orbit = analyse(s, &y, t, &fl, opts, &mut stats);
    if orbit.status != Status::Success {
        return unconverged(Failure::OrbitFlow { status: orbit.status, period: t }, rn, iterations, stats);
    }
    // Steady sliding is a "periodic orbit" of every period: Newton can end there from a poor
    // guess. That is no cycle.
    let swing = orbit.z_max - orbit.z_min;
    let floor = 1e-6 * sz[idx::Z];
    if swing.is_nan() || swing <= floor {
        return unconverged(Failure::NoCycle { swing, floor }, rn, iterations, stats);
    }
    orbit.residual_norm = rn;
    orbit.newton_iterations = iterations;
    orbit.stats = stats;
    orbit
}

/// Whether the multipliers of the monodromy matrix `phi` (kept by the chord, [`Newton::Chord`])
/// tell the orbit stable: every non-trivial one is inside the unit circle by more than
/// [`CHORD_MARGIN`] times the trivial one's distance from 1 (its error) and `stability_tol`.
fn chord_says_stable(phi: &Jacobian, stability_tol: f64) -> bool {
    let Some(ev) = eigenvalues(phi) else { return false };
    let trivial = trivial_index(&ev);
    let err = (ev[trivial] - 1.0).norm();
    (0..6).filter(|&k| k != trivial).all(|k| ev[k].norm() < 1.0 - CHORD_MARGIN * err - stability_tol)
}
