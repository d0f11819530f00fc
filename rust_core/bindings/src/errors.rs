//! The one Python exception hierarchy of `tribosweep._core`, and the local wrapper through which
//! every Rust error reaches it.
//!
//! ```text
//! Exception
//! └── TribosweepError                 every error tribosweep raises on purpose
//!     └── InvalidArgumentError        bad input, before any work; also a ValueError
//! ```
//!
//! A point that fails numerically is never an exception: it is a status code and a reason in the
//! results. So the only error the core reports is bad input (a parameter out of range, an unknown
//! name, an array of the wrong shape); its message names the argument, its value and the valid
//! range. `InvalidArgumentError` derives from `ValueError` too, so `except ValueError` keeps
//! catching it.

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

pyo3::create_exception!(
    tribosweep._core,
    TribosweepError,
    PyException,
    "Base class of every error tribosweep raises on purpose."
);

/// Docstring of `InvalidArgumentError`.
const INVALID_ARGUMENT_DOC: &str =
    "An argument is out of its valid range or of the wrong shape; the message names it, its value and the valid range.";

/// `InvalidArgumentError(TribosweepError, ValueError)`: two bases, which `create_exception!` does
/// not offer, so the class is made by calling `type` once and kept for the interpreter's life.
fn invalid_argument_type(py: Python<'_>) -> PyResult<Bound<'_, PyType>> {
    static TYPE: PyOnceLock<Py<PyType>> = PyOnceLock::new();
    let t = TYPE.get_or_try_init(py, || -> PyResult<Py<PyType>> {
        let bases = PyTuple::new(py, [py.get_type::<TribosweepError>(), py.get_type::<PyValueError>()])?;
        let namespace = PyDict::new(py);
        namespace.set_item("__module__", "tribosweep._core")?;
        namespace.set_item("__doc__", INVALID_ARGUMENT_DOC)?;
        let class = py.get_type::<PyType>().call1(("InvalidArgumentError", bases, namespace))?;
        Ok(class.cast_into::<PyType>()?.unbind())
    })?;
    Ok(t.bind(py).clone())
}

/// A Rust-side error on its way to Python: bad input, raised as `InvalidArgumentError` with this
/// message.
#[derive(Debug)]
pub(crate) struct CoreError(pub(crate) String);

impl From<CoreError> for PyErr {
    fn from(e: CoreError) -> PyErr {
        // Conversions run in the pyfunctions, attached to the interpreter; attaching again is free.
        Python::attach(|py| match invalid_argument_type(py) {
            Ok(t) => PyErr::from_type(t, e.0),
            Err(err) => err,
        })
    }
}

impl From<tribosweep_core::ParamError> for CoreError {
    fn from(e: tribosweep_core::ParamError) -> Self {
        CoreError(e.to_string())
    }
}

/// Add the exception classes to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("TribosweepError", py.get_type::<TribosweepError>())?;
    m.add("InvalidArgumentError", invalid_argument_type(py)?)?;
    Ok(())
}
