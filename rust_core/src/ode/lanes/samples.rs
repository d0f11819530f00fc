//! Samples at output times on the lanes: each trajectory's row of the flat output buffer, and
//! the samples of all lanes of a step at once.

use super::{lane_state, LaneDense, Lw, Vw};
use crate::ode::SampleStore;
use nalgebra::SVector;

/// A trajectory's row of a flat buffer of samples (6 values per time), filled in order from the
/// start; `n` counts the samples written.
pub(crate) struct Row<'a> {
    pub(crate) vals: &'a mut [f64],
    pub(crate) n: usize,
}

impl Row<'_> {
    /// NaN at the times not sampled (a run that stopped early).
    pub(crate) fn finish(self) {
        self.vals[6 * self.n..].fill(f64::NAN);
    }
}

/// The rows of a flat buffer of samples (`stride` values per trajectory), each handed out once
/// by trajectory index to whichever worker runs it (the lanes take trajectories in the order
/// they free up). The rows are disjoint and each is taken at most once (checked), so the
/// mutable rows never alias.
pub(crate) struct Rows<'a> {
    ptr: *mut f64,
    stride: usize,
    taken: Vec<std::sync::atomic::AtomicBool>,
    _buf: std::marker::PhantomData<&'a mut [f64]>,
}

// SAFETY: the rows handed out are disjoint parts of a buffer borrowed mutably for `'a`, each at
// most once (the atomic flags), so sharing the source between threads creates no aliasing.
unsafe impl Sync for Rows<'_> {}
unsafe impl Send for Rows<'_> {}

impl<'a> Rows<'a> {
    pub(crate) fn new(buf: &'a mut [f64], stride: usize) -> Self {
        let n = buf.len().checked_div(stride).unwrap_or(0);
        assert_eq!(n * stride, buf.len(), "a whole number of rows");
        Rows {
            ptr: buf.as_mut_ptr(),
            stride,
            taken: (0..n).map(|_| std::sync::atomic::AtomicBool::new(false)).collect(),
            _buf: std::marker::PhantomData,
        }
    }

    /// Trajectory `i`'s row (panics if taken before or out of range).
    pub(crate) fn take(&self, i: usize) -> Row<'a> {
        let was = self.taken[i].swap(true, std::sync::atomic::Ordering::Relaxed);
        assert!(!was, "the row of trajectory {i} is taken twice");
        // SAFETY: in bounds (`taken` has one flag per row), disjoint from every other row, and
        // never handed out before (the flag): no other reference to these values exists.
        let vals = unsafe { std::slice::from_raw_parts_mut(self.ptr.add(i * self.stride), self.stride) };
        Row { vals, n: 0 }
    }
}

impl SampleStore<6> for Row<'_> {
    #[inline]
    fn len(&self) -> usize {
        self.n
    }
    #[inline]
    fn push(&mut self, v: SVector<f64, 6>) {
        let k = 6 * self.n;
        self.vals[k..k + 6].copy_from_slice(v.as_slice());
        self.n += 1;
    }
}

/// The samples of every lane of `due` inside its accepted step (`t0`, `t1`, `h`: lane rows) from
/// `y0` to `y1`, by the scalar `Sampler`'s rule: a time at or before the start takes the start,
/// the end's time the end, any other the step's interpolant `dense`. Round by round: each lane's
/// next sample time is `next[l]`; the interpolant is evaluated for all lanes together, each at
/// its own `x = (t - t0) / h` (lane by lane the scalar formula's operations: the same bits).
/// `push(l, v)` appends lane `l`'s sample and returns the time of its next one (infinity: none),
/// left in `next[l]`.
///
/// One scalar evaluation per lane and sample cost a seventh of a 501-sample DOP853 run.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample_lanes<const N: usize>(
    due: &[bool; N],
    next: &mut Lw<N>,
    (t0, t1, h): (&Lw<N>, &Lw<N>, &Lw<N>),
    dense: &LaneDense<6, N>,
    y0: &Vw<N>,
    y1: &Vw<N>,
    mut push: impl FnMut(usize, SVector<f64, 6>) -> f64,
) {
    let mut act: [bool; N] = std::array::from_fn(|l| due[l] & (next[l] <= t1[l]));
    while act.iter().any(|&a| a) {
        let x: Lw<N> = std::array::from_fn(|l| (next[l] - t0[l]) / h[l]);
        let v = dense.eval_at(&x);
        for l in 0..N {
            if !act[l] {
                continue;
            }
            let t = next[l];
            let s = if t <= t0[l] {
                lane_state(y0, l)
            } else if t == t1[l] {
                lane_state(y1, l)
            } else {
                lane_state(&v, l)
            };
            next[l] = push(l, s);
            act[l] = next[l] <= t1[l];
        }
    }
}
