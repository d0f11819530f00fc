//! The root search of the describing function: the theta-eliminated closed form, the scan of
//! `g(w)` and the polish of every root (see the parent module's docs).

use super::*;

impl Tidf {
    /// The theta-eliminated closed form at frequency `w` (see the module docs).
    pub fn reduced(&self, w: f64) -> Reduced {
        let (l1, _) = self.linear_part(1.0, w);
        let (l2, _) = self.linear_part(2.0, w);
        self.reduced_from(w, l1, l2)
    }

    /// `g(w)` of [`Tidf::reduced`] alone, for the scan: `U c = (r1 v_x + i1 v_y) v_x / |v|^2` and
    /// `U^2 = (r1 v_x + i1 v_y)^2 / |v|^2` need neither `|v|` nor the angle (a hypot and an atan2
    /// per grid point, 45 % of a describing-function call's time) and are the same whichever way
    /// `(c, s)` is oriented. Equal to `reduced(w).g` to rounding.
    #[inline]
    pub(super) fn reduced_g(&self, w: f64) -> f64 {
        let (l1, _) = self.linear_part(1.0, w);
        let (l2, _) = self.linear_part(2.0, w);
        let (r1, i1, r2, i2) = (l1.re, l1.im, l2.re, l2.im);
        let (vx, vy) = (i1 + i2, r2 - r1);
        let p = r1 * vx + i1 * vy;
        (2.0 * self.alpha * p * vx + p * p) / (vx * vx + vy * vy) - 4.0 * i1 * i2 + 2.0 * i1 * i1
    }

    #[inline]
    fn reduced_from(&self, w: f64, l1: C64, l2: C64) -> Reduced {
        let (r1, i1, r2, i2) = (l1.re, l1.im, l2.re, l2.im);
        let (vx, vy) = (i1 + i2, r2 - r1);
        let nv = vx.hypot(vy);
        let (mut c, mut s) = (vx / nv, vy / nv);
        // Orientation with A2 = I_1 / (K_a c) >= 0 (the g below does not depend on it).
        if c * i1 < 0.0 {
            c = -c;
            s = -s;
        }
        let u = r1 * c + i1 * s;
        let g = 2.0 * self.alpha * u * c + u * u - 4.0 * i1 * i2 + 2.0 * i1 * i1;
        let ka = self.k_a;
        let a2 = i1 / (ka * c);
        let a0 = u / (2.0 * ka * c);
        let a1sq = -2.0 * i1 * i2 / (ka * c * ka * c);
        Reduced { g, x: Unknowns::new(w, a0, a1sq.max(0.0).sqrt(), a2, wrap_2pi(s.atan2(c))), a1_squared: a1sq }
    }

    /// Derived quantities of a root `x` (canonicalised first); `torsion_frequency` is the torsion
    /// mode's `Im(lambda)` for the `physical` flag, `band` its relative width (MODEL.md §5: 0.05).
    pub fn describe(&self, x: &Unknowns, torsion_frequency: f64, band: f64) -> Root {
        let x = canonical(x);
        let (w, a0, a1, a2, th) = (x[0], x[1], x[2], x[3], x[4]);
        let z2 = C64::from_polar(a2, th);
        let (lz1, _) = osc(1.0, w, self.wz, self.zz);
        let (lz2, _) = osc(2.0, w, self.wz, self.zz);
        let (lt1, _) = osc(1.0, w, self.wt, self.zt);
        let (lt2, _) = osc(2.0, w, self.wt, self.zt);
        let (lx1, _) = osc(1.0, w, self.wx, self.zx);
        let (lx2, _) = osc(2.0, w, self.wx, self.zx);
        // phi_k = s mu (L/I) m L_z(jkw) z_k / L_t(jkw); x_k = mu L_z(jkw) z_k / L_x(jkw) (MODEL.md §5)
        let phi1 = self.phi_gain * lz1 * a1 / lt1;
        let phi2 = self.phi_gain * lz2 * z2 / lt2;
        let x1 = self.mu * lz1 * a1 / lx1;
        let x2 = self.mu * lz2 * z2 / lx2;
        let z_max = two_harmonic_max(a0, a1, a2, th);
        // min z = -max(-z), the same waveform with every amplitude negated.
        let z_min = -two_harmonic_max(-a0, -a1, -a2, th);
        // Mean dynamic contact force per unit mass: w_z^2 A0 with the block fixed, 0 for a dead load.
        let fz0_m = match self.variant {
            Variant::Consistent => self.wz * self.wz * a0,
            Variant::DeadLoad => 0.0,
        };
        let f1 = (self.m * lz1 * a1).norm();
        let f2 = (self.m * lz2 * a2).norm();
        let f3 = self.k_a * a1 * a2;
        let residual_norm = self.residual(&x).amax();
        Root {
            x,
            omega: w,
            a0,
            a1,
            a2,
            theta: th,
            phi0: self.phi_gain * fz0_m / (self.wt * self.wt),
            x0: self.mu * fz0_m / (self.wx * self.wx),
            phi1,
            phi2,
            x1,
            x2,
            phi1_amp: phi1.norm(),
            phi1_phase: phi1.arg(),
            x_amp: x1.norm(),
            x_phase: x1.arg(),
            z_max,
            z_min,
            contact_opens: self.z_st + z_max > 0.0,
            physical: a0.abs() < self.z_st.abs() && (w - torsion_frequency).abs() <= band * torsion_frequency,
            fz_harmonics: [f1, f2, f3],
            third_harmonic_ratio: f3 / f1.hypot(f2),
            residual_norm,
            newton_iterations: 0,
            status: Status::Success,
        }
    }

    /// The search grid: log-spaced, refined near `w_t` and `w_t / 2` (see [`SearchOptions::kappa`]).
    fn grid_step(&self, w: f64, h_log: f64, kappa: f64) -> f64 {
        let mut h = h_log * w;
        for k in [1.0, 2.0] {
            let (lt, dlt) = osc(k, w, self.wt, self.zt);
            h = h.min(kappa * lt.norm() / dlt.norm());
        }
        h
    }

    /// All roots in the box `[w_min, w_max]` (MODEL.md §5 "Roots"; method in the module docs).
    ///
    /// # Errors
    /// `status` is `InvalidInput` for a bad box or `K_a = 0` (a linear contact has no describing
    /// function: only Hopf points), `NonFinite` if the reduced function is not finite on the grid,
    /// `NotComputed` if the caller cancelled during the scan ([`crate::cancel`], looked at every
    /// [`crate::cancel::CHECK_EVERY`] grid points).
    pub fn find_roots(&self, slider: &Slider, opts: &SearchOptions) -> RootSearch {
        let lin = linear_stability(slider);
        let torsion_frequency = lin.mode(ModeKind::Torsion).frequency;
        let near_marginal = lin.max_growth_rate.abs() < opts.marginal_tol * lin.least_stable_frequency.abs();
        let mut out = RootSearch {
            roots: Vec::new(),
            unresolved: Vec::new(),
            outcome: SearchOutcome::NoRoot,
            max_growth_rate: lin.max_growth_rate,
            torsion_frequency,
            near_marginal,
            complex_amplitude: Vec::new(),
            n_grid: 0,
            status: Status::Success,
        };
        let ok_box = opts.w_min.is_finite() && opts.w_min > 0.0 && opts.w_max.is_finite() && opts.w_max > opts.w_min;
        if !ok_box || self.k_a <= 0.0 || opts.n_base < 2 || opts.kappa.is_nan() || opts.kappa <= 0.0 {
            out.status = Status::InvalidInput;
            out.outcome = if near_marginal { SearchOutcome::BelowResolution } else { SearchOutcome::NoRoot };
            return out;
        }
        let h_log = (opts.w_max / opts.w_min).ln() / (opts.n_base - 1) as f64;
        let g_at = |w: f64| self.reduced_g(w);
        let mut candidates: Vec<(f64, Reduced)> = Vec::new();
        let mut w0 = opts.w_min;
        let mut g0 = g_at(w0);
        let mut n = 1;
        if g0 == 0.0 {
            candidates.push((w0, self.reduced(w0)));
        }
        while w0 < opts.w_max {
            if crate::cancel::requested_every(n as u64) {
                // The caller cancelled: the scan ends here, its roots unsearched.
                out.status = Status::NotComputed;
                out.n_grid = n;
                return out;
            }
            let w1 = (w0 + self.grid_step(w0, h_log, opts.kappa)).min(opts.w_max);
            let g1 = g_at(w1);
            n += 1;
            if !g1.is_finite() {
                out.status = Status::NonFinite;
            } else if g1 == 0.0 {
                candidates.push((w1, self.reduced(w1)));
            } else if g0 != 0.0 && g0.is_finite() && (g0 < 0.0) != (g1 < 0.0) {
                let b = brent(g_at, w0, w1, g0, g1, 4.0 * f64::EPSILON, 200);
                candidates.push((b.x, self.reduced(b.x)));
            }
            w0 = w1;
            g0 = g1;
        }
        out.n_grid = n;
        for (_, red) in candidates {
            if red.a1_squared.abs().sqrt() < opts.amp_resolution || red.x[var::A2].is_nan() || red.x[var::A2] <= 0.0 {
                out.unresolved.push(Unresolved { omega: red.x[0], a1_squared: red.a1_squared });
                continue;
            }
            if red.a1_squared < 0.0 {
                out.complex_amplitude.push(Unresolved { omega: red.x[0], a1_squared: red.a1_squared });
                continue;
            }
            let nr = self.solve(&red.x, &opts.newton);
            let xr = if nr.status == Status::Success { nr.x } else { red.x };
            let mut root = self.describe(&xr, torsion_frequency, opts.physical_band);
            root.newton_iterations = nr.iterations;
            root.status = nr.status;
            if root.residual_norm.is_nan() || root.residual_norm > opts.residual_tol {
                continue;
            }
            if root.omega < opts.w_min || root.omega > opts.w_max {
                continue;
            }
            let scale = Unknowns::new(self.w_ref, self.a_ref, self.a_ref, self.a_ref, 1.0);
            let dup = out.roots.iter().any(|r: &Root| {
                let mut d = (r.x - root.x).component_div(&scale);
                // theta is periodic
                d[var::THETA] = (d[var::THETA] + PI).rem_euclid(2.0 * PI) - PI;
                d.amax() < opts.dedup_tol
            });
            if !dup {
                out.roots.push(root);
            }
        }
        out.roots.sort_by(|a, b| a.omega.total_cmp(&b.omega));
        out.outcome = if !out.roots.is_empty() {
            SearchOutcome::Roots
        } else if !out.unresolved.is_empty() || near_marginal {
            SearchOutcome::BelowResolution
        } else {
            SearchOutcome::NoRoot
        };
        out
    }
}

/// Canonical form of a root: `w > 0`, `A1 > 0`, `A2 > 0`, `theta` in `[0, 2 pi)`, using the
/// invariances `w -> -w` (with `A2 -> -A2`, `theta -> -theta`), `A1 -> -A1` and
/// `(A2, theta) -> (-A2, theta + pi)`.
pub fn canonical(x: &Unknowns) -> Unknowns {
    let mut y = *x;
    if y[var::W] < 0.0 {
        y[var::W] = -y[var::W];
        y[var::A2] = -y[var::A2];
        y[var::THETA] = -y[var::THETA];
    }
    y[var::A1] = y[var::A1].abs();
    if y[var::A2] < 0.0 {
        y[var::A2] = -y[var::A2];
        y[var::THETA] += PI;
    }
    y[var::THETA] = wrap_2pi(y[var::THETA]);
    y
}

/// Largest value over `psi` of `A0 + A1 sin psi + A2 sin(2 psi + theta)`: see [`two_harmonic_argmax`].
pub fn two_harmonic_max(a0: f64, a1: f64, a2: f64, theta: f64) -> f64 {
    two_harmonic_argmax(a0, a1, a2, theta).1
}

/// Where `A0 + A1 sin psi + A2 sin(2 psi + theta)` is largest, and that value: 64 samples, then
/// Newton on the derivative from the best one (converges to rounding: the maximum is a simple one
/// unless two maxima tie, where either is the maximum value). `psi` in `[0, 2 pi)`.
pub fn two_harmonic_argmax(a0: f64, a1: f64, a2: f64, theta: f64) -> (f64, f64) {
    let f = |p: f64| a0 + a1 * p.sin() + a2 * (2.0 * p + theta).sin();
    // The samples from a table of sin p, sin 2p and cos 2p and one sin_cos of theta: 128 sines
    // per call were a tenth of a describing-function call (two calls per root). The samples only
    // pick Newton's start; the value returned is `f`'s own.
    const N: usize = 64;
    static TABLE: std::sync::LazyLock<[[f64; 3]; N]> = std::sync::LazyLock::new(|| {
        std::array::from_fn(|i| {
            let p = 2.0 * PI * i as f64 / N as f64;
            let (s2, c2) = (2.0 * p).sin_cos();
            [p.sin(), s2, c2]
        })
    });
    let (st, ct) = theta.sin_cos();
    let (a2c, a2s) = (a2 * ct, a2 * st);
    let mut best = (f64::NEG_INFINITY, 0.0);
    for (i, [s1, s2, c2]) in TABLE.iter().enumerate() {
        let v = a0 + a1 * s1 + (a2c * s2 + a2s * c2);
        if v > best.0 {
            best = (v, 2.0 * PI * i as f64 / N as f64);
        }
    }
    let mut p = best.1;
    for _ in 0..8 {
        let d1 = a1 * p.cos() + 2.0 * a2 * (2.0 * p + theta).cos();
        let d2 = -a1 * p.sin() - 4.0 * a2 * (2.0 * p + theta).sin();
        if d2 >= 0.0 {
            break;
        }
        let step = d1 / d2;
        p -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    let v = f(p);
    let at_best = f(best.1);
    if v >= at_best {
        (wrap_2pi(p), v)
    } else {
        (best.1, at_best)
    }
}

/// All describing-function roots of the slider with parameters `p` (see [`Tidf::find_roots`]).
///
/// # Errors
/// The first parameter out of range.
pub fn find_roots(p: &Params, variant: Variant, opts: &SearchOptions) -> Result<RootSearch, ParamError> {
    let s = Slider::new(*p)?;
    Ok(Tidf::new(&s, variant).find_roots(&s, opts))
}
