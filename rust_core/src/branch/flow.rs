//! The flows of a branch: fixed-mode segments with their monodromy matrix and parameter
//! sensitivity, and one run that locates its switches to learn a given orbit's mode sequence.
//!
//! A segment integrates the state, its monodromy matrix `Phi` and the sensitivity to the
//! continuation parameter `psi = dy/dp` together (48 components): `Phi' = J Phi`,
//! `psi' = J psi + df/dp`, with `df/dp` a central difference of the right-hand side between two
//! copies of the slider at `p +- h` (the right-hand side is polynomial in every parameter, so this
//! is exact to rounding, about `eps |f| / h`). Its mode is fixed: no switch is taken inside it
//! (the switches are the equations between segments, see `solve.rs`); instead the segment watches
//! where its mode stops being the physical one (a lift-off in contact, a touch-down in flight, a
//! law force that pulls), located on the dense output.

use crate::model::{event, idx, ContactMode, FrictionLaw, Jacobian, Params, Slider, State};
use crate::ode::{Control, EventAction, Method, Observer, OdeSystem, Options, Outcome, Stats, StepView, MAX_EVENTS};
use crate::shooting::{run_watched, switch_normal, Cap};
use crate::status::Status;
use nalgebra::SVector;

/// `[y, Phi[:,0], ..., Phi[:,5], psi]`.
type Aug = SVector<f64, 48>;

/// The slider at the parameter value and two copies at `p +- h` for `df/dp`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Model {
    pub s: Slider,
    plus: Slider,
    minus: Slider,
    /// `1 / (p+ - p-)`.
    inv_dp: f64,
}

/// Scale of event function `index` (gap [m], law force [N]) for the scaled residual.
pub(crate) fn event_scale(s: &Slider, sizes: &State, index: usize) -> f64 {
    match index {
        event::GAP => sizes[idx::Z],
        _ => s.k_s * sizes[idx::Z],
    }
}

impl Model {
    /// `p` with `name = value` (validated), and the copies at `value +- h` (one-sided where a
    /// copy would be invalid, e.g. `mu - h < 0`).
    pub fn new(p: &Params, name: &str, value: f64, h: f64) -> Result<Model, crate::ParamError> {
        let at = |v: f64| {
            let mut q = *p;
            q.set(name, v)?;
            Slider::new(q)
        };
        let s = at(value)?;
        let (plus, up) = at(value + h).map_or((s, value), |x| (x, value + h));
        let (minus, down) = at(value - h).map_or((s, value), |x| (x, value - h));
        let inv_dp = if up > down { 1.0 / (up - down) } else { 0.0 };
        Ok(Model { s, plus, minus, inv_dp })
    }

    #[inline(always)]
    pub fn dfdp(&self, x: &State, mode: ContactMode) -> State {
        (self.plus.rhs(x, mode) - self.minus.rhs(x, mode)) * self.inv_dp
    }

    /// The three sliders with the switch law's slip sign fixed ([`Slider::with_slip_sign`]).
    pub fn with_slip_sign(&self, sign: f64) -> Model {
        Model {
            s: self.s.with_slip_sign(sign),
            plus: self.plus.with_slip_sign(sign),
            minus: self.minus.with_slip_sign(sign),
            inv_dp: self.inv_dp,
        }
    }

    /// `dh/dp` of event `index` at `x`.
    pub fn dhdp(&self, x: &State, mode: ContactMode, index: usize) -> f64 {
        let (mut gp, mut gm) = ([0.0; MAX_EVENTS], [0.0; MAX_EVENTS]);
        OdeSystem::<6>::events(&self.plus, 0.0, x, mode, &mut gp);
        OdeSystem::<6>::events(&self.minus, 0.0, x, mode, &mut gm);
        (gp[index] - gm[index]) * self.inv_dp
    }
}

struct Sens<'a> {
    m: &'a Model,
    start: ContactMode,
}

#[inline]
fn state_of(y: &Aug) -> State {
    State::from_fn(|i, _| y[i])
}

impl OdeSystem<48> for Sens<'_> {
    type Mode = ContactMode;

    #[inline]
    fn rhs(&self, _t: f64, y: &Aug, mode: ContactMode) -> Aug {
        let x = state_of(y);
        let f = self.m.s.rhs(&x, mode);
        let j = self.m.s.jacobian(&x, mode);
        let fp = self.m.dfdp(&x, mode);
        let mut out = Aug::zeros();
        for i in 0..6 {
            out[i] = f[i];
        }
        // Columns of Phi, then psi: explicit loops (the inner loop of the continuation).
        for c in 0..7 {
            let b = 6 + 6 * c;
            for r in 0..6 {
                let mut acc = if c == 6 { fp[r] } else { 0.0 };
                for k in 0..6 {
                    acc += j[(r, k)] * y[b + k];
                }
                out[b + r] = acc;
            }
        }
        out
    }

    fn initial_mode(&self, _t: f64, _y: &Aug) -> ContactMode {
        self.start
    }

    fn n_events(&self) -> usize {
        OdeSystem::<6>::n_events(&self.m.s)
    }

    #[inline]
    fn events(&self, t: f64, y: &Aug, mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        OdeSystem::<6>::events(&self.m.s, t, &state_of(y), mode, g);
    }

    fn on_event(&self, t: f64, y: &Aug, mode: ContactMode, index: usize) -> EventAction<ContactMode> {
        OdeSystem::<6>::on_event(&self.m.s, t, &state_of(y), mode, index)
    }
}

/// What the branch keeps of an orbit besides its monodromy: harmonics and extremes of `z`, the
/// law's normal force, the time off the disk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Observed {
    /// Mean of `z` [m].
    pub a0: f64,
    /// First-harmonic amplitude of `z` [m].
    pub a1: f64,
    /// Largest `z`, located on the dense output where `zd` changes sign [m].
    pub z_max: f64,
    /// Smallest `z` [m].
    pub z_min: f64,
    /// Smallest total normal force of the contact law in contact [N].
    pub min_law_force: f64,
    /// Fraction of the period off the disk (in free segments).
    pub open_fraction: f64,
    /// Smallest `|v_r|` in contact [m/s] (0 where the orbit sticks; NaN: never in contact).
    pub min_slip_velocity: f64,
}

/// Records the mode switches of a run (taking each one).
struct Switches {
    hit: Option<(usize, ContactMode, ContactMode)>,
    list: Vec<Switch>,
}

impl Observer<48, ContactMode> for Switches {
    fn on_event(&mut self, index: usize, t: f64, _y: &Aug, before: ContactMode, after: ContactMode) -> Control {
        if before != after {
            self.hit = Some((index, before, after));
            self.list.push(Switch { t, index, after });
            Control::Stop
        } else {
            Control::Continue
        }
    }
}

/// A mode switch located on the way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Switch {
    /// Time [s].
    pub t: f64,
    /// Event index.
    pub index: usize,
    /// Mode after it.
    pub after: ContactMode,
}

/// Integration settings of one flow.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FlowSettings {
    pub method: Method,
    pub rtol: f64,
    /// Characteristic sizes of the state (absolute tolerances are `rtol` times them).
    pub sizes: State,
    /// Parameter scale (the sensitivity's absolute tolerance is `rtol sizes / p_ref`).
    pub p_ref: f64,
    pub max_switches: u32,
}

fn options(fs: &FlowSettings) -> Options<48> {
    let sz = fs.sizes;
    let mut o = Options::<48>::new(fs.rtol, 1.0);
    o.max_steps = crate::shooting::ORBIT_FLOW_MAX_STEPS;
    for i in 0..6 {
        o.atol[i] = fs.rtol * sz[i];
        for j in 0..6 {
            o.atol[6 + 6 * j + i] = fs.rtol * sz[i] / sz[j];
        }
        o.atol[42 + i] = fs.rtol * sz[i] / fs.p_ref;
    }
    o
}

/// The mode switches of the orbit through `y0` over `[0, t_end]`: a run that locates every switch
/// and takes it (with the local refinement of today's shooting for hops shorter than a step).
///
/// # Errors
/// The status of a failed run (`Diverged` when the escape event fires, `EventChatter` past
/// `max_switches`).
pub(crate) fn switches(
    m: &Model,
    y0: &State,
    t_end: f64,
    fs: &FlowSettings,
    stats: &mut Stats,
) -> Result<Vec<Switch>, Status> {
    let s = &m.s;
    let o = options(fs);
    let mut y = Aug::zeros();
    for i in 0..6 {
        y[i] = y0[i];
        y[6 + 7 * i] = 1.0;
    }
    let (mut t, mut mode) = (0.0, s.mode_at(y0));
    let mut cap = Cap::NONE;
    let mut obs = Switches { hit: None, list: Vec::new() };
    loop {
        obs.hit = None;
        let make = |md| Sens { m, start: md };
        let sol = run_watched(make, s, fs.method, t, y, mode, t_end, &o, false, &mut cap, &mut obs, stats);
        match sol.outcome {
            Outcome::Finished => return Ok(obs.list),
            Outcome::StoppedByObserver => {
                let Some((_, _, after)) = obs.hit else { return Err(Status::NotConverged) };
                if obs.list.len() > fs.max_switches as usize {
                    return Err(Status::EventChatter);
                }
                (t, y, mode) = (sol.t, sol.y, after);
            }
            Outcome::StoppedByEvent => return Err(Status::Diverged),
            other => return Err(other.status()),
        }
    }
}

/// One segment of a fixed mode: the 48-component flow without events, backwards in time for a
/// negative duration (a virtual segment while the branch crosses a change of the mode sequence).
struct Fixed<'a> {
    m: &'a Model,
    mode: ContactMode,
    sign: f64,
}

impl OdeSystem<48> for Fixed<'_> {
    type Mode = ContactMode;

    #[inline]
    fn rhs(&self, t: f64, y: &Aug, _mode: ContactMode) -> Aug {
        Sens { m: self.m, start: self.mode }.rhs(t, y, self.mode) * self.sign
    }

    fn initial_mode(&self, _t: f64, _y: &Aug) -> ContactMode {
        self.mode
    }
}

/// What a segment sees of its orbit: where its mode stops being the physical one, and samples.
///
/// Each extreme is located on the dense output (bisection on the sign of its rate) and comes with
/// its time from the segment start.
#[derive(Clone, Debug)]
pub(crate) struct SegmentWatch {
    /// Largest gap `zc` at a maximum of `z` (and at the start when `include_start`) [m]: > 0 in a
    /// contact segment means the pin lifts off there.
    pub gap_max: (f64, f64),
    /// Smallest law force at a minimum of it (and at the start when `include_start`) [N]: < 0 in a
    /// contact segment means the law pulls there (the pin detaches by force).
    pub law_min: (f64, f64),
    /// Largest contact margin `min(-zc K_s, N_law)` at a minimum of `z` or a maximum of the law
    /// force [N]: > 0 in a free segment means the pin would be in contact there.
    pub margin_max: (f64, f64, usize),
    /// Largest and smallest `z` [m].
    pub z_max: f64,
    pub z_min: f64,
    /// Smallest `|v_r|` in sliding contact [m/s], at the step ends and the extremes of `v_r`
    /// (0 in a stick or transition segment, or where `v_r` changes sign; infinite off the disk).
    pub slip_min: f64,
}

struct SegObs<'a> {
    s: &'a Slider,
    mode: ContactMode,
    /// Global time of the segment start and sample spacing (0: no samples).
    t_off: f64,
    dt: f64,
    n: usize,
    z: &'a mut Vec<f64>,
    w: SegmentWatch,
    diverged: bool,
    /// Slip under the switch law: the sign of the sliding velocity at the segment's start (0: not
    /// watched), and whether it reached zero, where the slip force reverses.
    slip_sign: f64,
    slip_reversed: bool,
}

impl SegObs<'_> {
    fn law(&self, y: &State) -> f64 {
        self.s.p.normal_load + self.s.dynamic_law_force(y)
    }

    /// Rates whose sign changes mark the extremes: `zd`, `dN_law/dt` and `dv_r/dt`.
    fn rates(&self, y: &Aug) -> [f64; 3] {
        let x = state_of(y);
        let n = switch_normal(self.s, &x, event::NORMAL).unwrap_or_else(State::zeros);
        let f = self.s.rhs(&x, self.mode);
        let sl = self.s.p.torsion_sign * self.s.p.moment_arm;
        [y[idx::ZD], n.dot(&f), -(f[idx::XD] + sl * f[idx::PHID])]
    }

    /// `|v_r|` at `x` into the segment's smallest (sliding contact only).
    fn slip_at(&mut self, x: &State) {
        if self.mode.slips() {
            self.w.slip_min = self.w.slip_min.min(self.s.slip_velocity(x).abs());
        }
    }

    fn extreme(&mut self, y: &Aug, t: f64, which: usize, up: bool) {
        let x = state_of(y);
        if which == 2 {
            // A minimum of the slip inside a step that reaches zero: the slip force reverses
            // there, though both step ends slip the same way (the flow's field is continued past
            // zero, `Slider::with_slip_sign`).
            if self.slip_sign != 0.0 && self.s.slip_velocity(&x) * self.slip_sign <= 0.0 {
                self.slip_reversed = true;
            }
            self.slip_at(&x);
            return;
        }
        let (zc, law) = (self.s.z_st + x[idx::Z], self.law(&x));
        let w = &mut self.w;
        w.z_max = w.z_max.max(x[idx::Z]);
        w.z_min = w.z_min.min(x[idx::Z]);
        match (which, up) {
            (0, true) if zc > w.gap_max.0 => w.gap_max = (zc, t),
            (1, false) if law < w.law_min.0 => w.law_min = (law, t),
            _ => {}
        }
        // A minimum of z or a maximum of the law force: where a free pin comes closest to contact.
        if (which == 0 && !up) || (which == 1 && up) {
            let margin = (-zc * self.s.k_s).min(law);
            if margin > w.margin_max.0 {
                w.margin_max = (margin, t, if -zc * self.s.k_s <= law { event::GAP } else { event::NORMAL });
            }
        }
    }
}

impl Observer<48, ContactMode> for SegObs<'_> {
    fn on_step(&mut self, st: &StepView<'_, 48, ContactMode>) -> Control {
        while self.dt > 0.0 && self.z.len() < self.n {
            let t = self.dt * self.z.len() as f64 - self.t_off;
            if t > st.t1 {
                break;
            }
            let v = if t <= st.t0 { *st.y0 } else { st.dense.eval(t) };
            self.z.push(v[idx::Z]);
        }
        self.w.z_max = self.w.z_max.max(st.y1[idx::Z]);
        self.w.z_min = self.w.z_min.min(st.y1[idx::Z]);
        // Interior extremes: a rate changes sign on 4 sub-intervals, bisected on the dense output.
        const SUB: usize = 4;
        let mut prev = (st.t0, self.rates(st.y0));
        for k in 1..=SUB {
            let tk = st.t0 + (st.t1 - st.t0) * k as f64 / SUB as f64;
            let yk = if k == SUB { *st.y1 } else { st.dense.eval(tk) };
            let rk = self.rates(&yk);
            // v_r's extremes (the last rate) matter in sliding contact only.
            let n_rates = if self.mode.slips() { 3 } else { 2 };
            for (which, (&a, &b)) in prev.1.iter().zip(&rk).enumerate().take(n_rates) {
                if (a > 0.0 && b <= 0.0) || (a < 0.0 && b >= 0.0) {
                    let up = a > 0.0;
                    let (mut lo, mut hi) = (prev.0, tk);
                    for _ in 0..100 {
                        let mid = 0.5 * (lo + hi);
                        if mid <= lo || mid >= hi {
                            break;
                        }
                        if (self.rates(&st.dense.eval(mid))[which] > 0.0) == up {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let t = 0.5 * (lo + hi);
                    self.extreme(&st.dense.eval(t), t, which, up);
                }
            }
            prev = (tk, rk);
        }
        let vr1 = self.s.slip_velocity(&state_of(st.y1));
        if self.mode.slips() {
            let crossed = self.s.slip_velocity(&state_of(st.y0)) * vr1 <= 0.0;
            self.w.slip_min = if crossed { 0.0 } else { self.w.slip_min.min(vr1.abs()) };
        }
        if st.y1[idx::Z].abs() > self.s.p.escape_limit {
            self.diverged = true;
            return Control::Stop;
        }
        // A slip segment whose sliding velocity reaches zero has left its mode: the slip force
        // `mu N sign(v_r)` reverses there and a fixed-mode flow chatters across it in ever smaller
        // steps (one continuation flow took millions); the orbit has gained a stick phase.
        if self.slip_reversed || (self.slip_sign != 0.0 && vr1 * self.slip_sign <= 0.0) {
            self.slip_reversed = true;
            return Control::Stop;
        }
        Control::Continue
    }
}

/// One fixed-mode segment from `y0` over `tau` (backwards for `tau < 0`).
#[derive(Clone, Debug)]
pub(crate) struct Segment {
    pub y: State,
    pub phi: Jacobian,
    pub psi: State,
    pub watch: SegmentWatch,
}

/// Integrate one segment of mode `mode` from `y0` for `tau` seconds. `samples`: the global time
/// of its start, the spacing and count of the uniform `z` samples of the whole orbit (appended to
/// `z`), or `None`. `include_start` counts the start point among the maxima (the phase point).
#[allow(clippy::too_many_arguments)]
pub(crate) fn segment(
    m: &Model,
    mode: ContactMode,
    y0: &State,
    tau: f64,
    fs: &FlowSettings,
    samples: Option<(f64, f64, usize)>,
    z: &mut Vec<f64>,
    include_start: bool,
    stats: &mut Stats,
) -> Result<Segment, Status> {
    let mut y = Aug::zeros();
    for i in 0..6 {
        y[i] = y0[i];
        y[6 + 7 * i] = 1.0;
    }
    let (zc0, law0) = (m.s.z_st + y0[idx::Z], m.s.p.normal_load + m.s.dynamic_law_force(y0));
    let w = SegmentWatch {
        gap_max: if include_start { (zc0, 0.0) } else { (f64::NEG_INFINITY, 0.0) },
        law_min: if include_start { (law0, 0.0) } else { (f64::INFINITY, 0.0) },
        margin_max: (f64::NEG_INFINITY, 0.0, event::GAP),
        z_max: y0[idx::Z],
        z_min: y0[idx::Z],
        slip_min: match mode {
            ContactMode::Contact | ContactMode::SlipBack => m.s.slip_velocity(y0).abs(),
            ContactMode::Free => f64::INFINITY,
            _ => 0.0,
        },
    };
    let (t_off, dt, n) = samples.unwrap_or((0.0, 0.0, 0));
    let slip = m.s.p.friction_law == FrictionLaw::Switch && mode.slips();
    let slip_sign = if slip { m.s.slip_velocity(y0).signum() } else { 0.0 };
    // The slip field of the segment's direction, continued past v_r = 0 (`with_slip_sign`).
    let signed;
    let m = if slip {
        signed = m.with_slip_sign(slip_sign);
        &signed
    } else {
        m
    };
    let mut obs = SegObs { s: &m.s, mode, t_off, dt, n, z, w, diverged: false, slip_sign, slip_reversed: false };
    if tau == 0.0 {
        return Ok(Segment { y: *y0, phi: Jacobian::identity(), psi: State::zeros(), watch: obs.w });
    }
    let sys = Fixed { m, mode, sign: tau.signum() };
    let sol = crate::ode::integrate(&sys, fs.method, 0.0, y, tau.abs(), &options(fs), &mut obs);
    *stats += sol.stats;
    if obs.diverged {
        return Err(Status::Diverged);
    }
    if obs.slip_reversed {
        return Err(Status::EventMissed);
    }
    if sol.outcome != Outcome::Finished {
        return Err(sol.outcome.status());
    }
    let yy = sol.y;
    Ok(Segment {
        y: state_of(&yy),
        phi: Jacobian::from_fn(|r, c| yy[6 + 6 * c + r]),
        psi: State::from_fn(|i, _| yy[42 + i]),
        watch: obs.w,
    })
}
