//! How a periodic orbit is unstable, from its Floquet multipliers: the kind of the largest
//! non-trivial one (fold, flip, torus) and the most negative real one (near a period doubling).

use super::C64;

/// The trivial multiplier of an orbit: the index of the one nearest 1 (exactly 1 on the orbit, the
/// flow's direction).
pub(crate) fn trivial_index(ev: &[C64; 6]) -> usize {
    (0..6).min_by(|&a, &b| (ev[a] - 1.0).norm().total_cmp(&(ev[b] - 1.0).norm())).unwrap_or(0)
}

/// How a periodic orbit is unstable: the kind of its largest non-trivial Floquet multiplier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Instability {
    /// Every non-trivial multiplier inside the unit circle.
    Stable,
    /// A real multiplier above 1 (a saddle cycle; it meets a stable cycle at a fold).
    Fold,
    /// A real multiplier below -1 (past a period doubling).
    Flip,
    /// A complex pair outside the unit circle (past a Neimark-Sacker bifurcation: a torus).
    Torus,
    /// Multipliers not computed.
    Unknown,
}

impl Instability {
    /// Code in the order of `INSTABILITY_NAMES`.
    pub fn code(self) -> u8 {
        self as u8
    }
}

/// Names of `Instability`, in code order.
pub const INSTABILITY_NAMES: [&str; 5] = ["stable", "fold", "flip", "torus", "unknown"];

/// A multiplier counts as real when its imaginary part is below this times `max(1, |rho|)`.
const REAL_TOL: f64 = 1e-8;

/// `(instability, flip_multiplier)` of sorted multipliers `ev` (modulus descending) with the
/// trivial one at `trivial`.
pub(super) fn classify(ev: &[C64; 6], trivial: usize, stable: bool) -> (Instability, f64) {
    let is_real = |c: &C64| c.im.abs() <= REAL_TOL * c.norm().max(1.0);
    let flip = (0..6)
        .filter(|&k| k != trivial && is_real(&ev[k]) && ev[k].re < 0.0)
        .map(|k| ev[k].re)
        .fold(f64::NAN, f64::min);
    let kind = if stable {
        Instability::Stable
    } else {
        match (0..6).find(|&k| k != trivial) {
            Some(k) if is_real(&ev[k]) && ev[k].re > 0.0 => Instability::Fold,
            Some(k) if is_real(&ev[k]) => Instability::Flip,
            Some(_) => Instability::Torus,
            None => Instability::Unknown,
        }
    };
    (kind, flip)
}
