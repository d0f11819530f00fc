"""The slider model as a frozen dataclass of physical parameters (SI units)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from . import _core

_SEED = _core.seed_params()
_CONTACTS = ("bilateral", "unilateral")
_FRICTION_LAWS = ("constant", "coulomb", "switch")

#: Units of every real parameter, for output attributes.
PARAM_UNITS: dict[str, str] = {
    "mass": "kg",
    "inertia": "kg m2",
    "moment_arm": "m",
    "omega_normal": "rad s-1",
    "omega_friction": "rad s-1",
    "omega_torsion": "rad s-1",
    "zeta_normal": "1",
    "zeta_friction": "1",
    "zeta_torsion": "1",
    "contact_stiffness": "N m-1",
    "contact_quadratic": "N m-2",
    "contact_damping": "N s m-1",
    "twist_coupling": "N rad-1",
    "mu": "1",
    "normal_load": "N",
    "sliding_speed": "m s-1",
    "torsion_sign": "1",
    "friction_regularization": "m s-1",
    "mu_static": "1",
    "stribeck_velocity": "m s-1",
    "escape_limit": "m",
    "stick_band": "m s-1",
}

#: Long names of the real parameters.
PARAM_LONG_NAMES: dict[str, str] = {
    "mass": "vibrating mass m",
    "inertia": "torsional inertia I",
    "moment_arm": "moment arm L of the friction force about the arm axis",
    "omega_normal": "normal natural frequency w_z, pin off the disk",
    "omega_friction": "frictional natural frequency w_x",
    "omega_torsion": "torsional natural frequency w_t",
    "zeta_normal": "normal damping ratio",
    "zeta_friction": "frictional damping ratio",
    "zeta_torsion": "torsional damping ratio",
    "contact_stiffness": "linear coefficient K_s0 of the total contact law",
    "contact_quadratic": "quadratic contact coefficient K_a",
    "contact_damping": "contact damping C_zc",
    "twist_coupling": "normal force per twist K_phi",
    "mu": "friction coefficient at the sliding speed",
    "normal_load": "normal load F_st",
    "sliding_speed": "sliding speed V",
    "torsion_sign": "sign s of the torsion coupling",
    "friction_regularization": "velocity scale of the tanh friction regularisation",
    "mu_static": "static friction coefficient of the Stribeck curve",
    "stribeck_velocity": "Stribeck velocity",
    "escape_limit": "|z| beyond which a run is declared diverged",
    "stick_band": "half-width eta of the stick band |v_r| <= eta of the switch friction law",
}

PARAM_NAMES: tuple[str, ...] = tuple(_core.param_names())


@dataclass(frozen=True, kw_only=True)
class SliderModel:
    """The 3-DOF pin-on-disk slider of the 1985 report (docs/model.md §2-3). Defaults: the seed configuration.

    Every field is keyword-only and validated on construction; a value out of range raises
    ``ValueError`` naming the field, its value and the valid range.

    Parameters
    ----------
    mass : float, kg
        Vibrating mass ``m`` (2.48).
    inertia : float, kg m^2
        Torsional inertia ``I`` (3.147e-3).
    moment_arm : float, m
        Moment arm ``L`` of the friction force about the arm axis (0.065).
    omega_normal, omega_friction, omega_torsion : float, rad/s
        Natural frequencies with the pin off the disk (2 pi x 55.00, 48.75, 98.75).
    zeta_normal, zeta_friction, zeta_torsion : float
        Damping ratios (0.01129, 0.00378, 0.00253).
    contact_stiffness : float, N/m
        ``K_s0`` (the report's ``K_s'``) of the total contact law ``F = -K_s0 zc + K_a zc^2`` (4.739e6).
    contact_quadratic : float, N/m^2
        ``K_a`` (2.179e10). ``0`` gives a linear contact.
    contact_damping : float, N s/m
        ``C_zc`` (222.63).
    twist_coupling : float, N/rad
        ``K_phi``, normal force per twist (-47.64e3).
    mu : float
        Friction coefficient at the sliding speed (0.215).
    normal_load : float, N
        ``F_st`` (84.46). The contact law was identified from 22-93 N: outside is extrapolation.
    sliding_speed : float, m/s
        ``V`` (0.46).
    torsion_sign : {-1, +1}
        ``s`` of eq. 18 (-1, the only reading with any instability).
    contact : {"unilateral", "bilateral"}
        ``unilateral`` (default): no force with the pin off the disk and no tension, the physical
        law and the one :func:`tribosweep.sweep` uses; ``bilateral``: the contact law everywhere,
        pulling the pin back with up to 258 N of tension once it leaves the disk (the report's
        model, which its describing function assumes; ask for it by name, as the reference-value
        tests do). The two agree while the pin stays on the disk (``zc < 0``).
    friction_law : {"constant", "coulomb", "switch"}
        ``constant``: the report's ``F_x = mu F_z``, valid while the sliding velocity stays
        positive; ``coulomb``: regularised ``mu(v_r) N tanh(v_r/eps)`` with a Stribeck curve
        through ``mu`` at ``V``, for stick-slip scenes; ``switch``: event-driven stick-slip (the
        switch model of Leine et al. 1998) on the same Stribeck curve: slip ``mu(v_r) N sign(v_r)``
        outside the band ``|v_r| <= stick_band``, inside it stick (the force that holds ``v_r``,
        up to ``mu_static N``) or the static bound. Not stiff: far fewer right-hand-side calls
        than a small ``eps``. Needs ``mu_static >= mu`` and ``stick_band < sliding_speed``.
    friction_regularization : float, m/s
        ``eps`` of the tanh regularisation (1e-3).
    mu_static : float or None
        Static coefficient of the Stribeck curve (``None``: equal to ``mu``, no Stribeck effect).
    stribeck_velocity : float, m/s
        Stribeck velocity ``v_s`` (0.1).
    escape_limit : float, m
        ``|z|`` at which a run is declared diverged (1e-3, well past the static saddle at 256.7 um).
    stick_band : float, m/s
        Half-width ``eta`` of the switch law's stick band (1e-6). While stuck the pin creeps at
        ``|v_r| <= eta`` instead of 0, so the band only needs to be small against the motion's
        velocities and well above the rounding of ``v_r`` (about 1e-16 ``V``).

    Examples
    --------
    >>> from tribosweep import SliderModel
    >>> m = SliderModel(normal_load=50.0, contact="unilateral")
    >>> round(m.static_point()[0] * 1e6, 3)
    -10.083
    """

    mass: float = _SEED["mass"]
    inertia: float = _SEED["inertia"]
    moment_arm: float = _SEED["moment_arm"]
    omega_normal: float = _SEED["omega_normal"]
    omega_friction: float = _SEED["omega_friction"]
    omega_torsion: float = _SEED["omega_torsion"]
    zeta_normal: float = _SEED["zeta_normal"]
    zeta_friction: float = _SEED["zeta_friction"]
    zeta_torsion: float = _SEED["zeta_torsion"]
    contact_stiffness: float = _SEED["contact_stiffness"]
    contact_quadratic: float = _SEED["contact_quadratic"]
    contact_damping: float = _SEED["contact_damping"]
    twist_coupling: float = _SEED["twist_coupling"]
    mu: float = _SEED["mu"]
    normal_load: float = _SEED["normal_load"]
    sliding_speed: float = _SEED["sliding_speed"]
    torsion_sign: float = _SEED["torsion_sign"]
    contact: str = "unilateral"
    friction_law: str = "constant"
    friction_regularization: float = _SEED["friction_regularization"]
    mu_static: float | None = None
    stribeck_velocity: float = _SEED["stribeck_velocity"]
    escape_limit: float = _SEED["escape_limit"]
    stick_band: float = _SEED["stick_band"]

    def __post_init__(self) -> None:
        for name in PARAM_NAMES:
            value = getattr(self, name)
            if name == "mu_static" and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                try:
                    value = float(value)
                except (TypeError, ValueError):
                    raise ValueError(f"{name} = {value!r} is not a real number") from None
            object.__setattr__(self, name, float(value))
        if self.contact not in _CONTACTS:
            raise ValueError(f"contact = {self.contact!r} is not valid: must be one of {_CONTACTS}")
        if self.friction_law not in _FRICTION_LAWS:
            raise ValueError(f"friction_law = {self.friction_law!r} is not valid: must be one of {_FRICTION_LAWS}")
        _core.validate_params(self.values(), self.contact, self.friction_law)

    def values(self) -> dict[str, float]:
        """The real parameters as a ``{name: value}`` dict (SI units)."""
        out = {name: getattr(self, name) for name in PARAM_NAMES}
        if out["mu_static"] is None:
            # No Stribeck effect unless asked for: the static coefficient equals mu.
            out["mu_static"] = self.mu
        return out

    def replace(self, **changes) -> SliderModel:
        """A copy with some fields changed (validated).

        Raises ``TypeError`` naming a field the model does not have, with the fields it has; the
        apparatus's arm length is not a field but sets the natural frequencies:
        :func:`tribosweep.apparatus_model` builds the model at a load, arm length and speed.
        """
        fields = [f.name for f in dataclasses.fields(self)]
        unknown = [k for k in changes if k not in fields]
        if unknown:
            hint = (" (the arm length sets the natural frequencies: use tribosweep.apparatus_model("
                    "normal_load, arm_length, sliding_speed, base=model))") if "arm_length" in unknown else ""
            raise TypeError(f"SliderModel.replace: no field {unknown[0]!r} = {changes[unknown[0]]!r}{hint}; "
                            f"the fields are {', '.join(fields)}")
        return dataclasses.replace(self, **changes)

    def static_point(self) -> tuple[float, float]:
        """Static penetration ``z_st`` [m] (< 0) and dynamic contact stiffness ``K_s`` [N/m]."""
        return _core.static_point(self.values())
