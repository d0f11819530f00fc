"""Mild-wear model of the report's appendix 4 ("Part 3: Wear Model"), docs/model.md §8.

Mild wear is fatigue of load-bearing areas cycled by the normal-force oscillation at frequency
``f`` [Hz]. Wear per unit sliding distance (eq. 8)::

    W_l = A_t rho V_w (f + f_s) / (N_f A_app V),      f_s = V / l_1

and with the real contact area of an exponential asperity-height distribution,
``A_t = P (pi beta / sigma)^(1/2) / E'`` (eq. 13, printed ``sigma`` read as ``sigma^(1/2)``).

Without a calibration the absolute rate is unknown (``a_w`` of the report's Table 3 is lost
from the OCR), so tribosweep reports the rate relative to a reference point::

    W / W_ref = (P / P_ref) (V_ref / V) (f + V/l_1) / (f_ref + V_ref/l_1)

where ``f`` is the normal-mode frequency of the linearised system in steady sliding,
``Im(lambda_normal) / 2 pi`` (229.2 Hz at the seed).

Caveats (also written into every sweep file, ``WEAR_CAVEATS``):

* The report's fitted intercept ``a_w`` was *negative*: the measured wear rose as
  ``b_w (f - 116.7 Hz)``, much more steeply than eq. 8's ``(f + f_s)`` (a 5 cm / 11 cm wear ratio
  of 2.98 against 1.16), and the report then used ``|a_w|`` to get ``tau_s = |b_w/a_w|``.
  ``l_1 = tau_s x 0.6 m/s`` inherits that choice.
* The model is for the mild (steady-sliding) regime only; self-excited points are reported as
  outside it (the report measured wear orders of magnitude higher there).
* With the printed constants eq. 13's real contact area exceeds the pin face (``A_t / A_app``
  about 10 at 84.46 N): its absolute constant is a fit constant, not a contact-mechanics result.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ._model import SliderModel

#: tau_s = |b_w / a_w| [s]: duration of load transmission by one area A_s (report, Table 3 fit).
TAU_S: float = 0.857e-2
#: Sliding speed of the wear experiments [m/s] (60 cm/s).
FIT_SPEED: float = 0.6
#: l_1 = tau_s x 0.6 m/s [m]: distance an area A_s transmits load (0.514 cm).
L1: float = TAU_S * FIT_SPEED
#: Density of the Fe2O3 wear particles [kg/m^3] (5.25 g/cm^3).
RHO: float = 5250.0
#: Pin and disk moduli [Pa] and Poisson ratios (appendix 4, Table 1).
PIN_MODULUS, PIN_POISSON = 207e9, 0.3
DISK_MODULUS, DISK_POISSON = 103e9, 0.26
#: rms roughness sigma [m] (0.026e-3 mm).
SIGMA: float = 0.026e-6
#: Pin diameter [m]; its face is the apparent contact area.
PIN_DIAMETER: float = 5e-3
#: Apparent contact area A_app = pi (2.5 mm)^2 [m^2].
A_APP: float = math.pi * (PIN_DIAMETER / 2) ** 2
#: Default reference point of the relative rate: the seed (load [N], speed [m/s], arm length [m]).
REFERENCE_LOAD, REFERENCE_SPEED, REFERENCE_ARM_LENGTH = 84.46, 0.46, 0.072

WEAR_CAVEATS: str = (
    "Relative mild-wear rate W/W_ref = (P/P_ref)(V_ref/V)(f + V/l_1)/(f_ref + V_ref/l_1) of the 1985 report's "
    "appendix 4 (eq. 8), f = normal-mode frequency of the linearised system in steady sliding, l_1 = 0.514 cm. "
    "Caveats: the report's fitted intercept a_w was negative (measured wear rose as b_w (f - 116.7 Hz), much "
    "steeper than eq. 8's (f + f_s)) and the report used |a_w|; the model holds only in the mild "
    "(steady-sliding) regime and is NaN elsewhere; the absolute rate needs a user calibration (b_w or N_f), "
    "and eq. 13's real contact area with the printed constants exceeds the apparent area."
)


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """Effective modulus ``E'`` [Pa] of two bodies: ``1/E' = (1 - nu1^2)/E1 + (1 - nu2^2)/E2``.

    Examples
    --------
    >>> round(effective_modulus(207e9, 0.3, 103e9, 0.26) / 1e9, 1)
    74.4
    """
    return 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)


#: E' of the steel pin on the cast-iron disk [Pa] (74.4 GPa; the report prints 74.6).
E_EFF: float = effective_modulus(PIN_MODULUS, PIN_POISSON, DISK_MODULUS, DISK_POISSON)
#: Effective asperity radius beta = l_1^2 / (4 sigma) [m] (report: 2.47e4 cm, as printed).
BETA: float = L1 * L1 / (4.0 * SIGMA)


def slide_frequency_hz(sliding_speed):
    """Frequency ``f_s = V / l_1`` [Hz] with which load-bearing areas are renewed.

    Parameters
    ----------
    sliding_speed : float or array_like, m/s

    Examples
    --------
    >>> round(slide_frequency_hz(0.46), 1)
    89.5
    """
    return np.asarray(sliding_speed, dtype=np.float64) / L1 if np.ndim(sliding_speed) else float(sliding_speed) / L1


def normal_mode_frequency_hz(model: SliderModel) -> float:
    """Frequency ``Im(lambda_normal) / 2 pi`` [Hz] of the normal mode of steady sliding (docs/model.md §8).

    The Rust core's linear stability (``rust_core/src/linear.rs``); the mode is identified by the
    energy participation of its eigenvector.

    Examples
    --------
    >>> round(normal_mode_frequency_hz(SliderModel()), 1)
    229.2
    """
    from . import _core

    lin = _core.linear_stability(model.values(), model.contact, model.friction_law, [], np.zeros((1, 0)), threads=1)
    return float(lin["normal_mode_frequency"][0])


def relative_wear_rate(
    normal_load,
    sliding_speed,
    frequency_hz,
    *,
    reference_load: float = REFERENCE_LOAD,
    reference_speed: float = REFERENCE_SPEED,
    reference_frequency_hz: float | None = None,
):
    """Mild-wear rate per sliding distance relative to a reference point (eq. 8).

    ``W/W_ref = (P/P_ref) (V_ref/V) (f + V/l_1) / (f_ref + V_ref/l_1)``.

    Parameters
    ----------
    normal_load : float or array_like, N
    sliding_speed : float or array_like, m/s
    frequency_hz : float or array_like, Hz
        Normal-mode frequency ``f`` at the point.
    reference_load : float, N
        ``P_ref`` (default the seed's 84.46 N).
    reference_speed : float, m/s
        ``V_ref`` (default 0.46 m/s).
    reference_frequency_hz : float, Hz, optional
        ``f_ref``; default the seed's normal-mode frequency (229.2 Hz).

    Returns
    -------
    float or numpy.ndarray
        Dimensionless ratio; inputs broadcast.

    Examples
    --------
    >>> round(relative_wear_rate(84.46, 0.46, 229.2, reference_frequency_hz=229.2), 12)
    1.0
    """
    if reference_frequency_hz is None:
        reference_frequency_hz = normal_mode_frequency_hz(SliderModel())
    p = np.asarray(normal_load, dtype=np.float64)
    v = np.asarray(sliding_speed, dtype=np.float64)
    f = np.asarray(frequency_hz, dtype=np.float64)
    out = (p / reference_load) * (reference_speed / v) * (f + v / L1) / (reference_frequency_hz + reference_speed / L1)
    return float(out) if out.ndim == 0 else out


@dataclass(frozen=True, kw_only=True)
class WearReference:
    """Reference operating point of the relative mild-wear rate (default: the seed).

    Parameters
    ----------
    normal_load : float, N
        ``P_ref`` (84.46).
    arm_length : float, m
        Arm length that sets ``f_ref`` through the apparatus model (0.072).
    sliding_speed : float, m/s
        ``V_ref`` (0.46).
    """

    normal_load: float = REFERENCE_LOAD
    arm_length: float = REFERENCE_ARM_LENGTH
    sliding_speed: float = REFERENCE_SPEED

    def __post_init__(self) -> None:
        for name in ("normal_load", "arm_length", "sliding_speed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
                raise ValueError(f"WearReference.{name} = {v!r} is out of range: must be a finite number > 0")
            object.__setattr__(self, name, float(v))

    def frequency_hz(self, base: SliderModel | None = None) -> float:
        """``f_ref`` [Hz]: normal-mode frequency of the apparatus at this point (``base``: the seed)."""
        from ._apparatus import apparatus_model

        return normal_mode_frequency_hz(apparatus_model(self.normal_load, self.arm_length, self.sliding_speed, base=base))


@dataclass(frozen=True, kw_only=True)
class WearCalibration:
    """A calibration that turns the relative mild-wear rate into kg per metre of sliding.

    Give either the slope ``b_w`` of the report's fit ``W_l = a_w + b_w f`` (eq. 9) measured at a
    calibration point, or the cycles to failure ``N_f`` with the particle volume ``V_w``.

    Parameters
    ----------
    b_w : float, kg s/m, optional
        ``dW_l/df`` (kg/m per Hz) at ``normal_load``, ``sliding_speed``. Then
        ``W_l = b_w (P/P_c)(V_c/V)(f + V/l_1)`` (eq. 8, ``b_w`` scales as ``A_t/V ~ P/V``).
    normal_load : float, N
        Load ``P_c`` at which ``b_w`` was measured (default the seed's 84.46 N).
    sliding_speed : float, m/s
        Speed ``V_c`` at which ``b_w`` was measured (default 0.46 m/s).
    cycles_to_failure : float, optional
        ``N_f``, loading cycles to form one wear particle. Then eq. 13:
        ``W_l = P (pi beta/sigma)^(1/2) rho V_w (f + f_s) / (N_f E' A_app V)``.
    particle_volume : float, m^3, optional
        ``V_w``, volume of one wear particle (needed with ``cycles_to_failure``).
    """

    b_w: float | None = None
    normal_load: float = REFERENCE_LOAD
    sliding_speed: float = REFERENCE_SPEED
    cycles_to_failure: float | None = None
    particle_volume: float | None = None

    def __post_init__(self) -> None:
        def pos(name):
            v = getattr(self, name)
            if v is None:
                return
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
                raise ValueError(f"WearCalibration.{name} = {v!r} is out of range: must be a finite number > 0")
            object.__setattr__(self, name, float(v))

        for name in ("b_w", "normal_load", "sliding_speed", "cycles_to_failure", "particle_volume"):
            pos(name)
        by_slope = self.b_w is not None
        by_cycles = self.cycles_to_failure is not None or self.particle_volume is not None
        if by_slope == by_cycles:
            raise ValueError("WearCalibration needs either b_w or (cycles_to_failure and particle_volume), not both")
        if by_cycles and (self.cycles_to_failure is None or self.particle_volume is None):
            raise ValueError("WearCalibration: cycles_to_failure and particle_volume must be given together")

    def as_dict(self) -> dict:
        """Plain-data form (for the picklable chunk function and the sweep manifest)."""
        return asdict(self)


def mild_fraction(regime, growth_rate, bistable, basin_stability, basin_stability_se) -> tuple[np.ndarray, np.ndarray]:
    """Fraction of disturbances after which the mild-wear model applies, and its standard error.

    Mild wear (eq. 8) is the wear of steady sliding. Where the census saw steady sliding coexist
    with vibration, which state the contact is in depends on the last disturbance, so the model
    holds only for the fraction of disturbances that return to sliding (``basin_stability``, with
    its binomial standard error). Elsewhere the fraction is exact:

    * 0 (SE 0) where steady sliding is linearly unstable (``growth_rate > 0``): it is no
      attractor, and any disturbance grows away from it, whatever the motion then settles on;
    * 1 (SE 0) at stable steady sliding where the describing function predicts no saddle cycle
      (``bistable = no_saddle``: nothing else to reach);
    * the census's ``basin_stability`` where a census ran;
    * NaN where it is unknown: stable sliding with a saddle but no census (``census=False``, or a
      strategy that takes none), and points whose linear stage failed.

    Parameters
    ----------
    regime, bistable : integer arrays (``REGIME_NAMES`` and ``BISTABLE_NAMES`` codes)
    growth_rate : float array, 1/s (largest real part of the eigenvalues of steady sliding)
    basin_stability, basin_stability_se : float arrays (NaN where no census ran)

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``mild_wear_fraction`` and ``mild_wear_fraction_se``.

    Examples
    --------
    >>> from tribosweep._codes import REGIME, BISTABLE
    >>> nan = float("nan")
    >>> f, se = mild_fraction([REGIME["steady_sliding"], REGIME["steady_sliding"], REGIME["contact_loss"]],
    ...                       [-0.33, -2.0, 0.5], [BISTABLE["coexisting"], BISTABLE["no_saddle"], BISTABLE["not_checked"]],
    ...                       [0.75, nan, nan], [0.0625, nan, nan])
    >>> f.tolist(), se.tolist()
    ([0.75, 1.0, 0.0], [0.0625, 0.0, 0.0])
    """
    from ._codes import BISTABLE, REGIME

    regime = np.asarray(regime)
    growth = np.asarray(growth_rate, dtype=np.float64)
    bistable = np.asarray(bistable)
    p = np.asarray(basin_stability, dtype=np.float64)
    se = np.asarray(basin_stability_se, dtype=np.float64)
    unstable = growth > 0
    stable = growth < 0
    censused = stable & np.isin(bistable, (BISTABLE["one_attractor"], BISTABLE["coexisting"])) & np.isfinite(p)
    alone = stable & (regime == REGIME["steady_sliding"]) & (bistable == BISTABLE["no_saddle"])
    frac = np.where(unstable, 0.0, np.where(censused, p, np.where(alone, 1.0, np.nan)))
    frac_se = np.where(unstable | alone, 0.0, np.where(censused, se, np.nan))
    return frac, frac_se


def calibrated_wear_rate(calibration: WearCalibration | dict, normal_load, sliding_speed, frequency_hz):
    """Absolute mild-wear rate per sliding distance [kg/m] (eq. 8 / eq. 13).

    Parameters
    ----------
    calibration : WearCalibration or dict
        ``b_w`` at a calibration point, or ``cycles_to_failure`` with ``particle_volume``.
    normal_load : float or array_like, N
    sliding_speed : float or array_like, m/s
    frequency_hz : float or array_like, Hz
        Normal-mode frequency ``f``.

    Returns
    -------
    float or numpy.ndarray, kg/m
    """
    c = calibration if isinstance(calibration, WearCalibration) else WearCalibration(**calibration)
    p = np.asarray(normal_load, dtype=np.float64)
    v = np.asarray(sliding_speed, dtype=np.float64)
    f = np.asarray(frequency_hz, dtype=np.float64)
    if c.b_w is not None:
        out = c.b_w * (p / c.normal_load) * (c.sliding_speed / v) * (f + v / L1)
    else:
        a_t = p * math.sqrt(math.pi * BETA / SIGMA) / E_EFF  # real contact area, eq. 13
        out = a_t * RHO * c.particle_volume * (f + v / L1) / (c.cycles_to_failure * A_APP * v)
    return float(out) if out.ndim == 0 else out


def appendix3_energy_balance(
    *,
    torsional_frequency: float = 2 * math.pi * 86.25,
    moment_arm: float = 0.03835,
    inertia: float = 0.0069,
    zeta_torsion: float = 0.0058,
    friction_amplitude: float = 78.62,
) -> dict[str, float]:
    """The report's appendix-3 linear energy balance (stiffness K3, 110.3 N), docs/model.md §9.

    An arithmetic check, not a physics test: ``W_s = W_d`` identically because ``phi0`` comes
    from the same resonance equation.

    Parameters
    ----------
    torsional_frequency : float, rad/s
        ``w_nt`` (2 pi x 86.25).
    moment_arm : float, m
        ``a`` (0.03835).
    inertia : float, kg m^2
        ``I`` (0.0069).
    zeta_torsion : float
        ``zeta_t`` (0.0058).
    friction_amplitude : float, N
        ``F_x0`` of ``F_x = F_x0 sin(w t)`` (78.62).

    Returns
    -------
    dict
        ``phi0`` [rad] = ``(a/I) F_x0 / (2 zeta_t w^2)`` (0.1283, at -90 deg), ``c2`` [N s] =
        ``F_x0 / (w phi0)`` (1.131), ``W_s`` [J] = ``pi a F_x0 phi0`` (work of ``a F_x`` per cycle)
        and ``W_d`` [J] = ``2 pi zeta_t I w^2 phi0^2`` (damping per cycle), both 1.215.

    Examples
    --------
    >>> r = appendix3_energy_balance()
    >>> round(r["phi0"], 4), round(r["c2"], 3), round(r["W_s"], 3), round(r["W_d"], 3)
    (0.1283, 1.131, 1.215, 1.215)
    """
    w, a, i, z, f0 = torsional_frequency, moment_arm, inertia, zeta_torsion, friction_amplitude
    phi0 = (a / i) * f0 / (2.0 * z * w * w)
    c2 = f0 / (w * phi0)
    return {
        "phi0": phi0,
        "c2": c2,
        "W_s": math.pi * a * c2 * w * phi0 * phi0,  # integral of a c2 phid^2 over one period
        "W_d": 2.0 * math.pi * z * i * w * w * phi0 * phi0,  # integral of 2 zeta_t w I phid^2
    }
