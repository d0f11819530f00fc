"""The seed census against pybasin 0.2.0 on the same model and the same samples, in one run.

pybasin (adrianwix/pybasin, the Python port of bSTAB) estimates basin stability by brute force:
integrate every sample over a fixed horizon with diffrax's Dopri5 (its JAX backend, here on CPU),
extract features of the last window, and classify them against template trajectories. tribosweep's
census runs each sample to its attractor, with the contact switches located as events and early
stops (cycle repeated, motion back inside the saddle). Both get the census's own disturbances
(``ts.census(...).y0``), so the fractions compare sample by sample.

pybasin needs Python >= 3.12 (PEP 695 generics in its source), the project's 3.11 does not run it.
Build a 3.12 environment with both packages, then run this script with its interpreter::

    bash benches/pybasin_env.sh                      # -> .venv-pybasin (needs a python3.12)
    .venv-pybasin/bin/python benches/bench_pybasin.py --samples 1024

The pybasin side of the model, written for this comparison (the same right-hand side as
``tribosweep.bench.reference.rhs`` with ``contact="unilateral"``, the pointwise switching law):
the state is scaled by the census's characteristic sizes (``|z_st|`` for z and x, ``|z_st|/L`` for
phi, times the torsional frequency for the rates), so that a scalar ``atol`` means the same in every
component, as the core's per-component atol does. The switch is a ``jnp.where``: pybasin has no
event location, its step-size controller steps across each touch and lift-off.

What is printed: the wall time of each side (pybasin's integration and its whole estimator run,
including feature extraction and classification, after a warm-up that pays JAX's compilation on 8
samples), the fractions of both, and the sample-by-sample agreement where the census reached
sliding or a cycle.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("JAX_PLATFORMS", "cpu")

import numpy as np

import tribosweep as ts
from tribosweep._irregular import characteristic_sizes
from tribosweep.bench.reference import _Coeffs

try:
    import jax
    import jax.numpy as jnp
    import torch
    from pybasin import BasinStabilityEstimator
    from pybasin.feature_extractors.feature_extractor import FeatureExtractor
    from pybasin.sampler import Sampler
    from pybasin.solvers import JaxSolver
    from pybasin.solvers.jax_ode_system import JaxODESystem
    from pybasin.template_integrator import TemplateIntegrator
    from sklearn.neighbors import KNeighborsClassifier
except ImportError as e:  # pragma: no cover - depends on the optional environment
    sys.exit(f"bench_pybasin needs pybasin[jax] 0.2.0 ({e}); build its environment with benches/pybasin_env.sh")

jax.config.update("jax_enable_x64", True)


class SliderJax(JaxODESystem):  # the 3-DOF slider, unilateral contact, in scaled state
    """docs/model.md §2 with the unilateral contact (pointwise switching law), state divided by ``sizes``."""

    def ode(self, t, u, p):
        s = p[13:19]
        y = u * s
        m, wz2, wx2, wt2, cz, cx, ct, k_s, k_a, c_zc, k_phi, mu, f_st = (p[i] for i in range(13))
        z_st, gain = p[19], p[20]
        n_law = f_st - k_s * y[0] + k_a * y[0] * y[0] - c_zc * y[1] + k_phi * y[4]
        n = jnp.where((z_st + y[0] <= 0.0) & (n_law >= 0.0), n_law, 0.0)
        f_z = n - f_st
        f_x = mu * f_z
        dy = jnp.stack([
            y[1], f_z / m - cz * y[1] - wz2 * y[0],
            y[3], f_x / m - cx * y[3] - wx2 * y[2],
            y[5], gain * f_x - ct * y[5] - wt2 * y[4],
        ])  # fmt: skip
        return dy / s

    def get_str(self) -> str:
        return "tribosweep seed slider, unilateral contact, scaled state"


class FixedSamples(Sampler):
    """The census's own disturbances (float64, scaled), in order."""

    display_name = "tribosweep census samples"

    def __init__(self, u: np.ndarray):
        super().__init__(list(u.min(axis=0)), list(u.max(axis=0)), device="cpu")
        self._u = torch.tensor(u, dtype=torch.float64)

    def sample(self, n: int) -> torch.Tensor:
        if n != self._u.shape[0]:
            raise ValueError(f"n = {n}: this sampler holds exactly {self._u.shape[0]} samples")
        return self._u.clone()


class HalfRange(FeatureExtractor):
    """Half the peak-to-peak range of each scaled component over the window (docs example of pybasin's
    ``FeatureExtractor``): sliding's features shrink towards 0, the bouncing cycle's are its amplitudes."""

    def extract_features(self, solution) -> torch.Tensor:
        y = self.filter_time(solution)  # (N', B, S)
        self._num_features = y.shape[2]
        return 0.5 * (y.max(dim=0).values - y.min(dim=0).values)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=1024)
    ap.add_argument("--horizon", type=float, default=5.0, help="pybasin's integration horizon, s (the issue's 5 s)")
    ap.add_argument("--window", type=float, default=0.2, help="pybasin's feature window at the end, s")
    ap.add_argument("--rtol", type=float, default=1e-8, help="pybasin's Dopri5 rtol (the issue's 1e-8)")
    ap.add_argument("--atol", type=float, default=1e-8, help="pybasin's atol on the scaled state")
    ap.add_argument("--referee", type=int, default=5, help="disagreements judged by the scipy reference")
    ap.add_argument("--referee-horizon", type=float, default=30.0, help="the scipy referee's horizon, s")
    ap.add_argument("--threads", type=int, default=None, help="census threads (default: all cores)")
    a = ap.parse_args()
    print(f"cores {os.cpu_count()}, load average {os.getloadavg()[0]:.2f}; jax {jax.__version__}, "
          f"devices {jax.devices()}")  # fmt: skip

    m = ts.SliderModel(contact="unilateral")
    params = {k: float(v) for k, v in m.values().items()}
    ts.census(m, samples=8, threads=a.threads)  # warm-up (first-call costs), as pybasin's below
    walls = {}
    for th in (1, a.threads):
        t0 = time.perf_counter()
        ds = ts.census(m, samples=a.samples, threads=th)
        walls[th] = time.perf_counter() - t0
    core = [ts.ATTRACTOR_NAMES[i] if i >= 0 else "failed" for i in ds.attractor_reached.values]
    pc, sc = ds.basin_fraction.values, ds.basin_fraction_se.values

    sizes = characteristic_sizes(params)[0]
    c = _Coeffs.of(params)
    p = np.array([c.m, c.wz2, c.wx2, c.wt2, c.cz, c.cx, c.ct, c.k_s, c.k_a, c.c_zc, c.k_phi, c.mu, c.f_st,
                  *sizes, c.z_st, c.torque_gain])  # fmt: skip
    pdict = {f"p{i:02d}": float(v) for i, v in enumerate(p)}
    u0 = np.asarray(ds.y0.values) / sizes
    orbit, _ = ts.follow_cycle(m)
    templates = [[0.0] * 6, list(np.asarray(orbit.state0.values) / sizes)]
    labels = ["sliding", "cycle"]

    def estimator(u: np.ndarray) -> BasinStabilityEstimator:
        solver = JaxSolver(t_span=(0.0, a.horizon), t_steps=1000, t_eval=(a.horizon - a.window, a.horizon),
                           rtol=a.rtol, atol=a.atol, device="cpu", cache_dir=None)  # fmt: skip
        return BasinStabilityEstimator(
            ode_system=SliderJax(pdict), sampler=FixedSamples(u), n=u.shape[0], solver=solver,
            feature_extractor=HalfRange(time_steady=a.horizon - a.window), feature_selector=None,
            predictor=KNeighborsClassifier(n_neighbors=1),
            template_integrator=TemplateIntegrator(templates, labels, pdict), output_dir=None,
        )  # fmt: skip

    import logging

    logging.getLogger("pybasin").setLevel(logging.WARNING)
    estimator(u0[:8]).run()  # warm-up: JAX compiles for this batch shape only; a new n recompiles
    bse = estimator(u0)
    t0 = time.perf_counter()
    res = bse.run()
    t_pb = time.perf_counter() - t0
    solver = JaxSolver(t_span=(0.0, a.horizon), t_steps=1000, t_eval=(a.horizon - a.window, a.horizon),
                       rtol=a.rtol, atol=a.atol, device="cpu", cache_dir=None)  # fmt: skip
    t0 = time.perf_counter()
    solver.integrate(SliderJax(pdict), torch.tensor(u0, dtype=torch.float64))
    t_int = time.perf_counter() - t0
    pb = [str(x) for x in res["labels"]]

    k = a.samples
    print(f"seed census, unilateral, K = {k} (the same samples on both sides)")
    for th, w in walls.items():
        print(f"  tribosweep census, {th or os.cpu_count()} thread(s): {w:.2f} s ({k / w:.0f} disturbances/s); "
              f"mean simulated time {ds.t_end.values.mean():.2f} s per disturbance")  # fmt: skip
    print(f"  pybasin 0.2.0 (JaxSolver Dopri5, rtol {a.rtol:g}, horizon {a.horizon:g} s, half-range features, 1-NN on templates): "
          f"{t_pb:.1f} s in all ({k / t_pb:.1f} disturbances/s), integration alone {t_int:.1f} s")  # fmt: skip
    best = min(walls.values())
    print(f"  ratio: pybasin / tribosweep = {t_pb / best:.0f}x (whole run, tribosweep's best), "
          f"{t_pb / walls[1]:.0f}x (tribosweep on one thread)")  # fmt: skip
    frac = ", ".join(f"{n} {x:.3f}+-{s:.3f}" for n, x, s in zip(ts.ATTRACTOR_NAMES, pc, sc))
    print(f"  tribosweep fractions: {frac}")
    for name in sorted(set(pb)):
        q = pb.count(name) / k
        print(f"  pybasin {name}: {q:.3f}+-{np.sqrt(q * (1 - q) / k):.3f}")
    both = [(x, y) for x, y in zip(core, pb) if x in ("sliding", "cycle")]
    agree = sum(x == y for x, y in both)
    print(f"  sample by sample, where the census reached sliding or a cycle: {agree} of {len(both)} agree "
          f"({100 * agree / max(len(both), 1):.1f} %)")  # fmt: skip
    irr = [y for x, y in zip(core, pb) if x == "irregular"]
    if irr:
        print(f"  census-irregular samples ({len(irr)}) pybasin called: "
              + ", ".join(f"{n} {irr.count(n)}" for n in sorted(set(irr))))
    mism = [(i, x, y, float(t)) for i, (x, y, t) in enumerate(zip(core, pb, ds.t_end.values))
            if x in ("sliding", "cycle") and x != y]  # fmt: skip
    if mism:
        # A referee for the disagreements: the event-driven scipy reference (every switch located),
        # judged on its last windows by tribosweep.bench.census_check (no code shared with the core).
        from tribosweep.bench import census_check

        half = census_check.cycle_half_range(params, orbit.state0.values)
        for i, x, y, t in mism[: a.referee]:
            ref = census_check.classify_unilateral(params, ds.y0.values[i], a.referee_horizon, float(ds.attrs["saddle_a1"]),
                                                   half, rtol=1e-10)  # fmt: skip
            print(f"    sample {i}: census {x} (stopped at {t:.2f} s), pybasin {y}; "
                  f"scipy event-driven, rtol 1e-10, to {a.referee_horizon:g} s: {ref}")  # fmt: skip


if __name__ == "__main__":
    main()
