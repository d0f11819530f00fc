//! `tribosweep._core`: the thin PyO3 layer over `tribosweep-core`.
//!
//! It only converts arguments and results (`convert`), maps errors into one exception hierarchy
//! (`errors`), and releases the GIL around the numerics, which Ctrl-C stops (`interrupt`); every policy (which integrator path, how
//! trajectories are grouped) is the core's. The public Python API (argument checking with clear
//! messages, xarray Datasets) lives in `python/tribosweep/`; this module is private.
//!
//! One file per API group, each with a `register` that adds its functions to the module.

mod convert;
mod describing;
mod errors;
mod interrupt;
mod linear;
mod names;
mod orbits;
mod simulate;

mod hopf;

mod branch;

use pyo3::prelude::*;

/// The compiled core of tribosweep (private: use the `tribosweep` package). Its only state is the
/// exception classes (created once behind pyo3's `PyOnceLock`) and the core's thread pools (behind
/// a mutex): it declares itself safe without the GIL (free-threaded Python).
#[pymodule(gil_used = false)]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    interrupt::register(m)?;
    names::register(m)?;
    simulate::register(m)?;
    linear::register(m)?;
    describing::register(m)?;
    orbits::register(m)?;
    hopf::register(m)?;
    branch::register(m)?;
    Ok(())
}
