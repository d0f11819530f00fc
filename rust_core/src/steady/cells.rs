//! A coarse occupancy grid of an irregular attractor's Poincare section: the cells of state space
//! its section states visit, for the recurrence stop of other runs of the same model.
//!
//! The recurrence method of Datseris & Wagemakers (Chaos 32, 2022, Attractors.jl) labels a
//! trajectory by the attractor whose cells it keeps visiting. Here the cells are those of a run
//! that has already been shown irregular by the stationarity test (three blocks of sections): a
//! run whose section states then fall in its cells [`RECUR_SECTIONS`] times in a row, with a
//! repetition residual of the same order as the attractor's, is on that attractor.
//!
//! The grid spans the section states' bounding box in `(z, phi, phid)` ([`CELL_COMPS`]; `zd` is 0
//! on the section, and `x, xd` are slaved under constant friction), widened by one cell on every
//! side, in [`CELLS`] cells per component. Each visited cell and its 26 neighbours are marked, so
//! that a state within about one cell (4-8 % of the attractor's extent) of a visited one counts:
//! 768 section states leave gaps in the attractor's cells that a later visit may fall into.

use crate::model::{idx, State};

/// Cells per component of the grid.
pub const CELLS: usize = 24;
/// Words of the grid's bit set (one bit per cell).
pub const CELL_WORDS: usize = (CELLS * CELLS * CELLS).div_ceil(64);
/// The section-state components the grid spans.
pub const CELL_COMPS: [usize; 3] = [idx::Z, idx::PHI, idx::PHID];
/// Consecutive sections in a known attractor's cells that put a run on it.
pub const RECUR_SECTIONS: usize = 32;

/// The cells of state space an irregular attractor's section states visit (see the module
/// documentation). `lo`/`hi`: the grid's extent in each of [`CELL_COMPS`] (NaN: an empty grid).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cells {
    /// Lower corner of the grid.
    pub lo: [f64; 3],
    /// Upper corner of the grid.
    pub hi: [f64; 3],
    /// One bit per cell, `i + CELLS (j + CELLS k)` for cell `(i, j, k)`.
    pub bits: [u64; CELL_WORDS],
}

impl Cells {
    /// No cells: nothing is inside.
    pub const EMPTY: Cells = Cells { lo: [f64::NAN; 3], hi: [f64::NAN; 3], bits: [0; CELL_WORDS] };

    /// Whether no cell is marked.
    pub fn is_empty(&self) -> bool {
        self.bits.iter().all(|&w| w == 0)
    }

    /// The grid of `points` (each the [`CELL_COMPS`] of a section state): their bounding box
    /// widened by one cell, every point's cell and its neighbours marked. Empty where there are no
    /// points, a value is not finite, or a component does not move.
    pub fn from_points(points: &[[f64; 3]]) -> Cells {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        let mut g = Cells::EMPTY;
        for c in 0..3 {
            let w = (hi[c] - lo[c]) / (CELLS - 2) as f64;
            if !(w.is_finite() && w > 0.0 && lo[c] - w < lo[c]) {
                return Cells::EMPTY;
            }
            (g.lo[c], g.hi[c]) = (lo[c] - w, hi[c] + w);
        }
        for p in points {
            let Some([i, j, k]) = g.cell(p) else { continue };
            for dk in k.saturating_sub(1)..=(k + 1).min(CELLS - 1) {
                for dj in j.saturating_sub(1)..=(j + 1).min(CELLS - 1) {
                    for di in i.saturating_sub(1)..=(i + 1).min(CELLS - 1) {
                        let n = di + CELLS * (dj + CELLS * dk);
                        g.bits[n / 64] |= 1 << (n % 64);
                    }
                }
            }
        }
        g
    }

    /// The cell of `p` (the [`CELL_COMPS`] of a state), `None` outside the grid.
    fn cell(&self, p: &[f64; 3]) -> Option<[usize; 3]> {
        let mut out = [0; 3];
        for c in 0..3 {
            let u = (p[c] - self.lo[c]) / (self.hi[c] - self.lo[c]) * CELLS as f64;
            // NaN (an empty grid, a NaN state) fails both comparisons.
            if !(u >= 0.0 && u < CELLS as f64) {
                return None;
            }
            out[c] = u as usize;
        }
        Some(out)
    }

    /// The [`CELL_COMPS`] of a section state.
    pub fn point(y: &State) -> [f64; 3] {
        CELL_COMPS.map(|c| y[c])
    }

    /// Whether the section state `y` is in a marked cell.
    pub fn contains(&self, y: &State) -> bool {
        self.cell(&Self::point(y)).is_some_and(|[i, j, k]| {
            let n = i + CELLS * (j + CELLS * k);
            self.bits[n / 64] >> (n % 64) & 1 == 1
        })
    }
}
