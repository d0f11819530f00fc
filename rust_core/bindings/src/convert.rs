//! Conversions between Python arguments and the core's types, and the preamble every pyfunction
//! shares ([`Call`]: validated parameters, the thread count, the GIL released around the numerics).
//!
//! Every check here raises `InvalidArgumentError` (a `ValueError`) through [`CoreError`], before any
//! work, with a message that names the argument, its value and what is valid.

use crate::errors::CoreError;
use crate::interrupt;
use numpy::ndarray::{Array1, Array2, ArrayView2};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use std::collections::HashMap;
use tribosweep_core::model::{ContactModel, FrictionLaw, Params, Slider, State};
use tribosweep_core::ode::{Method, Stats};
use tribosweep_core::parallel::{par_fill, par_map};
use tribosweep_core::steady::{Nearest, RunResult, Summary, Tolerances};
use tribosweep_core::tidf::Variant;

/// Most worker threads a call accepts (as the Python API's `_checks.MAX_THREADS`): far above any
/// machine's core count, and far below what would make the thread pool fail to start.
pub(crate) const MAX_THREADS: usize = 1024;

/// `threads`: `None` or an integer in `[1, MAX_THREADS]`.
pub(crate) fn threads_from(threads: Option<usize>) -> Result<Option<usize>, CoreError> {
    match threads {
        Some(n) if !(1..=MAX_THREADS).contains(&n) => {
            Err(CoreError(format!("threads = {n} is out of range: must be an integer in [1, {MAX_THREADS}] or None")))
        }
        t => Ok(t),
    }
}

/// `contact` by name.
pub(crate) fn contact_from(name: &str) -> Result<ContactModel, CoreError> {
    match name {
        "bilateral" => Ok(ContactModel::Bilateral),
        "unilateral" => Ok(ContactModel::Unilateral),
        _ => Err(CoreError(format!("contact = {name:?} is not valid: must be 'bilateral' or 'unilateral'"))),
    }
}

/// `friction_law` by name.
pub(crate) fn friction_from(name: &str) -> Result<FrictionLaw, CoreError> {
    match name {
        "constant" => Ok(FrictionLaw::Constant),
        "coulomb" => Ok(FrictionLaw::Coulomb),
        "switch" => Ok(FrictionLaw::Switch),
        _ => Err(CoreError(format!("friction_law = {name:?} is not valid: must be 'constant', 'coulomb' or 'switch'"))),
    }
}

/// The integrator `method` by name.
pub(crate) fn method_from(name: &str) -> Result<Method, CoreError> {
    Method::from_name(name).ok_or_else(|| {
        let all: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        CoreError(format!("method = {name:?} is not valid: must be one of {}", all.join(", ")))
    })
}

/// The describing-function `variant` by name.
pub(crate) fn variant_from(name: &str) -> Result<Variant, CoreError> {
    match name {
        "consistent" => Ok(Variant::Consistent),
        "dead_load" => Ok(Variant::DeadLoad),
        _ => Err(CoreError(format!("variant = {name:?} is not valid: must be 'consistent' or 'dead_load'"))),
    }
}

/// Validated parameters from a name -> value map plus the two categorical settings.
pub(crate) fn params_from(
    values: &HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
) -> Result<Params, CoreError> {
    let mut p = Params::seed();
    for (k, v) in values {
        p.set(k, *v)?;
    }
    p.contact = contact_from(contact)?;
    p.friction_law = friction_from(friction_law)?;
    p.validate()?;
    Ok(p)
}

/// Per-row parameter sets: the base map with the columns `names` of `values` (n, k) overriding.
fn param_rows(
    base: &HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    names: &[String],
    values: &ArrayView2<'_, f64>,
    threads: Option<usize>,
) -> Result<Vec<Params>, CoreError> {
    let p0 = params_from(base, contact, friction_law)?;
    if values.ncols() != names.len() {
        return Err(CoreError(format!(
            "values has {} columns but {} parameter names were given",
            values.ncols(),
            names.len()
        )));
    }
    par_fill(values.nrows(), threads, SETUP_ROWS, |i| {
        let mut p = p0;
        for (k, name) in names.iter().enumerate() {
            p.set(name, values[(i, k)])?;
        }
        p.validate().map_err(|e| CoreError(format!("trajectory {i}: {e}")))?;
        Ok(p)
    })
}

/// Rows per work item when a call's per-row preamble (parameters, validation, sliders) runs on the
/// thread pool. That preamble is work of the same order as a short trajectory: done on one thread,
/// with the results gathered serially, it capped a 16-core ensemble of 0.5 s runs at about 10x one
/// core.
const SETUP_ROWS: usize = 4096;

/// Start states: `y0` of shape (1, 6) for every row, or (n, 6) one per row.
pub(crate) fn y0_rows(y0: &ArrayView2<'_, f64>, n: usize) -> Result<Vec<State>, CoreError> {
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

/// Tolerances and limits of an integration; `atol` has one entry per state component.
pub(crate) fn tolerances(
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

/// The preamble every pyfunction shares: the validated parameters of the call (one set, or one
/// per row of a batch), the worker threads, and the GIL released around the numerics.
pub(crate) struct Call<'py> {
    py: Python<'py>,
    params: Vec<Params>,
    threads: Option<usize>,
}

impl<'py> Call<'py> {
    /// One parameter set: `values` over the seed, with `contact` and `friction_law`.
    pub(crate) fn one(
        py: Python<'py>,
        values: &HashMap<String, f64>,
        contact: &str,
        friction_law: &str,
        threads: Option<usize>,
    ) -> Result<Self, CoreError> {
        Ok(Call { py, params: vec![params_from(values, contact, friction_law)?], threads: threads_from(threads)? })
    }

    /// One parameter set per row: `base` with the columns `names` of `values` (n, k) overriding.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn rows(
        py: Python<'py>,
        base: &HashMap<String, f64>,
        contact: &str,
        friction_law: &str,
        names: &[String],
        values: &PyReadonlyArray2<'py, f64>,
        threads: Option<usize>,
    ) -> Result<Self, CoreError> {
        let threads = threads_from(threads)?;
        Ok(Call { py, params: param_rows(base, contact, friction_law, names, &values.as_array(), threads)?, threads })
    }

    /// Number of parameter sets.
    pub(crate) fn len(&self) -> usize {
        self.params.len()
    }

    /// The first (for [`Call::one`]: the only) parameter set.
    pub(crate) fn params(&self) -> Params {
        self.params[0]
    }

    /// The slider of the first (the only) parameter set.
    pub(crate) fn slider(&self) -> Result<Slider, CoreError> {
        Ok(Slider::new(self.params())?)
    }

    /// The slider of every parameter set.
    pub(crate) fn sliders(&self) -> Result<Vec<Slider>, CoreError> {
        let params = &self.params[..];
        par_fill(params.len(), self.threads, SETUP_ROWS, |i| Slider::new(params[i]).map_err(CoreError::from))
    }

    /// `f` with the GIL released, stopped by Ctrl-C (see [`interrupt::detach`]: the error of
    /// the signal handler, `KeyboardInterrupt`, is returned).
    pub(crate) fn detach<R: Send>(&self, f: impl FnOnce() -> R + Send) -> PyResult<R> {
        interrupt::detach(self.py, f)
    }

    /// `f` of every item on the core's thread pool, in item order, with the GIL released and
    /// stopped by Ctrl-C as [`Call::detach`]; a panic in `f` becomes `on_panic(message)` for its
    /// item.
    pub(crate) fn map<T: Sync, R: Send>(
        &self,
        items: &[T],
        f: impl Fn(&T) -> R + Sync + Send,
        on_panic: impl Fn(String) -> R + Sync + Send,
    ) -> PyResult<Vec<R>> {
        let threads = self.threads;
        interrupt::detach(self.py, move || par_map(items, threads, f, on_panic))
    }
}

/// Work counters as columns `n_rhs`, `n_jac`, `n_lu`, `n_accept`, `n_reject`, `n_events`.
pub(crate) fn stats_into(d: &Bound<'_, PyDict>, stats: &[Stats]) -> PyResult<()> {
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

/// The reason of a status: the failure's text, else empty (success).
pub(crate) fn reason_of(failure: Option<tribosweep_core::Failure>) -> String {
    failure.map(|f| f.to_string()).unwrap_or_default()
}

/// Plain runs as columns: status, reason, time and state reached, extremes, work counters. One
/// pass over the runs (an ensemble's columns are gathered on one thread).
pub(crate) fn runs_into(d: &Bound<'_, PyDict>, runs: &[&RunResult], reasons: Vec<String>) -> PyResult<()> {
    let py = d.py();
    let n = runs.len();
    let mut status = Vec::with_capacity(n);
    let mut cols: [Vec<f64>; 5] = std::array::from_fn(|_| Vec::with_capacity(n));
    let mut y = Array2::<f64>::zeros((n, 6));
    let mut stats = Vec::with_capacity(n);
    for (i, r) in runs.iter().enumerate() {
        status.push(r.status.code());
        let e = &r.extremes;
        for (c, v) in cols.iter_mut().zip([r.t, e.min_normal_force, e.max_gap, e.min_slip_velocity, e.max_abs_z]) {
            c.push(v);
        }
        for c in 0..6 {
            y[(i, c)] = r.y[c];
        }
        stats.push(r.stats);
    }
    d.set_item("status", status.into_pyarray(py))?;
    d.set_item("reason", reason_list(py, reasons.iter().map(String::as_str))?)?;
    let [t, min_normal_force, max_gap, min_slip_velocity, max_abs_z] = cols;
    d.set_item("t_reached", t.into_pyarray(py))?;
    d.set_item("min_normal_force", min_normal_force.into_pyarray(py))?;
    d.set_item("max_gap", max_gap.into_pyarray(py))?;
    d.set_item("min_slip_velocity", min_slip_velocity.into_pyarray(py))?;
    d.set_item("max_abs_z", max_abs_z.into_pyarray(py))?;
    d.set_item("y_end", y.into_pyarray(py))?;
    stats_into(d, &stats)
}

/// Reasons as a list of str, the empty reason of every success sharing one object.
pub(crate) fn reason_list<'py, 'a>(
    py: Python<'py>,
    reasons: impl ExactSizeIterator<Item = &'a str>,
) -> PyResult<Bound<'py, PyList>> {
    let empty = PyString::new(py, "");
    PyList::new(py, reasons.map(|r| if r.is_empty() { empty.clone() } else { PyString::new(py, r) }))
}

/// Summaries of runs to steady state as columns.
pub(crate) fn summaries_into(d: &Bound<'_, PyDict>, out: &[(Summary, String)]) -> PyResult<()> {
    let py = d.py();
    let f = |g: &dyn Fn(&Summary) -> f64| Array1::from_iter(out.iter().map(|o| g(&o.0))).into_pyarray(py);
    d.set_item("status", Array1::from_iter(out.iter().map(|o| o.0.status.code())).into_pyarray(py))?;
    d.set_item("reason", reason_list(py, out.iter().map(|o| o.1.as_str()))?)?;
    d.set_item("outcome", Array1::from_iter(out.iter().map(|o| o.0.outcome as u8)).into_pyarray(py))?;
    d.set_item("t_end", f(&|s| s.t_end))?;
    d.set_item("omega", f(&|s| s.omega))?;
    d.set_item("period", f(&|s| s.period))?;
    d.set_item("multiplicity", Array1::from_iter(out.iter().map(|o| o.0.multiplicity)).into_pyarray(py))?;
    d.set_item("y_end", states(out.iter().map(|o| &o.0.y_end), out.len()).into_pyarray(py))?;
    d.set_item("z0", f(&|s| s.z0))?;
    d.set_item("z_half_range", f(&|s| s.z_half_range))?;
    for k in 0..3 {
        d.set_item(format!("z{}_amplitude", k + 1), f(&|s| s.z_amp[k]))?;
        d.set_item(format!("z{}_phase", k + 1), f(&|s| s.z_phase[k]))?;
    }
    d.set_item("phi1_amplitude", f(&|s| s.phi_amp))?;
    d.set_item("phi1_phase", f(&|s| s.phi_phase))?;
    d.set_item("x1_amplitude", f(&|s| s.x_amp))?;
    d.set_item("x1_phase", f(&|s| s.x_phase))?;
    d.set_item("min_normal_force", f(&|s| s.min_normal_force))?;
    d.set_item("fraction_off_disk", f(&|s| s.fraction_off_disk))?;
    d.set_item("min_slip_velocity", f(&|s| s.min_slip_velocity))?;
    d.set_item("max_gap", f(&|s| s.extremes.max_gap))?;
    d.set_item("max_abs_z", f(&|s| s.extremes.max_abs_z))?;
    // Irregular runs: the attractor's fingerprint (NaN otherwise), and whether a known one matched.
    d.set_item("irregular_residual", f(&|s| s.fingerprint.map_or(f64::NAN, |p| p.residual)))?;
    let peaks: Vec<State> =
        out.iter().map(|o| o.0.fingerprint.map_or(State::repeat(f64::NAN), |p| State::from(p.peaks))).collect();
    let peaks = states(peaks.iter(), out.len());
    d.set_item("irregular_peaks", peaks.into_pyarray(py))?;
    d.set_item("irregular_matched", Array1::from_iter(out.iter().map(|o| o.0.matched_known)).into_pyarray(py))?;
    // Periodic runs that stopped on a slow approach (`approach_periods`), not a repetition.
    d.set_item("approach", Array1::from_iter(out.iter().map(|o| o.0.approach)).into_pyarray(py))?;
    // Irregular runs that stopped as intermittent motion: the unstable cycle they kept returning
    // to (its period, largest multiplier modulus; NaN otherwise) and the visits (0 otherwise).
    d.set_item("intermittent_period", f(&|s| s.intermittent.map_or(f64::NAN, |m| m.period)))?;
    d.set_item("intermittent_multiplier", f(&|s| s.intermittent.map_or(f64::NAN, |m| m.largest)))?;
    let visits = out.iter().map(|o| o.0.intermittent.map_or(0, |m| m.visits));
    d.set_item("intermittent_visits", Array1::from_iter(visits).into_pyarray(py))?;
    // How that cycle is unstable: `instability_names` codes 1-3 (fold, flip, torus); 0 otherwise.
    let kinds = out.iter().map(|o| o.0.intermittent.map_or(0u8, |m| m.kind));
    d.set_item("intermittent_instability", Array1::from_iter(kinds).into_pyarray(py))?;
    // Their cells (zeros and NaN extents where there are none): input for `known_cells`. Without
    // any (no stationarity blocks, no irregular run) the cell array has no columns: 1.7 KB per
    // trajectory of zeros would outweigh every other column together.
    let any = out.iter().any(|o| o.0.fingerprint.is_some_and(|p| !p.cells.is_empty()));
    let words = if any { tribosweep_core::steady::CELL_WORDS } else { 0 };
    let mut cells = Array2::<u64>::zeros((out.len(), words));
    let mut extent = Array2::<f64>::from_elem((out.len(), 6), f64::NAN);
    for (i, o) in out.iter().enumerate() {
        if let Some(c) = o.0.fingerprint.map(|p| p.cells).filter(|c| !c.is_empty()) {
            cells.row_mut(i).iter_mut().zip(c.bits).for_each(|(a, b)| *a = b);
            extent.row_mut(i).iter_mut().zip(c.lo.into_iter().chain(c.hi)).for_each(|(a, b)| *a = b);
        }
    }
    d.set_item("irregular_cells", cells.into_pyarray(py))?;
    d.set_item("irregular_cell_extent", extent.into_pyarray(py))?;
    // Unsettled runs: the newest section state's closest repetition (NaN and 0 otherwise).
    let near = |g: &dyn Fn(&Nearest) -> f64| f(&|s| s.nearest.as_ref().map_or(f64::NAN, g));
    d.set_item("nearest_period", near(&|n| n.period))?;
    d.set_item("nearest_residual", near(&|n| n.residual))?;
    let mult = Array1::from_iter(out.iter().map(|o| o.0.nearest.map_or(0, |n| n.multiplicity)));
    d.set_item("nearest_multiplicity", mult.into_pyarray(py))?;
    let ny: Vec<State> = out.iter().map(|o| o.0.nearest.map_or(State::repeat(f64::NAN), |n| n.y)).collect();
    d.set_item("nearest_y", states(ny.iter(), out.len()).into_pyarray(py))?;
    let stats: Vec<Stats> = out.iter().map(|o| o.0.stats).collect();
    stats_into(d, &stats)
}

/// States as an (n, 6) array.
pub(crate) fn states<'a>(ys: impl Iterator<Item = &'a State>, n: usize) -> Array2<f64> {
    let mut a = Array2::<f64>::zeros((n, 6));
    for (i, s) in ys.enumerate() {
        for c in 0..6 {
            a[(i, c)] = s[c];
        }
    }
    a
}
