//! The harmonic part of a periodic summary: one period integrated again from the section state,
//! sampled uniformly on its dense output, and its Fourier integrals (DC and harmonics 1-3 of `z`,
//! the first harmonics of `phi` and `x`, phases relative to `z1`), with the minimum forces and the
//! time off the disk over that period.

use super::{options_for, SteadyOptions, Summary};
use crate::model::{event, idx, ContactMode, Slider, State};
use crate::ode::{integrate, Control, Observer, Outcome, Sampler, StepView};
use crate::status::Failure;

/// Fourier coefficient pair (a_k, b_k) -> amplitude and phase alpha of |.| sin(k w t + alpha).
pub(super) fn amp_phase(a: f64, b: f64) -> (f64, f64) {
    ((a * a + b * b).sqrt(), a.atan2(b))
}

pub(super) fn wrap(x: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = x.rem_euclid(t);
    if r >= t {
        0.0
    } else {
        r
    }
}

/// Observer of the Fourier period: samples, off-disk time (from contact events), minimum forces.
struct PeriodObserver<'a> {
    s: &'a Slider,
    sampler: Sampler<'a, 6>,
    min_normal: f64,
    min_slip: f64,
    t_off: f64,
    off_since: Option<f64>,
}

impl Observer<6, ContactMode> for PeriodObserver<'_> {
    fn on_step(&mut self, st: &StepView<'_, 6, ContactMode>) -> Control {
        self.sampler.on_step(st);
        let f = self.s.forces(st.y1, st.mode);
        self.min_normal = self.min_normal.min(f.normal);
        self.min_slip = self.min_slip.min(f.slip_velocity);
        Control::Continue
    }
    fn on_event(&mut self, i: usize, t: f64, y: &State, before: ContactMode, after: ContactMode) -> Control {
        for m in [before, after] {
            let f = self.s.forces(y, m);
            self.min_normal = self.min_normal.min(f.normal);
            self.min_slip = self.min_slip.min(f.slip_velocity);
        }
        if i == event::GAP {
            // Off the disk after the crossing iff the pin moves away from it.
            if y[idx::ZD] > 0.0 {
                self.off_since = Some(t);
            } else if let Some(t0) = self.off_since.take() {
                self.t_off += t - t0;
            }
        }
        Control::Continue
    }
}

/// Re-integrate one period from the section state and fill the harmonic part of `sum`.
pub(super) fn fourier_period(s: &Slider, y0: &State, period: f64, opts: &SteadyOptions, sum: &mut Summary) {
    let n = opts.n_fourier.max(16);
    let t_eval: Vec<f64> = (0..n).map(|j| j as f64 * period / n as f64).collect();
    let mode0 = s.mode_at(y0);
    let mut obs = PeriodObserver {
        s,
        sampler: Sampler::new(&t_eval),
        min_normal: s.forces(y0, mode0).normal,
        min_slip: s.slip_velocity(y0),
        t_off: 0.0,
        off_since: if s.gap(y0) > 0.0 { Some(0.0) } else { None },
    };
    let o = options_for(s, &opts.tol);
    let sol = integrate(s, opts.method, 0.0, *y0, period, &o, &mut obs);
    sum.stats += sol.stats;
    if sol.outcome != Outcome::Finished || obs.sampler.out.len() != n {
        let failure = Failure::PeriodRerun { period, t: sum.t_end, status: sol.outcome.status() };
        sum.status = failure.status();
        sum.failure = Some(failure);
        return;
    }
    if let Some(t_start) = obs.off_since {
        obs.t_off += period - t_start;
    }
    let ys = &obs.sampler.out;
    let w = std::f64::consts::TAU / period;
    let coef = |comp: usize, k: usize| -> (f64, f64) {
        let (mut a, mut b) = (0.0, 0.0);
        for (j, y) in ys.iter().enumerate() {
            let arg = k as f64 * w * t_eval[j];
            a += y[comp] * arg.cos();
            b += y[comp] * arg.sin();
        }
        (2.0 * a / n as f64, 2.0 * b / n as f64)
    };
    sum.z0 = ys.iter().map(|y| y[idx::Z]).sum::<f64>() / n as f64;
    let (lo, hi) =
        ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| (lo.min(y[idx::Z]), hi.max(y[idx::Z])));
    sum.z_half_range = 0.5 * (hi - lo);
    let mut alpha = [0.0; 3];
    for k in 1..=3 {
        let (a, b) = coef(idx::Z, k);
        let (amp, ph) = amp_phase(a, b);
        sum.z_amp[k - 1] = amp;
        alpha[k - 1] = ph;
    }
    for k in 1..=3 {
        sum.z_phase[k - 1] = wrap(alpha[k - 1] - k as f64 * alpha[0]);
    }
    let (a, b) = coef(idx::PHI, 1);
    let (amp, ph) = amp_phase(a, b);
    sum.phi_amp = amp;
    sum.phi_phase = wrap(ph - alpha[0]);
    let (a, b) = coef(idx::X, 1);
    let (amp, ph) = amp_phase(a, b);
    sum.x_amp = amp;
    sum.x_phase = wrap(ph - alpha[0]);
    // Samples miss the extremes between them; combine with step ends and events.
    let mut min_n = obs.min_normal;
    let mut min_v = obs.min_slip;
    for y in ys {
        let f = s.forces(y, s.mode_at(y));
        min_n = min_n.min(f.normal);
        min_v = min_v.min(f.slip_velocity);
    }
    sum.min_normal_force = min_n;
    sum.min_slip_velocity = min_v;
    // For the bilateral law too: "off the disk" means zc > 0, where the law acts outside its validity.
    sum.fraction_off_disk = obs.t_off / period;
}
