//! Lane-batched Dormand–Prince 5(4) for the whole slider model: unilateral contact, the
//! regularised Coulomb/Stribeck law, output at `t_eval`, and runs to a steady state.
//!
//! [`run_lanes`] integrates many trajectories [`W`] = 8 at a time in structure-of-arrays form, as
//! [`super::batch`] does for the bilateral constant-`mu` end state, and refills a lane as soon as
//! its trajectory ends. What it adds is everything the scalar driver does around the step:
//!
//! - **Modes per lane.** Each lane knows whether its pin is on or off the disk; the contact force
//!   is selected branch-free from a per-lane mask, so lanes in different modes share the step.
//! - **Events per lane, never stepped across.** After every accepted step the four event
//!   functions of the slider (gap, law normal force, sliding velocity, escape) are evaluated on all
//!   lanes at once; for the unilateral model they are also evaluated at the three interior points of
//!   each step's dense output (the scalar driver's hidden-crossing check), and a lane with a
//!   crossing and its return inside its step redoes the step ending inside the excursion. A lane
//!   whose step shows a crossing (or has an event pending after a switch) goes to a cold path that
//!   builds that lane's Dormand–Prince interpolant and runs **the scalar driver's own event code**
//!   (`driver::step_events`: Illinois location, time order, actions, the re-trigger guard) on it,
//!   then restarts the lane in its new mode with a fresh derivative, as the scalar driver does.
//! - **Observers per lane.** Sampling at `t_eval` and the steady-state watcher (Poincare section
//!   `zd = 0` falling, decay, cycle detection) are the scalar path's observers, called on the cold
//!   path only for lanes that need them this step: a lane whose `t_eval` point falls inside its
//!   step, whose `zd` changes sign downwards, or whose motion fell below the rest floor. On all
//!   other steps the bookkeeping those observers do per step (extremes, the peaks since the last
//!   section) runs vectorised on the lanes.
//!
//! The result of a trajectory is that of `steady::run`, `steady::run_sampled` or
//! `steady::run_to_steady` with `Method::Dopri5` to integration accuracy (tested on every scene of
//! the work-precision bench and on the seed's bouncing cycle): the right-hand side is the same
//! algebra with the dynamic law force used directly, and `exp`/`tanh` of the Stribeck law are
//! branch-free lane polynomials, so states differ from the scalar path's by rounding per step.
//!
//! # Determinism
//! Every lane's arithmetic depends on that lane's values only, and the cold paths are scalar code
//! on one trajectory, so a trajectory's result is bitwise the same whatever trajectories share its
//! batch, in whatever order, on any thread count and on any x86-64 code path (tested).

// Index loops over lanes and components are the point here: they are what LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::batch::{each6, exp_lanes, lane_state, ln_lanes, splat, ALPHA, BETA, L, LN_ERR_FLOOR, LN_SAFETY, V6, W};
use super::Method;

/// The PI controller's exponent for DOP853 (error order 8, `beta = 0.04`).
const ALPHA8: f64 = 1.0 / 8.0 - 0.75 * BETA;
use super::controller::{initial_step, FAC_MAX, FAC_MIN, SAFETY};
use super::dop853::*;
use super::dopri5::{
    Dopri5Dense, A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, B1, B3, B4, B5, B6, D1, D3,
    D4, D5, D6, D7, E1, E3, E4, E5, E6, E7,
};
use super::driver::{step_events, StepDense, StepEnd};
use super::{Control, Observer, OdeSystem, Options, Outcome, Sampler, Stats, StepView, MAX_EVENTS};
use crate::model::{event, idx, ContactMode, ContactModel, FrictionLaw, Params, Slider, State};
use crate::steady::{
    options_for, status_of, summarize, Extremes, ExtremesObserver, RunResult, SteadyObserver, SteadyOptions, Summary,
    Tolerances,
};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Event functions of the slider (gap, law normal force, sliding velocity, escape).
const NE: usize = 4;

/// What each trajectory of a [`run_lanes`] call computes.
#[derive(Clone, Copy, Debug)]
pub enum Task<'a> {
    /// The end state at `t_end` (or where the run stopped).
    Final,
    /// The end state and the states at the increasing times `t_eval` (NaN past an early stop),
    /// as `steady::run_sampled`.
    Sampled(&'a [f64]),
    /// A run to a steady state and its summary, as `steady::run_to_steady`; `t_end` and `tol`
    /// of [`run_lanes`] are ignored (`opts.t_max`, `opts.tol` are used). `decay`: a decay
    /// amplitude per trajectory that overrides `opts.decay_amplitude`.
    Steady { opts: &'a SteadyOptions, decay: Option<&'a [f64]> },
    /// The end state and every located event `(index, time)`: for tests and diagnostics.
    Events,
}

/// The result of one trajectory.
#[derive(Clone, Debug)]
pub struct LaneResult {
    /// The plain run (for `Steady`: the transient up to the end of detection).
    pub run: RunResult,
    /// States at `t_eval` (`Sampled` only).
    pub samples: Vec<State>,
    /// Summary (`Steady` only).
    pub summary: Option<Summary>,
    /// Located events `(index, time)` (`Events` only).
    pub events: Vec<(usize, f64)>,
}

/// Whether [`run_lanes`] integrates sliders with these parameters (the contact models and
/// friction laws it knows).
pub fn supports(p: &Params) -> bool {
    matches!(p.friction_law, FrictionLaw::Constant | FrictionLaw::Coulomb)
}

/// Whether [`run_lanes`] integrates with this method (the explicit Dormand–Prince pair and DOP853).
pub fn supports_method(m: Method) -> bool {
    matches!(m, Method::Dopri5 | Method::Dop853)
}

/// Per-lane coefficients of the right-hand side and the tolerances (shared with `batch`).
#[derive(Clone, Copy)]
pub(crate) struct Coef {
    pub(crate) ks: L,
    pub(crate) ka: L,
    pub(crate) c: L,
    pub(crate) kphi: L,
    pub(crate) mu: L,
    pub(crate) inv_m: L,
    pub(crate) wz2: L,
    pub(crate) dz: L,
    pub(crate) wx2: L,
    pub(crate) dx: L,
    pub(crate) wt2: L,
    pub(crate) dt: L,
    /// s L / I
    pub(crate) tg: L,
    pub(crate) atol: V6,
    /// F_st, z_st, V, s L, escape limit.
    pub(crate) fst: L,
    pub(crate) zst: L,
    pub(crate) v: L,
    pub(crate) sl: L,
    pub(crate) esc: L,
    /// Stribeck law: mu_k, mu_s - mu_k, 1/v_s, 1/eps, mu(V) F_st tanh(V/eps).
    pub(crate) mu_k: L,
    pub(crate) dmu: L,
    pub(crate) inv_vs: L,
    pub(crate) inv_eps: L,
    pub(crate) stat: L,
}

impl Coef {
    pub(crate) fn zero() -> Self {
        let z = [0.0; W];
        Coef {
            ks: z,
            ka: z,
            c: z,
            kphi: z,
            mu: z,
            inv_m: z,
            wz2: z,
            dz: z,
            wx2: z,
            dx: z,
            wt2: z,
            dt: z,
            tg: z,
            atol: [splat(1.0); 6],
            fst: z,
            zst: z,
            v: z,
            sl: z,
            esc: splat(f64::INFINITY),
            mu_k: z,
            dmu: z,
            inv_vs: z,
            inv_eps: z,
            stat: z,
        }
    }

    pub(crate) fn set(&mut self, l: usize, s: &Slider, atol: &[f64; 6]) {
        let p = &s.p;
        let (wz, wx, wt) = (p.omega_normal, p.omega_friction, p.omega_torsion);
        self.ks[l] = s.k_s;
        self.ka[l] = p.contact_quadratic;
        self.c[l] = p.contact_damping;
        self.kphi[l] = p.twist_coupling;
        self.mu[l] = p.mu;
        self.inv_m[l] = 1.0 / p.mass;
        self.wz2[l] = wz * wz;
        self.dz[l] = 2.0 * p.zeta_normal * wz;
        self.wx2[l] = wx * wx;
        self.dx[l] = 2.0 * p.zeta_friction * wx;
        self.wt2[l] = wt * wt;
        self.dt[l] = 2.0 * p.zeta_torsion * wt;
        self.tg[l] = p.torsion_sign * p.moment_arm / p.inertia;
        for i in 0..6 {
            self.atol[i][l] = atol[i];
        }
        self.fst[l] = p.normal_load;
        self.zst[l] = s.z_st;
        self.v[l] = p.sliding_speed;
        self.sl[l] = p.torsion_sign * p.moment_arm;
        self.esc[l] = p.escape_limit;
        self.mu_k[l] = s.mu_k;
        self.dmu[l] = p.mu_static - s.mu_k;
        self.inv_vs[l] = 1.0 / p.stribeck_velocity;
        self.inv_eps[l] = 1.0 / p.friction_regularization;
        // The scalar law's static friction force, mu(V) F_st tanh(V/eps).
        self.stat[l] = s.mu_of(p.sliding_speed) * p.normal_load * (p.sliding_speed / p.friction_regularization).tanh();
    }
}

/// Right-hand side of the eight lanes and the dynamic law force `F_z` of each (the force the
/// contact law gives, whether or not it acts). `UNI`: unilateral contact (the mask `contact`
/// selects the law force or no normal force); `COUL`: the regularised Coulomb/Stribeck law.
#[inline(always)]
fn rhs<const UNI: bool, const COUL: bool>(c: &Coef, contact: &[bool; W], y: &V6, out: &mut V6, fzl: &mut L) {
    let mut fz = [0.0; W];
    for l in 0..W {
        let (z, zd, ph) = (y[0][l], y[1][l], y[4][l]);
        let f = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
        fzl[l] = f;
        fz[l] = if UNI && !contact[l] { -c.fst[l] } else { f };
    }
    let mut fx = [0.0; W];
    if COUL {
        let mut a = [0.0; W];
        let mut b = [0.0; W];
        let mut vr = [0.0; W];
        for l in 0..W {
            let v = c.v[l] - (y[3][l] + c.sl[l] * y[5][l]);
            vr[l] = v;
            a[l] = -v.abs() * c.inv_vs[l];
            b[l] = -2.0 * (v * c.inv_eps[l]).abs();
        }
        let ea = exp_lanes(&a);
        let eb = exp_lanes(&b);
        for l in 0..W {
            let mu = c.mu_k[l] + c.dmu[l] * ea[l];
            // tanh(v/eps) = sign(v) (1 - e^{-2|v|/eps}) / (1 + e^{-2|v|/eps}).
            let th = ((1.0 - eb[l]) / (1.0 + eb[l])).copysign(vr[l]);
            let normal = c.fst[l] + fz[l];
            fx[l] = mu * normal * th - c.stat[l];
        }
    } else {
        for l in 0..W {
            fx[l] = c.mu[l] * fz[l];
        }
    }
    for l in 0..W {
        let (z, zd, x, xd, ph, phd) = (y[0][l], y[1][l], y[2][l], y[3][l], y[4][l], y[5][l]);
        out[0][l] = zd;
        out[1][l] = fz[l] * c.inv_m[l] - c.dz[l] * zd - c.wz2[l] * z;
        out[2][l] = xd;
        out[3][l] = fx[l] * c.inv_m[l] - c.dx[l] * xd - c.wx2[l] * x;
        out[4][l] = phd;
        out[5][l] = c.tg[l] * fx[l] - c.dt[l] * phd - c.wt2[l] * ph;
    }
}

/// The slider's event functions on the lanes (`model::Slider::events`), from the state and the
/// dynamic law force.
#[inline(always)]
fn events_lanes<const COUL: bool>(c: &Coef, y: &V6, fzl: &L, g: &mut [L; NE]) {
    for l in 0..W {
        g[event::GAP][l] = c.zst[l] + y[idx::Z][l];
        g[event::NORMAL][l] = c.fst[l] + fzl[l];
        // No event under the constant law (see `Slider::events`).
        g[event::SLIP][l] = if COUL { c.v[l] - (y[idx::XD][l] + c.sl[l] * y[idx::PHID][l]) } else { 1.0 };
        g[event::ESCAPE][l] = c.esc[l] - y[idx::Z][l].abs();
    }
}

/// What a lane's observer watches.
enum Watch<'a> {
    Nothing,
    Sample(Sampler<'a, 6>),
    Steady(Box<SteadyObserver>, SteadyOptions),
    Log(Vec<(usize, f64)>),
}

impl Observer<6, ContactMode> for Watch<'_> {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        match self {
            Watch::Sample(s) => s.on_step(st),
            Watch::Steady(o, _) => o.on_step(st),
            Watch::Nothing | Watch::Log(_) => Control::Continue,
        }
    }
    fn on_event(&mut self, i: usize, t: f64, y: &State, before: ContactMode, after: ContactMode) -> Control {
        match self {
            Watch::Log(v) => {
                v.push((i, t));
                Control::Continue
            }
            Watch::Steady(o, _) => o.on_event(i, t, y, before, after),
            _ => Control::Continue,
        }
    }
}

/// The scalar side of a lane: what the cold paths need.
struct Side<'a> {
    /// Input index of the trajectory.
    i: usize,
    s: &'a Slider,
    opts: Options<6>,
    mode: ContactMode,
    pend: [Option<f64>; MAX_EVENTS],
    /// Right-hand sides outside the steps (start, starting step, restarts) and located events.
    stats: Stats,
    obs: ExtremesObserver<'a, Watch<'a>>,
}

/// The vector side of the eight lanes.
struct Lanes<'a> {
    c: Coef,
    y: V6,
    /// f(t, y) in the lane's mode: the FSAL stage.
    f: V6,
    t: L,
    h: L,
    ln_err_old: L,
    rejected: [bool; W],
    n_acc: [u64; W],
    n_rej: [u64; W],
    /// Right-hand sides of DOP853's interpolant built on the lanes (hidden-crossing checks).
    n_extra: [u64; W],
    /// The method is DOP853 (else DP5).
    m8: bool,
    contact: [bool; W],
    g0: [L; NE],
    pend: [[bool; W]; NE],
    min_n: L,
    max_gap: L,
    min_vr: L,
    max_z: L,
    /// Steady watcher: largest |z| and |y_c| since the last section, the rest floor (-inf: none).
    peak: L,
    peaks: V6,
    rest: L,
    /// Next `t_eval` time of each lane (+inf: none).
    next_sample: L,
    side: [Option<Side<'a>>; W],
}

/// Integrate each `sliders[i]` from `y0s[i]` at `t = 0` with `method` (Dormand–Prince 5(4) or
/// DOP853), eight trajectories at a time on this thread, and compute `task` for each; results in
/// input order.
///
/// Precondition (the caller checks): all sliders share one contact model and one friction law,
/// which [`supports`] accepts; [`supports_method`] accepts `method`; `sliders.len() ==
/// y0s.len()`. Panics otherwise.
pub fn run_lanes(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
) -> Vec<LaneResult> {
    check(sliders, y0s, method, &task);
    let feed = AtomicUsize::new(0);
    let mut out = dispatch(sliders, y0s, t_end, method, tol, task, &feed);
    out.sort_unstable_by_key(|r| r.0);
    out.into_iter().map(|r| r.1).collect()
}

/// [`run_lanes`] on `threads` threads (`None`: [`crate::ensemble::default_threads`]): every
/// thread runs its own eight lanes and takes the next trajectory of the call whenever one of its
/// lanes ends, so the threads stay busy to the end however unequal the runs. A trajectory's
/// result does not depend on which lanes or thread ran it (bitwise; tested), so results are the
/// same for any thread count. A panic on a thread becomes `Err(message)` for the trajectories
/// that thread had not finished.
pub fn run_lanes_threads(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
    threads: Option<usize>,
) -> Vec<Result<LaneResult, String>> {
    check(sliders, y0s, method, &task);
    let n = sliders.len();
    let nthreads = threads.unwrap_or_else(crate::ensemble::default_threads).max(1).min(n.div_ceil(W).max(1));
    let feed = AtomicUsize::new(0);
    let workers: Vec<usize> = (0..nthreads).collect();
    let parts = crate::ensemble::par_map(
        &workers,
        Some(nthreads),
        |_| Ok(dispatch(sliders, y0s, t_end, method, tol, task, &feed)),
        Err,
    );
    let mut out: Vec<Option<Result<LaneResult, String>>> = vec![None; n];
    let mut panic = None;
    for p in parts {
        match p {
            Ok(v) => {
                for (i, r) in v {
                    out[i] = Some(Ok(r));
                }
            }
            Err(msg) => panic = Some(msg),
        }
    }
    let msg = panic.unwrap_or_default();
    out.into_iter().map(|r| r.unwrap_or_else(|| Err(msg.clone()))).collect()
}

fn check(sliders: &[Slider], y0s: &[State], method: Method, task: &Task<'_>) {
    assert_eq!(sliders.len(), y0s.len(), "run_lanes: one initial state per slider");
    assert!(supports_method(method), "run_lanes: method {method:?} is not lane-batched");
    if let Some(first) = sliders.first() {
        for s in sliders {
            assert!(supports(&s.p), "run_lanes: friction law {:?} is not lane-batched", s.p.friction_law);
            assert!(
                s.p.contact == first.p.contact && s.p.friction_law == first.p.friction_law,
                "run_lanes: every slider of one call shares the contact model and friction law"
            );
        }
    }
    if let Task::Steady { decay: Some(d), .. } = task {
        assert_eq!(d.len(), sliders.len(), "run_lanes: one decay amplitude per slider");
    }
}

/// The monomorphised, CPU-dispatched lane driver for the sliders' model and `method`.
fn dispatch(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &AtomicUsize,
) -> Vec<(usize, LaneResult)> {
    let Some(first) = sliders.first() else { return Vec::new() };
    let uni = first.p.contact == ContactModel::Unilateral;
    let coul = first.p.friction_law == FrictionLaw::Coulomb;
    let m8 = method == Method::Dop853;
    macro_rules! go {
        ($u:literal, $c:literal, $m:literal) => {
            dispatch_cpu::<$u, $c, $m>(sliders, y0s, t_end, tol, task, feed)
        };
    }
    match (uni, coul, m8) {
        (false, false, false) => go!(false, false, false),
        (false, true, false) => go!(false, true, false),
        (true, false, false) => go!(true, false, false),
        (true, true, false) => go!(true, true, false),
        (false, false, true) => go!(false, false, true),
        (false, true, true) => go!(false, true, true),
        (true, false, true) => go!(true, false, true),
        (true, true, true) => go!(true, true, true),
    }
}

fn dispatch_cpu<const UNI: bool, const COUL: bool, const M8: bool>(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &AtomicUsize,
) -> Vec<(usize, LaneResult)> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { run_avx512::<UNI, COUL, M8>(sliders, y0s, t_end, tol, task, feed) };
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { run_avx2::<UNI, COUL, M8>(sliders, y0s, t_end, tol, task, feed) };
        }
    }
    run_impl::<UNI, COUL, M8>(sliders, y0s, t_end, tol, task, feed)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn run_avx512<const UNI: bool, const COUL: bool, const M8: bool>(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &AtomicUsize,
) -> Vec<(usize, LaneResult)> {
    run_impl::<UNI, COUL, M8>(sliders, y0s, t_end, tol, task, feed)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<const UNI: bool, const COUL: bool, const M8: bool>(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &AtomicUsize,
) -> Vec<(usize, LaneResult)> {
    run_impl::<UNI, COUL, M8>(sliders, y0s, t_end, tol, task, feed)
}

/// Everything the set-up and teardown of a lane needs.
struct Input<'a, 'b> {
    sliders: &'a [Slider],
    y0s: &'b [State],
    t_end: f64,
    tol: Tolerances,
    task: Task<'a>,
    /// Index of the next trajectory to start (shared by the workers of a threaded call).
    feed: &'b AtomicUsize,
}

/// The portable path (the tests check that the SIMD copies agree bitwise).
#[inline(always)]
fn run_impl<const UNI: bool, const COUL: bool, const M8: bool>(
    sliders: &[Slider],
    y0s: &[State],
    t_end: f64,
    tol: &Tolerances,
    task: Task<'_>,
    feed: &AtomicUsize,
) -> Vec<(usize, LaneResult)> {
    let (t_end, tol) = match task {
        Task::Steady { opts, .. } => (opts.t_max, opts.tol),
        _ => (t_end, *tol),
    };
    let inp = Input { sliders, y0s, t_end, tol, task, feed };
    let n = sliders.len();
    let rtol = tol.rtol;
    let mut out: Vec<(usize, LaneResult)> = Vec::with_capacity(n);
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
        n_extra: [0; W],
        m8: M8,
        contact: [true; W],
        g0: [splat(1.0); NE],
        pend: [[false; W]; NE],
        min_n: zero,
        max_gap: zero,
        min_vr: zero,
        max_z: zero,
        peak: zero,
        peaks: [zero; 6],
        rest: splat(f64::NEG_INFINITY),
        next_sample: splat(f64::INFINITY),
        side: std::array::from_fn(|_| None),
    };
    let steady = matches!(task, Task::Steady { .. });
    let sampled = matches!(task, Task::Sampled(_));
    let h_min_rel = Options::<6>::new(rtol, 1.0).h_min_rel;
    for l in 0..W {
        refill(&mut ln, l, &inp, &mut out);
    }

    let mut k2 = [zero; 6];
    let mut k3 = [zero; 6];
    let mut k4 = [zero; 6];
    let mut k5 = [zero; 6];
    let mut k6 = [zero; 6];
    let mut k7 = [zero; 6];
    let mut kk = [[zero; 6]; 16];
    let mut ys = [zero; 6];
    let mut yn = [zero; 6];
    let mut fzl = zero;
    let mut fzl_scratch = zero;

    while ln.side.iter().any(|s| s.is_some()) {
        let live: [bool; W] = std::array::from_fn(|l| ln.side[l].is_some());
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
        }
        for l in 0..W {
            if let Some(sd) = &ln.side[l] {
                let too_small = (hh[l].is_nan() || hh[l] < floor[l]) && !last[l];
                bad |= too_small || ln.n_acc[l] + ln.n_rej[l] >= sd.opts.max_steps;
            }
        }
        if bad {
            for l in 0..W {
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
                finish(&mut ln, l, t, y, outcome, &mut out);
                refill(&mut ln, l, &inp, &mut out);
            }
            continue;
        }

        let c = &ln.c;
        let cm = &ln.contact;
        let y = &ln.y;
        let k1 = &ln.f;
        // The error measure: the squared RMS norm for DP5 (`err <= 1` iff `err^2 <= 1`, no square
        // root needed), Hairer's combined 5th/3rd-order norm for DOP853.
        let (err, fin) = if M8 {
            step853::<UNI, COUL>(c, cm, y, k1, &hh, rtol, &mut kk, &mut yn, &mut fzl)
        } else {
            // ---- the step: six new right-hand sides per lane ----
            each6!(i, {
                for l in 0..W {
                    ys[i][l] = y[i][l] + hh[l] * (A21 * k1[i][l]);
                }
            });
            rhs::<UNI, COUL>(c, cm, &ys, &mut k2, &mut fzl);
            each6!(i, {
                for l in 0..W {
                    ys[i][l] = y[i][l] + hh[l] * (A31 * k1[i][l] + A32 * k2[i][l]);
                }
            });
            rhs::<UNI, COUL>(c, cm, &ys, &mut k3, &mut fzl);
            each6!(i, {
                for l in 0..W {
                    ys[i][l] = y[i][l] + hh[l] * (A41 * k1[i][l] + A42 * k2[i][l] + A43 * k3[i][l]);
                }
            });
            rhs::<UNI, COUL>(c, cm, &ys, &mut k4, &mut fzl);
            each6!(i, {
                for l in 0..W {
                    ys[i][l] = y[i][l] + hh[l] * (A51 * k1[i][l] + A52 * k2[i][l] + A53 * k3[i][l] + A54 * k4[i][l]);
                }
            });
            rhs::<UNI, COUL>(c, cm, &ys, &mut k5, &mut fzl);
            each6!(i, {
                for l in 0..W {
                    ys[i][l] = y[i][l]
                        + hh[l] * (A61 * k1[i][l] + A62 * k2[i][l] + A63 * k3[i][l] + A64 * k4[i][l] + A65 * k5[i][l]);
                }
            });
            rhs::<UNI, COUL>(c, cm, &ys, &mut k6, &mut fzl);
            each6!(i, {
                for l in 0..W {
                    yn[i][l] = y[i][l]
                        + hh[l] * (B1 * k1[i][l] + B3 * k3[i][l] + B4 * k4[i][l] + B5 * k5[i][l] + B6 * k6[i][l]);
                }
            });
            rhs::<UNI, COUL>(c, cm, &yn, &mut k7, &mut fzl);

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
            let mut e2 = zero;
            for l in 0..W {
                e2[l] = acc[l] / 6.0;
            }
            (e2, fin)
        };
        let fnew: &V6 = if M8 { &kk[12] } else { &k7 };
        let mut ok = [false; W];
        for l in 0..W {
            ok[l] = err[l] <= 1.0 && fin[l] && live[l];
        }

        // ---- events at the step end; hidden crossings inside the step (unilateral) ----
        let mut g1 = [zero; NE];
        events_lanes::<COUL>(c, &yn, &fzl, &mut g1);
        let mut hidden = zero; // theta of the interior point to end a redone step at (0: none)
        if UNI {
            // The interpolant at three interior points: DP5's from its stages, DOP853's needs
            // three more right-hand sides (its 7th-order dense output), counted as work.
            let dense = if M8 {
                for l in 0..W {
                    ln.n_extra[l] += 3 * ok[l] as u64;
                }
                dense853::<UNI, COUL>(c, cm, y, &yn, k1, &hh, &kk, &mut fzl_scratch)
            } else {
                dense5(y, &yn, [k1, &k3, &k4, &k5, &k6, &k7], &hh)
            };
            hidden_crossings::<COUL>(c, &dense, &ln.g0, &g1, &ln.pend, &ok, &mut hidden);
        }

        // ---- accept or reject, the controller (branch-free) ----
        let mut lnx = zero;
        for l in 0..W {
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
        for l in 0..W {
            arg[l] =
                if ok[l] { -(alpha * ln_err[l] - BETA * ln.ln_err_old[l] - LN_SAFETY) } else { -alpha * ln_err[l] };
        }
        let r = exp_lanes(&arg);
        let t_start = ln.t;
        let mut acc_ok = [false; W];
        let mut t_new = zero;
        for l in 0..W {
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
            t_new[l] = if last[l] { t_end } else { ln.t[l] + hh[l] };
        }
        for l in 0..W {
            ln.n_acc[l] += acc_ok[l] as u64;
            ln.n_rej[l] += (live[l] && !acc_ok[l]) as u64;
        }

        // ---- which accepted lanes need the cold path ----
        let mut busy = [false; W];
        let mut attn = [false; W];
        for e in 0..NE {
            for l in 0..W {
                busy[l] |= ln.pend[e][l] | cross(ln.g0[e][l], g1[e][l]);
            }
        }
        for l in 0..W {
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
        for l in 0..W {
            if !live[l] || acc_ok[l] || hidden[l] > 0.0 {
                continue;
            }
            let h_new = ln.h[l];
            if h_new.is_nan() || h_new < floor[l] {
                let ordinary = fin[l] && err[l].is_finite();
                let outcome = if ordinary { Outcome::StepTooSmall } else { Outcome::NonFinite };
                let (t, y) = (ln.t[l], lane_state(&ln.y, l));
                finish(&mut ln, l, t, y, outcome, &mut out);
                refill(&mut ln, l, &inp, &mut out);
            }
        }

        // ---- the common accepted step: commit on the lanes ----
        let plain: [bool; W] = std::array::from_fn(|l| acc_ok[l] && !attn[l]);
        each6!(i, {
            for l in 0..W {
                ln.y[i][l] = if plain[l] { yn[i][l] } else { ln.y[i][l] };
                ln.f[i][l] = if plain[l] { fnew[i][l] } else { ln.f[i][l] };
            }
        });
        for e in 0..NE {
            for l in 0..W {
                ln.g0[e][l] = if plain[l] { g1[e][l] } else { ln.g0[e][l] };
            }
        }
        for l in 0..W {
            let p = plain[l];
            ln.t[l] = if p { t_new[l] } else { ln.t[l] };
            let z = yn[idx::Z][l];
            let normal = if UNI && !ln.contact[l] { 0.0 } else { ln.c.fst[l] + fzl[l] };
            let gap = g1[event::GAP][l];
            let vr = ln.c.v[l] - (yn[idx::XD][l] + ln.c.sl[l] * yn[idx::PHID][l]);
            ln.min_n[l] = if p { ln.min_n[l].min(normal) } else { ln.min_n[l] };
            ln.max_gap[l] = if p { ln.max_gap[l].max(gap) } else { ln.max_gap[l] };
            ln.min_vr[l] = if p { ln.min_vr[l].min(vr) } else { ln.min_vr[l] };
            ln.max_z[l] = if p { ln.max_z[l].max(z.abs()) } else { ln.max_z[l] };
        }
        if steady {
            for l in 0..W {
                let p = plain[l];
                ln.peak[l] = if p { ln.peak[l].max(yn[idx::Z][l].abs()) } else { ln.peak[l] };
            }
            each6!(i, {
                for l in 0..W {
                    ln.peaks[i][l] = if plain[l] { ln.peaks[i][l].max(yn[i][l].abs()) } else { ln.peaks[i][l] };
                }
            });
        }

        // ---- the cold path: events, observers, the end of a run ----
        if attn.iter().any(|&a| a) {
            let stages: [&V6; 13] = if M8 {
                let mut a = [&ln.f; 13];
                for j in 1..13 {
                    a[j] = &kk[j];
                }
                a
            } else {
                [&ln.f, &k2, &k3, &k4, &k5, &k6, &k7, &k7, &k7, &k7, &k7, &k7, &k7]
            };
            let ks: [[State; 13]; W] = std::array::from_fn(|l| {
                if attn[l] {
                    std::array::from_fn(|j| lane_state(stages[j], l))
                } else {
                    [State::zeros(); 13]
                }
            });
            for l in 0..W {
                if !attn[l] {
                    continue;
                }
                let y0 = lane_state(&ln.y, l);
                let y1 = lane_state(&yn, l);
                let g0: [f64; MAX_EVENTS] = std::array::from_fn(|e| if e < NE { ln.g0[e][l] } else { 0.0 });
                let g1l: [f64; MAX_EVENTS] = std::array::from_fn(|e| if e < NE { g1[e][l] } else { 0.0 });
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
                    let dense = Dop853Dense::from_stages(sd.s, sd.mode, &ks[l], &y0, &y1, t_start[l], hh[l]);
                    let ev = cold_step(sd, &dense, busy[l], span, &g0, &g1l);
                    sd.stats.n_rhs += dense.extra_rhs();
                    ev
                } else {
                    let k7s: &[State; 7] = ks[l][..7].try_into().expect("seven stages");
                    let dense = Dopri5Dense::from_stages(k7s, &y0, &y1, t_start[l], hh[l]);
                    cold_step(sd, &dense, busy[l], span, &g0, &g1l)
                };
                sync_from_side(&mut ln, l, steady, sampled);
                if let Some(outcome) = ev.end {
                    finish(&mut ln, l, ev.t1, ev.y1, outcome, &mut out);
                    refill(&mut ln, l, &inp, &mut out);
                    continue;
                }
                if let Some(sw) = ev.switched {
                    // Restart at the event in the new mode: fresh derivative, fresh event values.
                    let sd = ln.side[l].as_mut().expect("live");
                    let (t, y1, mode) = (ev.t1, ev.y1, ev.new_mode);
                    sd.mode = mode;
                    let f = sd.s.rhs(&y1, mode);
                    sd.stats.n_rhs += 1;
                    if !f.iter().all(|v| v.is_finite()) {
                        finish(&mut ln, l, t, y1, Outcome::NonFinite, &mut out);
                        refill(&mut ln, l, &inp, &mut out);
                        continue;
                    }
                    let mut g = [0.0; MAX_EVENTS];
                    sd.s.events(t, &y1, mode, &mut g);
                    for e in 0..NE {
                        sd.pend[e] = match sw.pend_before[e] {
                            Some(ts) if t <= sw.t_check[e] => Some(ts),
                            _ if e == sw.index || g[e] == 0.0 => Some(t),
                            _ => None,
                        };
                    }
                    let contact = mode.in_contact();
                    let pend = sd.pend;
                    for i in 0..6 {
                        ln.y[i][l] = y1[i];
                        ln.f[i][l] = f[i];
                    }
                    for e in 0..NE {
                        ln.g0[e][l] = g[e];
                        ln.pend[e][l] = pend[e].is_some();
                    }
                    ln.t[l] = t;
                    ln.contact[l] = contact;
                    ln.ln_err_old[l] = LN_ERR_FLOOR;
                } else {
                    for i in 0..6 {
                        ln.y[i][l] = y1[i];
                        ln.f[i][l] = fnew[i][l];
                    }
                    ln.t[l] = t_new[l];
                    let sd = ln.side[l].as_mut().expect("live");
                    for e in 0..NE {
                        ln.g0[e][l] = g1[e][l];
                        if sd.pend[e].is_none() && g1[e][l] == 0.0 {
                            sd.pend[e] = Some(t_new[l]);
                        }
                        ln.pend[e][l] = sd.pend[e].is_some();
                    }
                    if last[l] {
                        finish(&mut ln, l, t_new[l], y1, Outcome::Finished, &mut out);
                        refill(&mut ln, l, &inp, &mut out);
                    }
                }
            }
        }
    }
    out
}

/// The scalar driver's handling of one accepted step of one lane: its events (located on the
/// step's interpolant, acted on in time order) or, without any, the observer's look at the step.
#[inline(never)]
fn cold_step<D: StepDense<6>>(
    sd: &mut Side<'_>,
    dense: &D,
    busy: bool,
    ((t0, y0), (t1, y1)): ((f64, &State), (f64, &State)),
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
            NE,
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

fn sync_to_side(min_n: &L, max_gap: &L, min_vr: &L, max_z: &L, l: usize, sd: &mut Side<'_>) {
    sd.obs.ext =
        Extremes { min_normal_force: min_n[l], max_gap: max_gap[l], min_slip_velocity: min_vr[l], max_abs_z: max_z[l] };
}

/// Copy what the scalar observers changed back onto the lanes.
fn sync_from_side(ln: &mut Lanes<'_>, l: usize, steady: bool, sampled: bool) {
    let sd = ln.side[l].as_ref().expect("live");
    let e = sd.obs.ext;
    ln.min_n[l] = e.min_normal_force;
    ln.max_gap[l] = e.max_gap;
    ln.min_vr[l] = e.min_slip_velocity;
    ln.max_z[l] = e.max_abs_z;
    if steady {
        if let Watch::Steady(o, _) = &sd.obs.inner {
            ln.peak[l] = o.w.peak_since;
            for i in 0..6 {
                ln.peaks[i][l] = o.w.peaks_since[i];
            }
        }
    }
    if sampled {
        if let Watch::Sample(s) = &sd.obs.inner {
            ln.next_sample[l] = s.t_eval.get(s.out.len()).copied().unwrap_or(f64::INFINITY);
        }
    }
}

/// A step's interpolant on the lanes, for the five components the event functions read (z, zd,
/// xd, phi, phid).
struct LaneDense {
    y0: [L; 5],
    /// DP5: `dy, bspl, r4, r5` (`y0 + (dy + (bspl + (r4 + r5 (1-x)) x) (1-x)) x`);
    /// DOP853: `c0..c6` (Hairer's `contd8` polynomial).
    c: [[L; 5]; 7],
    eight: bool,
}

const EV_COMPS: [usize; 5] = [idx::Z, idx::ZD, idx::XD, idx::PHI, idx::PHID];

impl LaneDense {
    #[inline(always)]
    fn eval(&self, x: f64) -> [L; 5] {
        let x1 = 1.0 - x;
        let c = &self.c;
        let mut v = [[0.0; W]; 5];
        for j in 0..5 {
            for l in 0..W {
                v[j][l] = if self.eight {
                    let mut p = c[6][j][l] * x;
                    p = (c[5][j][l] + p) * x1;
                    p = (c[4][j][l] + p) * x;
                    p = (c[3][j][l] + p) * x1;
                    p = (c[2][j][l] + p) * x;
                    p = (c[1][j][l] + p) * x1;
                    p = (c[0][j][l] + p) * x;
                    self.y0[j][l] + p
                } else {
                    self.y0[j][l] + (c[0][j][l] + (c[1][j][l] + (c[2][j][l] + c[3][j][l] * x1) * x) * x1) * x
                };
            }
        }
        v
    }
}

/// The DP5 interpolant of each lane's step.
#[inline(always)]
fn dense5(y0: &V6, y1: &V6, k: [&V6; 6], hh: &L) -> LaneDense {
    let [k1, k3, k4, k5, k6, k7] = k;
    let mut d = LaneDense { y0: [[0.0; W]; 5], c: [[[0.0; W]; 5]; 7], eight: false };
    for (j, &i) in EV_COMPS.iter().enumerate() {
        for l in 0..W {
            let h = hh[l];
            let dy = y1[i][l] - y0[i][l];
            let b = k1[i][l] * h - dy;
            d.y0[j][l] = y0[i][l];
            d.c[0][j][l] = dy;
            d.c[1][j][l] = b;
            d.c[2][j][l] = dy - k7[i][l] * h - b;
            d.c[3][j][l] = (D1 * h) * k1[i][l]
                + (D3 * h) * k3[i][l]
                + (D4 * h) * k4[i][l]
                + (D5 * h) * k5[i][l]
                + (D6 * h) * k6[i][l]
                + (D7 * h) * k7[i][l];
        }
    }
    d
}

/// `out = y + h (a_1 k_1 + ... + a_K k_K)` on the lanes.
#[inline(always)]
fn comb<const K: usize>(y: &V6, hh: &L, a: [f64; K], ks: [&V6; K], out: &mut V6) {
    for i in 0..6 {
        for l in 0..W {
            let mut s = 0.0;
            for j in 0..K {
                s += a[j] * ks[j][i][l];
            }
            out[i][l] = y[i][l] + hh[l] * s;
        }
    }
}

/// One DOP853 attempt on the lanes: the twelve stages into `kk[1..12]`, the new state `yn`, the
/// derivative there into `kk[12]` (and the law force there into `fzl`); returns Hairer's error
/// measure and whether the state and derivative are finite.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn step853<const UNI: bool, const COUL: bool>(
    c: &Coef,
    cm: &[bool; W],
    y: &V6,
    k1: &V6,
    hh: &L,
    rtol: f64,
    kk: &mut [V6; 16],
    yn: &mut V6,
    fzl: &mut L,
) -> (L, [bool; W]) {
    let mut ys = [[0.0; W]; 6];
    let mut t = [[0.0; W]; 6];
    macro_rules! stage {
        ($j:expr, $a:expr, $ks:expr) => {{
            comb(y, hh, $a, $ks, &mut ys);
            rhs::<UNI, COUL>(c, cm, &ys, &mut t, fzl);
            kk[$j] = t;
        }};
    }
    stage!(1, [A2_1], [k1]);
    stage!(2, [A3_1, A3_2], [k1, &kk[1]]);
    stage!(3, [A4_1, A4_3], [k1, &kk[2]]);
    stage!(4, [A5_1, A5_3, A5_4], [k1, &kk[2], &kk[3]]);
    stage!(5, [A6_1, A6_4, A6_5], [k1, &kk[3], &kk[4]]);
    stage!(6, [A7_1, A7_4, A7_5, A7_6], [k1, &kk[3], &kk[4], &kk[5]]);
    stage!(7, [A8_1, A8_4, A8_5, A8_6, A8_7], [k1, &kk[3], &kk[4], &kk[5], &kk[6]]);
    stage!(8, [A9_1, A9_4, A9_5, A9_6, A9_7, A9_8], [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7]]);
    stage!(9, [A10_1, A10_4, A10_5, A10_6, A10_7, A10_8, A10_9], [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7], &kk[8]]);
    stage!(
        10,
        [A11_1, A11_4, A11_5, A11_6, A11_7, A11_8, A11_9, A11_10],
        [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7], &kk[8], &kk[9]]
    );
    stage!(
        11,
        [A12_1, A12_4, A12_5, A12_6, A12_7, A12_8, A12_9, A12_10, A12_11],
        [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7], &kk[8], &kk[9], &kk[10]]
    );
    let used = [k1, &kk[5], &kk[6], &kk[7], &kk[8], &kk[9], &kk[10], &kk[11]];
    comb(y, hh, [A13_1, A13_6, A13_7, A13_8, A13_9, A13_10, A13_11, A13_12], used, yn);
    let mut s5 = [0.0; W];
    let mut s3 = [0.0; W];
    for i in 0..6 {
        for l in 0..W {
            let mut e5 = 0.0;
            let mut e3 = 0.0;
            let er = [ER_1, ER_6, ER_7, ER_8, ER_9, ER_10, ER_11, ER_12];
            let e3c = [E3_1, A13_6, A13_7, A13_8, E3_9, A13_10, A13_11, E3_12];
            for j in 0..8 {
                e5 += er[j] * used[j][i][l];
                e3 += e3c[j] * used[j][i][l];
            }
            let sk = c.atol[i][l] + rtol * y[i][l].abs().max(yn[i][l].abs());
            let (q5, q3) = (e5 / sk, e3 / sk);
            s5[l] += q5 * q5;
            s3[l] += q3 * q3;
        }
    }
    rhs::<UNI, COUL>(c, cm, yn, &mut t, fzl);
    kk[12] = t;
    let mut err = [0.0; W];
    let mut fin = [true; W];
    for l in 0..W {
        let den = s5[l] + 0.01 * s3[l];
        let e = hh[l].abs() * s5[l] / (den * 6.0).sqrt();
        err[l] = if den > 0.0 {
            e
        } else if den == 0.0 {
            0.0
        } else {
            f64::NAN
        };
    }
    for i in 0..6 {
        for l in 0..W {
            fin[l] &= yn[i][l].is_finite() & kk[12][i][l].is_finite();
        }
    }
    (err, fin)
}

/// The DOP853 interpolant of each lane's step: the three extra stages, then the seven
/// coefficients of the components the event functions read.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn dense853<const UNI: bool, const COUL: bool>(
    c: &Coef,
    cm: &[bool; W],
    y: &V6,
    y1: &V6,
    k1: &V6,
    hh: &L,
    kk: &[V6; 16],
    fzl: &mut L,
) -> LaneDense {
    let mut ys = [[0.0; W]; 6];
    let mut k14 = [[0.0; W]; 6];
    let mut k15 = [[0.0; W]; 6];
    let mut k16 = [[0.0; W]; 6];
    let k = |j: usize| &kk[j - 1];
    comb(
        y,
        hh,
        [A14_1, A14_7, A14_8, A14_9, A14_10, A14_11, A14_12, A14_13],
        [k1, k(7), k(8), k(9), k(10), k(11), k(12), k(13)],
        &mut ys,
    );
    rhs::<UNI, COUL>(c, cm, &ys, &mut k14, fzl);
    comb(
        y,
        hh,
        [A15_1, A15_6, A15_7, A15_8, A15_11, A15_12, A15_13, A15_14],
        [k1, k(6), k(7), k(8), k(11), k(12), k(13), &k14],
        &mut ys,
    );
    rhs::<UNI, COUL>(c, cm, &ys, &mut k15, fzl);
    comb(
        y,
        hh,
        [A16_1, A16_6, A16_7, A16_8, A16_9, A16_13, A16_14, A16_15],
        [k1, k(6), k(7), k(8), k(9), k(13), &k14, &k15],
        &mut ys,
    );
    rhs::<UNI, COUL>(c, cm, &ys, &mut k16, fzl);
    let st = [k1, k(6), k(7), k(8), k(9), k(10), k(11), k(12), k(13), &k14, &k15, &k16];
    let rows = [
        [D4_1, D4_6, D4_7, D4_8, D4_9, D4_10, D4_11, D4_12, D4_13, D4_14, D4_15, D4_16],
        [D5_1, D5_6, D5_7, D5_8, D5_9, D5_10, D5_11, D5_12, D5_13, D5_14, D5_15, D5_16],
        [D6_1, D6_6, D6_7, D6_8, D6_9, D6_10, D6_11, D6_12, D6_13, D6_14, D6_15, D6_16],
        [D7_1, D7_6, D7_7, D7_8, D7_9, D7_10, D7_11, D7_12, D7_13, D7_14, D7_15, D7_16],
    ];
    let mut d = LaneDense { y0: [[0.0; W]; 5], c: [[[0.0; W]; 5]; 7], eight: true };
    for (j, &i) in EV_COMPS.iter().enumerate() {
        for l in 0..W {
            let h = hh[l];
            let dy = y1[i][l] - y[i][l];
            d.y0[j][l] = y[i][l];
            d.c[0][j][l] = dy;
            d.c[1][j][l] = k1[i][l] * h - dy;
            d.c[2][j][l] = dy * 2.0 - (k1[i][l] + k(13)[i][l]) * h;
            for (r, row) in rows.iter().enumerate() {
                let mut s = 0.0;
                for m in 0..12 {
                    s += (row[m] * h) * st[m][i][l];
                }
                d.c[3 + r][j][l] = s;
            }
        }
    }
    d
}

/// The scalar driver's hidden-crossing check on all lanes at once: at the three interior points
/// `x = 1/4, 1/2, 3/4` of each accepted step's interpolant, an event function that is not pending
/// and differs in sign from the step start while the step end does not. `hidden[l]` becomes the
/// first such `x` (0 where none).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn hidden_crossings<const COUL: bool>(
    c: &Coef,
    dense: &LaneDense,
    g0: &[L; NE],
    g1: &[L; NE],
    pend: &[[bool; W]; NE],
    ok: &[bool; W],
    hidden: &mut L,
) {
    let mut found = [false; W];
    for q in 1..=3 {
        let th = q as f64 / 4.0;
        let v = dense.eval(th);
        let mut g = [[0.0; W]; NE];
        for l in 0..W {
            let (z, zd, xd, ph, phd) = (v[0][l], v[1][l], v[2][l], v[3][l], v[4][l]);
            let fz = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
            g[event::GAP][l] = c.zst[l] + z;
            g[event::NORMAL][l] = c.fst[l] + fz;
            g[event::SLIP][l] = if COUL { c.v[l] - (xd + c.sl[l] * phd) } else { 1.0 };
            g[event::ESCAPE][l] = c.esc[l] - z.abs();
        }
        let mut hit = [false; W];
        for e in 0..NE {
            for l in 0..W {
                hit[l] |= !pend[e][l] & cross(g0[e][l], g[e][l]) & !cross(g0[e][l], g1[e][l]);
            }
        }
        for l in 0..W {
            let take = hit[l] & ok[l] & !found[l];
            hidden[l] = if take { th } else { hidden[l] };
            found[l] |= take;
        }
    }
}

/// `driver::crosses` without short-circuit evaluation, so that loops over lanes vectorise.
#[inline(always)]
fn cross(a: f64, b: f64) -> bool {
    ((a > 0.0) & (b <= 0.0)) | ((a < 0.0) & (b >= 0.0))
}

/// Write lane `l`'s result (ended at `(t, y)` with `outcome`) and mark it idle.
#[cold]
fn finish(ln: &mut Lanes<'_>, l: usize, t: f64, y: State, outcome: Outcome, out: &mut Vec<(usize, LaneResult)>) {
    let mut sd = ln.side[l].take().expect("finish on a live lane");
    let ext = Extremes {
        min_normal_force: ln.min_n[l],
        max_gap: ln.max_gap[l],
        min_slip_velocity: ln.min_vr[l],
        max_abs_z: ln.max_z[l],
    };
    let steps = ln.n_acc[l] + ln.n_rej[l];
    let mut stats = sd.stats;
    // DP5: six new stages per attempt (FSAL); DOP853: eleven per attempt and the derivative at
    // each accepted step's end, plus its interpolants' extra stages.
    stats.n_rhs += if ln.m8 { 11 * steps + ln.n_acc[l] + ln.n_extra[l] } else { 6 * steps };
    stats.n_accept = ln.n_acc[l];
    stats.n_reject = ln.n_rej[l];
    let escaped = y[idx::Z].abs() >= sd.s.p.escape_limit * (1.0 - 1e-9);
    let run = RunResult { status: status_of(outcome, escaped), t, y, extremes: ext, stats };
    out.push((sd.i, conclude(run, &mut sd)));
    idle(ln, l);
}

/// The task's result from a finished run and its observer.
fn conclude(run: RunResult, sd: &mut Side<'_>) -> LaneResult {
    let mut res = LaneResult { run, samples: Vec::new(), summary: None, events: Vec::new() };
    match std::mem::replace(&mut sd.obs.inner, Watch::Nothing) {
        Watch::Sample(s) => {
            let mut v = s.out;
            v.resize(s.t_eval.len(), State::repeat(f64::NAN));
            res.samples = v;
        }
        Watch::Steady(o, opts) => res.summary = Some(summarize(sd.s, &res.run, &o.w, &opts)),
        Watch::Log(v) => res.events = v,
        Watch::Nothing => {}
    }
    res
}

/// Harmless values in an idle lane: at rest, far from every end condition and event.
fn idle(ln: &mut Lanes<'_>, l: usize) {
    for k in 0..6 {
        ln.y[k][l] = 0.0;
        ln.f[k][l] = 0.0;
    }
    ln.t[l] = 0.0;
    ln.h[l] = 0.0;
    ln.c.esc[l] = f64::INFINITY;
    ln.contact[l] = true;
    for e in 0..NE {
        ln.g0[e][l] = 1.0;
        ln.pend[e][l] = false;
    }
    ln.rest[l] = f64::NEG_INFINITY;
    ln.next_sample[l] = f64::INFINITY;
    ln.side[l] = None;
}

/// Load the next trajectory that needs a step into lane `l` (trajectories that end before their
/// first step get their result here); leave the lane idle when none is left.
#[cold]
fn refill<'a>(ln: &mut Lanes<'a>, l: usize, inp: &Input<'a, '_>, out: &mut Vec<(usize, LaneResult)>) {
    loop {
        // The next trajectory of the call, shared by every worker of it.
        let i = inp.feed.fetch_add(1, Ordering::Relaxed);
        if i >= inp.sliders.len() {
            break;
        }
        let s = &inp.sliders[i];
        let y0 = inp.y0s[i];
        let t_end = inp.t_end;
        let mode = s.mode_at(&y0);
        let watch = match inp.task {
            Task::Final => Watch::Nothing,
            Task::Sampled(te) => Watch::Sample(Sampler::new(te)),
            Task::Steady { opts, decay } => {
                let o = match decay {
                    Some(d) => SteadyOptions { decay_amplitude: Some(d[i]), ..*opts },
                    None => *opts,
                };
                Watch::Steady(Box::new(SteadyObserver::new(s, &o)), o)
            }
            Task::Events => Watch::Log(Vec::new()),
        };
        let mut obs = ExtremesObserver { s, ext: Extremes::default(), inner: watch };
        obs.ext.update(s, &y0, mode);
        let opts = options_for(s, &inp.tol);
        let mut sd = Side { i, s, opts, mode, pend: [None; MAX_EVENTS], stats: Stats::default(), obs };
        let early = |outcome: Outcome, n_rhs: u64, sd: &mut Side<'a>| {
            sd.stats.n_rhs = n_rhs;
            let run = RunResult {
                status: status_of(outcome, y0[idx::Z].abs() >= s.p.escape_limit * (1.0 - 1e-9)),
                t: 0.0,
                y: y0,
                extremes: sd.obs.ext,
                stats: sd.stats,
            };
            conclude(run, sd)
        };
        if !t_end.is_finite() || !y0.iter().all(|v| v.is_finite()) {
            out.push((i, early(Outcome::NonFinite, 0, &mut sd)));
            continue;
        }
        if t_end < 0.0 {
            out.push((i, early(Outcome::StepTooSmall, 0, &mut sd)));
            continue;
        }
        if t_end == 0.0 {
            out.push((i, early(Outcome::Finished, 0, &mut sd)));
            continue;
        }
        let f0 = s.rhs(&y0, mode);
        if !f0.iter().all(|v| v.is_finite()) {
            out.push((i, early(Outcome::NonFinite, 1, &mut sd)));
            continue;
        }
        let mut n_rhs = 1;
        let order = if ln.m8 { 8 } else { 5 };
        let h0 = initial_step(s, mode, 0.0, &y0, &f0, t_end, order, &opts.atol, opts.rtol, f64::INFINITY, &mut n_rhs);
        sd.stats.n_rhs = n_rhs;
        let mut g = [0.0; MAX_EVENTS];
        s.events(0.0, &y0, mode, &mut g);
        for e in 0..NE {
            if g[e] == 0.0 {
                sd.pend[e] = Some(0.0);
            }
            ln.g0[e][l] = g[e];
            ln.pend[e][l] = g[e] == 0.0;
        }
        let atol: [f64; 6] = std::array::from_fn(|k| opts.atol[k]);
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
        ln.contact[l] = mode.in_contact();
        let e = sd.obs.ext;
        ln.min_n[l] = e.min_normal_force;
        ln.max_gap[l] = e.max_gap;
        ln.min_vr[l] = e.min_slip_velocity;
        ln.max_z[l] = e.max_abs_z;
        ln.rest[l] = f64::NEG_INFINITY;
        ln.next_sample[l] = f64::INFINITY;
        match &sd.obs.inner {
            Watch::Steady(o, _) => {
                ln.rest[l] = o.decay_floor;
                ln.peak[l] = o.w.peak_since;
                for k in 0..6 {
                    ln.peaks[k][l] = o.w.peaks_since[k];
                }
            }
            Watch::Sample(smp) => {
                ln.next_sample[l] = smp.t_eval.first().copied().unwrap_or(f64::INFINITY);
            }
            _ => {}
        }
        ln.side[l] = Some(sd);
        return;
    }
    idle(ln, l);
}

#[cfg(test)]
mod tests;
