//! Integrators on fixed-size stack states, with dense output and event location.
//!
//! The contract:
//! - A system implements [`OdeSystem`]: a right-hand side that depends on a discrete `Mode`
//!   (e.g. pin in contact / off the disk), optional event functions `g_i(t, y, mode)`, and an
//!   `on_event` that says what happens when one crosses zero.
//! - [`integrate`] advances with one of the [`Method`]s, locates every sign change of an event
//!   function inside an accepted step on the step's dense output (to `Options::event_tol` in time),
//!   truncates the step at the first event whose action is `Switch` or `Stop`, and restarts there
//!   in the new mode. Non-smooth scenes are integrated through their switches, never stepped across.
//! - An [`Observer`] sees every accepted step (with its dense output) and every event, and may stop
//!   the run. Sampling at output times, Poincare sections and running extrema live in observers.
//! - The run ends with an [`Outcome`] and [`Stats`]; a failure is data, never a panic.
//! - A run looks at the caller's stop request ([`crate::cancel`], the one module outside `ode` it
//!   uses: a leaf that knows nothing else) every [`crate::cancel::CHECK_EVERY`] steps, and ends with
//!   [`Outcome::Cancelled`] when asked.
//!
//! Generic: nothing here knows the slider (the layering test `tests/architecture.rs` checks that
//! `ode` refers to no other module of the crate). The files, bottom up:
//! - `mod.rs`: the contract above; `controller.rs`: error norm, PI controller, starting step;
//! - `stepper.rs`: the crate-private `Stepper` trait each method implements, and stage sums;
//! - `dopri5.rs`, `dop853.rs`, `rodas.rs`: one method each (tableau, stepper, dense output);
//! - `events.rs`: event location and processing on an accepted step (shared with the slider's
//!   lane-batched paths in `crate::ensemble`);
//! - `driver.rs`: [`integrate`], the adaptive loop, and fixed-step integration;
//! - `lanes.rs`: the kit for lane-batched (SIMD) integration: lane types, one DOPRI5 or DOP853
//!   attempt on `N` trajectories (8 or 16), their interpolants, the PI controller in log form;
//! - tests: `test_systems.rs` (problems with known solutions), `method_tests.rs` (orders of
//!   convergence), `driver/tests.rs`, `driver/hidden_crossing_tests.rs`.

pub mod controller;
pub mod dop853;
pub mod dopri5;
pub mod driver;
pub(crate) mod events;
pub(crate) mod lanes;
#[cfg(test)]
mod method_tests;
pub mod rodas;
pub(crate) mod stepper;
#[cfg(test)]
pub(crate) mod test_systems;

use nalgebra::{SMatrix, SVector};

pub use driver::integrate;

/// Most event functions a system may declare.
pub const MAX_EVENTS: usize = 8;

/// What a located event does to the integration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventAction<M> {
    /// Record it; the dynamics do not change (the step is not truncated).
    Continue,
    /// Truncate the step at the event and restart in this mode.
    Switch(M),
    /// Truncate the step at the event and end the run (`Outcome::StoppedByEvent`).
    Stop,
}

/// An ODE `y' = f(t, y, mode)` with events.
pub trait OdeSystem<const N: usize> {
    /// Discrete state that selects the smooth branch of the right-hand side.
    type Mode: Copy + PartialEq + core::fmt::Debug;

    /// Right-hand side on the branch `mode`.
    fn rhs(&self, t: f64, y: &SVector<f64, N>, mode: Self::Mode) -> SVector<f64, N>;

    /// Jacobian `df/dy` on the branch `mode` (used by implicit methods). Default: central
    /// differences with steps scaled to each component.
    fn jacobian(&self, t: f64, y: &SVector<f64, N>, mode: Self::Mode) -> SMatrix<f64, N, N> {
        let mut j = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            let h = f64::EPSILON.cbrt() * y[c].abs().max(1e-8);
            let mut yp = *y;
            let mut ym = *y;
            yp[c] += h;
            ym[c] -= h;
            let col = (self.rhs(t, &yp, mode) - self.rhs(t, &ym, mode)) / (2.0 * h);
            j.set_column(c, &col);
        }
        j
    }

    /// Mode at the start of a run.
    fn initial_mode(&self, t: f64, y: &SVector<f64, N>) -> Self::Mode;

    /// Number of event functions (at most [`MAX_EVENTS`]).
    fn n_events(&self) -> usize {
        0
    }

    /// Event function values `g[i]`, `i < n_events()`. An event is a sign change of `g[i]`
    /// (in either direction) within a step.
    fn events(&self, _t: f64, _y: &SVector<f64, N>, _mode: Self::Mode, _g: &mut [f64; MAX_EVENTS]) {}

    /// The state components event function `i` reads (bit `j`: component `j`; all by default):
    /// root finding interpolates only those ([`Dense::eval_some`]).
    fn event_reads(&self, _i: usize) -> u64 {
        u64::MAX
    }

    /// Event function `i` alone: `events(t, y, mode)[i]`, the same bits (a system may compute it
    /// without the others: root finding reads one function at a time). Only the components of
    /// [`Self::event_reads`] may be read.
    fn event(&self, t: f64, y: &SVector<f64, N>, mode: Self::Mode, i: usize) -> f64 {
        let mut g = [0.0; MAX_EVENTS];
        self.events(t, y, mode, &mut g);
        g[i]
    }

    /// Time derivatives `d[i]` of the event functions at `(t, y)`, where `f` is the right-hand side
    /// there in `mode`; `false` where the system does not provide them (then the hidden-crossing
    /// check uses its interior points only). An entry may be NaN: no rate for that function.
    fn event_rates(
        &self,
        _t: f64,
        _y: &SVector<f64, N>,
        _f: &SVector<f64, N>,
        _mode: Self::Mode,
        _d: &mut [f64; MAX_EVENTS],
    ) -> bool {
        false
    }

    /// The longest step to attempt from `y` (with right-hand side `f` there) in `mode`: where the
    /// mode's field has a discontinuity ahead that an event ends the mode before, a step whose
    /// stages reached it would be rejected (often several times over). Unlimited by default.
    fn step_limit(&self, _y: &SVector<f64, N>, _f: &SVector<f64, N>, _mode: Self::Mode) -> f64 {
        f64::INFINITY
    }

    /// Whether a sign change of event function `i` in `mode` is an event: `rising` from negative
    /// to non-negative, else from positive to non-positive. Both directions by default. A system
    /// restricts a function to one direction where a crossing the other way can only be an
    /// artefact that acts on nothing (a function left within the integration error of its zero
    /// by an earlier switch): counted, it would cut the step and enter the log as the sign of
    /// that error happens to fall. The hidden-crossing check is unchanged (an excursion inside a
    /// step crosses both ways).
    fn crossing_counts(&self, _mode: Self::Mode, _i: usize, _rising: bool) -> bool {
        true
    }

    /// Action at a located event `index` at `(t, y)` in `mode`.
    fn on_event(&self, _t: f64, _y: &SVector<f64, N>, _mode: Self::Mode, _index: usize) -> EventAction<Self::Mode> {
        EventAction::Continue
    }
}

/// Integration method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Dormand-Prince 5(4), FSAL, 4th-order dense output.
    Dopri5,
    /// Dormand-Prince 8(5,3) (Hairer's DOP853), 7th-order dense output.
    Dop853,
    /// Rodas4: stiffly accurate L-stable Rosenbrock method of order 4(3), 3rd-order dense output.
    Rodas4,
}

impl Method {
    /// Every method.
    pub const ALL: [Method; 3] = [Method::Dopri5, Method::Dop853, Method::Rodas4];

    /// Classical order of the propagated solution.
    pub fn order(self) -> u32 {
        match self {
            Method::Dopri5 => 5,
            Method::Dop853 => 8,
            Method::Rodas4 => 4,
        }
    }

    /// Name as used in the Python API.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => "dopri5",
            Method::Dop853 => "dop853",
            Method::Rodas4 => "rodas4",
        }
    }

    /// Inverse of [`Method::name`].
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// True for methods that solve linear systems with the Jacobian.
    pub fn is_implicit(self) -> bool {
        matches!(self, Method::Rodas4)
    }
}

/// Integration options. Error test: `|err_i| <= atol_i + rtol |y_i|`, RMS norm over components.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options<const N: usize> {
    /// Relative tolerance (> 0).
    pub rtol: f64,
    /// Absolute tolerance per component (> 0).
    pub atol: SVector<f64, N>,
    /// Initial step; 0 chooses one automatically (Hairer's starting-step algorithm).
    pub h0: f64,
    /// Largest step; `f64::INFINITY` for none.
    pub h_max: f64,
    /// Smallest step relative to `|t|` before the run ends with `StepTooSmall`
    /// (the absolute floor is `h_min_rel * max(|t|, 1)`).
    pub h_min_rel: f64,
    /// Step budget (accepted + rejected).
    pub max_steps: u64,
    /// Absolute tolerance on located event times [s].
    pub event_tol: f64,
    /// After a `Switch` the same event function is ignored until the integration has moved by
    /// this much time [s] or the function has moved away from zero: the guard against grazing
    /// re-triggers (documented in the README).
    pub event_guard: f64,
    /// Most events in one run before it ends with `EventChatter`.
    pub max_events: u64,
    /// Event functions are also checked at this many evenly spaced interior points of each step's
    /// dense output; a sign change inside a step that the step's ends do not show (a crossing and
    /// its return within one step: a short hop off the disk) makes the driver redo the step ending
    /// at that interior point, so the excursion is located instead of stepped over; the turning
    /// points of systems with `event_rates` are checked with them. 0: ends only (no check inside).
    pub interior_checks: u32,
}

impl<const N: usize> Options<N> {
    /// Options with scalar tolerances and the defaults below.
    pub fn new(rtol: f64, atol: f64) -> Self {
        Options {
            rtol,
            atol: SVector::<f64, N>::repeat(atol),
            h0: 0.0,
            h_max: f64::INFINITY,
            h_min_rel: 1e-14,
            max_steps: 10_000_000,
            event_tol: 1e-13,
            event_guard: 1e-12,
            max_events: 10_000_000,
            interior_checks: 0,
        }
    }
}

/// Work counters of one run (they end up in the output).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Right-hand-side evaluations (including those of event location, if any).
    pub n_rhs: u64,
    /// Jacobian evaluations.
    pub n_jac: u64,
    /// LU decompositions.
    pub n_lu: u64,
    /// Accepted steps.
    pub n_accept: u64,
    /// Rejected steps.
    pub n_reject: u64,
    /// Located events (all actions).
    pub n_events: u64,
}

impl core::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Stats) {
        self.n_rhs += o.n_rhs;
        self.n_jac += o.n_jac;
        self.n_lu += o.n_lu;
        self.n_accept += o.n_accept;
        self.n_reject += o.n_reject;
        self.n_events += o.n_events;
    }
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Reached `t_end`.
    Finished,
    /// An event with action `Stop` ended it.
    StoppedByEvent,
    /// The observer asked to stop.
    StoppedByObserver,
    /// `max_steps` exhausted.
    MaxSteps,
    /// Step size fell below the floor.
    StepTooSmall,
    /// Non-finite state or derivative.
    NonFinite,
    /// More than `max_events` events.
    EventChatter,
    /// The caller asked to stop ([`crate::cancel`]): the run ended early where it was.
    Cancelled,
}

/// End state of a run.
#[derive(Clone, Copy, Debug)]
pub struct Solution<const N: usize, M> {
    /// Time reached.
    pub t: f64,
    /// State reached.
    pub y: SVector<f64, N>,
    /// Mode at the end.
    pub mode: M,
    /// How it ended.
    pub outcome: Outcome,
    /// Work counters.
    pub stats: Stats,
    /// The step size in use when the run ended [s]: for `StepTooSmall` and `NonFinite` the one that
    /// fell below the floor (for reasons; NaN before the first step was chosen).
    pub h: f64,
}

/// A step `(t0, t1)` and the right-hand side at both of its ends (see [`Dense::end_rates`]).
pub type EndRates<const N: usize> = ((f64, f64), (SVector<f64, N>, SVector<f64, N>));

/// Dense output of one accepted step on `[t0, t1]`.
pub trait Dense<const N: usize> {
    /// Interpolated state at `t` in `[t0, t1]`.
    fn eval(&self, t: f64) -> SVector<f64, N>;

    /// The components of [`Self::eval`] whose bit is set in `reads` (bit `i`: component `i`), the
    /// same bits; the others are unspecified (root finding reads one function of a few components).
    fn eval_some(&self, t: f64, _reads: u64) -> SVector<f64, N> {
        self.eval(t)
    }

    /// The step `(t0, t1)` this interpolant spans and the right-hand side at both of its ends,
    /// where the method keeps them (the explicit methods' first and last stages): root finders
    /// start from a cubic model of an event function with them. `None`: not kept.
    fn end_rates(&self) -> Option<EndRates<N>> {
        None
    }
}

/// One accepted (possibly event-truncated) step, as an observer sees it.
pub struct StepView<'a, const N: usize, M> {
    /// Start of the step.
    pub t0: f64,
    /// End of the step (an event time if truncated).
    pub t1: f64,
    /// State at `t0`.
    pub y0: &'a SVector<f64, N>,
    /// State at `t1`.
    pub y1: &'a SVector<f64, N>,
    /// Mode during the step.
    pub mode: M,
    /// Interpolant valid on `[t0, t1]`.
    pub dense: &'a dyn Dense<N>,
}

/// Whether the run goes on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// End the run now (`Outcome::StoppedByObserver`).
    Stop,
}

/// Sees the run as it goes.
pub trait Observer<const N: usize, M> {
    /// After each accepted step (before events at its end are processed).
    fn on_step(&mut self, _step: &StepView<'_, N, M>) -> Control {
        Control::Continue
    }
    /// At each located event: its index, time, state, and the modes before and after.
    fn on_event(&mut self, _index: usize, _t: f64, _y: &SVector<f64, N>, _before: M, _after: M) -> Control {
        Control::Continue
    }
}

/// An observer that watches nothing.
pub struct NoObserver;
impl<const N: usize, M> Observer<N, M> for NoObserver {}

/// Where a run's samples go, in order (a vector, or a row of a flat buffer).
pub trait SampleStore<const N: usize> {
    /// Samples stored so far (the index of the next one).
    fn len(&self) -> usize;
    /// Store the next sample.
    fn push(&mut self, v: SVector<f64, N>);
    /// No sample stored yet.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<const N: usize> SampleStore<N> for Vec<SVector<f64, N>> {
    #[inline]
    fn len(&self) -> usize {
        Vec::len(self)
    }
    #[inline]
    fn push(&mut self, v: SVector<f64, N>) {
        Vec::push(self, v)
    }
}

/// Samples the dense output at increasing times `t_eval` (an observer), into `out`.
pub struct Sampler<'a, const N: usize, S: SampleStore<N> = Vec<SVector<f64, N>>> {
    /// Requested times (increasing).
    pub t_eval: &'a [f64],
    /// Samples taken so far, one per requested time in order.
    pub out: S,
}

impl<'a, const N: usize> Sampler<'a, N> {
    /// A sampler for `t_eval` (increasing), into a vector.
    pub fn new(t_eval: &'a [f64]) -> Self {
        Sampler { t_eval, out: Vec::with_capacity(t_eval.len()) }
    }
}

impl<const N: usize, M, S: SampleStore<N>> Observer<N, M> for Sampler<'_, N, S> {
    fn on_step(&mut self, s: &StepView<'_, N, M>) -> Control {
        while let Some(&t) = self.t_eval.get(self.out.len()) {
            if t > s.t1 {
                break;
            }
            // Times before the first step's start are clamped to it (t0 of the run).
            let v = if t <= s.t0 {
                *s.y0
            } else if t == s.t1 {
                *s.y1
            } else {
                s.dense.eval(t)
            };
            self.out.push(v);
        }
        Control::Continue
    }
}
