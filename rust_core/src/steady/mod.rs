//! Trajectories of the slider: plain runs, sampled runs, and runs to a steady state with a summary.
//!
//! A run to steady state ends when the motion
//! - **decays** to steady sliding: the largest `|z|` over a window of Poincare sections is below
//!   `decay_amplitude` and below the window before it (the motion is small and shrinking);
//! - **settles on a periodic state**: on the Poincare section `zd = 0`, `z` at a maximum (crossing
//!   of `zd` from + to -), the section state repeats after `p` crossings (`p = 1..=MAX_MULTIPLICITY`,
//!   the smallest `p` wins, so a cycle with several maxima of `z` per period is still found) to
//!   `periodic_tol` relative to each component's range over the window, twice in a row;
//! - **escapes** the model's validity: `|z|` reaches the escape limit (an event);
//! - is **irregular**, where `irregular_block > 0`: bounded, neither repeating nor decaying, with
//!   its section statistics stationary over three blocks (`section.rs`);
//! - or reaches `t_max` without any of these (status `NotConverged`).
//!
//! For a periodic state the summary re-integrates one period from the section state and takes
//! Fourier integrals of uniform dense-output samples: DC and harmonics 1-3 of `z` with phases
//! relative to `z1`, the first harmonics of `phi` and `x`, the minimum total normal force, the
//! fraction of the period with the pin off the disk (`zc > 0`, from located contact events) and the
//! minimum sliding velocity. Phases are `alpha` in `|.| sin(k psi + alpha)`, `psi = w t` with the phase
//! of `z1` set to 0 (MODEL.md §5), in radians in `[0, 2 pi)`.

use crate::model::{idx, ContactMode, ContactModel, FrictionLaw, Slider, State};
use crate::ode::{integrate, Control, Method, Observer, Options, Outcome, Sampler, Stats, StepView};
use crate::status::{Failure, Status};
use nalgebra::SVector;

/// Largest period multiplicity (section crossings per period) looked for.
pub const MAX_MULTIPLICITY: usize = 8;

/// Tolerances and limits of a plain integration, with per-component absolute tolerances scaled to
/// the slider.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance (> 0).
    pub rtol: f64,
    /// Absolute tolerance per component; `None`: `rtol` times [`characteristic_sizes`].
    pub atol: Option<[f64; 6]>,
    /// Step budget (accepted + rejected); `None`: [`Options::new`]'s default.
    pub max_steps: Option<u64>,
    /// Event budget before `EventChatter`; `None`: [`Options::new`]'s default.
    pub max_events: Option<u64>,
}

impl Tolerances {
    /// `rtol` with default absolute tolerances and limits.
    pub fn new(rtol: f64) -> Self {
        Tolerances { rtol, atol: None, max_steps: None, max_events: None }
    }

    /// True when a limit differs from the defaults.
    pub fn has_limits(&self) -> bool {
        self.max_steps.is_some() || self.max_events.is_some()
    }
}

/// Characteristic size of each state component [m, m/s, m, m/s, rad, rad/s]: `|z_st|` for `z` and
/// `x`, the twist `|z_st|/L` that moves the contact by `|z_st|` for `phi` (`|z_st|` if `L = 0`), and
/// those times the torsional frequency for the rates. Default absolute tolerances are `rtol` times
/// these, so that a tolerance means the same relative accuracy on every component.
pub fn characteristic_sizes(s: &Slider) -> [f64; 6] {
    let z = s.z_st.abs();
    let phi = if s.p.moment_arm > 0.0 { z / s.p.moment_arm } else { z };
    let w = s.p.omega_torsion;
    [z, z * w, z, z * w, phi, phi * w]
}

/// Integration options for `s` at the given tolerances.
pub fn options_for(s: &Slider, tol: &Tolerances) -> Options<6> {
    let sizes = characteristic_sizes(s);
    let atol = tol.atol.unwrap_or(sizes.map(|v| v * tol.rtol));
    let mut o = Options::<6>::new(tol.rtol, 1.0);
    o.atol = SVector::<f64, 6>::from(atol);
    if let Some(n) = tol.max_steps {
        o.max_steps = n;
    }
    if let Some(n) = tol.max_events {
        o.max_events = n;
    }
    if s.p.contact == ContactModel::Unilateral || s.p.friction_law == FrictionLaw::Switch {
        // A hop off the disk can be shorter than one step (0.19 ms on the seed's bouncing cycle,
        // about one step at rtol 1e-8): check the contact functions inside every step too. The
        // switch law's band is as narrow as the user makes it: a slip that dips into the band and
        // out again within a step is caught the same way.
        o.interior_checks = 3;
    }
    o
}

/// Extremes seen along a run: the validity checks of MODEL.md §2-3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extremes {
    /// Minimum total normal force N [N] (0 while the pin is off the disk in the unilateral model).
    pub min_normal_force: f64,
    /// Largest `zc = z_st + z` [m]; `> 0` means the contact opened (for the bilateral law: outside its validity).
    pub max_gap: f64,
    /// Minimum sliding velocity `v_r` [m/s]; `<= 0` means stick-slip (the constant-mu law is invalid there).
    pub min_slip_velocity: f64,
    /// Largest `|z|` [m].
    pub max_abs_z: f64,
}

impl Default for Extremes {
    fn default() -> Self {
        Extremes {
            min_normal_force: f64::INFINITY,
            max_gap: f64::NEG_INFINITY,
            min_slip_velocity: f64::INFINITY,
            max_abs_z: 0.0,
        }
    }
}

impl Extremes {
    #[inline]
    pub(crate) fn update(&mut self, s: &Slider, y: &State, mode: ContactMode) {
        // `Slider::forces`'s normal force and sliding velocity (the same expressions), without
        // its friction law (an exponential under Stribeck's).
        let normal = if mode.in_contact() { s.p.normal_load + s.dynamic_law_force(y) } else { 0.0 };
        self.min_normal_force = self.min_normal_force.min(normal);
        self.max_gap = self.max_gap.max(s.gap(y));
        self.min_slip_velocity = self.min_slip_velocity.min(s.slip_velocity(y));
        self.max_abs_z = self.max_abs_z.max(y[idx::Z].abs());
    }
}

/// Result of a plain run.
#[derive(Clone, Copy, Debug)]
pub struct RunResult {
    /// Status of the run (`Diverged` when the escape event stopped it).
    pub status: Status,
    /// Time reached [s].
    pub t: f64,
    /// State reached.
    pub y: State,
    /// Extremes at step ends and events.
    pub extremes: Extremes,
    /// Work counters.
    pub stats: Stats,
    /// Why the run did not succeed, with its numbers (`None` for `Success`).
    pub failure: Option<Failure>,
}

impl RunResult {
    /// The result of a run that could not be computed: `status`, NaN state and time, no work.
    pub fn failed(status: Status, failure: Option<Failure>) -> Self {
        RunResult {
            status,
            t: f64::NAN,
            y: State::repeat(f64::NAN),
            extremes: Extremes::default(),
            stats: Stats::default(),
            failure,
        }
    }
}

/// The failure behind a run of `s` from `t = 0` towards `t_end` under `opts` that ended with
/// `status` at `(t, y)` with step size `h` after `steps` attempted steps (`None` for `Success`).
/// Shared by the scalar driver and the lane-batched paths, so that every route gives the same text.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_failure(
    status: Status,
    s: &Slider,
    t: f64,
    y: &State,
    h: f64,
    steps: u64,
    t_end: f64,
    opts: &Options<6>,
) -> Option<Failure> {
    Some(match status {
        Status::Success => return None,
        Status::MaxSteps => Failure::MaxSteps { max_steps: opts.max_steps, t, t_end },
        Status::StepTooSmall if t_end < 0.0 => Failure::Backwards { t0: 0.0, t_end },
        Status::StepTooSmall => {
            Failure::StepTooSmall { t, h, floor: opts.h_min_rel * t.abs().max(1.0), rtol: opts.rtol }
        }
        Status::NonFinite if steps == 0 && h.is_nan() => Failure::NonFiniteStart { t },
        Status::NonFinite => Failure::NonFinite { t, h },
        Status::EventChatter => Failure::EventChatter { max_events: opts.max_events, t },
        Status::Diverged => Failure::Escaped { t, z: y[idx::Z], limit: s.p.escape_limit },
        Status::EventMissed => {
            Failure::EventMissed { t, z: y[idx::Z], gap: s.gap(y), force: s.p.normal_load + s.dynamic_law_force(y) }
        }
        Status::NotComputed => Failure::Cancelled { t },
        other => Failure::Ended { status: other, t },
    })
}

pub(crate) struct ExtremesObserver<'a, O> {
    pub(crate) s: &'a Slider,
    pub(crate) ext: Extremes,
    pub(crate) inner: O,
}

impl<O: Observer<6, ContactMode>> Observer<6, ContactMode> for ExtremesObserver<'_, O> {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        self.ext.update(self.s, st.y1, st.mode);
        self.inner.on_step(st)
    }
    fn on_event(&mut self, i: usize, t: f64, y: &State, before: ContactMode, after: ContactMode) -> Control {
        self.ext.update(self.s, y, before);
        self.ext.update(self.s, y, after);
        self.inner.on_event(i, t, y, before, after)
    }
}

pub(crate) fn status_of(outcome: Outcome, escaped: bool) -> Status {
    if outcome == Outcome::StoppedByEvent && escaped {
        Status::Diverged
    } else {
        outcome.status()
    }
}

/// The status of a run of `s` that ended with `outcome` at `y` in `mode`: [`status_of`], except
/// that an escape in free flight inside the disk (gap < 0 with a positive law force: a state
/// that is in contact by both conditions) is [`Status::EventMissed`]. Only a missed contact event
/// gets there: in contact, 1 mm of penetration would take about 25 kN.
pub(crate) fn end_status(s: &Slider, outcome: Outcome, y: &State, mode: ContactMode) -> Status {
    let escaped = y[idx::Z].abs() >= s.p.escape_limit * (1.0 - 1e-9);
    match status_of(outcome, escaped) {
        Status::Diverged
            if mode == ContactMode::Free && s.gap(y) < 0.0 && s.p.normal_load + s.dynamic_law_force(y) > 0.0 =>
        {
            Status::EventMissed
        }
        st => st,
    }
}

/// Integrate `s` from `y0` at `t = 0` to `t_end`, observed by `obs`.
pub fn run_observed<O: Observer<6, ContactMode>>(
    s: &Slider,
    y0: &State,
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    obs: O,
) -> (RunResult, O) {
    let opts = options_for(s, tol);
    let mut o = ExtremesObserver { s, ext: Extremes::default(), inner: obs };
    o.ext.update(s, y0, s.mode_at(y0));
    let sol = integrate(s, method, 0.0, *y0, t_end, &opts, &mut o);
    let status = end_status(s, sol.outcome, &sol.y, sol.mode);
    let steps = sol.stats.n_accept + sol.stats.n_reject;
    let failure = run_failure(status, s, sol.t, &sol.y, sol.h, steps, t_end, &opts);
    (RunResult { status, t: sol.t, y: sol.y, extremes: o.ext, stats: sol.stats, failure }, o.inner)
}

/// Integrate to `t_end` and return the end state.
pub fn run(s: &Slider, y0: &State, t_end: f64, method: Method, tol: &Tolerances) -> RunResult {
    run_observed(s, y0, t_end, method, tol, crate::ode::NoObserver).0
}

/// Integrate to `t_end` and sample the state at increasing `t_eval` (times past the end of a run
/// that stopped early are filled with NaN).
pub fn run_sampled(
    s: &Slider,
    y0: &State,
    t_end: f64,
    method: Method,
    tol: &Tolerances,
    t_eval: &[f64],
) -> (RunResult, Vec<State>) {
    let (r, sampler) = run_observed(s, y0, t_end, method, tol, Sampler::new(t_eval));
    let mut out = sampler.out;
    out.resize(t_eval.len(), State::repeat(f64::NAN));
    (r, out)
}

/// Records every accepted step end and event point (the solver's natural output).
pub struct StepRecorder {
    /// Times [s].
    pub t: Vec<f64>,
    /// States.
    pub y: Vec<State>,
}

impl Observer<6, ContactMode> for StepRecorder {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        if self.t.is_empty() {
            self.t.push(st.t0);
            self.y.push(*st.y0);
        }
        self.t.push(st.t1);
        self.y.push(*st.y1);
        Control::Continue
    }
}

/// How a run to steady state ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum SteadyOutcome {
    /// The motion decayed to steady sliding.
    Decayed = 0,
    /// The motion settled on a periodic state.
    Periodic = 1,
    /// `|z|` reached the escape limit.
    Diverged = 2,
    /// `t_max` was reached with neither (see the status for failures).
    Unsettled = 3,
    /// The integration failed (see the status).
    Failed = 4,
    /// Sustained irregular motion: bounded, and its statistics on the section stationary over
    /// three blocks while it neither repeats nor decays (only with `SteadyOptions::irregular_block`).
    Irregular = 5,
}

impl SteadyOutcome {
    /// Machine name.
    pub fn name(self) -> &'static str {
        match self {
            SteadyOutcome::Decayed => "decayed",
            SteadyOutcome::Periodic => "periodic",
            SteadyOutcome::Diverged => "diverged",
            SteadyOutcome::Unsettled => "unsettled",
            SteadyOutcome::Failed => "failed",
            SteadyOutcome::Irregular => "irregular",
        }
    }
}

/// Settings of a run to steady state.
// `approach_check` is a function pointer: equal options hold the same one (there is one checker,
// `crate::shooting::approach_check`), and nothing decides by comparing them.
#[allow(unpredictable_function_pointer_comparisons)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteadyOptions {
    /// Longest simulated time [s].
    pub t_max: f64,
    /// Integrator.
    pub method: Method,
    /// Tolerances.
    pub tol: Tolerances,
    /// Relative tolerance of the section-state repetition that declares a periodic state.
    pub periodic_tol: f64,
    /// The repetition tolerance that sets the stationarity test's residual floor
    /// ([`STATIONARY_FLOOR`] times it, at least [`STATIONARY_MIN_RESIDUAL`]);
    /// `None`: `periodic_tol`. Runs whose stops repeat to a loose `periodic_tol`, each stop then
    /// checked by shooting (the census's first stops), keep the floor of the strict tolerance:
    /// what counts as irregular motion does not move with the stops.
    pub stationary_tol: Option<f64>,
    /// No periodic state is declared at a section crossed before this time [s]: a run going on
    /// from near an unstable cycle repeats there at first (0: no hold).
    pub hold: f64,
    /// Amplitude below which a shrinking motion counts as decayed [m of z]; every component is
    /// compared in units of its characteristic size times `decay_amplitude / |z_st|`.
    /// `None`: `1e-3 |z_st|`.
    pub decay_amplitude: Option<f64>,
    /// Amplitudes of each component [m, m/s, m, m/s, rad, rad/s] below which a shrinking motion
    /// counts as decayed: the motion's shape, not only its size. Overrides `decay_amplitude` (the
    /// census sets it to a fraction of the saddle cycle's own amplitude in every component).
    pub decay_thresholds: Option<[f64; 6]>,
    /// Sections per window of the decay test.
    pub decay_window: usize,
    /// Uniform samples per period for the Fourier integrals.
    pub n_fourier: usize,
    /// Whether the repetition and decay tests look at `x` and `xd` where they are slaved. Under
    /// constant friction nothing in the `z` and `phi` equations depends on them, so the attractor
    /// of the motion is decided in `(z, zd, phi, phid)` alone while `x` still rings down at its own
    /// light damping (`zeta_x omega_x`, about 1 1/s: some 12 s to a 1e-5 repetition). The census,
    /// which asks which attractor, turns this off; runs that report `x`'s amplitude keep it. Under
    /// a speed-dependent law `x` acts back through the sliding velocity and is always watched.
    pub watch_x: bool,
    /// Every periodic stop of these runs is checked by shooting (the census's first stops, at a
    /// loose `periodic_tol`): `x` and `xd` then need only repeat to
    /// [`CHECKED_X_SLACK`] times `periodic_tol`. The stop only says where to shoot from;
    /// shooting converges on the whole state, `x` included, and decides. Under a speed-dependent
    /// law `x` is the lightly damped friction mode (multiplier about 0.993 a period), whose
    /// ring-down otherwise holds a stop back by seconds after the motion in `z` and `phi` has
    /// settled.
    pub checked_stops: bool,
    /// Sections per block of the stationarity test that stops sustained irregular motion early
    /// ([`SteadyOutcome::Irregular`]); 0 turns it off (the run then goes on to `t_max`).
    pub irregular_block: usize,
    /// Periods per block of the slow-approach test, whose approach is then checked by shooting
    /// inside the run ([`Summary::approach`]; 0: off, the run waits for the repetition to
    /// `periodic_tol`): the largest repetition residual of `(z, zd, phi, phid)` (the check shoots
    /// on the whole state, and `x`'s light damping under a speed-dependent law would hold the
    /// trigger back: on the switch-law Stribeck sweep the transients' right-hand sides fell by 8 %,
    /// 20.0 -> 17.9 million, with no regime changed) after some `p` sections over blocks of
    /// `approach_periods * p` sections has shrunk over three blocks in a row to at most
    /// [`APPROACH_TOL`]. A run converging on a cycle whose slowest multiplier `mu`
    /// is near 1 otherwise takes `ln(APPROACH_TOL / periodic_tol) / ln(1 / |mu|)` periods more
    /// (660 at the Stribeck sweep's 0.993). Shooting from there (`approach_check`) converges on
    /// the cycle: a stable orbit of the same period (to 1 %) ends the run on it, measured on the
    /// orbit; near an unstable one the run goes on, declaring no cycle until a deviation along
    /// its largest multiplier has grown a thousandfold (4 to 1,000 periods); where shooting
    /// fails or finds another period, the run goes on with the approach test off. In the run, so
    /// that a run going on keeps its lane and its place in the call.
    pub approach_periods: usize,
    /// The check of [`Self::approach_periods`]' stops (`None`: no approach test), with its
    /// integration tolerance and Newton tolerance. Shooting lives above this module, which
    /// hands it in (`crate::shooting::approach_check`), so that the modules stay a hierarchy.
    pub approach_check: Option<ApproachCheck>,
    /// Integration tolerance of the approach checks, and of the run on a stable orbit that
    /// measures it (the run's own `tol` only found the cycle).
    pub approach_rtol: f64,
    /// Newton tolerance of the approach checks.
    pub approach_tol: f64,
    /// Fingerprints of irregular attractors already established at this point (by other runs of
    /// the same model): a block of sections that matches one of them ends the run as irregular
    /// without waiting for three stationary blocks ([`Fingerprint`]; only with `irregular_block > 0`).
    pub known_irregular: Known,
}

/// What shooting from a slow approach's stop found ([`ApproachCheck`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ApproachVerdict {
    /// A stable orbit of the stop's period (to 1 %): its state on the section and its period.
    Stable { state0: State, period: f64 },
    /// An unstable orbit of that period: its largest non-trivial multiplier's modulus, its period, the
    /// amplitude of z's first harmonic on it (with the period, the orbit's identity whatever
    /// section point the check started from) and how it is unstable (the code of
    /// `shooting::Instability`: 1 fold, 2 flip, 3 torus).
    Unstable { largest: f64, period: f64, a1: f64, kind: u8 },
    /// No orbit of that period (Newton failed, or converged on another period).
    Nothing,
}

/// Intermittent motion: laminar phases near one unstable cycle, each ended by a burst away from it
/// and followed by a return (reinjection), as in Pomeau-Manneville intermittency. Slow-approach
/// checks (`SteadyOptions::approach_periods`) found the same unstable orbit (period and A1 to
/// [`SAME_SADDLE`]) [`INTERMITTENT_VISITS`] times, the run each time having left it by at least
/// [`DEPART_TOL`] between. Sustained motion that keeps coming back to a saddle: irregular.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intermittent {
    /// Period of the unstable cycle [s].
    pub period: f64,
    /// Modulus of its largest non-trivial Floquet multiplier (above 1, or within the shooting's
    /// stability tolerance of it: the cycle is not stable).
    pub largest: f64,
    /// The laminar phases found near it.
    pub visits: u32,
    /// How the cycle is unstable (`shooting::Instability`'s code: 1 fold, a real multiplier above
    /// 1; 2 flip, below -1; 3 torus, a complex pair), the mechanism of Pomeau-Manneville's types
    /// I, III and II.
    pub kind: u8,
}

/// Laminar phases near one unstable cycle after which a run stops as intermittent ([`Intermittent`]).
pub const INTERMITTENT_VISITS: u32 = 3;
/// The repetition residual (relative, as the slow-approach test's) after the cycle's sections by
/// which a run has left an unstable cycle between two visits: ten times [`APPROACH_TOL`], where a
/// laminar phase ends.
pub const DEPART_TOL: f64 = 10.0 * APPROACH_TOL;
/// Two checks found the same unstable cycle where their periods and A1 agree to this (relative;
/// each converged to the shooting tolerance, far below it).
pub const SAME_SADDLE: f64 = 1e-3;

/// Shooting from a slow approach's stop: the slider, the section state, the period there, the
/// integration and Newton tolerances; the verdict and the work.
pub type ApproachCheck = fn(&Slider, &State, f64, f64, f64) -> (ApproachVerdict, Stats);

/// Most fingerprints of known irregular attractors a run compares its blocks with.
pub const KNOWN_MAX: usize = 2;

/// Fingerprints of known irregular attractors (`None`: an empty slot).
pub type Known = [Option<Fingerprint>; KNOWN_MAX];

/// An irregular attractor's section statistics per block of `irregular_block` sections: the mean
/// repetition residual and each component's largest excursion, in units of the characteristic
/// sizes (the stationarity test's statistics). A run that ends stationary reports the mean of its
/// three blocks; a block of another run of the same model that agrees with it within the
/// stationarity tolerances ([`STATIONARY_RESIDUAL_TOL`], [`STATIONARY_PEAK_TOL`]) is on the same
/// attractor, as in the recurrence method of Datseris & Wagemakers (Chaos 32, 2022) that labels a
/// trajectory by the attractor whose cells it keeps visiting.
///
/// A run that ends stationary also reports the [`Cells`] its section states visited over its
/// three blocks: a run of the same model whose section states fall in them [`RECUR_SECTIONS`]
/// times in a row, with a mean repetition residual of the same order (at least half the
/// fingerprint's, and above the stationarity floor), is on the same attractor, without waiting
/// for a whole block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fingerprint {
    /// Mean repetition residual.
    pub residual: f64,
    /// Largest excursion of each component (those the run compares; the others are not compared).
    pub peaks: [f64; 6],
    /// The cells of the section states over the stationary blocks ([`Cells::EMPTY`]: none known).
    pub cells: Cells,
}

impl Default for SteadyOptions {
    fn default() -> Self {
        SteadyOptions {
            t_max: 10.0,
            method: Method::Dopri5,
            tol: Tolerances::new(1e-8),
            periodic_tol: 1e-5,
            stationary_tol: None,
            hold: 0.0,
            decay_amplitude: None,
            decay_thresholds: None,
            decay_window: 8,
            n_fourier: 512,
            watch_x: true,
            checked_stops: false,
            irregular_block: 0,
            approach_periods: 0,
            approach_check: None,
            approach_rtol: 1e-9,
            approach_tol: 1e-8,
            known_irregular: [None; KNOWN_MAX],
        }
    }
}

/// Summary of a run to steady state. Amplitudes [m, rad], phases [rad] in `[0, 2 pi)` relative to `z1`.
#[derive(Clone, Copy, Debug)]
pub struct Summary {
    /// Status of the computation (`Success` when it ended in a recognised state: decayed, periodic
    /// or diverged; `NotConverged` when `t_max` was reached; a failure code otherwise).
    pub status: Status,
    /// What the motion did.
    pub outcome: SteadyOutcome,
    /// Simulated time at the end of detection [s].
    pub t_end: f64,
    /// Angular frequency of the fundamental [rad/s] (periodic: `2 pi / period`; otherwise from the
    /// last section interval, NaN if none).
    pub omega: f64,
    /// Period [s] (periodic only, else NaN).
    pub period: f64,
    /// Section crossings per period (periodic only, else 0).
    pub multiplicity: u32,
    /// Where the run ended: for a periodic outcome the section state (`zd = 0`) on the cycle, a
    /// start for shooting; otherwise the state at `t_end`.
    pub y_end: State,
    /// DC of z [m].
    pub z0: f64,
    /// Amplitudes of the first three harmonics of z [m].
    pub z_amp: [f64; 3],
    /// Half of z's range over the period [m] (periodic only, from the Fourier samples): the size of
    /// the motion, which a subharmonic cycle's first harmonics can be a small part of.
    pub z_half_range: f64,
    /// Phases of harmonics 1-3 of z relative to z1 (the first is 0 by definition) [rad].
    pub z_phase: [f64; 3],
    /// Amplitude [rad] and phase [rad] of the first harmonic of phi.
    pub phi_amp: f64,
    /// Phase of phi1 relative to z1 [rad].
    pub phi_phase: f64,
    /// Amplitude of the first harmonic of x [m].
    pub x_amp: f64,
    /// Phase of x1 relative to z1 [rad].
    pub x_phase: f64,
    /// Minimum total normal force over the final period (periodic) or the whole run (otherwise) [N].
    pub min_normal_force: f64,
    /// Fraction of the final period with the pin off the disk (`zc > 0`) (periodic only).
    pub fraction_off_disk: f64,
    /// Minimum sliding velocity over the final period or the run [m/s].
    pub min_slip_velocity: f64,
    /// Extremes over the whole run.
    pub extremes: Extremes,
    /// Work counters, transient and the Fourier period together.
    pub stats: Stats,
    /// Why the status is not `Success`, with its numbers (`None` for `Success`).
    pub failure: Option<Failure>,
    /// Irregular only: the attractor's fingerprint (the mean of the three stationary blocks with
    /// their cells, the block that matched a known fingerprint, or the known fingerprint whose
    /// cells the run kept visiting; the last two without cells of their own).
    pub fingerprint: Option<Fingerprint>,
    /// Irregular only: whether the run matched a known fingerprint (`SteadyOptions::known_irregular`:
    /// a block of its statistics, or [`RECUR_SECTIONS`] sections in a row in its cells) rather than
    /// three of its own blocks being stationary.
    pub matched_known: bool,
    /// Periodic only: the run stopped on a slow approach ([`SteadyOptions::approach_periods`])
    /// that shooting converged on a stable orbit of its period; `y_end`, the period and every
    /// cycle quantity are the orbit's (verified).
    pub approach: bool,
    /// Irregular only: the run stopped as intermittent motion ([`Intermittent`]) rather than by
    /// the stationarity test.
    pub intermittent: Option<Intermittent>,
    /// Unsettled only: the newest section state's closest repetition ([`Nearest`]; `None` with
    /// fewer than two sections). A slowly attracting cycle that had not repeated to
    /// `periodic_tol` by `t_max` shows here, a start for shooting.
    pub nearest: Option<Nearest>,
}

/// The closest repetition of a run's newest section state among the `p = 1..=MAX_MULTIPLICITY`
/// before it, measured as the repetition test does (each compared component's difference
/// relative to its amplitude over the `p` sections); `p` reduced to its smallest divisor whose
/// states repeat to [`REDUCE_TOL`], as for a found cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// The newest section state.
    pub y: State,
    /// Time over the `multiplicity` sections [s].
    pub period: f64,
    /// Sections per repetition.
    pub multiplicity: u32,
    /// The relative repetition residual at the smallest-residual `p` (before the reduction).
    pub residual: f64,
}

impl Summary {
    fn empty(status: Status, outcome: SteadyOutcome) -> Self {
        Summary {
            status,
            outcome,
            t_end: 0.0,
            omega: f64::NAN,
            period: f64::NAN,
            multiplicity: 0,
            y_end: State::repeat(f64::NAN),
            z0: f64::NAN,
            z_amp: [f64::NAN; 3],
            z_half_range: f64::NAN,
            z_phase: [f64::NAN; 3],
            phi_amp: f64::NAN,
            phi_phase: f64::NAN,
            x_amp: f64::NAN,
            x_phase: f64::NAN,
            min_normal_force: f64::NAN,
            fraction_off_disk: f64::NAN,
            min_slip_velocity: f64::NAN,
            extremes: Extremes::default(),
            stats: Stats::default(),
            failure: None,
            fingerprint: None,
            matched_known: false,
            approach: false,
            intermittent: None,
            nearest: None,
        }
    }

    /// A summary for a point that could not be computed (`failure`: why, where known).
    pub fn failed(status: Status, failure: Option<Failure>) -> Self {
        Summary { failure, ..Self::empty(status, SteadyOutcome::Failed) }
    }
}

/// The decay amplitude of `z` that `opts` sets for `s` (without per-component thresholds).
fn decay_amplitude(opts: &SteadyOptions, s: &Slider) -> f64 {
    opts.decay_amplitude.unwrap_or(1e-3 * s.z_st.abs())
}

/// A per-trajectory override of the decay test of a run to steady state (an ensemble's
/// `Task::Steady`): a decay amplitude of `z` (every component in units of its characteristic
/// size), or thresholds per component (`SteadyOptions::decay_thresholds`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DecayTest {
    Amplitude(f64),
    Thresholds([f64; 6]),
}

impl DecayTest {
    /// `opts` with this decay test.
    pub fn apply(self, opts: &SteadyOptions) -> SteadyOptions {
        match self {
            DecayTest::Amplitude(a) => SteadyOptions { decay_amplitude: Some(a), decay_thresholds: None, ..*opts },
            DecayTest::Thresholds(t) => SteadyOptions { decay_thresholds: Some(t), ..*opts },
        }
    }
}

/// Run `s` from `y0` until it decays, settles on a periodic state, escapes, or reaches `t_max`,
/// and summarise the motion.
pub fn run_to_steady(s: &Slider, y0: &State, opts: &SteadyOptions) -> Summary {
    let (r, obs) = run_observed(s, y0, opts.t_max, opts.method, &opts.tol, SteadyObserver::new(s, opts));
    summarize(s, &r, &obs.w, opts)
}

/// The summary of a run to steady state that ended with `r`, watched by `w` (shared by the
/// scalar driver and the lane-batched one).
pub(crate) fn summarize(s: &Slider, r: &RunResult, w: &SectionWatcher, opts: &SteadyOptions) -> Summary {
    let mut sum = Summary::empty(r.status, SteadyOutcome::Failed);
    sum.t_end = r.t;
    sum.y_end = r.y;
    sum.extremes = r.extremes;
    sum.stats = r.stats;
    sum.stats += w.extra;
    sum.failure = r.failure;
    sum.min_normal_force = r.extremes.min_normal_force;
    sum.min_slip_velocity = r.extremes.min_slip_velocity;
    // Not periodic: the mean crossing rate of the newest window (for a decayed motion, the
    // least-damped mode's frequency as seen in z's maxima).
    sum.omega = w.mean_omega(w.window);
    match r.status {
        Status::Diverged => {
            sum.outcome = SteadyOutcome::Diverged;
            sum.status = Status::Success;
            sum.failure = None;
            return sum;
        }
        Status::Success => {}
        _ => return sum,
    }
    if let Some(m) = &w.measured {
        // A slow approach that its check verified: the cycle as the run on the orbit measured it.
        let (t_end, extremes, stats) = (sum.t_end, sum.extremes, sum.stats);
        sum = **m;
        (sum.t_end, sum.extremes, sum.stats, sum.approach) = (t_end, extremes, stats, true);
    } else if let Some((p, period)) = w.found {
        sum.outcome = SteadyOutcome::Periodic;
        sum.period = period;
        sum.multiplicity = p as u32;
        sum.omega = std::f64::consts::TAU / period;
        let c = *w.get(0);
        sum.y_end = c.y;
        fourier_period(s, &c.y, period, opts, &mut sum);
    } else if w.decayed {
        sum.outcome = SteadyOutcome::Decayed;
    } else if w.irregular {
        sum.outcome = SteadyOutcome::Irregular;
        sum.fingerprint = w.fingerprint;
        sum.matched_known = w.matched_known;
        sum.intermittent = w.intermittent;
    } else {
        sum.outcome = SteadyOutcome::Unsettled;
        sum.status = Status::NotConverged;
        sum.failure = Some(Failure::Unsettled { t_max: opts.t_max, periodic_tol: opts.periodic_tol });
        sum.nearest = w.nearest();
    }
    sum
}

mod cells;
mod fourier;
mod observer;
mod section;
pub use cells::{Cells, CELLS, CELL_COMPS, CELL_WORDS, RECUR_SECTIONS};
use fourier::fourier_period;
#[cfg(test)]
use fourier::{amp_phase, wrap};
pub(crate) use observer::SteadyObserver;
#[cfg(test)]
use section::Crossing;
pub(crate) use section::SectionWatcher;
#[cfg(test)]
use section::{ALL, NOT_X};
pub use section::{
    APPROACH_TOL, CHECKED_X_SLACK, REDUCE_TOL, STATIONARY_FLOOR, STATIONARY_MIN_RESIDUAL, STATIONARY_PEAK_TOL,
    STATIONARY_RESIDUAL_TOL,
};

#[cfg(test)]
mod tests;
