//! The triple-input describing function: every root per parameter set, and warm-started Newton
//! solves from given guesses.

use crate::convert::{variant_from, Call};
use crate::errors::CoreError;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::status::Status;
use tribosweep_core::tidf::{self, RootSearch, SearchOptions, Tidf, Unknowns};

/// A named real quantity of a describing-function root.
type RootField = fn(&tidf::Root) -> f64;

/// All describing-function roots for each parameter set, padded to the largest root count.
#[pyfunction]
#[pyo3(signature = (base, contact, friction_law, names, values, *, variant="consistent", w_min=150.0, w_max=3000.0, n_base=1000, threads=None))]
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
    let call = Call::rows(py, &base, contact, friction_law, &names, &values, threads)?;
    let variant = variant_from(variant)?;
    let opts = SearchOptions { w_min, w_max, n_base, ..SearchOptions::default() };
    let sliders = call.sliders()?;
    let out: Vec<Option<RootSearch>> =
        call.map(&sliders, |s| Some(Tidf::new(s, variant).find_roots(s, &opts)), |_| None)?;
    let n = out.len();
    let r = out.iter().map(|o| o.as_ref().map_or(0, |s| s.roots.len())).max().unwrap_or(0).max(1);
    let d = PyDict::new(py);
    let fields: [(&str, RootField); 17] = [
        ("omega", |x| x.omega),
        ("A0", |x| x.a0),
        ("A1", |x| x.a1),
        ("A2", |x| x.a2),
        ("theta", |x| x.theta),
        ("phi0", |x| x.phi0),
        ("x0", |x| x.x0),
        ("phi1_amplitude", |x| x.phi1_amp),
        ("phi1_phase", |x| x.phi1_phase),
        ("phi2_amplitude", |x| x.phi2.norm()),
        ("phi2_phase", |x| x.phi2.arg()),
        ("x1_amplitude", |x| x.x_amp),
        ("x1_phase", |x| x.x_phase),
        ("z_max", |x| x.z_max),
        ("z_min", |x| x.z_min),
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
#[pyo3(signature = (values, friction_law, guesses, *, variant="consistent", threads=None))]
fn tidf_solve<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    friction_law: &str,
    guesses: PyReadonlyArray2<'py, f64>,
    variant: &str,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let call = Call::one(py, &values, "bilateral", friction_law, threads)?;
    let s = call.slider()?;
    let variant = variant_from(variant)?;
    let g = guesses.as_array();
    if g.ncols() != 5 {
        return Err(CoreError(format!("guesses has {} columns: must be 5 ([w, A0, A1, A2, theta])", g.ncols())).into());
    }
    let rows: Vec<Unknowns> = (0..g.nrows()).map(|i| Unknowns::from_fn(|c, _| g[(i, c)])).collect();
    let t = Tidf::new(&s, variant);
    let opts = tidf::NewtonOptions::default();
    let out: Vec<Option<tidf::NewtonResult>> = call.map(&rows, |x| Some(t.solve(x, &opts)), |_| None)?;
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

/// Add this group's functions to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(describing_function, m)?)?;
    m.add_function(wrap_pyfunction!(tidf_solve, m)?)?;
    Ok(())
}
