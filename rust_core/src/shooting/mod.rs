//! Periodic orbits of the full ODE by shooting, with Floquet multipliers (MODEL.md §6).
//!
//! Unknowns: the initial state without its `zd` component (phase condition `zd(0) = 0`) and the
//! period `T`. Residual: `y(T; y0) - y0` (six equations). Newton uses the monodromy matrix
//! `Phi(T) = dy(T)/dy0` from the variational equations `Phi' = J(y) Phi`, integrated with the state
//! as one 42-dimensional system ([`Variational`]) by `ode::integrate` (DOP853 by default). At every
//! contact switch of the unilateral model the integration stops, `Phi` jumps by the saltation matrix
//!
//! ```text
//! S = I + (f+ - f-) n^T / (n^T f-)          n = grad h, h the switching function
//! ```
//!
//! (`h = zc` for the gap event, `h = N_law` for the normal-force event; for the switch friction
//! law `h = v_r -+ eta` at the stick band's edges and `h = mu_s N - |F_req|` at the stick bound),
//! and the run restarts in the new mode. Entering stick, the saltation matrix projects every
//! perturbation onto the band edge (the stick field has `d v_r/dt = 0`), so a stick-slip cycle has
//! a zero multiplier besides the trivial one. The Newton matrix is `[Phi(T) - I]` without the `zd` column, plus the column `f(y(T))`
//! for `T`. The Floquet multipliers are the eigenvalues of `Phi(T)` at the converged orbit, sorted
//! by modulus; one of them is the trivial 1 of an autonomous system, and the orbit is stable when
//! every other one has modulus below `1 - stability_tol`.
//!
//! **Hidden switches.** `ode::integrate` finds an event from the signs of its function at step
//! ends, so a hop of the pin shorter than one step (the seed bouncing cycle has a 0.19 ms hop,
//! about one DOP853 step at rtol 1e-8 to 1e-11) goes unseen and the run follows another orbit.
//! Every step is therefore checked on 8 interior points of its dense output; a step that hides a
//! switch is redone from its start with steps capped at a quarter of it (local refinement). So is
//! a step that ends in flight with the pin pressed into the disk: the pin landed while the law's
//! force was tensile (it stays in flight at the gap event) and that force turned compressive again
//! inside the same step, two crossings that cancel at the step's ends.
//!
//! The orbit is then sampled densely over one period (the 6-state integrated again, with the
//! slider's own mode switching) for its harmonics, `z_max`, the fraction of the period with the
//! contact open (`zc > 0`, from the located gap events) and the minimum normal force.

use crate::linear::eigenvalues;
use crate::model::{event, idx, ContactMode, Jacobian, Slider, State};
use crate::ode::{
    integrate, Control, EventAction, Method, Observer, OdeSystem, Options, Outcome, Stats, StepView, MAX_EVENTS,
};
use crate::status::{Failure, Status};
use crate::steady::ApproachVerdict;
use crate::tidf::{two_harmonic_argmax, Root};
use nalgebra::{Complex, SMatrix, SVector};
use std::f64::consts::PI;

type C64 = Complex<f64>;
/// State and column-major monodromy matrix `[y, Phi[:,0], ..., Phi[:,5]]`.
pub type Augmented = SVector<f64, 42>;

mod floquet;
mod newton;
mod switches;
use floquet::classify;
pub(crate) use floquet::trivial_index;
pub use floquet::{Instability, INSTABILITY_NAMES};
use newton::{shoot_impl, Newton};
#[cfg(test)]
use switches::missed_crossing;
pub use switches::*;
use switches::{join, split, Forced, StopAtSwitch};

/// Options of the shooting solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShootingOptions {
    /// Integration method (DOP853 by default).
    pub method: Method,
    /// Relative tolerance of the integration; absolute tolerances are this times the slider's
    /// characteristic sizes (`steady::characteristic_sizes`); the variational equations'
    /// `Phi` follows on the state's steps (see `options_42`).
    pub rtol: f64,
    /// Most Newton iterations.
    pub max_iter: u32,
    /// Converged when the residual `y(T) - y0`, scaled by the characteristic sizes, is below this
    /// (infinity norm), or the scaled Newton step (with `T` relative) is below `tol / 100`.
    pub tol: f64,
    /// A multiplier other than the trivial one counts as on the unit circle within this.
    pub stability_tol: f64,
    /// Uniform samples per period for the harmonics and extremes.
    pub n_samples: usize,
    /// Most contact switches in one period before the solve gives up (`EventChatter`).
    pub max_switches: u32,
}

impl Default for ShootingOptions {
    fn default() -> Self {
        ShootingOptions {
            method: Method::Dop853,
            rtol: 1e-11,
            max_iter: 30,
            tol: 1e-9,
            stability_tol: 1e-6,
            n_samples: 2048,
            max_switches: 64,
        }
    }
}

/// Harmonics of `z` over one period, `z = A0 + A1 sin(psi + a1) + A2 sin(2 psi + a2) + ...`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Harmonics {
    /// Mean [m].
    pub a0: f64,
    /// Fundamental amplitude [m].
    pub a1: f64,
    /// Second harmonic amplitude [m].
    pub a2: f64,
    /// Third harmonic amplitude [m].
    pub a3: f64,
    /// Phase of the second harmonic relative to the first, `a2 - 2 a1`, in `[0, 2 pi)` [rad]
    /// (the describing function's `theta`).
    pub theta: f64,
}

/// A periodic orbit of the full ODE (MODEL.md §6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodicOrbit {
    /// Period T [s].
    pub period: f64,
    /// 2 pi / T [rad/s].
    pub omega: f64,
    /// State at t = 0 (`zd = 0`).
    pub state0: State,
    /// Contact mode at t = 0.
    pub mode0: ContactMode,
    /// Floquet multipliers (eigenvalues of the monodromy matrix), by modulus descending.
    pub multipliers: [C64; 6],
    /// Their moduli.
    pub moduli: [f64; 6],
    /// Index in `multipliers` of the trivial multiplier (the one closest to 1).
    pub trivial: usize,
    /// `|rho_trivial - 1|`: an accuracy check of the monodromy matrix.
    pub trivial_error: f64,
    /// True when every non-trivial multiplier has modulus below `1 - stability_tol`.
    pub stable: bool,
    /// How the orbit is unstable, judged by its largest non-trivial multiplier (`Stable` when
    /// `stable`).
    pub instability: Instability,
    /// The most negative real non-trivial multiplier (NaN if none is real and negative). Near
    /// `-1` the orbit is close to a period doubling: past it (`< -1`) the attractor nearby has
    /// twice the period, and a shooting solve for that doubled orbit is singular at the crossing
    /// (`rho^2 = 1`).
    pub flip_multiplier: f64,
    /// Harmonics of `z`.
    pub harmonics: Harmonics,
    /// Largest dynamic `z` over the period [m].
    pub z_max: f64,
    /// Smallest dynamic `z` [m].
    pub z_min: f64,
    /// True if `zc = z_st + z > 0` somewhere: the pin leaves the disk (for the bilateral law, the
    /// orbit is outside the law's validity, MODEL.md §2).
    pub contact_opens: bool,
    /// Fraction of the period with `zc > 0`.
    pub open_fraction: f64,
    /// Smallest total normal force N over the period [N] (0 if the pin leaves the disk in the
    /// unilateral model; negative = tension in the bilateral model).
    pub min_normal_force: f64,
    /// Smallest value of the contact law's total force [N] (may be negative in either model).
    pub min_law_force: f64,
    /// Mode switches per period.
    pub n_switches: u32,
    /// Steps of the last monodromy integration that hid a contact switch (a hop shorter than a
    /// step) and were redone with shorter steps (see the module docs).
    pub refinements: u32,
    /// Scaled residual of the periodicity condition at the end.
    pub residual_norm: f64,
    /// Newton iterations.
    pub newton_iterations: u32,
    /// `Success`; `NewtonNotConverged`, `NotConverged` (no cycle near the start: Newton ended on
    /// steady sliding, or the start never reached the section), `InvalidInput`, `Diverged` (the
    /// escape event fired), `NotComputed` (cancelled), or an integrator status. For every status
    /// but `Success` the orbit's values are NaN (`stable` false, `instability` `Unknown`,
    /// `contact_opens` false): never those of the last iterate; only `residual_norm`,
    /// `newton_iterations` and `stats` describe the attempt.
    pub status: Status,
    /// Integrator work, summed over every integration of the solve.
    pub stats: Stats,
    /// Why the status is not `Success`, with its numbers (`None` for `Success`).
    pub failure: Option<Failure>,
}

/// Initial state and period of the shooting guess from a describing-function root: the state of
/// `z = A0 + A1 sin psi + A2 sin(2 psi + theta)`, `phi`, `x` (from the root's phasors and means)
/// at the phase `psi0` where `z` is largest (`zd = 0` there).
pub fn guess_from_root(root: &Root) -> (State, f64) {
    let (psi0, z) = two_harmonic_argmax(root.a0, root.a1, root.a2, root.theta);
    let w = root.omega;
    let e1 = C64::from_polar(1.0, psi0);
    let e2 = C64::from_polar(1.0, 2.0 * psi0);
    // |p| sin(k psi + arg p) = Im(p e^{jk psi}); its rate is k w Re(p e^{jk psi}).
    let val = |p1: C64, p2: C64| (p1 * e1).im + (p2 * e2).im;
    let rate = |p1: C64, p2: C64| w * ((p1 * e1).re + 2.0 * (p2 * e2).re);
    let y = State::new(
        z,
        0.0,
        root.x0 + val(root.x1, root.x2),
        rate(root.x1, root.x2),
        root.phi0 + val(root.phi1, root.phi2),
        rate(root.phi1, root.phi2),
    );
    (y, 2.0 * PI / w)
}

/// Periodic orbit near a describing-function root (see [`guess_from_root`] and [`shoot`]).
///
/// The root's period is used as it is (no first-return refinement: the describing function's
/// frequency is a better guess than the return time of its approximate state).
pub fn shoot_from_root(s: &Slider, root: &Root, opts: &ShootingOptions) -> PeriodicOrbit {
    let (y0, t) = guess_from_root(root);
    shoot_impl(s, &y0, t, opts, false, Newton::Full)
}

pub(crate) fn scales(s: &Slider) -> State {
    State::from(crate::steady::characteristic_sizes(s))
}

/// The step budget of one flow of an orbit (one period, or one segment of it, with its variational
/// equations), in shooting and in continuation. An orbit's period takes about 100 steps at rtol
/// 1e-11 (the seed's bouncing cycle; stick-slip cycles up to a few thousand at twenty mode
/// periods). The integrators' own budget (10^7) let one flow run for minutes: a branch of the
/// switch law under bilateral contact (the grazing curve of the issue-10 model at 0.2 m/s, 7.9 cm,
/// near 25 N) took more than ten minutes in one continuation point's flows, and with it the
/// sweep's boundary stage. Past this budget the flow fails with `max_steps`, as an orbit that
/// does not converge: shooting reports it per point, continuation halves its step and ends with
/// the reason.
pub(crate) const ORBIT_FLOW_MAX_STEPS: u64 = 50_000;

fn options_42(s: &Slider, rtol: f64) -> Options<42> {
    let sz = scales(s);
    // The step is controlled by the state alone, as in a flow of the state (`rtol` and its
    // characteristic sizes): `Phi` follows on the same steps (the derivative of the discrete
    // flow), its tolerance infinite, and the state's tolerances are divided by sqrt(7) because the
    // integrator's error norm is the RMS over all 42 components. With `Phi` in the norm the
    // state's six weighed a seventh: over one period of the seed's flip orbit at rtol 1e-9 the
    // state ended 6.8e-8 (scaled) off against 6.0e-9 for the state's own flow, and its 0.998
    // multiplier left Newton's orbit 1.7e-5 off.
    let w = 7f64.sqrt();
    let mut o = Options::<42>::new(rtol / w, f64::INFINITY);
    o.max_steps = ORBIT_FLOW_MAX_STEPS;
    for i in 0..6 {
        o.atol[i] = rtol * sz[i] / w;
    }
    o
}

/// One period of the flow with its monodromy matrix.
struct Flow {
    y: State,
    phi: Jacobian,
    mode: ContactMode,
    n_switches: u32,
    refinements: u32,
}

/// Integrate `y0` (mode `mode0`) with its variational equations over `[0, t_end]`, applying the
/// saltation matrix at every switch, with the local refinement of [`run_watched`] (unilateral
/// model only: the bilateral flow has no switches to hide).
fn flow(
    s: &Slider,
    y0: &State,
    mode0: ContactMode,
    t_end: f64,
    opts: &ShootingOptions,
    o42: &Options<42>,
    stats: &mut Stats,
) -> Result<Flow, Status> {
    let mut t = 0.0;
    let mut y = join(y0, &Jacobian::identity());
    let mut mode = mode0;
    let mut n_switches = 0;
    let mut cap = Cap::NONE;
    loop {
        let mut obs = StopAtSwitch { hit: None };
        let make = |m| Variational { slider: s, start: m };
        let sol = run_watched(make, s, opts.method, t, y, mode, t_end, o42, false, &mut cap, &mut obs, stats);
        let (ye, phie) = split(&sol.y);
        match sol.outcome {
            Outcome::Finished => {
                return Ok(Flow { y: ye, phi: phie, mode: sol.mode, n_switches, refinements: cap.refinements })
            }
            Outcome::StoppedByObserver => {
                let Some((index, before, after)) = obs.hit else { return Err(Status::NotConverged) };
                n_switches += 1;
                if n_switches > opts.max_switches {
                    return Err(Status::EventChatter);
                }
                let sm = saltation(s, &ye, before, after, index);
                if !sm.iter().all(|v| v.is_finite()) {
                    return Err(Status::NonFinite);
                }
                t = sol.t;
                y = join(&ye, &(sm * phie));
                mode = after;
            }
            Outcome::StoppedByEvent => return Err(Status::Diverged),
            other => return Err(other.status()),
        }
    }
}

/// The free unknowns: every state component except `zd` (fixed at 0 by the phase condition).
pub(crate) const FREE: [usize; 5] = [idx::Z, idx::X, idx::XD, idx::PHI, idx::PHID];

/// The check of a run's slow approach ([`crate::steady::ApproachCheck`]): shooting from the section
/// state `y` over `period` at integration tolerance `rtol` and Newton tolerance `tol` (20
/// iterations at most, as `tribosweep._cycles.CHECK_MAX_ITER`), held to the period (1 %).
///
/// The stop is within [`crate::steady::APPROACH_TOL`] of the orbit and its period is the run's
/// own repetition time, so the check starts Newton there (no first return) and iterates on the
/// chord ([`Newton::Chord`]).
pub fn approach_check(s: &Slider, y: &State, period: f64, rtol: f64, tol: f64) -> (ApproachVerdict, Stats) {
    let opts = ShootingOptions { rtol, tol, max_iter: 20, n_samples: 256, ..ShootingOptions::default() };
    let orb = shoot_impl(s, y, period, &opts, false, Newton::Chord);
    let same = orb.status == Status::Success && (orb.period / period - 1.0).abs() <= 1e-2;
    let verdict = match (same, orb.stable) {
        (true, true) => ApproachVerdict::Stable { state0: orb.state0, period: orb.period },
        (true, false) => ApproachVerdict::Unstable {
            // The largest non-trivial multiplier (the trivial one, about 1, may come first).
            largest: orb.moduli[(0..6).find(|&k| k != orb.trivial).unwrap_or(0)],
            period: orb.period,
            a1: orb.harmonics.a1,
            kind: orb.instability.code(),
        },
        _ => ApproachVerdict::Nothing,
    };
    (verdict, orb.stats)
}

/// Periodic orbit through the neighbourhood of `y0` with period near `period` (MODEL.md §6).
///
/// If `y0` has `zd != 0` it is first carried along the flow to the next maximum of `z` (the
/// section `zd = 0`, `zd` decreasing), at most `2 period` ahead. The period guess is then replaced
/// by the first return to that section near it (the crossing within `[0.5, 1.5] period` closest
/// to `y0`): a 1 % error in `T` leaves the end point far from `y0` in the fast velocities and can
/// send Newton to another orbit or to steady sliding. Newton then solves
/// `y(T; y0) = y0` with `zd(0) = 0` (see the module docs), damped by halving the step while the
/// scaled residual grows.
///
/// # Errors
/// A failure is in `status` (see [`PeriodicOrbit::status`]), never a panic.
pub fn shoot(s: &Slider, y0: &State, period: f64, opts: &ShootingOptions) -> PeriodicOrbit {
    shoot_impl(s, y0, period, opts, true, Newton::Full)
}

/// The result of a solve that found no orbit: NaN values (never the last iterate), the failure's
/// status and the attempt's residual, iterations and work.
fn unconverged(failure: Failure, residual: f64, iterations: u32, stats: Stats) -> PeriodicOrbit {
    let mut o = failed(State::repeat(f64::NAN), f64::NAN, failure.status(), stats);
    o.residual_norm = residual;
    o.newton_iterations = iterations;
    o.failure = Some(failure);
    o
}

impl PeriodicOrbit {
    /// An orbit that was not computed (NaN everywhere) with `status`, e.g. after a panic.
    pub fn not_computed(status: Status) -> Self {
        failed(State::repeat(f64::NAN), f64::NAN, status, Stats::default())
    }
}

fn failed(y: State, t: f64, status: Status, stats: Stats) -> PeriodicOrbit {
    let nan = f64::NAN;
    PeriodicOrbit {
        period: t,
        omega: 2.0 * PI / t,
        state0: y,
        mode0: ContactMode::Contact,
        multipliers: [C64::new(nan, nan); 6],
        moduli: [nan; 6],
        trivial: 0,
        trivial_error: nan,
        stable: false,
        instability: Instability::Unknown,
        flip_multiplier: nan,
        harmonics: Harmonics { a0: nan, a1: nan, a2: nan, a3: nan, theta: nan },
        z_max: nan,
        z_min: nan,
        contact_opens: false,
        open_fraction: nan,
        min_normal_force: nan,
        min_law_force: nan,
        n_switches: 0,
        refinements: 0,
        residual_norm: nan,
        newton_iterations: 0,
        status,
        stats,
        failure: None,
    }
}

/// Crossings of the section `zd = 0` with `zd` decreasing (maxima of `z`), located on the dense
/// output by bisection; the run stops after `max_hits` of them.
struct Section {
    hits: Vec<(f64, State)>,
    max_hits: usize,
}

impl Observer<6, ContactMode> for Section {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        let (a, b) = (st.y0[idx::ZD], st.y1[idx::ZD]);
        // Sub-sample the step so that two crossings inside one long step are not missed.
        const SUB: usize = 4;
        let mut prev = (st.t0, a);
        for k in 1..=SUB {
            let tk = if k == SUB { st.t1 } else { st.t0 + (st.t1 - st.t0) * k as f64 / SUB as f64 };
            let vk = if k == SUB { b } else { st.dense.eval(tk)[idx::ZD] };
            if prev.1 > 0.0 && vk <= 0.0 && prev.0 > 0.0 {
                let (mut lo, mut hi) = (prev.0, tk);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if st.dense.eval(mid)[idx::ZD] > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let y = if hi == st.t1 { *st.y1 } else { st.dense.eval(hi) };
                self.hits.push((hi, y));
                if self.hits.len() >= self.max_hits {
                    return Control::Stop;
                }
            }
            prev = (tk, vk);
        }
        Control::Continue
    }
}

fn section_crossings(
    s: &Slider,
    y: &State,
    t_max: f64,
    max_hits: usize,
    opts: &ShootingOptions,
    stats: &mut Stats,
) -> Vec<(f64, State)> {
    let o = crate::steady::options_for(s, &crate::steady::Tolerances::new(opts.rtol.max(1e-10)));
    let mut obs = Section { hits: Vec::new(), max_hits };
    let make = |m| Forced { slider: s, start: m };
    let mut cap = Cap::NONE;
    run_watched(make, s, opts.method, 0.0, *y, s.mode_at(y), t_max, &o, false, &mut cap, &mut obs, stats);
    obs.hits
}

/// Carries `y` along the flow to the next point with `zd = 0` and `zd` decreasing (a maximum of `z`).
fn to_section(s: &Slider, y: &State, t_max: f64, opts: &ShootingOptions, stats: &mut Stats) -> Option<State> {
    section_crossings(s, y, t_max, 1, opts, stats).first().map(|h| h.1)
}

/// First return to the section near `t_guess`: the crossing with time in `[0.5, 1.5] t_guess`
/// whose state is closest to `y0` (scaled); `t_guess` if there is none.
fn first_return(s: &Slider, y0: &State, t_guess: f64, opts: &ShootingOptions, stats: &mut Stats) -> f64 {
    let sz = scales(s);
    let hits = section_crossings(s, y0, 1.5 * t_guess, 64, opts, stats);
    hits.iter()
        .filter(|(t, _)| *t >= 0.5 * t_guess)
        .min_by(|a, b| (a.1 - y0).component_div(&sz).amax().total_cmp(&(b.1 - y0).component_div(&sz).amax()))
        .map_or(t_guess, |h| h.0)
}

/// Dense samples and gap events over one period.
struct Recorder {
    t_eval: Vec<f64>,
    z: Vec<f64>,
    min_n: f64,
    min_law: f64,
    z_min: f64,
    z_max: f64,
    gap_events: Vec<f64>,
    switches: u32,
    slider: Slider,
}

impl Observer<6, ContactMode> for Recorder {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        while let Some(&t) = self.t_eval.get(self.z.len()) {
            if t > st.t1 {
                break;
            }
            let v = if t <= st.t0 {
                *st.y0
            } else if t == st.t1 {
                *st.y1
            } else {
                st.dense.eval(t)
            };
            self.z.push(v[idx::Z]);
            let f = self.slider.forces(&v, st.mode);
            self.min_n = self.min_n.min(f.normal);
            self.min_law = self.min_law.min(f.normal_law);
            // Extremes: samples plus a parabola through the last three samples near a turn.
            let n = self.z.len();
            self.z_max = self.z_max.max(v[idx::Z]);
            self.z_min = self.z_min.min(v[idx::Z]);
            if n >= 3 {
                let (a, b, c) = (self.z[n - 3], self.z[n - 2], self.z[n - 1]);
                let curv = a - 2.0 * b + c;
                if (b >= a && b >= c) || (b <= a && b <= c) {
                    let ext = if curv != 0.0 { b - (c - a) * (c - a) / (8.0 * curv) } else { b };
                    self.z_max = self.z_max.max(ext);
                    self.z_min = self.z_min.min(ext);
                }
            }
        }
        // The step end point too (a switch lands on it exactly).
        let f = self.slider.forces(st.y1, st.mode);
        self.min_n = self.min_n.min(f.normal);
        self.min_law = self.min_law.min(f.normal_law);
        Control::Continue
    }

    fn on_event(&mut self, index: usize, t: f64, _y: &State, before: ContactMode, after: ContactMode) -> Control {
        if index == event::GAP {
            self.gap_events.push(t);
        }
        if before != after {
            self.switches += 1;
        }
        Control::Continue
    }
}

fn analyse(s: &Slider, y0: &State, t: f64, fl: &Flow, opts: &ShootingOptions, stats: &mut Stats) -> PeriodicOrbit {
    let m = opts.n_samples.max(16);
    let o = crate::steady::options_for(s, &crate::steady::Tolerances::new(opts.rtol));
    let mut rec = Recorder {
        t_eval: (0..m).map(|k| t * k as f64 / m as f64).collect(),
        z: Vec::with_capacity(m),
        min_n: f64::INFINITY,
        min_law: f64::INFINITY,
        z_min: f64::INFINITY,
        z_max: f64::NEG_INFINITY,
        gap_events: Vec::new(),
        switches: 0,
        slider: *s,
    };
    // Every gap crossing counts here (the open fraction), also in the bilateral model.
    let make = |m| Forced { slider: s, start: m };
    let mut cap = Cap::NONE;
    let sol = run_watched(make, s, opts.method, 0.0, *y0, s.mode_at(y0), t, &o, true, &mut cap, &mut rec, stats);
    let mut out = failed(*y0, t, sol.outcome.status(), *stats);
    if sol.outcome == Outcome::StoppedByEvent {
        out.status = Status::Diverged;
    }
    out.mode0 = s.mode_at(y0);
    // Floquet multipliers.
    if let Some(ev) = eigenvalues(&fl.phi) {
        let mut ev = ev;
        ev.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
        let trivial = trivial_index(&ev);
        out.multipliers = ev;
        out.moduli = ev.map(|e| e.norm());
        out.trivial = trivial;
        out.trivial_error = (ev[trivial] - 1.0).norm();
        out.stable = (0..6).filter(|&k| k != trivial).all(|k| out.moduli[k] < 1.0 - opts.stability_tol);
        (out.instability, out.flip_multiplier) = classify(&ev, trivial, out.stable);
    } else {
        out.status = Status::NonFinite;
    }
    if rec.z.len() == m {
        // Fourier integrals on the uniform samples (trapezoid rule on one period).
        let coef = |k: usize| {
            let (mut a, mut b) = (0.0, 0.0);
            for (n, z) in rec.z.iter().enumerate() {
                let (sn, cs) = (2.0 * PI * (k * n) as f64 / m as f64).sin_cos();
                a += z * cs;
                b += z * sn;
            }
            // z_k = a cos + b sin = A sin(k psi + alpha), A sin alpha = a, A cos alpha = b
            let (a, b) = (2.0 * a / m as f64, 2.0 * b / m as f64);
            (a.hypot(b), a.atan2(b))
        };
        let a0 = rec.z.iter().sum::<f64>() / m as f64;
        let (a1, al1) = coef(1);
        let (a2, al2) = coef(2);
        let (a3, _) = coef(3);
        out.harmonics = Harmonics { a0, a1, a2, a3, theta: (al2 - 2.0 * al1).rem_euclid(2.0 * PI) };
        out.z_max = rec.z_max;
        out.z_min = rec.z_min;
        out.min_normal_force = rec.min_n;
        out.min_law_force = rec.min_law;
    }
    // Fraction of the period with the contact open, from the located gap crossings.
    let mut open = s.gap(y0) > 0.0;
    let mut t_prev = 0.0;
    let mut acc = 0.0;
    for &te in &rec.gap_events {
        if open {
            acc += te - t_prev;
        }
        open = !open;
        t_prev = te;
    }
    if open {
        acc += t - t_prev;
    }
    out.open_fraction = acc / t;
    out.contact_opens = s.gap(y0) > 0.0 || !rec.gap_events.is_empty() || s.z_st + out.z_max > 0.0;
    out.n_switches = fl.n_switches;
    out.refinements = fl.refinements;
    out
}

#[cfg(test)]
pub(crate) mod tests;
