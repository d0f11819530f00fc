//! Special points between two accepted points of a Hopf curve, located on the curve.

use super::{axpy, Ctx, CurvePoint, Node, PointType};
use crate::hopf::{Family, C64};
use crate::status::Status;

/// An event between two accepted points, with its values there.
#[derive(Clone, Copy, Debug)]
pub(super) enum Event {
    /// Sign change of l1.
    Bautin,
    /// Another eigenvalue's real part (the eigenvalue at each end).
    Other(C64, C64),
    /// Axis `k` reaches `value`.
    Mark(usize, f64),
}

impl<Fam> Ctx<'_, Fam> {
    /// Value of an event function at node `n` reached after `sigma` of a step of length `h`.
    pub(super) fn event_value(&self, ev: Event, n: &Node, sigma: f64, h: f64) -> f64 {
        match ev {
            Event::Bautin => n.l1,
            Event::Other(a, b) => {
                let guess = a + (b - a) * (sigma / h);
                let near = n.e.others.iter().min_by(|x, y| (**x - guess).norm().total_cmp(&(**y - guess).norm()));
                near.map_or(f64::NAN, |e| e.re)
            }
            Event::Mark(k, v) => self.phys(n.s)[k] - v,
        }
    }

    /// Events whose functions change sign between `a` and `b` (`b` at arclength `h` along `a.t`).
    pub(super) fn events_between(&self, a: &Node, b: &Node) -> Vec<Event> {
        let mut out = Vec::new();
        if a.l1.is_finite() && b.l1.is_finite() && (a.l1 < 0.0) != (b.l1 < 0.0) {
            out.push(Event::Bautin);
        }
        // Match the other eigenvalues (nearest), then look for sign changes.
        for oa in &a.e.others {
            let ob = b.e.others.iter().min_by(|x, y| (**x - oa).norm().total_cmp(&(**y - oa).norm()));
            if let Some(ob) = ob {
                if (oa.re < 0.0) != (ob.re < 0.0) {
                    out.push(Event::Other(*oa, *ob));
                }
            }
        }
        let (ua, ub) = (self.phys(a.s), self.phys(b.s));
        for k in 0..2 {
            for &m in &self.opts.marks[k] {
                if (ua[k] < m) != (ub[k] < m) && ua[k] != m {
                    out.push(Event::Mark(k, m));
                }
            }
        }
        out
    }

    /// Locate each event between `a` and `b` (arclength `h` along `a.t`) by the Illinois method on
    /// the arclength of the corrected point; returns the points in order along the curve.
    pub(super) fn locate_events<const N: usize>(&mut self, a: &Node, b: &Node, h: f64) -> Vec<(f64, CurvePoint)>
    where
        Fam: Family<N>,
    {
        let mut found = Vec::new();
        for ev in self.events_between(a, b) {
            let (mut x0, mut f0) = (0.0, self.event_value(ev, a, 0.0, h));
            let (mut x1, mut f1) = (h, self.event_value(ev, b, h, h));
            let mut best: Option<(f64, Node)> = None;
            let mut converged = false;
            for _ in 0..60 {
                let x = x1 - f1 * (x1 - x0) / (f1 - f0);
                if !(x > 0.0 && x < h) {
                    break;
                }
                let guess = a.e.lambda + (b.e.lambda - a.e.lambda) * (x / h);
                let Ok((s, e)) = self.correct(axpy(a.s, x, a.t), a.t, guess, h) else { break };
                let Ok(n) = self.node(s, e, a.t) else { break };
                let f = self.event_value(ev, &n, x, h);
                best = Some((x, n));
                if !f.is_finite() {
                    break;
                }
                if f == 0.0 || (x - x1).abs() <= self.opts.tol {
                    converged = true;
                    break;
                }
                if (f < 0.0) != (f1 < 0.0) {
                    (x0, f0) = (x1, f1);
                } else {
                    f0 *= 0.5;
                }
                (x1, f1) = (x, f);
                if (x1 - x0).abs() <= self.opts.tol {
                    converged = true;
                    break;
                }
            }
            if let Some((x, n)) = best {
                let kind = match ev {
                    Event::Bautin => PointType::Bautin,
                    Event::Other(oa, ob) if oa.im == 0.0 && ob.im == 0.0 => PointType::ZeroHopf,
                    Event::Other(..) => PointType::DoubleHopf,
                    Event::Mark(..) => PointType::Mark,
                };
                let status = if converged { Status::Success } else { Status::NotConverged };
                found.push((x, self.point(&n, kind, status)));
            }
        }
        found.sort_by(|p, q| p.0.total_cmp(&q.0));
        found
    }
}
