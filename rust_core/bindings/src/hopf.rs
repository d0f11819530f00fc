//! Bindings of the Hopf analysis (`tribosweep_core::hopf`): steady sliding along one parameter
//! and Hopf curves in two. Only conversion, error mapping and GIL release; the public API and its
//! argument checks live in `python/tribosweep/_hopf.py`.

use numpy::ndarray::{Array1, Array2};
use numpy::{Complex64, IntoPyArray};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::hopf::curve::{hopf_curves, CurveOptions, EndStatus, PointType};
use tribosweep_core::hopf::scan::{scan, ScanOptions};
use tribosweep_core::hopf::slider::{Axis, SliderFamily, Term};
use tribosweep_core::hopf::{Counters, Criticality, C64};
use tribosweep_core::linear::ModeKind;
use tribosweep_core::model::{ContactModel, FrictionLaw, Params};

/// An axis as Python passes it: `(name, reference, [(field, base, exponent), ...])`; no terms means
/// "set the field `name`", terms mean `field = base (value / reference)^exponent` each.
type AxisSpec = (String, f64, Vec<(String, f64, f64)>);

fn value_error(e: impl ToString) -> PyErr {
    crate::errors::CoreError(e.to_string()).into()
}

fn axis_from(spec: AxisSpec) -> PyResult<Axis> {
    let (name, reference, terms) = spec;
    let axis = if terms.is_empty() {
        Axis::field(&name)
    } else {
        let terms = terms
            .into_iter()
            .map(|(field, base, exponent)| Term::PowerLaw { field, base, reference, exponent })
            .collect();
        Axis { name, terms }
    };
    axis.check().map_err(value_error)?;
    Ok(axis)
}

fn family_from(
    values: &HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    axes: Vec<AxisSpec>,
) -> PyResult<SliderFamily> {
    let mut p = Params::seed();
    for (k, v) in values {
        p.set(k, *v).map_err(value_error)?;
    }
    p.contact = match contact {
        "bilateral" => ContactModel::Bilateral,
        "unilateral" => ContactModel::Unilateral,
        _ => {
            return Err(value_error(format!("contact = {contact:?} is not valid: must be 'bilateral' or 'unilateral'")))
        }
    };
    p.friction_law = match friction_law {
        "constant" => FrictionLaw::Constant,
        "coulomb" => FrictionLaw::Coulomb,
        "switch" => FrictionLaw::Switch,
        _ => {
            return Err(value_error(format!(
                "friction_law = {friction_law:?} is not valid: must be 'constant', 'coulomb' or 'switch'"
            )))
        }
    };
    p.validate().map_err(value_error)?;
    Ok(SliderFamily { base: p, axes: axes.into_iter().map(axis_from).collect::<PyResult<_>>()? })
}

fn complex(c: C64) -> Complex64 {
    Complex64::new(c.re, c.im)
}

fn counters_into(d: &Bound<'_, PyDict>, c: &Counters) -> PyResult<()> {
    d.set_item("n_eig", c.n_eig)?;
    d.set_item("n_jac", c.n_jac)
}

/// Flag names of the Hopf outputs, in code order.
#[pyfunction]
fn hopf_flag_names(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("criticality", Criticality::ALL.iter().map(|c| c.name()).collect::<Vec<_>>())?;
    d.set_item("point_type", PointType::ALL.iter().map(|c| c.name()).collect::<Vec<_>>())?;
    d.set_item("end_status", EndStatus::ALL.iter().map(|c| c.name()).collect::<Vec<_>>())?;
    d.set_item("mode", ModeKind::ALL.iter().map(|c| c.name()).collect::<Vec<_>>())?;
    Ok(d)
}

/// Steady sliding along one axis over `[lo, hi]`: the tracked eigenvalues at every sample and every
/// crossing of the imaginary axis with its normal form.
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, axis, lo, hi, *, n_points=201, xtol=1e-13))]
#[allow(clippy::too_many_arguments)]
fn sliding_branch<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    axis: AxisSpec,
    lo: f64,
    hi: f64,
    n_points: usize,
    xtol: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let fam = family_from(&values, contact, friction_law, vec![axis])?;
    let opts = ScanOptions { n_points, xtol, ..ScanOptions::default() };
    let sc = crate::interrupt::detach(py, || scan(&fam, lo, hi, &opts))?.map_err(value_error)?;
    let d = PyDict::new(py);
    let n = sc.samples.len();
    let m = sc.samples.iter().map(|s| s.eigenvalues.len()).max().unwrap_or(0);
    let mut ev = Array2::<Complex64>::from_elem((n, m), Complex64::new(f64::NAN, f64::NAN));
    let mut lab = Array2::<u8>::from_elem((n, m), u8::MAX);
    for (i, s) in sc.samples.iter().enumerate() {
        for (k, e) in s.eigenvalues.iter().enumerate() {
            ev[(i, k)] = complex(*e);
            lab[(i, k)] = s.labels[k];
        }
    }
    d.set_item("value", Array1::from_iter(sc.samples.iter().map(|s| s.value)).into_pyarray(py))?;
    d.set_item("eigenvalues", ev.into_pyarray(py))?;
    d.set_item("labels", lab.into_pyarray(py))?;
    let c = &sc.crossings;
    let col = |f: &dyn Fn(&tribosweep_core::hopf::scan::Crossing<6>) -> f64| Array1::from_iter(c.iter().map(f));
    d.set_item("hopf_value", col(&|x| x.value).into_pyarray(py))?;
    d.set_item("hopf_branch", Array1::from_iter(c.iter().map(|x| x.branch as i64)).into_pyarray(py))?;
    d.set_item("hopf_lambda", Array1::from_iter(c.iter().map(|x| complex(x.lambda))).into_pyarray(py))?;
    d.set_item("hopf_dlambda", Array1::from_iter(c.iter().map(|x| complex(x.dlambda))).into_pyarray(py))?;
    d.set_item("hopf_is_pair", Array1::from_iter(c.iter().map(|x| x.hopf)).into_pyarray(py))?;
    d.set_item("l1", col(&|x| x.normal_form.map_or(f64::NAN, |n| n.l1)).into_pyarray(py))?;
    d.set_item("l1_scale", col(&|x| x.normal_form.map_or(f64::NAN, |n| n.l1_scale)).into_pyarray(py))?;
    let c1 = Array1::from_iter(c.iter().map(|x| complex(x.normal_form.map_or(C64::new(f64::NAN, f64::NAN), |n| n.c1))));
    d.set_item("c1", c1.into_pyarray(py))?;
    d.set_item("criticality", Array1::from_iter(c.iter().map(|x| x.criticality as u8)).into_pyarray(py))?;
    d.set_item("mode", Array1::from_iter(c.iter().map(|x| x.mode)).into_pyarray(py))?;
    d.set_item("other_unstable", Array1::from_iter(c.iter().map(|x| x.other_unstable as i64)).into_pyarray(py))?;
    d.set_item("bracket", col(&|x| x.bracket).into_pyarray(py))?;
    d.set_item("status", Array1::from_iter(c.iter().map(|x| x.status.code())).into_pyarray(py))?;
    d.set_item("reason", c.iter().map(|x| x.reason.clone()).collect::<Vec<_>>())?;
    let nan = Complex64::new(f64::NAN, f64::NAN);
    let (mut q, mut h20, mut h11) = (
        Array2::from_elem((c.len(), 6), nan),
        Array2::from_elem((c.len(), 6), nan),
        Array2::from_elem((c.len(), 6), nan),
    );
    for (i, x) in c.iter().enumerate() {
        if let Some(nf) = x.normal_form {
            for k in 0..6 {
                q[(i, k)] = complex(nf.pair.q[k]);
                h20[(i, k)] = complex(nf.h20[k]);
                h11[(i, k)] = complex(nf.h11[k]);
            }
        }
    }
    d.set_item("eigenvector", q.into_pyarray(py))?;
    d.set_item("h20", h20.into_pyarray(py))?;
    d.set_item("h11", h11.into_pyarray(py))?;
    counters_into(&d, &sc.counters)?;
    Ok(d)
}

/// Every Hopf curve in the box `[x_lo, x_hi] x [y_lo, y_hi]` (struct of arrays over all points,
/// with the curve index, and per-curve end statuses and reasons).
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, x_axis, y_axis, x_range, y_range, *, grid=(16, 16), step=0.01, step_min=1e-7, step_max=0.05, tol=1e-10, max_points=5000, max_angle=0.1, chord_tol=1e-5, x_marks=vec![], y_marks=vec![]))]
#[allow(clippy::too_many_arguments)]
fn hopf_curve<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    x_axis: AxisSpec,
    y_axis: AxisSpec,
    x_range: (f64, f64),
    y_range: (f64, f64),
    grid: (usize, usize),
    step: f64,
    step_min: f64,
    step_max: f64,
    tol: f64,
    max_points: usize,
    max_angle: f64,
    chord_tol: f64,
    x_marks: Vec<f64>,
    y_marks: Vec<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let fam = family_from(&values, contact, friction_law, vec![x_axis, y_axis])?;
    let opts = CurveOptions {
        grid: [grid.0, grid.1],
        step,
        step_min,
        step_max,
        tol,
        max_points,
        max_angle,
        chord_tol,
        marks: [x_marks, y_marks],
    };
    let bx = [[x_range.0, x_range.1], [y_range.0, y_range.1]];
    let res = crate::interrupt::detach(py, || hopf_curves(&fam, bx, &opts))?.map_err(value_error)?;
    let pts: Vec<(usize, &tribosweep_core::hopf::curve::CurvePoint)> =
        res.curves.iter().enumerate().flat_map(|(i, c)| c.points.iter().map(move |p| (i, p))).collect();
    let d = PyDict::new(py);
    let f =
        |g: &dyn Fn(&tribosweep_core::hopf::curve::CurvePoint) -> f64| Array1::from_iter(pts.iter().map(|(_, p)| g(p)));
    d.set_item("curve", Array1::from_iter(pts.iter().map(|(i, _)| *i as i64)).into_pyarray(py))?;
    d.set_item("x", f(&|p| p.u[0]).into_pyarray(py))?;
    d.set_item("y", f(&|p| p.u[1]).into_pyarray(py))?;
    d.set_item("frequency", f(&|p| p.lambda.im).into_pyarray(py))?;
    d.set_item("growth_rate", f(&|p| p.lambda.re).into_pyarray(py))?;
    d.set_item("l1", f(&|p| p.l1).into_pyarray(py))?;
    d.set_item("criticality", Array1::from_iter(pts.iter().map(|(_, p)| p.criticality as u8)).into_pyarray(py))?;
    d.set_item("point_type", Array1::from_iter(pts.iter().map(|(_, p)| p.kind as u8)).into_pyarray(py))?;
    d.set_item("mode", Array1::from_iter(pts.iter().map(|(_, p)| p.mode)).into_pyarray(py))?;
    d.set_item("other_unstable", Array1::from_iter(pts.iter().map(|(_, p)| p.other_unstable as i64)).into_pyarray(py))?;
    d.set_item("status", Array1::from_iter(pts.iter().map(|(_, p)| p.status.code())).into_pyarray(py))?;
    let ends = |k: usize| Array1::from_iter(res.curves.iter().map(|c| c.ends[k].0 as u8));
    d.set_item("start_status", ends(0).into_pyarray(py))?;
    d.set_item("end_status", ends(1).into_pyarray(py))?;
    d.set_item("start_reason", res.curves.iter().map(|c| c.ends[0].1.clone()).collect::<Vec<_>>())?;
    d.set_item("end_reason", res.curves.iter().map(|c| c.ends[1].1.clone()).collect::<Vec<_>>())?;
    d.set_item("n_points", Array1::from_iter(res.curves.iter().map(|c| c.points.len() as i64)).into_pyarray(py))?;
    d.set_item("n_seeds", res.n_seeds)?;
    counters_into(&d, &res.counters)?;
    Ok(d)
}

/// Add the Hopf functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(hopf_flag_names, m)?)?;
    m.add_function(wrap_pyfunction!(sliding_branch, m)?)?;
    m.add_function(wrap_pyfunction!(hopf_curve, m)?)?;
    Ok(())
}
