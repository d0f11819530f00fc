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
}

impl Status {
    /// Every status, in code order (used to write `flag_values`/`flag_meanings`).
    pub const ALL: [Status; 11] = [
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
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_are_dense() {
        for (i, s) in Status::ALL.iter().enumerate() {
            assert_eq!(s.code() as usize, i);
            assert_eq!(Status::from_code(s.code()), Some(*s));
        }
        assert_eq!(Status::from_code(Status::ALL.len() as u8), None);
    }
}
