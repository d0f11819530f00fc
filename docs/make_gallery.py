"""Regenerate the charts of docs/gallery/ (and its README.md): ``python docs/make_gallery.py``.

Every chart comes from the public API, on grids small enough to run in a minute or two on two cores:

- ``regime_map.png``: the regime map of a normal load x arm length sweep at the seed's speed, with the
  attractor census (hatched: another attractor coexists; a ring: an unstable point's label that few
  disturbances reach) and the Hopf curves the sweep stores;
- ``facets.png``: a map over five sliding speeds with a Stribeck friction curve (one panel each, in rows);
- ``basin_fraction.png``: the census's basin fractions of that sweep, one panel per attractor;
- ``bifurcation.png``: the seed's unilateral cycles against the load (``ts.branch`` from the bouncing
  cycle both ways and from the Hopf point, drawn by ``ts.bifurcation_diagram``);
- ``stick_onset.png``: the regime map of a switch-law (stick-slip as a switch) sweep at 0.2 m/s with the
  curves it stores: the Hopf curve, and the stick curve where the cycles born there first stick;
- ``work_precision.png``: error against wall time per trajectory of the three Rust integrators and
  scipy on the report's seed scene (``tribosweep.bench``; timings are this machine's);
- ``sweep_settings.png``: the issue-10 Stribeck sweep's points/s against its agreement with a
  reference, over the transients' rtol x ``irregular_block`` (``tribosweep.bench.sweep_settings``);
- ``cycle_check.png``: where the Stribeck sweep's transients stopped on cycles against the orbits that
  shooting converged, and what the check costs (``tribosweep.bench.cycle_check``).

Options: ``--out DIR`` (default: docs/gallery next to this script), ``--skip-bench`` (no work-precision
chart), ``--dpi N`` (default 100: the size a README shows without scaling).
"""

from __future__ import annotations

import argparse
import pathlib
import platform
import time

import numpy as np

import tribosweep as ts
from tribosweep.plot import regime_map, variable_map

HERE = pathlib.Path(__file__).resolve().parent
STICK_ONSET = (
    "Regime map of the switch friction law (stick-slip as a switch, mu_static 0.3) at 0.2 m/s, 15 loads x 8 arm "
    "lengths, no census, with the curves the sweep stores: the Hopf curve, the stick curve (purple: where the "
    "cycles born at the Hopf curve first reach the stick band, the onset of their stick-slip) and, on 5.8-6.7 cm, "
    "the grazing and fold of those cycles; steady sliding is unstable over the whole box"
)


def sweeps() -> tuple:
    """The map's sweep (15 loads x 5 arm lengths, census of 16 disturbances) and a 5-speed one."""
    common = dict(samples=16, t_max=20.0, progress=False)
    one = ts.sweep(normal_load=np.linspace(10, 150, 15), arm_length=np.linspace(0.05, 0.127, 5), **common)
    stribeck = ts.SliderModel(friction_law="coulomb", mu_static=0.3)  # speed matters only with a Stribeck curve
    five = ts.sweep(stribeck, normal_load=np.linspace(10, 150, 8), arm_length=np.linspace(0.05, 0.127, 4),
                    sliding_speed=np.linspace(0.2, 1.0, 5), census=False, t_max=20.0, progress=False)  # fmt: skip
    return one, five


def bifurcation():
    """The seed's unilateral cycles against the load: the bouncing cycle's family, followed both ways from the
    seed. Upwards it turns at a fold (140.6 N), comes back down, turns again (19 N) and ends at the
    subcritical Hopf point (24.9 N): the small unstable cycle born there and the bouncing cycle are one family."""
    from matplotlib.lines import Line2D

    model = ts.SliderModel()
    orbit, _ = ts.follow_cycle(model)
    up = ts.branch(model, "normal_load", 150.0, start=84.46, orbit=orbit, bounds=(10.0, 150.0))
    down = ts.branch(model, "normal_load", 10.0, start=84.46, orbit=orbit)
    fig = ts.bifurcation_diagram(up)
    ax = fig.axes[0]
    ts.bifurcation_diagram(down, ax=ax)
    fig.set_size_inches(8.0, 5.0)
    fig.set_layout_engine("constrained")
    ax.plot([84.46], [orbit.A1.item() * 1e6] if "A1" in orbit else [], "s", color="k", ms=6, mfc="none")
    keys = [Line2D([], [], color="C0", ls="-", label="stable"), Line2D([], [], color="C3", ls="--", label="unstable"),
            Line2D([], [], color="k", marker="s", mfc="none", ls="none", label="the seed (84.46 N)")]
    keys += [Line2D([], [], ls="none", label=t) for t in ("H  Hopf point", "F  fold", "G  grazing (G/F: at a fold)",
                                                           "NS  Neimark-Sacker", "PD  period doubling")]
    ax.legend(handles=keys, fontsize=8, loc="upper left", handlelength=2.5)
    ax.set_title("the seed's bouncing cycle against the normal load (unilateral contact, mu = 0.215)", fontsize=10)
    hopf = ts.hopf_load(model, (1.0, 250.0))[0]["normal_load"]  # where the family ends (its amplitude -> 0)
    ax.plot([hopf], [0.0], "ko", ms=4)
    ax.annotate("H", (hopf, 0.0), textcoords="offset points", xytext=(4, 4), fontsize=8)
    # Four points within 5 N near 100 N: drawn again, magnified, so that their labels do not overlap.
    inset = ax.inset_axes([0.56, 0.07, 0.42, 0.42])
    for part in (up, down):
        ts.bifurcation_diagram(part, ax=inset)
    inset.set_xlim(97.0, 105.0)
    inset.set_ylim(27.0, 30.6)
    inset.set_title("")
    inset.set_xlabel("")
    inset.set_ylabel("")
    inset.get_legend().remove()
    inset.tick_params(labelsize=7)
    ax.indicate_inset_zoom(inset, edgecolor="0.4")
    return fig, (up, down)


def stick_onset():
    """A switch-law sweep at 0.2 m/s over the default box (no census) and the curves it stores."""
    model = ts.SliderModel(friction_law="switch", mu_static=0.3)
    ds = ts.sweep(model, normal_load=np.linspace(10, 150, 15), arm_length=np.linspace(0.05, 0.127, 8),
                  sliding_speed=[0.2], census=False, t_max=20.0, progress=False)  # fmt: skip
    return regime_map(ds)


def work_precision():
    from tribosweep.bench.charts import plot_work_precision
    from tribosweep.bench.workprecision import BenchConfig, measure

    payload = measure(BenchConfig(quick=True, scenes=["seed"], baselines=("scipy",)), progress=False)
    (scene,) = payload["scenes"]
    fig = plot_work_precision(payload["rows"], scene)
    fig.set_size_inches(8.5, 4.5)
    ax = fig.axes[0]
    # Each rung's rtol beside two lines of the same method (Rust and scipy DOP853): what a tolerance buys.
    for r in payload["rows"]:
        if r["label"] in ("rust dop853", "scipy DOP853") and not r["failed"]:
            ax.annotate(f"rtol {r['rtol']:.0e}", (max(r["error"], 1e-16), r["seconds_per_traj"]), fontsize=6,
                        textcoords="offset points", xytext=(-4, -9 if r["label"].startswith("rust") else 5),
                        ha="right", color="0.25")  # fmt: skip
    return fig


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "gallery"))
    ap.add_argument("--skip-bench", action="store_true")
    ap.add_argument("--dpi", type=int, default=100)
    a = ap.parse_args(argv)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    made = {}

    def save(fig, name, what):
        fig.savefig(out / name, dpi=a.dpi)
        made[name] = what
        print(f"{out / name}: {what}")

    t0 = time.perf_counter()
    one, five = sweeps()
    t_sweeps = time.perf_counter() - t0
    save(regime_map(one), "regime_map.png",
         "Regime map: 15 loads x 5 arm lengths at the seed's 0.46 m/s, the attractor census at 16 disturbances per "
         "point (hatched: another attractor coexists, with stable sliding or, where sliding is unstable, with the "
         "motion its transient reached; a ring: fewer than half the disturbances reach that motion) and the curves "
         "the sweep stores: the Hopf curve (sliding is unstable to its lower left) and the saddle cycle's grazing "
         "curve, here also its fold")
    save(regime_map(five), "facets.png", "Regime map over five sliding speeds with a Stribeck friction curve "
         "(mu_static 0.3, no census): one panel per speed, in rows of four")
    save(variable_map(one, "basin_fraction"), "basin_fraction.png",
         "Basin fractions of the regime map's census, one panel per attractor (white: no census there: stable "
         "sliding with no saddle cycle to find)")
    fig, _ = bifurcation()
    save(fig, "bifurcation.png", "The seed's bouncing cycle against the load (ts.branch both ways from the seed, "
         "ts.bifurcation_diagram): stable between its Neimark-Sacker points, it turns at folds at 140.6 and 19 N "
         "and ends at the subcritical Hopf point (24.9 N)")
    save(stick_onset(), "stick_onset.png", STICK_ONSET)
    if not a.skip_bench:
        save(work_precision(), "work_precision.png",
             "Work-precision of the Rust integrators and scipy on the report's seed scene (bilateral, 0.5 s from "
             f"1 um; one thread of a {platform.machine()} machine, labels: rtol)")
        from tribosweep.bench.sweep_settings import sweep_settings

        ss = sweep_settings(out, quick=True)
        made["sweep_settings.png"] = (
            "The Stribeck sweep (switch law, 200 points, t_max 20 s, 2 threads of a "
            f"{platform.machine()} machine) over the transients' rtol x irregular_block: points/s against the regimes "
            "that differ from a reference run to t_max at rtol 1e-10 (grey: the reference itself at rtol +-1 %) and "
            "against the cycles' amplitude error"
        )
        print(f"{ss['files']['sweep_settings']}: {made['sweep_settings.png']}")
        from tribosweep.bench.cycle_check import cycle_check

        cc = cycle_check(out, quick=True)
        made["cycle_check.png"] = (
            "The Stribeck sweep's cycles (both laws, 200 points each): the z1 amplitude where each transient stopped "
            "against the orbit shooting converged, over the gap of its slowest Floquet multiplier to 1 (dashed: "
            f"periodic_tol / (1 - |mu|)), and the sweep's wall time with that check and without it (2 threads of a "
            f"{platform.machine()} machine)"
        )
        print(f"{cc['files']['cycle_check']}: {made['cycle_check.png']}")
    lines = ["# Gallery", "", "Regenerate with `python docs/make_gallery.py` (the sweeps took "
             f"{t_sweeps:.0f} s on the machine that drew these). Each chart is described in "
             "[the guide](../guide.md).", ""]
    for name, what in made.items():
        lines += [f"## {name}", "", what + ".", "", f"![{name}]({name})", ""]
    (out / "README.md").write_text("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
