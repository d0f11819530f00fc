"""The output schema of a sweep: every variable, its dtype, units, long name and CF flags, in one place.

Per-point variables (:data:`POINT_VARIABLES`, the census's and the irregular measurement's), the
trailing ``attractor`` dimension, the coordinates and small static variables of a plan, and the
global attributes. The writers (:mod:`tribosweep._sweep.netcdf`) only write what this declares.
"""

from __future__ import annotations

import datetime
import json
from dataclasses import dataclass, field

import numpy as np

from .. import _apparatus, _census, _irregular, _wear
from .._codes import (
    ATTRACTOR_DOC,
    ATTRACTOR_NAMES,
    BISTABLE_NAMES,
    BISTABLE_VALUES,
    DECIDED_BY_NAMES,
    REGIME_DOC,
    REGIME_NAMES,
    SWEEP_STATUS_NAMES,
    SWEEP_STATUS_VALUES,
    WEAR_APPLICABILITY_NAMES,
    flag_attrs,
)
from .._model import PARAM_LONG_NAMES, PARAM_UNITS
from .plan import AXIS_ATTRS, Plan

HOPF_CAVEAT: str = (
    "In this model (docs/model.md section 4) steady sliding is linearly unstable BELOW a Hopf load (24.90 N at the "
    "seed's mu = 0.215, with K_phi, C_zc and mu fixed), so self-excitation appears at low loads: the opposite "
    "of the 1985 report's experiments, where self-excitation starts above a critical load. Stable sliding can "
    "also coexist with a stable bouncing cycle (as at the seed point), so a point's regime can depend on the "
    "initial disturbance; the bistable variable says whether that was checked."
)
REFERENCES: str = (
    "Interactions between friction-induced vibration and wear, Illinois Institute of Technology report, 1985 "
    "(chapter IV; appendix 3: self-excited vibrations; appendix 4: wear model)"
)


def coords(plan: Plan) -> dict:
    out = {}
    for d, a in plan.axes.items():
        attrs = dict(AXIS_ATTRS[d]) if d in AXIS_ATTRS else {"units": PARAM_UNITS[d], "long_name": PARAM_LONG_NAMES[d]}
        out[d] = (a, attrs)
    return out


def static_vars(plan: Plan) -> dict:
    arm = plan.axes["arm_length"]
    w = _apparatus.arm_frequencies(arm, plan.model)
    out = {}
    for mode, fname in _apparatus.MODE_FIELDS.items():
        out[fname] = (
            ("arm_length",),
            np.asarray(w[fname], dtype=np.float64).reshape(arm.shape),
            {"units": "rad s-1", "long_name": f"{PARAM_LONG_NAMES[fname]} (arm-length power law, exponent "
             f"{_apparatus.ARM_EXPONENTS[mode]:.3f})"},
        )  # fmt: skip
    flag = ("within_identified_range", "extrapolated")
    out["normal_load_extrapolated"] = (
        ("normal_load",),
        _apparatus.load_extrapolated(plan.axes["normal_load"]).astype(np.uint8),
        flag_attrs(flag, "load outside the contact law's identification range 22-93 N", (0, 1)),
    )
    out["arm_length_extrapolated"] = (
        ("arm_length",),
        _apparatus.arm_extrapolated(arm).astype(np.uint8),
        flag_attrs(flag, "arm length outside the report's tables 0.05-0.127 m", (0, 1)),
    )
    return out


def software_versions() -> dict[str, str]:
    """Versions of the software that computed and wrote a sweep (global attributes)."""
    import platform

    import netCDF4
    import xarray

    return {
        "numpy_version": np.__version__,
        "xarray_version": xarray.__version__,
        "netCDF4_version": netCDF4.__version__,
        "netcdf_library_version": netCDF4.__netcdf4libversion__,
        "hdf5_version": netCDF4.__hdf5libversion__,
        "python_version": platform.python_version(),
    }


def global_attrs(plan: Plan, command: str, f_ref: float) -> dict:
    from .. import __version__

    now = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    attrs = {
        "Conventions": "CF-1.11",
        "title": "tribosweep regime map of the 1985 pin-on-disk slider over normal load, arm length and sliding speed",
        "institution": "tribosweep",
        "source": f"tribosweep {__version__}",
        "tribosweep_version": __version__,
        "tribosweep_core_build": plan.config["core_build"],
        **software_versions(),
        # The whole configuration (model, contact and friction law, strategy, every solver setting),
        # as the resume manifest holds it; the axes are the coordinates, and the chunking changes no
        # result (tested), so that equal results make equal files.
        "tribosweep_config": json.dumps({k: v for k, v in plan.config.items() if k not in ("axes", "chunk_size")},
                                        sort_keys=True),  # fmt: skip
        "history": f"{now} {command}",
        "references": REFERENCES,
        "comment": HOPF_CAVEAT,
        "strategy": plan.strategy,
    }
    for k, v in plan.model_values.items():
        attrs[f"model_{k}"] = v
    attrs["model_contact"] = plan.model.contact
    attrs["model_friction_law"] = plan.model.friction_law
    for k, v in plan.options.items():
        if k != "wear":
            attrs[f"solver_{k}"] = v
    attrs["arm_length_seed"] = _apparatus.L_SEED
    for mode, p in _apparatus.ARM_EXPONENTS.items():
        attrs[f"arm_exponent_{mode}"] = p
    for (mode, table), err in _apparatus.ARM_FIT_MAX_REL_ERROR.items():
        attrs[f"arm_fit_max_rel_error_{mode}_{table}"] = err
    attrs["load_identification_range"] = np.asarray(_apparatus.LOAD_RANGE)
    ref = plan.wear_reference
    attrs["wear_reference_normal_load"] = ref.normal_load
    attrs["wear_reference_arm_length"] = ref.arm_length
    attrs["wear_reference_sliding_speed"] = ref.sliding_speed
    attrs["wear_reference_frequency_hz"] = f_ref
    attrs["wear_l1"] = _wear.L1
    if plan.wear_calibration is not None:
        for k, v in plan.wear_calibration.as_dict().items():
            attrs[f"wear_calibration_{k}"] = v
    attrs["wear_model_caveats"] = _wear.WEAR_CAVEATS
    return attrs




#: Per-point output of :func:`compute_chunk`: name -> (dtype, units or None, long name).
#: Flag variables carry their meanings in ``FLAG_MEANINGS``. Every name here is an output key.
POINT_VARIABLES: dict[str, tuple[str, str | None, str]] = {
    "regime": ("u1", None, "dynamic regime of the slider"),
    "status": ("u1", None, "status of the computation that decided the regime"),
    "reason": ("str", None, "reason for a failed or undetermined point (empty otherwise)"),
    "decided_by": ("u1", None, "analysis stage that decided the regime"),
    "bistable": ("i1", None, "coexistence of attractors seen by the census"),
    "regime_fraction": ("f8", "1", "fraction of the census disturbances that reach the point's regime (NaN: no "
                                   "census)"),
    "regime_fraction_se": ("f8", "1", "binomial standard error of regime_fraction, sqrt(p (1 - p) / K)"),
    "growth_rate": ("f8", "s-1", "largest real part of the eigenvalues of steady sliding (> 0: unstable)"),
    "linear_frequency": ("f8", "rad s-1", "angular frequency of the least stable linear mode"),
    "normal_mode_frequency": ("f8", "Hz", "frequency Im(lambda_normal)/2 pi of the linearised normal mode"),
    "cycle_omega": ("f8", "rad s-1", "angular frequency of the cycle the point's run ended on (NaN if none)"),
    "cycle_period_ratio": ("f8", "1", "period of the cycle in periods of the least stable linear mode: about 1 "
                                      "for the ordinary cycle, about 2 past a period doubling"),
    "z1_amplitude": ("f8", "m", "amplitude of the first harmonic of z on the cycle"),
    "z2_amplitude": ("f8", "m", "amplitude of the second harmonic of z on the cycle"),
    "z_half_range": ("f8", "m", "half of z's range over the cycle: the size of the motion, of which a "
                                "subharmonic cycle's first harmonics can be a small part"),
    "phi1_amplitude": ("f8", "rad", "amplitude of the first harmonic of the twist phi on the cycle"),
    "min_normal_force": ("f8", "N", "minimum total normal force (over the cycle if periodic, else the run)"),
    "fraction_off_disk": ("f8", "1", "fraction of the cycle with the pin off the disk"),
    "min_slip_velocity": ("f8", "m s-1", "minimum sliding velocity of the contact point"),
    "wear_rate_relative": ("f8", "1", "mild-wear rate per sliding distance relative to the reference point"),
    "wear_applicability": ("u1", None, "whether the mild-wear model applies"),
    "mild_wear_fraction": ("f8", "1", "fraction of disturbances after which the contact slides steadily, so that "
                                      "the mild-wear model applies"),
    "mild_wear_fraction_se": ("f8", "1", "standard error of mild_wear_fraction (binomial, from the census; 0 where "
                                         "it is exact)"),
    "wall_time": ("f8", "s", "wall-clock time of the point (its chunk's stage times shared evenly)"),
    "n_rhs": ("i8", "1", "right-hand-side evaluations of the time integration (0: none run)"),
    "tidf_roots": ("i8", "1", "describing-function roots in 150-3000 rad/s (-1: not computed)"),
    "tidf_omega": ("f8", "rad s-1", "angular frequency of the physical describing-function root"),
    "tidf_a1": ("f8", "m", "first-harmonic amplitude of z of the physical describing-function root"),
    "tidf_contact_opens": ("i1", None, "the physical root's waveform leaves the disk (outside the law's validity)"),
    "orbit_a1": ("f8", "m", "first-harmonic amplitude of z of the shooting orbit near the root"),
    "orbit_stable": ("i1", None, "stability of the shooting orbit (Floquet multipliers)"),
    "tidf_a1_error": ("f8", "1", "relative error of the describing function's A1 against the shooting orbit"),
    "newton_iterations": ("i8", "1", "Newton iterations of the TIDF and shooting stages (0: none run)"),
    "cycle_verified": ("i1", None, "whether shooting converged the cycle the point's transient ended on to a stable "
                                   "periodic orbit, on which the cycle variables were then measured"),
    **_irregular.IRREGULAR_VARIABLES,
    "irregular_intermittent_period": ("f8", "s", "intermittent irregular motion: period of the unstable cycle its "
                                                 "laminar phases return to (NaN elsewhere)"),
    "irregular_intermittent_multiplier": ("f8", "1", "intermittent irregular motion: modulus of that cycle's "
                                                     "largest non-trivial Floquet multiplier (the cycle is not "
                                                     "stable: above 1, or within the shooting's tolerance of it)"),
    "irregular_intermittent_instability": ("u1", None, "intermittent irregular motion: how that cycle is unstable "
                                                       "(fold, flip, torus: Pomeau-Manneville types I, III, II)"),
}
#: Variables of the cycle a point's own run ended on (a transient that ended periodic, or the
#: describing function's cycle where sliding is unstable).
CYCLE_VARIABLES: tuple[str, ...] = ("cycle_omega", "cycle_period_ratio", "z1_amplitude", "z2_amplitude", "z_half_range",
                                    "phi1_amplitude", "fraction_off_disk")  # fmt: skip
CYCLE_NOTE: str = (
    "the cycle the point's own run ended on, NaN where it did not end on one: where sliding is linearly "
    "unstable (growth_rate > 0), the motion that replaces it; where sliding is linearly stable (growth_rate < 0) "
    "and regime is a cycle, a cycle that COEXISTS with stable sliding, reached because the run started outside "
    "the saddle cycle (reason says so). A cycle seen only by the attractor census, at a point whose regime is "
    "steady_sliding, is not here but in the largest_cycle_* variables. Where cycle_verified is verified, the values "
    "are measured on the periodic orbit that shooting converged from the run's stop; elsewhere they are the stop's"
)
#: Optional per-point output (present only when configured).
OPTIONAL_POINT_VARIABLES: dict[str, tuple[str, str | None, str]] = {
    "wear_rate": ("f8", "kg m-1", "mild-wear mass loss per sliding distance (eq. 8, calibrated)"),
}
#: Flag meanings of the categorical per-point variables.
FLAG_MEANINGS: dict[str, tuple[tuple[int, ...], tuple[str, ...]]] = {
    "regime": (tuple(range(len(REGIME_NAMES))), REGIME_NAMES),
    "status": (SWEEP_STATUS_VALUES, SWEEP_STATUS_NAMES),
    "decided_by": (tuple(range(len(DECIDED_BY_NAMES))), DECIDED_BY_NAMES),
    "bistable": (BISTABLE_VALUES, BISTABLE_NAMES),
    "wear_applicability": (tuple(range(len(WEAR_APPLICABILITY_NAMES))), WEAR_APPLICABILITY_NAMES),
    "tidf_contact_opens": ((-1, 0, 1), ("not_computed", "closed", "opens")),
    "orbit_stable": ((-1, 0, 1), ("not_computed", "unstable", "stable")),
    "cycle_verified": ((-1, 0, 1), ("no_transient_cycle", "not_verified", "verified")),
    "largest_cycle_verified": _census.VERIFIED_FLAGS,
    "irregular_intermittent_instability": ((0, 1, 2, 3), ("not_intermittent", "fold", "flip", "torus")),
}


@dataclass
class VarSpec:
    """One variable of the output: name, dimensions, dtype (``"str"`` for text) and CF attributes."""

    name: str
    dims: tuple[str, ...]
    dtype: str
    attrs: dict = field(default_factory=dict)


def point_specs(dims: tuple[str, ...], *, wear_rate: bool = False) -> list[VarSpec]:
    """The per-point variables of a sweep over ``dims`` (``POINT_VARIABLES``)."""
    spec = dict(POINT_VARIABLES)
    if wear_rate:
        spec.update(OPTIONAL_POINT_VARIABLES)
    out = []
    for name, (dtype, units, long_name) in spec.items():
        if name in FLAG_MEANINGS:
            values, meanings = FLAG_MEANINGS[name]
            attrs = flag_attrs(meanings, long_name, values, dtype)
        else:
            attrs = {"long_name": long_name}
            if units is not None:
                attrs["units"] = units
        out.append(VarSpec(name, dims, dtype, attrs))
    for name, (dtype, units, long_name, per_attractor) in _census.CENSUS_VARIABLES.items():
        if name in FLAG_MEANINGS:
            attrs = flag_attrs(FLAG_MEANINGS[name][1], long_name, FLAG_MEANINGS[name][0], dtype)
        else:
            attrs = {"long_name": long_name} | ({} if units is None else {"units": units})
        out.append(VarSpec(name, dims + (("attractor",) if per_attractor else ()), dtype, attrs))
    by_name = {v.name: v for v in out}
    by_name["basin_fraction"].attrs["comment"] = (
        "census: K disturbances on the torsion and normal modes (amplitudes up to disturbance_scale |z_st|, a "
        "Halton sequence seeded by the point's parameters), each run to its attractor; taken where sliding is "
        "stable and a saddle cycle is predicted, and where sliding is unstable and the transient from its unstable "
        "mode reached a motion (a cycle, irregular motion or an escape; there no disturbance returns to sliding). "
        + "; ".join(f"{k}: {v}" for k, v in ATTRACTOR_DOC.items())
    )
    by_name["regime"].attrs["comment"] = "; ".join(f"{k}: {v}" for k, v in REGIME_DOC.items())
    by_name["bistable"].attrs["comment"] = (
        "derived from the attractor census: -1 not_checked (no census: census off, the linear stage or the transient "
        "failed, or every disturbance failed); "
        "0 one_attractor: every counted disturbance reached the same attractor; 1 coexisting: more than one "
        "attractor seen (steady sliding, each distinct cycle and irregular motion count; escapes do not), the "
        "evidence is basin_fraction; 2 no_saddle: stable sliding with no saddle cycle predicted by the describing "
        "function, nothing to find. One attractor seen is no proof that nothing else coexists: a basin smaller "
        "than about 1/K of the disturbances is likely missed"
    )
    by_name["regime_fraction"].attrs["comment"] = (
        "where sliding is stable, the fraction returning to steady sliding (basin_stability: the label, from a "
        "small disturbance, is certain there by linear stability, and the fraction is the size of sliding's "
        "basin); where it is unstable, the fraction reaching the motion its transient reached: the same cycle "
        "(frequency within 1 % and the first two harmonics of z within 1 % of its z_half_range), irregular "
        "motion, or an escape. There a small value marks a label that one run gave and most disturbances do not "
        "(a chaotic transient's fate, or where the unstable mode leads that larger disturbances seldom reach)"
    )
    by_name["reason"].attrs["comment"] = "free text; empty for a point decided without trouble"
    by_name["z1_amplitude"].attrs["comment"] = (
        "harmonics are of the cycle's own period: for a cycle of n mode periods (cycle_period_ratio about n, "
        "after a period doubling or on subharmonic bouncing) the motion at the mode's frequency is the n-th "
        "harmonic (z2_amplitude for n = 2), and z1_amplitude is small"
    )
    for name in CYCLE_VARIABLES:
        note = CYCLE_NOTE if name == "cycle_omega" else (
            "of the cycle the point's own run ended on (see cycle_omega): where sliding is linearly stable "
            "(growth_rate < 0) that cycle COEXISTS with stable sliding; a cycle seen only by the census is in "
            "largest_cycle_*")  # fmt: skip
        old = by_name[name].attrs.get("comment")
        by_name[name].attrs["comment"] = f"{old}; {note}" if old else note
    for name in ("tidf_omega", "tidf_a1"):
        by_name[name].attrs["comment"] = (
            "where sliding is linearly stable (growth_rate < 0) the root is the saddle cycle around stable sliding "
            "(unstable: it bounds sliding's basin, it is not a motion the slider keeps); where sliding is unstable, a "
            "predicted cycle (within the bilateral law's validity unless tidf_contact_opens)"
        )
    for name in ("largest_cycle_omega", "largest_cycle_a1", "largest_cycle_period_ratio",
                 "largest_cycle_fraction_off_disk"):  # fmt: skip
        by_name[name].attrs["comment"] = (
            "the census cycle most disturbances reach: where sliding is linearly stable, a cycle that coexists "
            "with stable sliding (regime there stays steady_sliding; bistable says coexisting when the census saw "
            "more than one attractor); where it is unstable, not necessarily the cycle of regime and cycle_omega "
            "(the motion of the transient from the unstable mode); measured on the orbit shooting converged where "
            "largest_cycle_verified is verified"
        )
    by_name["wall_time"].attrs["comment"] = (
        "a measurement: differs between runs; from 8 threads on, chunks computed at once share the cores, "
        "so the points' times add up to more than the sweep's")  # fmt: skip
    by_name["wear_rate_relative"].attrs["comment"] = (
        "the rate while the contact slides steadily (NaN where steady sliding is not what a small disturbance "
        "reaches); where steady sliding coexists with vibration (wear_applicability mild_wear_in_part) it holds only "
        "after the fraction mild_wear_fraction of disturbances; vibrating contacts wear much faster (outside the model)"
    )
    by_name["mild_wear_fraction"].attrs["comment"] = (
        "0 where steady sliding is linearly unstable; 1 at stable sliding with no saddle cycle predicted; the census's "
        "basin_stability where a census ran; NaN where unknown (stable sliding with a saddle and no census)"
    )
    by_name["irregular_ftle"].attrs["comment"] = (
        "only where regime is irregular (a bounded transient that neither repeated nor decayed by t_max), from where "
        "it ended: Benettin's two-trajectory method, separation solver_ftle_d0 in units of the characteristic sizes "
        "(|z_st|, |z_st| w_t, |z_st|, |z_st| w_t, |z_st|/L, |z_st| w_t/L), renormalised every solver_ftle_tau seconds, "
        "mean of ln(d_k/d0)/tau over the segments after solver_ftle_warmup: solver_ftle_min_segments, or more until "
        "the mean is 5 irregular_ftle_se from 0, at most solver_ftle_segments; about 0 (within a few "
        "irregular_ftle_se): quasi-periodic, or still creeping onto a cycle; clearly > 0: chaotic"
    )
    by_name["irregular_omega"].attrs["comment"] = (
        "peak of the Hann-windowed spectrum of z over solver_irregular_window seconds sampled every "
        "solver_irregular_sample_dt, refined by a parabola through the log magnitudes of the peak bin and its neighbours"
    )
    return out



#: Dimensions a per-point variable may carry after the sweep's own: name -> (values, attributes).
TRAILING_DIMS: dict[str, tuple[np.ndarray, dict]] = {
    "attractor": (
        np.arange(len(ATTRACTOR_NAMES), dtype=np.int8),
        {"long_name": "attractor reached by census disturbances",
         "flag_values": np.arange(len(ATTRACTOR_NAMES), dtype=np.int8),
         "flag_meanings": " ".join(ATTRACTOR_NAMES)},
    ),
}  # fmt: skip



def empty_result(n: int, *, wear_rate: bool = False) -> dict[str, np.ndarray]:
    """Output arrays of ``n`` points with fill values (NaN, 0, empty strings)."""
    out: dict[str, np.ndarray] = {}
    spec = dict(POINT_VARIABLES)
    if wear_rate:
        spec.update(OPTIONAL_POINT_VARIABLES)
    for name, (dtype, _units, _long) in spec.items():
        if dtype == "str":
            out[name] = np.full(n, "", dtype="<U1")
        elif dtype == "f8":
            out[name] = np.full(n, np.nan)
        else:
            out[name] = np.zeros(n, dtype=dtype)
    out.update(_census.empty(n))
    out["bistable"][:] = -1
    out["tidf_roots"][:] = -1
    out["tidf_contact_opens"][:] = -1
    out["orbit_stable"][:] = -1
    out["cycle_verified"][:] = -1
    return out


def boundary_box(plan: Plan) -> bool:
    """Whether :func:`boundary_vars` computes curves: normal load and arm length both swept, nothing else."""
    axes = plan.axes
    return (axes["normal_load"].size >= 2 and axes["arm_length"].size >= 2
            and not any(a.size > 1 for d, a in axes.items() if d not in ("normal_load", "arm_length")))  # fmt: skip


def boundary_vars(plan: Plan) -> tuple[dict, dict]:
    """The stability boundaries that cross a normal load x arm length sweep's box, as static variables.

    Stored when both are swept (two values or more) and every other axis holds one value (the
    curves are then those of the sweep's own model at that value), from
    :func:`tribosweep.boundary_curves`: the Hopf curves (``hopf_*`` on ``hopf_point``), across which
    steady sliding loses stability, so the sharp form of the map's linear boundary; and, for the
    unilateral contact law and a strategy that computes cycles (not ``linear``, which maps
    eigenvalues only), the fold and grazing curves of the cycles born there (``fold_*`` on
    ``fold_point``, ``grazing_*`` on ``grazing_point``); for the bilateral law, the grazing curve
    only (past it its cycles leave the law's validity); under the switch friction law also the
    stick curve (``stick_*`` on ``stick_point``), where those cycles first reach the stick band. Returns the variables and attributes (what
    was found, the continuation's tolerances, the calls that reproduce each curve, or why no curve
    is stored); a failure is recorded, never raised.
    """
    axes = plan.axes
    if not (axes["normal_load"].size >= 2 and axes["arm_length"].size >= 2):
        return {}, {}
    if not boundary_box(plan):
        return {}, {"hopf_curves": "not stored: a third axis is swept (curves are drawn per normal load x arm length box)"}
    from .. import _boundary

    fixed = {d: float(a[0]) for d, a in axes.items() if d not in ("normal_load", "arm_length")}
    model = plan.model.replace(**fixed)
    curves = ["hopf"]
    skipped = {}
    if plan.strategy == "linear":
        reason = "not computed: strategy linear maps eigenvalues only (tribosweep boundary computes them)"
        skipped = {"fold_curves": reason, "grazing_curves": reason}
        if model.friction_law == "switch":
            skipped["stick_curves"] = reason
    elif model.contact != "unilateral":
        # The grazing curve is where the bilateral law's cycles open the contact and leave its
        # validity: stored. A fold past it would be a fold of orbits outside the law's validity.
        curves += ["grazing"]
        skipped = {"fold_curves": "not computed for bilateral contact: past the grazing curve its cycles open the "
                                  "contact, outside the law's validity (tribosweep boundary computes them)"}
    else:
        curves += ["fold", "grazing"]
    if plan.strategy != "linear" and model.friction_law == "switch":
        # Where the cycles born at the Hopf curve first reach the stick band: the onset of stick-slip.
        curves += ["stick"]
    box = {"normal_load": (float(axes["normal_load"][0]), float(axes["normal_load"][-1])),
           "arm_length": (float(axes["arm_length"][0]), float(axes["arm_length"][-1]))}  # fmt: skip
    try:
        ds = _boundary.boundary_curves(model, **box, curves=curves, threads=plan.settings.threads)
    except Exception as e:  # noqa: BLE001 - a failed boundary must not stop the sweep
        return {}, {"hopf_curves": f"not stored: the continuation failed ({type(e).__name__}: {e})"}
    out = {name: (da.dims, da.values, dict(da.attrs)) for name, da in ds.data_vars.items()}
    attrs = dict(ds.attrs)
    attrs |= skipped
    return out, attrs
