//! Branches of periodic orbits: pseudo-arclength continuation of the shooting problem in one
//! model parameter, with Floquet multipliers at every point and the bifurcations of cycles
//! located on the branch (issue 12, items 3 and 4).
//!
//! **The problem** (`solve.rs`). An orbit is a sequence of fixed-mode segments (one in contact
//! for the bilateral law and for a unilateral orbit that never leaves the disk; flights, contacts
//! and detachments otherwise). Unknowns `u = (y0 without zd, tau_1..tau_K, p)`, scaled: state
//! components by the slider's characteristic sizes (from a Hopf point, the friction-direction
//! ones at least the critical mode's: `follow::hopf_sizes`), durations by the starting period, `p`
//! by its starting magnitude. Equations: the switching condition at the end of each segment but the
//! last, periodicity `y_K - y0 = 0` with the phase condition `zd(0) = 0` built in (as in
//! [`crate::shooting`]), and the pseudo-arclength row `tau . (u - u_pred) = 0`. One segment is
//! plain shooting with the monodromy matrix `[Phi - I | f | dy/dp]` as Newton's matrix; with
//! switches the Jacobian chains the segments' `Phi` (no saltation needed: the switches are
//! equations), which keeps the problem smooth through grazing, where a flight's duration passes
//! through zero (the one-run map has a square root there: Newton stalls on both sides). The
//! Floquet multipliers are those of the monodromy matrix with the saltation matrices at the
//! switches. `flow.rs` integrates a segment with `Phi` and `dy/dp` (48 components).
//!
//! **A step** (`follow.rs`). Tangent predictor `u + ds tau`; Newton corrector on the bordered
//! system (the first integrations at a graded, lower accuracy as in the shooting, convergence only
//! judged at full accuracy). A step that does not converge, turns the tangent by more than
//! `max_turn`, or lands farther from its prediction than half a step is halved; below `ds_min`
//! the branch ends with a status and a reason. The tangent is the null vector of the Jacobian,
//! from the bordered system `[J; tau_prev] t = e_n` (so it keeps its orientation through folds).
//!
//! **Test functions** between consecutive points, each located by a bracketed secant (Illinois)
//! search along the segment with pseudo-arclength corrections, to `locate_tol` in scaled
//! arclength (a count by bisection):
//! - fold of cycles: the parameter component of the tangent changes sign;
//! - period doubling: `Re prod (rho_i + 1)` over the non-trivial multipliers changes sign (a real
//!   multiplier through -1);
//! - Neimark-Sacker: complex non-trivial multipliers cross the unit circle (located on
//!   `Re prod_{i<j} (rho_i rho_j - 1)`, or by bisection on the count);
//! - branch point: a real multiplier through +1 without a fold (another branch of cycles crosses:
//!   never silent);
//! - grazing: with the bilateral law, `min_gap = -max_t zc(t)` changes sign (the orbit first
//!   touches contact loss; past it the law is outside its validity, flagged). With the unilateral
//!   law an orbit stops being physical in its sequence (`sequence.rs`): the point is located on
//!   the violated condition, the sequence changes (a flight or a detachment appears or vanishes,
//!   a landing changes its event), and the branch goes on along the physical piece. Where it
//!   turns back in the parameter, two cycles meet and end: a non-smooth fold, flagged.
//!
//! **Never silent.** A point whose tangent turned sharply or whose correction jumped (accepted only
//! at `ds_min`), whose trivial multiplier is off 1, or whose special point could not be located
//! carries a flag; the branch's end says why.

mod curve;
mod flow;
mod follow;
mod locate;
mod sequence;
mod solve;
#[cfg(test)]
mod tests;

pub use curve::{special_curve, Curve, CurveKind, CurvePoint};

use crate::model::{ContactModel, Params, Slider, State, PARAM_NAMES};
use crate::ode::{Method, Stats};
use crate::shooting::scales;
use crate::status::Status;
use nalgebra::Complex;
use solve::Ctx;
use std::f64::consts::PI;
use thiserror::Error;

type C64 = Complex<f64>;

/// What a point on a branch is (CF `flag_values`, in the order of [`POINT_TYPE_NAMES`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum PointType {
    /// An ordinary continuation point.
    Regular = 0,
    /// Fold of cycles (the parameter turns back; a real multiplier through +1).
    Fold = 1,
    /// Period doubling (a real multiplier through -1).
    PeriodDoubling = 2,
    /// Neimark-Sacker (a complex pair through the unit circle: a torus).
    NeimarkSacker = 3,
    /// Grazing: the orbit touches contact loss (`min_gap = 0`).
    Grazing = 4,
    /// A Hopf point of steady sliding (zero amplitude).
    Hopf = 5,
    /// The last point, on a bound of the parameter window.
    End = 6,
    /// A real multiplier through +1 without a fold: another branch of cycles crosses here.
    BranchPoint = 7,
    /// Switch law: the orbit's slip first reaches the stick band (`min_slip_velocity` = the
    /// band's half-width): it gains a stick phase, a sliding bifurcation. The branch ends here.
    Stick = 8,
}

/// Names of [`PointType`], in code order.
pub const POINT_TYPE_NAMES: [&str; 9] =
    ["regular", "fold", "period_doubling", "neimark_sacker", "grazing", "hopf", "end", "branch_point", "stick"];

/// Bits of [`BranchPoint::flags`] (CF `flag_masks`, names in [`FLAG_NAMES`]).
pub mod flags {
    /// The step to this point turned the tangent sharply or its correction jumped far from the
    /// prediction, and was accepted only at the smallest step: it may have switched branch.
    pub const SWITCH_SUSPECTED: u8 = 1;
    /// The trivial multiplier is off 1 by more than `1e-6`: the monodromy is inaccurate.
    pub const TRIVIAL_MULTIPLIER_OFF: u8 = 2;
    /// The contact law's total normal force is negative somewhere on the orbit.
    pub const LAW_TENSION: u8 = 4;
    /// Bilateral law with the pin off the disk somewhere: outside the law's validity.
    pub const OUTSIDE_BILATERAL_VALIDITY: u8 = 8;
    /// A special point that could not be located: it is reported at the end of its bracket.
    pub const NOT_LOCATED: u8 = 16;
    /// A grazing point where the branch turns back in the parameter (a non-smooth fold: two
    /// cycles, with and without the new switches, meet there and end).
    pub const PARAMETER_TURNS: u8 = 32;
    /// Switch law: the orbit slips with `|v_r|` inside the stick band somewhere, where the law
    /// would stick: past a sliding bifurcation (the cycle has gained a stick phase).
    pub const SLIP_IN_STICK_BAND: u8 = 64;
}

/// Names of the bits of [`flags`], lowest first.
pub const FLAG_NAMES: [&str; 7] = [
    "switch_suspected",
    "trivial_multiplier_off",
    "law_tension",
    "outside_bilateral_validity",
    "not_located",
    "parameter_turns",
    "slip_in_stick_band",
];

/// Options of the continuation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BranchOptions {
    /// Integration method.
    pub method: Method,
    /// Relative tolerance of the integration (absolute ones from the characteristic sizes).
    pub rtol: f64,
    /// Newton converges when the scaled periodicity residual (infinity norm) is below this.
    pub tol: f64,
    /// Most Newton steps per correction.
    pub max_newton: u32,
    /// First step, in scaled arclength.
    pub ds: f64,
    /// Smallest step: below it the branch ends.
    pub ds_min: f64,
    /// Largest step.
    pub ds_max: f64,
    /// Most points on the branch (special points included).
    pub max_points: usize,
    /// Special points are located to this, in scaled arclength.
    pub locate_tol: f64,
    /// A non-trivial multiplier counts as on the unit circle within this (for `stable`).
    pub stability_tol: f64,
    /// Samples of `z` per period for the harmonics.
    pub n_samples: usize,
    /// Most contact switches in one period.
    pub max_switches: u32,
    /// Amplitude of the first orbit of a branch started at a Hopf point, in units of `|z_st|`.
    pub hopf_amplitude: f64,
    /// Largest angle between consecutive tangents [rad] before a step is halved.
    pub max_turn: f64,
    /// The branch ends when the period exceeds this times the starting period.
    pub max_period_ratio: f64,
    /// End the branch at the first located point of this type.
    pub stop_at: Option<PointType>,
}

impl Default for BranchOptions {
    fn default() -> Self {
        BranchOptions {
            method: Method::Dop853,
            rtol: 1e-11,
            tol: 1e-9,
            max_newton: 8,
            ds: 0.02,
            ds_min: 1e-6,
            ds_max: 0.1,
            max_points: 1000,
            locate_tol: 1e-8,
            stability_tol: 1e-6,
            n_samples: 256,
            max_switches: 64,
            hopf_amplitude: 0.02,
            max_turn: 0.5,
            max_period_ratio: 20.0,
            stop_at: None,
        }
    }
}

/// One point of a branch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BranchPoint {
    /// Value of the continuation parameter.
    pub parameter: f64,
    /// Period T [s].
    pub period: f64,
    /// State at t = 0 (`zd = 0`).
    pub state0: State,
    /// Floquet multipliers, by modulus descending.
    pub multipliers: [C64; 6],
    /// Index of the trivial multiplier (closest to 1).
    pub trivial: usize,
    /// `|rho_trivial - 1|`.
    pub trivial_error: f64,
    /// Every non-trivial multiplier has modulus below `1 - stability_tol`.
    pub stable: bool,
    /// Non-trivial multipliers outside the unit circle.
    pub n_unstable: u8,
    /// Mean of z [m].
    pub a0: f64,
    /// First harmonic of z [m].
    pub a1: f64,
    /// Largest z [m].
    pub z_max: f64,
    /// Smallest z [m].
    pub z_min: f64,
    /// `-max_t zc(t) = -(z_st + z_max)` [m]: > 0 the pin never leaves the disk, 0 at grazing.
    pub min_gap: f64,
    /// Smallest total normal force of the contact law [N].
    pub min_law_force: f64,
    /// Fraction of the period off the disk.
    pub open_fraction: f64,
    /// Smallest sliding speed `|v_r|` of the contact point in contact [m/s] (0 where the orbit
    /// sticks, NaN if never in contact): how near the cycle comes to stick.
    pub min_slip_velocity: f64,
    /// Mode switches per period.
    pub n_switches: u32,
    /// `dp/ds`: parameter component of the unit tangent, in parameter units (per unit of scaled arclength).
    pub dp_ds: f64,
    /// Scaled arclength from the first point.
    pub arclength: f64,
    /// What the point is.
    pub point_type: PointType,
    /// Contact law of the orbit (a grazing point is computed with the bilateral law).
    pub contact: ContactModel,
    /// Newton steps of its correction.
    pub newton_iterations: u32,
    /// Scaled periodicity residual.
    pub residual: f64,
    /// Bits of [`flags`].
    pub flags: u8,
}

/// A computed branch: its points, how it ended, and what it cost.
#[derive(Clone, Debug)]
pub struct Branch {
    /// Name of the continuation parameter.
    pub parameter: String,
    /// The points, in order along the branch.
    pub points: Vec<BranchPoint>,
    /// `Success` when it ended on a bound, at `max_points`, at a requested stop or back at steady
    /// sliding; else the status of the failure that ended it.
    pub status: Status,
    /// Why it ended (never empty).
    pub reason: String,
    /// Integrator work.
    pub stats: Stats,
    /// Flow integrations (each with the monodromy matrix).
    pub n_flows: u32,
    /// Scales of the arclength: parameter, period [s].
    pub p_ref: f64,
    /// Period scale [s].
    pub t_ref: f64,
    /// From a Hopf point: the branch on the critical mode's scales failed, and these points are
    /// those of the run again on the static scales (see [`branch`]).
    pub static_scales: bool,
}

/// Where a branch starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    /// A periodic orbit (or a state near one, with its period) at the starting parameter value;
    /// the first step goes towards larger parameter values if `direction > 0`.
    Orbit { state0: State, period: f64, direction: f64 },
    /// A Hopf point of steady sliding at the starting parameter value, with its crossing frequency
    /// [rad/s]: the branch leaves it on the side where the cycles exist.
    Hopf { omega: f64 },
}

/// Bad input, rejected before any work.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum BranchError {
    /// A model parameter is invalid.
    #[error(transparent)]
    Param(#[from] crate::ParamError),
    /// An argument out of its range.
    #[error("{name} = {value:?} is out of range: must be {range}")]
    OutOfRange { name: &'static str, value: f64, range: String },
    /// The parameter cannot be continued.
    #[error("parameter = {0:?} cannot be continued: must be a real model parameter other than torsion_sign ({1})")]
    Parameter(String, String),
    /// A special point the model cannot have (a stick point without the switch law).
    #[error("{0}")]
    Kind(String),
}

fn check(name: &'static str, value: f64, ok: bool, range: &str) -> Result<(), BranchError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(BranchError::OutOfRange { name, value, range: range.to_string() })
    }
}

impl BranchOptions {
    /// Check every option.
    ///
    /// # Errors
    /// The first option out of range.
    pub fn validate(&self) -> Result<(), BranchError> {
        let o = self;
        check("rtol", o.rtol, (1e-14..1e-3).contains(&o.rtol), "in [1e-14, 1e-3)")?;
        check("tol", o.tol, o.tol > 0.0 && o.tol < 1e-2, "in (0, 1e-2)")?;
        check("max_newton", o.max_newton as f64, (2..=50).contains(&o.max_newton), "an integer in [2, 50]")?;
        check("ds_min", o.ds_min, o.ds_min > 0.0, "a finite number > 0")?;
        check("ds_max", o.ds_max, o.ds_max >= o.ds_min && o.ds_max <= 1.0, "in [ds_min, 1]")?;
        check("ds", o.ds, o.ds >= o.ds_min && o.ds <= o.ds_max, "in [ds_min, ds_max]")?;
        check("max_points", o.max_points as f64, o.max_points >= 2, "an integer >= 2")?;
        check("locate_tol", o.locate_tol, o.locate_tol > 0.0 && o.locate_tol <= o.ds_max, "in (0, ds_max]")?;
        check("stability_tol", o.stability_tol, (0.0..0.1).contains(&o.stability_tol), "in [0, 0.1)")?;
        check("n_samples", o.n_samples as f64, (16..=1 << 16).contains(&o.n_samples), "an integer in [16, 65536]")?;
        check("max_switches", o.max_switches as f64, o.max_switches >= 2, "an integer >= 2")?;
        check("hopf_amplitude", o.hopf_amplitude, o.hopf_amplitude > 0.0 && o.hopf_amplitude < 1.0, "in (0, 1)")?;
        check("max_turn", o.max_turn, o.max_turn > 0.0 && o.max_turn < PI / 2.0, "in (0, pi/2) rad")?;
        check("max_period_ratio", o.max_period_ratio, o.max_period_ratio > 1.0, "a finite number > 1")?;
        Ok(())
    }
}

/// Follow the branch of periodic orbits of `p` in parameter `name`, from `start` at
/// `name = value`, until the parameter leaves `bounds`, `max_points`, a requested stop, or a
/// failure (see the module docs).
///
/// # Errors
/// Bad input (before any work): an unknown or discrete parameter, invalid model parameters, a
/// start outside `bounds`, invalid options or start. A numerical failure ends the branch with a
/// status and a reason instead.
pub fn branch(
    p: &Params,
    name: &str,
    value: f64,
    start: Start,
    bounds: (f64, f64),
    opts: &BranchOptions,
) -> Result<Branch, BranchError> {
    if !PARAM_NAMES.contains(&name) || name == "torsion_sign" {
        return Err(BranchError::Parameter(name.to_string(), PARAM_NAMES.join(", ")));
    }
    opts.validate()?;
    let (lo, hi) = bounds;
    check("bounds[0]", lo, lo.is_finite(), "a finite number")?;
    check("bounds[1]", hi, hi > lo, "a finite number > bounds[0]")?;
    check("value", value, value >= lo && value <= hi, &format!("within bounds [{lo}, {hi}]"))?;
    let mut q = *p;
    q.set(name, value)?;
    let s0 = Slider::new(q)?;
    let t0 = match start {
        Start::Orbit { state0, period, direction } => {
            check("period", period, period > 0.0, "a finite number > 0 [s]")?;
            check("direction", direction, direction != 0.0, "a nonzero number (its sign is the first step's)")?;
            if !state0.iter().all(|v| v.is_finite()) {
                return Err(BranchError::OutOfRange { name: "state0", value: f64::NAN, range: "finite".into() });
            }
            period
        }
        Start::Hopf { omega } => {
            check("omega", omega, omega > 0.0, "a finite number > 0 [rad/s]")?;
            2.0 * PI / omega
        }
    };
    let p_ref = if value != 0.0 { value.abs() } else { hi - lo };
    let mut ctx =
        Ctx { base: q, name, opts: *opts, sizes: scales(&s0), t_ref: t0, p_ref, stats: Stats::default(), n_flows: 0 };
    let mut points = Vec::new();
    let run = |ctx: &mut Ctx<'_>, points: &mut Vec<BranchPoint>, mode_scales: bool| {
        let first = match start {
            Start::Orbit { state0, period, direction } => follow::first_from_orbit(ctx, &state0, period, direction),
            Start::Hopf { omega } => follow::first_from_hopf(ctx, &s0, omega, mode_scales, points),
        };
        match first {
            Ok(node) => follow::follow(ctx, node, (lo, hi), points),
            Err(f) => (f.status, format!("the first orbit did not converge: {}", f.reason)),
        }
    };
    let (mut status, mut reason) = run(&mut ctx, &mut points, true);
    let static_scales = matches!(start, Start::Hopf { .. }) && !matches!(status, Status::Success | Status::NotComputed);
    if static_scales {
        // The critical mode's scales take longer steps; where the branch then fails (a mode
        // sequence change that does not converge, in a cascade of grazings), it runs again from
        // the Hopf point on the static scales, whose shorter steps take the other way through.
        let (p_end, why) = (points.last().map_or(f64::NAN, |b| b.parameter), reason.clone());
        points.clear();
        ctx.opts = *opts;
        ctx.sizes = scales(&s0);
        (status, reason) = run(&mut ctx, &mut points, false);
        reason = format!(
            "{reason} (on the static scales: on the critical mode's the branch ended at {name} = {p_end:.10e}: {why})"
        );
    }
    let reason = if ctx.opts.hopf_amplitude < opts.hopf_amplitude && !points.is_empty() {
        let (a, a0) = (ctx.opts.hopf_amplitude, opts.hopf_amplitude);
        format!("{reason} (first orbit at hopf_amplitude = {a:.0e}: Newton did not converge from {a0:.0e})")
    } else {
        reason
    };
    Ok(Branch {
        parameter: name.to_string(),
        points,
        status,
        reason,
        stats: ctx.stats,
        n_flows: ctx.n_flows,
        p_ref: ctx.p_ref,
        t_ref: ctx.t_ref,
        static_scales,
    })
}
