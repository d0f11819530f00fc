//! The observer of a run to steady state: the section watcher on every step, and the shooting
//! check of a slow approach inside the run (`SteadyOptions::approach_periods`).

use super::section::{Crossing, SectionWatcher};
use super::{
    decay_amplitude, run_to_steady, ApproachVerdict, Intermittent, SteadyOptions, SteadyOutcome, Tolerances,
    DEPART_TOL, INTERMITTENT_VISITS, KNOWN_MAX, SAME_SADDLE,
};
use crate::model::{idx, ContactMode, Slider, State};
use crate::ode::{Control, Observer, StepView};

pub(crate) struct SteadyObserver {
    pub(crate) w: SectionWatcher,
    pub(crate) decay_floor: f64,
    /// The slider and the run's options, for the slow-approach checks.
    s: Slider,
    opts: SteadyOptions,
    /// The unstable cycle the newest check that found one found, and the run's visits to it.
    saddle: Option<Saddle>,
}

/// An unstable cycle that a slow-approach check found, as the run's intermittent motion would
/// report it (its visits so far), with what tells it and a departure from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Saddle {
    pub(super) cycle: Intermittent,
    /// z's first harmonic on it: with the period, its identity.
    pub(super) a1: f64,
    /// Its sections per period: the repetition residual after these tells a departure.
    pub(super) p: usize,
    /// The residual after `p` sections exceeded [`DEPART_TOL`] since the newest visit.
    pub(super) departed: bool,
}

impl Saddle {
    /// A check found the unstable cycle (`period`, `a1`, `largest`, `kind`, `p` sections per period):
    /// `saddle` updated, and the intermittent motion where this is its [`INTERMITTENT_VISITS`]th
    /// visit. The same cycle (period and A1 to [`SAME_SADDLE`]) counts a visit only where the run
    /// left it since the one before; another cycle starts the count again.
    pub(super) fn visit(
        saddle: &mut Option<Saddle>,
        period: f64,
        a1: f64,
        largest: f64,
        kind: u8,
        p: usize,
    ) -> Option<Intermittent> {
        let same = |s: &Saddle| {
            (s.cycle.period / period - 1.0).abs() <= SAME_SADDLE
                && (s.a1 - a1).abs() <= SAME_SADDLE * s.a1.abs().max(a1.abs())
        };
        match saddle {
            Some(s) if same(s) => {
                if s.departed {
                    (s.cycle.visits, s.departed) = (s.cycle.visits + 1, false);
                }
            }
            _ => {
                let cycle = Intermittent { period, largest, visits: 1, kind };
                *saddle = Some(Saddle { cycle, a1, p, departed: false });
            }
        }
        let c = saddle.as_ref().expect("set above").cycle;
        (c.visits >= INTERMITTENT_VISITS).then_some(c)
    }

    /// A section's repetition residual after the cycle's `p` sections: marks a departure.
    pub(super) fn watch(&mut self, residual: f64) {
        self.departed |= residual > DEPART_TOL;
    }
}

/// A slow approach's check grows a deviation along an unstable orbit's largest multiplier this
/// much before the run may stop on a cycle again (as `tribosweep._cycles.leave`).
const LEAVE_GROWTH: f64 = 1e3;

impl SteadyObserver {
    /// The observer of a run to steady state of `s` under `opts`.
    pub(crate) fn new(s: &Slider, opts: &SteadyOptions) -> Self {
        SteadyObserver {
            w: SectionWatcher::new(opts, s),
            decay_floor: 1e-6 * opts.decay_thresholds.map_or_else(|| decay_amplitude(opts, s), |t| t[idx::Z]),
            s: *s,
            opts: *opts,
            saddle: None,
        }
    }

    /// Shooting from a slow approach's stop (the newest section state, over the found period):
    /// `true` (stop) where it converged on a stable orbit of that period and a run started on the
    /// orbit repeated (its summary, kept in the watcher, is the cycle's: the measurement of
    /// `tribosweep._cycles.check`, whose period and multiplicity are the flow's own, not the
    /// shooting's); otherwise the run goes on, held off cycles near an unstable orbit, without
    /// approach stops where shooting failed, found another period or the orbit did not repeat.
    /// The [`INTERMITTENT_VISITS`]th visit to one unstable orbit stops the run as intermittent
    /// (irregular, [`Intermittent`]).
    fn check_approach(&mut self) -> bool {
        let (Some((p, period)), Some(check)) = (self.w.found, self.opts.approach_check) else { return true };
        let c = *self.w.get(0);
        let (verdict, work) = check(&self.s, &c.y, period, self.opts.approach_rtol, self.opts.approach_tol);
        self.w.extra += work;
        let hold = match verdict {
            ApproachVerdict::Stable { state0, .. } => {
                // Measured at the check's tolerance: the run's own only found the cycle (a
                // sweep's transients run looser than what it reports).
                let on = SteadyOptions {
                    approach_periods: 0,
                    irregular_block: 0,
                    hold: 0.0,
                    known_irregular: [None; KNOWN_MAX],
                    tol: Tolerances { rtol: self.opts.approach_rtol, ..self.opts.tol },
                    ..self.opts
                };
                let m = run_to_steady(&self.s, &state0, &on);
                self.w.extra += m.stats;
                if m.outcome == SteadyOutcome::Periodic {
                    self.w.measured = Some(Box::new(m));
                    return true;
                }
                None
            }
            ApproachVerdict::Unstable { largest, period, a1, kind } => {
                if let Some(im) = Saddle::visit(&mut self.saddle, period, a1, largest, kind, p) {
                    self.w.reject_approach(None);
                    (self.w.irregular, self.w.intermittent) = (true, Some(im));
                    return true;
                }
                let grow = if largest > 1.0 { (LEAVE_GROWTH.ln() / largest.ln()).ceil() } else { 1000.0 };
                Some(c.t + grow.clamp(4.0, 1000.0) * period)
            }
            ApproachVerdict::Nothing => None,
        };
        self.w.reject_approach(hold);
        false
    }
}

impl Observer<6, ContactMode> for SteadyObserver {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        let (zd0, zd1) = (st.y0[idx::ZD], st.y1[idx::ZD]);
        self.w.peak_since = self.w.peak_since.max(st.y1[idx::Z].abs());
        self.w.peaks_since = self.w.peaks_since.sup(&st.y1.abs());
        if zd0 > 0.0 && zd1 <= 0.0 {
            // Section: zd = 0 falling. Located on the dense output, which is accurate to the
            // integration tolerance; that sets the section's.
            let (t, y) = locate(st, idx::ZD, 1e-14 * st.t1.abs().max(1.0));
            let peaks = self.w.peaks_since.sup(&y.abs());
            self.w.peak_since = st.y1[idx::Z].abs();
            self.w.peaks_since = st.y1.abs();
            self.w.push(Crossing { t, y, peaks });
            if let Some(sd) = self.saddle.as_mut() {
                sd.watch(self.w.residual(sd.p));
            }
            if self.w.approach && !self.check_approach() {
                return Control::Continue;
            }
            if self.w.found.is_some() || self.w.decayed || self.w.irregular {
                return Control::Stop;
            }
        } else if st.y1.norm() == 0.0 || (self.w.peak_since < self.decay_floor && self.w.quiet_beside_z(st.y1)) {
            // Exactly at rest, or z below any meaningful size and the other compared components
            // below the decay threshold: nothing will ever cross the section.
            self.w.decayed = true;
            return Control::Stop;
        }
        Control::Continue
    }
}

/// Locate a zero of component `k` of the state (falling from > 0 to <= 0) inside a step on the
/// dense output (the events' root finder, [`crate::ode::events::locate`]), interpolating that
/// component alone: the time on the far side of the zero, and the state there.
///
/// Where the interpolant keeps the right-hand side at the ends of its step and the step was not
/// cut short by an event, the search starts at the root of the component's cubic model (its rate
/// from the state's derivative).
fn locate(st: &StepView<'_, 6, ContactMode>, k: usize, tol: f64) -> (f64, State) {
    use crate::ode::events::{hermite_root, locate_from};
    let (g0, g1) = (st.y0[k], st.y1[k]);
    let guess = st.dense.end_rates().and_then(|((t0, t1), (f0, f1))| {
        (t0 == st.t0 && t1 == st.t1).then(|| hermite_root(t0, t1 - t0, g0, g1, f0[k], f1[k])).flatten()
    });
    let t = locate_from(|t| st.dense.eval_some(t, 1 << k)[k], st.t0, g0, st.t1, g1, tol, guess);
    let y = if t == st.t1 { *st.y1 } else { st.dense.eval(t) };
    (t, y)
}
