//! The lane-batched integration kit: `N` trajectories at once in structure-of-arrays form
//! (`[f64; N]` per state component, [`Lw`] and [`Vw`]), so that the stage arithmetic of `N`
//! trajectories runs in SIMD registers (plain loops over the lanes that LLVM vectorises). Every
//! function is generic in `N`: the lane drivers (`crate::ensemble::batch`, `crate::ensemble::lanes`)
//! run [`W`] = 8 lanes, and 16 for end states in their AVX-512 copies (two registers per operation).
//!
//! Generic over the right-hand side (a closure on the lanes), it holds what any lane-batched
//! explicit integrator needs: the lane types, branch-free `exp` and `ln` for the PI controller in
//! log form, one Dormand–Prince 5(4) or DOP853 attempt on all lanes, and the interpolants of a
//! selection of components. The tableaux are the scalar steppers' ([`super::dopri5`],
//! [`super::dop853`]), so both paths use one table. The slider's lane drivers that use this kit
//! (events, observers, refilling lanes) live in `crate::ensemble`.
//!
//! # Determinism
//! Every function here computes each lane from that lane's values only, with the same sequence of
//! IEEE operations (masks only select; no reduction across lanes, no fused multiply-add): a
//! lane's result does not depend on what runs in the other lanes.

// Index loops over lanes and components are the point here: they are what LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::dop853::*;
use super::dopri5::{
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, B1, B3, B4, B5, B6, D1, D3, D4, D5, D6,
    D7, E1, E3, E4, E5, E6, E7,
};
use nalgebra::SVector;

/// Lanes of the slider's lane driver (SIMD lanes), except its AVX-512 copy for end states.
pub const W: usize = 8;
/// One `f64` per lane, on `N` lanes.
pub(crate) type Lw<const N: usize> = [f64; N];
/// A six-component state on `N` lanes, `v[component][lane]` (the slider's dimension: the only
/// one lane-batched so far).
pub(crate) type Vw<const N: usize> = [Lw<N>; 6];

// The PI controller of `controller.rs` in log form (one `exp` per lane and step).
/// Weight of the previous error (`beta = 0.04`, the explicit methods').
pub(crate) const BETA: f64 = 0.04;
/// The exponent of the current error for DOPRI5 (error order 5).
pub(crate) const ALPHA: f64 = 1.0 / 5.0 - 0.75 * BETA;
/// The PI controller's exponent for DOP853 (error order 8, `beta = 0.04`).
pub(crate) const ALPHA8: f64 = 1.0 / 8.0 - 0.75 * BETA;
/// `ln 0.9`: the safety factor.
pub(crate) const LN_SAFETY: f64 = -0.105_360_515_657_826_3;
/// `ln 1e-4`: the floor of the previous error in the PI formula.
pub(crate) const LN_ERR_FLOOR: f64 = -9.210_340_371_976_184;

/// A right-hand side on the lanes: `out = f(y)` for each lane. A trait rather than a closure so
/// that the implementation can be `#[inline(always)]`: the steps below call it up to 16 times, and
/// the cheap ones (the bilateral slider) lose a fifth of their speed when it is a call.
pub(crate) trait LaneRhs<const N: usize> {
    /// `out = f(y)` on every lane.
    fn eval(&mut self, y: &Vw<N>, out: &mut Vw<N>);
}

/// `x` in every lane.
#[inline(always)]
pub(crate) fn splat<const N: usize>(x: f64) -> Lw<N> {
    [x; N]
}

/// `$body` for `$i` = 0..6, unrolled: the loops inside run over the lanes, and unrolling the
/// component loop keeps LLVM from vectorising across components (with gathers) instead.
macro_rules! each6 {
    ($i:ident, $body:block) => {{
        {
            let $i = 0usize;
            $body
        }
        {
            let $i = 1usize;
            $body
        }
        {
            let $i = 2usize;
            $body
        }
        {
            let $i = 3usize;
            $body
        }
        {
            let $i = 4usize;
            $body
        }
        {
            let $i = 5usize;
            $body
        }
    }};
}
pub(crate) use each6;

/// `a` where `mask` is all ones, `b` where it is zero (bit for bit): a per-lane select that
/// vectorises (an `if` on a lane's `bool` often compiled to a branch per lane).
#[inline(always)]
pub(crate) fn blend(mask: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

/// `exp` of each lane, branch-free so that it vectorises: `2^n p(r)` with `x = n ln 2 + r`,
/// `|r| <= ln 2 / 2`, Taylor to degree 12 (relative error below 1e-15). Arguments are clamped to
/// `[-700, 700]` (the controller clips its factors far inside that).
#[inline(always)]
pub(crate) fn exp_lanes<const N: usize>(x: &Lw<N>) -> Lw<N> {
    exp_lanes_by::<false, N>(x)
}

/// [`exp_lanes`] with the polynomial by Estrin's scheme (`ESTRIN`): pairs of terms, then the
/// powers `r^2`, `r^4`, `r^8`, a chain of 8 dependent operations where Horner's is 26, for the
/// same accuracy (not the same bits). The Stribeck law's `exp` in every right-hand side uses it:
/// on 8 lanes (one vector) Horner's chain was a quarter of a switch-law lane step.
#[inline(always)]
pub(crate) fn exp_lanes_by<const ESTRIN: bool, const N: usize>(x: &Lw<N>) -> Lw<N> {
    const MAGIC: f64 = 6755399441055744.0; // 1.5 * 2^52: adding it rounds to an integer
                                           // ln 2 split so that n * LN2_HI is exact (fdlibm's constants).
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
    let mut out = [0.0; N];
    for l in 0..N {
        let x = x[l].clamp(-700.0, 700.0);
        let t = x * std::f64::consts::LOG2_E + MAGIC;
        let n = t - MAGIC;
        let r = (x - n * LN2_HI) - n * LN2_LO;
        let p = if ESTRIN {
            let r2 = r * r;
            let r4 = r2 * r2;
            let r8 = r4 * r4;
            let q0 = 1.0 + r;
            let q1 = 0.5 + r * (1.0 / 6.0);
            let q2 = 1.0 / 24.0 + r * (1.0 / 120.0);
            let q3 = 1.0 / 720.0 + r * (1.0 / 5040.0);
            let q4 = 1.0 / 40320.0 + r * (1.0 / 362880.0);
            let q5 = 1.0 / 3628800.0 + r * (1.0 / 39916800.0);
            let s0 = q0 + q1 * r2;
            let s1 = q2 + q3 * r2;
            let s2 = q4 + q5 * r2;
            (s0 + s1 * r4) + (s2 + (1.0 / 479001600.0) * r4) * r8
        } else {
            let mut p = 1.0 / 479001600.0;
            p = p * r + 1.0 / 39916800.0;
            p = p * r + 1.0 / 3628800.0;
            p = p * r + 1.0 / 362880.0;
            p = p * r + 1.0 / 40320.0;
            p = p * r + 1.0 / 5040.0;
            p = p * r + 1.0 / 720.0;
            p = p * r + 1.0 / 120.0;
            p = p * r + 1.0 / 24.0;
            p = p * r + 1.0 / 6.0;
            p = p * r + 0.5;
            p = p * r + 1.0;
            p * r + 1.0
        };
        let ni = t.to_bits().wrapping_sub(MAGIC.to_bits());
        let scale = f64::from_bits(ni.wrapping_add(1023) << 52);
        out[l] = p * scale;
    }
    out
}

/// `ln` of each lane for normal positive finite arguments, branch-free:
/// `x = 2^e m`, `m` in `[sqrt(1/2), sqrt 2)`, `ln m = 2 atanh s`, `s = (m - 1)/(m + 1)`, series to
/// `s^21` (relative error below 1e-15).
#[inline(always)]
pub(crate) fn ln_lanes<const N: usize>(x: &Lw<N>) -> Lw<N> {
    const TWO52: f64 = 4503599627370496.0;
    let mut out = [0.0; N];
    for l in 0..N {
        let b = x[l].to_bits();
        let mut m = f64::from_bits((b & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
        // Biased exponent as a double, exactly (no vector int->float conversion needed).
        let mut e = f64::from_bits(0x4330_0000_0000_0000 | (b >> 52)) - TWO52 - 1023.0;
        let big = m > std::f64::consts::SQRT_2;
        m = if big { 0.5 * m } else { m };
        e = if big { e + 1.0 } else { e };
        let s = (m - 1.0) / (m + 1.0);
        let s2 = s * s;
        let mut p = 1.0 / 21.0;
        p = p * s2 + 1.0 / 19.0;
        p = p * s2 + 1.0 / 17.0;
        p = p * s2 + 1.0 / 15.0;
        p = p * s2 + 1.0 / 13.0;
        p = p * s2 + 1.0 / 11.0;
        p = p * s2 + 1.0 / 9.0;
        p = p * s2 + 1.0 / 7.0;
        p = p * s2 + 1.0 / 5.0;
        p = p * s2 + 1.0 / 3.0;
        p = p * s2 + 1.0;
        out[l] = e * std::f64::consts::LN_2 + 2.0 * s * p;
    }
    out
}

/// The state of lane `l`.
#[inline]
pub(crate) fn lane_state<const N: usize>(v: &Vw<N>, l: usize) -> SVector<f64, 6> {
    SVector::<f64, 6>::from_fn(|i, _| v[i][l])
}

/// Every state component (the interpolant of steps whose samples are taken on the lanes).
pub(crate) const ALL_COMPS: [usize; 6] = [0, 1, 2, 3, 4, 5];

/// A value on a 64-byte boundary (one cache line, one AVX-512 register): the lane rows of a
/// step's stages. Plain `[f64; N]` arrays on the stack are 8-byte aligned and land wherever the
/// frame puts them; rows off the boundary make every 512-bit load and store touch two cache
/// lines, and any unrelated change that moved the frame moved the speed by 10 % (the bilateral
/// DOP853 end state 76k -> 68k trajectories/s on Zen 5 after a change elsewhere in the driver).
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub(crate) struct Al<T>(pub(crate) T);

impl<T> std::ops::Deref for Al<T> {
    type Target = T;
    #[inline(always)]
    fn deref(&self) -> &T {
        &self.0
    }
}

impl<T> std::ops::DerefMut for Al<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut T {
        &mut self.0
    }
}

/// `events::crosses` without short-circuit evaluation, so that loops over lanes vectorise.
#[inline(always)]
pub(crate) fn cross(a: f64, b: f64) -> bool {
    ((a > 0.0) & (b <= 0.0)) | ((a < 0.0) & (b >= 0.0))
}

/// `out = y + h (a_1 k_1 + ... + a_K k_K)` on the lanes.
#[inline(always)]
pub(crate) fn comb<const K: usize, const N: usize>(
    y: &Vw<N>,
    hh: &Lw<N>,
    a: [f64; K],
    ks: [&Vw<N>; K],
    out: &mut Vw<N>,
) {
    // Stage by stage over whole lane rows (the sum of each lane in the same order, `0 + a_1 k_1 +
    // ... + a_K k_K`): with the stage loop innermost, LLVM vectorised the sum across stages with
    // gathers, and DOP853's attempt cost 15x DP5's instead of about 2x. All six components' sums
    // at once, so that their adds overlap (one component's chain at a time, each add waited on
    // the one before: 3 % of the bilateral DOP853 end state).
    let mut s = [[0.0; N]; 6];
    for j in 0..K {
        let aj = a[j];
        each6!(i, {
            let kj = &ks[j][i];
            for l in 0..N {
                s[i][l] += aj * kj[l];
            }
        });
    }
    each6!(i, {
        for l in 0..N {
            out[i][l] = y[i][l] + hh[l] * s[i][l];
        }
    });
}

/// One Dormand–Prince 5(4) attempt on the lanes from `y` with first stage `k1` and step sizes
/// `hh`: the stages `k2..k7` into `k` (`k[5]` is the derivative at the new state, the FSAL stage),
/// the new state into `yn`; returns the squared RMS error norm (`err <= 1` iff `err^2 <= 1`, no
/// square root needed) and whether the new state and derivative are finite. `rhs` is the
/// right-hand side on the lanes.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dopri5_step<F: LaneRhs<N>, const N: usize>(
    rhs: &mut F,
    y: &Vw<N>,
    k1: &Vw<N>,
    hh: &Lw<N>,
    rtol: f64,
    atol: &Vw<N>,
    k: &mut [Vw<N>; 6],
    yn: &mut Vw<N>,
) -> (Lw<N>, [bool; N]) {
    let zero = [0.0; N];
    let mut ys = Al([zero; 6]);
    each6!(i, {
        for l in 0..N {
            ys[i][l] = y[i][l] + hh[l] * (A21 * k1[i][l]);
        }
    });
    rhs.eval(&ys, &mut k[0]);
    each6!(i, {
        for l in 0..N {
            ys[i][l] = y[i][l] + hh[l] * (A31 * k1[i][l] + A32 * k[0][i][l]);
        }
    });
    rhs.eval(&ys, &mut k[1]);
    each6!(i, {
        for l in 0..N {
            ys[i][l] = y[i][l] + hh[l] * (A41 * k1[i][l] + A42 * k[0][i][l] + A43 * k[1][i][l]);
        }
    });
    rhs.eval(&ys, &mut k[2]);
    each6!(i, {
        for l in 0..N {
            ys[i][l] = y[i][l] + hh[l] * (A51 * k1[i][l] + A52 * k[0][i][l] + A53 * k[1][i][l] + A54 * k[2][i][l]);
        }
    });
    rhs.eval(&ys, &mut k[3]);
    each6!(i, {
        for l in 0..N {
            ys[i][l] = y[i][l]
                + hh[l] * (A61 * k1[i][l] + A62 * k[0][i][l] + A63 * k[1][i][l] + A64 * k[2][i][l] + A65 * k[3][i][l]);
        }
    });
    rhs.eval(&ys, &mut k[4]);
    each6!(i, {
        for l in 0..N {
            yn[i][l] = y[i][l]
                + hh[l] * (B1 * k1[i][l] + B3 * k[1][i][l] + B4 * k[2][i][l] + B5 * k[3][i][l] + B6 * k[4][i][l]);
        }
    });
    rhs.eval(&*yn, &mut k[5]);

    // ---- error norm and finiteness ----
    let mut acc = zero;
    let mut fin = [true; N];
    each6!(i, {
        for l in 0..N {
            let h = hh[l];
            let e = (E1 * h) * k1[i][l]
                + (E3 * h) * k[1][i][l]
                + (E4 * h) * k[2][i][l]
                + (E5 * h) * k[3][i][l]
                + (E6 * h) * k[4][i][l]
                + (E7 * h) * k[5][i][l];
            let sk = atol[i][l] + rtol * y[i][l].abs().max(yn[i][l].abs());
            let q = e / sk;
            acc[l] += q * q;
            fin[l] &= yn[i][l].is_finite() && k[5][i][l].is_finite();
        }
    });
    let mut e2 = zero;
    for l in 0..N {
        e2[l] = acc[l] / 6.0;
    }
    (e2, fin)
}

/// One DOP853 attempt on the lanes: the twelve stages into `kk[1..12]`, the new state `yn`, the
/// derivative there into `kk[12]`; returns Hairer's error measure and whether the state and
/// derivative are finite. `rhs` is the right-hand side on the lanes.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dop853_step<F: LaneRhs<N>, const N: usize>(
    rhs: &mut F,
    y: &Vw<N>,
    k1: &Vw<N>,
    hh: &Lw<N>,
    rtol: f64,
    atol: &Vw<N>,
    kk: &mut [Vw<N>; 16],
    yn: &mut Vw<N>,
) -> (Lw<N>, [bool; N]) {
    let mut ys = Al([[0.0; N]; 6]);
    macro_rules! stage {
        ($j:expr, $a:expr, $ks:expr) => {{
            comb(y, hh, $a, $ks, &mut ys);
            rhs.eval(&ys, &mut kk[$j]);
        }};
    }
    stage!(1, [A2_1], [k1]);
    stage!(2, [A3_1, A3_2], [k1, &kk[1]]);
    stage!(3, [A4_1, A4_3], [k1, &kk[2]]);
    stage!(4, [A5_1, A5_3, A5_4], [k1, &kk[2], &kk[3]]);
    stage!(5, [A6_1, A6_4, A6_5], [k1, &kk[3], &kk[4]]);
    stage!(6, [A7_1, A7_4, A7_5, A7_6], [k1, &kk[3], &kk[4], &kk[5]]);
    stage!(7, [A8_1, A8_4, A8_5, A8_6, A8_7], [k1, &kk[3], &kk[4], &kk[5], &kk[6]]);
    stage!(8, [A9_1, A9_4, A9_5, A9_6, A9_7, A9_8], [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7]]);
    stage!(9, [A10_1, A10_4, A10_5, A10_6, A10_7, A10_8, A10_9], [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7], &kk[8]]);
    stage!(
        10,
        [A11_1, A11_4, A11_5, A11_6, A11_7, A11_8, A11_9, A11_10],
        [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7], &kk[8], &kk[9]]
    );
    stage!(
        11,
        [A12_1, A12_4, A12_5, A12_6, A12_7, A12_8, A12_9, A12_10, A12_11],
        [k1, &kk[3], &kk[4], &kk[5], &kk[6], &kk[7], &kk[8], &kk[9], &kk[10]]
    );
    let used = [k1, &kk[5], &kk[6], &kk[7], &kk[8], &kk[9], &kk[10], &kk[11]];
    comb(y, hh, [A13_1, A13_6, A13_7, A13_8, A13_9, A13_10, A13_11, A13_12], used, yn);
    let mut s5 = [0.0; N];
    let mut s3 = [0.0; N];
    let er = [ER_1, ER_6, ER_7, ER_8, ER_9, ER_10, ER_11, ER_12];
    let e3c = [E3_1, A13_6, A13_7, A13_8, E3_9, A13_10, A13_11, E3_12];
    each6!(i, {
        // Row by row, as in `comb`.
        let mut e5 = [0.0; N];
        let mut e3 = [0.0; N];
        for j in 0..8 {
            let (a5, a3, kj) = (er[j], e3c[j], &used[j][i]);
            for l in 0..N {
                e5[l] += a5 * kj[l];
                e3[l] += a3 * kj[l];
            }
        }
        // One division per component, not two (a vector division costs about a dozen FMAs).
        for l in 0..N {
            let sk = atol[i][l] + rtol * y[i][l].abs().max(yn[i][l].abs());
            let w = 1.0 / (sk * sk);
            s5[l] += e5[l] * e5[l] * w;
            s3[l] += e3[l] * e3[l] * w;
        }
    });
    rhs.eval(yn, &mut kk[12]);
    let mut err = [0.0; N];
    let mut fin = [true; N];
    for l in 0..N {
        let den = s5[l] + 0.01 * s3[l];
        let e = hh[l].abs() * s5[l] / (den * 6.0).sqrt();
        err[l] = if den > 0.0 {
            e
        } else if den == 0.0 {
            0.0
        } else {
            f64::NAN
        };
    }
    // Unrolled over the components: as a loop over them, LLVM vectorised it across the
    // components, with gathers over the lanes.
    each6!(i, {
        for l in 0..N {
            fin[l] &= yn[i][l].is_finite() & kk[12][i][l].is_finite();
        }
    });
    (err, fin)
}

/// A step's interpolant on the lanes, for `C` selected components of the state (its rows on
/// 64-byte boundaries, as [`Al`]'s).
#[repr(C, align(64))]
pub(crate) struct LaneDense<const C: usize, const N: usize> {
    y0: [Lw<N>; C],
    /// DP5: `dy, bspl, r4, r5` (`y0 + (dy + (bspl + (r4 + r5 (1-x)) x) (1-x)) x`);
    /// DOP853: `c0..c6` (Hairer's `contd8` polynomial).
    c: [[Lw<N>; C]; 7],
    eight: bool,
}

impl<const C: usize, const N: usize> LaneDense<C, N> {
    /// An interpolant to be filled by the `*_into` builders (zeros until then).
    pub(crate) fn new() -> Self {
        LaneDense { y0: [[0.0; N]; C], c: [[[0.0; N]; C]; 7], eight: false }
    }

    /// Component `j` of lane `l` at `x` (`x1 = 1 - x`): the scalar interpolants' formula,
    /// operation for operation (DP5's `y0 + (dy + (bspl + (r4 + r5 (1-x)) x) (1-x)) x`,
    /// DOP853's `contd8` Horner scheme).
    #[inline(always)]
    pub(crate) fn at(&self, j: usize, l: usize, x: f64, x1: f64) -> f64 {
        let c = &self.c;
        if self.eight {
            let mut p = c[6][j][l] * x;
            p = (c[5][j][l] + p) * x1;
            p = (c[4][j][l] + p) * x;
            p = (c[3][j][l] + p) * x1;
            p = (c[2][j][l] + p) * x;
            p = (c[1][j][l] + p) * x1;
            p = (c[0][j][l] + p) * x;
            self.y0[j][l] + p
        } else {
            self.y0[j][l] + (c[0][j][l] + (c[1][j][l] + (c[2][j][l] + c[3][j][l] * x1) * x) * x1) * x
        }
    }

    /// Lane `l`'s coefficients `c0..c6`, each over the selected components.
    #[inline]
    pub(crate) fn coefficients_of(&self, l: usize) -> [[f64; C]; 7] {
        std::array::from_fn(|r| std::array::from_fn(|j| self.c[r][j][l]))
    }

    /// The selected components of lane `l` alone at `x = (t - t0) / h` of its own step.
    #[inline]
    pub(crate) fn eval_lane(&self, l: usize, x: f64) -> [f64; C] {
        let x1 = 1.0 - x;
        std::array::from_fn(|j| self.at(j, l, x, x1))
    }

    #[inline(always)]
    /// The selected components at `x = (t - t0) / h` in `[0, 1]` of each lane's step.
    pub(crate) fn eval(&self, x: f64) -> [Lw<N>; C] {
        let x1 = 1.0 - x;
        let mut v = [[0.0; N]; C];
        for j in 0..C {
            for l in 0..N {
                v[j][l] = self.at(j, l, x, x1);
            }
        }
        v
    }
}

impl<const N: usize> LaneDense<6, N> {
    /// All six components of each lane at its own `x[l]` (`(t - t0) / h` of its step), by
    /// [`Self::at`]'s formula, all lanes at once.
    #[inline(always)]
    pub(crate) fn eval_at(&self, x: &Lw<N>) -> Vw<N> {
        let c = &self.c;
        let mut v = [[0.0; N]; 6];
        let x1: Lw<N> = std::array::from_fn(|l| 1.0 - x[l]);
        // Each operation over a whole lane row, the branch outside the loops: written lane by lane
        // (`at` per lane), LLVM vectorised across components, with gathers and scatters; so
        // the components are unrolled too.
        if self.eight {
            each6!(j, {
                let p = &mut v[j];
                for l in 0..N {
                    p[l] = c[6][j][l] * x[l];
                }
                for r in (0..6).rev() {
                    let xr = if r % 2 == 0 { x } else { &x1 };
                    for l in 0..N {
                        p[l] = (c[r][j][l] + p[l]) * xr[l];
                    }
                }
                for l in 0..N {
                    p[l] += self.y0[j][l];
                }
            });
        } else {
            each6!(j, {
                let p = &mut v[j];
                for l in 0..N {
                    p[l] = c[3][j][l] * x1[l];
                }
                for l in 0..N {
                    p[l] = (c[2][j][l] + p[l]) * x[l];
                }
                for l in 0..N {
                    p[l] = (c[1][j][l] + p[l]) * x1[l];
                }
                for l in 0..N {
                    p[l] = (c[0][j][l] + p[l]) * x[l];
                }
                for l in 0..N {
                    p[l] += self.y0[j][l];
                }
            });
        }
        v
    }
}

/// The DP5 interpolant of each lane's step from `y0` to `y1`, for the components `comps`, from the
/// stages `k = [k1, k3, k4, k5, k6, k7]`, into `d` (a buffer the driver keeps across steps:
/// an interpolant built and moved per step cost copies and zeroing).
#[inline(always)]
pub(crate) fn dopri5_dense_into<const C: usize, const N: usize>(
    d: &mut LaneDense<C, N>,
    comps: &[usize; C],
    y0: &Vw<N>,
    y1: &Vw<N>,
    k: [&Vw<N>; 6],
    hh: &Lw<N>,
) {
    let [k1, k3, k4, k5, k6, k7] = k;
    d.eight = false;
    for (j, &i) in comps.iter().enumerate() {
        for l in 0..N {
            let h = hh[l];
            let dy = y1[i][l] - y0[i][l];
            let b = k1[i][l] * h - dy;
            d.y0[j][l] = y0[i][l];
            d.c[0][j][l] = dy;
            d.c[1][j][l] = b;
            d.c[2][j][l] = dy - k7[i][l] * h - b;
            d.c[3][j][l] = (D1 * h) * k1[i][l]
                + (D3 * h) * k3[i][l]
                + (D4 * h) * k4[i][l]
                + (D5 * h) * k5[i][l]
                + (D6 * h) * k6[i][l]
                + (D7 * h) * k7[i][l];
        }
    }
}

/// The DOP853 interpolant of each lane's step from `y` to `y1`, for the components `comps`, into
/// `d` (a buffer the driver keeps across steps): the three extra stages (three evaluations of
/// `rhs`, left in `extra` for the cold path's full interpolant), then the seven coefficients of
/// each component ([`dop853_poly_into`]). `k1` and `kk` are the stages of [`dop853_step`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dop853_dense_into<F: LaneRhs<N>, const C: usize, const N: usize>(
    d: &mut LaneDense<C, N>,
    rhs: &mut F,
    comps: &[usize; C],
    y: &Vw<N>,
    y1: &Vw<N>,
    k1: &Vw<N>,
    hh: &Lw<N>,
    kk: &[Vw<N>; 16],
    extra: &mut [Vw<N>; 3],
) {
    let mut ys = Al([[0.0; N]; 6]);
    let [k14, k15, k16] = extra;
    let k = |j: usize| &kk[j - 1];
    comb(
        y,
        hh,
        [A14_1, A14_7, A14_8, A14_9, A14_10, A14_11, A14_12, A14_13],
        [k1, k(7), k(8), k(9), k(10), k(11), k(12), k(13)],
        &mut ys,
    );
    rhs.eval(&ys, k14);
    comb(
        y,
        hh,
        [A15_1, A15_6, A15_7, A15_8, A15_11, A15_12, A15_13, A15_14],
        [k1, k(6), k(7), k(8), k(11), k(12), k(13), &*k14],
        &mut ys,
    );
    rhs.eval(&ys, k15);
    comb(
        y,
        hh,
        [A16_1, A16_6, A16_7, A16_8, A16_9, A16_13, A16_14, A16_15],
        [k1, k(6), k(7), k(8), k(9), k(13), &*k14, &*k15],
        &mut ys,
    );
    rhs.eval(&ys, k16);
    dop853_poly_into(d, comps, y, y1, k1, hh, kk, extra);
}

/// DOP853's interpolant on the lanes from the stages and the three extra stages `extra` (see
/// [`dop853_dense_into`]), for the components `comps`, into `d`: Hairer's `contd8` coefficients, operation
/// for operation those of the scalar `dop853::poly`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dop853_poly_into<const C: usize, const N: usize>(
    d: &mut LaneDense<C, N>,
    comps: &[usize; C],
    y: &Vw<N>,
    y1: &Vw<N>,
    k1: &Vw<N>,
    hh: &Lw<N>,
    kk: &[Vw<N>; 16],
    extra: &[Vw<N>; 3],
) {
    let k = |j: usize| &kk[j - 1];
    let [k14, k15, k16] = extra;
    let st = [k1, k(6), k(7), k(8), k(9), k(10), k(11), k(12), k(13), k14, k15, k16];
    let rows = [
        [D4_1, D4_6, D4_7, D4_8, D4_9, D4_10, D4_11, D4_12, D4_13, D4_14, D4_15, D4_16],
        [D5_1, D5_6, D5_7, D5_8, D5_9, D5_10, D5_11, D5_12, D5_13, D5_14, D5_15, D5_16],
        [D6_1, D6_6, D6_7, D6_8, D6_9, D6_10, D6_11, D6_12, D6_13, D6_14, D6_15, D6_16],
        [D7_1, D7_6, D7_7, D7_8, D7_9, D7_10, D7_11, D7_12, D7_13, D7_14, D7_15, D7_16],
    ];
    d.eight = true;
    for (j, &i) in comps.iter().enumerate() {
        for l in 0..N {
            let h = hh[l];
            let dy = y1[i][l] - y[i][l];
            d.y0[j][l] = y[i][l];
            d.c[0][j][l] = dy;
            d.c[1][j][l] = k1[i][l] * h - dy;
            d.c[2][j][l] = dy * 2.0 - (k1[i][l] + k(13)[i][l]) * h;
        }
    }
    // Component by component, the four rows at once: four independent sums (each in the scalar
    // `weighted`'s order, `0 + (a_1 h) k_1 + ... + (a_12 h) k_12`) held in registers, each stage
    // row loaded once for all four. Row by row over all components at once, LLVM kept the C sums
    // in memory (a loop over the components, not unrolled) and every add waited on a store; with
    // a loop over the four rows, at 16 lanes that loop was not unrolled and the sums went back to
    // memory too (a fifth of a 501-sample run). Hence four named sums in one lane loop.
    for (j, &i) in comps.iter().enumerate() {
        let (mut s0, mut s1, mut s2, mut s3) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
        for m in 0..12 {
            let km = &st[m][i];
            let (a0, a1, a2, a3) = (rows[0][m], rows[1][m], rows[2][m], rows[3][m]);
            for l in 0..N {
                s0[l] += (a0 * hh[l]) * km[l];
                s1[l] += (a1 * hh[l]) * km[l];
                s2[l] += (a2 * hh[l]) * km[l];
                s3[l] += (a3 * hh[l]) * km[l];
            }
        }
        d.c[3][j] = s0;
        d.c[4][j] = s1;
        d.c[5][j] = s2;
        d.c[6][j] = s3;
    }
}

mod samples;
pub(crate) use samples::{sample_lanes, Row, Rows};

#[cfg(test)]
mod tests;
