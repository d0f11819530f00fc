//! Lane-batched Dormand–Prince 5(4) for the bilateral, constant-`mu` slider: the fast path of
//! ensembles that only need the end state.
//!
//! [`run_bilateral_batch`] integrates many trajectories at once, [`W`] = 8 at a time in
//! structure-of-arrays form (`[f64; 8]` per state component and per parameter), so that the
//! stage arithmetic of eight trajectories runs in SIMD registers (plain loops over the lanes that
//! LLVM vectorises; on x86-64 a copy compiled for AVX2/AVX-512 is picked at run time, std only).
//! Each lane has its own time, step size, error estimate, controller history and accept/reject
//! decision; when a lane's trajectory ends the lane is refilled at once with the next trajectory of
//! the input, so no lane idles while others run long.
//!
//! # Semantics (those of `steady::run(s, y0, t_end, Method::Dopri5, tol)`, to integration accuracy)
//! - Same tolerances (`atol` per component from [`characteristic_sizes`] when `tol.atol` is
//!   `None`), same error norm (Hairer's RMS), same PI controller (`beta = 0.04`, safety 0.9,
//!   factors in `[0.2, 10]`, no growth right after a rejection), same starting step (the scalar
//!   [`initial_step`] on the same right-hand side, so the first step is bitwise the scalar one), same
//!   landing rule on `t_end` (the last step is stretched by up to 1 %), same step floor
//!   (`h_min_rel * max(|t|, 1)`) and step budget ([`Options::new`] defaults).
//! - The right-hand side is the slider's in contact mode, with the dynamic law force used directly
//!   instead of `(F_st + F_z) - F_st`, so states agree with the scalar path to rounding per step,
//!   not bitwise; step counts agree to a few per cent (they are identical on most trajectories).
//! - **Only the escape is located.** The bilateral constant-`mu` model never switches mode, so only
//!   the escape event matters: when `|z| >= escape_limit` at the end of an accepted step, the
//!   crossing is located on the step's interpolant as the scalar path's event is (Illinois to
//!   `event_tol`, the far side of the crossing) and the lane stops there with `Status::Diverged`.
//!   `Stats::n_events` is 0 (the scalar path counts the located, non-acting gap, normal-force and
//!   slip crossings too). A run that starts at `|z| >= escape_limit` stops after its first step.
//! - [`Extremes`] are updated at the initial state and at every accepted step end (the scalar path
//!   also sees the located event points, where `max_gap` and `min_slip_velocity` can differ by the
//!   interpolation between a step end and the crossing; this path only sees step ends).
//! - Failures: non-finite state or derivative (after cutting the step to the floor) ->
//!   `NonFinite`, a step below the floor -> `StepTooSmall`, the step budget -> `MaxSteps`, as in
//!   the scalar driver.
//!
//! # Determinism
//! Every lane's arithmetic is the same sequence of IEEE operations on that lane's values only
//! (masks only select; no reduction across lanes, no fused multiply-add), and lane set-up and
//! teardown are scalar code on one trajectory. The result for a trajectory is therefore bitwise
//! the same whatever trajectories share its batch, in whatever order, on whatever thread count
//! (tested), and on any x86-64 code path (the AVX copies only widen the same operations).

// Index loops over lanes and components are the point here: they are what LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::controller::{initial_step, FAC_MAX, FAC_MIN, SAFETY};
use super::dopri5::Dopri5Dense;
use super::driver::locate;
use super::lanes::Coef;
use super::{Dense, Options, Stats};
use crate::model::{idx, ContactMode, ContactModel, FrictionLaw, Slider, State};
use crate::status::Status;
use crate::steady::{characteristic_sizes, options_for, Extremes, RunResult, Tolerances};

/// Trajectories per batch (SIMD lanes).
pub const W: usize = 8;
pub(crate) type L = [f64; W];
pub(crate) type V6 = [L; 6];

// Dormand–Prince 5(4) coefficients: the scalar stepper's, one table for both paths.
use super::dopri5::{
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, B1, B3, B4, B5, B6, E1, E3, E4, E5, E6,
    E7,
};

// The PI controller of `controller.rs` for DOPRI5 (k = 5, beta = 0.04).
pub(crate) const BETA: f64 = 0.04;
pub(crate) const ALPHA: f64 = 1.0 / 5.0 - 0.75 * BETA;
pub(crate) const LN_SAFETY: f64 = -0.105_360_515_657_826_3;
pub(crate) const LN_ERR_FLOOR: f64 = -9.210_340_371_976_184;

/// The state of the eight lanes.
struct Lanes {
    c: Coef,
    y: V6,
    /// f(t, y): the FSAL stage.
    f: V6,
    t: L,
    h: L,
    ln_err_old: L,
    rejected: [bool; W],
    n_acc: [u64; W],
    n_rej: [u64; W],
    min_n: L,
    max_gap: L,
    min_vr: L,
    max_z: L,
    /// Input index of each lane's trajectory (`usize::MAX`: idle).
    who: [usize; W],
}

#[inline(always)]
pub(crate) fn splat(x: f64) -> L {
    [x; W]
}

/// `$body` for `$i` = 0..6, unrolled: the loops inside run over the lanes, and unrolling the
/// component loop keeps LLVM from vectorising across components (with gathers) instead.
macro_rules! each6 {
    ($i:ident, $body:block) => {{
        {
            let $i = 0usize;
            $body
        }
        {
            let $i = 1usize;
            $body
        }
        {
            let $i = 2usize;
            $body
        }
        {
            let $i = 3usize;
            $body
        }
        {
            let $i = 4usize;
            $body
        }
        {
            let $i = 5usize;
            $body
        }
    }};
}
pub(crate) use each6;

/// Right-hand side of the eight lanes, and the dynamic law force `F_z` of each.
#[inline(always)]
fn rhs(c: &Coef, y: &V6, out: &mut V6, fz: &mut L) {
    for l in 0..W {
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

/// Integrate each `sliders[i]` from `y0s[i]` at `t = 0` to `t_end` with Dormand–Prince 5(4),
/// eight trajectories at a time; the result for each trajectory, in input order.
///
/// Precondition (the caller checks): every slider has `ContactModel::Bilateral` and
/// `FrictionLaw::Constant`; `sliders.len() == y0s.len()`. Panics otherwise. See the module
/// documentation for how the results relate to `steady::run(s, y0, t_end, Method::Dopri5, tol)`.
pub fn run_bilateral_batch(sliders: &[Slider], y0s: &[State], t_end: f64, tol: &Tolerances) -> Vec<RunResult> {
    assert_eq!(sliders.len(), y0s.len(), "run_bilateral_batch: one initial state per slider");
    for s in sliders {
        assert!(
            s.p.contact == ContactModel::Bilateral && s.p.friction_law == FrictionLaw::Constant,
            "run_bilateral_batch: only bilateral contact with constant friction"
        );
    }
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { run_avx512(sliders, y0s, t_end, tol) };
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { run_avx2(sliders, y0s, t_end, tol) };
        }
    }
    run_impl(sliders, y0s, t_end, tol)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn run_avx512(sliders: &[Slider], y0s: &[State], t_end: f64, tol: &Tolerances) -> Vec<RunResult> {
    run_impl(sliders, y0s, t_end, tol)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2(sliders: &[Slider], y0s: &[State], t_end: f64, tol: &Tolerances) -> Vec<RunResult> {
    run_impl(sliders, y0s, t_end, tol)
}

/// The portable path (also used by the tests to check that the SIMD copies agree bitwise).
#[inline(always)]
fn run_impl(sliders: &[Slider], y0s: &[State], t_end: f64, tol: &Tolerances) -> Vec<RunResult> {
    let n = sliders.len();
    let opts = Options::<6>::new(tol.rtol, 1.0);
    let rtol = tol.rtol;
    let max_steps = opts.max_steps;
    let event_tol = opts.event_tol;
    let h_min_rel = opts.h_min_rel;
    let mut out: Vec<Option<RunResult>> = vec![None; n];
    let zero = [0.0; W];
    let mut ln = Lanes {
        c: Coef::zero(),
        y: [zero; 6],
        f: [zero; 6],
        t: zero,
        h: zero,
        ln_err_old: splat(LN_ERR_FLOOR),
        rejected: [false; W],
        n_acc: [0; W],
        n_rej: [0; W],
        min_n: zero,
        max_gap: zero,
        min_vr: zero,
        max_z: zero,
        who: [usize::MAX; W],
    };
    let mut next = 0usize;
    for l in 0..W {
        refill(&mut ln, l, &mut next, sliders, y0s, t_end, tol, &mut out);
    }

    // Scratch of the step.
    let mut k2 = [zero; 6];
    let mut k3 = [zero; 6];
    let mut k4 = [zero; 6];
    let mut k5 = [zero; 6];
    let mut k6 = [zero; 6];
    let mut k7 = [zero; 6];
    let mut ys = [zero; 6];
    let mut yn = [zero; 6];
    let mut fz = zero;

    while ln.who.iter().any(|&w| w != usize::MAX) {
        // ---- before the attempt: landing on t_end, the step floor, the step budget ----
        let mut hh = zero;
        let mut last = [false; W];
        let mut floor = zero;
        let mut bad = false;
        for l in 0..W {
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
            for l in 0..W {
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
                finish(&mut ln, l, status, &mut out);
                refill(&mut ln, l, &mut next, sliders, y0s, t_end, tol, &mut out);
            }
            continue;
        }

        // ---- the step: six new right-hand sides per lane ----
        let c = &ln.c;
        let y = &ln.y;
        let k1 = &ln.f;
        each6!(i, {
            for l in 0..W {
                ys[i][l] = y[i][l] + hh[l] * (A21 * k1[i][l]);
            }
        });
        rhs(c, &ys, &mut k2, &mut fz);
        each6!(i, {
            for l in 0..W {
                ys[i][l] = y[i][l] + hh[l] * (A31 * k1[i][l] + A32 * k2[i][l]);
            }
        });
        rhs(c, &ys, &mut k3, &mut fz);
        each6!(i, {
            for l in 0..W {
                ys[i][l] = y[i][l] + hh[l] * (A41 * k1[i][l] + A42 * k2[i][l] + A43 * k3[i][l]);
            }
        });
        rhs(c, &ys, &mut k4, &mut fz);
        each6!(i, {
            for l in 0..W {
                ys[i][l] = y[i][l] + hh[l] * (A51 * k1[i][l] + A52 * k2[i][l] + A53 * k3[i][l] + A54 * k4[i][l]);
            }
        });
        rhs(c, &ys, &mut k5, &mut fz);
        each6!(i, {
            for l in 0..W {
                ys[i][l] = y[i][l]
                    + hh[l] * (A61 * k1[i][l] + A62 * k2[i][l] + A63 * k3[i][l] + A64 * k4[i][l] + A65 * k5[i][l]);
            }
        });
        rhs(c, &ys, &mut k6, &mut fz);
        each6!(i, {
            for l in 0..W {
                yn[i][l] =
                    y[i][l] + hh[l] * (B1 * k1[i][l] + B3 * k3[i][l] + B4 * k4[i][l] + B5 * k5[i][l] + B6 * k6[i][l]);
            }
        });
        rhs(c, &yn, &mut k7, &mut fz);

        // ---- error norm and finiteness ----
        let mut acc = zero;
        let mut fin = [true; W];
        each6!(i, {
            for l in 0..W {
                let h = hh[l];
                let e = (E1 * h) * k1[i][l]
                    + (E3 * h) * k3[i][l]
                    + (E4 * h) * k4[i][l]
                    + (E5 * h) * k5[i][l]
                    + (E6 * h) * k6[i][l]
                    + (E7 * h) * k7[i][l];
                let sk = c.atol[i][l] + rtol * y[i][l].abs().max(yn[i][l].abs());
                let q = e / sk;
                acc[l] += q * q;
                fin[l] &= yn[i][l].is_finite() && k7[i][l].is_finite();
            }
        });

        // ---- accept or reject, the controller, extremes, the end tests (branch-free) ----
        let mut err = zero;
        let mut ok = [false; W];
        let mut lnx = zero;
        for l in 0..W {
            // The squared RMS norm: `err <= 1` iff `err^2 <= 1`, and ln err = ln(err^2) / 2, so
            // no square root is needed.
            err[l] = acc[l] / 6.0;
            ok[l] = err[l] <= 1.0 && fin[l];
            // ln of the error, floored far below anything that matters (a zero or subnormal error
            // gives the largest growth either way); non-finite errors are not used below.
            lnx[l] = err[l].max(1e-300);
        }
        let mut ln_err = ln_lanes(&lnx);
        for v in ln_err.iter_mut() {
            *v *= 0.5;
        }
        let mut arg = zero;
        for l in 0..W {
            // One exp per lane: the accept factor err^-alpha err_old^beta / safety, or the reject
            // factor err^-alpha (times safety), as in `Controller::accept` / `Controller::reject`.
            arg[l] =
                if ok[l] { -(ALPHA * ln_err[l] - BETA * ln.ln_err_old[l] - LN_SAFETY) } else { -ALPHA * ln_err[l] };
        }
        let r = exp_lanes(&arg);
        // Kept as several simple loops over the lanes: each vectorises on its own.
        let t_start = ln.t;
        let mut ended = [false; W];
        for l in 0..W {
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
        // Off the common path: only when some lane ends this step.
        let attention = ended.iter().fold(false, |a, &b| a | b);
        if attention && (0..W).any(|l| ok[l] && ended[l] && yn[idx::Z][l].abs() >= c.esc[l]) {
            let stages = [&ln.f, &k2, &k3, &k4, &k5, &k6, &k7];
            let step = Step { t0: &t_start, h: &hh, ok: &ok };
            locate_escapes(c, &ln.who, &ln.y, &stages, &step, &mut yn, &mut fz, &mut ln.t, sliders, event_tol);
        }
        for l in 0..W {
            ln.n_acc[l] += ok[l] as u64;
            ln.n_rej[l] += (!ok[l]) as u64;
        }
        each6!(i, {
            for l in 0..W {
                ln.y[i][l] = if ok[l] { yn[i][l] } else { ln.y[i][l] };
                ln.f[i][l] = if ok[l] { k7[i][l] } else { ln.f[i][l] };
            }
        });
        for l in 0..W {
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
            for l in 0..W {
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
                finish(&mut ln, l, status, &mut out);
                refill(&mut ln, l, &mut next, sliders, y0s, t_end, tol, &mut out);
            }
        }
    }
    out.into_iter().map(|r| r.expect("every trajectory has a result")).collect()
}

/// `exp` of each lane, branch-free so that it vectorises: `2^n p(r)` with `x = n ln 2 + r`,
/// `|r| <= ln 2 / 2`, Taylor to degree 12 (relative error below 1e-15). Arguments are clamped to
/// `[-700, 700]` (the controller clips its factors far inside that).
#[inline(always)]
pub(crate) fn exp_lanes(x: &L) -> L {
    const MAGIC: f64 = 6755399441055744.0; // 1.5 * 2^52: adding it rounds to an integer
                                           // ln 2 split so that n * LN2_HI is exact (fdlibm's constants).
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
    let mut out = [0.0; W];
    for l in 0..W {
        let x = x[l].clamp(-700.0, 700.0);
        let t = x * std::f64::consts::LOG2_E + MAGIC;
        let n = t - MAGIC;
        let r = (x - n * LN2_HI) - n * LN2_LO;
        let mut p = 1.0 / 479001600.0;
        p = p * r + 1.0 / 39916800.0;
        p = p * r + 1.0 / 3628800.0;
        p = p * r + 1.0 / 362880.0;
        p = p * r + 1.0 / 40320.0;
        p = p * r + 1.0 / 5040.0;
        p = p * r + 1.0 / 720.0;
        p = p * r + 1.0 / 120.0;
        p = p * r + 1.0 / 24.0;
        p = p * r + 1.0 / 6.0;
        p = p * r + 0.5;
        p = p * r + 1.0;
        p = p * r + 1.0;
        let ni = t.to_bits().wrapping_sub(MAGIC.to_bits());
        let scale = f64::from_bits(ni.wrapping_add(1023) << 52);
        out[l] = p * scale;
    }
    out
}

/// `ln` of each lane for normal positive finite arguments, branch-free:
/// `x = 2^e m`, `m` in `[sqrt(1/2), sqrt 2)`, `ln m = 2 atanh s`, `s = (m - 1)/(m + 1)`, series to
/// `s^21` (relative error below 1e-15).
#[inline(always)]
pub(crate) fn ln_lanes(x: &L) -> L {
    const TWO52: f64 = 4503599627370496.0;
    let mut out = [0.0; W];
    for l in 0..W {
        let b = x[l].to_bits();
        let mut m = f64::from_bits((b & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
        // Biased exponent as a double, exactly (no vector int->float conversion needed).
        let mut e = f64::from_bits(0x4330_0000_0000_0000 | (b >> 52)) - TWO52 - 1023.0;
        let big = m > std::f64::consts::SQRT_2;
        m = if big { 0.5 * m } else { m };
        e = if big { e + 1.0 } else { e };
        let s = (m - 1.0) / (m + 1.0);
        let s2 = s * s;
        let mut p = 1.0 / 21.0;
        p = p * s2 + 1.0 / 19.0;
        p = p * s2 + 1.0 / 17.0;
        p = p * s2 + 1.0 / 15.0;
        p = p * s2 + 1.0 / 13.0;
        p = p * s2 + 1.0 / 11.0;
        p = p * s2 + 1.0 / 9.0;
        p = p * s2 + 1.0 / 7.0;
        p = p * s2 + 1.0 / 5.0;
        p = p * s2 + 1.0 / 3.0;
        p = p * s2 + 1.0;
        out[l] = e * std::f64::consts::LN_2 + 2.0 * s * p;
    }
    out
}

#[inline]
pub(crate) fn lane_state(v: &V6, l: usize) -> State {
    State::from_fn(|i, _| v[i][l])
}

/// Lanes whose accepted step ends at `|z| >= escape_limit`: locate the crossing on the step's
/// interpolant, as the scalar path's escape event does (Illinois to `event_tol`, the time on the
/// far side of the crossing), and make the lane's step end there: `yn`, the contact force `fz`
/// and `t` of those lanes are replaced, so that the state, the extremes and the time reported are
/// the located ones. Called before the lane state is overwritten (`ln.y`, `ln.f` still hold the
/// step's start and first stage). Cold: diverging runs are rare.
/// The attempted step of every lane: start times, step sizes, accepted or not.
struct Step<'a> {
    t0: &'a L,
    h: &'a L,
    ok: &'a [bool; W],
}

#[cold]
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn locate_escapes(
    c: &Coef,
    who: &[usize; W],
    y: &V6,
    stages: &[&V6; 7],
    step: &Step<'_>,
    yn: &mut V6,
    fz: &mut L,
    t: &mut L,
    sliders: &[Slider],
    event_tol: f64,
) {
    for l in 0..W {
        if who[l] == usize::MAX || !step.ok[l] || yn[idx::Z][l].abs() < c.esc[l] {
            continue;
        }
        let esc = c.esc[l];
        let k: [State; 7] = std::array::from_fn(|j| lane_state(stages[j], l));
        let (y0, y1) = (lane_state(y, l), lane_state(yn, l));
        // `t` already holds the accepted step's end.
        let (t0, t1) = (step.t0[l], t[l]);
        let dense = Dopri5Dense::from_stages(&k, &y0, &y1, t0, step.h[l]);
        let g = |tt: f64| esc - dense.eval(tt)[idx::Z].abs();
        let (g0, g1) = (esc - y0[idx::Z].abs(), esc - y1[idx::Z].abs());
        let te = if g0 > 0.0 { locate(g, t0, g0, t1, g1, event_tol) } else { t1 };
        let ye = if te == t1 { y1 } else { dense.eval(te) };
        for i in 0..6 {
            yn[i][l] = ye[i];
        }
        fz[l] = sliders[who[l]].forces(&ye, ContactMode::Contact).normal - c.fst[l];
        t[l] = te;
    }
}

/// Write lane `l`'s result and mark it idle.
#[cold]
fn finish(ln: &mut Lanes, l: usize, status: Status, out: &mut [Option<RunResult>]) {
    let i = ln.who[l];
    let steps = ln.n_acc[l] + ln.n_rej[l];
    out[i] = Some(RunResult {
        status,
        t: ln.t[l],
        y: lane_state(&ln.y, l),
        extremes: Extremes {
            min_normal_force: ln.min_n[l],
            max_gap: ln.max_gap[l],
            min_slip_velocity: ln.min_vr[l],
            max_abs_z: ln.max_z[l],
        },
        stats: Stats { n_rhs: 2 + 6 * steps, n_accept: ln.n_acc[l], n_reject: ln.n_rej[l], ..Stats::default() },
    });
    ln.who[l] = usize::MAX;
}

/// Load the next trajectory that needs a step into lane `l` (trajectories that end before their
/// first step get their result here); leave the lane idle (harmless values) when none is left.
#[cold]
#[allow(clippy::too_many_arguments)]
fn refill(
    ln: &mut Lanes,
    l: usize,
    next: &mut usize,
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
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
        let early = |status, n_rhs| RunResult {
            status,
            t: 0.0,
            y: y0,
            extremes: ext,
            stats: Stats { n_rhs, ..Stats::default() },
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
        let opts = options_for(s, tol);
        let mut n_rhs = 1;
        let h0 = initial_step(
            s,
            ContactMode::Contact,
            0.0,
            &y0,
            &f0,
            t_end,
            5,
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
mod tests {
    use super::*;
    use crate::model::Params;
    use crate::ode::Method;
    use crate::steady::run;

    /// The benchmark ensemble of issue 2 (seed configuration, `mu` in [0.15, 0.30], load in
    /// [17, 152] N, z0 = 1 um), from a fixed linear congruential generator.
    fn ensemble(n: usize, seed: u64) -> (Vec<Slider>, Vec<State>) {
        let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut u = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut s = Vec::with_capacity(n);
        for _ in 0..n {
            let mu = 0.15 + 0.15 * u();
            let normal_load = 17.0 + 135.0 * u();
            s.push(Slider::new(Params { mu, normal_load, ..Params::seed() }).unwrap());
        }
        let y0 = vec![State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0); n];
        (s, y0)
    }

    fn tol(rtol: f64) -> Tolerances {
        Tolerances::new(rtol)
    }

    fn same(a: &RunResult, b: &RunResult) -> bool {
        let bits = |r: &RunResult| {
            let mut v: Vec<u64> = r.y.iter().map(|x| x.to_bits()).collect();
            v.push(r.t.to_bits());
            let e = r.extremes;
            v.extend([e.min_normal_force, e.max_gap, e.min_slip_velocity, e.max_abs_z].map(f64::to_bits));
            v.extend([r.stats.n_rhs, r.stats.n_accept, r.stats.n_reject]);
            v
        };
        a.status == b.status && bits(a) == bits(b)
    }

    #[test]
    fn lane_exp_and_ln() {
        let mut worst = (0.0f64, 0.0f64);
        let mut x: f64 = 1e-300;
        while x < 1e300 {
            let v = [x, 1.0 / x, 0.7 * x, 1.3 * x, x.sqrt(), 1.0, 0.5, 2.0];
            let l = ln_lanes(&v);
            for k in 0..W {
                worst.0 = worst.0.max((l[k] - v[k].ln()).abs() / v[k].ln().abs().max(1.0));
            }
            x *= 1.37;
        }
        let mut a: f64 = -700.0;
        while a < 700.0 {
            let v = [a, -a, 0.5 * a, 1e-3 * a, 0.0, 1e-17, a + 0.3, -0.1];
            let e = exp_lanes(&v);
            for k in 0..W {
                worst.1 = worst.1.max((e[k] - v[k].exp()).abs() / v[k].exp());
            }
            a += 0.913;
        }
        assert!(worst.0 < 1e-15 && worst.1 < 2e-15, "{worst:?}");
    }

    #[test]
    fn agrees_with_the_scalar_path() {
        let (s, y0) = ensemble(50, 1);
        let t_end = 0.5;
        let refs: Vec<RunResult> =
            s.iter().zip(&y0).map(|(s, y)| run(s, y, t_end, Method::Dop853, &tol(1e-13))).collect();
        for rtol in [1e-6, 1e-9] {
            let b = run_bilateral_batch(&s, &y0, t_end, &tol(rtol));
            let (mut worst, mut steps_b, mut steps_s) = (0.0f64, 0u64, 0u64);
            for i in 0..s.len() {
                let sc = run(&s[i], &y0[i], t_end, Method::Dopri5, &tol(rtol));
                let r = &refs[i];
                assert_eq!(r.status, Status::Success);
                assert_eq!(sc.status, Status::Success);
                assert_eq!(b[i].status, Status::Success, "{i}");
                assert_eq!(b[i].t, t_end);
                let scale = r.extremes.max_abs_z;
                let e_s = (sc.y[0] - r.y[0]).abs();
                let e_b = (b[i].y[0] - r.y[0]).abs();
                assert!(
                    e_b <= 10.0 * e_s + 1e-3 * rtol * scale,
                    "rtol {rtol} #{i}: batch error {e_b:e}, scalar {e_s:e}"
                );
                worst = worst.max(e_b / scale);
                for c in 0..6 {
                    let size = characteristic_sizes(&s[i])[c];
                    assert!(
                        (b[i].y[c] - sc.y[c]).abs() <= 1e3 * rtol * size.max(r.y[c].abs()),
                        "rtol {rtol} #{i} y[{c}]"
                    );
                }
                let (nb, ns) = (b[i].stats.n_accept + b[i].stats.n_reject, sc.stats.n_accept + sc.stats.n_reject);
                assert!((nb as f64 - ns as f64).abs() <= 0.03 * ns as f64 + 2.0, "#{i}: {nb} vs {ns} steps");
                assert_eq!(b[i].stats.n_rhs, 2 + 6 * nb);
                let (eb, es) = (b[i].extremes, sc.extremes);
                assert!((eb.max_abs_z - es.max_abs_z).abs() <= 1e-3 * es.max_abs_z);
                assert!((eb.min_normal_force - es.min_normal_force).abs() <= 1e-3 * s[i].p.normal_load);
                assert!((eb.max_gap - es.max_gap).abs() <= 1e-3 * es.max_abs_z);
                assert!((eb.min_slip_velocity - es.min_slip_velocity).abs() <= 1e-3 * s[i].p.sliding_speed);
                steps_b += nb;
                steps_s += ns;
            }
            println!("rtol {rtol:e}: max |z - z_ref|/max|z| = {worst:.2e}; steps batch {steps_b}, scalar {steps_s}");
        }
    }

    #[test]
    fn results_do_not_depend_on_the_batch() {
        let (s, y0) = ensemble(37, 2);
        let t = tol(1e-7);
        let all = run_bilateral_batch(&s, &y0, 0.2, &t);
        // Each alone.
        for i in (0..s.len()).step_by(5) {
            let one = run_bilateral_batch(&s[i..i + 1], &y0[i..i + 1], 0.2, &t);
            assert!(same(&one[0], &all[i]), "#{i} alone");
        }
        // Permuted and in other groupings.
        let perm: Vec<usize> = (0..s.len()).map(|k| (k * 11 + 3) % s.len()).collect();
        let sp: Vec<Slider> = perm.iter().map(|&k| s[k]).collect();
        let yp: Vec<State> = perm.iter().map(|&k| y0[k]).collect();
        let rp = run_bilateral_batch(&sp, &yp, 0.2, &t);
        for (j, &k) in perm.iter().enumerate() {
            assert!(same(&rp[j], &all[k]), "permuted #{k}");
        }
        for chunk in [3, 8, 13] {
            let mut k = 0;
            for (cs, cy) in s.chunks(chunk).zip(y0.chunks(chunk)) {
                for r in run_bilateral_batch(cs, cy, 0.2, &t) {
                    assert!(same(&r, &all[k]), "chunk {chunk} #{k}");
                    k += 1;
                }
            }
        }
        // The portable code path gives the same bits as the SIMD copy picked at run time.
        let portable = run_impl(&s, &y0, 0.2, &t);
        for i in 0..s.len() {
            assert!(same(&portable[i], &all[i]), "portable #{i}");
        }
    }

    #[test]
    fn escape_stops_with_diverged() {
        let s = Slider::new(Params { mu: 0.35, normal_load: 84.46, ..Params::seed() }).unwrap();
        let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
        let (ens, ey) = ensemble(5, 3);
        let mut sl = ens.clone();
        let mut ys = ey.clone();
        sl.insert(2, s);
        ys.insert(2, y0);
        let r = run_bilateral_batch(&sl, &ys, 20.0, &tol(1e-6));
        let d = &r[2];
        assert_eq!(d.status, Status::Diverged);
        assert!(d.y[0].abs() >= s.p.escape_limit && d.extremes.max_abs_z >= s.p.escape_limit);
        assert!(d.t < 20.0 && d.y.iter().all(|v| v.is_finite()));
        let sc = run(&s, &y0, 20.0, Method::Dopri5, &tol(1e-6));
        assert_eq!(sc.status, Status::Diverged);
        // The escape is located inside the step, as the scalar path's event: the same time and
        // state to the paths' rounding-level differences (amplified over a growing run).
        eprintln!("batch t {:.15e} z {:.6e}; scalar t {:.15e} z {:.6e}", d.t, d.y[0], sc.t, sc.y[0]);
        assert!((d.t - sc.t).abs() < 1e-9 * sc.t, "{} vs {}", d.t, sc.t);
        assert!((d.y[0].abs() / s.p.escape_limit - 1.0) < 1e-9, "{}", d.y[0]);
        assert!((d.y - sc.y).amax() < 1e-6 * sc.y.amax(), "{} vs {}", d.y, sc.y);
        assert_eq!(d.stats.n_accept, sc.stats.n_accept);
        assert!((d.extremes.max_abs_z - sc.extremes.max_abs_z).abs() < 1e-12, "{:?} vs {:?}", d.extremes, sc.extremes);
        for (i, x) in r.iter().enumerate() {
            assert!(x.y.iter().all(|v| v.is_finite()), "#{i}");
            if i != 2 {
                assert_eq!(x.status, Status::Success);
                assert_eq!(x.t, 20.0);
            }
        }
    }

    #[test]
    fn failures_and_trivial_runs() {
        let (s, mut y0) = ensemble(4, 4);
        y0[1][3] = f64::NAN;
        let r = run_bilateral_batch(&s, &y0, 0.1, &tol(1e-6));
        assert_eq!(r[1].status, Status::NonFinite);
        assert!([0, 2, 3].iter().all(|&i| r[i].status == Status::Success && r[i].t == 0.1));
        let r = run_bilateral_batch(&s[..1], &y0[..1], 0.0, &tol(1e-6));
        assert_eq!((r[0].status, r[0].stats.n_rhs), (Status::Success, 0));
        assert!(run_bilateral_batch(&[], &[], 1.0, &tol(1e-6)).is_empty());
        // Past the escape limit the quadratic contact law blows up in finite time: both paths end
        // with the same failure, never with NaN in the state.
        let s = Slider::new(Params { mu: 0.35, escape_limit: 1e300, ..Params::seed() }).unwrap();
        let y0 = State::new(1e-6, 0.0, 0.0, 0.0, 0.0, 0.0);
        let r = run_bilateral_batch(&[s], &[y0], 20.0, &tol(1e-6));
        let sc = run(&s, &y0, 20.0, Method::Dopri5, &tol(1e-6));
        println!("{:?} {:?} {:?} | {:?} {:?} {:?}", r[0].status, r[0].t, r[0].stats, sc.status, sc.t, sc.stats);
        assert_eq!(r[0].status, sc.status);
        assert!(r[0].status != Status::Success && (r[0].t - sc.t).abs() < 1e-3 * sc.t);
    }

    /// One path alone, for `perf stat` (cycles do not count the time other processes hold the
    /// core): `BATCH_PATH=batch|scalar|portable BATCH_RTOL=1e-6 ... batch::tests::one_path -- --ignored`.
    #[test]
    #[ignore]
    fn one_path() {
        let n = 1000;
        let (s, y0) = ensemble(n, 7);
        let rtol: f64 = std::env::var("BATCH_RTOL").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-6);
        let t = tol(rtol);
        let path = std::env::var("BATCH_PATH").unwrap_or_else(|_| "batch".into());
        for _ in 0..5 {
            match path.as_str() {
                "scalar" => {
                    for i in 0..n {
                        std::hint::black_box(run(&s[i], &y0[i], 0.5, Method::Dopri5, &t));
                    }
                }
                "portable" => {
                    std::hint::black_box(run_impl(&s, &y0, 0.5, &t));
                }
                _ => {
                    std::hint::black_box(run_bilateral_batch(&s, &y0, 0.5, &t));
                }
            }
        }
    }

    /// Throughput against the scalar driver in the same process (single thread; the three are
    /// interleaved and the best of five taken, against a noisy machine):
    /// `cargo test --release -p tribosweep-core batch::tests::throughput -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn throughput() {
        use std::time::Instant;
        let n = 1000;
        let (s, y0) = ensemble(n, 7);
        for rtol in [1e-6, 1e-9] {
            let t = tol(rtol);
            let time = |f: &dyn Fn()| {
                let t0 = Instant::now();
                f();
                t0.elapsed().as_secs_f64()
            };
            let mut best = [f64::INFINITY; 3];
            for _ in 0..5 {
                best[0] = best[0].min(time(&|| {
                    std::hint::black_box(run_bilateral_batch(&s, &y0, 0.5, &t));
                }));
                best[1] = best[1].min(time(&|| {
                    for i in 0..n {
                        std::hint::black_box(run(&s[i], &y0[i], 0.5, Method::Dopri5, &t));
                    }
                }));
                best[2] = best[2].min(time(&|| {
                    std::hint::black_box(run_impl(&s, &y0, 0.5, &t));
                }));
            }
            let r = run_bilateral_batch(&s, &y0, 0.5, &t);
            let steps: u64 = r.iter().map(|x| x.stats.n_accept + x.stats.n_reject).sum();
            println!(
                "rtol {rtol:e}: batch {:.0} traj/s, scalar steady::run {:.0} traj/s ({:.2}x), portable (no AVX) batch {:.0} traj/s; {:.0} steps/traj, {:.1} ns/step/traj",
                n as f64 / best[0],
                n as f64 / best[1],
                best[1] / best[0],
                n as f64 / best[2],
                steps as f64 / n as f64,
                best[0] / steps as f64 * 1e9
            );
        }
    }
}
