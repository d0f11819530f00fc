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
    /// curve. Outside the band `|v_r| <= eta` (slip: mode `Contact` forwards, `SlipBack` backwards)
    /// the total friction force is `mu(v_r) N sign(v_r)`; inside it the pin sticks (mode `Stick`: the force that keeps
    /// `d v_r/dt = 0`, while that is within `mu_s N`) or is in transition (mode `Transition`: the
    /// static bound `mu_s N sign(F_req)`). The dynamic force subtracts `mu(V) F_st` as `Coulomb` does.
    Switch = 2,
}

/// Contact and friction state: selects the smooth branch of the right-hand side.
///
/// The bilateral model is never `Free`; only the switch friction law uses `SlipBack`, `Stick` and
/// `Transition` (with the other laws an in-contact state is always `Contact`). Stick is impossible
/// off the disk, so every mode but `Free` is "in contact" ([`ContactMode::in_contact`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ContactMode {
    /// The contact law acts (`zc <= 0` and `N >= 0`) and the pin slides; with the switch law it
    /// slides forwards, `v_r > eta`.
    Contact,
    /// Switch law: in contact, sliding backwards, `v_r < -eta` (the pin faster than the disk).
    ///
    /// Slip's two directions are two modes, as in Leine et al.'s switch model, so that each has a
    /// smooth field: friction `sign mu(sign v_r) N` with the phase's own `sign`, continued past
    /// `v_r = 0` (`Slider::mu_signed`). With the sign taken from `v_r` at each evaluation, the
    /// stages of a step that reached past zero met the force reversed; the error estimate of such
    /// a step was 1e3-1e5, and every approach to stick was cut into geometrically shrinking steps,
    /// a third of them rejected. A slip phase ends in the band (an event) before `v_r` can change
    /// sign, so its direction is fixed from its start.
    SlipBack,
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

    /// True in the slip modes (`Contact`, `SlipBack`): in contact, outside the stick band.
    #[inline(always)]
    pub fn slips(self) -> bool {
        matches!(self, ContactMode::Contact | ContactMode::SlipBack)
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

mod slider;
pub use slider::*;

#[cfg(test)]
mod tests;
