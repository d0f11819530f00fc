//! The slider on the lanes: per-lane coefficients, the right-hand side of MODEL.md §2-3 for
//! bilateral or unilateral contact and the constant or Coulomb/Stribeck law, the event functions
//! (`model::Slider::events`) and the scalar driver's hidden-crossing check, on `N` trajectories
//! at once.

use crate::model::{event, idx, Slider};
use crate::ode::lanes::{cross, exp_lanes, splat, LaneDense, LaneRhs, Lw, Vw};

/// Event functions of the slider (gap, law normal force, sliding velocity, escape).
pub(super) const NE: usize = 4;

/// The components the event functions read (z, zd, xd, phi, phid): the lane interpolants are
/// built for these only.
pub(super) const EV_COMPS: [usize; 5] = [idx::Z, idx::ZD, idx::XD, idx::PHI, idx::PHID];
/// Under constant friction the sliding velocity is no event (`Slider::events`): the contact and
/// escape functions read z, zd and phi only, and the interpolants need no more.
pub(super) const EV_COMPS_CONST: [usize; 3] = [idx::Z, idx::ZD, idx::PHI];

/// Per-lane coefficients of the right-hand side and the tolerances (shared with `batch`).
#[derive(Clone, Copy)]
pub(crate) struct Coef<const N: usize> {
    pub(crate) ks: Lw<N>,
    pub(crate) ka: Lw<N>,
    pub(crate) c: Lw<N>,
    pub(crate) kphi: Lw<N>,
    pub(crate) mu: Lw<N>,
    pub(crate) inv_m: Lw<N>,
    pub(crate) wz2: Lw<N>,
    pub(crate) dz: Lw<N>,
    pub(crate) wx2: Lw<N>,
    pub(crate) dx: Lw<N>,
    pub(crate) wt2: Lw<N>,
    pub(crate) dt: Lw<N>,
    /// s L / I
    pub(crate) tg: Lw<N>,
    pub(crate) atol: Vw<N>,
    /// F_st, z_st, V, s L, escape limit.
    pub(crate) fst: Lw<N>,
    pub(crate) zst: Lw<N>,
    pub(crate) v: Lw<N>,
    pub(crate) sl: Lw<N>,
    pub(crate) esc: Lw<N>,
    /// Stribeck law: mu_k, mu_s - mu_k, 1/v_s, 1/eps, mu(V) F_st tanh(V/eps).
    pub(crate) mu_k: Lw<N>,
    pub(crate) dmu: Lw<N>,
    pub(crate) inv_vs: Lw<N>,
    pub(crate) inv_eps: Lw<N>,
    pub(crate) stat: Lw<N>,
}

impl<const N: usize> Coef<N> {
    pub(crate) fn zero() -> Self {
        let z = [0.0; N];
        Coef {
            ks: z,
            ka: z,
            c: z,
            kphi: z,
            mu: z,
            inv_m: z,
            wz2: z,
            dz: z,
            wx2: z,
            dx: z,
            wt2: z,
            dt: z,
            tg: z,
            atol: [splat(1.0); 6],
            fst: z,
            zst: z,
            v: z,
            sl: z,
            esc: splat(f64::INFINITY),
            mu_k: z,
            dmu: z,
            inv_vs: z,
            inv_eps: z,
            stat: z,
        }
    }

    pub(crate) fn set(&mut self, l: usize, s: &Slider, atol: &[f64; 6]) {
        let p = &s.p;
        let (wz, wx, wt) = (p.omega_normal, p.omega_friction, p.omega_torsion);
        self.ks[l] = s.k_s;
        self.ka[l] = p.contact_quadratic;
        self.c[l] = p.contact_damping;
        self.kphi[l] = p.twist_coupling;
        self.mu[l] = p.mu;
        self.inv_m[l] = 1.0 / p.mass;
        self.wz2[l] = wz * wz;
        self.dz[l] = 2.0 * p.zeta_normal * wz;
        self.wx2[l] = wx * wx;
        self.dx[l] = 2.0 * p.zeta_friction * wx;
        self.wt2[l] = wt * wt;
        self.dt[l] = 2.0 * p.zeta_torsion * wt;
        self.tg[l] = p.torsion_sign * p.moment_arm / p.inertia;
        for i in 0..6 {
            self.atol[i][l] = atol[i];
        }
        self.fst[l] = p.normal_load;
        self.zst[l] = s.z_st;
        self.v[l] = p.sliding_speed;
        self.sl[l] = p.torsion_sign * p.moment_arm;
        self.esc[l] = p.escape_limit;
        self.mu_k[l] = s.mu_k;
        self.dmu[l] = p.mu_static - s.mu_k;
        self.inv_vs[l] = 1.0 / p.stribeck_velocity;
        self.inv_eps[l] = 1.0 / p.friction_regularization;
        // The scalar law's static friction force, mu(V) F_st tanh(V/eps).
        self.stat[l] = s.mu_of(p.sliding_speed) * p.normal_load * (p.sliding_speed / p.friction_regularization).tanh();
    }
}

/// Right-hand side of the `N` lanes and the dynamic law force `F_z` of each (the force the
/// contact law gives, whether or not it acts). `UNI`: unilateral contact (the mask `contact`
/// selects the law force or no normal force); `COUL`: the regularised Coulomb/Stribeck law.
#[inline(always)]
pub(super) fn rhs<const UNI: bool, const COUL: bool, const N: usize>(
    c: &Coef<N>,
    contact: &[bool; N],
    y: &Vw<N>,
    out: &mut Vw<N>,
    fzl: &mut Lw<N>,
) {
    let mut fz = [0.0; N];
    for l in 0..N {
        let (z, zd, ph) = (y[0][l], y[1][l], y[4][l]);
        let f = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
        fzl[l] = f;
        fz[l] = if UNI && !contact[l] { -c.fst[l] } else { f };
    }
    let mut fx = [0.0; N];
    if COUL {
        let mut a = [0.0; N];
        let mut b = [0.0; N];
        let mut vr = [0.0; N];
        for l in 0..N {
            let v = c.v[l] - (y[3][l] + c.sl[l] * y[5][l]);
            vr[l] = v;
            a[l] = -v.abs() * c.inv_vs[l];
            b[l] = -2.0 * (v * c.inv_eps[l]).abs();
        }
        let ea = exp_lanes(&a);
        let eb = exp_lanes(&b);
        for l in 0..N {
            let mu = c.mu_k[l] + c.dmu[l] * ea[l];
            // tanh(v/eps) = sign(v) (1 - e^{-2|v|/eps}) / (1 + e^{-2|v|/eps}).
            let th = ((1.0 - eb[l]) / (1.0 + eb[l])).copysign(vr[l]);
            let normal = c.fst[l] + fz[l];
            fx[l] = mu * normal * th - c.stat[l];
        }
    } else {
        for l in 0..N {
            fx[l] = c.mu[l] * fz[l];
        }
    }
    for l in 0..N {
        let (z, zd, x, xd, ph, phd) = (y[0][l], y[1][l], y[2][l], y[3][l], y[4][l], y[5][l]);
        out[0][l] = zd;
        out[1][l] = fz[l] * c.inv_m[l] - c.dz[l] * zd - c.wz2[l] * z;
        out[2][l] = xd;
        out[3][l] = fx[l] * c.inv_m[l] - c.dx[l] * xd - c.wx2[l] * x;
        out[4][l] = phd;
        out[5][l] = c.tg[l] * fx[l] - c.dt[l] * phd - c.wt2[l] * ph;
    }
}

/// [`rhs`] as the lane kit's [`LaneRhs`]: the law force of the last evaluation is left in `fzl`.
pub(super) struct SliderRhs<'a, const UNI: bool, const COUL: bool, const N: usize> {
    pub(super) c: &'a Coef<N>,
    pub(super) contact: &'a [bool; N],
    pub(super) fzl: &'a mut Lw<N>,
}

impl<const UNI: bool, const COUL: bool, const N: usize> LaneRhs<N> for SliderRhs<'_, UNI, COUL, N> {
    #[inline(always)]
    fn eval(&mut self, y: &Vw<N>, out: &mut Vw<N>) {
        rhs::<UNI, COUL, N>(self.c, self.contact, y, out, self.fzl);
    }
}

/// The slider's event functions on the lanes (`model::Slider::events`), from the state and the
/// dynamic law force.
#[inline(always)]
pub(super) fn events_lanes<const COUL: bool, const N: usize>(c: &Coef<N>, y: &Vw<N>, fzl: &Lw<N>, g: &mut [Lw<N>; NE]) {
    for l in 0..N {
        g[event::GAP][l] = c.zst[l] + y[idx::Z][l];
        g[event::NORMAL][l] = c.fst[l] + fzl[l];
        // No event under the constant law (see `Slider::events`).
        g[event::SLIP][l] = if COUL { c.v[l] - (y[idx::XD][l] + c.sl[l] * y[idx::PHID][l]) } else { 1.0 };
        g[event::ESCAPE][l] = c.esc[l] - y[idx::Z][l].abs();
    }
}

/// The event functions of lane `l` from its interpolant's components there: EV_COMPS (5 values,
/// speed-dependent friction) or EV_COMPS_CONST (3: z, zd, phi), as `Slider::events` computes them.
#[inline(always)]
pub(super) fn events_at<const COUL: bool, const N: usize>(c: &Coef<N>, v: &[f64], l: usize) -> [f64; NE] {
    let n = v.len();
    let (ip, ixd, iphd) = if n == 5 { (3, 2, 4) } else { (2, usize::MAX, usize::MAX) };
    let at = |k: usize| if k < n { v[k] } else { 0.0 };
    let (z, zd, ph) = (v[0], v[1], at(ip));
    let fz = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
    let mut g = [0.0; NE];
    g[event::GAP] = c.zst[l] + z;
    g[event::NORMAL] = c.fst[l] + fz;
    g[event::SLIP] = if COUL { c.v[l] - (at(ixd) + c.sl[l] * at(iphd)) } else { 1.0 };
    g[event::ESCAPE] = c.esc[l] - z.abs();
    g
}

/// The scalar driver's hidden-crossing check on all lanes at once: at the three interior points
/// `x = 1/4, 1/2, 3/4` of each accepted step's interpolant and at each lane's own turning point
/// `turn[l]` (0: none; see `run::near_events`), an event function that is not pending and differs
/// in sign from the step start while the step end does not. `hidden[l]` becomes the earliest such
/// `x` (0 where none).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn hidden_crossings<const COUL: bool, const C: usize, const N: usize>(
    c: &Coef<N>,
    dense: &LaneDense<C, N>,
    g0: &[Lw<N>; NE],
    g1: &[Lw<N>; NE],
    pend: &[[bool; N]; NE],
    ok: &[bool; N],
    turn: &Lw<N>,
    hidden: &mut Lw<N>,
) {
    let g_at = |v: [f64; C], l: usize| events_at::<COUL, N>(c, &v, l);
    let hit_of = |g: &[f64; NE], l: usize| {
        let mut hit = false;
        for e in 0..NE {
            hit |= !pend[e][l] & cross(g0[e][l], g[e]) & !cross(g0[e][l], g1[e][l]);
        }
        hit
    };
    let mut found = [false; N];
    for q in 1..=3 {
        let th = q as f64 / 4.0;
        let v = dense.eval(th);
        for l in 0..N {
            let g = g_at(std::array::from_fn(|k| v[k][l]), l);
            let take = hit_of(&g, l) & ok[l] & !found[l];
            hidden[l] = if take { th } else { hidden[l] };
            found[l] |= take;
        }
    }
    for l in 0..N {
        let x = turn[l];
        if x > 0.0 && ok[l] && !(found[l] && hidden[l] <= x) {
            let v = dense.eval_lane(l, x);
            if hit_of(&g_at(v, l), l) {
                hidden[l] = x;
            }
        }
    }
}
