"""The seed configuration's analysis, end to end: the table the README shows, computed by the code."""

from __future__ import annotations

import json
import pathlib

import numpy as np

from ._frequency import describing_function, follow_cycle, hopf_load, linear_stability, periodic_orbit
from ._model import SliderModel
from ._simulate import ensemble

# The report's solution and the experiment (docs/model.md §5), printed values: not computed here.
REPORT_SOLUTION = dict(omega=647.034, A0=0.42e-6, A1=14.460e-6, A2=2.289e-6, theta_deg=253.31, phi1=1.413e-3,
                       phi1_deg=180.21, x=2.864e-6, x_deg=-0.70)
EXPERIMENT = dict(omega=644.026, A0=float("nan"), A1=14.774e-6, A2=2.248e-6, theta_deg=102.85, phi1=1.540e-3,
                  phi1_deg=176.61, x=3.813e-6, x_deg=-6.63)

_DEG = 180 / np.pi


def seed_analysis(model: SliderModel | None = None) -> dict:
    """Linear stability, Hopf load, describing-function roots, the bilateral shooting orbit and the
    unilateral bouncing cycle of ``model`` (default: the seed configuration).

    Returns a dict of plain numbers (SI; angles in degrees where the key ends in ``_deg``).
    """
    m = model or SliderModel()
    lin = linear_stability(m)
    hopf = hopf_load(m)
    df = describing_function(m)
    phys = [i for i in range(df.sizes["root"]) if int(df.physical[i]) == 1]
    out: dict = {
        "eigen_growth_rate": dict(zip(lin.mode.values.tolist(), lin.mode_growth_rate.values.tolist())),
        "eigen_frequency": dict(zip(lin.mode.values.tolist(), lin.mode_frequency.values.tolist())),
        "stable": bool(lin.stable),
        "hopf_loads": [h["normal_load"] for h in hopf],
        "tidf_search_outcome": df.attrs["search_outcome"],
        "tidf_roots": [
            {k: float(df[k][i]) for k in ("omega", "A0", "A1", "A2", "theta", "third_harmonic_ratio")}
            | {"physical": bool(df.physical[i]), "contact_opens": bool(df.contact_opens[i])}
            for i in range(df.sizes["root"])
        ],
    }
    if phys:
        r = df.isel(root=phys[0])
        out["tidf"] = dict(omega=float(r.omega), A0=float(r.A0), A1=float(r.A1), A2=float(r.A2),
                           theta_deg=float(r.theta) * _DEG, phi1=float(r.phi1_amplitude),
                           phi1_deg=float(r.phi1_phase) * _DEG % 360, x=float(r.x1_amplitude), x_deg=float(r.x1_phase) * _DEG)
        orb = periodic_orbit(m.replace(contact="bilateral"), r)
        out["orbit"] = dict(omega=float(orb.omega), period=float(orb.period), A0=float(orb.A0), A1=float(orb.A1),
                            A2=float(orb.A2), A3=float(orb.A3), theta_deg=float(orb.theta) * _DEG,
                            moduli=orb.floquet_moduli.values.tolist(),
                            stable=bool(orb.stable) if "stable" in orb else None,
                            z_max=float(orb.z_max), fraction_off_disk=float(orb.fraction_off_disk), status=int(orb.status))
    # The unilateral bouncing cycle, followed from mu = 0.30 (where it is the attractor a small
    # disturbance grows into) down to the model's mu by shooting: a property of the model, not of
    # one trajectory. docs/model.md §6's recipe (22 s at 0.30, then a transient at 0.215) lands near a
    # basin boundary, and its outcome flips with the last bit of a float. The harmonics are then
    # read by a run started on the orbit (it repeats within two periods).
    um = m.replace(contact="unilateral")
    orb, _path = follow_cycle(um)
    cyc = ensemble(um, 1.0, {"mu": [m.mu]}, y0=orb.state0.values, steady=True, rtol=1e-11, method="dop853")
    out["bouncing"] = dict(omega=float(cyc.omega[0]), A0=float(cyc.z0[0]), A1=float(cyc.z1_amplitude[0]),
                           A2=float(cyc.z2_amplitude[0]), A3=float(cyc.z3_amplitude[0]), theta_deg=float(cyc.z2_phase[0]) * _DEG,
                           phi1=float(cyc.phi1_amplitude[0]), phi1_deg=float(cyc.phi1_phase[0]) * _DEG,
                           fraction_off_disk=float(cyc.fraction_off_disk[0]), stable=bool(orb.stable),
                           orbit_omega=float(orb.omega), moduli=orb.floquet_moduli.values.tolist())  # fmt: skip
    return out


def comparison_table(a: dict) -> str:
    """Markdown table: this reading / the report's solution / the experiment / the shooting orbit / the bouncing cycle."""
    um = 1e6
    rows = []

    def row(name, d, phi=True):
        def f(key, scale=1.0, fmt="{:.3f}"):
            v = d.get(key, float("nan"))
            return "-" if v is None or (isinstance(v, float) and np.isnan(v)) else fmt.format(v * scale)
        rows.append(f"| {name} | {f('omega')} | {f('A0', um)} | {f('A1', um)} | {f('A2', um)} | {f('theta_deg', fmt='{:.2f}')} | "
                    + (f"{f('phi1', fmt='{:.3e}')} ({f('phi1_deg', fmt='{:.2f}')})" if phi else "-") + " |")

    head = ("| source | w rad/s | A0 um | A1 um | A2 um | theta deg | phi1 rad (deg) |\n"
            "|---|---|---|---|---|---|---|")
    if "tidf" in a:
        row("describing function, this reading", a["tidf"])
    row("report's solution (printed)", REPORT_SOLUTION)
    row("experiment (printed)", EXPERIMENT)
    if "orbit" in a:
        o = a["orbit"]
        row(f"shooting orbit, bilateral ({'stable' if o['stable'] else 'unstable'}; contact open {o['fraction_off_disk']:.0%})", o, phi=False)
    b = a["bouncing"]
    row(f"bouncing cycle, unilateral (off the disk {b['fraction_off_disk']:.1%})", b)
    return head + "\n" + "\n".join(rows)


def write_seed_report(out_dir: str | pathlib.Path) -> str:
    """Compute :func:`seed_analysis`, write ``seed_report.json`` and ``seed_report.md``; return the markdown."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    a = seed_analysis()
    table = comparison_table(a)
    hopf = ", ".join(f"{h:.3f} N" for h in a["hopf_loads"]) or "none in 1-250 N"
    md = (
        "# Seed configuration (docs/model.md §3-6), computed by tribosweep\n\n"
        f"Linear stability: {'stable' if a['stable'] else 'unstable'} sliding; torsion mode "
        f"{a['eigen_growth_rate']['torsion']:.4f} +- {a['eigen_frequency']['torsion']:.2f}j 1/s. "
        f"Hopf load(s): {hopf} (sliding is unstable BELOW it in this model — the opposite of the "
        "report's experiments, where self-excitation starts above a critical load).\n\n"
        f"Describing function: {len(a['tidf_roots'])} root(s), {sum(r['physical'] for r in a['tidf_roots'])} physical.\n\n"
        + table + "\n"
    )
    (out / "seed_report.json").write_text(json.dumps(a, indent=1))
    (out / "seed_report.md").write_text(md)
    return md
