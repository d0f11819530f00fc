"""Frequency-domain speed: warm-started TIDF Newton solves, all-roots searches, shooting solves.

Issue 3's benchmark. Baseline in the same process: scipy.optimize.root (MINPACK hybrd) on the same
five equations, written here independently from docs/model.md §5 in numpy. Per-core rates (one thread).

    python benches/bench_frequency.py [--solves 20000] [--searches 200] [--shoots 20]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.optimize import root

import tribosweep as ts
from tribosweep import _core


def tidf_residual(x, p):
    """The consistent reading of docs/model.md §5, scaled like the Rust core: 4 harmonic equations / K_s,
    the DC balance / (K_s |z_st|)."""
    w, a0, a1, a2, th = x
    z_st, k_s = ts.SliderModel(**p).static_point()
    m, wz, zz, wt, zt = p["mass"], p["omega_normal"], p["zeta_normal"], p["omega_torsion"], p["zeta_torsion"]
    ka, c, kphi, mu, L, inertia, s = (p["contact_quadratic"], p["contact_damping"], p["twist_coupling"], p["mu"],
                                       p["moment_arm"], p["inertia"], p["torsion_sign"])

    def lin(k):
        lz = -(k * w) ** 2 + wz**2 + 2j * zz * wz * k * w
        lt = -(k * w) ** 2 + wt**2 + 2j * zt * wt * k * w
        return m * lz * (1 - s * mu * L * kphi / (inertia * lt)) + k_s + 1j * k * w * c

    n1 = ka * ((2 * a0 - a2 * np.sin(th)) + 1j * a2 * np.cos(th))
    n2 = ka * ((2 * a0 - a1**2 / (2 * a2) * np.sin(th)) - 1j * a1**2 / (2 * a2) * np.cos(th))
    e1, e2 = lin(1) - n1, lin(2) - n2
    phi0 = s * (L / inertia) * mu * m * wz**2 * a0 / wt**2
    dc = -k_s * a0 + ka * (a0**2 + (a1**2 + a2**2) / 2) + kphi * phi0 - m * wz**2 * a0
    return np.array([e1.real, e1.imag, e2.real, e2.imag]) / k_s, dc / (k_s * abs(z_st))


def scipy_residual(x, p, scale):
    # Solve in scaled unknowns (w / w_t, A / |z_st|, theta), as the Rust Newton does.
    r4, dc = tidf_residual(x * scale, p)
    return np.append(r4, dc)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--solves", type=int, default=20000)
    ap.add_argument("--searches", type=int, default=200)
    ap.add_argument("--shoots", type=int, default=20)
    a = ap.parse_args(argv)
    model = ts.SliderModel(contact="bilateral")  # the describing function's law (and its shooting orbit)
    p = model.values()
    df = ts.describing_function(model)
    r = df.isel(root=int(np.argmax(df.physical.values)))
    x_root = np.array([float(r[k]) for k in ("omega", "A0", "A1", "A2", "theta")])
    assert np.max(np.abs(np.append(*tidf_residual(x_root, p)))) < 1e-9, "independent residual disagrees with the core"

    rng = np.random.default_rng(0)
    guesses = x_root * (1 + 0.02 * rng.standard_normal((a.solves, 5)))
    t0 = time.perf_counter()
    out = _core.tidf_solve(p, "constant", guesses, threads=1)
    t_rust = time.perf_counter() - t0
    ok = (out["status"] == 0) & (np.abs(out["x"][:, 0] - x_root[0]) < 1e-6)
    print(f"warm-start Newton (2 % perturbed guesses): Rust {a.solves / t_rust:10.0f} solves/s/core, "
          f"{ok.mean():.1%} reach the seed root, mean {out['iterations'].mean():.1f} iterations")
    z_st = abs(model.static_point()[0])
    scale = np.array([p["omega_torsion"], z_st, z_st, z_st, 1.0])
    k = min(a.solves, 500)
    t0 = time.perf_counter()
    sc_ok = 0
    for g in guesses[:k]:
        sol = root(scipy_residual, g / scale, args=(p, scale), method="hybr", tol=1e-13)
        xs = sol.x * scale
        sc_ok += bool(sol.success and abs(xs[0] - x_root[0]) < 1e-6)
    t_sc = time.perf_counter() - t0
    print(f"                                           scipy {k / t_sc:10.0f} solves/s, {sc_ok / k:.1%} reach it"
          f"  -> Rust/scipy {a.solves / t_rust / (k / t_sc):.0f}x")

    loads = rng.uniform(17, 152, a.searches)
    t0 = time.perf_counter()
    s = _core.describing_function(p, "bilateral", "constant", ["normal_load"], loads[:, None], threads=1)
    t_s = time.perf_counter() - t0
    print(f"all-roots search (load 17-152 N): Rust {a.searches / t_s:8.0f} searches/s/core "
          f"({t_s / a.searches * 1e3:.3f} ms each), mean {s['n_roots'].mean():.1f} roots")
    # Baseline all-roots: scipy root from a grid of 64 starts per point (w x theta, A from the
    # seed root), deduplicated: the naive way without the closed-form elimination.
    starts = [(w, th) for w in np.geomspace(150, 3000, 16) for th in np.linspace(0, 2 * np.pi, 4, endpoint=False)]
    kk = min(5, a.searches)
    t0 = time.perf_counter()
    found = []
    for load in loads[:kk]:
        pp = dict(p, normal_load=float(load))
        zs = abs(ts.SliderModel(**pp).static_point()[0])
        sc = np.array([pp["omega_torsion"], zs, zs, zs, 1.0])
        roots = set()
        for w, th in starts:
            g = np.array([w, x_root[1], x_root[2], x_root[3], th]) / sc
            sol = root(scipy_residual, g, args=(pp, sc), method="hybr", tol=1e-12)
            if sol.success and sol.x[2] > 0 and sol.x[3] > 0:
                roots.add(round(sol.x[0] * sc[0], 3))
        found.append(len(roots))
    t_b = time.perf_counter() - t0
    print(f"                                  scipy grid of 64 starts {kk / t_b:8.1f} searches/s "
          f"(found {np.mean(found):.1f} roots on average vs Rust {s['n_roots'][:kk].mean():.1f})"
          f"  -> Rust/scipy {(a.searches / t_s) / (kk / t_b):.0f}x")

    t0 = time.perf_counter()
    for _ in range(a.shoots):
        orb = ts.periodic_orbit(model, r)
    t_o = (time.perf_counter() - t0) / a.shoots
    print(f"shooting with Floquet multipliers (seed, rtol 1e-11): {t_o * 1e3:.2f} ms per solve, "
          f"{int(orb.newton_iterations)} Newton iterations, {int(orb.n_rhs)} rhs")
    orb6 = None
    t0 = time.perf_counter()
    for _ in range(a.shoots):
        orb6 = ts.periodic_orbit(model, r, rtol=1e-8, tol=1e-6)
    t6 = (time.perf_counter() - t0) / a.shoots
    print(f"                                       (rtol 1e-8):   {t6 * 1e3:.2f} ms per solve, period error "
          f"{abs(float(orb6.period) / float(orb.period) - 1):.1e}")
    # Batched: many parameter sets in one call (the sweep's shooting stage), mu 0.19-0.26.
    mus = np.linspace(0.19, 0.26, 8 * a.shoots)
    dfb = _core.describing_function(model.values(), "bilateral", model.friction_law, ["mu"], mus[:, None])
    keep = dfb["physical"].max(axis=1) == 1
    kb = np.argmax(dfb["physical"], axis=1)[keep]
    roots_b = np.column_stack([dfb[v][np.flatnonzero(keep), kb] for v in ("omega", "A0", "A1", "A2", "theta")])
    rows = mus[keep][:, None]
    t0 = time.perf_counter()
    for i in range(rows.shape[0]):
        _core.periodic_orbit(model.replace(mu=float(rows[i, 0])).values(), "bilateral", model.friction_law,
                             root=roots_b[i])  # fmt: skip
    t_single = (time.perf_counter() - t0) / rows.shape[0]
    for th in sorted({1, os.cpu_count() or 1}):
        t0 = time.perf_counter()
        _core.periodic_orbits(model.values(), "bilateral", model.friction_law, ["mu"], rows, roots=roots_b, threads=th)
        t_b = (time.perf_counter() - t0) / rows.shape[0]
        print(f"batched shooting, {rows.shape[0]} orbits, {th} thread(s): {t_b * 1e3:.3f} ms per orbit (wall) "
              f"-> {t_single / t_b:.2f}x one call per orbit ({t_single * 1e3:.3f} ms)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
