//! The slider's variational equations and the runs that stop at every contact switch: saltation
//! matrices, the hidden-crossing check and local refinement (see the parent module's docs).

use super::*;

/// The slider with its variational equations: `y' = f(y)`, `Phi' = J(y) Phi` in the same mode,
/// with the slider's events and mode logic. `start` is the mode a run begins in (the shooting
/// restarts after each switch in the new mode).
#[derive(Clone, Copy, Debug)]
pub struct Variational<'a> {
    /// The slider.
    pub slider: &'a Slider,
    /// Mode at the start of a run.
    pub start: ContactMode,
}

#[inline]
pub(super) fn split(y: &Augmented) -> (State, Jacobian) {
    let phi = Jacobian::from_fn(|r, c| y[6 + 6 * c + r]);
    (head(y), phi)
}

/// The state part of `y` (the slider's own functions read only that, not `Phi`).
#[inline]
fn head(y: &Augmented) -> State {
    State::from_fn(|i, _| y[i])
}

#[inline]
pub(super) fn join(x: &State, phi: &Jacobian) -> Augmented {
    Augmented::from_fn(|i, _| if i < 6 { x[i] } else { phi[((i - 6) % 6, (i - 6) / 6)] })
}

impl OdeSystem<42> for Variational<'_> {
    type Mode = ContactMode;

    #[inline]
    fn rhs(&self, _t: f64, y: &Augmented, mode: ContactMode) -> Augmented {
        let x = head(y);
        let f = self.slider.rhs(&x, mode);
        let j = self.slider.jacobian(&x, mode);
        let mut out = Augmented::zeros();
        for i in 0..6 {
            out[i] = f[i];
        }
        // Phi' = J Phi, column by column (explicit loops: several times faster than a generic
        // 6x6 product here, and this is the inner loop of the shooting).
        for c in 0..6 {
            let b = 6 + 6 * c;
            for r in 0..6 {
                let mut acc = 0.0;
                for k in 0..6 {
                    acc += j[(r, k)] * y[b + k];
                }
                out[b + r] = acc;
            }
        }
        out
    }

    fn initial_mode(&self, _t: f64, _y: &Augmented) -> ContactMode {
        self.start
    }

    fn n_events(&self) -> usize {
        OdeSystem::<6>::n_events(self.slider)
    }

    #[inline]
    fn events(&self, t: f64, y: &Augmented, mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        OdeSystem::<6>::events(self.slider, t, &head(y), mode, g);
    }

    // The slider's own rules for the steps and crossings (the stick band's step limit, the band
    // edges counted one way), as in the transients' runs.
    fn event_rates(&self, t: f64, y: &Augmented, f: &Augmented, mode: ContactMode, d: &mut [f64; MAX_EVENTS]) -> bool {
        OdeSystem::<6>::event_rates(self.slider, t, &head(y), &head(f), mode, d)
    }

    fn crossing_counts(&self, mode: ContactMode, i: usize, rising: bool) -> bool {
        OdeSystem::<6>::crossing_counts(self.slider, mode, i, rising)
    }

    fn on_event(&self, t: f64, y: &Augmented, mode: ContactMode, index: usize) -> EventAction<ContactMode> {
        OdeSystem::<6>::on_event(self.slider, t, &head(y), mode, index)
    }
}

/// Saltation matrix of a switch from mode `before` to `after` on event `index` at state `y`:
/// `S = I + (f+ - f-) n^T / (n^T f-)` with `n` the gradient of the switching function.
/// Identity for events that do not switch the vector field.
pub fn saltation(s: &Slider, y: &State, before: ContactMode, after: ContactMode, index: usize) -> Jacobian {
    let Some(n) = switch_normal(s, y, index) else { return Jacobian::identity() };
    if before == after {
        return Jacobian::identity();
    }
    let fm = s.rhs(y, before);
    let fp = s.rhs(y, after);
    Jacobian::identity() + (fp - fm) * n.transpose() / n.dot(&fm)
}

/// Gradient `n = grad h` of the switching function of event `index` at `y` (`None` for events
/// that switch no vector field).
pub(crate) fn switch_normal(s: &Slider, y: &State, index: usize) -> Option<State> {
    let p = &s.p;
    let mut n = State::zeros();
    match index {
        event::GAP => n[idx::Z] = 1.0,
        event::NORMAL => {
            n[idx::Z] = -s.k_s + 2.0 * p.contact_quadratic * y[idx::Z];
            n[idx::ZD] = -p.contact_damping;
            n[idx::PHI] = p.twist_coupling;
        }
        // Switch law: band edges `v_r = +-eta` and the stick bound `mu_s N - |F_req| = 0`.
        event::BAND_HI | event::BAND_LO => n = s.slip_velocity_gradient(),
        event::STICK => n = s.stick_margin_gradient(y),
        _ => return None,
    }
    Some(n)
}

/// A sign change of the gap or the law's normal force that the step-end test cannot see: the
/// function leaves its sign and comes back inside one step (two crossings cancel in a sign-based
/// locator). On the seed bouncing cycle a 0.19 ms hop is as long as one DOP853 step at rtol 1e-8 to
/// 1e-11; missing it changes the dynamics (a different cycle). Checked on 8 interior points of the
/// dense output; `gap_always` also flags gap excursions that switch nothing (the bilateral model,
/// where they only matter for the open fraction); and a step that ends in flight with the pin
/// pressed into the disk is one (see inside). Returns the step length when one is found.
pub(super) fn missed_crossing<const N: usize>(
    s: &Slider,
    st: &StepView<'_, N, ContactMode>,
    gap_always: bool,
) -> Option<f64> {
    pub(super) const SUB: usize = 8;
    let six = |y: &SVector<f64, N>| State::from_fn(|i, _| y[i]);
    let g = |y: &State| [s.gap(y), s.p.normal_load + s.dynamic_law_force(y)];
    let unilateral = s.p.contact == crate::model::ContactModel::Unilateral;
    if !unilateral && !gap_always {
        return None;
    }
    let (g0, g1) = (g(&six(st.y0)), g(&six(st.y1)));
    let h = st.t1 - st.t0;
    // A step that ends in flight with the pin pressed into the disk (its gap and the law's force
    // both clearly past zero: a step cut at either event ends on that event's zero). The pin landed
    // while the law's force was tensile, stayed in flight at the gap event, and the force turned
    // compressive again inside the same step: its two crossings cancel at the step's ends, and the
    // interior points can miss them all (they count the force's crossings only where the gap is
    // closed). Left alone, the pin flies on through the disk.
    let landed = unilateral
        && st.mode == ContactMode::Free
        && g1[0] < -LANDED * s.z_st.abs()
        && g1[1] > LANDED * s.p.normal_load;
    if landed {
        return Some(h);
    }
    for k in 1..SUB {
        let yk = six(&st.dense.eval(st.t0 + h * k as f64 / SUB as f64));
        let gk = g(&yk);
        for e in 0..2 {
            let (a, b, c) = (g0[e] > 0.0, gk[e] > 0.0, g1[e] > 0.0);
            if a != c || b == a {
                continue;
            }
            let relevant = match e {
                0 => unilateral || gap_always,
                _ => unilateral && (st.mode.in_contact() || s.gap(&yk) <= 0.0),
            };
            if relevant {
                return Some(h);
            }
        }
    }
    None
}

/// How far past zero, relative to the static penetration and the load, the gap and the law's force
/// must be at the end of a step in flight for [`missed_crossing`] to call it a hidden landing: far
/// above the error of a located event (1e-13 s at the event's rate: about 1e-7 N and 1e-14 m).
const LANDED: f64 = 1e-6;

/// Stops a run at the first event that changes the mode.
pub(super) struct StopAtSwitch {
    pub(super) hit: Option<(usize, ContactMode, ContactMode)>,
}

impl<const N: usize> Observer<N, ContactMode> for StopAtSwitch {
    fn on_event(
        &mut self,
        index: usize,
        _t: f64,
        _y: &SVector<f64, N>,
        before: ContactMode,
        after: ContactMode,
    ) -> Control {
        if before != after {
            self.hit = Some((index, before, after));
            Control::Stop
        } else {
            Control::Continue
        }
    }
}

/// The slider starting in a given mode (a restart in the middle of a run keeps its mode).
#[derive(Clone, Copy, Debug)]
pub(super) struct Forced<'a> {
    pub(super) slider: &'a Slider,
    pub(super) start: ContactMode,
}

impl OdeSystem<6> for Forced<'_> {
    type Mode = ContactMode;

    #[inline]
    fn rhs(&self, _t: f64, y: &State, mode: ContactMode) -> State {
        self.slider.rhs(y, mode)
    }

    fn initial_mode(&self, _t: f64, _y: &State) -> ContactMode {
        self.start
    }

    fn n_events(&self) -> usize {
        OdeSystem::<6>::n_events(self.slider)
    }

    #[inline]
    fn events(&self, t: f64, y: &State, mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        OdeSystem::<6>::events(self.slider, t, y, mode, g);
    }

    // As `Variational`'s: the slider's own rules for the steps and crossings.
    fn event_rates(&self, t: f64, y: &State, f: &State, mode: ContactMode, d: &mut [f64; MAX_EVENTS]) -> bool {
        OdeSystem::<6>::event_rates(self.slider, t, y, f, mode, d)
    }

    fn crossing_counts(&self, mode: ContactMode, i: usize, rising: bool) -> bool {
        OdeSystem::<6>::crossing_counts(self.slider, mode, i, rising)
    }

    fn on_event(&self, t: f64, y: &State, mode: ContactMode, index: usize) -> EventAction<ContactMode> {
        OdeSystem::<6>::on_event(self.slider, t, y, mode, index)
    }
}

/// Passes steps and events to `inner` unless a step hides a contact switch ([`missed_crossing`]);
/// then it stops the run and keeps the step's start.
pub(super) struct Watched<'a, const N: usize, O> {
    pub(super) inner: &'a mut O,
    pub(super) slider: &'a Slider,
    pub(super) gap_always: bool,
    pub(super) missed: Option<(f64, f64, SVector<f64, N>, ContactMode)>,
}

impl<const N: usize, O: Observer<N, ContactMode>> Observer<N, ContactMode> for Watched<'_, N, O> {
    fn on_step(&mut self, st: &StepView<'_, N, ContactMode>) -> Control {
        if let Some(h) = missed_crossing(self.slider, st, self.gap_always) {
            self.missed = Some((h, st.t0, *st.y0, st.mode));
            return Control::Stop;
        }
        self.inner.on_step(st)
    }

    fn on_event(
        &mut self,
        index: usize,
        t: f64,
        y: &SVector<f64, N>,
        before: ContactMode,
        after: ContactMode,
    ) -> Control {
        self.inner.on_event(index, t, y, before, after)
    }
}

/// Step-size cap of a local refinement: steps at most `h` until time `until`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cap {
    pub(crate) until: f64,
    pub(crate) h: f64,
    pub(crate) refinements: u32,
}

impl Cap {
    pub(crate) const NONE: Cap = Cap { until: f64::NEG_INFINITY, h: f64::INFINITY, refinements: 0 };
    /// Most local refinements in one run.
    pub(super) const MAX: u32 = 200;
}

/// `ode::integrate` from `(t, y)` in mode `mode` to `t_end`, observed by `inner`, with local
/// refinement: a step that hides a contact switch is thrown away and the run restarts at its start
/// with steps capped at a quarter of it for two step lengths (repeatedly, if a smaller hop hides
/// in a capped step). Returns when `inner` stops the run, at `t_end`, or on failure
/// (`EventChatter` after [`Cap::MAX`] refinements).
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_watched<const N: usize, S, O, F>(
    make: F,
    slider: &Slider,
    method: Method,
    mut t: f64,
    mut y: SVector<f64, N>,
    mut mode: ContactMode,
    t_end: f64,
    opts: &Options<N>,
    gap_always: bool,
    cap: &mut Cap,
    inner: &mut O,
    stats: &mut Stats,
) -> crate::ode::Solution<N, ContactMode>
where
    S: OdeSystem<N, Mode = ContactMode>,
    O: Observer<N, ContactMode>,
    F: Fn(ContactMode) -> S,
{
    loop {
        let (stop, o) = if t < cap.until {
            (cap.until.min(t_end), Options { h_max: opts.h_max.min(cap.h), ..*opts })
        } else {
            (t_end, *opts)
        };
        let sys = make(mode);
        let mut w = Watched { inner: &mut *inner, slider, gap_always, missed: None };
        let sol = integrate(&sys, method, t, y, stop, &o, &mut w);
        *stats += sol.stats;
        if let Some((h, t0, y0, m0)) = w.missed {
            cap.refinements += 1;
            if cap.refinements > Cap::MAX {
                return crate::ode::Solution { outcome: Outcome::EventChatter, ..sol };
            }
            t = t0;
            y = y0;
            mode = m0;
            cap.until = t0 + 2.0 * h;
            cap.h = h / 4.0;
            continue;
        }
        if sol.outcome == Outcome::Finished && stop < t_end {
            t = stop;
            y = sol.y;
            mode = sol.mode;
            continue;
        }
        return sol;
    }
}
