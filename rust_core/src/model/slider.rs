//! The slider in motion: its forces, the right-hand side for bilateral and unilateral contact,
//! the analytic Jacobian, contact events and their actions (MODEL.md §2).

use super::*;

/// A validated slider with its derived quantities: the right-hand side of MODEL.md §2.
#[derive(Clone, Copy, Debug)]
pub struct Slider {
    /// The parameters it was built from.
    pub p: Params,
    /// z_st: static penetration [m] (< 0)
    pub z_st: f64,
    /// K_s: dynamic contact stiffness [N/m]
    pub k_s: f64,
    /// mu_k of the Stribeck curve (Coulomb and switch laws)
    pub mu_k: f64,
    /// Effective mass of the sliding direction, `1 / (1/m + L^2/I)` [kg]: `d v_r/dt` changes by
    /// `-dF_x / m_eff` per change of the friction force.
    pub m_eff: f64,
    /// s L / I [1/(kg m)]
    torque_gain: f64,
    /// mu(V) F_st sgn_eps(V): static friction force removed from the dynamic one [N]
    static_friction: f64,
    /// 1/m, so the hot right-hand side multiplies instead of dividing.
    inv_mass: f64,
    /// Switch law, slip: 0 takes the sign of `v_r` at each evaluation; +-1 fixes it (see
    /// [`Slider::with_slip_sign`]).
    slip_sign: f64,
}

/// Forces at one state: the pieces every consumer (RHS, observers, summaries) needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Forces {
    /// Total normal force N [N] (0 off the disk in the unilateral model).
    pub normal: f64,
    /// Total normal force the contact law would give at this state [N] (may be negative).
    pub normal_law: f64,
    /// Dynamic friction force F_x [N].
    pub friction: f64,
    /// Sliding velocity v_r [m/s].
    pub slip_velocity: f64,
}

impl Slider {
    /// Validate `p` and precompute the static point.
    ///
    /// # Errors
    /// The first parameter out of range.
    pub fn new(p: Params) -> Result<Self, ParamError> {
        p.validate()?;
        let z_st = p.static_penetration();
        let k_s = p.dynamic_contact_stiffness();
        let mu_k = p.mu_kinetic();
        let mut s = Slider {
            p,
            z_st,
            k_s,
            mu_k,
            m_eff: 1.0 / (1.0 / p.mass + p.moment_arm * p.moment_arm / p.inertia),
            torque_gain: p.torsion_sign * p.moment_arm / p.inertia,
            static_friction: 0.0,
            inv_mass: 1.0 / p.mass,
            slip_sign: 0.0,
        };
        // The switch law slips at V > eta with sign +1; the tanh law's sign is tanh(V/eps).
        let sgn_v = if p.friction_law == FrictionLaw::Switch { 1.0 } else { s.sgn_eps(p.sliding_speed) };
        s.static_friction = s.mu_of(p.sliding_speed) * p.normal_load * sgn_v;
        Ok(s)
    }

    /// The switch law's slip field of one direction, `sign` (+-1; 0: both, as built), continued
    /// smoothly past `v_r = 0`: friction `sign mu_k + sign (mu_s - mu_k) exp(-sign v_r / v_s)`
    /// times `N`, which is the law's own wherever `sign v_r >= 0` (bit for bit: `sign v_r` is
    /// then `|v_r|` exactly).
    ///
    /// For a fixed-mode flow of a slip segment (continuation, `branch::flow`). With the sign taken
    /// at each evaluation a trial orbit of Newton whose slip reaches zero met a field that reverses
    /// there: the reversed force pushes `v_r` back, the accepted steps crept up to zero from above
    /// and never crossed (a Filippov sliding motion), and the flow ran to its step budget, 50,000
    /// steps, two in three rejected. Near the switch law's stick curve at 0.2 m/s such flows were
    /// 85 % of a branch's work. On the continued field the flow crosses zero in a step, and the
    /// flow's watch ends it there.
    pub fn with_slip_sign(mut self, sign: f64) -> Self {
        self.slip_sign = sign;
        self
    }

    /// The sign of the slip friction in slip mode `mode`: the fixed one ([`Slider::with_slip_sign`]),
    /// or the mode's own (`Contact` +1, `SlipBack` -1).
    #[inline]
    fn slip_sign_in(&self, mode: ContactMode) -> f64 {
        if self.slip_sign != 0.0 {
            self.slip_sign
        } else if mode == ContactMode::SlipBack {
            -1.0
        } else {
            1.0
        }
    }

    /// The Stribeck curve at `sign v_r` (= `mu_of(v_r)` where `sign v_r >= 0`), continued past zero.
    #[inline]
    fn mu_signed(&self, sv: f64) -> f64 {
        self.mu_k + (self.p.mu_static - self.mu_k) * (-sv / self.p.stribeck_velocity).exp()
    }

    /// The seed configuration.
    pub fn seed() -> Self {
        Self::new(Params::seed()).expect("seed parameters are valid")
    }

    /// Stribeck curve `mu(v)`; constant `mu` for the constant law.
    #[inline]
    pub fn mu_of(&self, v: f64) -> f64 {
        match self.p.friction_law {
            FrictionLaw::Constant => self.p.mu,
            FrictionLaw::Coulomb | FrictionLaw::Switch => {
                self.mu_k + (self.p.mu_static - self.mu_k) * (-v.abs() / self.p.stribeck_velocity).exp()
            }
        }
    }

    /// `d mu / d(sign v)` of the Stribeck curve at `sv = sign v` (`mu_signed`'s slope; for
    /// `sign = sign(v)` the slope in `|v|`).
    #[inline]
    fn mu_slope_signed(&self, sv: f64) -> f64 {
        -(self.p.mu_static - self.mu_k) / self.p.stribeck_velocity * (-sv / self.p.stribeck_velocity).exp()
    }

    /// Dynamic friction force `F_x` that keeps `d v_r/dt = 0` (stick), in closed form.
    ///
    /// `d v_r/dt = -(xdd + s L phidd)` with `xdd = F_x/m + a_x`, `phidd = (s L/I) F_x + a_t`
    /// (`a_x`, `a_t` the spring and damper accelerations) and `s^2 = 1`, so
    /// `d v_r/dt = -(F_x/m_eff + a_x + s L a_t)`, zero for `F_x = -m_eff (a_x + s L a_t)`.
    /// The total force needed is this plus the static sliding force `mu(V) F_st`.
    #[inline]
    pub fn stick_force(&self, y: &State) -> f64 {
        let p = &self.p;
        let (wx, wt) = (p.omega_friction, p.omega_torsion);
        let a_x = -2.0 * p.zeta_friction * wx * y[idx::XD] - wx * wx * y[idx::X];
        let a_t = -2.0 * p.zeta_torsion * wt * y[idx::PHID] - wt * wt * y[idx::PHI];
        -self.m_eff * (a_x + p.torsion_sign * p.moment_arm * a_t)
    }

    /// Gradient of [`Slider::stick_force`] (it is linear in the state).
    fn stick_force_gradient(&self) -> State {
        let p = &self.p;
        let (wx, wt) = (p.omega_friction, p.omega_torsion);
        let sl = p.torsion_sign * p.moment_arm;
        let mut d = State::zeros();
        d[idx::X] = self.m_eff * wx * wx;
        d[idx::XD] = self.m_eff * 2.0 * p.zeta_friction * wx;
        d[idx::PHI] = self.m_eff * sl * wt * wt;
        d[idx::PHID] = self.m_eff * sl * 2.0 * p.zeta_torsion * wt;
        d
    }

    /// The static sliding force removed from the dynamic friction force, `mu(V) F_st` times
    /// `tanh(V/eps)` (tanh law) or 1 (switch law) [N].
    #[inline]
    pub fn static_friction(&self) -> f64 {
        self.static_friction
    }

    /// Total friction force the pin needs to stick, `F_req = stick_force + mu(V) F_st` [N].
    #[inline]
    pub fn required_friction(&self, y: &State) -> f64 {
        self.stick_force(y) + self.static_friction
    }

    #[inline]
    fn sgn_eps(&self, v: f64) -> f64 {
        (v / self.p.friction_regularization).tanh()
    }

    /// Sliding velocity of the contact point `v_r = V - (xd + s L phid)` [m/s].
    #[inline]
    pub fn slip_velocity(&self, y: &State) -> f64 {
        self.p.sliding_speed - (y[idx::XD] + self.p.torsion_sign * self.p.moment_arm * y[idx::PHID])
    }

    /// Pin position relative to the disk surface, `zc = z_st + z` [m].
    #[inline]
    pub fn gap(&self, y: &State) -> f64 {
        self.z_st + y[idx::Z]
    }

    /// Dynamic normal contact force of the law, `F_z = -K_s z + K_a z^2 - C_zc zd + K_phi phi` [N];
    /// the total law force is `F_st + F_z` (the same as `-K_s0 zc + K_a zc^2 - C_zc zd + K_phi phi`,
    /// written without the cancellation of the total form).
    #[inline]
    pub fn dynamic_law_force(&self, y: &State) -> f64 {
        let p = &self.p;
        let z = y[idx::Z];
        -self.k_s * z + p.contact_quadratic * z * z - p.contact_damping * y[idx::ZD] + p.twist_coupling * y[idx::PHI]
    }

    /// The mode a run takes at state `y`: `Free` off the disk (unilateral model only), else the
    /// friction regime of [`Slider::contact_regime`].
    pub fn mode_at(&self, y: &State) -> ContactMode {
        match self.p.contact {
            ContactModel::Bilateral => self.contact_regime(y),
            ContactModel::Unilateral => {
                if self.gap(y) <= 0.0 && self.p.normal_load + self.dynamic_law_force(y) >= 0.0 {
                    self.contact_regime(y)
                } else {
                    ContactMode::Free
                }
            }
        }
    }

    /// In-contact mode at `y`: `Contact` for the constant and tanh laws; for the switch law
    /// `Contact` (slip) outside the stick band, else [`Slider::band_regime`].
    pub fn contact_regime(&self, y: &State) -> ContactMode {
        if self.p.friction_law != FrictionLaw::Switch {
            ContactMode::Contact
        } else if self.slip_velocity(y).abs() > self.p.stick_band {
            slip_mode(self.slip_velocity(y))
        } else {
            self.band_regime(y)
        }
    }

    /// Friction regime of the switch law at a state inside the stick band: `Stick` when the force
    /// needed to stick is within `mu_s N`, else `Transition` towards the edge `sign(F_req) eta`
    /// (or `Contact` at once when `v_r` is already on that edge, to [`EDGE_TOL`] of `eta`: a
    /// transition started there would begin on its own exit event).
    pub fn band_regime(&self, y: &State) -> ContactMode {
        let n = self.p.normal_load + self.dynamic_law_force(y);
        let req = self.required_friction(y);
        if req.abs() <= self.p.mu_static * n {
            ContactMode::Stick
        } else if req.signum() * self.slip_velocity(y) >= self.p.stick_band * (1.0 - EDGE_TOL) {
            slip_mode(req)
        } else {
            ContactMode::Transition
        }
    }

    /// Forces at state `y` in contact mode `mode`.
    #[inline(always)]
    pub fn forces(&self, y: &State, mode: ContactMode) -> Forces {
        let p = &self.p;
        let f_law = self.dynamic_law_force(y);
        let normal_law = p.normal_load + f_law;
        let (normal, f_z) = if mode.in_contact() { (normal_law, f_law) } else { (0.0, -p.normal_load) };
        let v_r = self.slip_velocity(y);
        let friction = match p.friction_law {
            FrictionLaw::Constant => p.mu * f_z,
            FrictionLaw::Coulomb => self.coulomb_friction(v_r, normal),
            FrictionLaw::Switch => self.switch_friction(y, v_r, normal, mode),
        };
        Forces { normal, normal_law, friction, slip_velocity: v_r }
    }

    /// Regularised Coulomb/Stribeck friction force; out of line so that the constant law's hot
    /// path stays small (exp and tanh are not needed there).
    #[inline(never)]
    fn coulomb_friction(&self, v_r: f64, normal: f64) -> f64 {
        self.mu_of(v_r) * normal * self.sgn_eps(v_r) - self.static_friction
    }

    /// Dynamic friction force of the switch law in mode `mode` (Leine et al. 1998). The sign of
    /// `v_r` in slip and of `F_req` in transition are far from zero by the modes' invariants
    /// (`|v_r| > eta`; `|F_req| > mu_s N`), kept by the events.
    #[inline(never)]
    fn switch_friction(&self, y: &State, v_r: f64, normal: f64, mode: ContactMode) -> f64 {
        match mode {
            ContactMode::Contact | ContactMode::SlipBack => {
                let sg = self.slip_sign_in(mode);
                self.mu_signed(sg * v_r) * normal * sg - self.static_friction
            }
            ContactMode::Free => -self.static_friction,
            ContactMode::Stick => self.stick_force(y),
            ContactMode::Transition => {
                self.p.mu_static * normal * self.required_friction(y).signum() - self.static_friction
            }
        }
    }

    /// Right-hand side `dy/dt` in contact mode `mode` (MODEL.md §2).
    #[inline(always)]
    pub fn rhs(&self, y: &State, mode: ContactMode) -> State {
        let p = &self.p;
        let f = self.forces(y, mode);
        let f_z = f.normal - p.normal_load;
        let (wz, wx, wt) = (p.omega_normal, p.omega_friction, p.omega_torsion);
        let inv_m = self.inv_mass;
        State::new(
            y[1],
            f_z * inv_m - 2.0 * p.zeta_normal * wz * y[1] - wz * wz * y[0],
            y[3],
            f.friction * inv_m - 2.0 * p.zeta_friction * wx * y[3] - wx * wx * y[2],
            y[5],
            self.torque_gain * f.friction - 2.0 * p.zeta_torsion * wt * y[5] - wt * wt * y[4],
        )
    }

    /// Analytic Jacobian `d rhs / dy` in contact mode `mode`.
    pub fn jacobian(&self, y: &State, mode: ContactMode) -> Jacobian {
        let p = &self.p;
        let (wz, wx, wt) = (p.omega_normal, p.omega_friction, p.omega_torsion);
        // dF_z/dy (zero off the disk, where F_z = -F_st).
        let mut dfz = SVector::<f64, 6>::zeros();
        if mode.in_contact() {
            dfz[idx::Z] = -self.k_s + 2.0 * p.contact_quadratic * y[idx::Z];
            dfz[idx::ZD] = -p.contact_damping;
            dfz[idx::PHI] = p.twist_coupling;
        }
        let dfx = match p.friction_law {
            FrictionLaw::Constant => dfz * p.mu,
            FrictionLaw::Coulomb => {
                let v = self.slip_velocity(y);
                let normal = if mode.in_contact() { p.normal_load + self.dynamic_law_force(y) } else { 0.0 };
                let th = self.sgn_eps(v);
                let eps = p.friction_regularization;
                let dmu = -(p.mu_static - self.mu_k) / p.stribeck_velocity
                    * (-v.abs() / p.stribeck_velocity).exp()
                    * v.signum();
                let g = self.mu_of(v) * th;
                let dg = dmu * th + self.mu_of(v) * (1.0 - th * th) / eps;
                let mut d = dfz * g;
                d[idx::XD] -= normal * dg;
                d[idx::PHID] += normal * dg * -(p.torsion_sign * p.moment_arm);
                d
            }
            FrictionLaw::Switch => match mode {
                ContactMode::Contact | ContactMode::SlipBack => {
                    // mu(v_r) N sign(v_r): d/dv of mu(v) sign(v) is the slope in |v| (in
                    // sign v, continued past zero: the mode's sign, or `with_slip_sign`'s).
                    let v = self.slip_velocity(y);
                    let sg = self.slip_sign_in(mode);
                    let normal = p.normal_load + self.dynamic_law_force(y);
                    let dg = self.mu_slope_signed(sg * v);
                    let mut d = dfz * (self.mu_signed(sg * v) * sg);
                    d[idx::XD] -= normal * dg;
                    d[idx::PHID] -= normal * dg * p.torsion_sign * p.moment_arm;
                    d
                }
                ContactMode::Free => SVector::<f64, 6>::zeros(),
                ContactMode::Stick => self.stick_force_gradient(),
                ContactMode::Transition => dfz * (p.mu_static * self.required_friction(y).signum()),
            },
        };
        let mut j = Jacobian::zeros();
        j[(0, 1)] = 1.0;
        j[(2, 3)] = 1.0;
        j[(4, 5)] = 1.0;
        for c in 0..6 {
            j[(1, c)] = dfz[c] / p.mass;
            j[(3, c)] = dfx[c] / p.mass;
            j[(5, c)] = self.torque_gain * dfx[c];
        }
        j[(1, 0)] -= wz * wz;
        j[(1, 1)] -= 2.0 * p.zeta_normal * wz;
        j[(3, 2)] -= wx * wx;
        j[(3, 3)] -= 2.0 * p.zeta_friction * wx;
        j[(5, 4)] -= wt * wt;
        j[(5, 5)] -= 2.0 * p.zeta_torsion * wt;
        j
    }
}

/// Relative margin below `eta` within which a state counts as on the band edge (see
/// [`Slider::band_regime`]). A stick phase entered from slip sits on the edge only to the accuracy
/// of the located entry: the event time is bracketed to `event_tol` (1e-13 s), so `v_r` is inside
/// the band by up to `|d v_r/dt| event_tol`, about 1e-11 m/s at 1e2 m/s^2. Leaving stick from
/// there through a transition would take a time that grows as the square root of that offset (the
/// transition starts with zero net force), which makes the cycle depend on the event locator's
/// last digits (seen: 4e-6 relative against an independent solver with 1e-3 here it is 3e-8). So
/// within 1e-3 eta of the target edge the pin slips at once: a hundred times the location error
/// at the default eta, and a thousandth of the band, which is itself the model's resolution.
pub const EDGE_TOL: f64 = 1e-3;

/// Event indices of the slider as an [`OdeSystem`].
pub mod event {
    /// `zc = z_st + z` crosses zero: contact opens or closes.
    pub const GAP: usize = 0;
    /// The contact law's total normal force crosses zero inside the contact.
    pub const NORMAL: usize = 1;
    /// The sliding velocity `v_r` crosses zero (stick-slip).
    pub const SLIP: usize = 2;
    /// `|z|` reaches the escape limit: the run diverged.
    pub const ESCAPE: usize = 3;
    /// Switch law: `v_r` crosses the upper band edge `+eta` (slip in or out of the stick band).
    pub const BAND_HI: usize = 4;
    /// Switch law: `v_r` crosses the lower band edge `-eta`.
    pub const BAND_LO: usize = 5;
    /// Switch law: the force needed to stick reaches the static bound, `|F_req| = mu_s N`.
    pub const STICK: usize = 6;
}

impl OdeSystem<6> for Slider {
    type Mode = ContactMode;

    #[inline(always)]
    fn rhs(&self, _t: f64, y: &State, mode: ContactMode) -> State {
        Slider::rhs(self, y, mode)
    }

    fn jacobian(&self, _t: f64, y: &State, mode: ContactMode) -> Jacobian {
        Slider::jacobian(self, y, mode)
    }

    fn initial_mode(&self, _t: f64, y: &State) -> ContactMode {
        self.mode_at(y)
    }

    fn n_events(&self) -> usize {
        if self.p.friction_law == FrictionLaw::Switch {
            7
        } else {
            4
        }
    }

    #[inline]
    fn events(&self, _t: f64, y: &State, mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        g[event::GAP] = self.gap(y);
        g[event::NORMAL] = self.p.normal_load + self.dynamic_law_force(y);
        let v_r = self.slip_velocity(y);
        // Under the constant law the sliding velocity acts on nothing and V only shifts it: its
        // zero crossing is no event (it would make a run's steps and work depend on V, and sweeps
        // share one run among points that differ only in V). `min_slip_velocity` still sees it at
        // every step end and event, and on the cycle's Fourier samples.
        g[event::SLIP] = if self.p.friction_law == FrictionLaw::Constant { 1.0 } else { v_r };
        g[event::ESCAPE] = self.p.escape_limit - y[idx::Z].abs();
        if self.p.friction_law == FrictionLaw::Switch {
            self.switch_events(y, v_r, mode, g);
        }
    }

    fn event_reads(&self, i: usize) -> u64 {
        let (z, zd, xd, phi, phid) = (1 << idx::Z, 1 << idx::ZD, 1 << idx::XD, 1 << idx::PHI, 1 << idx::PHID);
        match i {
            event::GAP | event::ESCAPE => z,
            event::NORMAL => z | zd | phi,
            event::SLIP | event::BAND_HI | event::BAND_LO => xd | phid,
            _ => u64::MAX,
        }
    }

    /// One of [`Self::events`]'s functions, by the same expressions (the tests compare the bits).
    fn event(&self, t: f64, y: &State, mode: ContactMode, i: usize) -> f64 {
        let (band, bound) = switch_live(mode);
        let switch = self.p.friction_law == FrictionLaw::Switch;
        match i {
            event::GAP => self.gap(y),
            event::NORMAL => self.p.normal_load + self.dynamic_law_force(y),
            event::SLIP if self.p.friction_law == FrictionLaw::Constant => 1.0,
            event::SLIP => self.slip_velocity(y),
            event::ESCAPE => self.p.escape_limit - y[idx::Z].abs(),
            event::BAND_HI if switch && band => self.slip_velocity(y) - self.p.stick_band,
            event::BAND_LO if switch && band => self.slip_velocity(y) + self.p.stick_band,
            event::STICK if switch && bound => self.stick_margin(y),
            event::BAND_HI | event::BAND_LO | event::STICK if switch => 1.0,
            _ => {
                let mut g = [0.0; MAX_EVENTS];
                self.events(t, y, mode, &mut g);
                g[i]
            }
        }
    }

    /// Exact rates of the event functions along the flow (`f` = the right-hand side at `y` in
    /// `mode`); a switch-law function that is the constant 1 in `mode` has rate 0.
    fn event_rates(&self, _t: f64, y: &State, f: &State, mode: ContactMode, d: &mut [f64; MAX_EVENTS]) -> bool {
        let p = &self.p;
        let (z, zd) = (y[idx::Z], y[idx::ZD]);
        d.fill(f64::NAN);
        d[event::GAP] = zd;
        d[event::NORMAL] = self.law_force_rate(y, f);
        if p.friction_law != FrictionLaw::Constant {
            d[event::SLIP] = self.slip_velocity_gradient().dot(f);
        }
        d[event::ESCAPE] = -z.signum() * zd;
        if p.friction_law == FrictionLaw::Switch {
            let (band, bound) = switch_live(mode);
            let dv = d[event::SLIP];
            d[event::BAND_HI] = if band { dv } else { 0.0 };
            d[event::BAND_LO] = if band { dv } else { 0.0 };
            d[event::STICK] = if bound { self.stick_margin_gradient(y).dot(f) } else { 0.0 };
        }
        true
    }

    /// The switch law's band edges count one way per mode: in slip only entries into the band
    /// (`BAND_HI` falling, `BAND_LO` rising), in a transition only exits. The other way acts on
    /// nothing (`friction_after_switch` keeps the mode) and is an artefact: stick that ends in
    /// slip at once (`band_exit`) leaves `v_r` on its edge, off by the stick phase's integration
    /// error (1e-16 to 1e-11 m/s) on either side, and the sign of that error decided whether a
    /// run logged (and cut a step at) an exit crossing just after the switch.
    fn crossing_counts(&self, mode: ContactMode, i: usize, rising: bool) -> bool {
        let inward = match i {
            event::BAND_HI => !rising,
            event::BAND_LO => rising,
            _ => return true,
        };
        match mode {
            ContactMode::Contact | ContactMode::SlipBack => inward,
            ContactMode::Transition => !inward,
            _ => true,
        }
    }

    fn on_event(&self, _t: f64, y: &State, mode: ContactMode, index: usize) -> EventAction<ContactMode> {
        match index {
            event::ESCAPE => EventAction::Stop,
            event::GAP | event::NORMAL if self.p.contact == ContactModel::Unilateral => {
                // At the event the crossing function is zero to rounding; decide the new mode from the
                // direction the state is heading rather than from the sign of a rounding-level value.
                let new = self.mode_after_switch(y, mode, index);
                if new == mode {
                    EventAction::Continue
                } else {
                    EventAction::Switch(new)
                }
            }
            event::BAND_HI | event::BAND_LO | event::STICK if self.p.friction_law == FrictionLaw::Switch => {
                let new = self.friction_after_switch(y, mode, index);
                if new == mode {
                    EventAction::Continue
                } else {
                    EventAction::Switch(new)
                }
            }
            _ => EventAction::Continue,
        }
    }
}

/// The switch law's slip mode in the direction of `sign` (of `v_r`, or of the force driving it
/// out of the band): `Contact` forwards, `SlipBack` backwards.
#[inline]
pub(crate) fn slip_mode(sign: f64) -> ContactMode {
    if sign < 0.0 {
        ContactMode::SlipBack
    } else {
        ContactMode::Contact
    }
}

/// Which of the switch law's event functions are live in `mode` (see `Slider::switch_events`):
/// the band edges (slip and transition) and the stick bound (stick and transition).
#[inline]
pub(crate) fn switch_live(mode: ContactMode) -> (bool, bool) {
    match mode {
        ContactMode::Contact | ContactMode::SlipBack => (true, false),
        ContactMode::Transition => (true, true),
        ContactMode::Stick => (false, true),
        ContactMode::Free => (false, false),
    }
}

impl Slider {
    /// The switch law's event functions. Each is live only in the modes it can end: the band
    /// edges in slip and transition, the stick bound in stick and transition. Elsewhere it is the
    /// constant 1: in stick `v_r` sits on a band edge (to rounding) for the whole stick phase,
    /// and a live edge function there would fire on rounding noise.
    #[inline(never)]
    fn switch_events(&self, y: &State, v_r: f64, mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        let eta = self.p.stick_band;
        let (band, bound) = switch_live(mode);
        g[event::BAND_HI] = if band { v_r - eta } else { 1.0 };
        g[event::BAND_LO] = if band { v_r + eta } else { 1.0 };
        g[event::STICK] = if bound { self.stick_margin(y) } else { 1.0 };
    }

    /// `mu_s N - |F_req|`: positive while the pin can stick.
    #[inline]
    pub fn stick_margin(&self, y: &State) -> f64 {
        self.p.mu_static * (self.p.normal_load + self.dynamic_law_force(y)) - self.required_friction(y).abs()
    }

    /// Gradient of [`Slider::stick_margin`] in an in-contact mode, at a state where `F_req != 0`.
    pub fn stick_margin_gradient(&self, y: &State) -> State {
        let p = &self.p;
        let mut dn = State::zeros();
        dn[idx::Z] = -self.k_s + 2.0 * p.contact_quadratic * y[idx::Z];
        dn[idx::ZD] = -p.contact_damping;
        dn[idx::PHI] = p.twist_coupling;
        dn * p.mu_static - self.stick_force_gradient() * self.required_friction(y).signum()
    }

    /// Gradient of the sliding velocity `v_r` (constant).
    pub fn slip_velocity_gradient(&self) -> State {
        let mut n = State::zeros();
        n[idx::XD] = -1.0;
        n[idx::PHID] = -self.p.torsion_sign * self.p.moment_arm;
        n
    }

    /// New mode of the switch law after a band-edge or stick-bound event located at `y` in `mode`.
    ///
    /// As for contact switches, the located event function is zero to rounding, so the direction
    /// of the crossing along the current mode's flow decides, never the function's sign: slip
    /// enters the band only if `v_r` heads inwards; a transition ends in slip only if it heads
    /// outwards (it always does: `v_r` runs monotonically to `sign(F_req) eta`); stick ends when the
    /// margin `mu_s N - |F_req|` is falling, and a transition ends in stick when it is rising.
    fn friction_after_switch(&self, y: &State, mode: ContactMode, index: usize) -> ContactMode {
        let f = Slider::rhs(self, y, mode);
        match (mode, index) {
            (
                ContactMode::Contact | ContactMode::SlipBack | ContactMode::Transition,
                event::BAND_HI | event::BAND_LO,
            ) => {
                let edge = if index == event::BAND_HI { 1.0 } else { -1.0 };
                let outwards = edge * self.slip_velocity_gradient().dot(&f) > 0.0;
                match (mode, outwards) {
                    // Entering from slip: stick, or a transition across the band (never back to the edge
                    // just crossed, since mu_s >= mu(v): `band_regime` returns `Contact` only for a
                    // grazing entry, which then keeps slipping).
                    (ContactMode::Contact | ContactMode::SlipBack, false) => self.band_regime(y),
                    (ContactMode::Transition, true) => slip_mode(edge),
                    _ => mode,
                }
            }
            (ContactMode::Stick | ContactMode::Transition, event::STICK) => {
                let rate = self.stick_margin_gradient(y).dot(&f);
                match mode {
                    ContactMode::Stick if rate < 0.0 => self.band_exit(y),
                    ContactMode::Transition if rate > 0.0 => ContactMode::Stick,
                    _ => mode,
                }
            }
            _ => mode,
        }
    }

    /// Regime when stick ends (`|F_req|` has grown past `mu_s N`): slip at once if `v_r` is on the
    /// edge the force drives it to (the usual case: the pin stuck where it entered the band), else
    /// a transition across the band.
    pub(crate) fn band_exit(&self, y: &State) -> ContactMode {
        let req = self.required_friction(y);
        if req.signum() * self.slip_velocity(y) >= self.p.stick_band * (1.0 - EDGE_TOL) {
            slip_mode(req)
        } else {
            ContactMode::Transition
        }
    }

    /// New contact mode of the unilateral model after event `index` located at state `y`.
    ///
    /// At a located event the crossing function is zero to rounding. The direction of the crossing
    /// decides: on the gap event the pin leaves the disk if `zd > 0` and lands if `zd < 0`; on the
    /// normal-force event the law force's rate decides. The other condition is then checked with
    /// its actual value (e.g. landing with a law force that would pull keeps the pin free).
    fn mode_after_switch(&self, y: &State, mode: ContactMode, index: usize) -> ContactMode {
        let n_law = self.p.normal_load + self.dynamic_law_force(y);
        match (mode, index) {
            (ContactMode::Free, event::GAP) => {
                if y[idx::ZD] < 0.0 && n_law >= 0.0 {
                    self.contact_regime(y)
                } else {
                    mode
                }
            }
            (ContactMode::Free, event::NORMAL) => {
                if self.gap(y) <= 0.0 && self.normal_law_rate(y, mode) > 0.0 {
                    self.contact_regime(y)
                } else {
                    mode
                }
            }
            (_, event::GAP) => {
                if y[idx::ZD] > 0.0 {
                    ContactMode::Free
                } else {
                    mode
                }
            }
            (_, event::NORMAL) => {
                if self.normal_law_rate(y, mode) < 0.0 {
                    ContactMode::Free
                } else {
                    mode
                }
            }
            _ => mode,
        }
    }

    /// Time derivative of the law's normal force along the flow in mode `mode`.
    fn normal_law_rate(&self, y: &State, mode: ContactMode) -> f64 {
        self.law_force_rate(y, &Slider::rhs(self, y, mode))
    }

    /// Time derivative of the law's normal force at `y` along `yd` (the right-hand side there).
    fn law_force_rate(&self, y: &State, yd: &State) -> f64 {
        let p = &self.p;
        let dfz_dz = -self.k_s + 2.0 * p.contact_quadratic * y[idx::Z];
        dfz_dz * yd[idx::Z] - p.contact_damping * yd[idx::ZD] + p.twist_coupling * yd[idx::PHI]
    }
}
