//! Seeds of the Hopf curves: sign changes of a complex pair's real part along a grid's edges.

use super::{axpy, dot, norm, sub, Ctx, Eval};
use crate::hopf::{Family, C64};

/// Seeds: sign changes of a complex pair's real part along the edges of the grid, located on the edge.
pub(super) fn seeds<Fam: Family<N>, const N: usize>(ctx: &mut Ctx<'_, Fam>) -> Vec<([f64; 2], Eval)> {
    let [nx, ny] = ctx.opts.grid;
    let node_s = |i: usize, j: usize| [i as f64 / (nx - 1) as f64, j as f64 / (ny - 1) as f64];
    let mut spec: Vec<Option<Vec<C64>>> = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            let p = ctx.phys(node_s(i, j));
            let ev = crate::hopf::jacobian_at(ctx.fam, &p, &mut ctx.cnt).ok().and_then(|(_, a)| {
                ctx.cnt.n_eig += 1;
                crate::hopf::spectrum(&a)
            });
            spec.push(ev.map(|v| v.into_iter().filter(|e| e.im > 0.0).collect()));
        }
    }
    let mut out = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            for (di, dj) in [(1, 0), (0, 1)] {
                let (i2, j2) = (i + di, j + dj);
                if i2 >= nx || j2 >= ny {
                    continue;
                }
                let (Some(ea), Some(eb)) = (&spec[i * ny + j], &spec[i2 * ny + j2]) else { continue };
                for la in ea {
                    let Some(lb) = eb.iter().min_by(|x, y| (**x - la).norm().total_cmp(&(**y - la).norm())) else {
                        continue;
                    };
                    if (la.re < 0.0) == (lb.re < 0.0) {
                        continue;
                    }
                    if let Some(seed) = seed_on_edge(ctx, node_s(i, j), node_s(i2, j2), *la, *lb) {
                        out.push(seed);
                    }
                }
            }
        }
    }
    out
}

/// Newton (safeguarded by bisection) on `Re lambda` along the edge from `sa` to `sb`.
fn seed_on_edge<Fam: Family<N>, const N: usize>(
    ctx: &mut Ctx<'_, Fam>,
    sa: [f64; 2],
    sb: [f64; 2],
    la: C64,
    lb: C64,
) -> Option<([f64; 2], Eval)> {
    let d = sub(sb, sa);
    let (mut xa, mut xb, mut fa) = (0.0, 1.0, la.re);
    let mut x = fa / (fa - lb.re);
    for _ in 0..100 {
        let s = axpy(sa, x, d);
        let e = ctx.eval(s, la + (lb - la) * x).ok()?;
        let (f, df) = (e.lambda.re, dot(e.g, d));
        if f == 0.0 {
            return Some((s, e));
        }
        if (f < 0.0) == (fa < 0.0) {
            (xa, fa) = (x, f);
        } else {
            xb = x;
        }
        let newton = x - f / df;
        let next = if df.is_finite() && newton > xa.min(xb) && newton < xa.max(xb) { newton } else { 0.5 * (xa + xb) };
        let done = (next - x).abs() <= ctx.opts.tol;
        x = next;
        if done {
            let s = axpy(sa, x, d);
            let e = ctx.eval(s, e.lambda).ok()?;
            return Some((s, e));
        }
    }
    None
}

/// Distance from `s` to the segment `[a, b]`.
pub(super) fn segment_distance(s: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64) {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 > 0.0 { (dot(sub(s, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (norm(sub(s, axpy(a, t, ab))), t)
}
