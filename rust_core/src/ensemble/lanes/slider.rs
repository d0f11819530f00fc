//! The slider on the lanes: per-lane coefficients and modes, the right-hand side of MODEL.md
//! §2-3 for bilateral or unilateral contact and the constant, Coulomb/Stribeck (tanh) or switch
//! friction law, the event functions (`model::Slider::events`) and the scalar driver's
//! hidden-crossing check, on `N` trajectories at once.
//!
//! The friction law is the const generic `LAW` (`FrictionLaw as u8`: [`CONST`], [`TANH`],
//! [`SWITCH`]), so each law's copy of the loop carries only its own arithmetic.

use crate::model::{event, idx, ContactMode, FrictionLaw, Slider};
use crate::ode::lanes::{blend, cross, exp_lanes_by, splat, LaneDense, LaneRhs, Lw, Vw};

/// The constant law.
pub(super) const CONST: u8 = FrictionLaw::Constant as u8;
/// The regularised Coulomb/Stribeck law.
pub(super) const TANH: u8 = FrictionLaw::Coulomb as u8;
/// The switch law (Leine et al.).
pub(super) const SWITCH: u8 = FrictionLaw::Switch as u8;

/// Event functions of the slider, the most any law has: gap, law normal force, sliding
/// velocity, escape, and the switch law's band edges and stick bound. The lanes keep this many
/// per lane; a law's loop reads only its own [`n_events`].
pub(super) const NE: usize = 7;

/// The event functions of law `law` (`Slider::n_events`).
#[inline(always)]
pub(super) const fn n_events(law: u8) -> usize {
    if law == SWITCH {
        7
    } else {
        4
    }
}

/// The components the event functions of the Stribeck (tanh) law read (z, zd, xd, phi, phid):
/// the lane interpolants are built for these only.
pub(super) const EV_COMPS: [usize; 5] = [idx::Z, idx::ZD, idx::XD, idx::PHI, idx::PHID];
/// Under constant friction the sliding velocity is no event (`Slider::events`): the contact and
/// escape functions read z, zd and phi only, and the interpolants need no more. The switch law's
/// stick bound reads every component.
pub(super) const EV_COMPS_CONST: [usize; 3] = [idx::Z, idx::ZD, idx::PHI];

/// The mode of each lane (`ContactMode`) as masks the branch-free right-hand side selects by:
/// on the disk, and (switch law) sticking or in transition. Slip is in contact with neither.
#[derive(Clone, Copy)]
pub(super) struct Modes<const N: usize> {
    pub(super) contact: [bool; N],
    pub(super) stick: [bool; N],
    pub(super) trans: [bool; N],
    /// Slipping backwards (`ContactMode::SlipBack`): the slip force's sign is -1.
    pub(super) back: [bool; N],
}

impl<const N: usize> Modes<N> {
    pub(super) fn new() -> Self {
        Modes { contact: [true; N], stick: [false; N], trans: [false; N], back: [false; N] }
    }

    #[inline]
    pub(super) fn set(&mut self, l: usize, mode: ContactMode) {
        self.contact[l] = mode.in_contact();
        self.stick[l] = mode == ContactMode::Stick;
        self.trans[l] = mode == ContactMode::Transition;
        self.back[l] = mode == ContactMode::SlipBack;
    }

    /// The switch law's live event functions in lane `l` (`model::switch_live`): the band edges
    /// in slip and transition, the stick bound in stick and transition.
    #[inline(always)]
    fn live(&self, l: usize) -> (bool, bool) {
        (self.contact[l] & !self.stick[l], self.stick[l] | self.trans[l])
    }
}

/// Per-lane coefficients of the right-hand side and the tolerances (shared with `batch`), on
/// 64-byte boundaries (as `ode::lanes::Al`).
#[derive(Clone, Copy)]
#[repr(C, align(64))]
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
    /// Switch law: mu_s, the stick band eta, the effective mass of the sliding direction.
    pub(crate) mu_s: Lw<N>,
    pub(crate) eta: Lw<N>,
    pub(crate) meff: Lw<N>,
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
            mu_s: z,
            eta: z,
            meff: z,
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
        // The scalar law's static friction force, mu(V) F_st tanh(V/eps) (tanh law) or mu(V) F_st.
        self.stat[l] = s.static_friction();
        self.mu_s[l] = p.mu_static;
        self.eta[l] = p.stick_band;
        self.meff[l] = s.m_eff;
    }
}

/// The force that keeps `d v_r/dt = 0` in lane `l` (`Slider::stick_force`).
#[inline(always)]
fn stick_force<const N: usize>(c: &Coef<N>, y: &Vw<N>, l: usize) -> f64 {
    let a_x = -c.dx[l] * y[idx::XD][l] - c.wx2[l] * y[idx::X][l];
    let a_t = -c.dt[l] * y[idx::PHID][l] - c.wt2[l] * y[idx::PHI][l];
    -c.meff[l] * (a_x + c.sl[l] * a_t)
}

/// Right-hand side of the `N` lanes and the dynamic law force `F_z` of each (the force the
/// contact law gives, whether or not it acts). `UNI`: unilateral contact (the mask
/// `m.contact` selects the law force or no normal force); `LAW`: the friction law, the switch
/// law's regime selected per lane by the masks `m.stick` and `m.trans`.
#[inline(always)]
pub(super) fn rhs<const UNI: bool, const LAW: u8, const N: usize>(
    c: &Coef<N>,
    m: &Modes<N>,
    y: &Vw<N>,
    out: &mut Vw<N>,
    fzl: &mut Lw<N>,
) {
    let mut fz = [0.0; N];
    for l in 0..N {
        let (z, zd, ph) = (y[0][l], y[1][l], y[4][l]);
        let f = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
        fzl[l] = f;
        // Masks, not `if`: with a branch per lane the loop stayed scalar.
        fz[l] = if UNI { blend((m.contact[l] as u64).wrapping_neg(), f, -c.fst[l]) } else { f };
    }
    let mut fx = [0.0; N];
    if LAW == CONST {
        for l in 0..N {
            fx[l] = c.mu[l] * fz[l];
        }
    } else {
        let mut a = [0.0; N];
        let mut vr = [0.0; N];
        for l in 0..N {
            let v = c.v[l] - (y[3][l] + c.sl[l] * y[5][l]);
            vr[l] = v;
            // The switch law's slip field has its mode's sign, continued past v_r = 0
            // (`Slider::mu_signed`): sign v_r = |v_r| exactly wherever the signs agree.
            a[l] = if LAW == SWITCH {
                -blend((m.back[l] as u64).wrapping_neg(), -v, v) * c.inv_vs[l]
            } else {
                -v.abs() * c.inv_vs[l]
            };
        }
        let ea = exp_lanes_by::<true, N>(&a);
        if LAW == TANH {
            let mut b = [0.0; N];
            for l in 0..N {
                b[l] = -2.0 * (vr[l] * c.inv_eps[l]).abs();
            }
            let eb = exp_lanes_by::<true, N>(&b);
            for l in 0..N {
                let mu = c.mu_k[l] + c.dmu[l] * ea[l];
                // tanh(v/eps) = sign(v) (1 - e^{-2|v|/eps}) / (1 + e^{-2|v|/eps}).
                let th = ((1.0 - eb[l]) / (1.0 + eb[l])).copysign(vr[l]);
                let normal = c.fst[l] + fz[l];
                fx[l] = mu * normal * th - c.stat[l];
            }
        } else {
            // Slip: mu(v_r) N sign(v_r) (off the disk N = 0: the scalar's -mu(V) F_st); stick:
            // the force that holds v_r; transition: the static bound mu_s N sign(F_req).
            for l in 0..N {
                let mu = c.mu_k[l] + c.dmu[l] * ea[l];
                let normal = c.fst[l] + fz[l];
                let sg = blend((m.back[l] as u64).wrapping_neg(), -1.0, 1.0);
                let slip = mu * normal * sg - c.stat[l];
                let st = stick_force(c, y, l);
                let tr = c.mu_s[l] * normal * 1.0f64.copysign(st + c.stat[l]) - c.stat[l];
                // Selected by masks: written as `if stick {..} else if trans {..}`, LLVM kept a
                // branch per lane and this whole loop scalar (a third of a switch-law step).
                let (ms, mt) = ((m.stick[l] as u64).wrapping_neg(), (m.trans[l] as u64).wrapping_neg());
                fx[l] = blend(ms, st, blend(mt, tr, slip));
            }
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
pub(super) struct SliderRhs<'a, const UNI: bool, const LAW: u8, const N: usize> {
    pub(super) c: &'a Coef<N>,
    pub(super) m: &'a Modes<N>,
    pub(super) fzl: &'a mut Lw<N>,
}

impl<const UNI: bool, const LAW: u8, const N: usize> LaneRhs<N> for SliderRhs<'_, UNI, LAW, N> {
    #[inline(always)]
    fn eval(&mut self, y: &Vw<N>, out: &mut Vw<N>) {
        rhs::<UNI, LAW, N>(self.c, self.m, y, out, self.fzl);
    }
}

/// The switch law's three event functions of lane `l` (`Slider::switch_events`) from its sliding
/// velocity, law force and stick force.
#[inline(always)]
fn switch_events_of<const N: usize>(c: &Coef<N>, m: &Modes<N>, l: usize, vr: f64, fzl: f64, st: f64) -> [f64; 3] {
    let (band, bound) = m.live(l);
    let margin = c.mu_s[l] * (c.fst[l] + fzl) - (st + c.stat[l]).abs();
    [if band { vr - c.eta[l] } else { 1.0 }, if band { vr + c.eta[l] } else { 1.0 }, if bound { margin } else { 1.0 }]
}

/// The slider's event functions on the lanes (`model::Slider::events`), from the state and the
/// dynamic law force; the law's first [`n_events`] entries of `g` are written.
#[inline(always)]
pub(super) fn events_lanes<const LAW: u8, const N: usize>(
    c: &Coef<N>,
    m: &Modes<N>,
    y: &Vw<N>,
    fzl: &Lw<N>,
    g: &mut [Lw<N>; NE],
) {
    for l in 0..N {
        let vr = c.v[l] - (y[idx::XD][l] + c.sl[l] * y[idx::PHID][l]);
        g[event::GAP][l] = c.zst[l] + y[idx::Z][l];
        g[event::NORMAL][l] = c.fst[l] + fzl[l];
        // No event under the constant law (see `Slider::events`).
        g[event::SLIP][l] = if LAW != CONST { vr } else { 1.0 };
        g[event::ESCAPE][l] = c.esc[l] - y[idx::Z][l].abs();
        if LAW == SWITCH {
            let sw = switch_events_of(c, m, l, vr, fzl[l], stick_force(c, y, l));
            g[event::BAND_HI][l] = sw[0];
            g[event::BAND_LO][l] = sw[1];
            g[event::STICK][l] = sw[2];
        }
    }
}

/// The event functions of lane `l` from its interpolant's components there, as
/// `Slider::events` computes them: all six in order (switch law), EV_COMPS (5 values, the tanh
/// law) or EV_COMPS_CONST (3: z, zd, phi). Entries past the law's [`n_events`] are 1.
#[inline(always)]
pub(super) fn events_at<const LAW: u8, const N: usize>(c: &Coef<N>, m: &Modes<N>, v: &[f64], l: usize) -> [f64; NE] {
    let n = v.len();
    // Positions of x, xd, phi, phid in `v` (usize::MAX: not there).
    let (ix, ixd, ip, iphd) = match n {
        6 => (idx::X, idx::XD, idx::PHI, idx::PHID),
        5 => (usize::MAX, 2, 3, 4),
        _ => (usize::MAX, usize::MAX, 2, usize::MAX),
    };
    let at = |k: usize| if k < n { v[k] } else { 0.0 };
    let (z, zd, ph) = (v[0], v[1], at(ip));
    let fz = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
    let vr = c.v[l] - (at(ixd) + c.sl[l] * at(iphd));
    let mut g = [1.0; NE];
    g[event::GAP] = c.zst[l] + z;
    g[event::NORMAL] = c.fst[l] + fz;
    g[event::SLIP] = if LAW != CONST { vr } else { 1.0 };
    g[event::ESCAPE] = c.esc[l] - z.abs();
    if LAW == SWITCH {
        let (x, xd, phd) = (at(ix), at(ixd), at(iphd));
        let a_x = -c.dx[l] * xd - c.wx2[l] * x;
        let a_t = -c.dt[l] * phd - c.wt2[l] * ph;
        let st = -c.meff[l] * (a_x + c.sl[l] * a_t);
        let sw = switch_events_of(c, m, l, vr, fz, st);
        g[event::BAND_HI] = sw[0];
        g[event::BAND_LO] = sw[1];
        g[event::STICK] = sw[2];
    }
    g
}

/// [`events_at`] of every lane at once, from the interpolant's components `v` of all lanes: the
/// same operations lane by lane (so the same bits), written over whole lane rows with masks so
/// that they vectorise (the hidden-crossing check's three interior points, where `events_at`
/// called lane by lane was a tenth of a switch-law run's time).
#[inline(always)]
pub(super) fn events_at_lanes<const LAW: u8, const C: usize, const N: usize>(
    c: &Coef<N>,
    m: &Modes<N>,
    v: &[Lw<N>; C],
) -> [Lw<N>; NE] {
    // Positions of x, xd, phi, phid in `v` (usize::MAX: not there), as in `events_at`.
    let (ix, ixd, ip, iphd) = match C {
        6 => (idx::X, idx::XD, idx::PHI, idx::PHID),
        5 => (usize::MAX, 2, 3, 4),
        _ => (usize::MAX, usize::MAX, 2, usize::MAX),
    };
    let zero = [0.0; N];
    let at = |k: usize| if k < C { &v[k] } else { &zero };
    let (vx, vxd, vp, vphd) = (at(ix), at(ixd), at(ip), at(iphd));
    let mut g = [[1.0; N]; NE];
    for l in 0..N {
        let (z, zd, ph) = (v[0][l], v[1][l], vp[l]);
        let fz = -c.ks[l] * z + c.ka[l] * z * z - c.c[l] * zd + c.kphi[l] * ph;
        let vr = c.v[l] - (vxd[l] + c.sl[l] * vphd[l]);
        g[event::GAP][l] = c.zst[l] + z;
        g[event::NORMAL][l] = c.fst[l] + fz;
        g[event::SLIP][l] = if LAW != CONST { vr } else { 1.0 };
        g[event::ESCAPE][l] = c.esc[l] - z.abs();
        if LAW == SWITCH {
            let a_x = -c.dx[l] * vxd[l] - c.wx2[l] * vx[l];
            let a_t = -c.dt[l] * vphd[l] - c.wt2[l] * ph;
            let st = -c.meff[l] * (a_x + c.sl[l] * a_t);
            let (band, bound) = m.live(l);
            let (band, bound) = ((band as u64).wrapping_neg(), (bound as u64).wrapping_neg());
            let margin = c.mu_s[l] * (c.fst[l] + fz) - (st + c.stat[l]).abs();
            g[event::BAND_HI][l] = blend(band, vr - c.eta[l], 1.0);
            g[event::BAND_LO][l] = blend(band, vr + c.eta[l], 1.0);
            g[event::STICK][l] = blend(bound, margin, 1.0);
        }
    }
    g
}

/// The rates of the event functions of [`events_lanes`] on the lanes, from the state `y` and its
/// derivative `f` (the slider's `event_rates`).
#[inline(always)]
pub(super) fn event_rates_lanes<const LAW: u8, const N: usize>(
    c: &Coef<N>,
    m: &Modes<N>,
    y: &Vw<N>,
    f: &Vw<N>,
    d: &mut [Lw<N>; NE],
) {
    for l in 0..N {
        let (z, zd) = (y[idx::Z][l], y[idx::ZD][l]);
        let dn = (-c.ks[l] + 2.0 * c.ka[l] * z) * zd - c.c[l] * f[idx::ZD][l] + c.kphi[l] * y[idx::PHID][l];
        let dv = -(f[idx::XD][l] + c.sl[l] * f[idx::PHID][l]);
        d[event::GAP][l] = zd;
        d[event::NORMAL][l] = dn;
        d[event::SLIP][l] = if LAW != CONST { dv } else { 0.0 };
        d[event::ESCAPE][l] = -z.signum() * zd;
        if LAW == SWITCH {
            let (band, bound) = m.live(l);
            let (band, bound) = ((band as u64).wrapping_neg(), (bound as u64).wrapping_neg());
            // d/dt of the stick force (linear in the state) and of the margin mu_s N - |F_req|.
            let dst = c.meff[l]
                * (c.wx2[l] * f[idx::X][l]
                    + c.dx[l] * f[idx::XD][l]
                    + c.sl[l] * (c.wt2[l] * f[idx::PHI][l] + c.dt[l] * f[idx::PHID][l]));
            let req = stick_force(c, y, l) + c.stat[l];
            // Masks, not `if`s (as in `rhs`): this loop stayed scalar.
            d[event::BAND_HI][l] = blend(band, dv, 0.0);
            d[event::BAND_LO][l] = blend(band, dv, 0.0);
            d[event::STICK][l] = blend(bound, c.mu_s[l] * dn - 1.0f64.copysign(req) * dst, 0.0);
        }
    }
}

/// The scalar driver's hidden-crossing check on all lanes at once: at the three interior points
/// `x = 1/4, 1/2, 3/4` of each accepted step's interpolant and at each lane's turning points
/// `turn[e][l]` of its event functions (0: none; see `run::near_events`), an event function that
/// is not pending and differs in sign from the step start while the step end does not.
/// `hidden[l]` becomes the earliest such `x` (0 where none).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn hidden_crossings<const LAW: u8, const C: usize, const N: usize>(
    c: &Coef<N>,
    m: &Modes<N>,
    dense: &LaneDense<C, N>,
    g0: &[Lw<N>; NE],
    g1: &[Lw<N>; NE],
    pend: &[[bool; N]; NE],
    ok: &[bool; N],
    turn: &[Lw<N>; NE],
    hidden: &mut Lw<N>,
) {
    let g_at = |v: [f64; C], l: usize| events_at::<LAW, N>(c, m, &v, l);
    let hit_of = |g: &[f64; NE], l: usize| {
        let mut hit = false;
        for e in 0..n_events(LAW) {
            hit |= !pend[e][l] & cross(g0[e][l], g[e]) & !cross(g0[e][l], g1[e][l]);
        }
        hit
    };
    let mut found = [false; N];
    for q in 1..=3 {
        let th = q as f64 / 4.0;
        let gq = events_at_lanes::<LAW, C, N>(c, m, &dense.eval(th));
        for l in 0..N {
            let g: [f64; NE] = std::array::from_fn(|e| gq[e][l]);
            let take = hit_of(&g, l) & ok[l] & !found[l];
            hidden[l] = if take { th } else { hidden[l] };
            found[l] |= take;
        }
    }
    for tu in turn.iter().take(n_events(LAW)) {
        for l in 0..N {
            let x = tu[l];
            if x > 0.0 && ok[l] && !(found[l] && hidden[l] <= x) {
                let v = dense.eval_lane(l, x);
                if hit_of(&g_at(v, l), l) {
                    hidden[l] = x;
                    found[l] = true;
                }
            }
        }
    }
}
