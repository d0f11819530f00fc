//! The corrector: an orbit as a sequence of fixed-mode segments, one evaluation per iterate,
//! Newton on the bordered system, tangents, and what a corrected orbit reports.
//!
//! **Unknowns** `xi = (y0 without zd, tau_1 .. tau_K, p)`, scaled: the state by the characteristic
//! sizes, the durations by the starting period, `p` by its scale. **Equations**: the switching
//! condition `h_k(y_k) = 0` at the end of each segment but the last (the gap for lift-off and
//! landing, the law's force for a detachment), and periodicity `y_K - y0 = 0`; with the phase
//! condition `zd(0) = 0` built in, `K + 5` equations in `K + 6` unknowns: a curve. A contact piece
//! is one segment (`K = 1`): plain shooting with the monodromy matrix as Newton's matrix.
//!
//! Why segments rather than one run that locates its switches: near grazing the switching times
//! depend on the state through a square root (a flight of height `d` lasts as `sqrt(d)`), so the
//! one-run map is not differentiable there and Newton fails on both sides of the grazing point
//! (observed on the seed's saddle cycle at 36.83 N). With the durations as unknowns and the
//! switches as equations the problem is smooth through grazing, where a flight's duration passes
//! through zero (the multi-segment formulation of hybrid periodic orbits, as in COCO's `hspo`).
//! The Floquet multipliers are still those of the monodromy matrix with the saltation matrices at
//! the switches, `M = Phi_K S_{K-1} ... S_1 Phi_1`.

use super::flow::{event_scale, segment, FlowSettings, Model, Observed, SegmentWatch};
use super::{flags, BranchOptions, BranchPoint, PointType, C64};
use crate::linear::eigenvalues;
use crate::model::{event, idx, ContactMode, ContactModel, FrictionLaw, Jacobian, Params, State};
use crate::ode::Stats;
use crate::shooting::{saltation, FREE};
use crate::status::Status;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

pub(super) type Xi = DVector<f64>;
/// Derivatives of a state with respect to the unknowns.
type D6 = nalgebra::OMatrix<f64, nalgebra::U6, nalgebra::Dyn>;

/// The mode sequence of an orbit: segment modes, and the event that ends each segment but the last.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Seq {
    pub modes: Vec<ContactMode>,
    pub events: Vec<usize>,
}

impl Seq {
    /// One segment in contact: the bilateral law, or a unilateral orbit that never leaves the disk.
    pub fn contact() -> Seq {
        Seq { modes: vec![ContactMode::Contact], events: vec![] }
    }
    pub fn k(&self) -> usize {
        self.modes.len()
    }
    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.modes.len() + 6
    }
    /// Index of the parameter among the unknowns.
    pub fn ip(&self) -> usize {
        self.modes.len() + 5
    }
    /// True if the phase point is the top of a flight (first and last segments free).
    pub fn phase_in_flight(&self) -> bool {
        self.k() >= 3 && self.modes[0] == ContactMode::Free && self.modes[self.k() - 1] == ContactMode::Free
    }
}

/// Why a correction failed.
#[derive(Clone, Debug)]
pub(super) struct Failure {
    pub status: Status,
    pub reason: String,
}

pub(super) fn fail(status: Status, reason: String) -> Failure {
    Failure { status, reason }
}

/// Validity of the mode sequence on an orbit (what a change of sequence is detected on). Each
/// entry: value, segment, time in the segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Monitors {
    /// Smallest segment duration [s] (time: unused).
    pub tau_min: (f64, usize, f64),
    /// Largest gap at a maximum of z in contact (or at the phase point) [m]: > 0, a lift-off.
    pub contact_gap: (f64, usize, f64),
    /// Smallest law force at a minimum in contact (or at the phase point) [N]: < 0, a detachment.
    pub contact_law: (f64, usize, f64),
    /// Largest contact margin in a free segment [N]: > 0, a touch-down; and its event (gap or law).
    pub free_margin: (f64, usize, f64),
    pub free_margin_event: usize,
    /// Largest violation of a landing's other condition [m], and its switch: > 0, the landing
    /// changes its event (the pin lands on the gap instead of the law's force, or back).
    pub landing: (f64, usize, f64),
}

impl Monitors {
    fn new() -> Monitors {
        Monitors {
            tau_min: (f64::INFINITY, 0, 0.0),
            contact_gap: (f64::NEG_INFINITY, 0, 0.0),
            contact_law: (f64::INFINITY, 0, 0.0),
            free_margin: (f64::NEG_INFINITY, 0, 0.0),
            free_margin_event: event::GAP,
            landing: (f64::NEG_INFINITY, 0, 0.0),
        }
    }

    /// Each violated condition as a value that is > 0 when violated.
    pub fn violations(&self, law_scale: f64, gap_scale: f64, t_ref: f64) -> [f64; 5] {
        [
            -self.tau_min.0 / t_ref,
            self.contact_gap.0 / gap_scale,
            -self.contact_law.0 / law_scale,
            self.free_margin.0 / law_scale,
            self.landing.0 / gap_scale,
        ]
    }
}

/// An evaluated orbit: its unknowns, sequence, Jacobian, residual and what it looks like.
#[derive(Clone)]
pub(super) struct Eval {
    pub xi: Xi,
    pub seq: Seq,
    pub model: Model,
    pub jac: DMatrix<f64>,
    pub residual: f64,
    pub observed: Observed,
    pub monodromy: Jacobian,
    pub monitors: Monitors,
    pub iterations: u32,
}

/// Multiplier data of one orbit: sorted multipliers, the trivial one, counts and test functions.
#[derive(Clone, Copy, Debug)]
pub(super) struct Spectrum {
    pub rho: [C64; 6],
    pub trivial: usize,
    /// Real non-trivial multipliers above 1.
    pub n_real_pos: u8,
    /// Real non-trivial multipliers below -1.
    pub n_real_neg: u8,
    /// Complex non-trivial multipliers outside the unit circle.
    pub n_complex: u8,
    /// Non-trivial multipliers outside the unit circle.
    pub n_out: u8,
    /// `Re prod (rho + 1)` over the non-trivial ones.
    pub pd: f64,
    /// `Re prod_{i<j} (rho_i rho_j - 1)` over the non-trivial ones.
    pub ns: f64,
}

pub(super) fn spectrum(phi: &Jacobian) -> Option<Spectrum> {
    let mut ev = eigenvalues(phi)?;
    ev.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    let trivial = crate::shooting::trivial_index(&ev);
    let nt: Vec<C64> = (0..6).filter(|&k| k != trivial).map(|k| ev[k]).collect();
    let is_real = |c: &C64| c.im.abs() <= 1e-8 * c.norm().max(1.0);
    let count = |f: &dyn Fn(&C64) -> bool| nt.iter().filter(|c| f(c)).count() as u8;
    let mut pd = C64::new(1.0, 0.0);
    let mut ns = C64::new(1.0, 0.0);
    for (i, a) in nt.iter().enumerate() {
        pd *= a + 1.0;
        for b in &nt[i + 1..] {
            ns *= a * b - 1.0;
        }
    }
    Some(Spectrum {
        rho: ev,
        trivial,
        n_real_pos: count(&|c| is_real(c) && c.re > 1.0),
        n_real_neg: count(&|c| is_real(c) && c.re < -1.0),
        n_complex: count(&|c| !is_real(c) && c.norm() > 1.0),
        n_out: count(&|c| c.norm() > 1.0),
        pd: pd.re,
        ns: ns.re,
    })
}

/// The continuation's fixed context: model, parameter, scales, options, counters.
pub(super) struct Ctx<'a> {
    pub base: Params,
    pub name: &'a str,
    pub opts: BranchOptions,
    pub sizes: State,
    pub t_ref: f64,
    pub p_ref: f64,
    pub stats: Stats,
    pub n_flows: u32,
}

impl Ctx<'_> {
    pub fn pack(&self, y: &State, taus: &[f64], p: f64) -> Xi {
        let k = taus.len();
        Xi::from_fn(k + 6, |i, _| match i {
            0..=4 => y[FREE[i]] / self.sizes[FREE[i]],
            _ if i < 5 + k => taus[i - 5] / self.t_ref,
            _ => p / self.p_ref,
        })
    }

    pub fn unpack(&self, xi: &Xi) -> (State, Vec<f64>, f64) {
        let n = xi.len();
        let mut y = State::zeros();
        for (c, &j) in FREE.iter().enumerate() {
            y[j] = xi[c] * self.sizes[j];
        }
        let taus = (5..n - 1).map(|i| xi[i] * self.t_ref).collect();
        (y, taus, xi[n - 1] * self.p_ref)
    }

    fn settings(&self, rtol: f64) -> FlowSettings {
        FlowSettings {
            method: self.opts.method,
            rtol,
            sizes: self.sizes,
            p_ref: self.p_ref,
            max_switches: self.opts.max_switches,
        }
    }

    /// The model at parameter value `p` (with the sequence's law: a single contact segment is
    /// the bilateral law, which is the unilateral orbit too while the pin stays on the disk).
    pub fn model(&self, p: f64) -> Result<Model, Failure> {
        Model::new(&self.base, self.name, p, 1e-6 * self.p_ref)
            .map_err(|e| fail(Status::InvalidInput, format!("the branch reached an invalid parameter value: {e}")))
    }

    /// Segments at `xi`: residual, Jacobian, monodromy, observations.
    pub fn evaluate(&mut self, xi: &Xi, seq: &Seq, rtol: f64) -> Result<(Eval, Xi), Failure> {
        let (y0, taus, p) = self.unpack(xi);
        let period: f64 = taus.iter().sum();
        if !(period.is_finite() && period > 0.0 && y0.iter().all(|v| v.is_finite())) {
            return Err(fail(Status::NonFinite, format!("the iterate left the valid region (period {period:e} s)")));
        }
        let model = self.model(p)?;
        let s = &model.s;
        let fs = self.settings(rtol);
        let (k, n, ip) = (seq.k(), seq.n(), seq.ip());
        let sz = self.sizes;
        let record = rtol <= self.opts.rtol && taus.iter().all(|t| *t >= 0.0);
        let ns = self.opts.n_samples;
        let mut z = Vec::with_capacity(if record { ns } else { 0 });
        // D = d y_k / d xi (6 x n), carried along the segments.
        let mut d = D6::zeros(n);
        for (c, &j) in FREE.iter().enumerate() {
            d[(j, c)] = sz[j];
        }
        let d0 = d.clone();
        let mut res = Xi::zeros(k + 5);
        let mut jac = DMatrix::<f64>::zeros(k + 5, n);
        let mut mono = Jacobian::identity();
        let mut y = y0;
        let mut t_off = 0.0;
        let mut mon = Monitors::new();
        let mut law_min = f64::INFINITY;
        let mut slip_min = f64::INFINITY;
        let (mut z_max, mut z_min) = (f64::NEG_INFINITY, f64::INFINITY);
        self.n_flows += 1;
        for (i, (&mode, &tau)) in seq.modes.iter().zip(&taus).enumerate() {
            let samples = record.then_some((t_off, period / ns as f64, ns));
            let include_start = i == 0 && mode != ContactMode::Free;
            let sg =
                segment(&model, mode, &y, tau, &fs, samples, &mut z, include_start, &mut self.stats).map_err(|st| {
                    if st == Status::EventMissed && mode.slips() {
                        fail(
                            st,
                            format!(
                                "segment {i} of the orbit (slip) reaches zero sliding velocity at parameter \
                                          {p:.10e}: the orbit gains a stick phase there (a sliding bifurcation, which \
                                          continuation does not follow)"
                            ),
                        )
                    } else {
                        fail(st, format!("segment {i} of the orbit failed ({}) at parameter {p:.10e}", st.name()))
                    }
                })?;
            let f_end = s.rhs(&sg.y, mode);
            d = sg.phi * d;
            for r in 0..6 {
                d[(r, 5 + i)] += f_end[r] * self.t_ref;
                d[(r, ip)] += sg.psi[r] * self.p_ref;
            }
            watch(&mut mon, &sg.watch, mode, i, tau);
            if mode != ContactMode::Free {
                law_min = law_min.min(sg.watch.law_min.0);
                slip_min = slip_min.min(sg.watch.slip_min);
            }
            z_max = z_max.max(sg.watch.z_max);
            z_min = z_min.min(sg.watch.z_min);
            mono = sg.phi * mono;
            if i + 1 < k {
                let ev = seq.events[i];
                let scale = event_scale(s, &sz, ev);
                let (h, grad) = switching(&model, &sg.y, mode, ev);
                res[i] = h / scale;
                for c in 0..n {
                    let mut v = 0.0;
                    for r in 0..6 {
                        v += grad[r] * d[(r, c)];
                    }
                    jac[(i, c)] = v / scale;
                }
                jac[(i, ip)] += model.dhdp(&sg.y, mode, ev) * self.p_ref / scale;
                mono = saltation(s, &sg.y, mode, seq.modes[i + 1], ev) * mono;
                if mode == ContactMode::Free {
                    // A landing on one condition needs the other one met: on the gap, a law that
                    // pushes; on the law's force, the pin on the disk.
                    let v = match ev {
                        event::GAP => -(s.p.normal_load + s.dynamic_law_force(&sg.y)) / s.k_s,
                        _ => s.gap(&sg.y),
                    };
                    if v > mon.landing.0 {
                        mon.landing = (v, i, 0.0);
                    }
                }
            }
            y = sg.y;
            t_off += tau;
        }
        for r in 0..6 {
            res[k - 1 + r] = (y[r] - y0[r]) / sz[r];
            for c in 0..n {
                jac[(k - 1 + r, c)] = (d[(r, c)] - d0[(r, c)]) / sz[r];
            }
        }
        let observed = if record && z.len() == ns {
            harmonics(&z, z_max, z_min, &taus, seq, law_min, slip_min)
        } else {
            unobserved()
        };
        let residual = res.amax();
        let e = Eval {
            xi: xi.clone(),
            seq: seq.clone(),
            model,
            jac,
            residual,
            observed,
            monodromy: mono,
            monitors: mon,
            iterations: 0,
        };
        Ok((e, res))
    }

    /// Newton on `[equations; c . (xi - anchor)] = 0` from `xi0`, in sequence `seq`.
    pub fn correct(&mut self, xi0: &Xi, seq: &Seq, c: &Xi, anchor: &Xi) -> Result<Eval, Failure> {
        let o = self.opts;
        let n = seq.n();
        let mut xi = xi0.clone();
        let mut rtol = o.rtol.max(1e-7);
        let (mut e, mut r) = self.evaluate(&xi, seq, rtol)?;
        let mut iterations = 0;
        loop {
            if !e.residual.is_finite() {
                return Err(fail(Status::NonFinite, "non-finite residual".into()));
            }
            if e.residual <= o.tol && rtol <= o.rtol {
                e.iterations = iterations;
                return Ok(e);
            }
            if e.residual <= o.tol {
                rtol = o.rtol;
                (e, r) = self.evaluate(&xi, seq, rtol)?;
                continue;
            }
            if iterations >= o.max_newton {
                let why = format!("Newton did not converge in {iterations} steps (scaled residual {:.2e})", e.residual);
                return Err(fail(Status::NewtonNotConverged, why));
            }
            iterations += 1;
            let mut m = DMatrix::<f64>::zeros(n, n);
            m.rows_mut(0, n - 1).copy_from(&e.jac);
            m.row_mut(n - 1).copy_from(&c.transpose());
            let mut rhs = -r.clone();
            rhs = rhs.push(-c.dot(&(&xi - anchor)));
            let Some(dx) = m.lu().solve(&rhs).filter(|d| d.iter().all(|v| v.is_finite())) else {
                return Err(fail(Status::NewtonNotConverged, "singular Newton matrix".into()));
            };
            if dx.norm() > 0.5 {
                let why = format!("a Newton step of {:.2e} (scaled) would leave the branch's neighbourhood", dx.norm());
                return Err(fail(Status::NewtonNotConverged, why));
            }
            xi += dx;
            let prev = e.residual;
            rtol = (1e-3 * prev * prev).clamp(o.rtol, 1e-6);
            (e, r) = self.evaluate(&xi, seq, rtol)?;
            if e.residual > 2.0 * prev && iterations > 1 {
                let why = format!("Newton diverged: scaled residual grew from {prev:.2e} to {:.2e}", e.residual);
                return Err(fail(Status::NewtonNotConverged, why));
            }
        }
    }

    /// Unit null vector of the Jacobian, oriented with `prev` (bordered system).
    pub fn tangent(&self, jac: &DMatrix<f64>, prev: &Xi) -> Option<Xi> {
        let n = jac.ncols();
        let mut m = DMatrix::<f64>::zeros(n, n);
        m.rows_mut(0, n - 1).copy_from(jac);
        m.row_mut(n - 1).copy_from(&prev.transpose());
        let mut e = Xi::zeros(n);
        e[n - 1] = 1.0;
        let t = m.lu().solve(&e)?;
        let norm = t.norm();
        (norm.is_finite() && norm > 0.0).then(|| t / norm)
    }

    /// The branch point of an evaluated orbit.
    pub fn point(&self, e: &Eval, tangent: &Xi, arclength: f64) -> BranchPoint {
        let (y0, taus, p) = self.unpack(&e.xi);
        let sp = spectrum(&e.monodromy);
        let o = &e.observed;
        let nan = C64::new(f64::NAN, f64::NAN);
        let (rho, trivial) = sp.map_or(([nan; 6], 0), |s| (s.rho, s.trivial));
        let moduli: Vec<f64> = (0..6).filter(|&k| k != trivial).map(|k| rho[k].norm()).collect();
        let trivial_error = (rho[trivial] - 1.0).norm();
        let min_gap = -(e.model.s.z_st + o.z_max);
        let law = self.base.contact;
        let mut fl = 0;
        if trivial_error.is_nan() || trivial_error > 1e-6 {
            fl |= flags::TRIVIAL_MULTIPLIER_OFF;
        }
        if o.min_law_force < 0.0 {
            fl |= flags::LAW_TENSION;
        }
        if law == ContactModel::Bilateral && min_gap < 0.0 {
            fl |= flags::OUTSIDE_BILATERAL_VALIDITY;
        }
        let p_m = &e.model.s.p;
        if p_m.friction_law == FrictionLaw::Switch && o.min_slip_velocity < p_m.stick_band {
            fl |= flags::SLIP_IN_STICK_BAND;
        }
        BranchPoint {
            parameter: p,
            period: taus.iter().sum(),
            state0: y0,
            multipliers: rho,
            trivial,
            trivial_error,
            stable: sp.is_some() && moduli.iter().all(|m| *m < 1.0 - self.opts.stability_tol),
            n_unstable: moduli.iter().filter(|m| **m > 1.0).count() as u8,
            a0: o.a0,
            a1: o.a1,
            z_max: o.z_max,
            z_min: o.z_min,
            min_gap,
            min_law_force: o.min_law_force,
            open_fraction: o.open_fraction,
            min_slip_velocity: o.min_slip_velocity,
            n_switches: e.seq.events.len() as u32,
            dp_ds: tangent[tangent.len() - 1] * self.p_ref,
            arclength,
            point_type: PointType::Regular,
            contact: law,
            newton_iterations: e.iterations,
            residual: e.residual,
            flags: fl,
        }
    }
}

/// Switching function `h` of event `ev` at `y` and its gradient.
fn switching(m: &Model, y: &State, mode: ContactMode, ev: usize) -> (f64, State) {
    let s = &m.s;
    let grad = crate::shooting::switch_normal(s, y, ev).unwrap_or_else(State::zeros);
    let h = match ev {
        event::GAP => s.gap(y),
        _ => {
            let mut g = [0.0; crate::ode::MAX_EVENTS];
            crate::ode::OdeSystem::<6>::events(s, 0.0, y, mode, &mut g);
            g[ev]
        }
    };
    (h, grad)
}

fn watch(mon: &mut Monitors, w: &SegmentWatch, mode: ContactMode, i: usize, tau: f64) {
    if tau < mon.tau_min.0 {
        mon.tau_min = (tau, i, 0.0);
    }
    if mode == ContactMode::Free {
        if w.margin_max.0 > mon.free_margin.0 {
            mon.free_margin = (w.margin_max.0, i, w.margin_max.1);
            mon.free_margin_event = w.margin_max.2;
        }
    } else {
        if w.gap_max.0 > mon.contact_gap.0 {
            mon.contact_gap = (w.gap_max.0, i, w.gap_max.1);
        }
        if w.law_min.0 < mon.contact_law.0 {
            mon.contact_law = (w.law_min.0, i, w.law_min.1);
        }
    }
}

fn unobserved() -> Observed {
    let nan = f64::NAN;
    Observed {
        a0: nan,
        a1: nan,
        z_max: nan,
        z_min: nan,
        min_law_force: nan,
        open_fraction: nan,
        min_slip_velocity: nan,
    }
}

fn harmonics(z: &[f64], z_max: f64, z_min: f64, taus: &[f64], seq: &Seq, law_min: f64, slip_min: f64) -> Observed {
    let n = z.len();
    let (mut a, mut b) = (0.0, 0.0);
    for (k, v) in z.iter().enumerate() {
        let (sn, cs) = (2.0 * PI * k as f64 / n as f64).sin_cos();
        a += v * cs;
        b += v * sn;
    }
    let free: f64 = seq.modes.iter().zip(taus).filter(|(m, _)| **m == ContactMode::Free).map(|(_, t)| t).sum();
    Observed {
        a0: z.iter().sum::<f64>() / n as f64,
        a1: (2.0 * a / n as f64).hypot(2.0 * b / n as f64),
        z_max,
        z_min,
        min_law_force: law_min,
        open_fraction: free / taus.iter().sum::<f64>(),
        min_slip_velocity: if slip_min.is_finite() { slip_min } else { f64::NAN },
    }
}

/// A point on the branch with what the continuation needs to go on.
pub(super) struct Node {
    pub e: Eval,
    pub tangent: Xi,
    pub point: BranchPoint,
    pub spec: Option<Spectrum>,
}

pub(super) fn node(ctx: &Ctx<'_>, e: Eval, tangent: Xi, arclength: f64) -> Node {
    let point = ctx.point(&e, &tangent, arclength);
    let spec = spectrum(&e.monodromy);
    Node { e, tangent, point, spec }
}

/// `true` if the orbit is a physical orbit of the model in its sequence: every segment lasts,
/// in contact the pin stays on the disk and the law pushes, in flight the pin is not in contact.
/// (The bilateral law: always.)
pub(super) fn valid(ctx: &Ctx<'_>, e: &Eval) -> bool {
    ctx.base.contact == ContactModel::Bilateral || ctx.violations(e).iter().all(|v| v.is_nan() || *v <= 0.0)
}

impl Ctx<'_> {
    /// The validity conditions of `e`'s sequence, each > 0 when violated (see [`Monitors`]).
    pub fn violations(&self, e: &Eval) -> [f64; 5] {
        let gap = self.sizes[idx::Z];
        e.monitors.violations(e.model.s.k_s * gap, gap, self.t_ref)
    }
}
