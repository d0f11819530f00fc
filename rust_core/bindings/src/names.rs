//! Names, codes and the model's parameters: the vocabulary the Python package builds on
//! (parameter names and seed values, status, method, outcome and instability names in code
//! order), parameter validation and the static point.

use crate::convert::params_from;
use pyo3::prelude::*;
use std::collections::HashMap;
use tribosweep_core::model::{Params, PARAM_NAMES};
use tribosweep_core::ode::Method;
use tribosweep_core::shooting::INSTABILITY_NAMES;
use tribosweep_core::status::Status;
use tribosweep_core::steady::SteadyOutcome;

/// Names of the real-valued model parameters.
#[pyfunction]
fn param_names() -> Vec<&'static str> {
    PARAM_NAMES.to_vec()
}

/// Seed values of the real-valued parameters.
#[pyfunction]
fn seed_params() -> HashMap<&'static str, f64> {
    let p = Params::seed();
    PARAM_NAMES.iter().map(|n| (*n, p.get(n).expect("known name"))).collect()
}

/// Status names in code order.
#[pyfunction]
fn status_names() -> Vec<&'static str> {
    Status::ALL.iter().map(|s| s.name()).collect()
}

/// Integration method names.
#[pyfunction]
fn method_names() -> Vec<&'static str> {
    Method::ALL.iter().map(|m| m.name()).collect()
}

/// Outcome names of a run to steady state, in code order.
#[pyfunction]
fn steady_outcome_names() -> Vec<&'static str> {
    use SteadyOutcome::*;
    [Decayed, Periodic, Diverged, Unsettled, Failed, Irregular].iter().map(|o| o.name()).collect()
}

/// How a periodic orbit is unstable (`PeriodicOrbit::instability`), in code order.
#[pyfunction]
fn instability_names() -> Vec<&'static str> {
    INSTABILITY_NAMES.to_vec()
}

/// Validate parameters; raise InvalidArgumentError (a ValueError) naming the first one out of range.
#[pyfunction]
fn validate_params(values: HashMap<String, f64>, contact: &str, friction_law: &str) -> PyResult<()> {
    params_from(&values, contact, friction_law)?;
    Ok(())
}

/// Static penetration z_st [m] and dynamic contact stiffness K_s [N/m].
#[pyfunction]
fn static_point(values: HashMap<String, f64>) -> PyResult<(f64, f64)> {
    let p = params_from(&values, "bilateral", "constant")?;
    Ok((p.static_penetration(), p.dynamic_contact_stiffness()))
}

/// Add this group's functions to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(param_names, m)?)?;
    m.add_function(wrap_pyfunction!(seed_params, m)?)?;
    m.add_function(wrap_pyfunction!(status_names, m)?)?;
    m.add_function(wrap_pyfunction!(method_names, m)?)?;
    m.add_function(wrap_pyfunction!(steady_outcome_names, m)?)?;
    m.add_function(wrap_pyfunction!(instability_names, m)?)?;
    m.add_function(wrap_pyfunction!(validate_params, m)?)?;
    m.add_function(wrap_pyfunction!(static_point, m)?)?;
    Ok(())
}
