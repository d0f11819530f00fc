//! Periodic orbits by shooting, with Floquet multipliers: one orbit, or one per parameter set.

use crate::convert::{reason_of, variant_from, y0_rows, Call};
use crate::errors::CoreError;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::linear;
use tribosweep_core::model::{Slider, State};
use tribosweep_core::shooting::{self, PeriodicOrbit, ShootingOptions};
use tribosweep_core::status::Status;
use tribosweep_core::tidf::{SearchOptions, Tidf, Unknowns, Variant};

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

fn orbit_dict<'py>(py: Python<'py>, o: &PeriodicOrbit) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("period", o.period)?;
    d.set_item("omega", o.omega)?;
    d.set_item("state0", o.state0.as_slice().to_vec())?;
    d.set_item("multipliers_re", o.multipliers.iter().map(|c| c.re).collect::<Vec<_>>())?;
    d.set_item("multipliers_im", o.multipliers.iter().map(|c| c.im).collect::<Vec<_>>())?;
    d.set_item("moduli", o.moduli.to_vec())?;
    d.set_item("trivial_error", o.trivial_error)?;
    // Unset (None) for an orbit that was not found: its stability is unknown.
    d.set_item("stable", if o.status == Status::Success { Some(o.stable) } else { None })?;
    d.set_item("reason", reason_of(o.failure))?;
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
    d.set_item("fraction_off_disk", o.open_fraction)?;
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
/// root `root = [omega, A0, A1, A2, theta]` (with `variant` to rebuild its phasors). When no orbit
/// was found the values are NaN, `stable` is None and `reason` says why.
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, *, y0=None, period=None, root=None, variant="consistent", rtol=1e-11, max_iter=30, tol=1e-9))]
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
    let call = Call::one(py, &values, contact, friction_law, None)?;
    let s = call.slider()?;
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
    let orbit = call.detach(|| shoot_start(&s, &start, variant, &opts))?;
    orbit_dict(py, &orbit)
}

/// Periodic orbits of many parameter sets in parallel (GIL released; a panic becomes
/// `status = panic` for its row; `reason` says why a row's status is not success; `stable` is
/// false where the orbit was not found). Each row starts from a describing-function root
/// `roots[i] = [omega, A0, A1, A2, theta]` (with `variant`), or from a state `y0[i]` with a
/// period guess `periods[i]`. Returns arrays over rows, the per-orbit fields of `periodic_orbit`.
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, *, roots=None, y0=None, periods=None, variant="consistent", rtol=1e-11, max_iter=30, tol=1e-9, threads=None))]
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
    let call = Call::rows(py, &base, contact, friction_law, &names, &values, threads)?;
    let n = call.len();
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
    let rows: Vec<(Slider, Start)> = call.sliders()?.into_iter().zip(starts).collect();
    let out: Vec<(PeriodicOrbit, String)> = call.map(
        &rows,
        |(s, start)| {
            let o = shoot_start(s, start, variant, &opts);
            (o, reason_of(o.failure))
        },
        |msg| (PeriodicOrbit::not_computed(Status::Panic), format!("panic: {msg}")),
    )?;
    let (out, reasons): (Vec<PeriodicOrbit>, Vec<String>) = out.into_iter().unzip();
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
    d.set_item("fraction_off_disk", f(|o| o.open_fraction))?;
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
    d.set_item("reason", reasons)?;
    d.set_item("newton_iterations", Array1::from_iter(out.iter().map(|o| o.newton_iterations)).into_pyarray(py))?;
    d.set_item("n_rhs", Array1::from_iter(out.iter().map(|o| o.stats.n_rhs)).into_pyarray(py))?;
    Ok(d)
}

/// Add this group's functions to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(periodic_orbit, m)?)?;
    m.add_function(wrap_pyfunction!(periodic_orbits, m)?)?;
    Ok(())
}
