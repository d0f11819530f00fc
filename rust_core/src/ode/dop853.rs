//! Hairer's DOP853: the explicit Runge–Kutta method of order 8 by Dormand & Prince with Hairer's
//! 5th- and 3rd-order embedded estimators combined (`err5^2 / sqrt(err5^2 + 0.01 err3^2)`, which
//! behaves as `h^8`), 12 stages per step plus `f(t + h, y_new)` (reused as the next step's first
//! stage), and the 7th-order continuous extension that needs three extra stages.
//!
//! The three extra stages cost three right-hand sides per step; they are computed lazily, the
//! first time the step's dense output is evaluated (by an observer or the event locator), so runs
//! that never interpolate do not pay for them. The driver adds them to `Stats::n_rhs`.
//!
//! Coefficients: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.5, and Hairer's `dop853.f`, as
//! transcribed (numbers only) from SciPy's `dop853_coefficients.py`. The constant names follow
//! that table with 1-based indices: `A{i}_{j}` is `a_ij`, row 13 holds the weights `b_j`,
//! rows 14-16 the extra dense stages, `D{r}_{j}` the interpolant's coefficients, `ER_j` the 5th-order
//! error weights and `BHH_j` the 3rd-order weights (subtracted from `b_j`).
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

use super::stepper::{combine, weighted, StepDense, Stepper};
use super::{Dense, OdeSystem, Stats};
use nalgebra::SVector;
use std::cell::{Cell, OnceCell};

pub(crate) const C2: f64 = 0.526001519587677318785587544488e-01;
pub(crate) const C3: f64 = 0.789002279381515978178381316732e-01;
pub(crate) const C4: f64 = 0.118350341907227396726757197510;
pub(crate) const C5: f64 = 0.281649658092772603273242802490;
pub(crate) const C6: f64 = 0.333333333333333333333333333333;
pub(crate) const C7: f64 = 0.25;
pub(crate) const C8: f64 = 0.307692307692307692307692307692;
pub(crate) const C9: f64 = 0.651282051282051282051282051282;
pub(crate) const C10: f64 = 0.6;
pub(crate) const C11: f64 = 0.857142857142857142857142857142;
pub(crate) const C14: f64 = 0.1;
pub(crate) const C15: f64 = 0.2;
pub(crate) const C16: f64 = 0.777777777777777777777777777778;
pub(crate) const A2_1: f64 = 5.26001519587677318785587544488e-2;
pub(crate) const A3_1: f64 = 1.97250569845378994544595329183e-2;
pub(crate) const A3_2: f64 = 5.91751709536136983633785987549e-2;
pub(crate) const A4_1: f64 = 2.95875854768068491816892993775e-2;
pub(crate) const A4_3: f64 = 8.87627564304205475450678981324e-2;
pub(crate) const A5_1: f64 = 2.41365134159266685502369798665e-1;
pub(crate) const A5_3: f64 = -8.84549479328286085344864962717e-1;
pub(crate) const A5_4: f64 = 9.24834003261792003115737966543e-1;
pub(crate) const A6_1: f64 = 3.7037037037037037037037037037e-2;
pub(crate) const A6_4: f64 = 1.70828608729473871279604482173e-1;
pub(crate) const A6_5: f64 = 1.25467687566822425016691814123e-1;
pub(crate) const A7_1: f64 = 3.7109375e-2;
pub(crate) const A7_4: f64 = 1.70252211019544039314978060272e-1;
pub(crate) const A7_5: f64 = 6.02165389804559606850219397283e-2;
pub(crate) const A7_6: f64 = -1.7578125e-2;
pub(crate) const A8_1: f64 = 3.70920001185047927108779319836e-2;
pub(crate) const A8_4: f64 = 1.70383925712239993810214054705e-1;
pub(crate) const A8_5: f64 = 1.07262030446373284651809199168e-1;
pub(crate) const A8_6: f64 = -1.53194377486244017527936158236e-2;
pub(crate) const A8_7: f64 = 8.27378916381402288758473766002e-3;
pub(crate) const A9_1: f64 = 6.24110958716075717114429577812e-1;
pub(crate) const A9_4: f64 = -3.36089262944694129406857109825;
pub(crate) const A9_5: f64 = -8.68219346841726006818189891453e-1;
pub(crate) const A9_6: f64 = 2.75920996994467083049415600797e1;
pub(crate) const A9_7: f64 = 2.01540675504778934086186788979e1;
pub(crate) const A9_8: f64 = -4.34898841810699588477366255144e1;
pub(crate) const A10_1: f64 = 4.77662536438264365890433908527e-1;
pub(crate) const A10_4: f64 = -2.48811461997166764192642586468;
pub(crate) const A10_5: f64 = -5.90290826836842996371446475743e-1;
pub(crate) const A10_6: f64 = 2.12300514481811942347288949897e1;
pub(crate) const A10_7: f64 = 1.52792336328824235832596922938e1;
pub(crate) const A10_8: f64 = -3.32882109689848629194453265587e1;
pub(crate) const A10_9: f64 = -2.03312017085086261358222928593e-2;
pub(crate) const A11_1: f64 = -9.3714243008598732571704021658e-1;
pub(crate) const A11_4: f64 = 5.18637242884406370830023853209;
pub(crate) const A11_5: f64 = 1.09143734899672957818500254654;
pub(crate) const A11_6: f64 = -8.14978701074692612513997267357;
pub(crate) const A11_7: f64 = -1.85200656599969598641566180701e1;
pub(crate) const A11_8: f64 = 2.27394870993505042818970056734e1;
pub(crate) const A11_9: f64 = 2.49360555267965238987089396762;
pub(crate) const A11_10: f64 = -3.0467644718982195003823669022;
pub(crate) const A12_1: f64 = 2.27331014751653820792359768449;
pub(crate) const A12_4: f64 = -1.05344954667372501984066689879e1;
pub(crate) const A12_5: f64 = -2.00087205822486249909675718444;
pub(crate) const A12_6: f64 = -1.79589318631187989172765950534e1;
pub(crate) const A12_7: f64 = 2.79488845294199600508499808837e1;
pub(crate) const A12_8: f64 = -2.85899827713502369474065508674;
pub(crate) const A12_9: f64 = -8.87285693353062954433549289258;
pub(crate) const A12_10: f64 = 1.23605671757943030647266201528e1;
pub(crate) const A12_11: f64 = 6.43392746015763530355970484046e-1;
pub(crate) const A13_1: f64 = 5.42937341165687622380535766363e-2;
pub(crate) const A13_6: f64 = 4.45031289275240888144113950566;
pub(crate) const A13_7: f64 = 1.89151789931450038304281599044;
pub(crate) const A13_8: f64 = -5.8012039600105847814672114227;
pub(crate) const A13_9: f64 = 3.1116436695781989440891606237e-1;
pub(crate) const A13_10: f64 = -1.52160949662516078556178806805e-1;
pub(crate) const A13_11: f64 = 2.01365400804030348374776537501e-1;
pub(crate) const A13_12: f64 = 4.47106157277725905176885569043e-2;
pub(crate) const A14_1: f64 = 5.61675022830479523392909219681e-2;
pub(crate) const A14_7: f64 = 2.53500210216624811088794765333e-1;
pub(crate) const A14_8: f64 = -2.46239037470802489917441475441e-1;
pub(crate) const A14_9: f64 = -1.24191423263816360469010140626e-1;
pub(crate) const A14_10: f64 = 1.5329179827876569731206322685e-1;
pub(crate) const A14_11: f64 = 8.20105229563468988491666602057e-3;
pub(crate) const A14_12: f64 = 7.56789766054569976138603589584e-3;
pub(crate) const A14_13: f64 = -8.298e-3;
pub(crate) const A15_1: f64 = 3.18346481635021405060768473261e-2;
pub(crate) const A15_6: f64 = 2.83009096723667755288322961402e-2;
pub(crate) const A15_7: f64 = 5.35419883074385676223797384372e-2;
pub(crate) const A15_8: f64 = -5.49237485713909884646569340306e-2;
pub(crate) const A15_11: f64 = -1.08347328697249322858509316994e-4;
pub(crate) const A15_12: f64 = 3.82571090835658412954920192323e-4;
pub(crate) const A15_13: f64 = -3.40465008687404560802977114492e-4;
pub(crate) const A15_14: f64 = 1.41312443674632500278074618366e-1;
pub(crate) const A16_1: f64 = -4.28896301583791923408573538692e-1;
pub(crate) const A16_6: f64 = -4.69762141536116384314449447206;
pub(crate) const A16_7: f64 = 7.68342119606259904184240953878;
pub(crate) const A16_8: f64 = 4.06898981839711007970213554331;
pub(crate) const A16_9: f64 = 3.56727187455281109270669543021e-1;
pub(crate) const A16_13: f64 = -1.39902416515901462129418009734e-3;
pub(crate) const A16_14: f64 = 2.9475147891527723389556272149;
pub(crate) const A16_15: f64 = -9.15095847217987001081870187138;
pub(crate) const BHH_1: f64 = 0.244094488188976377952755905512;
pub(crate) const BHH_9: f64 = 0.733846688281611857341361741547;
pub(crate) const BHH_12: f64 = 0.220588235294117647058823529412e-1;
pub(crate) const D4_1: f64 = -0.84289382761090128651353491142e+1;
pub(crate) const D4_6: f64 = 0.56671495351937776962531783590;
pub(crate) const D4_7: f64 = -0.30689499459498916912797304727e+1;
pub(crate) const D4_8: f64 = 0.23846676565120698287728149680e+1;
pub(crate) const D4_9: f64 = 0.21170345824450282767155149946e+1;
pub(crate) const D4_10: f64 = -0.87139158377797299206789907490;
pub(crate) const D4_11: f64 = 0.22404374302607882758541771650e+1;
pub(crate) const D4_12: f64 = 0.63157877876946881815570249290;
pub(crate) const D4_13: f64 = -0.88990336451333310820698117400e-1;
pub(crate) const D4_14: f64 = 0.18148505520854727256656404962e+2;
pub(crate) const D4_15: f64 = -0.91946323924783554000451984436e+1;
pub(crate) const D4_16: f64 = -0.44360363875948939664310572000e+1;
pub(crate) const D5_1: f64 = 0.10427508642579134603413151009e+2;
pub(crate) const D5_6: f64 = 0.24228349177525818288430175319e+3;
pub(crate) const D5_7: f64 = 0.16520045171727028198505394887e+3;
pub(crate) const D5_8: f64 = -0.37454675472269020279518312152e+3;
pub(crate) const D5_9: f64 = -0.22113666853125306036270938578e+2;
pub(crate) const D5_10: f64 = 0.77334326684722638389603898808e+1;
pub(crate) const D5_11: f64 = -0.30674084731089398182061213626e+2;
pub(crate) const D5_12: f64 = -0.93321305264302278729567221706e+1;
pub(crate) const D5_13: f64 = 0.15697238121770843886131091075e+2;
pub(crate) const D5_14: f64 = -0.31139403219565177677282850411e+2;
pub(crate) const D5_15: f64 = -0.93529243588444783865713862664e+1;
pub(crate) const D5_16: f64 = 0.35816841486394083752465898540e+2;
pub(crate) const D6_1: f64 = 0.19985053242002433820987653617e+2;
pub(crate) const D6_6: f64 = -0.38703730874935176555105901742e+3;
pub(crate) const D6_7: f64 = -0.18917813819516756882830838328e+3;
pub(crate) const D6_8: f64 = 0.52780815920542364900561016686e+3;
pub(crate) const D6_9: f64 = -0.11573902539959630126141871134e+2;
pub(crate) const D6_10: f64 = 0.68812326946963000169666922661e+1;
pub(crate) const D6_11: f64 = -0.10006050966910838403183860980e+1;
pub(crate) const D6_12: f64 = 0.77771377980534432092869265740;
pub(crate) const D6_13: f64 = -0.27782057523535084065932004339e+1;
pub(crate) const D6_14: f64 = -0.60196695231264120758267380846e+2;
pub(crate) const D6_15: f64 = 0.84320405506677161018159903784e+2;
pub(crate) const D6_16: f64 = 0.11992291136182789328035130030e+2;
pub(crate) const D7_1: f64 = -0.25693933462703749003312586129e+2;
pub(crate) const D7_6: f64 = -0.15418974869023643374053993627e+3;
pub(crate) const D7_7: f64 = -0.23152937917604549567536039109e+3;
pub(crate) const D7_8: f64 = 0.35763911791061412378285349910e+3;
pub(crate) const D7_9: f64 = 0.93405324183624310003907691704e+2;
pub(crate) const D7_10: f64 = -0.37458323136451633156875139351e+2;
pub(crate) const D7_11: f64 = 0.10409964950896230045147246184e+3;
pub(crate) const D7_12: f64 = 0.29840293426660503123344363579e+2;
pub(crate) const D7_13: f64 = -0.43533456590011143754432175058e+2;
pub(crate) const D7_14: f64 = 0.96324553959188282948394950600e+2;
pub(crate) const D7_15: f64 = -0.39177261675615439165231486172e+2;
pub(crate) const D7_16: f64 = -0.14972683625798562581422125276e+3;
pub(crate) const ER_1: f64 = 0.1312004499419488073250102996e-1;
pub(crate) const ER_6: f64 = -0.1225156446376204440720569753e+1;
pub(crate) const ER_7: f64 = -0.4957589496572501915214079952;
pub(crate) const ER_8: f64 = 0.1664377182454986536961530415e+1;
pub(crate) const ER_9: f64 = -0.3503288487499736816886487290;
pub(crate) const ER_10: f64 = 0.3341791187130174790297318841;
pub(crate) const ER_11: f64 = 0.8192320648511571246570742613e-1;
pub(crate) const ER_12: f64 = -0.2235530786388629525884427845e-1;

// 3rd-order error weights: b_j - bhh_j (only the three bhh above are nonzero).
pub(crate) const E3_1: f64 = A13_1 - BHH_1;
pub(crate) const E3_9: f64 = A13_9 - BHH_9;
pub(crate) const E3_12: f64 = A13_12 - BHH_12;

/// The DOP853 stepper: stages `k1..k12` of the last attempted step and, once accepted,
/// `k13 = f(t + h, y_new)`.
pub(crate) struct Dop853<const N: usize> {
    k: [SVector<f64, N>; 13],
}

/// DOP853's interpolant on one step. The polynomial's coefficients (which need the three extra
/// stages) are computed on first use and cached.
pub(crate) struct Dop853Dense<'a, const N: usize, S: OdeSystem<N>> {
    sys: &'a S,
    mode: S::Mode,
    /// The step's stages (`None` where the coefficients came with the interpolant).
    k: Option<&'a [SVector<f64, N>; 13]>,
    /// The right-hand side at both ends (the stages `k[0]` and `k[12]`).
    ends: (SVector<f64, N>, SVector<f64, N>),
    y0: &'a SVector<f64, N>,
    y1: &'a SVector<f64, N>,
    t0: f64,
    h: f64,
    cont: OnceCell<[SVector<f64, N>; 7]>,
    extra: Cell<u64>,
}

impl<'a, const N: usize, S: OdeSystem<N>> Dop853Dense<'a, N, S> {
    /// The interpolant of a step from its stages (`k[12]`: the derivative at `y1`), for the
    /// lane-batched driver's cold paths; the three extra stages are computed on first use.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn from_stages(
        sys: &'a S,
        mode: S::Mode,
        k: &'a [SVector<f64, N>; 13],
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
        t0: f64,
        h: f64,
    ) -> Self {
        let ends = (k[0], k[12]);
        Dop853Dense { sys, mode, k: Some(k), ends, y0, y1, t0, h, cont: OnceCell::new(), extra: Cell::new(0) }
    }

    /// The interpolant of a step from its polynomial's coefficients `c0..c6` (Hairer's `contd8`,
    /// as [`poly`] computes them; the lanes compute them for all their lanes at once, operation
    /// for operation the same): no right-hand side is evaluated. `ends`: the right-hand side at
    /// both ends (the stages `k[0]` and `k[12]` of [`Self::from_stages`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn from_coefficients(
        sys: &'a S,
        mode: S::Mode,
        cont: [SVector<f64, N>; 7],
        ends: (SVector<f64, N>, SVector<f64, N>),
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
        t0: f64,
        h: f64,
    ) -> Self {
        Dop853Dense { sys, mode, k: None, ends, y0, y1, t0, h, cont: OnceCell::from(cont), extra: Cell::new(0) }
    }

    fn coefficients(&self) -> [SVector<f64, N>; 7] {
        let k = self.k.expect("the stages, where the coefficients were not given");
        let (t, h, y) = (self.t0, self.h, self.y0);
        let k14 = self.sys.rhs(
            t + C14 * h,
            &combine(
                y,
                h,
                [A14_1, A14_7, A14_8, A14_9, A14_10, A14_11, A14_12, A14_13],
                [&k[0], &k[6], &k[7], &k[8], &k[9], &k[10], &k[11], &k[12]],
            ),
            self.mode,
        );
        let k15 = self.sys.rhs(
            t + C15 * h,
            &combine(
                y,
                h,
                [A15_1, A15_6, A15_7, A15_8, A15_11, A15_12, A15_13, A15_14],
                [&k[0], &k[5], &k[6], &k[7], &k[10], &k[11], &k[12], &k14],
            ),
            self.mode,
        );
        let k16 = self.sys.rhs(
            t + C16 * h,
            &combine(
                y,
                h,
                [A16_1, A16_6, A16_7, A16_8, A16_9, A16_13, A16_14, A16_15],
                [&k[0], &k[5], &k[6], &k[7], &k[8], &k[12], &k14, &k15],
            ),
            self.mode,
        );
        self.extra.set(3);
        poly(k, &[k14, k15, k16], y, self.y1, h)
    }
}

/// Hairer's `contd8` coefficients of a step of size `h` from `y0` to `y1`, from its stages `k`
/// (`k[12]`: the derivative at `y1`) and the three extra stages.
fn poly<const N: usize>(
    k: &[SVector<f64, N>; 13],
    [k14, k15, k16]: &[SVector<f64, N>; 3],
    y0: &SVector<f64, N>,
    y1: &SVector<f64, N>,
    h: f64,
) -> [SVector<f64, N>; 7] {
    let dy = y1 - y0;
    let f1 = k[0] * h - dy;
    let f2 = dy * 2.0 - (k[0] + k[12]) * h;
    let stages = [&k[0], &k[5], &k[6], &k[7], &k[8], &k[9], &k[10], &k[11], &k[12], k14, k15, k16];
    let row = |d: [f64; 12]| weighted(d.map(|x| x * h), stages);
    let f3 = row([D4_1, D4_6, D4_7, D4_8, D4_9, D4_10, D4_11, D4_12, D4_13, D4_14, D4_15, D4_16]);
    let f4 = row([D5_1, D5_6, D5_7, D5_8, D5_9, D5_10, D5_11, D5_12, D5_13, D5_14, D5_15, D5_16]);
    let f5 = row([D6_1, D6_6, D6_7, D6_8, D6_9, D6_10, D6_11, D6_12, D6_13, D6_14, D6_15, D6_16]);
    let f6 = row([D7_1, D7_6, D7_7, D7_8, D7_9, D7_10, D7_11, D7_12, D7_13, D7_14, D7_15, D7_16]);
    [dy, f1, f2, f3, f4, f5, f6]
}

impl<const N: usize, S: OdeSystem<N>> Dop853Dense<'_, N, S> {
    /// The components `i` with `keep(i)` at `t` (zeros elsewhere):
    /// y0 + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + x (F4 + (1-x) (F5 + x F6)))))), component
    /// by component (the lanes' `LaneDense` evaluates the same operations).
    #[inline(always)]
    fn eval_where(&self, t: f64, keep: impl Fn(usize) -> bool) -> SVector<f64, N> {
        let c = self.cont.get_or_init(|| self.coefficients());
        let x = (t - self.t0) / self.h;
        let x1 = 1.0 - x;
        SVector::from_fn(|i, _| {
            if !keep(i) {
                return 0.0;
            }
            let mut p = c[6][i] * x;
            p = (c[5][i] + p) * x1;
            p = (c[4][i] + p) * x;
            p = (c[3][i] + p) * x1;
            p = (c[2][i] + p) * x;
            p = (c[1][i] + p) * x1;
            p = (c[0][i] + p) * x;
            self.y0[i] + p
        })
    }
}

impl<const N: usize, S: OdeSystem<N>> Dense<N> for Dop853Dense<'_, N, S> {
    fn eval(&self, t: f64) -> SVector<f64, N> {
        self.eval_where(t, |_| true)
    }

    fn eval_some(&self, t: f64, reads: u64) -> SVector<f64, N> {
        // Beyond the 64 bits of `reads`, every component.
        self.eval_where(t, |i| i >= 64 || reads & (1 << i) != 0)
    }

    fn end_rates(&self) -> Option<super::EndRates<N>> {
        Some(((self.t0, self.t0 + self.h), self.ends))
    }
}

impl<const N: usize, S: OdeSystem<N>> StepDense<N> for Dop853Dense<'_, N, S> {
    fn extra_rhs(&self) -> u64 {
        self.extra.get()
    }
}

impl<const N: usize, S: OdeSystem<N>> Stepper<N, S> for Dop853<N> {
    const ORDER: u32 = 8;
    const ERR_EXP: u32 = 8;
    const BETA: f64 = 0.04;
    const PREDICTIVE: bool = false;

    type Dense<'a>
        = Dop853Dense<'a, N, S>
    where
        Self: 'a,
        S: 'a;

    fn new() -> Self {
        Dop853 { k: [SVector::zeros(); 13] }
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
        let k1 = *f;
        let k2 = sys.rhs(t + C2 * h, &combine(y, h, [A2_1], [&k1]), mode);
        let k3 = sys.rhs(t + C3 * h, &combine(y, h, [A3_1, A3_2], [&k1, &k2]), mode);
        let k4 = sys.rhs(t + C4 * h, &combine(y, h, [A4_1, A4_3], [&k1, &k3]), mode);
        let k5 = sys.rhs(t + C5 * h, &combine(y, h, [A5_1, A5_3, A5_4], [&k1, &k3, &k4]), mode);
        let k6 = sys.rhs(t + C6 * h, &combine(y, h, [A6_1, A6_4, A6_5], [&k1, &k4, &k5]), mode);
        let k7 = sys.rhs(t + C7 * h, &combine(y, h, [A7_1, A7_4, A7_5, A7_6], [&k1, &k4, &k5, &k6]), mode);
        let k8 = sys.rhs(t + C8 * h, &combine(y, h, [A8_1, A8_4, A8_5, A8_6, A8_7], [&k1, &k4, &k5, &k6, &k7]), mode);
        let k9 = sys.rhs(
            t + C9 * h,
            &combine(y, h, [A9_1, A9_4, A9_5, A9_6, A9_7, A9_8], [&k1, &k4, &k5, &k6, &k7, &k8]),
            mode,
        );
        let k10 = sys.rhs(
            t + C10 * h,
            &combine(y, h, [A10_1, A10_4, A10_5, A10_6, A10_7, A10_8, A10_9], [&k1, &k4, &k5, &k6, &k7, &k8, &k9]),
            mode,
        );
        let k11 = sys.rhs(
            t + C11 * h,
            &combine(
                y,
                h,
                [A11_1, A11_4, A11_5, A11_6, A11_7, A11_8, A11_9, A11_10],
                [&k1, &k4, &k5, &k6, &k7, &k8, &k9, &k10],
            ),
            mode,
        );
        let k12 = sys.rhs(
            t + h,
            &combine(
                y,
                h,
                [A12_1, A12_4, A12_5, A12_6, A12_7, A12_8, A12_9, A12_10, A12_11],
                [&k1, &k4, &k5, &k6, &k7, &k8, &k9, &k10, &k11],
            ),
            mode,
        );
        stats.n_rhs += 11;
        let used = [&k1, &k6, &k7, &k8, &k9, &k10, &k11, &k12];
        let y_new = combine(y, h, [A13_1, A13_6, A13_7, A13_8, A13_9, A13_10, A13_11, A13_12], used);
        let err5 = weighted([ER_1, ER_6, ER_7, ER_8, ER_9, ER_10, ER_11, ER_12], used);
        let err3 = weighted([E3_1, A13_6, A13_7, A13_8, E3_9, A13_10, A13_11, E3_12], used);
        self.k = [k1, k2, k3, k4, k5, k6, k7, k8, k9, k10, k11, k12, SVector::zeros()];
        // Hairer's combination: |h| e5^2 / sqrt(n (e5^2 + 0.01 e3^2)), e5^2 and e3^2 the sums of
        // squares of the components weighted by 1/sk. Summed with the lane path's operations
        // (`lanes::dop853_step`: `e^2 w`, `w = 1/sk^2`), so that both paths' estimates agree to the
        // bit where their stages do: after a switch the first steps' estimates are at rounding
        // level (1e-18), and any difference there steered the two paths onto different steps.
        let n = N as f64;
        let (mut s5, mut s3) = (0.0, 0.0);
        for i in 0..N {
            let sk = atol[i] + rtol * y[i].abs().max(y_new[i].abs());
            let w = 1.0 / (sk * sk);
            s5 += err5[i] * err5[i] * w;
            s3 += err3[i] * err3[i] * w;
        }
        let den = s5 + 0.01 * s3;
        let err = if den > 0.0 {
            h.abs() * s5 / (den * n).sqrt()
        } else if den == 0.0 {
            0.0
        } else {
            f64::NAN
        };
        (y_new, err)
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
        // Not FSAL in the strict sense: f(t + h, y_new) is a 13th evaluation, made only once the
        // step is accepted; it is stage 1 of the next step and a node of the interpolant.
        let f = sys.rhs(t + h, y_new, mode);
        stats.n_rhs += 1;
        self.k[12] = f;
        f
    }

    #[inline]
    fn dense<'a>(
        &'a self,
        sys: &'a S,
        mode: S::Mode,
        t: f64,
        h: f64,
        y0: &'a SVector<f64, N>,
        y1: &'a SVector<f64, N>,
    ) -> Dop853Dense<'a, N, S> {
        Dop853Dense::from_stages(sys, mode, &self.k, y0, y1, t, h)
    }
}
