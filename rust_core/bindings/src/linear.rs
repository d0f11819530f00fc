//! Linear stability of steady sliding: eigenvalues per parameter set, Hopf loads.

use crate::convert::Call;
use crate::errors::CoreError;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::linear::{self, LinearStability};
use tribosweep_core::model::Slider;
use tribosweep_core::status::Status;

/// The result of a row whose computation panicked.
fn failed_linear() -> LinearStability {
    let mut l = linear::linear_stability(&Slider::seed());
    l.status = Status::Panic;
    l.stable = false;
    l.max_growth_rate = f64::NAN;
    l.least_stable_frequency = f64::NAN;
    l.normal_mode_frequency_hz = f64::NAN;
    l
}

/// Linear stability of steady sliding for each parameter set (GIL released, parallel).
/// Returns eigenvalues (n, 6) complex, per-mode growth rates and frequencies (n, 3) in the
/// order friction, torsion, normal, and the least stable mode's growth rate and frequency.
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, *, threads=None))]
fn linear_stability<'py>(
    py: Python<'py>,
    base: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let call = Call::rows(py, &base, contact, friction_law, &names, &values, threads)?;
    let n = call.len();
    let sliders = call.sliders()?;
    let out: Vec<LinearStability> = call.map(&sliders, linear::linear_stability, |_| failed_linear())?;
    let d = PyDict::new(py);
    let mut ev = Array2::<numpy::Complex64>::zeros((n, 6));
    let mut gr = Array2::<f64>::zeros((n, 3));
    let mut fr = Array2::<f64>::zeros((n, 3));
    let kinds = [linear::ModeKind::Friction, linear::ModeKind::Torsion, linear::ModeKind::Normal];
    for (i, l) in out.iter().enumerate() {
        for c in 0..6 {
            ev[(i, c)] = numpy::Complex64::new(l.eigenvalues[c].re, l.eigenvalues[c].im);
        }
        for (k, kind) in kinds.iter().enumerate() {
            let m = l.mode(*kind);
            gr[(i, k)] = m.growth_rate;
            fr[(i, k)] = m.frequency;
        }
    }
    let f = |g: fn(&LinearStability) -> f64| Array1::from_iter(out.iter().map(g)).into_pyarray(py);
    d.set_item("eigenvalues", ev.into_pyarray(py))?;
    d.set_item("mode_growth_rate", gr.into_pyarray(py))?;
    d.set_item("mode_frequency", fr.into_pyarray(py))?;
    d.set_item("mode_names", kinds.iter().map(|k| k.name()).collect::<Vec<_>>())?;
    d.set_item("growth_rate", f(|l| l.max_growth_rate))?;
    d.set_item("linear_frequency", f(|l| l.least_stable_frequency))?;
    d.set_item("normal_mode_frequency", f(|l| l.normal_mode_frequency_hz))?;
    d.set_item("stable", Array1::from_iter(out.iter().map(|l| l.stable)).into_pyarray(py))?;
    d.set_item("status", Array1::from_iter(out.iter().map(|l| l.status.code())).into_pyarray(py))?;
    Ok(d)
}

/// Hopf loads in [load_min, load_max] (only z_st and K_s follow the load). List of dicts.
#[pyfunction]
fn hopf_loads<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    friction_law: &str,
    load_min: f64,
    load_max: f64,
    n_grid: usize,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let call = Call::one(py, &values, "bilateral", friction_law, None)?;
    let p = call.params();
    let pts = call.detach(|| linear::hopf_loads(&p, load_min, load_max, n_grid))?.map_err(CoreError::from)?;
    let mut out = Vec::new();
    for h in pts {
        let d = PyDict::new(py);
        d.set_item("normal_load", h.normal_load)?;
        d.set_item(
            "direction",
            match h.direction {
                linear::HopfDirection::StableToUnstable => "stable_to_unstable",
                linear::HopfDirection::UnstableToStable => "unstable_to_stable",
            },
        )?;
        d.set_item("mode", h.mode.name())?;
        d.set_item("frequency", h.frequency)?;
        d.set_item("bracket", h.bracket)?;
        d.set_item("status", h.status.code())?;
        d.set_item("extrapolated", h.extrapolated)?;
        out.push(d);
    }
    Ok(out)
}

/// Add this group's functions to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(linear_stability, m)?)?;
    m.add_function(wrap_pyfunction!(hopf_loads, m)?)?;
    Ok(())
}
