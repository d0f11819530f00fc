"""Independent scipy reference of the switch friction law (Leine et al. 1998) on the slider.

Like :mod:`tribosweep.bench.reference`, written from the equations and not from the Rust core;
it imports nothing from ``tribosweep._core``.
"""

import math

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["SWITCH_EDGE_TOL", "SwitchReference"]

# --- the switch friction law (event-driven stick-slip) ----------------------------------------------
#
# The switch model of Leine et al. (1998) on the slider, bilateral contact, written from the
# equations and not from the Rust core: three modes, each a smooth vector field, with scipy's own
# terminal, directional events ending each one.
#
# - ``slip`` (``|v_r| > eta``): total friction ``mu(v_r) N sign(v_r)``; ends when ``v_r`` reaches
#   the band edge ``sign(v_r) eta`` moving inwards.
# - ``stick``: friction ``F_req``, the force that makes ``d v_r/dt = 0``; ends when ``|F_req|``
#   reaches ``mu_s N`` from below.
# - ``transition``: friction ``mu_s N sign(F_req)``; ends at the edge ``sign(F_req) eta`` (slip) or
#   when ``|F_req|`` falls back to ``mu_s N`` (stick).
#
# The dynamic friction force of the ODE is the total less ``mu(V) F_st``;
# ``mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v_s)`` with ``mu(V) = mu``.

SWITCH_EDGE_TOL = 1e-3  # as the core: within 1e-3 eta of the target edge, leaving stick slips at once


class SwitchReference:
    """The switch-law slider with bilateral contact (see the comment above).

    ``values``: every real model parameter by name (``SliderModel.values()``), including
    ``mu_static``, ``stribeck_velocity`` and ``stick_band``.
    """

    def __init__(self, values: dict[str, float]):
        p = dict(values)
        self.p = p
        f, k0, ka = p["normal_load"], p["contact_stiffness"], p["contact_quadratic"]
        self.z_st = -2.0 * f / (k0 + math.sqrt(k0 * k0 + 4.0 * ka * f))
        self.k_s = k0 - 2.0 * ka * self.z_st
        e = math.exp(-p["sliding_speed"] / p["stribeck_velocity"])
        self.mu_k = (p["mu"] - p["mu_static"] * e) / (1.0 - e)
        self.f0 = self.mu(p["sliding_speed"]) * f
        self.sl = p["torsion_sign"] * p["moment_arm"]

    def mu(self, v: float) -> float:
        p = self.p
        return self.mu_k + (p["mu_static"] - self.mu_k) * math.exp(-abs(v) / p["stribeck_velocity"])

    def normal(self, y) -> float:
        p = self.p
        z = y[0]
        return p["normal_load"] - self.k_s * z + p["contact_quadratic"] * z * z - p["contact_damping"] * y[1] \
            + p["twist_coupling"] * y[4]

    def v_r(self, y) -> float:
        return self.p["sliding_speed"] - (y[3] + self.sl * y[5])

    def spring_accel(self, y) -> tuple[float, float]:
        p = self.p
        wx, wt = p["omega_friction"], p["omega_torsion"]
        a_x = -2.0 * p["zeta_friction"] * wx * y[3] - wx * wx * y[2]
        a_t = -2.0 * p["zeta_torsion"] * wt * y[5] - wt * wt * y[4]
        return a_x, a_t

    def f_req(self, y) -> float:
        """Total friction force that holds v_r constant: 0 = xdd + sL phidd with the dynamic force F - F0."""
        p = self.p
        a_x, a_t = self.spring_accel(y)
        compliance = 1.0 / p["mass"] + self.sl * self.sl / p["inertia"]
        return -(a_x + self.sl * a_t) / compliance + self.f0

    def friction(self, y, mode: str) -> float:
        """Total friction force in ``mode``."""
        if mode == "slip":
            v = self.v_r(y)
            return self.mu(v) * self.normal(y) * math.copysign(1.0, v)
        if mode == "stick":
            return self.f_req(y)
        return self.p["mu_static"] * self.normal(y) * math.copysign(1.0, self.f_req(y))

    def rhs(self, t, y, mode: str):
        p = self.p
        wz = p["omega_normal"]
        fz = self.normal(y) - p["normal_load"]
        fx = self.friction(y, mode) - self.f0
        a_x, a_t = self.spring_accel(y)
        return np.array([
            y[1],
            fz / p["mass"] - 2.0 * p["zeta_normal"] * wz * y[1] - wz * wz * y[0],
            y[3],
            fx / p["mass"] + a_x,
            y[5],
            self.sl / p["inertia"] * fx + a_t,
        ])

    def mode_in_band(self, y) -> str:
        req = self.f_req(y)
        if abs(req) <= self.p["mu_static"] * self.normal(y):
            return "stick"
        if math.copysign(1.0, req) * self.v_r(y) >= self.p["stick_band"] * (1.0 - SWITCH_EDGE_TOL):
            return "slip"
        return "transition"

    def mode_at(self, y) -> str:
        return "slip" if abs(self.v_r(y)) > self.p["stick_band"] else self.mode_in_band(y)

    def events(self, y, mode: str):
        """Terminal events of ``mode`` as (function, next-mode rule) pairs."""
        eta, mus = self.p["stick_band"], self.p["mu_static"]
        out = []
        if mode == "slip":
            sgn = math.copysign(1.0, self.v_r(y))

            def edge(t, yy):
                return sgn * (self.v_r(yy) - sgn * eta)

            out.append((edge, self.mode_in_band))
        else:
            def bound(t, yy):
                return mus * self.normal(yy) - abs(self.f_req(yy))

            if mode == "stick":
                out.append((bound, lambda yy: "slip" if math.copysign(1.0, self.f_req(yy)) * self.v_r(yy)
                            >= eta * (1.0 - SWITCH_EDGE_TOL) else "transition"))
            else:
                sgn = math.copysign(1.0, self.f_req(y))

                def edge(t, yy):
                    return sgn * (sgn * eta - self.v_r(yy))

                def back(t, yy):
                    return -bound(t, yy)

                out.append((edge, lambda yy: "slip"))
                out.append((back, lambda yy: "stick"))
        for fn, _ in out:
            fn.terminal = True
            fn.direction = -1.0  # every function above is positive inside its mode
        return out

    def solve(self, y0, t_end: float, t_eval, rtol: float = 1e-12, atol=None, max_segments: int = 10_000):
        """States at ``t_eval`` and the list of (time, mode before, mode after) switches."""
        t_eval = np.asarray(t_eval, dtype=float)
        t, y = 0.0, np.asarray(y0, dtype=float)
        mode = self.mode_at(y)
        out = np.full((t_eval.size, 6), np.nan)
        switches = []
        for _ in range(max_segments):
            evs = self.events(y, mode)
            sol = solve_ivp(lambda tt, yy, m=mode: self.rhs(tt, yy, m), (t, t_end), y, method="DOP853", rtol=rtol,
                            atol=atol, dense_output=True, events=[e[0] for e in evs])
            t1 = sol.t[-1]
            sel = (t_eval >= t) & (t_eval <= t1)
            if sel.any():
                out[sel] = sol.sol(t_eval[sel]).T
            if sol.status != 1:
                return out, switches
            k = next(i for i, te in enumerate(sol.t_events) if te.size)
            y = sol.y_events[k][0]
            t = float(sol.t_events[k][0])
            new = evs[k][1](y)
            switches.append((t, mode, new))
            mode = new
        raise RuntimeError("too many mode switches")


