//! Trajectories: one (`simulate`) or many (`ensemble`, routed by the core's `ensemble::run`).

use crate::convert::{method_from, reason_of, runs_into, states, summaries_into, tolerances, y0_rows, Call};
use crate::errors::CoreError;
use numpy::ndarray::{Array1, ArrayView1};
use numpy::{IntoPyArray, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::ensemble::{run as run_ensemble, run_sampled_into, Restart, Settings, Task, TrajectoryResult};
use tribosweep_core::model::State;
use tribosweep_core::shooting::approach_check;
use tribosweep_core::status::Status;
use tribosweep_core::steady::{
    self, ApproachCheck, Cells, DecayTest, Fingerprint, Known, RunResult, SteadyOptions, Summary, CELL_WORDS, KNOWN_MAX,
};

/// One trajectory. Returns a dict: `t` (n,), `y` (n, 6), and the run's status, reason (why the
/// status is not success, with its numbers; empty for success), counters, extremes. With `t_eval`
/// the states are sampled there; otherwise every accepted step end is returned. Ctrl-C stops it
/// (`KeyboardInterrupt`).
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, y0, t_end, method, rtol, *, atol=None, t_eval=None, max_steps=None, max_events=None))]
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
    let call = Call::one(py, &values, contact, friction_law, None)?;
    let method = method_from(method)?;
    let tol = tolerances(rtol, atol, max_steps, max_events)?;
    let y0 = State::from_column_slice(y0.as_slice()?);
    let t_eval: Option<Vec<f64>> = t_eval.map(|a| a.as_slice().map(|s| s.to_vec())).transpose()?;
    let slider = call.slider()?;
    let (run, t, ys) = call.detach(move || match t_eval {
        Some(te) => {
            let (r, ys) = steady::run_sampled(&slider, &y0, t_end, method, &tol, &te);
            (r, te, ys)
        }
        None => {
            let rec = steady::StepRecorder { t: Vec::new(), y: Vec::new() };
            let (r, rec) = steady::run_observed(&slider, &y0, t_end, method, &tol, rec);
            (r, rec.t, rec.y)
        }
    })?;
    let d = PyDict::new(py);
    d.set_item("t", Array1::from_vec(t).into_pyarray(py))?;
    d.set_item("y", states(ys.iter(), ys.len()).into_pyarray(py))?;
    runs_into(&d, &[&run], vec![reason_of(run.failure)])?;
    Ok(d)
}

/// What `ensemble` computes per trajectory (its `kind`).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// The end state, or with `t_eval` also the states there.
    Plain,
    /// A run to steady state and its summary.
    Steady,
}

impl Kind {
    fn parse(kind: &str, has_t_eval: bool) -> Result<Kind, CoreError> {
        match kind {
            "final" => Ok(Kind::Plain),
            "sampled" if has_t_eval => Ok(Kind::Plain),
            "sampled" => Err(CoreError("kind = 'sampled' needs t_eval".into())),
            "steady" => Ok(Kind::Steady),
            _ => Err(CoreError(format!("kind = {kind:?} is not valid: must be 'final', 'sampled' or 'steady'"))),
        }
    }
}

/// Per-trajectory decay tests of the steady kind (they override `decay_amplitude`): an amplitude
/// of `z` each (`decay_amplitudes`, shape `(n,)`) or thresholds of every component each
/// (`decay_thresholds`, shape `(n, 6)`), not both.
fn decays(
    amplitudes: Option<PyReadonlyArray1<'_, f64>>,
    thresholds: Option<PyReadonlyArray2<'_, f64>>,
    n: usize,
) -> PyResult<Option<Vec<DecayTest>>> {
    let bad = |x: &f64| !(x.is_finite() && *x > 0.0);
    match (amplitudes, thresholds) {
        (None, None) => Ok(None),
        (Some(_), Some(_)) => {
            Err(CoreError("decay_amplitudes and decay_thresholds: give one of them, not both".into()).into())
        }
        (Some(a), None) => {
            let v = a.as_slice()?.to_vec();
            if v.len() != n || v.iter().any(bad) {
                return Err(CoreError(format!(
                    "decay_amplitudes must hold {n} finite values > 0 (one per trajectory); got {} values",
                    v.len()
                ))
                .into());
            }
            Ok(Some(v.into_iter().map(DecayTest::Amplitude).collect()))
        }
        (None, Some(t)) => {
            let t = t.as_array();
            if t.shape() != [n, 6] || t.iter().any(bad) {
                return Err(CoreError(format!(
                    "decay_thresholds must be an ({n}, 6) array of finite values > 0 (one row per trajectory); \
                     got shape {:?}",
                    t.shape()
                ))
                .into());
            }
            Ok(Some(t.rows().into_iter().map(|r| DecayTest::Thresholds(std::array::from_fn(|c| r[c]))).collect()))
        }
    }
}

/// Per-trajectory restarts of runs to steady state (`restart`, shape `(n, 2)`: each run's `t_max`
/// and `hold`, from its own `t = 0`): finite, `t_max > 0`, `0 <= hold`.
fn restarts(restart: Option<PyReadonlyArray2<'_, f64>>, n: usize) -> PyResult<Option<Vec<Restart>>> {
    let Some(r) = restart else { return Ok(None) };
    let r = r.as_array();
    let ok = |row: &[f64]| row[0].is_finite() && row[0] > 0.0 && row[1].is_finite() && row[1] >= 0.0;
    if r.shape() != [n, 2] || !r.rows().into_iter().all(|row| ok(&[row[0], row[1]])) {
        return Err(CoreError(format!(
            "restart must be an ({n}, 2) array of rows (t_max > 0, hold >= 0), finite, one per trajectory; got \
             shape {:?}",
            r.shape()
        ))
        .into());
    }
    Ok(Some(r.rows().into_iter().map(|row| Restart { t_max: row[0], hold: row[1] }).collect()))
}

/// Per-trajectory fingerprints of known irregular attractors (`known_irregular`, shape
/// `(n, KNOWN_MAX, 7)`: the mean residual, then the six largest excursions, in characteristic
/// sizes, as the `irregular_residual` and `irregular_peaks` of an earlier steady run; a row of NaN
/// is an empty slot).
///
/// `known_cells` `(n, KNOWN_MAX, CELL_WORDS)` and `known_cell_extent` `(n, KNOWN_MAX, 6)`, both or
/// neither, give each fingerprint its cells (`irregular_cells` and `irregular_cell_extent` of the
/// same earlier run: the grid's lower corner, then its upper corner): zeros and NaN for none.
fn knowns(
    known: Option<PyReadonlyArray3<'_, f64>>,
    cells: Option<PyReadonlyArray3<'_, u64>>,
    extent: Option<PyReadonlyArray3<'_, f64>>,
    n: usize,
) -> PyResult<Option<Vec<Known>>> {
    // Views of the caller's arrays (they outlive this function's use of them): no copy.
    let cells = match (&cells, &extent, &known) {
        (None, None, _) => None,
        (Some(c), Some(e), Some(_)) => {
            let (c, e) = (c.as_array(), e.as_array());
            let ok = c.shape() == [n, KNOWN_MAX, CELL_WORDS]
                && e.shape() == [n, KNOWN_MAX, 6]
                && e.outer_iter().zip(c.outer_iter()).all(|(et, ct)| {
                    et.outer_iter().zip(ct.outer_iter()).all(|(r, b)| {
                        let none = r.iter().all(|x| x.is_nan()) && b.iter().all(|&w| w == 0);
                        let some = r.iter().all(|x| x.is_finite()) && (0..3).all(|i| r[i] < r[i + 3]);
                        none || some
                    })
                });
            if !ok {
                return Err(CoreError(format!(
                    "known_cells must be an ({n}, {KNOWN_MAX}, {CELL_WORDS}) uint64 array and known_cell_extent an \
                     ({n}, {KNOWN_MAX}, 6) array whose rows are all NaN (with zero cells: none) or finite lower \
                     corners below the upper ones; got shapes {:?} and {:?}",
                    c.shape(),
                    e.shape()
                ))
                .into());
            }
            Some((c, e))
        }
        _ => {
            return Err(CoreError(
                "known_cells and known_cell_extent go together, and with known_irregular: give all three or \
                 neither of the first two"
                    .to_string(),
            )
            .into())
        }
    };
    let Some(k) = known else { return Ok(None) };
    let k = k.as_array();
    let shape_ok = k.shape() == [n, KNOWN_MAX, 7];
    let row_ok = |r: ArrayView1<'_, f64>| {
        r.iter().all(|x| x.is_nan()) || (r.iter().all(|x| x.is_finite() && *x >= 0.0) && r[0] > 0.0)
    };
    if !shape_ok || !k.outer_iter().all(|t| t.outer_iter().all(row_ok)) {
        return Err(CoreError(format!(
            "known_irregular must be an ({n}, {KNOWN_MAX}, 7) array whose rows are all NaN (no fingerprint) or \
             finite values >= 0 with a residual > 0; got shape {:?}",
            k.shape()
        ))
        .into());
    }
    Ok(Some(
        k.outer_iter()
            .enumerate()
            .map(|(i, t)| {
                std::array::from_fn(|j| {
                    let r = t.row(j);
                    let cells = cells.as_ref().map_or(Cells::EMPTY, |(c, e)| {
                        let e = e.slice(numpy::ndarray::s![i, j, ..]);
                        Cells {
                            lo: std::array::from_fn(|m| e[m]),
                            hi: std::array::from_fn(|m| e[m + 3]),
                            bits: std::array::from_fn(|w| c[[i, j, w]]),
                        }
                    });
                    (!r[0].is_nan()).then(|| Fingerprint {
                        residual: r[0],
                        peaks: std::array::from_fn(|c| r[c + 1]),
                        cells,
                    })
                })
            })
            .collect(),
    ))
}

/// The summaries of runs to steady state with their reasons (the summary's failure): a trajectory
/// whose computation panicked gets a failed summary (`Status::Panic`) and the message.
fn summaries(out: Vec<Result<TrajectoryResult, String>>) -> Vec<(Summary, String)> {
    out.into_iter()
        .map(|r| match r {
            Ok(x) => {
                let s = x.summary.map_or_else(|| Summary::failed(x.run.status, x.run.failure), |s| *s);
                let reason = reason_of(s.failure);
                (s, reason)
            }
            Err(msg) => (Summary::failed(Status::Panic, None), format!("panic: {msg}")),
        })
        .collect()
}

/// Many trajectories in parallel (GIL released). `kind` is "final" (end state), "sampled"
/// (states at `t_eval`) or "steady" (run to steady state and summarise; `t_end` is then `t_max`;
/// `watch_x=False`: the settling tests ignore `x, xd` where they are slaved, under constant friction;
/// `irregular_block > 0`: sustained irregular motion stops once stationary over three blocks of
/// that many sections, outcome "irregular", or once a block matches one of the trajectory's
/// `known_irregular` fingerprints, those of irregular runs of the same model, or its sections keep
/// to their `known_cells`; see `knowns`; `restart`: each run's own `t_max` and hold, see `restarts`;
/// `stationary_tol`: the repetition tolerance that sets the stationarity floor, default `periodic_tol`;
/// `approach_periods > 0`: a slow approach to a cycle is checked by shooting inside the run after that
/// many periods of steady contraction (at `approach_rtol`, Newton tolerance `approach_tol`), and a
/// stable orbit ends the run on it, output `approach`; the third check that finds the same unstable
/// orbit, the run having left it between, ends the run as intermittent irregular motion, outputs
/// `intermittent_period`, `intermittent_multiplier` and `intermittent_visits`; `checked_stops`: the
/// caller shoots from every periodic stop, so `x` and `xd` need only repeat to `CHECKED_X_SLACK`
/// (10) times `periodic_tol`).
/// The core picks the path (lane-batched or scalar) and the grouping; results do not depend on it
/// beyond integration accuracy, nor on the thread count at all. Every non-success status has a
/// reason; Ctrl-C stops every thread (`KeyboardInterrupt`, the results are dropped).
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, y0, t_end, method, rtol, *, atol=None, t_eval=None, threads=None, kind="final", periodic_tol=1e-5, decay_amplitude=None, n_fourier=512, max_steps=None, max_events=None, decay_amplitudes=None, watch_x=true, decay_thresholds=None, irregular_block=0, known_irregular=None, known_cells=None, known_cell_extent=None, restart=None, stationary_tol=None, approach_periods=0, approach_rtol=None, approach_tol=None, checked_stops=false))]
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
    watch_x: bool,
    decay_thresholds: Option<PyReadonlyArray2<'py, f64>>,
    irregular_block: usize,
    known_irregular: Option<PyReadonlyArray3<'py, f64>>,
    known_cells: Option<PyReadonlyArray3<'py, u64>>,
    known_cell_extent: Option<PyReadonlyArray3<'py, f64>>,
    restart: Option<PyReadonlyArray2<'py, f64>>,
    stationary_tol: Option<f64>,
    approach_periods: usize,
    approach_rtol: Option<f64>,
    approach_tol: Option<f64>,
    checked_stops: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let call = Call::rows(py, &base, contact, friction_law, &names, &values, threads)?;
    let n = call.len();
    let y0s = y0_rows(&y0.as_array(), n)?;
    let decays = decays(decay_amplitudes, decay_thresholds, n)?;
    let knowns = knowns(known_irregular, known_cells, known_cell_extent, n)?;
    let restarts = restarts(restart, n)?;
    let settings =
        Settings { t_end, method: method_from(method)?, tol: tolerances(rtol, atol, max_steps, max_events)?, threads };
    let t_eval: Option<Vec<f64>> = t_eval.map(|a| a.as_slice().map(|s| s.to_vec())).transpose()?;
    let kind = Kind::parse(kind, t_eval.is_some())?;
    let sliders = call.sliders()?;
    let d = PyDict::new(py);
    match kind {
        Kind::Plain => {
            let te = t_eval.unwrap_or_default();
            // The samples go straight into the array's buffer, allocated by numpy (which asks for
            // huge pages for a large one: the run's writes fault a few pages, not every 4 KiB).
            let (out, y) = if te.is_empty() {
                (call.detach(|| run_ensemble(&sliders, &y0s, &settings, Task::Final))?, None)
            } else {
                let y = PyArray3::<f64>::zeros(py, [n, te.len(), 6], false);
                let mut rw = y.readwrite();
                let flat = rw.as_slice_mut().expect("a new array is contiguous");
                (call.detach(|| run_sampled_into(&sliders, &y0s, &settings, &te, flat))?, Some(y.clone()))
            };
            // Columns straight from the results: with every run 0.5 s long, moving the results
            // once more on this one thread was a tenth of a 16-thread call.
            let panicked = RunResult::failed(Status::Panic, None);
            let runs: Vec<&RunResult> = out.iter().map(|o| o.as_ref().map_or(&panicked, |x| &x.run)).collect();
            let reasons: Vec<String> = out
                .iter()
                .map(|o| match o {
                    Ok(x) => reason_of(x.run.failure),
                    Err(msg) => format!("panic: {msg}"),
                })
                .collect();
            runs_into(&d, &runs, reasons)?;
            if let Some(y) = y {
                d.set_item("y", y)?;
            }
        }
        Kind::Steady => {
            let opts = SteadyOptions {
                t_max: t_end,
                method: settings.method,
                tol: settings.tol,
                periodic_tol,
                stationary_tol,
                decay_amplitude,
                n_fourier,
                watch_x,
                checked_stops,
                irregular_block,
                approach_periods,
                approach_check: (approach_periods > 0).then_some(approach_check as ApproachCheck),
                approach_rtol: approach_rtol.unwrap_or(SteadyOptions::default().approach_rtol),
                approach_tol: approach_tol.unwrap_or(SteadyOptions::default().approach_tol),
                ..SteadyOptions::default()
            };
            let task = Task::Steady {
                opts: &opts,
                decay: decays.as_deref(),
                known: knowns.as_deref(),
                restart: restarts.as_deref(),
            };
            let sums = summaries(call.detach(|| run_ensemble(&sliders, &y0s, &settings, task))?);
            summaries_into(&d, &sums)?;
        }
    }
    Ok(d)
}

/// Add this group's functions to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    Ok(())
}
