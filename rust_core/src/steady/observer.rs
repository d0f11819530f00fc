//! The observer of a run to steady state: the section watcher on every step, and the shooting
//! check of a slow approach inside the run (`SteadyOptions::approach_periods`).

use super::section::{Crossing, SectionWatcher};
use super::{decay_amplitude, run_to_steady, ApproachVerdict, SteadyOptions, SteadyOutcome, KNOWN_MAX};
use crate::model::{idx, ContactMode, Slider, State};
use crate::ode::{Control, Observer, StepView};

pub(crate) struct SteadyObserver {
    pub(crate) w: SectionWatcher,
    pub(crate) decay_floor: f64,
    /// The slider and the run's options, for the slow-approach checks.
    s: Slider,
    opts: SteadyOptions,
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
        }
    }

    /// Shooting from a slow approach's stop (the newest section state, over the found period):
    /// `true` (stop) where it converged on a stable orbit of that period and a run started on the
    /// orbit repeated (its summary, kept in the watcher, is the cycle's: the measurement of
    /// `tribosweep._cycles.check`, whose period and multiplicity are the flow's own, not the
    /// shooting's); otherwise the run goes on, held off cycles near an unstable orbit, without
    /// approach stops where shooting failed, found another period or the orbit did not repeat.
    fn check_approach(&mut self) -> bool {
        let (Some((_, period)), Some(check)) = (self.w.found, self.opts.approach_check) else { return true };
        let c = *self.w.get(0);
        let (verdict, work) = check(&self.s, &c.y, period, self.opts.approach_rtol, self.opts.approach_tol);
        self.w.extra += work;
        let hold = match verdict {
            ApproachVerdict::Stable { state0, .. } => {
                let on = SteadyOptions {
                    approach_periods: 0,
                    irregular_block: 0,
                    hold: 0.0,
                    known_irregular: [None; KNOWN_MAX],
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
            ApproachVerdict::Unstable { largest, period } => {
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
            let (t, y) = locate(st, |y| y[idx::ZD], |f| f[idx::ZD], 1e-14 * st.t1.abs().max(1.0));
            let peaks = self.w.peaks_since.sup(&y.abs());
            self.w.peak_since = st.y1[idx::Z].abs();
            self.w.peaks_since = st.y1.abs();
            self.w.push(Crossing { t, y, peaks });
            if self.w.approach && !self.check_approach() {
                return Control::Continue;
            }
            if self.w.found.is_some() || self.w.decayed || self.w.irregular {
                return Control::Stop;
            }
        } else if st.y1.norm() == 0.0 || self.w.peak_since < self.decay_floor {
            // Exactly at rest (or below any meaningful size): nothing will ever cross the section.
            self.w.decayed = true;
            return Control::Stop;
        }
        Control::Continue
    }
}

/// Locate a zero of `g` (falling from > 0 to <= 0) inside a step on the dense output (the events'
/// root finder, [`crate::ode::events::locate`]): the time on the far side of the zero, and the state there.
///
/// Where the interpolant keeps the right-hand side at the ends of its step and the step was not
/// cut short by an event, the search starts at the root of `g`'s cubic model (`rate`: `dg/dt`
/// from the state's derivative).
fn locate(
    st: &StepView<'_, 6, ContactMode>,
    g: impl Fn(&State) -> f64,
    rate: impl Fn(&State) -> f64,
    tol: f64,
) -> (f64, State) {
    use crate::ode::events::{hermite_root, locate_from};
    let (g0, g1) = (g(st.y0), g(st.y1));
    let guess = st.dense.end_rates().and_then(|((t0, t1), (f0, f1))| {
        (t0 == st.t0 && t1 == st.t1).then(|| hermite_root(t0, t1 - t0, g0, g1, rate(&f0), rate(&f1))).flatten()
    });
    let t = locate_from(|t| g(&st.dense.eval(t)), st.t0, g0, st.t1, g1, tol, guess);
    let y = if t == st.t1 { *st.y1 } else { st.dense.eval(t) };
    (t, y)
}
