//! Per-point status codes: the one place where they are defined.
//!
//! A failed point is data, not an exception: every trajectory, root search or
//! orbit solve of a sweep ends with one of these codes and a reason, and the
//! sweep goes on. The integer values are part of the output format (netCDF
//! `flag_values`), so they never change meaning; new codes get new numbers.

use crate::ode::Outcome;

/// Outcome of one numerical task (a trajectory, a Newton solve, a shooting solve).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Status {
    /// Finished as asked (reached `t_end`, converged, settled).
    Success = 0,
    /// The step budget `max_steps` ran out before `t_end`.
    MaxSteps = 1,
    /// The step-size controller asked for a step below `h_min`.
    StepTooSmall = 2,
    /// A state or right-hand side became NaN or infinite.
    NonFinite = 3,
    /// A Newton iteration did not converge (implicit step, root refinement, shooting).
    NewtonNotConverged = 4,
    /// The motion escaped the model's validity (|z| beyond the escape limit).
    Diverged = 5,
    /// Too many events in too short a time (Zeno / chattering contact).
    EventChatter = 6,
    /// The input was rejected before any work (should not reach a sweep: inputs are validated first).
    InvalidInput = 7,
    /// A Rust panic was caught while computing this point.
    Panic = 8,
    /// The computation ran to its time/iteration limit without reaching the requested state
    /// (no steady state detected by `t_max`, no periodic orbit near the guess).
    NotConverged = 9,
    /// The point was not computed (e.g. skipped because an earlier stage decided it).
    NotComputed = 10,
    /// A contact event was missed: the run ended with the pin in free flight inside the disk.
    EventMissed = 11,
}

impl Status {
    /// Every status, in code order (used to write `flag_values`/`flag_meanings`).
    pub const ALL: [Status; 12] = [
        Status::Success,
        Status::MaxSteps,
        Status::StepTooSmall,
        Status::NonFinite,
        Status::NewtonNotConverged,
        Status::Diverged,
        Status::EventChatter,
        Status::InvalidInput,
        Status::Panic,
        Status::NotConverged,
        Status::NotComputed,
        Status::EventMissed,
    ];

    /// Short machine name (CF `flag_meanings` token).
    pub fn name(self) -> &'static str {
        match self {
            Status::Success => "success",
            Status::MaxSteps => "max_steps",
            Status::StepTooSmall => "step_too_small",
            Status::NonFinite => "non_finite",
            Status::NewtonNotConverged => "newton_not_converged",
            Status::Diverged => "diverged",
            Status::EventChatter => "event_chatter",
            Status::InvalidInput => "invalid_input",
            Status::Panic => "panic",
            Status::NotConverged => "not_converged",
            Status::NotComputed => "not_computed",
            Status::EventMissed => "event_missed",
        }
    }

    /// Integer code as stored in the output.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`Status::code`].
    pub fn from_code(code: u8) -> Option<Status> {
        Status::ALL.get(code as usize).copied()
    }

    /// True only for [`Status::Success`].
    pub fn is_ok(self) -> bool {
        self == Status::Success
    }
}

/// The per-point meaning of an integrator's [`Outcome`]. Defined here rather than in `ode`, so that the
/// generic integrators know nothing of the sweep's status codes.
impl Outcome {
    /// The per-point status this outcome maps to (a stop by event or observer is a success of the
    /// integrator; the caller decides what it means).
    pub fn status(self) -> Status {
        match self {
            Outcome::Finished | Outcome::StoppedByEvent | Outcome::StoppedByObserver => Status::Success,
            Outcome::MaxSteps => Status::MaxSteps,
            Outcome::StepTooSmall => Status::StepTooSmall,
            Outcome::NonFinite => Status::NonFinite,
            Outcome::EventChatter => Status::EventChatter,
            Outcome::Cancelled => Status::NotComputed,
        }
    }
}

/// Why a computation ended without success: the numbers behind a non-success status. Its
/// `Display` is the `reason` text of the output (times and step sizes in seconds).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Failure {
    /// The step budget ran out before `t_end` ([`Status::MaxSteps`]).
    #[error(
        "the step budget ran out: max_steps = {max_steps} steps (accepted + rejected) were taken by \
         t = {t:.6e} s, short of t_end = {t_end:.6e} s"
    )]
    MaxSteps {
        /// The budget.
        max_steps: u64,
        /// Time reached [s].
        t: f64,
        /// Time asked for [s].
        t_end: f64,
    },
    /// The step-size controller asked for a step below the floor ([`Status::StepTooSmall`]).
    #[error(
        "step size underflow at t = {t:.6e} s: the error test at rtol = {rtol:.1e} asked for a step \
         h = {h:.3e} s, below the floor {floor:.3e} s there"
    )]
    StepTooSmall {
        /// Time reached [s].
        t: f64,
        /// The step size asked for [s].
        h: f64,
        /// The floor at `t` [s].
        floor: f64,
        /// The relative tolerance of the error test.
        rtol: f64,
    },
    /// An end time before the start ([`Status::StepTooSmall`]).
    #[error(
        "t_end = {t_end:.6e} s is before the start t = {t0:.6e} s: integration backwards in time is not supported"
    )]
    Backwards {
        /// Start time [s].
        t0: f64,
        /// End time asked for [s].
        t_end: f64,
    },
    /// The state or its derivative became NaN or infinite during the run ([`Status::NonFinite`]).
    #[error(
        "non-finite values at t = {t:.6e} s: the state or its derivative became NaN or infinite and \
         cutting the step down to h = {h:.3e} s did not help"
    )]
    NonFinite {
        /// Time reached [s] (the last finite state's).
        t: f64,
        /// The step size when the run gave up [s].
        h: f64,
    },
    /// The start state or its derivative is NaN or infinite ([`Status::NonFinite`]).
    #[error("the initial state or its derivative at t = {t:.6e} s is not finite (NaN or infinite)")]
    NonFiniteStart {
        /// Start time [s].
        t: f64,
    },
    /// More located events than the budget ([`Status::EventChatter`]).
    #[error(
        "event chatter: more than max_events = {max_events} located events by t = {t:.6e} s (contact or \
         stick-slip switching ever faster)"
    )]
    EventChatter {
        /// The budget.
        max_events: u64,
        /// Time reached [s].
        t: f64,
    },
    /// `|z|` reached the escape limit ([`Status::Diverged`]).
    #[error(
        "|z| = {z:.4e} m reached the escape limit {limit:.4e} m at t = {t:.6e} s: the motion left the model's validity"
    )]
    Escaped {
        /// Time of the escape [s].
        t: f64,
        /// `z` there [m].
        z: f64,
        /// The escape limit [m].
        limit: f64,
    },
    /// The escape limit was reached in free flight inside the disk ([`Status::EventMissed`]):
    /// the pin re-entered the disk without its contact event, and the load drove it on. A
    /// numerical failure, not an escape.
    #[error(
        "|z| = {z:.4e} m reached the escape limit at t = {t:.6e} s in free flight inside the disk (gap {gap:.4e} m, \
         law force {force:.4e} N): a contact event was missed (numerical failure, not an escape)"
    )]
    EventMissed {
        /// Time [s].
        t: f64,
        /// `z` there [m].
        z: f64,
        /// The gap `z_st + z` there [m] (negative: inside the disk).
        gap: f64,
        /// The contact law's normal force there [N] (positive: it would push the pin out).
        force: f64,
    },
    /// A run to steady state reached `t_max` with neither decay nor a repeating section state
    /// ([`Status::NotConverged`]).
    #[error(
        "no steady state by t_max = {t_max:.6e} s: the motion neither decayed nor repeated on the \
         section zd = 0 (to periodic_tol = {periodic_tol:.1e})"
    )]
    Unsettled {
        /// The time limit [s].
        t_max: f64,
        /// The repetition tolerance.
        periodic_tol: f64,
    },
    /// A cycle was found but the run over one period for its harmonics failed.
    #[error(
        "a cycle of period {period:.6e} s was found at t = {t:.6e} s, but re-integrating one period for \
         its harmonics ended with {}", status.name()
    )]
    PeriodRerun {
        /// The cycle's period [s].
        period: f64,
        /// When the cycle was recognised [s].
        t: f64,
        /// How the re-integration ended.
        status: Status,
    },
    /// The caller cancelled the computation while it ran ([`Status::NotComputed`]).
    #[error("cancelled{}: the computation was interrupted", at_time(*t))]
    Cancelled {
        /// Time reached [s] (NaN where no single time applies).
        t: f64,
    },
    /// A shooting start that cannot be used ([`Status::InvalidInput`]).
    #[error(
        "the shooting start is not valid: period guess {period:.6e} s (must be finite and > 0) and a finite state"
    )]
    InvalidStart {
        /// The period guess [s].
        period: f64,
    },
    /// The shooting start's trajectory never reached the section `zd = 0` ([`Status::NotConverged`]).
    #[error("the start never reached a maximum of z (the section zd = 0, falling) within {horizon:.6e} s")]
    NoSection {
        /// How long it was integrated [s].
        horizon: f64,
    },
    /// Integrating the orbit over one period failed ([`Status`] as given).
    #[error("integrating one period T = {period:.6e} s of the orbit ended with {}: {}", status.name(), flow_hint(*status))]
    OrbitFlow {
        /// How it ended.
        status: Status,
        /// The period integrated [s].
        period: f64,
    },
    /// Newton's iteration for the periodic orbit did not converge ([`Status::NewtonNotConverged`]).
    #[error(
        "Newton did not converge after {iterations} of max_iter = {max_iter} iterations: the scaled \
         periodicity residual is {residual:.3e}, above tol = {tol:.1e}"
    )]
    Newton {
        /// Iterations done.
        iterations: u32,
        /// The budget.
        max_iter: u32,
        /// The scaled residual of the last iterate.
        residual: f64,
        /// The tolerance asked for.
        tol: f64,
    },
    /// Newton converged on steady sliding, not on a cycle ([`Status::NotConverged`]).
    #[error(
        "Newton ended on steady sliding, not a cycle: z varies by {swing:.3e} m over the period, below \
         {floor:.3e} m"
    )]
    NoCycle {
        /// `z_max - z_min` of the solution [m].
        swing: f64,
        /// The least swing of a cycle [m].
        floor: f64,
    },
    /// The caller cancelled the computation before this item started ([`Status::NotComputed`]).
    #[error("cancelled before this item started: the computation was interrupted")]
    NotStarted,
    /// Any other status at the end of a run (not produced by the integrators; kept so that every
    /// status has a reason).
    #[error("the run ended with status {} at t = {t:.6e} s", status.name())]
    Ended {
        /// The status.
        status: Status,
        /// Time reached [s].
        t: f64,
    },
}

/// ` at t = ... s` for a finite time, nothing otherwise.
fn at_time(t: f64) -> String {
    if t.is_finite() {
        format!(" at t = {t:.6e} s")
    } else {
        String::new()
    }
}

/// What a status means for an integration over one period of an orbit.
fn flow_hint(status: Status) -> &'static str {
    match status {
        Status::EventChatter => "more contact switches in one period than max_switches",
        Status::NonFinite => "a non-finite state, derivative or saltation matrix (a grazing switch?)",
        Status::Diverged => "|z| reached the escape limit",
        Status::MaxSteps => "the integrator's step budget ran out",
        Status::StepTooSmall => "the integrator's step size fell below its floor",
        Status::NotComputed => "the computation was interrupted",
        _ => "the run stopped before the end of the period",
    }
}

impl Failure {
    /// The status this failure reports.
    pub fn status(&self) -> Status {
        match self {
            Failure::MaxSteps { .. } => Status::MaxSteps,
            Failure::StepTooSmall { .. } | Failure::Backwards { .. } => Status::StepTooSmall,
            Failure::NonFinite { .. } | Failure::NonFiniteStart { .. } => Status::NonFinite,
            Failure::EventChatter { .. } => Status::EventChatter,
            Failure::Escaped { .. } => Status::Diverged,
            Failure::EventMissed { .. } => Status::EventMissed,
            Failure::Unsettled { .. } => Status::NotConverged,
            Failure::PeriodRerun { status, .. } => {
                if status.is_ok() {
                    Status::NotConverged
                } else {
                    *status
                }
            }
            Failure::Cancelled { .. } | Failure::NotStarted => Status::NotComputed,
            Failure::Ended { status, .. } | Failure::OrbitFlow { status, .. } => *status,
            Failure::InvalidStart { .. } => Status::InvalidInput,
            Failure::NoSection { .. } | Failure::NoCycle { .. } => Status::NotConverged,
            Failure::Newton { .. } => Status::NewtonNotConverged,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_name_their_numbers() {
        let f = Failure::StepTooSmall { t: 0.0123, h: 1.2e-17, floor: 1e-14, rtol: 1e-8 };
        let text = f.to_string();
        assert_eq!(f.status(), Status::StepTooSmall);
        for part in ["1.230000e-2", "1.200e-17", "1.000e-14", "1.0e-8"] {
            assert!(text.contains(part), "{text:?} lacks {part}");
        }
        let f = Failure::MaxSteps { max_steps: 100, t: 0.5, t_end: 2.0 };
        assert!(f.to_string().contains("max_steps = 100") && f.to_string().contains("2.000000e0"));
        let f = Failure::PeriodRerun { period: 0.01, t: 3.0, status: Status::MaxSteps };
        assert_eq!(f.status(), Status::MaxSteps);
        assert!(f.to_string().ends_with("max_steps"));
    }

    #[test]
    fn codes_round_trip_and_are_dense() {
        for (i, s) in Status::ALL.iter().enumerate() {
            assert_eq!(s.code() as usize, i);
            assert_eq!(Status::from_code(s.code()), Some(*s));
        }
        assert_eq!(Status::from_code(Status::ALL.len() as u8), None);
    }
}
