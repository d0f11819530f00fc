//! Bindings of `tribosweep_core::branch`: one-parameter branches of periodic orbits and
//! two-parameter curves of folds and grazing. Converts, maps errors to `ValueError`, releases the
//! GIL; the Python side (`tribosweep._branch`) checks arguments and builds the Datasets.

use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use tribosweep_core::branch::{
    self as core, BranchOptions, BranchPoint, CurveKind, PointType, Start, FLAG_NAMES, POINT_TYPE_NAMES,
};
use tribosweep_core::model::{ContactModel, FrictionLaw, Params, State};

fn err(e: impl std::fmt::Display) -> PyErr {
    crate::errors::CoreError(e.to_string()).into()
}

/// Validated parameters from a name -> value map and the two categorical settings.
fn params(values: &HashMap<String, f64>, contact: &str, friction_law: &str) -> PyResult<Params> {
    let mut p = Params::seed();
    for (k, v) in values {
        p.set(k, *v).map_err(err)?;
    }
    p.contact = match contact {
        "bilateral" => ContactModel::Bilateral,
        "unilateral" => ContactModel::Unilateral,
        _ => return Err(err(format!("contact = {contact:?} is not valid: must be 'bilateral' or 'unilateral'"))),
    };
    p.friction_law = match friction_law {
        "constant" => FrictionLaw::Constant,
        "coulomb" => FrictionLaw::Coulomb,
        "switch" => FrictionLaw::Switch,
        _ => return Err(err(format!("friction_law = {friction_law:?} is not valid"))),
    };
    p.validate().map_err(err)?;
    Ok(p)
}

fn start(
    y0: Option<PyReadonlyArray1<'_, f64>>,
    period: Option<f64>,
    direction: f64,
    hopf_omega: Option<f64>,
) -> PyResult<Start> {
    match (y0, period, hopf_omega) {
        (Some(y), Some(t), None) => {
            let y = y.as_slice()?;
            if y.len() != 6 {
                return Err(err(format!("y0 has {} entries: must be 6", y.len())));
            }
            Ok(Start::Orbit { state0: State::from_column_slice(y), period: t, direction })
        }
        (None, None, Some(omega)) => Ok(Start::Hopf { omega }),
        _ => Err(err("give either y0 and period, or hopf_omega")),
    }
}

fn point_type_from(name: Option<&str>) -> PyResult<Option<PointType>> {
    const ALL: [PointType; 9] = [
        PointType::Regular,
        PointType::Fold,
        PointType::PeriodDoubling,
        PointType::NeimarkSacker,
        PointType::Grazing,
        PointType::Hopf,
        PointType::End,
        PointType::BranchPoint,
        PointType::Stick,
    ];
    match name {
        None => Ok(None),
        Some(n) => ALL
            .into_iter()
            .find(|k| POINT_TYPE_NAMES[*k as usize] == n)
            .map(Some)
            .ok_or_else(|| err(format!("stop_at = {n:?} is not valid: must be one of {POINT_TYPE_NAMES:?}"))),
    }
}

/// The continuation options from a name -> value map (missing names keep their defaults).
fn options(o: &HashMap<String, f64>, stop_at: Option<&str>) -> PyResult<BranchOptions> {
    let mut b = BranchOptions::default();
    for (k, &v) in o {
        let as_int = |name: &str| -> PyResult<u64> {
            if v.fract() == 0.0 && (0.0..1e15).contains(&v) {
                Ok(v as u64)
            } else {
                Err(err(format!("{name} = {v} is not valid: must be a non-negative integer")))
            }
        };
        match k.as_str() {
            "rtol" => b.rtol = v,
            "tol" => b.tol = v,
            "max_newton" => b.max_newton = as_int(k)? as u32,
            "ds" => b.ds = v,
            "ds_min" => b.ds_min = v,
            "ds_max" => b.ds_max = v,
            "max_points" => b.max_points = as_int(k)? as usize,
            "locate_tol" => b.locate_tol = v,
            "stability_tol" => b.stability_tol = v,
            "n_samples" => b.n_samples = as_int(k)? as usize,
            "max_switches" => b.max_switches = as_int(k)? as u32,
            "hopf_amplitude" => b.hopf_amplitude = v,
            "max_turn" => b.max_turn = v,
            "max_period_ratio" => b.max_period_ratio = v,
            _ => return Err(err(format!("unknown continuation option {k:?}"))),
        }
    }
    b.stop_at = point_type_from(stop_at)?;
    b.validate().map_err(err)?;
    Ok(b)
}

/// Struct-of-arrays of branch points into `d`.
fn points_into(d: &Bound<'_, PyDict>, pts: &[BranchPoint]) -> PyResult<()> {
    let py = d.py();
    let n = pts.len();
    let f = |g: fn(&BranchPoint) -> f64| Array1::from_iter(pts.iter().map(g)).into_pyarray(py);
    let u = |g: fn(&BranchPoint) -> u8| Array1::from_iter(pts.iter().map(g)).into_pyarray(py);
    d.set_item("parameter", f(|p| p.parameter))?;
    d.set_item("period", f(|p| p.period))?;
    d.set_item("trivial_error", f(|p| p.trivial_error))?;
    d.set_item("a0", f(|p| p.a0))?;
    d.set_item("a1", f(|p| p.a1))?;
    d.set_item("z_max", f(|p| p.z_max))?;
    d.set_item("z_min", f(|p| p.z_min))?;
    d.set_item("min_gap", f(|p| p.min_gap))?;
    d.set_item("min_law_force", f(|p| p.min_law_force))?;
    d.set_item("min_slip_velocity", f(|p| p.min_slip_velocity))?;
    d.set_item("fraction_off_disk", f(|p| p.open_fraction))?;
    d.set_item("dp_ds", f(|p| p.dp_ds))?;
    d.set_item("arclength", f(|p| p.arclength))?;
    d.set_item("residual", f(|p| p.residual))?;
    d.set_item("stable", Array1::from_iter(pts.iter().map(|p| p.stable)).into_pyarray(py))?;
    d.set_item("n_unstable", u(|p| p.n_unstable))?;
    d.set_item("point_type", u(|p| p.point_type as u8))?;
    d.set_item("contact", u(|p| p.contact as u8))?;
    d.set_item("flags", u(|p| p.flags))?;
    d.set_item("trivial", u(|p| p.trivial as u8))?;
    d.set_item("n_switches", Array1::from_iter(pts.iter().map(|p| p.n_switches)).into_pyarray(py))?;
    d.set_item("newton_iterations", Array1::from_iter(pts.iter().map(|p| p.newton_iterations)).into_pyarray(py))?;
    let (mut y, mut re, mut im) =
        (Array2::<f64>::zeros((n, 6)), Array2::<f64>::zeros((n, 6)), Array2::<f64>::zeros((n, 6)));
    for (i, p) in pts.iter().enumerate() {
        for c in 0..6 {
            y[(i, c)] = p.state0[c];
            re[(i, c)] = p.multipliers[c].re;
            im[(i, c)] = p.multipliers[c].im;
        }
    }
    d.set_item("state0", y.into_pyarray(py))?;
    d.set_item("multipliers_re", re.into_pyarray(py))?;
    d.set_item("multipliers_im", im.into_pyarray(py))?;
    Ok(())
}

/// A branch of periodic orbits of the model in `parameter`, from `value` (an orbit `y0, period`
/// or a Hopf point with frequency `hopf_omega`) within `[lo, hi]`. Dict of arrays over points
/// plus `status`, `reason`, `n_flows`, `n_rhs`, `p_ref`, `t_ref`.
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, parameter, value, lo, hi, *, y0=None, period=None, direction=1.0, hopf_omega=None, options=HashMap::new(), stop_at=None))]
#[allow(clippy::too_many_arguments)]
fn branch<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    parameter: &str,
    value: f64,
    lo: f64,
    hi: f64,
    y0: Option<PyReadonlyArray1<'py, f64>>,
    period: Option<f64>,
    direction: f64,
    hopf_omega: Option<f64>,
    options: HashMap<String, f64>,
    stop_at: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = params(&values, contact, friction_law)?;
    let st = start(y0, period, direction, hopf_omega)?;
    let o = self::options(&options, stop_at)?;
    let name = parameter.to_string();
    let b = crate::interrupt::detach(py, || core::branch(&p, &name, value, st, (lo, hi), &o))?.map_err(err)?;
    let d = PyDict::new(py);
    points_into(&d, &b.points)?;
    d.set_item("status", b.status.code())?;
    d.set_item("reason", b.reason)?;
    d.set_item("n_flows", b.n_flows)?;
    d.set_item("n_rhs", b.stats.n_rhs)?;
    d.set_item("p_ref", b.p_ref)?;
    d.set_item("t_ref", b.t_ref)?;
    d.set_item("static_scales", b.static_scales)?;
    Ok(d)
}

/// A two-parameter curve of folds (`kind = "fold"`, smooth or where a grazing turns the branch),
/// of grazing points (`"grazing"`) or of the switch law's stick points (`"stick"`), slice by slice over the values `ys` of `y` (see
/// `tribosweep_core::branch::curve`). Dict of arrays over curve points (`y` and the located
/// branch points, `parameter` being `x`) plus `status`, `reason`, `n_flows`, `n_rhs`.
#[pyfunction]
#[pyo3(signature = (values, contact, friction_law, kind, x, x_value, x_lo, x_hi, y, ys, *, y0=None, period=None, direction=1.0, hopf_omega=None, options=HashMap::new()))]
#[allow(clippy::too_many_arguments)]
fn special_curve<'py>(
    py: Python<'py>,
    values: HashMap<String, f64>,
    contact: &str,
    friction_law: &str,
    kind: &str,
    x: &str,
    x_value: f64,
    x_lo: f64,
    x_hi: f64,
    y: &str,
    ys: PyReadonlyArray1<'py, f64>,
    y0: Option<PyReadonlyArray1<'py, f64>>,
    period: Option<f64>,
    direction: f64,
    hopf_omega: Option<f64>,
    options: HashMap<String, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = params(&values, contact, friction_law)?;
    let st = start(y0, period, direction, hopf_omega)?;
    let o = self::options(&options, None)?;
    let kind = match kind {
        "fold" => CurveKind::Fold,
        "grazing" => CurveKind::Grazing,
        "stick" => CurveKind::Stick,
        _ => return Err(err(format!("kind = {kind:?} is not valid: must be 'fold', 'grazing' or 'stick'"))),
    };
    let ys = ys.as_slice()?.to_vec();
    let (xn, yn) = (x.to_string(), y.to_string());
    let c =
        crate::interrupt::detach(py, || core::special_curve(&p, kind, &xn, x_value, (x_lo, x_hi), st, &yn, &ys, &o))?
            .map_err(err)?;
    let d = PyDict::new(py);
    let pts: Vec<BranchPoint> = c.points.iter().map(|q| q.point).collect();
    points_into(&d, &pts)?;
    d.set_item("y", Array1::from_iter(c.points.iter().map(|q| q.y)).into_pyarray(py))?;
    d.set_item("status", c.status.code())?;
    d.set_item("reason", c.reason)?;
    d.set_item("n_flows", c.n_flows)?;
    d.set_item("n_rhs", c.stats.n_rhs)?;
    Ok(d)
}

/// Names of the point types of a branch, in code order.
#[pyfunction]
fn branch_point_type_names() -> Vec<&'static str> {
    POINT_TYPE_NAMES.to_vec()
}

/// Names of the flag bits of a branch point, lowest first.
#[pyfunction]
fn branch_flag_names() -> Vec<&'static str> {
    FLAG_NAMES.to_vec()
}

/// The continuation defaults, by option name.
#[pyfunction]
fn branch_defaults() -> HashMap<&'static str, f64> {
    let o = BranchOptions::default();
    HashMap::from([
        ("rtol", o.rtol),
        ("tol", o.tol),
        ("max_newton", o.max_newton as f64),
        ("ds", o.ds),
        ("ds_min", o.ds_min),
        ("ds_max", o.ds_max),
        ("max_points", o.max_points as f64),
        ("locate_tol", o.locate_tol),
        ("stability_tol", o.stability_tol),
        ("n_samples", o.n_samples as f64),
        ("max_switches", o.max_switches as f64),
        ("hopf_amplitude", o.hopf_amplitude),
        ("max_turn", o.max_turn),
        ("max_period_ratio", o.max_period_ratio),
    ])
}

/// Add this module's functions to `_core`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(branch, m)?)?;
    m.add_function(wrap_pyfunction!(special_curve, m)?)?;
    m.add_function(wrap_pyfunction!(branch_point_type_names, m)?)?;
    m.add_function(wrap_pyfunction!(branch_flag_names, m)?)?;
    m.add_function(wrap_pyfunction!(branch_defaults, m)?)?;
    Ok(())
}
