//! The 3-DOF pin-on-disk slider of the 1985 report (MODEL.md §2-3).
//!
//! Legend (SI units): `m` vibrating mass [kg], `I` torsional inertia [kg m^2], `L` moment arm of the
//! friction force about the arm axis [m], `w_z, w_x, w_t` natural frequencies off the disk [rad/s],
//! `zeta_*` damping ratios [-], `K_s0` linear coefficient of the total contact law [N/m] (the report's
//! K_s'), `K_a` quadratic contact coefficient [N/m^2], `C_zc` contact damping [N s/m], `K_phi` normal
//! force per twist [N/rad], `mu` friction coefficient at the operating speed, `F_st` normal load [N],
//! `V` sliding speed [m/s], `s` torsion sign (eq. 18: -1).
//!
//! State `y = [z, zd, x, xd, phi, phid]`, dynamic parts measured from the static equilibrium;
//! `zc = z_st + z` is the pin position relative to the disk surface (`zc < 0`: penetration).

use crate::ode::{EventAction, OdeSystem, MAX_EVENTS};
use nalgebra::{SMatrix, SVector};
use thiserror::Error;

/// State vector `[z, zd, x, xd, phi, phid]`.
pub type State = SVector<f64, 6>;
/// Jacobian of the right-hand side.
pub type Jacobian = SMatrix<f64, 6, 6>;

/// Index of each state component.
pub mod idx {
    pub const Z: usize = 0;
    pub const ZD: usize = 1;
    pub const X: usize = 2;
    pub const XD: usize = 3;
    pub const PHI: usize = 4;
    pub const PHID: usize = 5;
}

/// How the contact law is applied (MODEL.md §2, "Contact").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum ContactModel {
    /// The law everywhere, also in tension with the pin off the disk (the report's model).
    Bilateral = 0,
    /// `N = 0` while the pin is off the disk and `N = max(N, 0)` in contact (the physical one).
    Unilateral = 1,
}

/// Friction law on the sliding velocity `v_r = V - (xd + s L phid)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FrictionLaw {
    /// The report's constant `mu`: `F_x = mu F_z`. Valid only while `v_r > 0`; a run where `v_r`
    /// reaches zero is flagged (stick-slip needs [`FrictionLaw::Coulomb`]).
    Constant = 0,
    /// Regularised Coulomb friction with an optional Stribeck curve:
    /// `F_x = mu(v_r) N tanh(v_r/eps) - mu(V) F_st tanh(V/eps)`,
    /// `mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v_s)`, with `mu_k` chosen so that `mu(V) = mu`.
    Coulomb = 1,
    /// Event-driven stick-slip, the switch model of Leine et al. (1998), with the same Stribeck
    /// curve. Outside the band `|v_r| <= eta` (slip, mode `Contact`) the total friction force is
    /// `mu(v_r) N sign(v_r)`; inside it the pin sticks (mode `Stick`: the force that keeps
    /// `d v_r/dt = 0`, while that is within `mu_s N`) or is in transition (mode `Transition`: the
    /// static bound `mu_s N sign(F_req)`). The dynamic force subtracts `mu(V) F_st` as `Coulomb` does.
    Switch = 2,
}

/// Contact and friction state: selects the smooth branch of the right-hand side.
///
/// The bilateral model is never `Free`; only the switch friction law uses `Stick` and
/// `Transition` (with the other laws an in-contact state is always `Contact`). Stick is impossible
/// off the disk, so every mode but `Free` is "in contact" ([`ContactMode::in_contact`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ContactMode {
    /// The contact law acts (`zc <= 0` and `N >= 0`) and the pin slides; with the switch law the
    /// sliding velocity is outside the stick band, `|v_r| > eta`.
    Contact,
    /// No normal force: the pin is off the disk (`zc > 0`) or the law would pull (`N < 0`).
    Free,
    /// Switch law: in contact, `|v_r| <= eta`, and the friction force that keeps `d v_r/dt = 0`
    /// is within the static bound `mu_s N`: friction is that force.
    Stick,
    /// Switch law: in contact, `|v_r| <= eta`, and the force needed to stick exceeds `mu_s N`:
    /// friction is `mu_s N sign(F_req)`, and `v_r` runs monotonically to the band edge
    /// `sign(F_req) eta`, where the pin slips.
    Transition,
}

impl ContactMode {
    /// True in every mode with a normal force (all but `Free`).
    #[inline(always)]
    pub fn in_contact(self) -> bool {
        self != ContactMode::Free
    }
}

/// A parameter outside its valid range.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ParamError {
    /// `name` has value `value`, outside `range`.
    #[error("{name} = {value:?} is out of range: must be {range}")]
    OutOfRange { name: &'static str, value: f64, range: &'static str },
    /// No parameter of that name.
    #[error("unknown parameter {0:?}; valid names: {1}")]
    Unknown(String, String),
}

/// Physical parameters of one slider. Defaults are the seed configuration (report chapter IV).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// m: vibrating mass [kg]
    pub mass: f64,
    /// I: torsional inertia [kg m^2]
    pub inertia: f64,
    /// L: moment arm of the friction force about the arm axis [m]
    pub moment_arm: f64,
    /// w_z: normal natural frequency, pin off the disk [rad/s]
    pub omega_normal: f64,
    /// w_x: frictional natural frequency [rad/s]
    pub omega_friction: f64,
    /// w_t: torsional natural frequency [rad/s]
    pub omega_torsion: f64,
    /// zeta_z [-]
    pub zeta_normal: f64,
    /// zeta_x [-]
    pub zeta_friction: f64,
    /// zeta_t [-]
    pub zeta_torsion: f64,
    /// K_s0 (report's K_s'): linear coefficient of the total contact law [N/m]
    pub contact_stiffness: f64,
    /// K_a: quadratic contact coefficient [N/m^2]
    pub contact_quadratic: f64,
    /// C_zc: contact damping [N s/m]
    pub contact_damping: f64,
    /// K_phi: normal force per twist [N/rad]
    pub twist_coupling: f64,
    /// mu: friction coefficient at the operating sliding speed [-]
    pub mu: f64,
    /// F_st: normal load [N]
    pub normal_load: f64,
    /// V: sliding speed [m/s]
    pub sliding_speed: f64,
    /// s: sign of the torsion coupling, -1 (eq. 18) or +1 (eq. 24's print)
    pub torsion_sign: f64,
    /// Contact law application.
    pub contact: ContactModel,
    /// Friction law.
    pub friction_law: FrictionLaw,
    /// eps: velocity scale of the tanh regularisation [m/s] (Coulomb law only)
    pub friction_regularization: f64,
    /// mu_s: static friction coefficient of the Stribeck curve [-] (Coulomb law; equal to `mu` for no Stribeck effect)
    pub mu_static: f64,
    /// v_s: Stribeck velocity [m/s] (Coulomb and switch laws)
    pub stribeck_velocity: f64,
    /// eta: half-width of the stick band `|v_r| <= eta` of the switch law [m/s]
    pub stick_band: f64,
    /// |z| beyond which a run is declared diverged [m] (well past the static saddle, 256.7 um at the seed)
    pub escape_limit: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self::seed()
    }
}

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Names of the real-valued parameters, in the order of [`Params::get`]/[`Params::set`].
pub const PARAM_NAMES: [&str; 22] = [
    "mass",
    "inertia",
    "moment_arm",
    "omega_normal",
    "omega_friction",
    "omega_torsion",
    "zeta_normal",
    "zeta_friction",
    "zeta_torsion",
    "contact_stiffness",
    "contact_quadratic",
    "contact_damping",
    "twist_coupling",
    "mu",
    "normal_load",
    "sliding_speed",
    "torsion_sign",
    "friction_regularization",
    "mu_static",
    "stribeck_velocity",
    "escape_limit",
    "stick_band",
];

impl Params {
    /// The seed configuration of MODEL.md §3.
    pub fn seed() -> Self {
        Params {
            mass: 2.48,
            inertia: 3.147e-3,
            moment_arm: 0.065,
            omega_normal: TWO_PI * 55.00,
            omega_friction: TWO_PI * 48.75,
            omega_torsion: TWO_PI * 98.75,
            zeta_normal: 0.01129,
            zeta_friction: 0.00378,
            zeta_torsion: 0.00253,
            contact_stiffness: 4.739e6,
            contact_quadratic: 2.179e10,
            contact_damping: 222.63,
            twist_coupling: -47.64e3,
            mu: 0.215,
            normal_load: 84.46,
            sliding_speed: 0.46,
            torsion_sign: -1.0,
            contact: ContactModel::Bilateral,
            friction_law: FrictionLaw::Constant,
            friction_regularization: 1e-3,
            mu_static: 0.215,
            stribeck_velocity: 0.1,
            escape_limit: 1e-3,
            stick_band: 1e-6,
        }
    }

    /// Value of the real parameter `name`.
    ///
    /// # Errors
    /// [`ParamError::Unknown`] if `name` is not in [`PARAM_NAMES`].
    pub fn get(&self, name: &str) -> Result<f64, ParamError> {
        let mut copy = *self;
        Ok(*copy.field_mut(name)?)
    }

    /// Set the real parameter `name` (not validated: call [`Params::validate`]).
    ///
    /// # Errors
    /// [`ParamError::Unknown`] if `name` is not in [`PARAM_NAMES`].
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), ParamError> {
        *self.field_mut(name)? = value;
        Ok(())
    }

    fn field_mut(&mut self, name: &str) -> Result<&mut f64, ParamError> {
        Ok(match name {
            "mass" => &mut self.mass,
            "inertia" => &mut self.inertia,
            "moment_arm" => &mut self.moment_arm,
            "omega_normal" => &mut self.omega_normal,
            "omega_friction" => &mut self.omega_friction,
            "omega_torsion" => &mut self.omega_torsion,
            "zeta_normal" => &mut self.zeta_normal,
            "zeta_friction" => &mut self.zeta_friction,
            "zeta_torsion" => &mut self.zeta_torsion,
            "contact_stiffness" => &mut self.contact_stiffness,
            "contact_quadratic" => &mut self.contact_quadratic,
            "contact_damping" => &mut self.contact_damping,
            "twist_coupling" => &mut self.twist_coupling,
            "mu" => &mut self.mu,
            "normal_load" => &mut self.normal_load,
            "sliding_speed" => &mut self.sliding_speed,
            "torsion_sign" => &mut self.torsion_sign,
            "friction_regularization" => &mut self.friction_regularization,
            "mu_static" => &mut self.mu_static,
            "stribeck_velocity" => &mut self.stribeck_velocity,
            "escape_limit" => &mut self.escape_limit,
            "stick_band" => &mut self.stick_band,
            _ => return Err(ParamError::Unknown(name.to_string(), PARAM_NAMES.join(", "))),
        })
    }

    /// Check every parameter against its valid range.
    ///
    /// # Errors
    /// The first parameter out of range, with its name, value and the valid range.
    pub fn validate(&self) -> Result<(), ParamError> {
        fn check(name: &'static str, v: f64, ok: bool, range: &'static str) -> Result<(), ParamError> {
            if v.is_finite() && ok {
                Ok(())
            } else {
                Err(ParamError::OutOfRange { name, value: v, range })
            }
        }
        const POS: &str = "a finite number > 0";
        const NONNEG: &str = "a finite number >= 0";
        check("mass", self.mass, self.mass > 0.0, POS)?;
        check("inertia", self.inertia, self.inertia > 0.0, POS)?;
        check("moment_arm", self.moment_arm, self.moment_arm >= 0.0, NONNEG)?;
        check("omega_normal", self.omega_normal, self.omega_normal > 0.0, POS)?;
        check("omega_friction", self.omega_friction, self.omega_friction > 0.0, POS)?;
        check("omega_torsion", self.omega_torsion, self.omega_torsion > 0.0, POS)?;
        check("zeta_normal", self.zeta_normal, self.zeta_normal >= 0.0, NONNEG)?;
        check("zeta_friction", self.zeta_friction, self.zeta_friction >= 0.0, NONNEG)?;
        check("zeta_torsion", self.zeta_torsion, self.zeta_torsion >= 0.0, NONNEG)?;
        check("contact_stiffness", self.contact_stiffness, self.contact_stiffness > 0.0, POS)?;
        check("contact_quadratic", self.contact_quadratic, self.contact_quadratic >= 0.0, NONNEG)?;
        check("contact_damping", self.contact_damping, self.contact_damping >= 0.0, NONNEG)?;
        check("twist_coupling", self.twist_coupling, true, "a finite number")?;
        check("mu", self.mu, self.mu >= 0.0, NONNEG)?;
        check("normal_load", self.normal_load, self.normal_load > 0.0, POS)?;
        check("sliding_speed", self.sliding_speed, self.sliding_speed > 0.0, POS)?;
        check("torsion_sign", self.torsion_sign, self.torsion_sign == 1.0 || self.torsion_sign == -1.0, "-1 or +1")?;
        check("friction_regularization", self.friction_regularization, self.friction_regularization > 0.0, POS)?;
        check("mu_static", self.mu_static, self.mu_static >= 0.0, NONNEG)?;
        check("stribeck_velocity", self.stribeck_velocity, self.stribeck_velocity > 0.0, POS)?;
        check("escape_limit", self.escape_limit, self.escape_limit > 0.0, POS)?;
        check("stick_band", self.stick_band, self.stick_band > 0.0, POS)?;
        if self.friction_law == FrictionLaw::Switch {
            // Steady sliding must be slip, outside the band.
            check(
                "stick_band",
                self.stick_band,
                self.stick_band < self.sliding_speed,
                "a finite number > 0 and below sliding_speed (steady sliding must lie outside the stick band)",
            )?;
            // A Stribeck curve that rises with speed would put the slip force at the band edge above
            // the static bound mu_s N: slip would push into the band and the transition back out of
            // it, forever (the switch model is ill-posed there).
            check(
                "mu_static",
                self.mu_static,
                self.mu_static >= self.mu,
                "a finite number >= mu for the switch law (a Stribeck curve that does not rise with speed)",
            )?;
        }
        if matches!(self.friction_law, FrictionLaw::Coulomb | FrictionLaw::Switch) {
            // mu_k follows from mu(V) = mu; it must not be negative.
            let e = (-self.sliding_speed / self.stribeck_velocity).exp();
            let mu_k = (self.mu - self.mu_static * e) / (1.0 - e);
            check(
                "mu_static",
                self.mu_static,
                mu_k >= 0.0,
                "small enough that the kinetic coefficient mu_k = (mu - mu_static e^(-V/v_s))/(1 - e^(-V/v_s)) is >= 0",
            )?;
        }
        Ok(())
    }

    /// Static penetration `z_st < 0` [m] at the normal load: root of `F_st = -K_s0 z + K_a z^2`.
    /// Written in the cancellation-free form, valid for `K_a = 0` too.
    pub fn static_penetration(&self) -> f64 {
        let (k0, ka, f) = (self.contact_stiffness, self.contact_quadratic, self.normal_load);
        -2.0 * f / (k0 + (k0 * k0 + 4.0 * ka * f).sqrt())
    }

    /// Dynamic contact stiffness `K_s = K_s0 - 2 K_a z_st` [N/m].
    pub fn dynamic_contact_stiffness(&self) -> f64 {
        self.contact_stiffness - 2.0 * self.contact_quadratic * self.static_penetration()
    }

    /// Kinetic friction coefficient of the Stribeck curve, chosen so that `mu(V) = mu`.
    pub fn mu_kinetic(&self) -> f64 {
        let e = (-self.sliding_speed / self.stribeck_velocity).exp();
        (self.mu - self.mu_static * e) / (1.0 - e)
    }
}

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
        };
        // The switch law slips at V > eta with sign +1; the tanh law's sign is tanh(V/eps).
        let sgn_v = if p.friction_law == FrictionLaw::Switch { 1.0 } else { s.sgn_eps(p.sliding_speed) };
        s.static_friction = s.mu_of(p.sliding_speed) * p.normal_load * sgn_v;
        Ok(s)
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

    /// `d mu / d|v|` of the Stribeck curve (zero for the constant law).
    #[inline]
    fn mu_slope(&self, v: f64) -> f64 {
        match self.p.friction_law {
            FrictionLaw::Constant => 0.0,
            _ => {
                -(self.p.mu_static - self.mu_k) / self.p.stribeck_velocity * (-v.abs() / self.p.stribeck_velocity).exp()
            }
        }
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
        if self.p.friction_law != FrictionLaw::Switch || self.slip_velocity(y).abs() > self.p.stick_band {
            ContactMode::Contact
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
            ContactMode::Contact
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
            ContactMode::Contact => self.mu_of(v_r) * normal * v_r.signum() - self.static_friction,
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
                ContactMode::Contact => {
                    // mu(v_r) N sign(v_r): d/dv of mu(v) sign(v) is the slope in |v|.
                    let v = self.slip_velocity(y);
                    let normal = p.normal_load + self.dynamic_law_force(y);
                    let dg = self.mu_slope(v);
                    let mut d = dfz * (self.mu_of(v) * v.signum());
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

impl Slider {
    /// The switch law's event functions. Each is live only in the modes it can end: the band
    /// edges in slip and transition, the stick bound in stick and transition. Elsewhere it is the
    /// constant 1: in stick `v_r` sits on a band edge (to rounding) for the whole stick phase,
    /// and a live edge function there would fire on rounding noise.
    #[inline(never)]
    fn switch_events(&self, y: &State, v_r: f64, mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        let eta = self.p.stick_band;
        let (band, bound) = match mode {
            ContactMode::Contact => (true, false),
            ContactMode::Transition => (true, true),
            ContactMode::Stick => (false, true),
            ContactMode::Free => (false, false),
        };
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
            (ContactMode::Contact | ContactMode::Transition, event::BAND_HI | event::BAND_LO) => {
                let edge = if index == event::BAND_HI { 1.0 } else { -1.0 };
                let outwards = edge * self.slip_velocity_gradient().dot(&f) > 0.0;
                match (mode, outwards) {
                    // Entering from slip: stick, or a transition across the band (never back to the edge
                    // just crossed, since mu_s >= mu(v): `band_regime` returns `Contact` only for a
                    // grazing entry, which then keeps slipping).
                    (ContactMode::Contact, false) => self.band_regime(y),
                    (ContactMode::Transition, true) => ContactMode::Contact,
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
    fn band_exit(&self, y: &State) -> ContactMode {
        let req = self.required_friction(y);
        if req.signum() * self.slip_velocity(y) >= self.p.stick_band * (1.0 - EDGE_TOL) {
            ContactMode::Contact
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
        let yd = Slider::rhs(self, y, mode);
        let p = &self.p;
        let dfz_dz = -self.k_s + 2.0 * p.contact_quadratic * y[idx::Z];
        dfz_dz * yd[idx::Z] - p.contact_damping * yd[idx::ZD] + p.twist_coupling * yd[idx::PHI]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn static_point_matches_model_md() {
        let s = Slider::seed();
        // MODEL.md §3: z_st = -16.5612 um, K_s = 5.4607e6 N/m.
        assert!(close(s.z_st, -16.5612e-6, 1e-5), "z_st = {}", s.z_st);
        assert!(close(s.k_s, 5.4607e6, 1e-4), "K_s = {}", s.k_s);
        // The law reproduces the load at the static point.
        let p = s.p;
        let f = -p.contact_stiffness * s.z_st + p.contact_quadratic * s.z_st * s.z_st;
        assert!(close(f, p.normal_load, 1e-13));
    }

    #[test]
    fn static_point_without_quadratic_term() {
        let p = Params { contact_quadratic: 0.0, ..Params::seed() };
        assert!(close(p.static_penetration(), -p.normal_load / p.contact_stiffness, 1e-15));
        assert_eq!(p.dynamic_contact_stiffness(), p.contact_stiffness);
    }

    #[test]
    fn sliding_is_an_equilibrium_for_every_law() {
        for contact in [ContactModel::Bilateral, ContactModel::Unilateral] {
            for law in [FrictionLaw::Constant, FrictionLaw::Coulomb, FrictionLaw::Switch] {
                let s = Slider::new(Params { contact, friction_law: law, mu_static: 0.3, ..Params::seed() }).unwrap();
                let y = State::zeros();
                assert_eq!(s.mode_at(&y), ContactMode::Contact);
                let f = s.rhs(&y, ContactMode::Contact);
                assert!(f.norm() < 1e-12, "{contact:?} {law:?}: {f}");
            }
        }
    }

    #[test]
    fn bilateral_force_equals_total_law() {
        let s = Slider::seed();
        let y = State::new(3e-6, -0.01, 1e-6, 0.002, 1e-4, 0.05);
        let zc = s.gap(&y);
        let p = s.p;
        let total = -p.contact_stiffness * zc + p.contact_quadratic * zc * zc - p.contact_damping * y[1]
            + p.twist_coupling * y[4];
        let f = s.forces(&y, ContactMode::Contact);
        assert!((f.normal - total).abs() < 1e-9 * p.normal_load);
    }

    /// The analytic Jacobian against central differences (steps `h_rel` times each component's
    /// scale), element by element to 1e-6 (1 + |J|).
    fn assert_jacobian_matches_fd(s: &Slider, y: &State, mode: ContactMode, h_rel: f64, label: &str) {
        let j = s.jacobian(y, mode);
        let scale = [1e-6, 1e-3, 1e-6, 1e-3, 1e-4, 1e-2];
        for c in 0..6 {
            let h = scale[c] * h_rel;
            let (mut yp, mut ym) = (*y, *y);
            yp[c] += h;
            ym[c] -= h;
            let col = (s.rhs(&yp, mode) - s.rhs(&ym, mode)) / (2.0 * h);
            for r in 0..6 {
                let tol = 1e-6 * (1.0 + j[(r, c)].abs());
                assert!(
                    (col[r] - j[(r, c)]).abs() < tol,
                    "{label} {mode:?} J[{r},{c}] = {} vs fd {}",
                    j[(r, c)],
                    col[r]
                );
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        for law in [FrictionLaw::Constant, FrictionLaw::Coulomb] {
            for mode in [ContactMode::Contact, ContactMode::Free] {
                let s = Slider::new(Params {
                    friction_law: law,
                    mu_static: 0.3,
                    friction_regularization: 0.05,
                    ..Params::seed()
                })
                .unwrap();
                let y = State::new(2e-6, 1e-3, -1e-6, 0.01, 2e-4, 0.3);
                assert_jacobian_matches_fd(&s, &y, mode, 1e-4, &format!("{law:?}"));
            }
        }
    }

    /// A slider with the switch law and a state inside the stick band, in contact.
    fn switch_slider() -> Slider {
        Slider::new(Params {
            friction_law: FrictionLaw::Switch,
            mu_static: 0.3,
            stribeck_velocity: 0.02,
            sliding_speed: 0.01,
            stick_band: 1e-4,
            ..Params::seed()
        })
        .unwrap()
    }

    /// State with `v_r = v` and some spring and twist deflection.
    fn state_with_slip(s: &Slider, v: f64, x: f64, phi: f64) -> State {
        let p = s.p;
        // v_r = V - (xd + s L phid): put the rest in xd.
        let phid = 0.02;
        let xd = p.sliding_speed - v - p.torsion_sign * p.moment_arm * phid;
        State::new(1e-6, 1e-3, x, xd, phi, phid)
    }

    #[test]
    fn switch_jacobian_matches_finite_differences_in_every_mode() {
        let s = switch_slider();
        for (mode, v) in [
            (ContactMode::Contact, 3e-3),
            (ContactMode::Contact, -2e-3),
            (ContactMode::Free, 3e-3),
            (ContactMode::Stick, 5e-5),
            (ContactMode::Transition, -5e-5),
        ] {
            for (x, phi) in [(2e-6, 1e-4), (-3e-5, -2e-4)] {
                let y = state_with_slip(&s, v, x, phi);
                assert_jacobian_matches_fd(&s, &y, mode, 1e-5, &format!("v_r = {v}"));
            }
        }
    }

    #[test]
    fn stick_force_holds_the_sliding_velocity() {
        let s = switch_slider();
        let n = s.slip_velocity_gradient();
        for (x, phi) in [(2e-6, 1e-4), (-3e-5, -2e-4), (0.0, 0.0), (1e-4, 3e-3)] {
            let y = state_with_slip(&s, 3e-5, x, phi);
            let f = s.rhs(&y, ContactMode::Stick);
            // d v_r/dt = grad(v_r) . f; the accelerations are O(1e2) m/s^2, so 1e-12 is rounding.
            let acc = f[idx::XD].abs() + s.p.moment_arm * f[idx::PHID].abs();
            assert!(n.dot(&f).abs() <= 1e-13 * acc.max(1.0), "dv_r/dt = {} (scale {acc})", n.dot(&f));
            assert_eq!(s.forces(&y, ContactMode::Stick).friction, s.stick_force(&y));
            // The total force is the required one, and the margin is the bound less its size.
            let req = s.required_friction(&y);
            assert!(close(req, s.stick_force(&y) + s.mu_of(s.p.sliding_speed) * s.p.normal_load, 1e-15));
            let nf = s.forces(&y, ContactMode::Stick).normal;
            assert!(close(s.stick_margin(&y), s.p.mu_static * nf - req.abs(), 1e-12));
        }
        // Steady sliding needs exactly the static sliding force.
        let y0 = State::zeros();
        assert_eq!(s.stick_force(&y0), 0.0);
        assert!(close(s.required_friction(&y0), s.p.mu * s.p.normal_load, 1e-14));
    }

    #[test]
    fn switch_modes_and_slip_friction() {
        let s = switch_slider();
        let eta = s.p.stick_band;
        // Outside the band: slip with the Stribeck force in the direction of v_r.
        for v in [3e-3, -3e-3] {
            let y = state_with_slip(&s, v, 0.0, 0.0);
            assert_eq!(s.mode_at(&y), ContactMode::Contact);
            let f = s.forces(&y, ContactMode::Contact);
            let total = f.friction + s.mu_of(s.p.sliding_speed) * s.p.normal_load;
            assert!(close(total, s.mu_of(v) * f.normal * v.signum(), 1e-14), "{total}");
        }
        // Inside the band near the static point: stick (mu_s N = 25 N > the 18 N needed).
        let y = state_with_slip(&s, 0.5 * eta, 0.0, 0.0);
        assert_eq!(s.mode_at(&y), ContactMode::Stick);
        // A large spring deflection needs more than mu_s N: transition, at the static bound.
        let y = state_with_slip(&s, 0.5 * eta, -1e-3, 0.0);
        assert!(s.stick_margin(&y) < 0.0);
        assert_eq!(s.mode_at(&y), ContactMode::Transition);
        let f = s.forces(&y, ContactMode::Transition);
        let total = f.friction + s.mu_of(s.p.sliding_speed) * s.p.normal_load;
        assert!(close(total.abs(), s.p.mu_static * f.normal, 1e-14));
        assert_eq!(total.signum(), s.required_friction(&y).signum());
        // The transition drives v_r towards the edge sign(F_req) eta.
        let rate = s.slip_velocity_gradient().dot(&s.rhs(&y, ContactMode::Transition));
        assert_eq!(rate.signum(), s.required_friction(&y).signum());
        // Stick ends at the bound with v_r on the edge the force drives it to: slip at once.
        let req_sign = s.required_friction(&y).signum();
        let y_edge = state_with_slip(&s, req_sign * eta, -1e-3, 0.0);
        assert_eq!(s.band_regime(&y_edge), ContactMode::Contact);
        assert_eq!(s.band_exit(&y_edge), ContactMode::Contact);
        let y_far = state_with_slip(&s, -req_sign * eta, -1e-3, 0.0);
        assert_eq!(s.band_exit(&y_far), ContactMode::Transition);
    }

    #[test]
    fn switch_events_fire_at_the_band_edges() {
        use crate::ode::{integrate, Control, Method, Observer, Options};
        // Free stick-slip from a pre-loaded spring: record every event with its v_r and modes.
        struct Log(Vec<(usize, f64, ContactMode, ContactMode)>, Slider);
        impl Observer<6, ContactMode> for Log {
            fn on_event(&mut self, i: usize, _t: f64, y: &State, b: ContactMode, a: ContactMode) -> Control {
                self.0.push((i, self.1.slip_velocity(y), b, a));
                Control::Continue
            }
        }
        let s = Slider::new(Params { stick_band: 1e-5, ..switch_slider().p }).unwrap();
        let eta = s.p.stick_band;
        let mut y0 = State::zeros();
        // Start stuck: v_r = 0 inside the band (xd = V), spring unloaded.
        y0[idx::XD] = s.p.sliding_speed;
        assert_eq!(s.mode_at(&y0), ContactMode::Stick);
        let mut log = Log(Vec::new(), s);
        let o = Options::<6>::new(1e-10, 1e-14);
        let sol = integrate(&s, Method::Dop853, 0.0, y0, 0.05, &o, &mut log);
        assert_eq!(sol.outcome, crate::ode::Outcome::Finished);
        let switches: Vec<_> = log.0.iter().filter(|e| e.2 != e.3).collect();
        assert!(switches.len() >= 4, "{switches:?}");
        // A located edge is inside the band by |dv_r/dt| x event_tol (1e-13 s): about 1e-11 m/s,
        // 1e-6 of this eta; 1e-4 of eta says "on the edge" with a hundredfold margin.
        for &&(i, v, b, a) in &switches {
            match i {
                event::BAND_HI => assert!((v - eta).abs() <= 1e-4 * eta, "{v}"),
                event::BAND_LO => assert!((v + eta).abs() <= 1e-4 * eta, "{v}"),
                event::STICK => assert!(b == ContactMode::Stick || a == ContactMode::Stick, "{b:?} -> {a:?}"),
                _ => {}
            }
            assert!(b.in_contact() && a.in_contact());
        }
        // It sticks, slips, and sticks again.
        assert!(switches.iter().any(|e| e.2 == ContactMode::Stick && e.3 != ContactMode::Stick));
        assert!(switches.iter().filter(|e| e.3 == ContactMode::Stick).count() >= 1);
    }

    #[test]
    fn switch_law_validation() {
        let p = Params { friction_law: FrictionLaw::Switch, mu_static: 0.2, ..Params::seed() };
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("mu_static") && e.contains(">= mu"), "{e}");
        let p = Params { friction_law: FrictionLaw::Switch, stick_band: 0.5, ..Params::seed() };
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("stick_band") && e.contains("0.5") && e.contains("sliding_speed"), "{e}");
        let p = Params { stick_band: -1.0, ..Params::seed() };
        assert!(p.validate().unwrap_err().to_string().contains("stick_band"));
    }

    #[test]
    fn validation_names_the_argument() {
        let bad = Params { mass: -1.0, ..Params::seed() };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("mass") && e.contains("-1") && e.contains("> 0"), "{e}");
        let bad = Params { normal_load: f64::NAN, ..Params::seed() };
        assert!(bad.validate().unwrap_err().to_string().contains("normal_load"));
        let bad = Params { torsion_sign: 0.5, ..Params::seed() };
        assert!(bad.validate().unwrap_err().to_string().contains("-1 or +1"));
        let mut p = Params::seed();
        assert!(p.set("no_such", 1.0).is_err());
        p.set("mu", 0.3).unwrap();
        assert_eq!(p.get("mu").unwrap(), 0.3);
        for name in PARAM_NAMES {
            let v = p.get(name).unwrap();
            p.set(name, v).unwrap();
        }
        assert_eq!(p, Params { mu: 0.3, ..Params::seed() });
    }

    #[test]
    fn stribeck_curve_passes_through_mu_at_operating_speed() {
        let s = Slider::new(Params { friction_law: FrictionLaw::Coulomb, mu_static: 0.3, ..Params::seed() }).unwrap();
        assert!(close(s.mu_of(s.p.sliding_speed), s.p.mu, 1e-14));
        assert!(s.mu_of(0.0) > s.mu_of(0.1));
        assert!(close(s.mu_of(0.0), 0.3, 1e-14));
    }
}
