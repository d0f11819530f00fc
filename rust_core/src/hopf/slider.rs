//! Steady sliding of the slider as a [`VectorField`]: the in-contact right-hand side with analytic
//! second and third derivatives, and the parameter axes the Hopf analysis moves along.
//!
//! Near steady sliding the pin stays on the disk (`zc = z_st + z < 0`) and slides (`v_r` near
//! `V > 0`), so the field is the smooth `ContactMode::Contact` branch for both contact models and
//! every friction law. Its nonlinear parts (MODEL.md §2):
//!
//! ```text
//!   F_z = -K_s z + K_a z^2 - C_zc zd + K_phi phi                 (quadratic in y)
//!   F_x = G(v_r) N - mu(V) F_st sgn(V),   N = F_st + F_z,   v_r = V - (xd + s L phid)  (linear in y)
//!   G(v) = mu                      constant law (so F_x = mu F_z)
//!        = mu(v) tanh(v / eps)     regularised Coulomb/Stribeck law
//!        = mu(v) sign(v)           switch law, slip mode
//!   mu(v) = mu_k + (mu_s - mu_k) exp(-|v| / v_s)
//! ```
//!
//! `F_z` enters `zdd / m`; `F_x` enters `xdd / m` and `phidd` through `s L / I`. So
//! `D^2 F_x[u,v] = G'' dv_u dv_v N + G' (dv_u dN_v + dv_v dN_u) + G d2N[u,v]` and
//! `D^3 F_x[u,v,w] = G''' dv_u dv_v dv_w N + G'' (sum of dv dv dN over the 3 pairings)
//! + G' (sum of dv d2N over the 3 pairings)`, with `dN = dF_z`, `d2N[u,v] = 2 K_a u_z v_z`,
//! `dv_u = -(u_xd + s L u_phid)`.

use super::{Family, VectorField, C64};
use crate::linear::{participation, ModeKind};
use crate::model::{idx, FrictionLaw, Jacobian, ParamError, Params, Slider, State};
use crate::ContactMode;
use nalgebra::SVector;

/// The slider's in-contact field, with analytic `B` and `C`.
#[derive(Clone, Copy, Debug)]
pub struct SliderField(pub Slider);

impl SliderField {
    /// `G(v)` and its first three derivatives at the sliding velocity `v` (see the module docs).
    fn friction_curve(&self, v: f64) -> [f64; 4] {
        let s = &self.0;
        let p = &s.p;
        match p.friction_law {
            FrictionLaw::Constant => [p.mu, 0.0, 0.0, 0.0],
            law => {
                // mu^(k)(v) = (mu_s - mu_k) (-sgn(v)/v_s)^k exp(-|v|/v_s)
                let e = (p.mu_static - s.mu_k) * (-v.abs() / p.stribeck_velocity).exp();
                let r = -v.signum() / p.stribeck_velocity;
                let mu = [s.mu_k + e, e * r, e * r * r, e * r * r * r];
                let t = if law == FrictionLaw::Coulomb {
                    // T = tanh(v/eps): T' = (1-T^2)/eps, T'' = -2T(1-T^2)/eps^2, T''' = -2(1-T^2)(1-3T^2)/eps^3
                    let eps = p.friction_regularization;
                    let th = (v / eps).tanh();
                    let sech2 = 1.0 - th * th;
                    [
                        th,
                        sech2 / eps,
                        -2.0 * th * sech2 / (eps * eps),
                        -2.0 * sech2 * (1.0 - 3.0 * th * th) / eps.powi(3),
                    ]
                } else {
                    [v.signum(), 0.0, 0.0, 0.0]
                };
                // Leibniz: (mu T)^(k) = sum_j binom(k, j) mu^(j) T^(k-j)
                [
                    mu[0] * t[0],
                    mu[1] * t[0] + mu[0] * t[1],
                    mu[2] * t[0] + 2.0 * mu[1] * t[1] + mu[0] * t[2],
                    mu[3] * t[0] + 3.0 * mu[2] * t[1] + 3.0 * mu[1] * t[2] + mu[0] * t[3],
                ]
            }
        }
    }

    /// `dF_z[u]` at state `y`.
    fn d_normal(&self, y: &State, u: &State) -> f64 {
        let p = &self.0.p;
        (-self.0.k_s + 2.0 * p.contact_quadratic * y[idx::Z]) * u[idx::Z] - p.contact_damping * u[idx::ZD]
            + p.twist_coupling * u[idx::PHI]
    }

    /// `dv_r[u]`.
    fn d_slip(&self, u: &State) -> f64 {
        -(u[idx::XD] + self.0.p.torsion_sign * self.0.p.moment_arm * u[idx::PHID])
    }

    /// A force pair `(d^k F_z, d^k F_x)` placed into the acceleration rows.
    fn rows(&self, fz: f64, fx: f64) -> State {
        let p = &self.0.p;
        let mut out = State::zeros();
        out[idx::ZD] = fz / p.mass;
        out[idx::XD] = fx / p.mass;
        out[idx::PHID] = p.torsion_sign * p.moment_arm / p.inertia * fx;
        out
    }
}

impl VectorField<6> for SliderField {
    fn rhs(&self, x: &State) -> State {
        self.0.rhs(x, ContactMode::Contact)
    }

    fn jacobian(&self, x: &State) -> Jacobian {
        self.0.jacobian(x, ContactMode::Contact)
    }

    /// Displacements: the static penetration (the contact law changes by its own size over it);
    /// the twist whose `K_phi phi` matches `K_s z_st`; velocities: those times `w_t`.
    fn fd_scale(&self) -> SVector<f64, 6> {
        let s = &self.0;
        let z = s.z_st.abs();
        let phi = if s.p.twist_coupling != 0.0 { s.k_s * z / s.p.twist_coupling.abs() } else { 1.0 };
        let w = s.p.omega_torsion;
        SVector::<f64, 6>::from([z, z * w, z, z * w, phi, phi * w])
    }

    fn bilinear(&self, y: &State, u: &State, v: &State) -> State {
        let ka2 = 2.0 * self.0.p.contact_quadratic;
        let d2n = ka2 * u[idx::Z] * v[idx::Z];
        let [g, g1, g2, _] = self.friction_curve(self.0.slip_velocity(y));
        let n = self.0.p.normal_load + self.0.dynamic_law_force(y);
        let (du, dv) = (self.d_slip(u), self.d_slip(v));
        let d2x = g2 * du * dv * n + g1 * (du * self.d_normal(y, v) + dv * self.d_normal(y, u)) + g * d2n;
        self.rows(d2n, d2x)
    }

    fn trilinear(&self, y: &State, u: &State, v: &State, w: &State) -> State {
        let ka2 = 2.0 * self.0.p.contact_quadratic;
        let [_, g1, g2, g3] = self.friction_curve(self.0.slip_velocity(y));
        let n = self.0.p.normal_load + self.0.dynamic_law_force(y);
        let (su, sv, sw) = (self.d_slip(u), self.d_slip(v), self.d_slip(w));
        let (nu, nv, nw) = (self.d_normal(y, u), self.d_normal(y, v), self.d_normal(y, w));
        let d2n = |a: &State, b: &State| ka2 * a[idx::Z] * b[idx::Z];
        let d3x = g3 * su * sv * sw * n
            + g2 * (su * sv * nw + su * sw * nv + sv * sw * nu)
            + g1 * (su * d2n(v, w) + sv * d2n(u, w) + sw * d2n(u, v));
        self.rows(0.0, d3x)
    }
}

/// One term of a parameter axis.
#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    /// The model field is set to the axis value.
    Set(String),
    /// `field = base (value / reference)^exponent` (the apparatus' frequencies against arm length).
    PowerLaw {
        /// Model field.
        field: String,
        /// Its value at `value = reference`.
        base: f64,
        /// Reference value of the axis.
        reference: f64,
        /// Exponent.
        exponent: f64,
    },
}

/// A parameter the analysis moves along: one model field, or several fields that follow one
/// apparatus quantity (arm length sets the three natural frequencies by fitted power laws).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Name in the output (e.g. `normal_load`, `arm_length`).
    pub name: String,
    /// What the value sets.
    pub terms: Vec<Term>,
}

impl Axis {
    /// The axis that sets the model field `name`.
    pub fn field(name: &str) -> Self {
        Axis { name: name.to_string(), terms: vec![Term::Set(name.to_string())] }
    }

    /// Apply `value` to `p` (not validated).
    ///
    /// # Errors
    /// [`ParamError::Unknown`] for a field that does not exist.
    pub fn apply(&self, p: &mut Params, value: f64) -> Result<(), ParamError> {
        for t in &self.terms {
            match t {
                Term::Set(field) => p.set(field, value)?,
                Term::PowerLaw { field, base, reference, exponent } => {
                    let ratio = value / reference;
                    // Exactly the base at the reference, as the Python apparatus model does.
                    p.set(field, if ratio == 1.0 { *base } else { base * ratio.powf(*exponent) })?
                }
            }
        }
        Ok(())
    }

    /// Check the field names without a value.
    ///
    /// # Errors
    /// [`ParamError::Unknown`] for a field that does not exist.
    pub fn check(&self) -> Result<(), ParamError> {
        let p = Params::seed();
        for t in &self.terms {
            let field = match t {
                Term::Set(f) | Term::PowerLaw { field: f, .. } => f,
            };
            p.get(field)?;
        }
        Ok(())
    }
}

/// Steady sliding of a base slider with one or two axes moved.
#[derive(Clone, Debug)]
pub struct SliderFamily {
    /// Everything that does not move.
    pub base: Params,
    /// The moving parameters (one or two).
    pub axes: Vec<Axis>,
}

impl SliderFamily {
    /// The parameters at axis values `values`.
    ///
    /// # Errors
    /// Unknown field or a parameter out of range (validated).
    pub fn params(&self, values: &[f64]) -> Result<Params, ParamError> {
        let mut p = self.base;
        for (a, v) in self.axes.iter().zip(values) {
            a.apply(&mut p, *v)?;
        }
        p.validate()?;
        Ok(p)
    }
}

impl Family<6> for SliderFamily {
    type Field = SliderField;

    fn field(&self, values: &[f64]) -> Result<SliderField, String> {
        let p = self.params(values).map_err(|e| e.to_string())?;
        Slider::new(p).map(SliderField).map_err(|e| e.to_string())
    }

    /// Displacement norm: `q` is scaled as `[z, zd/w, x, xd/w, L phi, L phid/w]`, every component
    /// a displacement in metres (`L phi` is the twist's displacement of the contact point), so
    /// `l1` is in m^-2 and `2 |v| |q_z|` is the amplitude of `z` on the small cycle.
    fn weights(&self, f: &SliderField, omega: f64) -> SVector<f64, 6> {
        // A real eigenvalue (no frequency): plain displacements and velocities.
        let w2 = if omega > 1e-9 { 1.0 / (omega * omega) } else { 1.0 };
        let l = f.0.p.moment_arm;
        let l2 = if l > 0.0 { l * l } else { 1.0 };
        SVector::<f64, 6>::from([1.0, w2, 1.0, w2, l2, l2 * w2])
    }

    fn mode_label(&self, f: &SliderField, lambda: C64) -> u8 {
        let j = f.0.jacobian(&State::zeros(), ContactMode::Contact);
        let part = participation(&j, &f.0.p, lambda);
        let k = (0..3).max_by(|&a, &b| part[a].total_cmp(&part[b])).unwrap_or(1);
        ModeKind::ALL[k] as u8
    }
}
