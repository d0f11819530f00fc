//! (in progress) The integration driver: step-size control, dense output, event location.
use super::{Method, Observer, OdeSystem, Options, Solution};
use nalgebra::SVector;

/// Integrate `sys` from `(t0, y0)` to `t_end` (> t0) with `method`, starting in `sys.initial_mode(t0, y0)`.
pub fn integrate<const N: usize, S: OdeSystem<N>, O: Observer<N, S::Mode>>(
    sys: &S,
    method: Method,
    t0: f64,
    y0: SVector<f64, N>,
    t_end: f64,
    opts: &Options<N>,
    observer: &mut O,
) -> Solution<N, S::Mode> {
    let _ = (sys, method, t0, y0, t_end, opts, observer);
    unimplemented!("driver in progress")
}
