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
}

/// Contact state of the unilateral model (the bilateral model is always `Contact`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ContactMode {
    /// The contact law acts: `zc <= 0` and `N >= 0`.
    Contact,
    /// No normal force: the pin is off the disk (`zc > 0`) or the law would pull (`N < 0`).
    Free,
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
    /// v_s: Stribeck velocity [m/s] (Coulomb law)
    pub stribeck_velocity: f64,
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
pub const PARAM_NAMES: [&str; 21] = [
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
        if self.friction_law == FrictionLaw::Coulomb {
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
    /// mu_k of the Stribeck curve (Coulomb law)
    pub mu_k: f64,
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
            torque_gain: p.torsion_sign * p.moment_arm / p.inertia,
            static_friction: 0.0,
            inv_mass: 1.0 / p.mass,
        };
        s.static_friction = s.mu_of(p.sliding_speed) * p.normal_load * s.sgn_eps(p.sliding_speed);
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
            FrictionLaw::Coulomb => {
                self.mu_k + (self.p.mu_static - self.mu_k) * (-v.abs() / self.p.stribeck_velocity).exp()
            }
        }
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

    /// The contact mode the unilateral model takes at state `y` (always `Contact` for bilateral).
    pub fn mode_at(&self, y: &State) -> ContactMode {
        match self.p.contact {
            ContactModel::Bilateral => ContactMode::Contact,
            ContactModel::Unilateral => {
                if self.gap(y) <= 0.0 && self.p.normal_load + self.dynamic_law_force(y) >= 0.0 {
                    ContactMode::Contact
                } else {
                    ContactMode::Free
                }
            }
        }
    }

    /// Forces at state `y` in contact mode `mode`.
    #[inline(always)]
    pub fn forces(&self, y: &State, mode: ContactMode) -> Forces {
        let p = &self.p;
        let f_law = self.dynamic_law_force(y);
        let normal_law = p.normal_load + f_law;
        let (normal, f_z) = match mode {
            ContactMode::Contact => (normal_law, f_law),
            ContactMode::Free => (0.0, -p.normal_load),
        };
        let v_r = self.slip_velocity(y);
        let friction = match p.friction_law {
            FrictionLaw::Constant => p.mu * f_z,
            FrictionLaw::Coulomb => self.coulomb_friction(v_r, normal),
        };
        Forces { normal, normal_law, friction, slip_velocity: v_r }
    }

    /// Regularised Coulomb/Stribeck friction force; out of line so that the constant law's hot
    /// path stays small (exp and tanh are not needed there).
    #[inline(never)]
    fn coulomb_friction(&self, v_r: f64, normal: f64) -> f64 {
        self.mu_of(v_r) * normal * self.sgn_eps(v_r) - self.static_friction
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
        if mode == ContactMode::Contact {
            dfz[idx::Z] = -self.k_s + 2.0 * p.contact_quadratic * y[idx::Z];
            dfz[idx::ZD] = -p.contact_damping;
            dfz[idx::PHI] = p.twist_coupling;
        }
        let dfx = match p.friction_law {
            FrictionLaw::Constant => dfz * p.mu,
            FrictionLaw::Coulomb => {
                let v = self.slip_velocity(y);
                let normal = match mode {
                    ContactMode::Contact => p.normal_load + self.dynamic_law_force(y),
                    ContactMode::Free => 0.0,
                };
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
        4
    }

    #[inline]
    fn events(&self, _t: f64, y: &State, _mode: ContactMode, g: &mut [f64; MAX_EVENTS]) {
        g[event::GAP] = self.gap(y);
        g[event::NORMAL] = self.p.normal_load + self.dynamic_law_force(y);
        g[event::SLIP] = self.slip_velocity(y);
        g[event::ESCAPE] = self.p.escape_limit - y[idx::Z].abs();
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
            _ => EventAction::Continue,
        }
    }
}

impl Slider {
    /// New contact mode of the unilateral model after event `index` located at state `y`.
    ///
    /// At a located event the crossing function is zero to rounding. The direction of the crossing
    /// decides: on the gap event the pin leaves the disk if `zd > 0` and lands if `zd < 0`; on the
    /// normal-force event the law force's rate decides. The other condition is then checked with
    /// its actual value (e.g. landing with a law force that would pull keeps the pin free).
    fn mode_after_switch(&self, y: &State, mode: ContactMode, index: usize) -> ContactMode {
        let n_law = self.p.normal_load + self.dynamic_law_force(y);
        match (mode, index) {
            (ContactMode::Contact, event::GAP) => {
                if y[idx::ZD] > 0.0 {
                    ContactMode::Free
                } else {
                    mode
                }
            }
            (ContactMode::Contact, event::NORMAL) => {
                if self.normal_law_rate(y, mode) < 0.0 {
                    ContactMode::Free
                } else {
                    mode
                }
            }
            (ContactMode::Free, event::GAP) => {
                if y[idx::ZD] < 0.0 && n_law >= 0.0 {
                    ContactMode::Contact
                } else {
                    mode
                }
            }
            (ContactMode::Free, event::NORMAL) => {
                if self.gap(y) <= 0.0 && self.normal_law_rate(y, mode) > 0.0 {
                    ContactMode::Contact
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
            for law in [FrictionLaw::Constant, FrictionLaw::Coulomb] {
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
                let j = s.jacobian(&y, mode);
                let scale = [1e-6, 1e-3, 1e-6, 1e-3, 1e-4, 1e-2];
                for c in 0..6 {
                    let h = scale[c] * 1e-4;
                    let mut yp = y;
                    let mut ym = y;
                    yp[c] += h;
                    ym[c] -= h;
                    let col = (s.rhs(&yp, mode) - s.rhs(&ym, mode)) / (2.0 * h);
                    for r in 0..6 {
                        let tol = 1e-6 * (1.0 + j[(r, c)].abs());
                        assert!(
                            (col[r] - j[(r, c)]).abs() < tol,
                            "{law:?} {mode:?} J[{r},{c}] = {} vs fd {}",
                            j[(r, c)],
                            col[r]
                        );
                    }
                }
            }
        }
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
