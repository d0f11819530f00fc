//! Lane-batched Dormand–Prince 5(4) and DOP853 for the bilateral, constant-`mu` slider: the fast
//! path of ensembles that only need the end state.
//!
//! [`run_bilateral_batch`] integrates many trajectories at once, `N` lanes at a time in
//! structure-of-arrays form (`[f64; N]` per state component and per parameter), so that the
//! stage arithmetic of `N` trajectories runs in SIMD registers (plain loops over the lanes that
//! LLVM vectorises; on x86-64 a copy compiled for AVX2/AVX-512 is picked at run time, std only).
//! `N` is 8, or 16 in the AVX-512 copy ([`W_AVX512`]).
//! Each lane has its own time, step size, error estimate, controller history and accept/reject
//! decision; when a lane's trajectory ends the lane is refilled at once with the next trajectory of
//! the input, so no lane idles while others run long.
//!
//! # Semantics (those of `steady::run(s, y0, t_end, method, tol)`, to integration accuracy)
//! - Same tolerances (`atol` per component from [`characteristic_sizes`] when `tol.atol` is
//!   `None`), same error norm (Hairer's RMS; DOP853's combined 5th/3rd-order one), same PI
//!   controller (`beta = 0.04`, safety 0.9,
//!   factors in `[0.2, 10]`, no growth right after a rejection), same starting step (the scalar
//!   [`initial_step`] on the same right-hand side, so the first step is bitwise the scalar one), same
//!   landing rule on `t_end` (the last step is stretched by up to 1 %), same step floor
//!   (`h_min_rel * max(|t|, 1)`) and step budget ([`Options::new`] defaults).
//! - The right-hand side is the slider's in contact mode, with the dynamic law force used directly
//!   instead of `(F_st + F_z) - F_st`, so states agree with the scalar path to rounding per step,
//!   not bitwise; step counts agree to a few per cent (they are identical on most trajectories).
//! - **Only the escape is located.** The bilateral constant-`mu` model never switches mode, so only
//!   the escape event matters: when `|z| >= escape_limit` at the end of an accepted step, the
//!   crossing is located on the step's interpolant as the scalar path's event is (`events::locate` to
//!   `event_tol`, the far side of the crossing) and the lane stops there with `Status::Diverged`.
//!   `Stats::n_events` is 0 (the scalar path counts the located, non-acting gap, normal-force and
//!   slip crossings too). A run that starts at `|z| >= escape_limit` stops after its first step.
//! - [`Extremes`] are updated at the initial state and at every accepted step end (the scalar path
//!   also sees the located event points, where `max_gap` and `min_slip_velocity` can differ by the
//!   interpolation between a step end and the crossing; this path only sees step ends).
//! - Failures: non-finite state or derivative (after cutting the step to the floor) ->
//!   `NonFinite`, a step below the floor -> `StepTooSmall`, the step budget -> `MaxSteps`, as in
//!   the scalar driver, each with the same [`Failure`] (its reason).
//! - Cancellation ([`crate::cancel`]): looked at every [`cancel::CHECK_EVERY`] steps of the lanes;
//!   the running trajectories end with `NotComputed` (`Failure::Cancelled`), the others are not
//!   started (`Failure::NotStarted`).
//!
//! # Determinism
//! Every lane's arithmetic is the same sequence of IEEE operations on that lane's values only
//! (masks only select; no reduction across lanes, no fused multiply-add), and lane set-up and
//! teardown are scalar code on one trajectory. The result for a trajectory is therefore bitwise
//! the same whatever trajectories share its batch, in whatever order, on whatever thread count
//! (tested), and on any x86-64 code path (the AVX copies only widen the same operations).

// Index loops over lanes and components are the point here: they are what LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::lanes::Coef;
use crate::cancel;
use crate::model::{idx, ContactMode, ContactModel, FrictionLaw, Slider, State};
use crate::ode::controller::{initial_step, FAC_MAX, FAC_MIN, SAFETY};
use crate::ode::dop853::Dop853Dense;
use crate::ode::dopri5::Dopri5Dense;
use crate::ode::events::locate;
use crate::ode::lanes::{
    dop853_dense_into, dop853_step, dopri5_dense_into, dopri5_step, each6, exp_lanes, lane_state, ln_lanes,
    sample_lanes, splat, Al, LaneDense, LaneRhs, Lw, Row, Vw, ALL_COMPS, ALPHA, ALPHA8, BETA, LN_ERR_FLOOR, LN_SAFETY,
    W,
};
use crate::ode::stepper::StepDense;
use crate::ode::{Dense, Method, Options, SampleStore, Stats};
use crate::status::{Failure, Status};
use crate::steady::{characteristic_sizes, options_for, run_failure, Extremes, RunResult, Tolerances};

/// The state of the `N` lanes (state and stage first, on 64-byte boundaries, as `Al`).
#[repr(C, align(64))]
struct Lanes<const N: usize> {
    y: Vw<N>,
    /// f(t, y): the FSAL stage.
    f: Vw<N>,
    c: Coef<N>,
    t: Lw<N>,
    h: Lw<N>,
    ln_err_old: Lw<N>,
    rejected: [bool; N],
    n_acc: [u64; N],
    n_rej: [u64; N],
    /// Right-hand sides of DOP853 interpolants built to locate an escape.
    n_extra: [u64; N],
    min_n: Lw<N>,
    max_gap: Lw<N>,
    min_vr: Lw<N>,
    max_z: Lw<N>,
    /// Input index of each lane's trajectory (`usize::MAX`: idle).
    who: [usize; N],
}

/// Right-hand side of the `N` lanes, and the dynamic law force `F_z` of each.
#[inline(always)]
fn rhs<const N: usize>(c: &Coef<N>, y: &Vw<N>, out: &mut Vw<N>, fz: &mut Lw<N>) {
    for l in 0..N {
        let (z, zd, x, xd, ph, phd) = (y[0][l], y[1][l], y[2][l], y[3][l], y[4][l], y[5][l]);
        let f = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
        let fx = c.mu[l] * f;
        out[0][l] = zd;
        out[1][l] = f * c.inv_m[l] - c.dz[l] * zd - c.wz2[l] * z;
        out[2][l] = xd;
        out[3][l] = fx * c.inv_m[l] - c.dx[l] * xd - c.wx2[l] * x;
        out[4][l] = phd;
        out[5][l] = c.tg[l] * fx - c.dt[l] * phd - c.wt2[l] * ph;
        fz[l] = f;
    }
}

/// [`rhs`] as the lane kit's [`LaneRhs`]: the law force of the last evaluation is left in `fz`.
struct BatchRhs<'a, const N: usize> {
    c: &'a Coef<N>,
    fz: &'a mut Lw<N>,
}

impl<const N: usize> LaneRhs<N> for BatchRhs<'_, N> {
    #[inline(always)]
    fn eval(&mut self, y: &Vw<N>, out: &mut Vw<N>) {
        rhs(self.c, y, out, self.fz);
    }
}

/// Integrate each `sliders[i]` from `y0s[i]` at `t = 0` to `t_end` with `method` (Dormand–Prince
/// 5(4) or DOP853), `N` trajectories at a time; the result for each trajectory, in input order.
///
/// Precondition (the caller checks): every slider has `ContactModel::Bilateral` and
/// `FrictionLaw::Constant`; [`supports_method`] accepts `method`; `sliders.len() == y0s.len()`.
/// Panics otherwise. See the module documentation for how the results relate to
/// `steady::run(s, y0, t_end, method, tol)`.
pub fn run_bilateral_batch(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
) -> Vec<RunResult> {
    run_bilateral_batch_sampled(sliders, y0s, t_end, method, tol, &[]).into_iter().map(|(r, _)| r).collect()
}

/// [`run_bilateral_batch`] with the states at the times `t_eval` (sorted, in `[0, t_end]`) of each
/// trajectory, by the scalar `Sampler`'s rule on each accepted step: a time at or before the step's
/// start takes the start, the step end's time the end, any other the step's interpolant (DP5's
/// from its stages; DOP853's needs three more right-hand sides per sampled step, counted). A run
/// that escapes has the samples up to the located crossing, then NaN (as `steady::run_sampled`).
pub fn run_bilateral_batch_sampled(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    t_eval: &[f64],
) -> Vec<(RunResult, Vec<State>)> {
    let nt = t_eval.len();
    let mut flat = vec![0.0; sliders.len() * nt * 6];
    let runs = run_bilateral_batch_into(sliders, y0s, t_end, method, tol, t_eval, &mut flat);
    let samples = flat.chunks_exact(6 * nt.max(1)).map(states_of).chain(std::iter::repeat(Vec::new()));
    runs.into_iter().zip(samples).collect()
}

/// The states of a row of samples (6 values each).
pub(crate) fn states_of(row: &[f64]) -> Vec<State> {
    row.chunks_exact(6).map(State::from_column_slice).collect()
}

/// [`run_bilateral_batch_sampled`] writing the samples into `out`, a row of `6 t_eval.len()`
/// values per trajectory (state by state): the samples the run reached, NaN after them.
pub fn run_bilateral_batch_into(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    t_eval: &[f64],
    out: &mut [f64],
) -> Vec<RunResult> {
    assert_eq!(sliders.len(), y0s.len(), "run_bilateral_batch: one initial state per slider");
    assert!(supports_method(method), "run_bilateral_batch: method {method:?} is not batched");
    assert_eq!(out.len(), sliders.len() * t_eval.len() * 6, "run_bilateral_batch: one row of samples per slider");
    for s in sliders {
        assert!(
            s.p.contact == ContactModel::Bilateral && s.p.friction_law == FrictionLaw::Constant,
            "run_bilateral_batch: only bilateral contact with constant friction"
        );
    }
    let mut counts = vec![0usize; if t_eval.is_empty() { 0 } else { sliders.len() }];
    let job = Job { sliders, y0s, t_end, tol, t_eval, samples: out, counts: &mut counts };
    let runs = if method == Method::Dop853 { dispatch::<true>(job) } else { dispatch::<false>(job) };
    // As the scalar `run_sampled`: a run that stopped early has NaN at the times it did not reach.
    let stride = 6 * t_eval.len();
    for (i, &k) in counts.iter().enumerate() {
        out[i * stride + 6 * k..(i + 1) * stride].fill(f64::NAN);
    }
    runs
}

/// Whether [`run_bilateral_batch`] integrates with this method.
pub fn supports_method(m: Method) -> bool {
    matches!(m, Method::Dopri5 | Method::Dop853)
}

/// One call's trajectories, horizon, tolerances and samples requested: the times and, per
/// trajectory, the states (empty `t_eval`: the end state only).
struct Job<'a> {
    sliders: &'a [Slider],
    y0s: &'a [State],
    t_end: f64,
    tol: &'a Tolerances,
    t_eval: &'a [f64],
    /// A row of `6 t_eval.len()` values per trajectory, and the samples written to each.
    samples: &'a mut [f64],
    counts: &'a mut [usize],
}

/// The lanes of the copy [`dispatch`] picks on this CPU: [`W_AVX512`] with AVX-512, else [`W`].
pub fn lane_count() -> usize {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx512f") {
        return W_AVX512;
    }
    W
}

fn dispatch<const M8: bool>(job: Job<'_>) -> Vec<RunResult> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { run_avx512::<M8, W_AVX512>(job) };
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { run_avx2::<M8>(job) };
        }
    }
    run_impl::<M8, W>(job)
}

/// Lanes of the AVX-512 copy: two registers per operation, so that two independent chains of a
/// stage's arithmetic overlap (a stage waits on the one before: at 8 lanes the step is partly
/// latency-bound). Measured against 8 lanes on the issue-2 ensemble (Zen 4, one thread, 4,000
/// trajectories, builds alternating): the DOP853 end state 28-31k -> 42.5k trajectories/s at rtol
/// 1e-6 and 13.4-13.7k -> 18-18.7k at 1e-9, DP5 19-20k -> 22-23.5k; with 501 samples DP5 16.3k ->
/// 20.4k. DOP853 with many samples ran 8 lanes until its interpolant's rows stayed in registers
/// and the samples were taken on all lanes at once (`lanes::sample_lanes`); since then 16 lanes
/// win at any number of samples (Zen 5, 1,000 trajectories, rtol 1e-6): 21 samples 34.5k ->
/// 50k, 501 samples 27k -> 36k, 2,001 samples 20k -> 25k.
pub const W_AVX512: usize = 16;

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn run_avx512<const M8: bool, const N: usize>(job: Job<'_>) -> Vec<RunResult> {
    run_impl::<M8, N>(job)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<const M8: bool>(job: Job<'_>) -> Vec<RunResult> {
    run_impl::<M8, W>(job)
}

/// The portable path (also used by the tests to check that the SIMD copies agree bitwise).
/// `M8`: DOP853, else Dormand–Prince 5(4).
#[inline(always)]
fn run_impl<const M8: bool, const N: usize>(job: Job<'_>) -> Vec<RunResult> {
    let Job { sliders, y0s, t_end, tol, t_eval, samples, counts } = job;
    let stride = 6 * t_eval.len();
    let n = sliders.len();
    let sampled = !t_eval.is_empty();
    let first_sample = t_eval.first().copied().unwrap_or(f64::INFINITY);
    // Per lane: the time of its trajectory's next sample (its index is the length of the
    // trajectory's samples so far).
    let mut next_t = [first_sample; N];
    let opts = Options::<6>::new(tol.rtol, 1.0);
    let rtol = tol.rtol;
    let max_steps = opts.max_steps;
    let event_tol = opts.event_tol;
    let h_min_rel = opts.h_min_rel;
    let mut out: Vec<Option<RunResult>> = vec![None; n];
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
        min_n: zero,
        max_gap: zero,
        min_vr: zero,
        max_z: zero,
        who: [usize::MAX; N],
    };
    let mut next = 0usize;
    for l in 0..N {
        refill(&mut ln, l, &mut next, sliders, y0s, t_end, tol, M8, &mut out);
    }
    let end = End { sliders, t_end, opts: &opts, m8: M8 };
    let mut rounds = 0u64;

    // Scratch of the step: DP5's stages k2..k7, DOP853's (see `ode::lanes::dop853_step`), the new state.
    // The stages on 64-byte boundaries (`Al`).
    let mut k = Al([[zero; 6]; 6]);
    let mut kk = Al([[zero; 6]; 16]);
    let mut yn = Al([zero; 6]);
    let mut fz = zero;
    let mut fz_scratch = zero;
    let mut extra = Al([[zero; 6]; 3]);
    let mut dense = LaneDense::<6, N>::new();

    while ln.who.iter().any(|&w| w != usize::MAX) {
        rounds += 1;
        if cancel::requested_every(rounds) {
            stop_all(&mut ln, &end, &mut out);
            break;
        }
        // ---- before the attempt: landing on t_end, the step floor, the step budget ----
        let mut hh = zero;
        let mut last = [false; N];
        let mut floor = zero;
        let mut bad = false;
        for l in 0..N {
            let h = ln.h[l];
            let rem = t_end - ln.t[l];
            let la = h >= rem || 1.01 * h >= rem;
            last[l] = la;
            hh[l] = if la { rem } else { h };
            floor[l] = h_min_rel * ln.t[l].abs().max(1.0);
            let too_small = (hh[l].is_nan() || hh[l] < floor[l]) && !la;
            bad |= ln.who[l] != usize::MAX && (too_small || ln.n_acc[l] + ln.n_rej[l] >= max_steps);
        }
        if bad {
            for l in 0..N {
                if ln.who[l] == usize::MAX {
                    continue;
                }
                let too_small = (hh[l].is_nan() || hh[l] < floor[l]) && !last[l];
                let status = if too_small {
                    if hh[l].is_finite() {
                        Status::StepTooSmall
                    } else {
                        Status::NonFinite
                    }
                } else if ln.n_acc[l] + ln.n_rej[l] >= max_steps {
                    Status::MaxSteps
                } else {
                    continue;
                };
                finish(&mut ln, l, status, hh[l], &end, &mut out);
                refill(&mut ln, l, &mut next, sliders, y0s, t_end, tol, M8, &mut out);
                next_t[l] = first_sample;
            }
            continue;
        }

        // ---- the step: six (DOP853: twelve) new right-hand sides per lane, the error norm and
        // finiteness ----
        let c = &ln.c;
        let y = &ln.y;
        let k1 = &ln.f;
        // DP5: the squared RMS norm (`err <= 1` iff `err^2 <= 1`, and ln err = ln(err^2) / 2, so
        // no square root is needed); DOP853: Hairer's combined norm.
        let (err, fin) = if M8 {
            dop853_step(&mut BatchRhs { c, fz: &mut fz }, y, k1, &hh, rtol, &c.atol, &mut kk, &mut yn)
        } else {
            dopri5_step(&mut BatchRhs { c, fz: &mut fz }, y, k1, &hh, rtol, &c.atol, &mut k, &mut yn)
        };
        let fnew: &Vw<N> = if M8 { &kk[12] } else { &k[5] };

        // ---- accept or reject, the controller, extremes, the end tests (branch-free) ----
        let mut ok = [false; N];
        let mut lnx = zero;
        for l in 0..N {
            ok[l] = err[l] <= 1.0 && fin[l];
            // ln of the error, floored far below anything that matters (a zero or subnormal error
            // gives the largest growth either way); non-finite errors are not used below.
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
            // One exp per lane: the accept factor err^-alpha err_old^beta / safety, or the reject
            // factor err^-alpha (times safety), as in `Controller::accept` / `Controller::reject`.
            arg[l] =
                if ok[l] { -(alpha * ln_err[l] - BETA * ln.ln_err_old[l] - LN_SAFETY) } else { -alpha * ln_err[l] };
        }
        let r = exp_lanes(&arg);
        // Kept as several simple loops over the lanes: each vectorises on its own.
        let t_start = ln.t;
        let mut ended = [false; N];
        for l in 0..N {
            let ok = ok[l];
            let e = err[l];
            // Accepted: the PI ratio, no growth right after a rejection.
            let ra = if e <= 0.0 { FAC_MAX } else { r[l].clamp(FAC_MIN, FAC_MAX) };
            let ratio_a = if ln.rejected[l] { ra.min(1.0) } else { ra };
            // Rejected: an ordinary rejection or, for anything non-finite, the largest cut.
            let ordinary = e.is_finite() && fin[l];
            let ratio_r = if ordinary { (SAFETY * r[l]).clamp(FAC_MIN, 1.0) } else { FAC_MIN };
            let h_new = hh[l] * if ok { ratio_a } else { ratio_r };
            ln.h[l] = h_new;
            let lo = if e <= 0.0 { LN_ERR_FLOOR } else { ln_err[l].max(LN_ERR_FLOOR) };
            ln.ln_err_old[l] = if ok { lo } else { ln.ln_err_old[l] };
            ln.rejected[l] = !ok;
            let t_new = if last[l] { t_end } else { ln.t[l] + hh[l] };
            ln.t[l] = if ok { t_new } else { ln.t[l] };
            let z = yn[idx::Z][l].abs();
            let end_a = last[l] || z >= c.esc[l];
            let end_r = h_new.is_nan() || h_new < floor[l];
            ended[l] = if ok { end_a } else { end_r };
        }
        // ---- samples: the interpolant of the step, built when some accepted lane passes its next
        // sample time (before an escape cuts the step: the crossing is located on it) ----
        let due: [bool; N] =
            std::array::from_fn(|l| sampled & ok[l] & (ln.who[l] != usize::MAX) & (ln.t[l] >= next_t[l]));
        // Built into one buffer kept across steps (an interpolant built and moved per step cost
        // a tenth of a sampled run in copies and zeroing).
        let have_dense = due.iter().any(|&d| d);
        if have_dense {
            if M8 {
                for l in 0..N {
                    ln.n_extra[l] += 3 * due[l] as u64;
                }
                let f = &mut BatchRhs { c, fz: &mut fz_scratch };
                dop853_dense_into(&mut dense, f, &ALL_COMPS, y, &yn, k1, &hh, &kk, &mut extra);
            } else {
                dopri5_dense_into(&mut dense, &ALL_COMPS, y, &yn, [k1, &k[1], &k[2], &k[3], &k[4], &k[5]], &hh);
            }
        }

        // Off the common path: only when some lane ends this step.
        let attention = ended.iter().fold(false, |a, &b| a | b);
        if attention && (0..N).any(|l| ok[l] && ended[l] && yn[idx::Z][l].abs() >= c.esc[l]) {
            let step = Step { t0: &t_start, h: &hh, ok: &ok };
            let stages: [&Vw<N>; 13] = if M8 {
                std::array::from_fn(|j| if j == 0 { &ln.f } else { &kk[j] })
            } else {
                std::array::from_fn(|j| if j == 0 { &ln.f } else { &k[(j - 1).min(5)] })
            };
            let esc = Escapes { c, who: &ln.who, y: &ln.y, stages: &stages, step: &step, sliders, event_tol, m8: M8 };
            locate_escapes(&esc, &mut yn, &mut fz, &mut ln.t, &mut ln.n_extra);
        }
        if have_dense {
            // The step as it ends (an escape ends it at the crossing).
            let span = (&t_start, &ln.t, &hh);
            let who = &ln.who;
            sample_lanes(&due, &mut next_t, span, &dense, &ln.y, &yn, |l, v| {
                let w = who[l];
                let mut row = Row { vals: &mut samples[w * stride..(w + 1) * stride], n: counts[w] };
                row.push(v);
                counts[w] = row.n;
                t_eval.get(row.n).copied().unwrap_or(f64::INFINITY)
            });
        }
        for l in 0..N {
            ln.n_acc[l] += ok[l] as u64;
            ln.n_rej[l] += (!ok[l]) as u64;
        }
        each6!(i, {
            for l in 0..N {
                ln.y[i][l] = if ok[l] { yn[i][l] } else { ln.y[i][l] };
                ln.f[i][l] = if ok[l] { fnew[i][l] } else { ln.f[i][l] };
            }
        });
        for l in 0..N {
            let ok = ok[l];
            let z = yn[idx::Z][l];
            let normal = c.fst[l] + fz[l];
            let gap = c.zst[l] + z;
            let vr = c.v[l] - (yn[idx::XD][l] + c.sl[l] * yn[idx::PHID][l]);
            ln.min_n[l] = if ok { ln.min_n[l].min(normal) } else { ln.min_n[l] };
            ln.max_gap[l] = if ok { ln.max_gap[l].max(gap) } else { ln.max_gap[l] };
            ln.min_vr[l] = if ok { ln.min_vr[l].min(vr) } else { ln.min_vr[l] };
            ln.max_z[l] = if ok { ln.max_z[l].max(z.abs()) } else { ln.max_z[l] };
        }
        if attention {
            for l in 0..N {
                if !ended[l] || ln.who[l] == usize::MAX {
                    continue;
                }
                let status = if ln.rejected[l] {
                    let ordinary = fin[l] && err[l].is_finite();
                    if ordinary {
                        Status::StepTooSmall
                    } else {
                        Status::NonFinite
                    }
                } else if ln.y[idx::Z][l].abs() >= ln.c.esc[l] {
                    Status::Diverged
                } else {
                    Status::Success
                };
                // After a rejection the step that fell below the floor is the new one.
                let h = if ln.rejected[l] { ln.h[l] } else { hh[l] };
                finish(&mut ln, l, status, h, &end, &mut out);
                refill(&mut ln, l, &mut next, sliders, y0s, t_end, tol, M8, &mut out);
                next_t[l] = first_sample;
            }
        }
    }
    // Only a cancelled call leaves trajectories without a result.
    out.into_iter()
        .map(|r| r.unwrap_or_else(|| RunResult::failed(Status::NotComputed, Some(Failure::NotStarted))))
        .collect()
}

/// The caller cancelled: every running lane ends where it is (`NotComputed`).
#[cold]
#[inline(never)]
fn stop_all<const N: usize>(ln: &mut Lanes<N>, end: &End<'_>, out: &mut [Option<RunResult>]) {
    for l in 0..N {
        if ln.who[l] != usize::MAX {
            let h = ln.h[l];
            finish(ln, l, Status::NotComputed, h, end, out);
        }
    }
}

/// What [`finish`] needs to say why a run failed and count its work.
struct End<'a> {
    sliders: &'a [Slider],
    t_end: f64,
    opts: &'a Options<6>,
    /// DOP853 (else DP5).
    m8: bool,
}

/// Lanes whose accepted step ends at `|z| >= escape_limit`: locate the crossing on the step's
/// interpolant, as the scalar path's escape event does (`events::locate` to `event_tol`, the time on the
/// far side of the crossing), and make the lane's step end there: `yn`, the contact force `fz`
/// and `t` of those lanes are replaced, so that the state, the extremes and the time reported are
/// the located ones. Called before the lane state is overwritten (`ln.y`, `ln.f` still hold the
/// step's start and first stage). Cold: diverging runs are rare.
/// The attempted step of every lane: start times, step sizes, accepted or not.
struct Step<'a, const N: usize> {
    t0: &'a Lw<N>,
    h: &'a Lw<N>,
    ok: &'a [bool; N],
}

/// One batch step's lanes, for [`locate_escapes`]: the stages (DP5: `k1..k7` in the first seven,
/// DOP853: `k1..k13`), the step, the method.
struct Escapes<'a, const N: usize> {
    c: &'a Coef<N>,
    who: &'a [usize; N],
    y: &'a Vw<N>,
    stages: &'a [&'a Vw<N>; 13],
    step: &'a Step<'a, N>,
    sliders: &'a [Slider],
    event_tol: f64,
    m8: bool,
}

#[cold]
#[inline(never)]
fn locate_escapes<const N: usize>(
    e: &Escapes<'_, N>,
    yn: &mut Vw<N>,
    fz: &mut Lw<N>,
    t: &mut Lw<N>,
    n_extra: &mut [u64; N],
) {
    let c = e.c;
    for l in 0..N {
        if e.who[l] == usize::MAX || !e.step.ok[l] || yn[idx::Z][l].abs() < c.esc[l] {
            continue;
        }
        let esc = c.esc[l];
        let s = &e.sliders[e.who[l]];
        let k: [State; 13] = std::array::from_fn(|j| lane_state(e.stages[j], l));
        let (y0, y1) = (lane_state(e.y, l), lane_state(yn, l));
        // `t` already holds the accepted step's end.
        let (t0, t1) = (e.step.t0[l], t[l]);
        let (g0, g1) = (esc - y0[idx::Z].abs(), esc - y1[idx::Z].abs());
        let at = |dense: &dyn Dense<6>| {
            let g = |tt: f64| esc - dense.eval(tt)[idx::Z].abs();
            let te = if g0 > 0.0 { locate(g, t0, g0, t1, g1, e.event_tol) } else { t1 };
            (te, if te == t1 { y1 } else { dense.eval(te) })
        };
        let (te, ye) = if e.m8 {
            let dense = Dop853Dense::from_stages(s, ContactMode::Contact, &k, &y0, &y1, t0, e.step.h[l]);
            let r = at(&dense);
            n_extra[l] += dense.extra_rhs();
            r
        } else {
            let k7: &[State; 7] = k[..7].try_into().expect("seven stages");
            at(&Dopri5Dense::from_stages(k7, &y0, &y1, t0, e.step.h[l]))
        };
        for i in 0..6 {
            yn[i][l] = ye[i];
        }
        fz[l] = s.forces(&ye, ContactMode::Contact).normal - c.fst[l];
        t[l] = te;
    }
}

/// Write lane `l`'s result (ended with `status`, step size `h`) and mark it idle.
#[cold]
fn finish<const N: usize>(
    ln: &mut Lanes<N>,
    l: usize,
    status: Status,
    h: f64,
    end: &End<'_>,
    out: &mut [Option<RunResult>],
) {
    let i = ln.who[l];
    let steps = ln.n_acc[l] + ln.n_rej[l];
    let (t, y) = (ln.t[l], lane_state(&ln.y, l));
    let failure = run_failure(status, &end.sliders[i], t, &y, h, steps, end.t_end, end.opts);
    let work = if end.m8 { 11 * steps + ln.n_acc[l] + ln.n_extra[l] } else { 6 * steps };
    out[i] = Some(RunResult {
        status,
        t,
        y,
        extremes: Extremes {
            min_normal_force: ln.min_n[l],
            max_gap: ln.max_gap[l],
            min_slip_velocity: ln.min_vr[l],
            max_abs_z: ln.max_z[l],
        },
        // DP5: six new stages per attempt (FSAL); DOP853: eleven per attempt and the derivative at
        // each accepted step's end, and any interpolant's extra stages; both: the start's two.
        stats: Stats { n_rhs: 2 + work, n_accept: ln.n_acc[l], n_reject: ln.n_rej[l], ..Stats::default() },
        failure,
    });
    ln.who[l] = usize::MAX;
}

/// Load the next trajectory that needs a step into lane `l` (trajectories that end before their
/// first step get their result here); leave the lane idle (harmless values) when none is left.
#[cold]
#[allow(clippy::too_many_arguments)]
fn refill<const N: usize>(
    ln: &mut Lanes<N>,
    l: usize,
    next: &mut usize,
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
    m8: bool,
    out: &mut [Option<RunResult>],
) {
    while *next < sliders.len() {
        let i = *next;
        *next += 1;
        let s = &sliders[i];
        let y0 = y0s[i];
        let mut ext = Extremes::default();
        let f = s.forces(&y0, ContactMode::Contact);
        ext.min_normal_force = f.normal;
        ext.max_gap = s.gap(&y0);
        ext.min_slip_velocity = f.slip_velocity;
        ext.max_abs_z = y0[idx::Z].abs();
        let opts = options_for(s, tol);
        let early = |status, n_rhs| RunResult {
            status,
            t: 0.0,
            y: y0,
            extremes: ext,
            stats: Stats { n_rhs, ..Stats::default() },
            failure: run_failure(status, s, 0.0, &y0, f64::NAN, 0, t_end, &opts),
        };
        if !t_end.is_finite() || !y0.iter().all(|v| v.is_finite()) {
            out[i] = Some(early(Status::NonFinite, 0));
            continue;
        }
        if t_end < 0.0 {
            out[i] = Some(early(Status::StepTooSmall, 0));
            continue;
        }
        if t_end == 0.0 {
            out[i] = Some(early(Status::Success, 0));
            continue;
        }
        let f0 = s.rhs(&y0, ContactMode::Contact);
        if !f0.iter().all(|v| v.is_finite()) {
            out[i] = Some(early(Status::NonFinite, 1));
            continue;
        }
        let mut n_rhs = 1;
        let h0 = initial_step(
            s,
            ContactMode::Contact,
            0.0,
            &y0,
            &f0,
            t_end,
            if m8 { 8 } else { 5 },
            &opts.atol,
            tol.rtol,
            f64::INFINITY,
            &mut n_rhs,
        );
        let atol = tol.atol.unwrap_or(characteristic_sizes(s).map(|v| v * tol.rtol));
        ln.c.set(l, s, &atol);
        for k in 0..6 {
            ln.y[k][l] = y0[k];
            ln.f[k][l] = f0[k];
        }
        ln.t[l] = 0.0;
        ln.h[l] = h0;
        ln.ln_err_old[l] = LN_ERR_FLOOR;
        ln.rejected[l] = false;
        ln.n_acc[l] = 0;
        ln.n_rej[l] = 0;
        ln.n_extra[l] = 0;
        ln.min_n[l] = ext.min_normal_force;
        ln.max_gap[l] = ext.max_gap;
        ln.min_vr[l] = ext.min_slip_velocity;
        ln.max_z[l] = ext.max_abs_z;
        ln.who[l] = i;
        return;
    }
    // Idle: a state at rest far from any end condition, so the lane computes harmless numbers.
    for k in 0..6 {
        ln.y[k][l] = 0.0;
        ln.f[k][l] = 0.0;
    }
    ln.t[l] = 0.0;
    ln.h[l] = 0.0;
    ln.c.esc[l] = f64::INFINITY;
    ln.who[l] = usize::MAX;
}

#[cfg(test)]
mod tests;
