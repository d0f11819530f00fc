//! Rodas4 (Hairer & Wanner): a stiffly accurate, L-stable Rosenbrock method of order 4 with an
//! embedded order-3 solution, 6 stages, and a 3rd-order continuous extension, in the form of
//! Hairer's `rodas.f` (transformed stage variables, so that every stage solves with the same
//! matrix `E = I/(gamma h) - J`).
//!
//! Per step: one Jacobian `J = df/dy` at the step start (`sys.jacobian`, kept across rejections),
//! one LU of `E` per attempt (own partial-pivoting LU on the stack: nalgebra's `lu()` would need
//! type-level dimension bounds that the generic driver cannot state), 5 right-hand sides per
//! attempt, plus `f(t + h, y_new)` on acceptance. Being stiffly accurate, the last stage is the
//! solution and the error estimate is the last stage increment.
//!
//! Non-autonomous systems: the `df/dt` term is a central difference
//! `(f(t + d, y) - f(t - d, y)) / 2d`, `d = eps^(1/3) max(|t|, 1)`: two extra right-hand sides per
//! step start (counted in `n_rhs`); for an autonomous system it is exactly zero.
//!
//! Coefficients: Hairer & Wanner, *Solving ODEs II*, §IV.7 (RODAS, `METH = 1` of
//! `rodas.f`), transcribed as published numbers; order verified empirically in the tests.

use super::controller::error_norm;
use super::driver::{StepDense, Stepper};
use super::{Dense, OdeSystem, Stats};
use nalgebra::{SMatrix, SVector};

const GAMMA: f64 = 0.25;
const C2: f64 = 0.386;
const C3: f64 = 0.21;
const C4: f64 = 0.63;
const D1: f64 = 0.25;
const D2: f64 = -0.1043;
const D3: f64 = 0.1035;
const D4: f64 = -0.036_200_000_000_000_23;
const A21: f64 = 1.544;
const A31: f64 = 0.946_678_528_081_582_6;
const A32: f64 = 0.255_701_169_898_328_4;
const A41: f64 = 3.314_825_187_068_521;
const A42: f64 = 2.896_124_015_972_201;
const A43: f64 = 0.998_641_913_997_781_7;
const A51: f64 = 1.221_224_509_226_641;
const A52: f64 = 6.019_134_481_288_629;
const A53: f64 = 12.537_083_329_320_87;
const A54: f64 = -0.687_886_036_105_895;
const C21: f64 = -5.6688;
const C31: f64 = -2.430_093_356_833_875;
const C32: f64 = -0.206_359_915_709_191_5;
const C41: f64 = -0.107_352_905_815_137_5;
const C42: f64 = -9.594_562_251_023_355;
const C43: f64 = -20.470_286_148_096_16;
const C51: f64 = 7.496_443_313_967_647;
const C52: f64 = -10.246_804_314_643_52;
const C53: f64 = -33.999_903_528_199_05;
const C54: f64 = 11.708_908_932_061_6;
const C61: f64 = 8.083_246_795_921_522;
const C62: f64 = -7.981_132_988_064_893;
const C63: f64 = -31.521_594_328_743_71;
const C64: f64 = 16.319_305_431_231_36;
const C65: f64 = -6.058_818_238_834_054;
// Dense output.
const H21: f64 = 10.126_235_083_445_86;
const H22: f64 = -7.487_995_877_610_167;
const H23: f64 = -34.800_918_615_557_47;
const H24: f64 = -7.992_771_707_568_823;
const H25: f64 = 1.025_137_723_295_662;
const H31: f64 = -0.676_280_339_280_125_3;
const H32: f64 = 6.087_714_651_680_015;
const H33: f64 = 16.430_843_208_924_78;
const H34: f64 = 24.767_225_114_183_86;
const H35: f64 = -6.594_389_125_716_872;

/// LU factors with partial pivoting of an `N x N` matrix, on the stack.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lu<const N: usize> {
    lu: SMatrix<f64, N, N>,
    perm: [usize; N],
}

impl<const N: usize> Lu<N> {
    /// Factor `a`; `None` if a pivot is zero or not finite (singular or broken matrix).
    #[inline]
    pub(crate) fn new(mut a: SMatrix<f64, N, N>) -> Option<Self> {
        let mut perm = [0usize; N];
        for k in 0..N {
            let mut p = k;
            let mut best = a[(k, k)].abs();
            for i in k + 1..N {
                let v = a[(i, k)].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return None;
            }
            perm[k] = p;
            if p != k {
                a.swap_rows(p, k);
            }
            let inv = 1.0 / a[(k, k)];
            for i in k + 1..N {
                let l = a[(i, k)] * inv;
                a[(i, k)] = l;
                for j in k + 1..N {
                    a[(i, j)] -= l * a[(k, j)];
                }
            }
        }
        Some(Lu { lu: a, perm })
    }

    /// Solve `A x = b`.
    #[inline]
    pub(crate) fn solve(&self, mut b: SVector<f64, N>) -> SVector<f64, N> {
        for k in 0..N {
            b.swap_rows(k, self.perm[k]);
        }
        for i in 1..N {
            let mut s = b[i];
            for j in 0..i {
                s -= self.lu[(i, j)] * b[j];
            }
            b[i] = s;
        }
        for i in (0..N).rev() {
            let mut s = b[i];
            for j in i + 1..N {
                s -= self.lu[(i, j)] * b[j];
            }
            b[i] = s / self.lu[(i, i)];
        }
        b
    }
}

/// The Rodas4 stepper: Jacobian and `df/dt` at the step start, stage increments of the last
/// attempt, and `f` at the accepted end.
pub(crate) struct Rodas4<const N: usize> {
    jac: SMatrix<f64, N, N>,
    dfdt: SVector<f64, N>,
    ak: [SVector<f64, N>; 5],
}

/// Rodas4's interpolant on one step (`rodas.f`'s `CONTRO`), evaluated from the stages.
pub(crate) struct Rodas4Dense<'a, const N: usize> {
    ak: &'a [SVector<f64, N>; 5],
    y0: &'a SVector<f64, N>,
    y1: &'a SVector<f64, N>,
    t0: f64,
    h: f64,
}

impl<const N: usize> Dense<N> for Rodas4Dense<'_, N> {
    #[inline]
    fn eval(&self, t: f64) -> SVector<f64, N> {
        let a = self.ak;
        let s = (t - self.t0) / self.h;
        let s1 = 1.0 - s;
        let c3 = a[0] * H21 + a[1] * H22 + a[2] * H23 + a[3] * H24 + a[4] * H25;
        let c4 = a[0] * H31 + a[1] * H32 + a[2] * H33 + a[3] * H34 + a[4] * H35;
        self.y0 * s1 + (self.y1 + (c3 + c4 * s) * s1) * s
    }
}

impl<const N: usize> StepDense<N> for Rodas4Dense<'_, N> {}

impl<const N: usize, S: OdeSystem<N>> Stepper<N, S> for Rodas4<N> {
    const ORDER: u32 = 4;
    const ERR_EXP: u32 = 4;
    const BETA: f64 = 0.0;
    const PREDICTIVE: bool = true;

    type Dense<'a>
        = Rodas4Dense<'a, N>
    where
        Self: 'a,
        S: 'a;

    fn new() -> Self {
        Rodas4 { jac: SMatrix::zeros(), dfdt: SVector::zeros(), ak: [SVector::zeros(); 5] }
    }

    fn begin(&mut self, sys: &S, mode: S::Mode, t: f64, y: &SVector<f64, N>, _f: &SVector<f64, N>, stats: &mut Stats) {
        self.jac = sys.jacobian(t, y, mode);
        stats.n_jac += 1;
        // Central difference: O(d^2) truncation against O(eps / d) rounding, balanced at
        // d ~ eps^(1/3) on the time scale max(|t|, 1). (A forward difference, as in rodas.f, saves
        // one evaluation but limits non-autonomous problems to about 1e-8 accuracy.) For an
        // autonomous system both evaluations equal f exactly and the term vanishes.
        let d = f64::EPSILON.cbrt() * t.abs().max(1.0);
        let fp = sys.rhs(t + d, y, mode);
        let fm = sys.rhs(t - d, y, mode);
        stats.n_rhs += 2;
        self.dfdt = (fp - fm) / (2.0 * d);
    }

    #[inline]
    fn try_step(
        &mut self,
        sys: &S,
        mode: S::Mode,
        t: f64,
        y: &SVector<f64, N>,
        f: &SVector<f64, N>,
        h: f64,
        atol: &SVector<f64, N>,
        rtol: f64,
        stats: &mut Stats,
    ) -> (SVector<f64, N>, f64) {
        let mut e = -self.jac;
        let diag = 1.0 / (GAMMA * h);
        for i in 0..N {
            e[(i, i)] += diag;
        }
        stats.n_lu += 1;
        let Some(lu) = Lu::new(e) else {
            // Singular iteration matrix: a failed step; the driver cuts h.
            return (*y, f64::INFINITY);
        };
        let ft = self.dfdt;
        let (hc21, hc31, hc32) = (C21 / h, C31 / h, C32 / h);
        let (hc41, hc42, hc43) = (C41 / h, C42 / h, C43 / h);
        let (hc51, hc52, hc53, hc54) = (C51 / h, C52 / h, C53 / h, C54 / h);
        let (hc61, hc62, hc63, hc64, hc65) = (C61 / h, C62 / h, C63 / h, C64 / h, C65 / h);

        let ak1 = lu.solve(f + ft * (D1 * h));
        let dy = sys.rhs(t + C2 * h, &(y + ak1 * A21), mode);
        let ak2 = lu.solve(dy + ak1 * hc21 + ft * (D2 * h));
        let dy = sys.rhs(t + C3 * h, &(y + ak1 * A31 + ak2 * A32), mode);
        let ak3 = lu.solve(dy + ak1 * hc31 + ak2 * hc32 + ft * (D3 * h));
        let dy = sys.rhs(t + C4 * h, &(y + ak1 * A41 + ak2 * A42 + ak3 * A43), mode);
        let ak4 = lu.solve(dy + ak1 * hc41 + ak2 * hc42 + ak3 * hc43 + ft * (D4 * h));
        let y5 = y + ak1 * A51 + ak2 * A52 + ak3 * A53 + ak4 * A54;
        let dy = sys.rhs(t + h, &y5, mode);
        let ak5 = lu.solve(dy + ak1 * hc51 + ak2 * hc52 + ak3 * hc53 + ak4 * hc54);
        let y6 = y5 + ak5;
        let dy = sys.rhs(t + h, &y6, mode);
        let ak6 = lu.solve(dy + ak1 * hc61 + ak2 * hc62 + ak3 * hc63 + ak4 * hc64 + ak5 * hc65);
        stats.n_rhs += 5;
        let y_new = y6 + ak6;
        self.ak = [ak1, ak2, ak3, ak4, ak5];
        (y_new, error_norm(&ak6, y, &y_new, atol, rtol))
    }

    #[inline]
    fn finish(
        &mut self,
        sys: &S,
        mode: S::Mode,
        t: f64,
        h: f64,
        y_new: &SVector<f64, N>,
        stats: &mut Stats,
    ) -> SVector<f64, N> {
        stats.n_rhs += 1;
        sys.rhs(t + h, y_new, mode)
    }

    #[inline]
    fn dense<'a>(
        &'a self,
        _sys: &'a S,
        _mode: S::Mode,
        t: f64,
        h: f64,
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
    ) -> Rodas4Dense<'a, N> {
        Rodas4Dense { ak: &self.ak, y0, y1, t0: t, h }
    }
}

#[cfg(test)]
mod tests {
    use super::{Lu, Rodas4};
    use crate::ode::driver::test_systems::*;
    use crate::ode::Method;
    use nalgebra::{SMatrix, SVector};

    #[test]
    fn order_four_on_forced_duffing() {
        // Non-autonomous (exercises the df/dt term) with an analytic Jacobian.
        // Measured: errors 1.5e-8 .. 3.4e-12 for n = 200 .. 1600, order 4.03.
        let p =
            observed_order(&DUFFING, Method::Rodas4, SVector::<f64, 2>::new(1.0, 0.0), 10.0, &[200, 400, 800, 1600]);
        assert!((p - 4.0).abs() < 0.3, "observed order {p}");
    }

    #[test]
    fn dense_output_is_third_order() {
        // Local interpolation error at mid-step ~ h^4. Measured pairwise orders 3.84, 3.93, 3.97.
        let y0 = SVector::<f64, 2>::new(1.0, 3.0);
        let hs = [0.1, 0.05, 0.025, 0.0125];
        let errs: Vec<f64> = hs.iter().map(|&h| midpoint_error::<Rodas4<2>, _, 2>(&LotkaVolterra, y0, h)).collect();
        assert_dense_order("Rodas4", &errs, 4.0);
    }

    #[test]
    fn lu_solves_with_pivoting() {
        // A zero leading entry needs a row exchange.
        let a = SMatrix::<f64, 3, 3>::new(0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0);
        let x = SVector::<f64, 3>::new(1.0, -2.0, 0.5);
        let lu = Lu::new(a).expect("regular");
        assert!((lu.solve(a * x) - x).amax() < 1e-14);
        assert!(Lu::new(SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 4.0)).is_none());
    }
}
