//! `tribosweep._core`: the thin PyO3 layer over `tribosweep-core`.
//!
//! It only converts arrays in and out, maps errors to `ValueError`, and releases the GIL around
//! the numerics. The public Python API (argument checking with clear messages, xarray Datasets)
//! lives in `python/tribosweep/`; this module is private.

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::ensemble::par_map;
use tribosweep_core::model::{ContactModel, FrictionLaw, Params, Slider, State, PARAM_NAMES};
use tribosweep_core::ode::{Method, Stats};
use tribosweep_core::status::Status;
use tribosweep_core::steady::{self, RunResult, SteadyOptions, Summary, Tolerances};

/// Local wrapper so core errors map into Python exceptions in one place.
struct CoreError(String);

impl From<CoreError> for PyErr {
    fn from(e: CoreError) -> PyErr {
        PyValueError::new_err(e.0)
    }
}

impl From<tribosweep_core::ParamError> for CoreError {
    fn from(e: tribosweep_core::ParamError) -> Self {
        CoreError(e.to_string())
    }
}

fn contact_from(name: &str) -> Result<ContactModel, CoreError> {
    match name {
        "bilateral" => Ok(ContactModel::Bilateral),
        "unilateral" => Ok(ContactModel::Unilateral),
        _ => Err(CoreError(format!("contact = {name:?} is not valid: must be 'bilateral' or 'unilateral'"))),
    }
}

fn friction_from(name: &str) -> Result<FrictionLaw, CoreError> {
    match name {
        "constant" => Ok(FrictionLaw::Constant),
        "coulomb" => Ok(FrictionLaw::Coulomb),
        _ => Err(CoreError(format!("friction_law = {name:?} is not valid: must be 'constant' or 'coulomb'"))),
    }
}

fn method_from(name: &str) -> Result<Method, CoreError> {
    Method::from_name(name).ok_or_else(|| {
        let all: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        CoreError(format!("method = {name:?} is not valid: must be one of {}", all.join(", ")))
    })
}

/// Build validated parameters from a name -> value map plus the two categorical settings.
fn params_from(values: &HashMap<String, f64>, contact: &str, friction_law: &str) -> Result<Params, CoreError> {
    let mut p = Params::seed();
    for (k, v) in values {
        p.set(k, *v)?;
    }
    p.contact = contact_from(contact)?;
    p.friction_law = friction_from(friction_law)?;
    p.validate()?;
    Ok(p)
}

fn tolerances(rtol: f64, atol: Option<PyReadonlyArray1<'_, f64>>) -> Result<Tolerances, CoreError> {
    let atol = match atol {
        None => None,
        Some(a) => {
            let s = a.as_slice().map_err(|e| CoreError(format!("atol: {e}")))?;
            let arr: [f64; 6] = s
                .try_into()
                .map_err(|_| CoreError(format!("atol has {} entries: must have 6 (one per state component)", s.len())))?;
            Some(arr)
        }
    };
    Ok(Tolerances { rtol, atol })
}

fn stats_into(d: &Bound<'_, PyDict>, stats: &[Stats]) -> PyResult<()> {
    let py = d.py();
    let col = |f: fn(&Stats) -> u64| Array1::from_iter(stats.iter().map(f)).into_pyarray(py);
    d.set_item("n_rhs", col(|s| s.n_rhs))?;
    d.set_item("n_jac", col(|s| s.n_jac))?;
    d.set_item("n_lu", col(|s| s.n_lu))?;
    d.set_item("n_accept", col(|s| s.n_accept))?;
    d.set_item("n_reject", col(|s| s.n_reject))?;
    d.set_item("n_events", col(|s| s.n_events))?;
    Ok(())
}

fn runs_into(d: &Bound<'_, PyDict>, runs: &[RunResult], reasons: &[String]) -> PyResult<()> {
    let py = d.py();
    let n = runs.len();
    let f = |g: fn(&RunResult) -> f64| Array1::from_iter(runs.iter().map(g)).into_pyarray(py);
    d.set_item("status", Array1::from_iter(runs.iter().map(|r| r.status.code())).into_pyarray(py))?;
    d.set_item("reason", reasons.to_vec())?;
    d.set_item("t_reached", f(|r| r.t))?;
    d.set_item("min_normal_force", f(|r| r.extremes.min_normal_force))?;
    d.set_item("max_gap", f(|r| r.extremes.max_gap))?;
    d.set_item("min_slip_velocity", f(|r| r.extremes.min_slip_velocity))?;
    d.set_item("max_abs_z", f(|r| r.extremes.max_abs_z))?;
    let mut y = Array2::<f64>::zeros((n, 6));
    for (i, r) in runs.iter().enumerate() {
        for c in 0..6 {
            y[(i, c)] = r.y[c];
        }
    }
    d.set_item("y_end", y.into_pyarray(py))?;
    let stats: Vec<Stats> = runs.iter().map(|r| r.stats).collect();
    stats_into(d, &stats)
}

fn failed_run(status: Status) -> RunResult {
    RunResult {
        status,
        t: f64::NAN,
        y: State::repeat(f64::NAN),
        extremes: Default::default(),
        stats: Stats::default(),
    }
}

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

/// Validate parameters; raise ValueError naming the first one out of range.
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

/// One trajectory. Returns a dict: `t` (n,), `y` (n, 6), and the run's status, counters, extremes.
/// With `t_eval` the states are sampled there; otherwise every accepted step end is returned.
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, y0, t_end, method, rtol, atol=None, t_eval=None))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    y0: PyReadonlyArray1<'py, f64>,
    t_end: f64,
    method: &str,
    rtol: f64,
    atol: Option<PyReadonlyArray1<'py, f64>>,
    t_eval: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = params_from(&values, contact, friction_law)?;
    let method = method_from(method)?;
    let tol = tolerances(rtol, atol)?;
    let y0 = State::from_column_slice(y0.as_slice()?);
    let t_eval: Option<Vec<f64>> = t_eval.map(|a| a.as_slice().map(|s| s.to_vec())).transpose()?;
    let slider = Slider::new(p).map_err(CoreError::from)?;
    let (run, t, ys) = py.detach(move || match t_eval {
        Some(te) => {
            let (r, ys) = steady::run_sampled(&slider, &y0, t_end, method, &tol, &te);
            (r, te, ys)
        }
        None => {
            let rec = steady::StepRecorder { t: Vec::new(), y: Vec::new() };
            let (r, rec) = steady::run_observed(&slider, &y0, t_end, method, &tol, rec);
            (r, rec.t, rec.y)
        }
    });
    let d = PyDict::new(py);
    let mut y = Array2::<f64>::zeros((ys.len(), 6));
    for (i, s) in ys.iter().enumerate() {
        for c in 0..6 {
            y[(i, c)] = s[c];
        }
    }
    d.set_item("t", Array1::from_vec(t).into_pyarray(py))?;
    d.set_item("y", y.into_pyarray(py))?;
    runs_into(&d, &[run], &[String::new()])?;
    Ok(d)
}

/// Per-trajectory parameter sets: the base map with columns `names` of `values` (n, k) overriding.
fn ensemble_params(
    base: &HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: &[String],
    values: &numpy::ndarray::ArrayView2<'_, f64>,
) -> Result<Vec<Params>, CoreError> {
    let p0 = params_from(base, contact, friction_law)?;
    if values.ncols() != names.len() {
        return Err(CoreError(format!(
            "values has {} columns but {} parameter names were given",
            values.ncols(),
            names.len()
        )));
    }
    let mut out = Vec::with_capacity(values.nrows());
    for i in 0..values.nrows() {
        let mut p = p0;
        for (k, name) in names.iter().enumerate() {
            p.set(name, values[(i, k)])?;
        }
        p.validate().map_err(|e| CoreError(format!("trajectory {i}: {e}")))?;
        out.push(p);
    }
    Ok(out)
}

fn y0_rows(y0: &numpy::ndarray::ArrayView2<'_, f64>, n: usize) -> Result<Vec<State>, CoreError> {
    if y0.ncols() != 6 || (y0.nrows() != 1 && y0.nrows() != n) {
        return Err(CoreError(format!(
            "y0 has shape ({}, {}): must be (6,), (1, 6) or ({n}, 6)",
            y0.nrows(),
            y0.ncols()
        )));
    }
    Ok((0..n)
        .map(|i| {
            let r = if y0.nrows() == 1 { 0 } else { i };
            State::from_fn(|c, _| y0[(r, c)])
        })
        .collect())
}

/// Many trajectories in parallel (GIL released). `kind` is "final" (end state), "sampled"
/// (states at `t_eval`) or "steady" (run to steady state and summarise; `t_end` is then `t_max`).
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, y0, t_end, method, rtol, atol=None, t_eval=None, threads=None, kind="final", periodic_tol=1e-5, decay_amplitude=None, n_fourier=512))]
#[allow(clippy::too_many_arguments)]
fn ensemble<'py>(
    py: Python<'py>,
    base: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    y0: PyReadonlyArray2<'py, f64>,
    t_end: f64,
    method: &str,
    rtol: f64,
    atol: Option<PyReadonlyArray1<'py, f64>>,
    t_eval: Option<PyReadonlyArray1<'py, f64>>,
    threads: Option<usize>,
    kind: &str,
    periodic_tol: f64,
    decay_amplitude: Option<f64>,
    n_fourier: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ensemble_params(&base, contact, friction_law, &names, &values.as_array())?;
    let n = params.len();
    let y0s = y0_rows(&y0.as_array(), n)?;
    let method = method_from(method)?;
    let tol = tolerances(rtol, atol)?;
    let t_eval: Option<Vec<f64>> = t_eval.map(|a| a.as_slice().map(|s| s.to_vec())).transpose()?;
    let items: Vec<(Params, State)> = params.into_iter().zip(y0s).collect();
    let d = PyDict::new(py);
    match kind {
        "final" | "sampled" => {
            if kind == "sampled" && t_eval.is_none() {
                return Err(CoreError("kind = 'sampled' needs t_eval".into()).into());
            }
            let te = t_eval.unwrap_or_default();
            let out: Vec<(RunResult, Vec<State>, String)> = py.detach(|| {
                par_map(
                    &items,
                    threads,
                    |(p, y0)| {
                        let s = Slider::new(*p).expect("validated before the parallel section");
                        if te.is_empty() {
                            (steady::run(&s, y0, t_end, method, &tol), Vec::new(), String::new())
                        } else {
                            let (r, ys) = steady::run_sampled(&s, y0, t_end, method, &tol, &te);
                            (r, ys, String::new())
                        }
                    },
                    |msg| (failed_run(Status::Panic), vec![State::repeat(f64::NAN); te.len()], format!("panic: {msg}")),
                )
            });
            let runs: Vec<RunResult> = out.iter().map(|o| o.0).collect();
            let reasons: Vec<String> = out.iter().map(|o| o.2.clone()).collect();
            runs_into(&d, &runs, &reasons)?;
            if !te.is_empty() {
                let mut y = Array3::<f64>::zeros((n, te.len(), 6));
                for (i, o) in out.iter().enumerate() {
                    for (j, s) in o.1.iter().enumerate() {
                        for c in 0..6 {
                            y[(i, j, c)] = s[c];
                        }
                    }
                }
                d.set_item("y", y.into_pyarray(py))?;
            }
        }
        "steady" => {
            let opts = SteadyOptions {
                t_max: t_end,
                method,
                tol,
                periodic_tol,
                decay_amplitude,
                n_fourier,
                ..SteadyOptions::default()
            };
            let out: Vec<(Summary, String)> = py.detach(|| {
                par_map(
                    &items,
                    threads,
                    |(p, y0)| {
                        let s = Slider::new(*p).expect("validated before the parallel section");
                        (steady::run_to_steady(&s, y0, &opts), String::new())
                    },
                    |msg| (Summary::failed(Status::Panic), format!("panic: {msg}")),
                )
            });
            summaries_into(&d, &out)?;
        }
        _ => {
            return Err(CoreError(format!("kind = {kind:?} is not valid: must be 'final', 'sampled' or 'steady'")).into())
        }
    }
    Ok(d)
}

fn summaries_into(d: &Bound<'_, PyDict>, out: &[(Summary, String)]) -> PyResult<()> {
    let py = d.py();
    let f = |g: &dyn Fn(&Summary) -> f64| Array1::from_iter(out.iter().map(|o| g(&o.0))).into_pyarray(py);
    d.set_item("status", Array1::from_iter(out.iter().map(|o| o.0.status.code())).into_pyarray(py))?;
    d.set_item("reason", out.iter().map(|o| o.1.clone()).collect::<Vec<_>>())?;
    d.set_item("outcome", Array1::from_iter(out.iter().map(|o| o.0.outcome as u8)).into_pyarray(py))?;
    d.set_item("t_end", f(&|s| s.t_end))?;
    d.set_item("omega", f(&|s| s.omega))?;
    d.set_item("period", f(&|s| s.period))?;
    d.set_item("multiplicity", Array1::from_iter(out.iter().map(|o| o.0.multiplicity)).into_pyarray(py))?;
    d.set_item("z0", f(&|s| s.z0))?;
    for k in 0..3 {
        d.set_item(format!("z{}_amp", k + 1), f(&|s| s.z_amp[k]))?;
        d.set_item(format!("z{}_phase", k + 1), f(&|s| s.z_phase[k]))?;
    }
    d.set_item("phi1_amp", f(&|s| s.phi_amp))?;
    d.set_item("phi1_phase", f(&|s| s.phi_phase))?;
    d.set_item("x1_amp", f(&|s| s.x_amp))?;
    d.set_item("x1_phase", f(&|s| s.x_phase))?;
    d.set_item("min_normal_force", f(&|s| s.min_normal_force))?;
    d.set_item("fraction_off_disk", f(&|s| s.fraction_off_disk))?;
    d.set_item("min_slip_velocity", f(&|s| s.min_slip_velocity))?;
    d.set_item("max_gap", f(&|s| s.extremes.max_gap))?;
    d.set_item("max_abs_z", f(&|s| s.extremes.max_abs_z))?;
    let stats: Vec<Stats> = out.iter().map(|o| o.0.stats).collect();
    stats_into(d, &stats)
}

/// Outcome names of a run to steady state, in code order.
#[pyfunction]
fn steady_outcome_names() -> Vec<&'static str> {
    use tribosweep_core::steady::SteadyOutcome::*;
    [Decayed, Periodic, Diverged, Unsettled, Failed].iter().map(|o| o.name()).collect()
}

/// The compiled core of tribosweep (private: use the `tribosweep` package).
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(param_names, m)?)?;
    m.add_function(wrap_pyfunction!(seed_params, m)?)?;
    m.add_function(wrap_pyfunction!(status_names, m)?)?;
    m.add_function(wrap_pyfunction!(method_names, m)?)?;
    m.add_function(wrap_pyfunction!(steady_outcome_names, m)?)?;
    m.add_function(wrap_pyfunction!(validate_params, m)?)?;
    m.add_function(wrap_pyfunction!(static_point, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    Ok(())
}
