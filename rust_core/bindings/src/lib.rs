//! `tribosweep._core`: the thin PyO3 layer over `tribosweep-core`.
//!
//! It only converts arrays in and out, maps errors to `ValueError`, and releases the GIL around
//! the numerics. The public Python API (argument checking with clear messages, xarray Datasets)
//! lives in `python/tribosweep/`; this module is private.

mod branch;

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::ensemble::par_map;
use tribosweep_core::linear::{self, LinearStability};
use tribosweep_core::model::{ContactModel, FrictionLaw, Params, Slider, State, PARAM_NAMES};
use tribosweep_core::ode::lanes::{self, LaneResult, Task};
use tribosweep_core::ode::{Method, Stats};
use tribosweep_core::shooting::{self, PeriodicOrbit, ShootingOptions};
use tribosweep_core::status::Status;
use tribosweep_core::steady::{self, RunResult, SteadyOptions, Summary, Tolerances};
use tribosweep_core::tidf::{self, RootSearch, SearchOptions, Tidf, Unknowns, Variant};

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
        "switch" => Ok(FrictionLaw::Switch),
        _ => Err(CoreError(format!("friction_law = {name:?} is not valid: must be 'constant', 'coulomb' or 'switch'"))),
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

fn tolerances(
    rtol: f64,
    atol: Option<PyReadonlyArray1<'_, f64>>,
    max_steps: Option<u64>,
    max_events: Option<u64>,
) -> Result<Tolerances, CoreError> {
    let atol = match atol {
        None => None,
        Some(a) => {
            let s = a.as_slice().map_err(|e| CoreError(format!("atol: {e}")))?;
            let arr: [f64; 6] = s.try_into().map_err(|_| {
                CoreError(format!("atol has {} entries: must have 6 (one per state component)", s.len()))
            })?;
            Some(arr)
        }
    };
    Ok(Tolerances { rtol, atol, max_steps, max_events })
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
    RunResult { status, t: f64::NAN, y: State::repeat(f64::NAN), extremes: Default::default(), stats: Stats::default() }
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
#[pyo3(signature = (values, contact, friction_law, y0, t_end, method, rtol, atol=None, t_eval=None, max_steps=None, max_events=None))]
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
    max_steps: Option<u64>,
    max_events: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = params_from(&values, contact, friction_law)?;
    let method = method_from(method)?;
    let tol = tolerances(rtol, atol, max_steps, max_events)?;
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
#[pyo3(signature = (base, contact, friction_law, names, values, y0, t_end, method, rtol, atol=None, t_eval=None, threads=None, kind="final", periodic_tol=1e-5, decay_amplitude=None, n_fourier=512, max_steps=None, max_events=None, decay_amplitudes=None))]
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
    max_steps: Option<u64>,
    max_events: Option<u64>,
    decay_amplitudes: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ensemble_params(&base, contact, friction_law, &names, &values.as_array())?;
    let n = params.len();
    let y0s = y0_rows(&y0.as_array(), n)?;
    // Per-trajectory decay thresholds of the steady kind (override `decay_amplitude`).
    let decays: Option<Vec<f64>> = match decay_amplitudes {
        Some(a) => {
            let v = a.as_slice()?.to_vec();
            if v.len() != n || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(CoreError(format!(
                    "decay_amplitudes must hold {n} finite values > 0 (one per trajectory); got {} values",
                    v.len()
                ))
                .into());
            }
            Some(v)
        }
        None => None,
    };
    let method = method_from(method)?;
    let tol = tolerances(rtol, atol, max_steps, max_events)?;
    let t_eval: Option<Vec<f64>> = t_eval.map(|a| a.as_slice().map(|s| s.to_vec())).transpose()?;
    let items: Vec<(Params, State)> = params.into_iter().zip(y0s).collect();
    let d = PyDict::new(py);
    let p0 = items.first().map(|it| it.0);
    // The lane-batched paths: `ode::batch` (DP5) for the bilateral constant-mu end state,
    // `ode::lanes` (DP5 and DOP853) for everything else it supports (unilateral contact, the
    // Coulomb/Stribeck law, t_eval, runs to steady state). Same method and tolerances as the scalar driver, to
    // integration accuracy; each trajectory's result does not depend on which others share its
    // batch (tested in the core), so any grouping is deterministic for any thread count.
    let lanes_ok = lanes::supports_method(method) && p0.is_some_and(|p| lanes::supports(&p));
    match kind {
        "final" | "sampled" => {
            if kind == "sampled" && t_eval.is_none() {
                return Err(CoreError("kind = 'sampled' needs t_eval".into()).into());
            }
            let te = t_eval.unwrap_or_default();
            let batchable = te.is_empty()
                && !tol.has_limits()
                && method == Method::Dopri5
                && p0.is_some_and(|p| p.contact == ContactModel::Bilateral && p.friction_law == FrictionLaw::Constant);
            if batchable || lanes_ok {
                let task = if te.is_empty() { Task::Final } else { Task::Sampled(&te) };
                let out: Vec<(LaneResult, String)> = py.detach(|| {
                    if batchable {
                        // The batch locates an escape inside its step, as the scalar path does.
                        grouped(&items, threads, |sliders, y0s| {
                            tribosweep_core::ode::batch::run_bilateral_batch(sliders, y0s, t_end, &tol)
                                .into_iter()
                                .map(|run| LaneResult { run, samples: Vec::new(), summary: None, events: Vec::new() })
                                .collect()
                        })
                    } else {
                        let (sliders, y0s) = unzip_items(&items);
                        lanes_out(lanes::run_lanes_threads(&sliders, &y0s, t_end, method, &tol, task, threads))
                    }
                });
                let runs: Vec<RunResult> = out.iter().map(|o| o.0.run).collect();
                let reasons: Vec<String> = out.iter().map(|o| o.1.clone()).collect();
                runs_into(&d, &runs, &reasons)?;
                if !te.is_empty() {
                    let mut y = Array3::<f64>::from_elem((n, te.len(), 6), f64::NAN);
                    for (i, o) in out.iter().enumerate() {
                        for (j, s) in o.0.samples.iter().enumerate() {
                            for c in 0..6 {
                                y[(i, j, c)] = s[c];
                            }
                        }
                    }
                    d.set_item("y", y.into_pyarray(py))?;
                }
                return Ok(d);
            }
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
            if lanes_ok {
                let out: Vec<(LaneResult, String)> = py.detach(|| {
                    let (sliders, y0s) = unzip_items(&items);
                    let task = Task::Steady { opts: &opts, decay: decays.as_deref() };
                    lanes_out(lanes::run_lanes_threads(&sliders, &y0s, t_end, method, &tol, task, threads))
                });
                let sums: Vec<(Summary, String)> = out
                    .into_iter()
                    .map(|(r, reason)| (r.summary.unwrap_or_else(|| Summary::failed(r.run.status)), reason))
                    .collect();
                summaries_into(&d, &sums)?;
                return Ok(d);
            }
            let rows: Vec<(usize, &(Params, State))> = items.iter().enumerate().collect();
            let out: Vec<(Summary, String)> = py.detach(|| {
                par_map(
                    &rows,
                    threads,
                    |&(i, (p, y0))| {
                        let s = Slider::new(*p).expect("validated before the parallel section");
                        let o = match &decays {
                            Some(d) => SteadyOptions { decay_amplitude: Some(d[i]), ..opts },
                            None => opts,
                        };
                        (steady::run_to_steady(&s, y0, &o), String::new())
                    },
                    |msg| (Summary::failed(Status::Panic), format!("panic: {msg}")),
                )
            });
            summaries_into(&d, &out)?;
        }
        _ => {
            return Err(
                CoreError(format!("kind = {kind:?} is not valid: must be 'final', 'sampled' or 'steady'")).into()
            )
        }
    }
    Ok(d)
}

/// Sliders and start states of validated items.
fn unzip_items(items: &[(Params, State)]) -> (Vec<Slider>, Vec<State>) {
    items.iter().map(|(p, y)| (Slider::new(*p).expect("validated before the parallel section"), *y)).unzip()
}

/// Lane results with their reasons (a panic on a worker thread: `Status::Panic` and its message).
fn lanes_out(v: Vec<Result<LaneResult, String>>) -> Vec<(LaneResult, String)> {
    v.into_iter()
        .map(|r| match r {
            Ok(x) => (x, String::new()),
            Err(msg) => (
                LaneResult {
                    run: failed_run(Status::Panic),
                    samples: Vec::new(),
                    summary: Some(Summary::failed(Status::Panic)),
                    events: Vec::new(),
                },
                format!("panic: {msg}"),
            ),
        })
        .collect()
}

/// Run `f` on groups of the items in parallel (each group a slice of sliders and start states),
/// one result per item in input order. Groups are big enough to keep the
/// eight lanes busy (the last long runs of a small group leave lanes idle) and small enough to
/// spread over the threads. A panic marks its whole group.
fn grouped<F>(items: &[(Params, State)], threads: Option<usize>, f: F) -> Vec<(LaneResult, String)>
where
    F: Fn(&[Slider], &[State]) -> Vec<LaneResult> + Sync,
{
    // About four groups per thread, so that the threads stay busy to the end of a call even when
    // a few long runs (a census's 30 s disturbances) dominate it; at least one full set of lanes.
    let nthreads = threads.unwrap_or_else(tribosweep_core::ensemble::default_threads).max(1);
    let group = items.len().div_ceil(4 * nthreads).clamp(8, 1024);
    let ranges: Vec<std::ops::Range<usize>> =
        (0..items.len()).step_by(group).map(|a| a..(a + group).min(items.len())).collect();
    let out: Vec<Vec<(LaneResult, String)>> = par_map(
        &ranges,
        threads,
        |r| {
            let g = &items[r.clone()];
            let sliders: Vec<Slider> = g.iter().map(|(p, _)| Slider::new(*p).expect("validated")).collect();
            let y0s: Vec<State> = g.iter().map(|(_, y)| *y).collect();
            f(&sliders, &y0s).into_iter().map(|x| (x, String::new())).collect()
        },
        |msg| {
            let failed = LaneResult {
                run: failed_run(Status::Panic),
                samples: Vec::new(),
                summary: Some(Summary::failed(Status::Panic)),
                events: Vec::new(),
            };
            vec![(failed, format!("panic: {msg}")); group]
        },
    );
    out.into_iter().zip(&ranges).flat_map(|(v, r)| v.into_iter().take(r.len())).collect()
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
    let mut y = Array2::<f64>::zeros((out.len(), 6));
    for (i, o) in out.iter().enumerate() {
        for c in 0..6 {
            y[(i, c)] = o.0.y_end[c];
        }
    }
    d.set_item("y_end", y.into_pyarray(py))?;
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

fn variant_from(name: &str) -> Result<Variant, CoreError> {
    match name {
        "consistent" => Ok(Variant::Consistent),
        "dead_load" => Ok(Variant::DeadLoad),
        _ => Err(CoreError(format!("variant = {name:?} is not valid: must be 'consistent' or 'dead_load'"))),
    }
}

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
#[pyo3(signature = (base, contact, friction_law, names, values, threads=None))]
fn linear_stability<'py>(
    py: Python<'py>,
    base: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ensemble_params(&base, contact, friction_law, &names, &values.as_array())?;
    let n = params.len();
    let out: Vec<LinearStability> = py.detach(|| {
        par_map(
            &params,
            threads,
            |p| linear::linear_stability(&Slider::new(*p).expect("validated")),
            |_| failed_linear(),
        )
    });
    let d = PyDict::new(py);
    let mut ev = numpy::ndarray::Array2::<numpy::Complex64>::zeros((n, 6));
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
    d.set_item("max_growth_rate", f(|l| l.max_growth_rate))?;
    d.set_item("least_stable_frequency", f(|l| l.least_stable_frequency))?;
    d.set_item("normal_mode_frequency_hz", f(|l| l.normal_mode_frequency_hz))?;
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
    let p = params_from(&values, "bilateral", friction_law)?;
    let pts = py.detach(|| linear::hopf_loads(&p, load_min, load_max, n_grid)).map_err(CoreError::from)?;
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

/// A named real quantity of a describing-function root.
type RootField = fn(&tidf::Root) -> f64;

fn search_options(w_min: f64, w_max: f64, n_base: usize) -> SearchOptions {
    SearchOptions { w_min, w_max, n_base, ..SearchOptions::default() }
}

/// All describing-function roots for each parameter set, padded to the largest root count.
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, variant="consistent", w_min=150.0, w_max=3000.0, n_base=1000, threads=None))]
#[allow(clippy::too_many_arguments)]
fn describing_function<'py>(
    py: Python<'py>,
    base: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    variant: &str,
    w_min: f64,
    w_max: f64,
    n_base: usize,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ensemble_params(&base, contact, friction_law, &names, &values.as_array())?;
    let variant = variant_from(variant)?;
    let opts = search_options(w_min, w_max, n_base);
    let out: Vec<Option<RootSearch>> = py.detach(|| {
        par_map(
            &params,
            threads,
            |p| {
                let s = Slider::new(*p).expect("validated");
                Some(Tidf::new(&s, variant).find_roots(&s, &opts))
            },
            |_| None,
        )
    });
    let n = out.len();
    let r = out.iter().map(|o| o.as_ref().map_or(0, |s| s.roots.len())).max().unwrap_or(0).max(1);
    let d = PyDict::new(py);
    let fields: [(&str, RootField); 16] = [
        ("omega", |x| x.omega),
        ("A0", |x| x.a0),
        ("A1", |x| x.a1),
        ("A2", |x| x.a2),
        ("theta", |x| x.theta),
        ("phi0", |x| x.phi0),
        ("x0", |x| x.x0),
        ("phi1_amp", |x| x.phi1_amp),
        ("phi1_phase", |x| x.phi1_phase),
        ("phi2_amp", |x| x.phi2.norm()),
        ("phi2_phase", |x| x.phi2.arg()),
        ("x1_amp", |x| x.x_amp),
        ("x1_phase", |x| x.x_phase),
        ("z_max", |x| x.z_max),
        ("third_harmonic_ratio", |x| x.third_harmonic_ratio),
        ("residual", |x| x.residual_norm),
    ];
    for (name, g) in fields {
        let mut a = Array2::<f64>::from_elem((n, r), f64::NAN);
        for (i, o) in out.iter().enumerate() {
            if let Some(sr) = o {
                for (k, root) in sr.roots.iter().enumerate() {
                    a[(i, k)] = g(root);
                }
            }
        }
        d.set_item(name, a.into_pyarray(py))?;
    }
    let flag = |g: fn(&tidf::Root) -> bool| {
        let mut a = Array2::<i8>::from_elem((n, r), -1);
        for (i, o) in out.iter().enumerate() {
            if let Some(sr) = o {
                for (k, root) in sr.roots.iter().enumerate() {
                    a[(i, k)] = g(root) as i8;
                }
            }
        }
        a.into_pyarray(py)
    };
    d.set_item("physical", flag(|x| x.physical))?;
    d.set_item("contact_opens", flag(|x| x.contact_opens))?;
    let mut iters = Array2::<i64>::from_elem((n, r), -1);
    for (i, o) in out.iter().enumerate() {
        if let Some(sr) = o {
            for (k, root) in sr.roots.iter().enumerate() {
                iters[(i, k)] = root.newton_iterations as i64;
            }
        }
    }
    d.set_item("newton_iterations", iters.into_pyarray(py))?;
    d.set_item(
        "n_roots",
        Array1::from_iter(out.iter().map(|o| o.as_ref().map_or(0, |s| s.roots.len() as i64))).into_pyarray(py),
    )?;
    d.set_item(
        "search_outcome",
        out.iter().map(|o| o.as_ref().map_or("failed", |s| s.outcome.name())).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "status",
        Array1::from_iter(out.iter().map(|o| o.as_ref().map_or(Status::Panic, |s| s.status).code())).into_pyarray(py),
    )?;
    d.set_item(
        "n_grid",
        Array1::from_iter(out.iter().map(|o| o.as_ref().map_or(0, |s| s.n_grid as i64))).into_pyarray(py),
    )?;
    Ok(d)
}

/// Warm-started damped Newton solves of the describing-function equations for one parameter set,
/// from each row of `guesses` (n, 5) = [w, A0, A1, A2, theta]. Returns roots, iterations, status,
/// residual norms. (The benchmark's warm-start workload; sweeps use `describing_function`.)
#[pyfunction]
#[pyo3(signature = (values, friction_law, guesses, variant="consistent", threads=None))]
fn tidf_solve<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    friction_law: &str,
    guesses: PyReadonlyArray2<'py, f64>,
    variant: &str,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = params_from(&values, "bilateral", friction_law)?;
    let s = Slider::new(p).map_err(CoreError::from)?;
    let variant = variant_from(variant)?;
    let g = guesses.as_array();
    if g.ncols() != 5 {
        return Err(CoreError(format!("guesses has {} columns: must be 5 ([w, A0, A1, A2, theta])", g.ncols())).into());
    }
    let rows: Vec<Unknowns> = (0..g.nrows()).map(|i| Unknowns::from_fn(|c, _| g[(i, c)])).collect();
    let t = Tidf::new(&s, variant);
    let opts = tidf::NewtonOptions::default();
    let out: Vec<Option<tidf::NewtonResult>> =
        py.detach(|| par_map(&rows, threads, |x| Some(t.solve(x, &opts)), |_| None));
    let n = out.len();
    let mut x = Array2::<f64>::from_elem((n, 5), f64::NAN);
    for (i, o) in out.iter().enumerate() {
        if let Some(r) = o {
            let c = tidf::canonical(&r.x);
            for k in 0..5 {
                x[(i, k)] = c[k];
            }
        }
    }
    let d = PyDict::new(py);
    d.set_item("x", x.into_pyarray(py))?;
    d.set_item("iterations", Array1::from_iter(out.iter().map(|o| o.map_or(0, |r| r.iterations))).into_pyarray(py))?;
    d.set_item(
        "status",
        Array1::from_iter(out.iter().map(|o| o.map_or(Status::Panic, |r| r.status).code())).into_pyarray(py),
    )?;
    d.set_item(
        "residual",
        Array1::from_iter(out.iter().map(|o| o.map_or(f64::NAN, |r| r.residual_norm))).into_pyarray(py),
    )?;
    Ok(d)
}

fn orbit_dict<'py>(py: Python<'py>, o: &PeriodicOrbit) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("period", o.period)?;
    d.set_item("omega", o.omega)?;
    d.set_item("state0", o.state0.as_slice().to_vec())?;
    d.set_item("multipliers_re", o.multipliers.iter().map(|c| c.re).collect::<Vec<_>>())?;
    d.set_item("multipliers_im", o.multipliers.iter().map(|c| c.im).collect::<Vec<_>>())?;
    d.set_item("moduli", o.moduli.to_vec())?;
    d.set_item("trivial_error", o.trivial_error)?;
    d.set_item("stable", o.stable)?;
    d.set_item("instability", o.instability.code())?;
    d.set_item("flip_multiplier", o.flip_multiplier)?;
    d.set_item("A0", o.harmonics.a0)?;
    d.set_item("A1", o.harmonics.a1)?;
    d.set_item("A2", o.harmonics.a2)?;
    d.set_item("A3", o.harmonics.a3)?;
    d.set_item("theta", o.harmonics.theta)?;
    d.set_item("z_max", o.z_max)?;
    d.set_item("z_min", o.z_min)?;
    d.set_item("contact_opens", o.contact_opens)?;
    d.set_item("open_fraction", o.open_fraction)?;
    d.set_item("min_normal_force", o.min_normal_force)?;
    d.set_item("min_law_force", o.min_law_force)?;
    d.set_item("n_switches", o.n_switches)?;
    d.set_item("residual", o.residual_norm)?;
    d.set_item("newton_iterations", o.newton_iterations)?;
    d.set_item("status", o.status.code())?;
    d.set_item("n_rhs", o.stats.n_rhs)?;
    d.set_item("n_accept", o.stats.n_accept)?;
    d.set_item("n_reject", o.stats.n_reject)?;
    Ok(d)
}

/// Periodic orbit by shooting from a state on it and a period guess, or from a describing-function
/// root `root = [omega, A0, A1, A2, theta]` (with `variant` to rebuild its phasors).
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, y0=None, period=None, root=None, variant="consistent", rtol=1e-11, max_iter=30, tol=1e-9))]
#[allow(clippy::too_many_arguments)]
fn periodic_orbit<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    y0: Option<PyReadonlyArray1<'py, f64>>,
    period: Option<f64>,
    root: Option<PyReadonlyArray1<'py, f64>>,
    variant: &str,
    rtol: f64,
    max_iter: u32,
    tol: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let p = params_from(&values, contact, friction_law)?;
    let s = Slider::new(p).map_err(CoreError::from)?;
    let opts = ShootingOptions { rtol, max_iter, tol, ..ShootingOptions::default() };
    let variant = variant_from(variant)?;
    let start = match (y0, period, root) {
        (Some(y), Some(t), None) => Start::State(State::from_column_slice(y.as_slice()?), t),
        (None, None, Some(r)) => {
            let r = r.as_slice()?;
            if r.len() != 5 {
                return Err(
                    CoreError(format!("root has {} entries: must be [omega, A0, A1, A2, theta]", r.len())).into()
                );
            }
            Start::Root(Unknowns::from_column_slice(r))
        }
        _ => return Err(CoreError("give either y0 and period, or root".into()).into()),
    };
    let orbit = py.detach(|| shoot_start(&s, &start, variant, &opts));
    orbit_dict(py, &orbit)
}

/// Where a shooting solve starts.
enum Start {
    /// A describing-function root `[omega, A0, A1, A2, theta]`.
    Root(Unknowns),
    /// A state on (or near) the orbit and a period guess [s].
    State(State, f64),
}

/// Shoot from `start`.
fn shoot_start(s: &Slider, start: &Start, variant: Variant, opts: &ShootingOptions) -> PeriodicOrbit {
    match start {
        Start::Root(x) => {
            let t = Tidf::new(s, variant);
            let torsion = linear::linear_stability(s).mode(linear::ModeKind::Torsion).frequency;
            let root = t.describe(x, torsion, SearchOptions::default().physical_band);
            shooting::shoot_from_root(s, &root, opts)
        }
        Start::State(y, period) => shooting::shoot(s, y, *period, opts),
    }
}

/// Periodic orbits of many parameter sets in parallel (GIL released; a panic becomes
/// `status = panic` for its row). Each row starts from a describing-function root
/// `roots[i] = [omega, A0, A1, A2, theta]` (with `variant`), or from a state `y0[i]` with a
/// period guess `periods[i]`. Returns arrays over rows, the per-orbit fields of `periodic_orbit`.
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, roots=None, y0=None, periods=None, variant="consistent", rtol=1e-11, max_iter=30, tol=1e-9, threads=None))]
#[allow(clippy::too_many_arguments)]
fn periodic_orbits<'py>(
    py: Python<'py>,
    base: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    roots: Option<PyReadonlyArray2<'py, f64>>,
    y0: Option<PyReadonlyArray2<'py, f64>>,
    periods: Option<PyReadonlyArray1<'py, f64>>,
    variant: &str,
    rtol: f64,
    max_iter: u32,
    tol: f64,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let params = ensemble_params(&base, contact, friction_law, &names, &values.as_array())?;
    let n = params.len();
    let opts = ShootingOptions { rtol, max_iter, tol, ..ShootingOptions::default() };
    let variant = variant_from(variant)?;
    let starts: Vec<Start> = match (roots, y0, periods) {
        (Some(r), None, None) => {
            let r = r.as_array();
            if r.dim() != (n, 5) {
                return Err(CoreError(format!("roots has shape {:?}: must be ({n}, 5)", r.dim())).into());
            }
            (0..n).map(|i| Start::Root(Unknowns::from_fn(|c, _| r[(i, c)]))).collect()
        }
        (None, Some(y), Some(t)) => {
            let (y, t) = (y.as_array(), t.as_array());
            let states = y0_rows(&y, n)?;
            if t.len() != n {
                return Err(CoreError(format!("periods has {} entries: must be {n}", t.len())).into());
            }
            states.into_iter().zip(t.iter()).map(|(s, &p)| Start::State(s, p)).collect()
        }
        _ => return Err(CoreError("give either roots, or y0 and periods".into()).into()),
    };
    let rows: Vec<(Params, Start)> = params.into_iter().zip(starts).collect();
    let out: Vec<PeriodicOrbit> = py.detach(|| {
        par_map(
            &rows,
            threads,
            |(p, start)| shoot_start(&Slider::new(*p).expect("validated"), start, variant, &opts),
            |_| PeriodicOrbit::not_computed(Status::Panic),
        )
    });
    let d = PyDict::new(py);
    let f = |g: fn(&PeriodicOrbit) -> f64| Array1::from_iter(out.iter().map(g)).into_pyarray(py);
    d.set_item("period", f(|o| o.period))?;
    d.set_item("omega", f(|o| o.omega))?;
    d.set_item("A0", f(|o| o.harmonics.a0))?;
    d.set_item("A1", f(|o| o.harmonics.a1))?;
    d.set_item("A2", f(|o| o.harmonics.a2))?;
    d.set_item("A3", f(|o| o.harmonics.a3))?;
    d.set_item("theta", f(|o| o.harmonics.theta))?;
    d.set_item("z_max", f(|o| o.z_max))?;
    d.set_item("open_fraction", f(|o| o.open_fraction))?;
    d.set_item("min_normal_force", f(|o| o.min_normal_force))?;
    d.set_item("flip_multiplier", f(|o| o.flip_multiplier))?;
    d.set_item("residual", f(|o| o.residual_norm))?;
    let mut moduli = Array2::<f64>::zeros((n, 6));
    let mut state0 = Array2::<f64>::zeros((n, 6));
    for (i, o) in out.iter().enumerate() {
        for c in 0..6 {
            moduli[(i, c)] = o.moduli[c];
            state0[(i, c)] = o.state0[c];
        }
    }
    d.set_item("moduli", moduli.into_pyarray(py))?;
    d.set_item("state0", state0.into_pyarray(py))?;
    d.set_item("stable", Array1::from_iter(out.iter().map(|o| o.stable)).into_pyarray(py))?;
    d.set_item("contact_opens", Array1::from_iter(out.iter().map(|o| o.contact_opens)).into_pyarray(py))?;
    d.set_item("instability", Array1::from_iter(out.iter().map(|o| o.instability.code())).into_pyarray(py))?;
    d.set_item("status", Array1::from_iter(out.iter().map(|o| o.status.code())).into_pyarray(py))?;
    d.set_item("newton_iterations", Array1::from_iter(out.iter().map(|o| o.newton_iterations)).into_pyarray(py))?;
    d.set_item("n_rhs", Array1::from_iter(out.iter().map(|o| o.stats.n_rhs)).into_pyarray(py))?;
    Ok(d)
}

/// How a periodic orbit is unstable (`PeriodicOrbit::instability`), in code order.
#[pyfunction]
fn instability_names() -> Vec<&'static str> {
    tribosweep_core::shooting::INSTABILITY_NAMES.to_vec()
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
    m.add_function(wrap_pyfunction!(instability_names, m)?)?;
    m.add_function(wrap_pyfunction!(periodic_orbits, m)?)?;
    m.add_function(wrap_pyfunction!(validate_params, m)?)?;
    m.add_function(wrap_pyfunction!(static_point, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(linear_stability, m)?)?;
    m.add_function(wrap_pyfunction!(hopf_loads, m)?)?;
    m.add_function(wrap_pyfunction!(describing_function, m)?)?;
    m.add_function(wrap_pyfunction!(periodic_orbit, m)?)?;
    m.add_function(wrap_pyfunction!(tidf_solve, m)?)?;
    branch::register(m)?;
    Ok(())
}
