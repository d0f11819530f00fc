"""Work-precision rows and what is read from them: errors, time at a matched error (log-log interpolation), speed ratios, the fastest method, friction laws compared."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .runners import (
    BatchRun,
    _status_name,
    error_of,
    is_failed,
)
from .scenes import FASTEST_AT, MATCHED_ERRORS, RATIO_PAIRS, RUST_METHODS


def make_row(scene: str, impl: str, method: str, rtol: float, run: BatchRun, z_ref, scale) -> dict:
    """One table row of a rung (see ``COLUMNS``)."""
    n = int(run.z_end.size)
    err = error_of(run.z_end, z_ref, scale)
    row = {
        "scene": scene,
        "impl": impl,
        "method": method,
        "label": f"{impl} {method}",
        "rtol": float(rtol),
        "n_traj": n,
        "seconds_per_traj": run.seconds / max(n, 1),
        "error": err,
        "n_rhs": float(np.mean(run.n_rhs)),
        "steps": float(np.mean(run.steps)),
        "n_reject": float(np.mean(run.n_reject)),
        "status": _status_name(np.asarray(run.status)),
        "n_failed": int(np.count_nonzero(np.asarray(run.status) != 0)),
        "reason": run.reason,
    }
    if row["n_failed"] == 0 and not math.isfinite(err):
        row["status"], row["reason"] = "non_finite", row["reason"] or "non-finite final state"
    row["failed"] = is_failed(row)
    if row["failed"] and row["status"] == "success":
        row["status"] = "error_above_1"
    return row


# --- interpolation and quoting ---------------------------------------------------------------------


def time_at_error(errors: Sequence[float], times: Sequence[float], target: float) -> float:
    """Time of a work-precision line at error ``target``: linear in (log error, log time), no extrapolation.

    ``errors`` and ``times`` are the rungs in ladder order (loose to tight); NaN, zero or negative entries
    are skipped. The first pair of consecutive valid rungs whose errors bracket ``target`` is
    interpolated; NaN when no pair does.

    Examples
    --------
    >>> round(time_at_error([1e-3, 1e-5], [1.0, 100.0], 1e-4), 12)
    10.0
    """
    e = np.asarray(errors, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    ok = np.isfinite(e) & np.isfinite(t) & (e > 0) & (t > 0)
    e, t = e[ok], t[ok]
    if not (target > 0) or e.size == 0:
        return math.nan
    le, lt, lx = np.log(e), np.log(t), math.log(target)
    for i in range(e.size):
        if le[i] == lx:
            return float(t[i])
        if i + 1 < e.size and min(le[i], le[i + 1]) <= lx <= max(le[i], le[i + 1]) and le[i] != le[i + 1]:
            w = (lx - le[i]) / (le[i + 1] - le[i])
            return float(math.exp(lt[i] + w * (lt[i + 1] - lt[i])))
    return math.nan


def _lines(rows: list[dict], scene: str) -> dict[str, list[dict]]:
    """Successful rungs of each method label of ``scene``, in ladder order (loose to tight)."""
    out: dict[str, list[dict]] = {}
    for r in rows:
        if r["scene"] == scene:
            out.setdefault(r["label"], [])
            if not r["failed"]:
                out[r["label"]].append(r)
    for line in out.values():
        line.sort(key=lambda r: -r["rtol"])
    return out


def times_at(rows: list[dict], scene: str, target: float) -> dict[str, float]:
    """``{label: seconds per trajectory at error target}`` for every method of ``scene`` that brackets it.

    Adds ``"rust (fastest)"`` and ``"scipy (fastest)"``: the least time over that implementation's methods.
    """
    out = {}
    for label, line in _lines(rows, scene).items():
        v = time_at_error([r["error"] for r in line], [r["seconds_per_traj"] for r in line], target)
        if math.isfinite(v):
            out[label] = v
    for impl in ("rust", "scipy"):
        vals = {k: v for k, v in out.items() if k.startswith(impl + " ")}
        if vals:
            out[f"{impl} (fastest)"] = min(vals.values())
            out[f"_{impl}_fastest_label"] = min(vals, key=vals.get)
    return out


def speed_ratios(rows: list[dict], targets: Sequence[float] = MATCHED_ERRORS,
                 pairs: Sequence[tuple[str, str]] = RATIO_PAIRS) -> list[dict]:  # fmt: skip
    """Speed ratio ``t_baseline / t_rust`` at matched error, for every scene and pair where both lines reach it."""
    out, seen = [], set()
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for target in targets:
            at = times_at(rows, scene, target)
            for rust, base in pairs:
                if rust in at and base in at:
                    key = (scene, target, at.get("_rust_fastest_label", rust) if rust == "rust (fastest)" else rust,
                           at.get("_scipy_fastest_label", base) if base == "scipy (fastest)" else base)
                    if key in seen:  # "fastest" resolved to a pair already quoted
                        continue
                    seen.add(key)
                    out.append({
                        "scene": scene, "error": target, "rust": rust, "baseline": base,
                        "rust_label": key[2], "baseline_label": key[3],
                        "rust_seconds": at[rust], "baseline_seconds": at[base], "ratio": at[base] / at[rust],
                    })  # fmt: skip
    return out


def fastest(rows: list[dict], targets: Sequence[float] = FASTEST_AT) -> list[dict]:
    """Per scene and target error: the method with the least time per trajectory (all implementations)."""
    out = []
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for target in targets:
            at = {k: v for k, v in times_at(rows, scene, target).items() if not k.startswith("_") and "(" not in k}
            if at:
                best = min(at, key=at.get)
                runner = sorted(at.values())[1] if len(at) > 1 else math.nan
                out.append({"scene": scene, "error": target, "label": best, "seconds": at[best],
                            "next_seconds": runner, "n_methods": len(at)})  # fmt: skip
            else:
                errs = [r["error"] for line in _lines(rows, scene).values() for r in line]
                why = ("every method is more accurate already at its loosest rung" if errs and max(errs) < target
                       else "no method reaches it" if errs and min(errs) > target else "no successful rung")
                out.append({"scene": scene, "error": target, "label": None, "seconds": math.nan,
                            "next_seconds": math.nan, "n_methods": 0, "why": why})  # fmt: skip
    return out


def law_comparison(rows: list[dict], scenes: list[dict], targets: Sequence[float] = FASTEST_AT) -> list[dict]:
    """Per scene with variants, method and target error: time and rhs calls of the base law and each variant.

    Both read off their own work-precision lines (log-log interpolation, no extrapolation); only pairs
    where both lines reach the error are listed.
    """
    out = []
    for s in scenes:
        lines = _lines(rows, s["name"])
        for key in s.get("variants") or {}:
            for method in RUST_METHODS:
                base, var = lines.get(f"rust {method}"), lines.get(f"{key} {method}")
                if not base or not var:
                    continue
                for target in targets:
                    def at(line, col, target=target):
                        return time_at_error([r["error"] for r in line], [r[col] for r in line], target)

                    tb, tv = at(base, "seconds_per_traj"), at(var, "seconds_per_traj")
                    nb, nv = at(base, "n_rhs"), at(var, "n_rhs")
                    if all(math.isfinite(v) for v in (tb, tv, nb, nv)):
                        out.append({"scene": s["name"], "variant": key, "method": method, "error": target,
                                    "base_seconds": tb, "variant_seconds": tv, "time_ratio": tb / tv,
                                    "base_rhs": nb, "variant_rhs": nv, "rhs_ratio": nb / nv})  # fmt: skip
            # The best method of each law against each other (least time and least rhs, taken separately).
            for target in targets:
                got = [q for q in out if q["scene"] == s["name"] and q["variant"] == key and q["error"] == target
                       and q["method"] in RUST_METHODS]  # fmt: skip
                if len(got) > 1:
                    tb, tv = min(q["base_seconds"] for q in got), min(q["variant_seconds"] for q in got)
                    nb, nv = min(q["base_rhs"] for q in got), min(q["variant_rhs"] for q in got)
                    out.append({"scene": s["name"], "variant": key, "method": "best of each", "error": target,
                                "base_seconds": tb, "variant_seconds": tv, "time_ratio": tb / tv,
                                "base_rhs": nb, "variant_rhs": nv, "rhs_ratio": nb / nv})  # fmt: skip
    return out


# --- the run ---------------------------------------------------------------------------------------
