//! Small systems with known solutions, shared by the integrator tests.

use crate::ode::{EventAction, OdeSystem, MAX_EVENTS};
use nalgebra::{SMatrix, SVector};

/// `x'' + 2 zeta w x' + w^2 x = 0`, `y = [x, x']`.
pub struct Damped {
    pub w: f64,
    pub zeta: f64,
}
impl Damped {
    /// Exact solution from `x(0) = 1, x'(0) = 0`.
    pub fn exact(&self, t: f64) -> SVector<f64, 2> {
        let a = self.zeta * self.w;
        let wd = self.w * (1.0 - self.zeta * self.zeta).sqrt();
        let b = a / wd;
        let (s, c) = (wd * t).sin_cos();
        let e = (-a * t).exp();
        SVector::<f64, 2>::new(e * (c + b * s), e * (-a * (c + b * s) + (-wd * s + b * wd * c)))
    }
}
impl OdeSystem<2> for Damped {
    type Mode = ();
    fn rhs(&self, _t: f64, y: &SVector<f64, 2>, _m: ()) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(y[1], -2.0 * self.zeta * self.w * y[1] - self.w * self.w * y[0])
    }
    fn jacobian(&self, _t: f64, _y: &SVector<f64, 2>, _m: ()) -> SMatrix<f64, 2, 2> {
        SMatrix::<f64, 2, 2>::new(0.0, 1.0, -self.w * self.w, -2.0 * self.zeta * self.w)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
}

/// Kepler problem, `y = [q1, q2, p1, p2]`, started at pericentre with eccentricity `e`
/// (period 2 pi). Smooth and nonlinear: the order-of-convergence problem.
pub struct Kepler;
impl Kepler {
    pub fn y0(e: f64) -> SVector<f64, 4> {
        SVector::<f64, 4>::new(1.0 - e, 0.0, 0.0, ((1.0 + e) / (1.0 - e)).sqrt())
    }
}
impl OdeSystem<4> for Kepler {
    type Mode = ();
    fn rhs(&self, _t: f64, y: &SVector<f64, 4>, _m: ()) -> SVector<f64, 4> {
        let r2 = y[0] * y[0] + y[1] * y[1];
        let r3 = r2 * r2.sqrt();
        SVector::<f64, 4>::new(y[2], y[3], -y[0] / r3, -y[1] / r3)
    }
    fn jacobian(&self, _t: f64, y: &SVector<f64, 4>, _m: ()) -> SMatrix<f64, 4, 4> {
        let r2 = y[0] * y[0] + y[1] * y[1];
        let r3 = r2 * r2.sqrt();
        let r5 = r3 * r2;
        let (a, b, c) = (3.0 * y[0] * y[0] / r5 - 1.0 / r3, 3.0 * y[0] * y[1] / r5, 3.0 * y[1] * y[1] / r5 - 1.0 / r3);
        SMatrix::<f64, 4, 4>::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, a, b, 0.0, 0.0, b, c, 0.0, 0.0)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 4>) {}
}

/// Forced Duffing oscillator `x'' + d x' + k1 x + k3 x^3 = g cos(w t)`: non-autonomous when
/// `g != 0`; analytic Jacobian.
pub struct Duffing {
    pub d: f64,
    pub k1: f64,
    pub k3: f64,
    pub g: f64,
    pub w: f64,
}
/// The classic double-well parameters.
pub const DUFFING: Duffing = Duffing { d: 0.2, k1: -1.0, k3: 1.0, g: 0.3, w: 1.2 };
impl OdeSystem<2> for Duffing {
    type Mode = ();
    fn rhs(&self, t: f64, y: &SVector<f64, 2>, _m: ()) -> SVector<f64, 2> {
        let x = y[0];
        SVector::<f64, 2>::new(y[1], -self.d * y[1] - self.k1 * x - self.k3 * x * x * x + self.g * (self.w * t).cos())
    }
    fn jacobian(&self, _t: f64, y: &SVector<f64, 2>, _m: ()) -> SMatrix<f64, 2, 2> {
        SMatrix::<f64, 2, 2>::new(0.0, 1.0, -self.k1 - 3.0 * self.k3 * y[0] * y[0], -self.d)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
}

/// `x'' = -x` with the event `g = x - level` and a fixed action.
pub struct Level {
    pub level: f64,
    pub stop: bool,
}
impl OdeSystem<2> for Level {
    type Mode = ();
    fn rhs(&self, _t: f64, y: &SVector<f64, 2>, _m: ()) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(y[1], -y[0])
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, _t: f64, y: &SVector<f64, 2>, _m: (), g: &mut [f64; MAX_EVENTS]) {
        g[0] = y[0] - self.level;
    }
    fn on_event(&self, _t: f64, _y: &SVector<f64, 2>, _m: (), _i: usize) -> EventAction<()> {
        if self.stop {
            EventAction::Stop
        } else {
            EventAction::Continue
        }
    }
}

/// A ball on a stiff undamped floor spring: in the air `h'' = -g`, in contact
/// `h'' = -g - k h`. The event `h = 0` switches the mode (the right-hand side changes).
/// Energy is conserved, so each bounce returns to the drop height: exact solution below.
pub struct Ball {
    pub g: f64,
    pub k: f64,
}
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BallMode {
    Air,
    Floor,
}
impl Ball {
    /// Time of one flight from `h0` down to the floor, impact speed, time in contact.
    pub fn phases(&self, h0: f64) -> (f64, f64, f64) {
        let tf = (2.0 * h0 / self.g).sqrt();
        let v0 = self.g * tf;
        let w = self.k.sqrt();
        // h(s) = (g/k)(cos ws - 1) - (v0/w) sin ws = 0 again at ws = 2 pi - 2 phi.
        let phi = (v0 / w).atan2(self.g / self.k);
        (tf, v0, (2.0 * std::f64::consts::PI - 2.0 * phi) / w)
    }
    /// Exact state at time `t` of a drop from rest at `h0 > 0`.
    pub fn exact(&self, h0: f64, t: f64) -> SVector<f64, 2> {
        let (tf, v0, tc) = self.phases(h0);
        let period = 2.0 * tf + tc;
        // Phase measured from the first impact.
        let s = t - tf;
        if s < 0.0 {
            return SVector::<f64, 2>::new(h0 - 0.5 * self.g * t * t, -self.g * t);
        }
        let s = s % period;
        if s < tc {
            let w = self.k.sqrt();
            let (sn, cs) = (w * s).sin_cos();
            let gk = self.g / self.k;
            SVector::<f64, 2>::new(gk * (cs - 1.0) - v0 / w * sn, -gk * w * sn - v0 * cs)
        } else {
            let u = s - tc;
            SVector::<f64, 2>::new(v0 * u - 0.5 * self.g * u * u, v0 - self.g * u)
        }
    }
}
impl OdeSystem<2> for Ball {
    type Mode = BallMode;
    fn rhs(&self, _t: f64, y: &SVector<f64, 2>, m: BallMode) -> SVector<f64, 2> {
        let spring = if m == BallMode::Floor { -self.k * y[0] } else { 0.0 };
        SVector::<f64, 2>::new(y[1], -self.g + spring)
    }
    fn initial_mode(&self, _t: f64, y: &SVector<f64, 2>) -> BallMode {
        if y[0] > 0.0 {
            BallMode::Air
        } else {
            BallMode::Floor
        }
    }
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, _t: f64, y: &SVector<f64, 2>, _m: BallMode, g: &mut [f64; MAX_EVENTS]) {
        g[0] = y[0];
    }
    fn on_event(&self, _t: f64, y: &SVector<f64, 2>, m: BallMode, _i: usize) -> EventAction<BallMode> {
        // Decide by the direction of motion, not by the rounding-level sign of h.
        match m {
            BallMode::Air if y[1] < 0.0 => EventAction::Switch(BallMode::Floor),
            BallMode::Floor if y[1] > 0.0 => EventAction::Switch(BallMode::Air),
            _ => EventAction::Continue,
        }
    }
}

/// Lotka–Volterra `x' = x (2 - y)`, `y' = y (x - 1)`: smooth, nonlinear, periodic.
pub struct LotkaVolterra;
impl OdeSystem<2> for LotkaVolterra {
    type Mode = ();
    fn rhs(&self, _t: f64, y: &SVector<f64, 2>, _m: ()) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(y[0] * (2.0 - y[1]), y[1] * (y[0] - 1.0))
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
}

/// `y' = y^2`: blows up at `t = 1` from `y(0) = 1`.
pub struct BlowUp;
impl OdeSystem<1> for BlowUp {
    type Mode = ();
    fn rhs(&self, _t: f64, y: &SVector<f64, 1>, _m: ()) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(y[0] * y[0])
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 1>) {}
}

/// Prothero–Robinson: `y' = -lambda (y - cos t) - sin t`, exact `y = cos t` from `y(0) = 1`.
pub struct Prothero {
    pub lambda: f64,
}
impl OdeSystem<1> for Prothero {
    type Mode = ();
    fn rhs(&self, t: f64, y: &SVector<f64, 1>, _m: ()) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(-self.lambda * (y[0] - t.cos()) - t.sin())
    }
    fn jacobian(&self, _t: f64, _y: &SVector<f64, 1>, _m: ()) -> SMatrix<f64, 1, 1> {
        SMatrix::<f64, 1, 1>::new(-self.lambda)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 1>) {}
}

/// Van der Pol in Hairer's scaled form, `x' = v`, `eps v' = (1 - x^2) v - x`
/// (`eps = 1/mu^2`; `eps = 1e-6` is `mu = 1e3`): stiff relaxation oscillations.
pub struct VanDerPol {
    pub eps: f64,
}
impl OdeSystem<2> for VanDerPol {
    type Mode = ();
    fn rhs(&self, _t: f64, y: &SVector<f64, 2>, _m: ()) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(y[1], ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.eps)
    }
    fn jacobian(&self, _t: f64, y: &SVector<f64, 2>, _m: ()) -> SMatrix<f64, 2, 2> {
        SMatrix::<f64, 2, 2>::new(0.0, 1.0, (-2.0 * y[0] * y[1] - 1.0) / self.eps, (1.0 - y[0] * y[0]) / self.eps)
    }
    fn initial_mode(&self, _t: f64, _y: &SVector<f64, 2>) {}
}

/// Checks that the dense output's local error at mid-step, `errs` at step sizes halving from
/// one to the next, converges like `h^order`: `e(h) = C h^order (1 + O(h))`, so the slope of each
/// halving, `p_k = log2(e_k / e_(k+1))`, is `order + O(h_k)`, and in the asymptotic regime the
/// change from one slope to the next shrinks by a ratio `r` near 1/2 (an O(h) term; 1/4 for O(h^2)).
/// Asserts `r <= 2/3` for the last two changes, then that the last slope is `order` within the
/// changes still to come, `d r + d r^2 + ... = d r / (1 - r) <= 2 d` for the last change `d`, plus
/// rounding: three ulps of `|y| < 4` (6 eps) on the finest error move its slope by
/// `log2(1 + 6 eps / e)`.
pub fn assert_dense_order(name: &str, errs: &[f64], order: f64) {
    let p: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("{name} dense: {} -> pairwise orders {p:.3?}", sci(errs));
    let k = p.len() - 1;
    let (d1, d2) = ((p[k - 1] - p[k - 2]).abs(), (p[k] - p[k - 1]).abs());
    assert!(d2 <= 2.0 / 3.0 * d1, "{name}: not in the asymptotic regime, pairwise orders {p:?} ({errs:?})");
    let bound = 2.0 * d2 + (6.0 * f64::EPSILON / errs[k + 1]).ln_1p() / std::f64::consts::LN_2;
    assert!((p[k] - order).abs() < bound, "{name}: dense order {:.3} is not {order} within {bound:.3}", p[k]);
}

/// Numbers in scientific notation, for test output.
pub fn sci(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|e| format!("{e:.2e}")).collect();
    format!("[{}]", parts.join(", "))
}

/// Observed order from errors at step counts `n` (least-squares slope of log e vs log n).
pub fn slope(ns: &[usize], errs: &[f64]) -> f64 {
    let xs: Vec<f64> = ns.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let m = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / m, ys.iter().sum::<f64>() / m);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    -sxy / sxx
}
