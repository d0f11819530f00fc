//! Events on an accepted step: sign changes located on the step's dense output ([`locate`]), acted
//! on in time order, reported to the observer; the hidden-crossing check inside a step.
//!
//! The rules (restart, grazing guard, truncation) are those of the driver's module documentation;
//! this code is shared by the scalar driver ([`super::driver`]) and the lane-batched slider paths
//! (`crate::ensemble::lanes`), which call [`step_events`] for a lane whose step shows a crossing.

use super::stepper::StepDense;
use super::{Control, Dense, EventAction, Observer, OdeSystem, Options, Outcome, Stats, StepView, MAX_EVENTS};
use nalgebra::SVector;

/// A sign change from `a` (nonzero) to `b` (other sign or exactly zero).
#[inline]
pub(crate) fn crosses(a: f64, b: f64) -> bool {
    (a > 0.0 && b <= 0.0) || (a < 0.0 && b >= 0.0)
}

/// A root of `g` in `[a, b]`, `ga` and `gb` of opposite signs (or `gb == 0`): returns a time on the
/// `b` side of the root with `b - root <= tol` (or a point where `g` is exactly 0).
///
/// A bracketing method in the manner of Brent's: inverse quadratic interpolation through the two
/// ends and the last point dropped from the bracket (a secant step on the first iteration), taken
/// when it falls inside the bracket; bisection when the bracket failed to halve in two iterations.
/// Every new point is kept at least `tol/2` from both ends, so once the estimate has converged
/// onto one end the next point lands just past the root and the bracket collapses to `tol`,
/// instead of creeping in from the far end as plain regula falsi does. On the slider's contact
/// events this takes about 4 evaluations where Illinois took about 20.
pub(crate) fn locate(g: impl FnMut(f64) -> f64, a: f64, ga: f64, b: f64, gb: f64, tol: f64) -> f64 {
    locate_from(g, a, ga, b, gb, tol, None)
}

/// [`locate`] started from a model of `g`: `guess = (t, slope)`, a time near the root and the
/// model's `dg/dt` there (from [`hermite_root`]). The first point is the guess; the second a
/// Newton step from it with the model's slope, aimed `tol/2` past the predicted root so that it
/// lands on the root's far side and the bracket collapses to the guess's error at once. Then
/// [`locate`]'s iteration, on a bracket that is already small. With the slider's contact events
/// and sections this takes about 3 evaluations of `g` where `locate` took about 6. The result
/// obeys `locate`'s contract whatever the guess (a poor one costs at most two evaluations).
pub(crate) fn locate_from(
    mut g: impl FnMut(f64) -> f64,
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
    tol: f64,
    guess: Option<(f64, f64)>,
) -> f64 {
    if gb == 0.0 {
        return b;
    }
    // The last point dropped from the bracket (NaN: none yet, or not usable).
    let (mut d, mut gd) = (f64::NAN, f64::NAN);
    // `c` replaces the end of the bracket on its side of the root (a NaN value: the right end).
    macro_rules! take {
        ($c:expr, $gc:expr) => {{
            let (c, gc) = ($c, $gc);
            if gc.is_nan() {
                b = c;
                (d, gd) = (f64::NAN, f64::NAN);
            } else if (gc > 0.0) == (gb > 0.0) {
                (d, gd) = (b, gb);
                (b, gb) = (c, gc);
            } else {
                (d, gd) = (a, ga);
                (a, ga) = (c, gc);
            }
        }};
    }
    if let Some((tg, slope)) = guess {
        let (lo, hi) = (a + 0.5 * tol, b - 0.5 * tol);
        if tg.is_finite() && lo < hi {
            let c = tg.clamp(lo, hi);
            let gc = g(c);
            if gc == 0.0 {
                return c;
            }
            take!(c, gc);
            if gc.is_finite() && slope.is_finite() && slope != 0.0 && b - a > tol {
                // The root lies after `c` where `c` became the left end.
                let past = if a == c { 0.5 * tol } else { -0.5 * tol };
                let c2 = c - gc / slope + past;
                if c2 > a + 0.5 * tol && c2 < b - 0.5 * tol {
                    let g2 = g(c2);
                    if g2 == 0.0 {
                        return c2;
                    }
                    take!(c2, g2);
                }
            }
        }
    }
    let mut width_2ago = f64::INFINITY;
    let mut width_1ago = f64::INFINITY;
    for _ in 0..300 {
        let w = b - a;
        if w <= tol {
            break;
        }
        let bisect = w > 0.5 * width_2ago;
        width_2ago = width_1ago;
        width_1ago = w;
        let mut c = 0.5 * (a + b);
        if !bisect {
            let secant = b - gb * (b - a) / (gb - ga);
            c = secant;
            if gd.is_finite() && gd != ga && gd != gb {
                let iqi = a * (gb / (ga - gb)) * (gd / (ga - gd))
                    + b * (ga / (gb - ga)) * (gd / (gb - gd))
                    + d * (ga / (gd - ga)) * (gb / (gd - gb));
                if iqi > a && iqi < b {
                    c = iqi;
                }
            }
        }
        c = c.max(a + 0.5 * tol).min(b - 0.5 * tol);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
            if !(c > a && c < b) {
                break; // the bracket is down to adjacent floats
            }
        }
        let gc = g(c);
        if gc == 0.0 {
            return c;
        }
        // A NaN value is treated as lying on the far side (shrinks from the right).
        take!(c, gc);
    }
    b
}

/// The root of the cubic Hermite model of a function on a step of length `h`, from its values
/// `g0`, `g1` (of opposite signs, or `g1 == 0`) and time derivatives `d0`, `d1` at the ends: the
/// time `t0 + x h` of the model's sign change in `(0, 1)` (safeguarded Newton on the cubic from
/// the secant point) and the model's `dg/dt` there. `None` when an input is not finite. The
/// model's error is that of a cubic over the step, far below the step: a start for
/// [`locate_from`], which checks it against the function itself.
pub(crate) fn hermite_root(t0: f64, h: f64, g0: f64, g1: f64, d0: f64, d1: f64) -> Option<(f64, f64)> {
    let (m0, m1) = (h * d0, h * d1);
    if !(g0.is_finite() && g1.is_finite() && m0.is_finite() && m1.is_finite() && h > 0.0) || g0 == 0.0 {
        return None;
    }
    // p(x) = a3 x^3 + a2 x^2 + m0 x + g0 with p(1) = g1, p'(1) = m1.
    let a2 = 3.0 * (g1 - g0) - 2.0 * m0 - m1;
    let a3 = 2.0 * (g0 - g1) + m0 + m1;
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let mut x = g0 / (g0 - g1);
    for _ in 0..8 {
        let p = ((a3 * x + a2) * x + m0) * x + g0;
        let dp = (3.0 * a3 * x + 2.0 * a2) * x + m0;
        if p == 0.0 {
            break;
        }
        if (p > 0.0) == (g0 > 0.0) {
            lo = x;
        } else {
            hi = x;
        }
        let mut xn = x - p / dp;
        if !(xn > lo && xn < hi) {
            xn = 0.5 * (lo + hi);
        }
        let step = (xn - x).abs();
        x = xn;
        if step <= 1e-12 {
            break;
        }
    }
    let dp = (3.0 * a3 * x + 2.0 * a2) * x + m0;
    Some((t0 + h * x, dp / h))
}

/// `sys.on_event`, kept out of line: it runs only at events (the slider's evaluates its
/// right-hand side), so there is no reason to grow the step loop with it.
#[inline(never)]
#[cold]
fn event_action<const N: usize, S: OdeSystem<N>>(
    sys: &S,
    t: f64,
    y: &SVector<f64, N>,
    mode: S::Mode,
    index: usize,
) -> EventAction<S::Mode> {
    sys.on_event(t, y, mode, index)
}

/// A located crossing within the current step.
#[derive(Clone, Copy)]
struct Found<const N: usize, M> {
    t: f64,
    index: usize,
    y: SVector<f64, N>,
    action: EventAction<M>,
}

/// How an accepted step ended, as the driver continues from it.
pub(crate) struct StepEnd<const N: usize, M> {
    /// End of the step as the observer saw it (an event time if truncated).
    pub(crate) t1: f64,
    pub(crate) y1: SVector<f64, N>,
    /// Mode from here on.
    pub(crate) new_mode: M,
    /// The run ends here.
    pub(crate) end: Option<Outcome>,
    /// A `Switch` truncated the step: restart there.
    pub(crate) switched: Option<Switched>,
}

/// What a restart after a `Switch` needs to set the pending events.
pub(crate) struct Switched {
    /// The event that switched.
    pub(crate) index: usize,
    /// Pending state of every event at the start of the truncated step.
    pub(crate) pend_before: [Option<f64>; MAX_EVENTS],
    /// Check times of the events pending in that step (`-inf` for the others).
    pub(crate) t_check: [f64; MAX_EVENTS],
}

/// Where an event function that does not change sign between the ends of a step may still touch
/// zero inside it: the turning point of its cubic Hermite model, from its values `g0`, `g1` and
/// time derivatives `d0`, `d1` at the ends of a step of length `h`, as `x = (t - t0) / h` in
/// `(0, 1)`, with the model's value there. `None` unless the function heads towards zero at the start and away from it at the
/// end (`g0 d0 < 0`, `g1 d1 > 0`, same signs at both ends): only then can a crossing and its return
/// hide inside the step. Evenly spaced interior points miss an excursion shorter than their
/// spacing (a pin that rises 50 nm above the disk for 0.1 ms of a 0.5 ms step); the turning
/// point is where such an excursion peaks, to the model's accuracy (exact for a parabola).
#[inline]
pub(crate) fn turn_point(g0: f64, g1: f64, d0: f64, d1: f64, h: f64) -> Option<(f64, f64)> {
    let x = turn_x(g0, g1, d0, d1, h);
    if x.is_nan() {
        return None;
    }
    let (m0, m1) = (h * d0, h * d1);
    let x1 = 1.0 - x;
    let p = g0 * (1.0 + 2.0 * x) * x1 * x1 + m0 * x * x1 * x1 + g1 * x * x * (3.0 - 2.0 * x) - m1 * x * x * x1;
    Some((x, p))
}

/// The `x` of [`turn_point`], NaN where it gives `None`; branch-free (selects by bit masks), so
/// that the lanes' loop over it vectorises with the scalar's bits.
#[inline(always)]
pub(crate) fn turn_x(g0: f64, g1: f64, d0: f64, d1: f64, h: f64) -> f64 {
    let heads = (g0 * g1 > 0.0) & (g0 * d0 < 0.0) & (g1 * d1 > 0.0);
    let (m0, m1) = (h * d0, h * d1);
    // p'(x) = a x^2 + b x + c, with p'(0) = m0 and p'(1) = m1 of opposite signs: one root in (0, 1).
    let a = 6.0 * (g0 - g1) + 3.0 * (m0 + m1);
    let b = 6.0 * (g1 - g0) - 4.0 * m0 - 2.0 * m1;
    let c = m0;
    // The root in [0, 1] by the cancellation-free quadratic formula (a linear p' when a is
    // negligible); the sign change makes the discriminant non-negative up to rounding.
    let lin = -c / b;
    let q = -0.5 * (b + b.signum() * (b * b - 4.0 * a * c).max(0.0).sqrt());
    let (r1, r2) = (q / a, c / q);
    let quad = sel((0.0..=1.0).contains(&r1), r1, r2);
    let x = sel(a.abs() <= 1e-12 * (b.abs() + c.abs()), lin, quad);
    sel(heads & (x > 0.0) & (x < 1.0), x, f64::NAN)
}

/// `a` if `c`, else `b`, by bit masks (no branch).
#[inline(always)]
fn sel(c: bool, a: f64, b: f64) -> f64 {
    super::lanes::blend((c as u64).wrapping_neg(), a, b)
}

/// A crossing and its return hidden inside a step: the earliest of the interior points (of
/// `opts.interior_checks` evenly spaced ones, and each event function's [`turn_point`] where the
/// system gives the rates of its event functions, `f0`/`f1` being the right-hand side at the step
/// ends) at which an event function that is not pending differs in sign from the step start while
/// the step end does not.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn hidden_crossing<const N: usize, S: OdeSystem<N>, D: Dense<N>>(
    sys: &S,
    dense: &D,
    mode: S::Mode,
    (t, y0, f0): (f64, &SVector<f64, N>, &SVector<f64, N>),
    (t_new, y1, f1): (f64, &SVector<f64, N>, &SVector<f64, N>),
    n_ev: usize,
    g0: &[f64; MAX_EVENTS],
    g1: &[f64; MAX_EVENTS],
    pend: &[Option<f64>; MAX_EVENTS],
    opts: &Options<N>,
) -> Option<f64> {
    let hidden_at = |tj: f64| {
        let mut gk = [0.0; MAX_EVENTS];
        sys.events(tj, &dense.eval(tj), mode, &mut gk);
        (0..n_ev).any(|i| pend[i].is_none() && crosses(g0[i], gk[i]) && !crosses(g0[i], g1[i]))
    };
    let mut first: Option<f64> = None;
    let (mut d0, mut d1) = ([f64::NAN; MAX_EVENTS], [f64::NAN; MAX_EVENTS]);
    if sys.event_rates(t, y0, f0, mode, &mut d0) && sys.event_rates(t_new, y1, f1, mode, &mut d1) {
        let h = t_new - t;
        for i in 0..n_ev {
            if pend[i].is_some() {
                continue;
            }
            if let Some((x, _)) = turn_point(g0[i], g1[i], d0[i], d1[i], h) {
                let tj = t + h * x;
                if tj > t && tj < t_new && first.is_none_or(|f| tj < f) && hidden_at(tj) {
                    first = Some(tj);
                }
            }
        }
    }
    let k = opts.interior_checks as usize;
    for j in 1..=k {
        let tj = t + (t_new - t) * j as f64 / (k + 1) as f64;
        if first.is_some_and(|f| f <= tj) {
            break;
        }
        if hidden_at(tj) {
            return Some(tj);
        }
    }
    first
}

/// Locate, act on and report the events of an accepted step `[t, t_new]` in which some event
/// function changed sign or was pending; calls the observer for the (possibly truncated) step and
/// its events. Out of line: most steps have no event, and keeping this off the step loop keeps
/// that loop small.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_events<const N: usize, S, O, D>(
    sys: &S,
    obs: &mut O,
    opts: &Options<N>,
    stats: &mut Stats,
    dense: &D,
    mode: S::Mode,
    (t, y): (f64, &SVector<f64, N>),
    (t_new, y_new): (f64, &SVector<f64, N>),
    n_ev: usize,
    g0: &[f64; MAX_EVENTS],
    g1: &[f64; MAX_EVENTS],
    pend: &mut [Option<f64>; MAX_EVENTS],
) -> StepEnd<N, S::Mode>
where
    S: OdeSystem<N>,
    O: Observer<N, S::Mode>,
    D: StepDense<N>,
{
    // One slot per function, and as many again for crossings seen after a `Continue` event.
    let mut found: [Option<Found<N, S::Mode>>; 2 * MAX_EVENTS] = [None; 2 * MAX_EVENTS];
    let mut n_found = 0;
    let pend_before = *pend;
    let mut t_check = [f64::NEG_INFINITY; MAX_EVENTS];
    let g_at = |i: usize, tt: f64| sys.event(tt, &dense.eval_some(tt, sys.event_reads(i)), mode, i);
    // The event functions' rates at both ends (for the cubic model each crossing's search starts
    // from), computed at the first crossing that needs them.
    let mut rates: Option<Option<([f64; MAX_EVENTS], [f64; MAX_EVENTS])>> = None;
    let mut rates_of = || -> Option<([f64; MAX_EVENTS], [f64; MAX_EVENTS])> {
        let (_, (f0, f1)) = dense.end_rates()?;
        let (mut d0, mut d1) = ([f64::NAN; MAX_EVENTS], [f64::NAN; MAX_EVENTS]);
        (sys.event_rates(t, y, &f0, mode, &mut d0) && sys.event_rates(t_new, y_new, &f1, mode, &mut d1))
            .then_some((d0, d1))
    };
    for i in 0..n_ev {
        let (ta, ga) = match pend[i] {
            None => (t, g0[i]),
            Some(ts) => {
                let tc = (ts + opts.event_guard).max(t + 1e-6 * (t_new - t));
                t_check[i] = tc;
                if tc >= t_new {
                    continue;
                }
                let gc = g_at(i, tc);
                if gc == 0.0 || gc.is_nan() {
                    if g1[i] != 0.0 {
                        pend[i] = None;
                    }
                    continue;
                }
                pend[i] = None;
                (tc, gc)
            }
        };
        if crosses(ga, g1[i]) && sys.crossing_counts(mode, i, ga < 0.0) {
            // From the start of the step, the search starts at the root of the function's cubic
            // model (after a pending event's check time, the model's root may be that event's).
            let guess = if ta == t {
                rates
                    .get_or_insert_with(&mut rates_of)
                    .and_then(|(d0, d1)| hermite_root(t, t_new - t, ga, g1[i], d0[i], d1[i]))
            } else {
                None
            };
            let te = locate_from(|tt| g_at(i, tt), ta, ga, t_new, g1[i], opts.event_tol, guess);
            found[n_found] = Some(Found { t: te, index: i, y: *y_new, action: EventAction::Continue });
            n_found += 1;
        }
    }
    // Time order (ties by index); at most MAX_EVENTS entries: insertion sort.
    for a in 1..n_found {
        let mut b = a;
        while b > 0 && found[b - 1].map(|e| e.t) > found[b].map(|e| e.t) {
            found.swap(b - 1, b);
            b -= 1;
        }
    }

    // Actions in time order, up to the first truncating one. An event that changes nothing
    // (`Continue`) is a point inside the step where every function can be read: one that crossed
    // and came back before it looked unchanged at the step's ends, and may now show a crossing
    // between the event and the end, which is then located and acted on in its turn. In
    // particular a pin that meets the disk with the law in tension (`GAP`, no landing) lands
    // where the law turns compressive (`NORMAL`); within one long free-flight step that turn
    // can lie inside a dip of the law force that the step's ends and interior checks miss.
    let mut n_proc = 0;
    let mut trunc = false;
    let mut g_e = [0.0; MAX_EVENTS];
    while n_proc < n_found {
        let e = found[n_proc].as_mut().expect("filled above");
        if e.t < t_new {
            e.y = dense.eval(e.t);
        }
        e.action = event_action(sys, e.t, &e.y, mode, e.index);
        n_proc += 1;
        if !matches!(e.action, EventAction::Continue) {
            trunc = true;
            break;
        }
        let (te, ye) = (e.t, e.y);
        if te >= t_new {
            continue;
        }
        sys.events(te, &ye, mode, &mut g_e);
        for j in 0..n_ev {
            // Not a function just crossed here or earlier in the step (its value at `te` is its
            // own root's rounding), nor one still guarded after an earlier event, nor one whose
            // crossing is already queued.
            let seen = found[..n_found].iter().flatten().any(|f| f.index == j);
            if seen || te < t_check[j] || g_e[j] == 0.0 || g_e[j].is_nan() || n_found == found.len() {
                continue;
            }
            if crosses(g_e[j], g1[j]) && sys.crossing_counts(mode, j, g_e[j] < 0.0) {
                let tj = locate_from(|tt| g_at(j, tt), te, g_e[j], t_new, g1[j], opts.event_tol, None);
                let mut b = n_found;
                found[b] = Some(Found { t: tj, index: j, y: *y_new, action: EventAction::Continue });
                n_found += 1;
                while b > n_proc && found[b - 1].map(|f| f.t) > found[b].map(|f| f.t) {
                    found.swap(b - 1, b);
                    b -= 1;
                }
            }
        }
    }
    let (t1, y1) = if trunc {
        let e = found[n_proc - 1].expect("filled above");
        (e.t, e.y)
    } else {
        (t_new, *y_new)
    };

    let mut end = None;
    let mut new_mode = mode;
    let view = StepView { t0: t, t1, y0: y, y1: &y1, mode, dense };
    if obs.on_step(&view) == Control::Stop {
        end = Some(Outcome::StoppedByObserver);
    } else {
        for e in found.iter().take(n_proc).flatten() {
            stats.n_events += 1;
            if stats.n_events > opts.max_events {
                end = Some(Outcome::EventChatter);
                break;
            }
            let after = match e.action {
                EventAction::Switch(m) => m,
                _ => mode,
            };
            let c = obs.on_event(e.index, e.t, &e.y, mode, after);
            new_mode = after;
            if matches!(e.action, EventAction::Stop) {
                end = Some(Outcome::StoppedByEvent);
            }
            if c == Control::Stop {
                end = Some(Outcome::StoppedByObserver);
            }
            if end.is_some() {
                break;
            }
        }
    }
    let switched = if trunc && end.is_none() {
        let index = found[n_proc - 1].expect("filled above").index;
        Some(Switched { index, pend_before, t_check })
    } else {
        None
    };
    StepEnd { t1, y1, new_mode, end, switched }
}
