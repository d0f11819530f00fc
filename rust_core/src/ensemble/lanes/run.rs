//! The loop over steps of the `N` lanes: the attempt, the events at the step end and inside it,
//! the controller, the common accepted step on the lanes, and the cold path for lanes that need
//! their scalar side (the scalar driver's event code, observers, the end of a run).

use super::quick::{go_on, quick_event, restart, Quick};
use super::slider::{
    event_rates_lanes, events_at, events_lanes, hidden_crossings, n_events, Coef, Modes, SliderRhs, EV_COMPS,
    EV_COMPS_CONST, NE, SWITCH, TANH,
};
use super::state::{finish, park, refill, sync_from_side, sync_to_side, unpark, Input, Lanes, Parked, Side, Watch};
use crate::cancel;
use crate::ensemble::{Task, TrajectoryResult};
use crate::model::{event, idx, ContactMode, State};
use crate::ode::controller::{FAC_MAX, FAC_MIN, SAFETY};
use crate::ode::dop853::Dop853Dense;
use crate::ode::dopri5::Dopri5Dense;
use crate::ode::events::{step_events, turn_x, StepEnd};
use crate::ode::lanes::{
    blend, cross, dop853_dense_into, dop853_poly_into, dop853_step, dopri5_dense_into, dopri5_step, each6, exp_lanes,
    lane_state, ln_lanes, sample_lanes, splat, Lw, Vw, ALL_COMPS, ALPHA, ALPHA8, BETA, LN_ERR_FLOOR, LN_SAFETY,
};
use crate::ode::lanes::{Al, LaneDense};
use crate::ode::stepper::StepDense;
use crate::ode::{Control, Observer, Options, Outcome, SampleStore, StepView, MAX_EVENTS};
use std::sync::atomic::Ordering::Relaxed;

/// The portable path (the tests check that the SIMD copies agree bitwise).
///
/// `seed`: trajectories parked by another set of lanes (at most `N`), run here before the
/// feed's. `narrow`: once the feed is dry and at most half the lanes run, they are parked and
/// returned with the results so far, for a narrower set to finish (a round on 1, 2, 4 and 8
/// lanes: about 0.72, 0.97, 1.09 and 1.28 us on the switch law's transients).
#[inline(always)]
pub(super) fn run_impl<'a, const UNI: bool, const LAW: u8, const M8: bool, const N: usize>(
    inp: &Input<'a, '_>,
    seed: Vec<Parked<'a>>,
    narrow: bool,
) -> (Vec<(usize, TrajectoryResult)>, Vec<Parked<'a>>) {
    let (task, t_end) = (inp.task, inp.t_end);
    let n = inp.sliders.len();
    let rtol = inp.tol.rtol;
    let mut out: Vec<(usize, TrajectoryResult)> = Vec::with_capacity(n);
    let zero = [0.0; N];
    let mut ln = Lanes {
        c: Coef::zero(),
        y: [zero; 6],
        f: [zero; 6],
        t: zero,
        h: zero,
        ln_err_old: splat(LN_ERR_FLOOR),
        rejected: [false; N],
        n_acc: [0; N],
        n_rej: [0; N],
        n_extra: [0; N],
        m8: M8,
        modes: Modes::new(),
        g0: [splat(1.0); NE],
        pend: [[false; N]; NE],
        pend_t: [splat(f64::NAN); NE],
        min_n: zero,
        max_gap: zero,
        min_vr: zero,
        max_z: zero,
        peak: zero,
        peaks: [zero; 6],
        rest: splat(f64::NEG_INFINITY),
        next_sample: splat(f64::INFINITY),
        t_end: splat(t_end),
        side: std::array::from_fn(|_| None),
    };
    let steady = matches!(task, Task::Steady { .. });
    let sampled = matches!(task, Task::Sampled(_));
    let h_min_rel = Options::<6>::new(rtol, 1.0).h_min_rel;
    // The law's event functions, and whether steps are checked inside for hidden crossings (as
    // `steady::options_for` sets `interior_checks`: unilateral contact or the switch law).
    let ne = n_events(LAW);
    let checks = UNI || LAW == SWITCH;
    let mut seed = seed;
    assert!(seed.len() <= N, "run_impl: {} parked trajectories for {N} lanes", seed.len());
    for l in 0..N {
        match seed.pop() {
            Some(p) => unpark(&mut ln, l, p),
            None => refill(&mut ln, l, inp, &mut out),
        }
    }

    // Stages of the step: DP5's k2..k7, DOP853's (see `ode::lanes::dop853_step`).
    // On 64-byte boundaries (`Al`).
    let mut k = Al([[zero; 6]; 6]);
    let mut kk = Al([[zero; 6]; 16]);
    // DOP853's three extra stages of the interpolant (unilateral: built on the lanes every step).
    let mut extra = Al([[zero; 6]; 3]);
    // The step's interpolants, built into buffers kept across steps (built and moved per step,
    // they cost copies and zeroing): for the hidden-crossing check (the components its event
    // functions read), for samples, and DOP853's of all components shared by samples and the cold
    // path (`full`, valid where `full_built`). The switch law's events read every component, so
    // its check builds `full` itself: the cold path and the samples read the same coefficients
    // (same function, same inputs for the lanes they read) without building them again (an
    // eleventh of a Stribeck sweep's transients).
    let mut ev5 = LaneDense::<5, N>::new();
    let mut ev3 = LaneDense::<3, N>::new();
    let mut samp = LaneDense::<6, N>::new();
    let mut full = LaneDense::<6, N>::new();
    let mut yn = Al([zero; 6]);
    let mut fzl = zero;
    let mut fzl_scratch = zero;

    let mut rounds = 0u64;
    while ln.side.iter().any(|s| s.is_some()) {
        rounds += 1;
        if cancel::requested_every(rounds) {
            // The running trajectories end where they are; no new one starts (the caller marks
            // those as not started).
            for l in 0..N {
                if ln.side[l].is_some() {
                    let (t, y, h) = (ln.t[l], lane_state(&ln.y, l), ln.h[l]);
                    finish(&mut ln, l, t, y, h, Outcome::Cancelled, &mut out);
                }
            }
            break;
        }
        let live: [bool; N] = std::array::from_fn(|l| ln.side[l].is_some());
        if narrow && N > 1 && 2 * live.iter().filter(|&&x| x).count() <= N && inp.feed.next.load(Relaxed) >= n {
            let parked = (0..N).filter(|&l| live[l]).map(|l| park(&mut ln, l)).collect();
            return (out, parked);
        }
        // ---- before the attempt: landing on t_end, the step floor, the step budget ----
        let mut hh = zero;
        let mut last = [false; N];
        let mut floor = zero;
        let mut bad = false;
        for l in 0..N {
            let h = ln.h[l];
            let rem = ln.t_end[l] - ln.t[l];
            let la = h >= rem || 1.01 * h >= rem;
            last[l] = la;
            hh[l] = if la { rem } else { h };
            floor[l] = h_min_rel * ln.t[l].abs().max(1.0);
        }
        for l in 0..N {
            if let Some(sd) = &ln.side[l] {
                let too_small = (hh[l].is_nan() || hh[l] < floor[l]) && !last[l];
                bad |= too_small || ln.n_acc[l] + ln.n_rej[l] >= sd.opts.max_steps;
            }
        }
        if bad {
            for l in 0..N {
                let Some(sd) = &ln.side[l] else { continue };
                let too_small = (hh[l].is_nan() || hh[l] < floor[l]) && !last[l];
                let outcome = if too_small {
                    if hh[l].is_finite() {
                        Outcome::StepTooSmall
                    } else {
                        Outcome::NonFinite
                    }
                } else if ln.n_acc[l] + ln.n_rej[l] >= sd.opts.max_steps {
                    Outcome::MaxSteps
                } else {
                    continue;
                };
                let (t, y) = (ln.t[l], lane_state(&ln.y, l));
                finish(&mut ln, l, t, y, hh[l], outcome, &mut out);
                refill(&mut ln, l, inp, &mut out);
            }
            continue;
        }

        let c = &ln.c;
        let cm = &ln.modes;
        let y = &ln.y;
        let k1 = &ln.f;
        // The error measure: the squared RMS norm for DP5 (`err <= 1` iff `err^2 <= 1`, no square
        // root needed), Hairer's combined 5th/3rd-order norm for DOP853. The law force at the new
        // state is left in `fzl` by the last right-hand side.
        let (err, fin) = if M8 {
            dop853_step(
                &mut SliderRhs::<UNI, LAW, N> { c, m: cm, fzl: &mut fzl },
                y,
                k1,
                &hh,
                rtol,
                &c.atol,
                &mut kk,
                &mut yn,
            )
        } else {
            dopri5_step(
                &mut SliderRhs::<UNI, LAW, N> { c, m: cm, fzl: &mut fzl },
                y,
                k1,
                &hh,
                rtol,
                &c.atol,
                &mut k,
                &mut yn,
            )
        };
        let fnew: &Vw<N> = if M8 { &kk[12] } else { &k[5] };
        let mut ok = [false; N];
        for l in 0..N {
            ok[l] = (err[l] <= 1.0) & fin[l] & live[l];
        }

        // ---- events at the step end; hidden crossings inside the step (unilateral) ----
        let mut g1 = [splat(1.0); NE];
        events_lanes::<LAW, N>(c, cm, &yn, &fzl, &mut g1);
        // Theta of the interior point to end a redone step at (0: none).
        let mut hidden = zero;
        // The lanes whose step needs the hidden-crossing check (`near_events`): the check runs
        // when any does, and acts, counts and leaves its extra stages (DOP853) for those only, so
        // that a lane's run does not depend on the other lanes of its batch.
        // `turn[e]`: each near lane's turning point of event function `e` inside the step (0:
        // none), checked on the interpolant beside the three fixed points, as the scalar does.
        let mut turn = [zero; NE];
        let mut full_built = false;
        let need = if checks {
            near_events::<LAW, N>(c, cm, y, k1, &yn, fnew, &ln.g0, &g1, &ln.pend, &ok, &hh, &mut turn)
        } else {
            [false; N]
        };
        if need.iter().any(|&x| x) {
            let ok: [bool; N] = std::array::from_fn(|l| ok[l] & need[l]);
            // The interpolant at three interior points: DP5's from its stages, DOP853's needs
            // three more right-hand sides (its 7th-order dense output), counted as work. Only the
            // components the event functions read: under constant friction z, zd and phi.
            if M8 {
                for l in 0..N {
                    ln.n_extra[l] += 3 * ok[l] as u64;
                }
            }
            // One body for both component sets (their count is a const generic).
            macro_rules! check {
                ($comps:expr, $dense:expr) => {{
                    let dense = $dense;
                    if M8 {
                        let mut f = SliderRhs::<UNI, LAW, N> { c, m: cm, fzl: &mut fzl_scratch };
                        dop853_dense_into(dense, &mut f, $comps, y, &yn, k1, &hh, &kk, &mut extra);
                    } else {
                        dopri5_dense_into(dense, $comps, y, &yn, [k1, &k[1], &k[2], &k[3], &k[4], &k[5]], &hh);
                    }
                    hidden_crossings::<LAW, _, N>(c, cm, dense, &ln.g0, &g1, &ln.pend, &ok, &turn, &mut hidden);
                }};
            }
            match LAW {
                SWITCH => {
                    check!(&ALL_COMPS, &mut full);
                    full_built = M8;
                }
                TANH => check!(&EV_COMPS, &mut ev5),
                _ => check!(&EV_COMPS_CONST, &mut ev3),
            }
        }

        // ---- accept or reject, the controller (branch-free) ----
        let mut lnx = zero;
        for l in 0..N {
            lnx[l] = err[l].max(1e-300);
        }
        let mut ln_err = ln_lanes(&lnx);
        if !M8 {
            for v in ln_err.iter_mut() {
                *v *= 0.5;
            }
        }
        let alpha = if M8 { ALPHA8 } else { ALPHA };
        let mut arg = zero;
        for l in 0..N {
            // Both, then the bits of one (an `if` here compiled to a branch per lane).
            let accept = -(alpha * ln_err[l] - BETA * ln.ln_err_old[l] - LN_SAFETY);
            arg[l] = blend((ok[l] as u64).wrapping_neg(), accept, -alpha * ln_err[l]);
        }
        let r = exp_lanes(&arg);
        let t_start = ln.t;
        let mut acc_ok = [false; N];
        let mut t_new = zero;
        for l in 0..N {
            let okl = ok[l];
            let hid = hidden[l] > 0.0;
            let e = err[l];
            let ra = if e <= 0.0 { FAC_MAX } else { r[l].clamp(FAC_MIN, FAC_MAX) };
            let ratio_a = if ln.rejected[l] { ra.min(1.0) } else { ra };
            let ordinary = e.is_finite() && fin[l];
            let ratio_r = if ordinary { (SAFETY * r[l]).clamp(FAC_MIN, 1.0) } else { FAC_MIN };
            // A hidden crossing redoes the step ending inside the excursion; the controller's
            // history is left as it was (the scalar driver's `h = t_in - t; continue`).
            let h_new = if hid { hh[l] * hidden[l] } else { hh[l] * if okl { ratio_a } else { ratio_r } };
            ln.h[l] = h_new;
            let accepted = okl && !hid;
            acc_ok[l] = accepted;
            let lo = if e <= 0.0 { LN_ERR_FLOOR } else { ln_err[l].max(LN_ERR_FLOOR) };
            ln.ln_err_old[l] = if accepted { lo } else { ln.ln_err_old[l] };
            ln.rejected[l] = if hid { ln.rejected[l] } else { !okl };
            t_new[l] = if last[l] { ln.t_end[l] } else { ln.t[l] + hh[l] };
        }
        for l in 0..N {
            ln.n_acc[l] += acc_ok[l] as u64;
            ln.n_rej[l] += (live[l] && !acc_ok[l]) as u64;
        }

        // ---- which accepted lanes need the cold path ----
        let mut busy = [false; N];
        let mut attn = [false; N];
        for e in 0..ne {
            for l in 0..N {
                busy[l] |= ln.pend[e][l] | cross(ln.g0[e][l], g1[e][l]);
            }
        }
        // A lane busy only with pending events goes to the cold path for `step_events` to read
        // each pending function just after its event and clear it; where the hidden-crossing check
        // built (and counted) the lane's interpolant this step, that reading is done here, on the
        // same coefficients with the same operations (the scalar's bits). Whatever the cold path would decide
        // otherwise (a crossing after the check, a zero or NaN reading, a zero at the step end)
        // still goes there.
        if checks {
            // Lanes the check counted its interpolant for (the cold path reuses it uncounted),
            // busy with no sign change and no zero at the step end.
            let mut cand = [false; N];
            for l in 0..N {
                let mut quiet = true;
                for e in 0..ne {
                    quiet &= !cross(ln.g0[e][l], g1[e][l]) & (g1[e][l] != 0.0);
                }
                cand[l] = busy[l] & acc_ok[l] & need[l] & ok[l] & quiet;
            }
            if cand.iter().any(|&x| x) {
                let span = (&t_start, &t_new, &hh);
                match LAW {
                    SWITCH => pending_on_lanes::<LAW, 6, N>(&mut ln, &full, &cand, &g1, span, &mut busy),
                    TANH => pending_on_lanes::<LAW, 5, N>(&mut ln, &ev5, &cand, &g1, span, &mut busy),
                    _ => pending_on_lanes::<LAW, 3, N>(&mut ln, &ev3, &cand, &g1, span, &mut busy),
                }
            }
        }
        for l in 0..N {
            let mut a = busy[l] | last[l];
            if steady {
                let section = (ln.y[idx::ZD][l] > 0.0) & (yn[idx::ZD][l] <= 0.0);
                let pk = ln.peak[l].max(yn[idx::Z][l].abs());
                let mut rest = true;
                for i in 0..6 {
                    rest &= yn[i][l] == 0.0;
                }
                a |= section | (pk < ln.rest[l]) | rest;
            }
            if sampled {
                a |= t_new[l] >= ln.next_sample[l];
            }
            attn[l] = a & acc_ok[l];
        }
        // A step end where the floor of the step rejects (the scalar driver's check after a
        // rejection): the lane ends with StepTooSmall / NonFinite.
        for l in 0..N {
            if !live[l] || acc_ok[l] || hidden[l] > 0.0 {
                continue;
            }
            let h_new = ln.h[l];
            if h_new.is_nan() || h_new < floor[l] {
                let ordinary = fin[l] && err[l].is_finite();
                let outcome = if ordinary { Outcome::StepTooSmall } else { Outcome::NonFinite };
                let (t, y) = (ln.t[l], lane_state(&ln.y, l));
                finish(&mut ln, l, t, y, h_new, outcome, &mut out);
                refill(&mut ln, l, inp, &mut out);
            }
        }

        // ---- samples at t_eval inside an accepted step with nothing else to do: on the lanes ----
        // The scalar Sampler's rule on the same interpolant formula, so the samples are the bits
        // the cold path would give; steps with an event, a pending event or the run's end take
        // the cold path. DOP853's interpolant needs three more stages: those the hidden-crossing
        // check built this step where it ran (computed for every lane, counted for its own), else
        // built here; a sampled lane that the check did not count counts them now.
        // DOP853's interpolant of every lane, all components, from the extra stages the
        // hidden-crossing check built this step: built at most once per step, for the samples
        // here or the cold path below (which reads only lanes it leaves uncommitted).
        let checked = need.iter().any(|&x| x);
        if sampled {
            let due: [bool; N] =
                std::array::from_fn(|l| acc_ok[l] & !busy[l] & !last[l] & (t_new[l] >= ln.next_sample[l]));
            if due.iter().any(|&d| d) {
                let dense: &LaneDense<6, N> = if M8 {
                    for l in 0..N {
                        ln.n_extra[l] += 3 * (due[l] & !(ok[l] & need[l])) as u64;
                    }
                    if checked {
                        if !full_built {
                            dop853_poly_into(&mut full, &ALL_COMPS, &ln.y, &yn, &ln.f, &hh, &kk, &extra);
                            full_built = true;
                        }
                        &full
                    } else {
                        let mut f = SliderRhs::<UNI, LAW, N> { c: &ln.c, m: &ln.modes, fzl: &mut fzl_scratch };
                        dop853_dense_into(&mut samp, &mut f, &ALL_COMPS, &ln.y, &yn, &ln.f, &hh, &kk, &mut extra);
                        &samp
                    }
                } else {
                    let st = [&ln.f, &k[1], &k[2], &k[3], &k[4], &k[5]];
                    dopri5_dense_into(&mut samp, &ALL_COMPS, &ln.y, &yn, st, &hh);
                    &samp
                };
                let side = &mut ln.side;
                sample_lanes(&due, &mut ln.next_sample, (&t_start, &t_new, &hh), dense, &ln.y, &yn, |l, v| {
                    sampler_push(&mut side[l], v)
                });
                for l in 0..N {
                    attn[l] &= !due[l];
                }
            }
        }

        // ---- the common accepted step: commit on the lanes ----
        // The lanes that commit here (accepted, nothing for the cold path), as bit masks: with
        // `if plain[l] { new } else { old }` LLVM kept the lanes' bools in general registers and
        // committed lane by lane, a branch per lane and component.
        let keep: [u64; N] = std::array::from_fn(|l| ((acc_ok[l] & !attn[l]) as u64).wrapping_neg());
        each6!(i, {
            for l in 0..N {
                ln.y[i][l] = blend(keep[l], yn[i][l], ln.y[i][l]);
                ln.f[i][l] = blend(keep[l], fnew[i][l], ln.f[i][l]);
            }
        });
        for e in 0..ne {
            for l in 0..N {
                ln.g0[e][l] = blend(keep[l], g1[e][l], ln.g0[e][l]);
            }
        }
        for l in 0..N {
            let p = keep[l];
            ln.t[l] = blend(p, t_new[l], ln.t[l]);
            let z = yn[idx::Z][l];
            let normal = if UNI && !ln.modes.contact[l] { 0.0 } else { ln.c.fst[l] + fzl[l] };
            let gap = g1[event::GAP][l];
            let vr = ln.c.v[l] - (yn[idx::XD][l] + ln.c.sl[l] * yn[idx::PHID][l]);
            ln.min_n[l] = blend(p, ln.min_n[l].min(normal), ln.min_n[l]);
            ln.max_gap[l] = blend(p, ln.max_gap[l].max(gap), ln.max_gap[l]);
            ln.min_vr[l] = blend(p, ln.min_vr[l].min(vr), ln.min_vr[l]);
            ln.max_z[l] = blend(p, ln.max_z[l].max(z.abs()), ln.max_z[l]);
        }
        if steady {
            for l in 0..N {
                ln.peak[l] = blend(keep[l], ln.peak[l].max(yn[idx::Z][l].abs()), ln.peak[l]);
            }
            each6!(i, {
                for l in 0..N {
                    ln.peaks[i][l] = blend(keep[l], ln.peaks[i][l].max(yn[i][l].abs()), ln.peaks[i][l]);
                }
            });
        }

        // ---- the cold path: events, observers, the end of a run ----
        if attn.iter().any(|&a| a) {
            // A lane whose extra stages the hidden-crossing check built (and counted) takes its
            // coefficients from `full`, the others from their stages (`Dop853Dense::from_stages`).
            // Under constant friction the two give the same numbers; under the Stribeck laws the
            // lanes' exponential differs from libm's in the last bits, and so do the extra stages:
            // which interpolant a lane's events are located on then depends on whether the check
            // ran for it, on its own values only (not on the batch).
            if M8 && checks && !full_built && (0..N).any(|l| attn[l] && need[l]) {
                dop853_poly_into(&mut full, &ALL_COMPS, &ln.y, &yn, &ln.f, &hh, &kk, &extra);
                full_built = true;
            }
            for l in 0..N {
                if !attn[l] {
                    continue;
                }
                // The common event, on the lane's own values (the cold path's bits).
                if M8 && full_built && need[l] && busy[l] {
                    let span = (t_start[l], t_new[l], hh[l]);
                    match quick_event::<LAW, N>(&mut ln, l, &full, (&yn, fnew, &g1), span, last[l]) {
                        Quick::Cold => {}
                        Quick::Done => continue,
                        Quick::End(t, y, outcome) => {
                            finish(&mut ln, l, t, y, hh[l], outcome, &mut out);
                            refill(&mut ln, l, inp, &mut out);
                            continue;
                        }
                    }
                }
                let y0 = lane_state(&ln.y, l);
                let y1 = lane_state(&yn, l);
                // This lane's stages (DP5 uses the first seven): k1 = f(y0), then the attempt's.
                let k1l = lane_state(&ln.f, l);
                let gather = || -> [State; 13] {
                    std::array::from_fn(|j| match j {
                        0 => k1l,
                        _ if M8 => lane_state(&kk[j], l),
                        _ => lane_state(&k[(j - 1).min(5)], l),
                    })
                };
                let ks: [State; 13];
                let g0: [f64; MAX_EVENTS] = std::array::from_fn(|e| if e < ne { ln.g0[e][l] } else { 0.0 });
                let g1l: [f64; MAX_EVENTS] = std::array::from_fn(|e| if e < ne { g1[e][l] } else { 0.0 });
                let ln_ref = &mut ln;
                let sd = ln_ref.side[l].as_mut().expect("attention only on live lanes");
                sync_to_side(&ln_ref.min_n, &ln_ref.max_gap, &ln_ref.min_vr, &ln_ref.max_z, l, sd);
                if steady {
                    if let Watch::Steady(o, _) = &mut sd.obs.inner {
                        o.w.peak_since = ln_ref.peak[l];
                        o.w.peaks_since = lane_state(&ln_ref.peaks, l);
                    }
                }
                let span = ((t_start[l], &y0), (t_new[l], &y1));
                let ev: StepEnd<6, ContactMode> = if M8 {
                    let dense = match (full_built && need[l]).then_some(&full) {
                        Some(full) => {
                            let c = full.coefficients_of(l).map(State::from);
                            let ends = (k1l, lane_state(fnew, l));
                            Dop853Dense::from_coefficients(sd.s, sd.mode, c, ends, &y0, &y1, t_start[l], hh[l])
                        }
                        None => {
                            ks = gather();
                            Dop853Dense::from_stages(sd.s, sd.mode, &ks, &y0, &y1, t_start[l], hh[l])
                        }
                    };
                    let ev = cold_step(sd, &dense, busy[l], span, ne, &g0, &g1l);
                    sd.stats.n_rhs += dense.extra_rhs();
                    ev
                } else {
                    ks = gather();
                    let k7s: &[State; 7] = ks[..7].try_into().expect("seven stages");
                    let dense = Dopri5Dense::from_stages(k7s, &y0, &y1, t_start[l], hh[l]);
                    cold_step(sd, &dense, busy[l], span, ne, &g0, &g1l)
                };
                sync_from_side(&mut ln, l, steady, sampled);
                if let Some(outcome) = ev.end {
                    finish(&mut ln, l, ev.t1, ev.y1, hh[l], outcome, &mut out);
                    refill(&mut ln, l, inp, &mut out);
                    continue;
                }
                if let Some(sw) = ev.switched {
                    // Restart at the event in the new mode: fresh derivative, fresh event values.
                    let (t, y1, mode) = (ev.t1, ev.y1, ev.new_mode);
                    if !restart(&mut ln, l, t, &y1, mode, sw.index, &sw.pend_before, &sw.t_check) {
                        finish(&mut ln, l, t, y1, hh[l], Outcome::NonFinite, &mut out);
                        refill(&mut ln, l, inp, &mut out);
                    }
                } else {
                    go_on(&mut ln, l, &y1, fnew, &g1, t_new[l]);
                    if last[l] {
                        finish(&mut ln, l, t_new[l], y1, hh[l], Outcome::Finished, &mut out);
                        refill(&mut ln, l, inp, &mut out);
                    }
                }
            }
        }
    }
    (out, Vec::new())
}

/// The cold path's reading of the pending event functions (`step_events`) for the lanes `cand`,
/// on their interpolant `dense` (built this step by the hidden-crossing check: the scalar's
/// coefficients and operations, so the same bits): each pending function read at its check time
/// that is inside the step, nonzero and of the step end's sign is cleared, and the lane is no
/// longer busy. A lane with a reading the cold path would act on (zero, NaN, or a sign change
/// after the check: a crossing to locate) is left as it was, busy.
#[inline(never)]
fn pending_on_lanes<const LAW: u8, const C: usize, const N: usize>(
    ln: &mut Lanes<'_, N>,
    dense: &LaneDense<C, N>,
    cand: &[bool; N],
    g1: &[Lw<N>; NE],
    (t_start, t_new, hh): (&Lw<N>, &Lw<N>, &Lw<N>),
    busy: &mut [bool; N],
) {
    for l in 0..N {
        if !cand[l] {
            continue;
        }
        let (t0, t1) = (t_start[l], t_new[l]);
        let sd = ln.side[l].as_mut().expect("busy only on live lanes");
        let guard = sd.opts.event_guard;
        let mut clear = [false; NE];
        let mut here = true;
        for e in 0..n_events(LAW) {
            if !ln.pend[e][l] {
                continue;
            }
            let tc = (ln.pend_t[e][l] + guard).max(t0 + 1e-6 * (t1 - t0));
            if tc >= t1 {
                continue;
            }
            let gc = events_at::<LAW, N>(&ln.c, &ln.modes, &dense.eval_lane(l, (tc - t0) / hh[l]), l)[e];
            if gc == 0.0 || gc.is_nan() || cross(gc, g1[e][l]) {
                here = false;
                break;
            }
            clear[e] = true;
        }
        if !here {
            continue;
        }
        for e in 0..n_events(LAW) {
            if clear[e] {
                ln.pend[e][l] = false;
                ln.pend_t[e][l] = f64::NAN;
                sd.pend[e] = None;
            }
        }
        busy[l] = false;
    }
}

/// Safety factor of [`near_events`].
const FAR: f64 = 4.0;

/// The lanes whose accepted step may hold a hidden crossing; the others skip the check (and, for
/// DOP853, the three extra stages it needs). A lane skips when, for every event function
/// that is not pending, both ends are more than `FAR` times the step's travel bound
/// `h (|g'(t0)| + |g'(t1)|)` from zero, with the exact derivatives of the event functions at both
/// ends (from the state and its derivative there). A crossing and return inside the step would
/// need the function's slope inside to exceed several times its slopes at both ends: an
/// oscillation of the event function within one step, which an accepted step of an error-controlled
/// method does not hold (steps are a small fraction of the period). When it skips, the check would
/// have found nothing, so the run is the same; on the disk, far from lift-off, it always skips.
///
/// For the near lanes, `turn[e][l]` is the [`turn_point`](crate::ode::events::turn_point) of event function `e` (not pending)
/// inside the step, 0 where it does not turn: the scalar driver checks each one.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn near_events<const LAW: u8, const N: usize>(
    c: &Coef<N>,
    m: &Modes<N>,
    y0: &Vw<N>,
    f0: &Vw<N>,
    y1: &Vw<N>,
    f1: &Vw<N>,
    g0: &[[f64; N]; NE],
    g1: &[[f64; N]; NE],
    pend: &[[bool; N]; NE],
    ok: &[bool; N],
    hh: &[f64; N],
    turn: &mut [Lw<N>; NE],
) -> [bool; N] {
    // d/dt of each event function (`events_lanes`) at both ends, lane-wise (vectorised).
    let (mut d0, mut d1) = ([[0.0; N]; NE], [[0.0; N]; NE]);
    event_rates_lanes::<LAW, N>(c, m, y0, f0, &mut d0);
    event_rates_lanes::<LAW, N>(c, m, y1, f1, &mut d1);
    let mut near = [false; N];
    for l in 0..N {
        let mut clear = true;
        for e in 0..n_events(LAW) {
            let travel = FAR * hh[l] * (d0[e][l].abs() + d1[e][l].abs());
            // NaN anywhere: not far (the check runs).
            clear &= pend[e][l] | ((g0[e][l].abs() > travel) & (g1[e][l].abs() > travel));
        }
        near[l] = !clear & ok[l];
    }
    if !near.iter().any(|&x| x) {
        return near;
    }
    // All lanes at once (branch-free, so that it vectorises), kept for the near lanes only.
    for e in 0..n_events(LAW) {
        for l in 0..N {
            let x = turn_x(g0[e][l], g1[e][l], d0[e][l], d1[e][l], hh[l]);
            let keep = near[l] & !pend[e][l] & !x.is_nan();
            turn[e][l] = blend((keep as u64).wrapping_neg(), x, 0.0);
        }
    }
    near
}

/// Appends a sample to the lane's sampler; returns the time of its next sample (infinity: none).
fn sampler_push(side: &mut Option<Side<'_>>, v: State) -> f64 {
    let Some(sd) = side.as_mut() else { return f64::INFINITY };
    let Watch::Sample(smp) = &mut sd.obs.inner else { return f64::INFINITY };
    smp.out.push(v);
    smp.t_eval.get(smp.out.len()).copied().unwrap_or(f64::INFINITY)
}

/// The scalar driver's handling of one accepted step of one lane: its events (located on the
/// step's interpolant, acted on in time order) or, without any, the observer's look at the step.
#[inline(never)]
fn cold_step<D: StepDense<6>>(
    sd: &mut Side<'_>,
    dense: &D,
    busy: bool,
    ((t0, y0), (t1, y1)): ((f64, &State), (f64, &State)),
    ne: usize,
    g0: &[f64; MAX_EVENTS],
    g1: &[f64; MAX_EVENTS],
) -> StepEnd<6, ContactMode> {
    let mode = sd.mode;
    if busy {
        step_events(
            sd.s,
            &mut sd.obs,
            &sd.opts,
            &mut sd.stats,
            dense,
            mode,
            (t0, y0),
            (t1, y1),
            ne,
            g0,
            g1,
            &mut sd.pend,
        )
    } else {
        let view = StepView { t0, t1, y0, y1, mode, dense };
        let end = if sd.obs.on_step(&view) == Control::Stop { Some(Outcome::StoppedByObserver) } else { None };
        StepEnd { t1, y1: *y1, new_mode: mode, end, switched: None }
    }
}
