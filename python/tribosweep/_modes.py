"""Linear modes of steady sliding: the Jacobian of docs/model.md §2 and its eigenvectors.

Used for the census's disturbances and the start of an unstable point's transient. Everything here
gives the same bits on every machine: complex arithmetic, square roots and the C library's scalar
``exp``/``tanh``, but no LAPACK or BLAS (OpenBLAS picks its kernels by CPU) and none of numpy's array
transcendental functions (SIMD kernels picked by the CPU: AVX-512 machines round differently).

One limit, measured on numpy 2.4 (2026-11-28): numpy multiplies complex arrays with fused
multiply-adds where the CPU has them. Its AVX2 and AVX-512 kernels gave the same bits
(``NPY_DISABLE_CPU_FEATURES``), but its baseline x86-64-v2 kernel, for CPUs without FMA (before
2013), rounds differently. A numpy scalar's complex product rounds like the latter, so mixing the
two changes the bits as well.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np


def static(v: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Static penetration ``z_st`` [m] and the contact stiffness there [N/m] (docs/model.md §3)."""
    f, k0, ka = v["normal_load"], v["contact_stiffness"], v["contact_quadratic"]
    z_st = -2.0 * f / (k0 + np.sqrt(k0 * k0 + 4.0 * ka * f))  # cancellation-free, docs/model.md §3
    return z_st, k0 - 2.0 * ka * z_st


def mode_shape(v: Mapping[str, np.ndarray], lam: np.ndarray) -> np.ndarray:
    """Eigenvectors ``(n, 6)`` with ``z = 1`` for eigenvalues ``lam`` (n,) of steady sliding, constant friction.

    Closed form of docs/model.md §2 linearised: with ``z = 1`` the torsion equation gives ``phi``,
    then the frictional equation ``x``. Only complex arithmetic: no LAPACK, so the shapes do not
    depend on which BLAS kernels a machine picks.
    """
    z_st, k_s = static(v)
    c = v["torsion_sign"] * v["moment_arm"] / v["inertia"] * v["mu"]
    lt = lam * lam + 2.0 * v["zeta_torsion"] * v["omega_torsion"] * lam + v["omega_torsion"] ** 2
    lx = lam * lam + 2.0 * v["zeta_friction"] * v["omega_friction"] * lam + v["omega_friction"] ** 2
    phi = c * (-k_s - v["contact_damping"] * lam) / (lt - c * v["twist_coupling"])
    fz = -k_s - v["contact_damping"] * lam + v["twist_coupling"] * phi
    x = v["mu"] * fz / v["mass"] / lx
    one = np.ones_like(lam)
    return np.stack([one, lam, x, lam * x, phi, lam * phi], axis=1)


def null_vector(a: np.ndarray) -> np.ndarray:
    """A null vector of the singular ``(d, d)`` complex matrix ``a``: :func:`null_vectors` of one."""
    return null_vectors(np.asarray(a)[None])[0]


def null_vectors(a: np.ndarray) -> np.ndarray:
    """A null vector of each singular ``(d, d)`` complex matrix of ``a`` ``(n, d, d)``, by Gaussian
    elimination with complete pivoting: after ``d - 1`` pivots the last pivot column is the free
    variable, set to 1.

    Only elementwise complex arithmetic on the batch and comparisons of ``|.|^2`` (no LAPACK, no
    BLAS, no transcendental function), with ties broken by the first index; the back-substitution
    sums in index order (a BLAS dot, as ``@`` calls, sums as the CPU's kernel does). All matrices
    at once: the Stribeck sweep's 95 unstable points took 6.5 ms one by one, 0.4 ms so.
    """
    a = np.array(a, dtype=complex)
    n, d = a.shape[0], a.shape[1]
    at = np.arange(n)
    cols = np.tile(np.arange(d), (n, 1))
    for k in range(d - 1):
        sub = a[:, k:, k:]
        mag = (sub.real * sub.real + sub.imag * sub.imag).reshape(n, -1)
        r, c = np.divmod(np.argmax(mag, axis=1), d - k)
        a[at, k], a[at, k + r] = a[at, k + r].copy(), a[at, k].copy()
        a[at, :, k], a[at, :, k + c] = a[at, :, k + c].copy(), a[at, :, k].copy()
        cols[at, k], cols[at, k + c] = cols[at, k + c].copy(), cols[at, k].copy()
        a[:, k + 1 :, k:] -= (a[:, k + 1 :, k] / a[:, k, k, None])[:, :, None] * a[:, k, None, k:]
    u = np.zeros((n, d), dtype=complex)
    u[:, d - 1] = 1.0
    for k in range(d - 2, -1, -1):
        acc = a[:, k, k + 1] * u[:, k + 1]
        for j in range(k + 2, d):
            acc = acc + a[:, k, j] * u[:, j]
        u[:, k] = -acc / a[:, k, k]
    out = np.empty((n, d), dtype=complex)
    out[at[:, None], cols] = u
    return out


def mode_shape_numeric(j: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """Eigenvectors from the null space of ``J - lam I`` (speed-dependent friction: x acts back),
    with ``z = 1`` where ``z`` takes part (else the largest component 1); :func:`null_vectors`."""
    lam = np.asarray(lam)
    vec = null_vectors(np.asarray(j) - lam[:, None, None] * np.eye(6))
    mag = vec.real * vec.real + vec.imag * vec.imag
    at = np.arange(lam.size)
    pick = np.where(mag[:, 0] > 1e-24 * mag.max(axis=1), 0, np.argmax(mag, axis=1))
    out = vec / vec[at, pick][:, None]
    out[at, pick] = 1.0  # exactly (numpy's complex division of a number by itself may round to 1 - 1 ulp)
    return out


_LINEAR_FIELDS = (
    "mass", "inertia", "moment_arm", "omega_normal", "omega_friction", "omega_torsion", "zeta_normal",
    "zeta_friction", "zeta_torsion", "contact_stiffness", "contact_quadratic", "contact_damping",
    "twist_coupling", "mu", "normal_load", "sliding_speed", "torsion_sign", "friction_regularization",
    "mu_static", "stribeck_velocity",
)  # fmt: skip


def scalar(f):
    """``f`` (a ``math`` function) element by element: numpy's own exp, tanh, power, arctan2 on
    arrays run SIMD kernels picked by the CPU (AVX-512 machines and others round differently)."""
    return np.vectorize(f, otypes=[np.float64])


def jacobians(values: Mapping[str, np.ndarray | float], friction_law: str = "constant") -> np.ndarray:
    """Jacobians of steady sliding ``y = 0`` (in contact), shape ``(n, 6, 6)``, docs/model.md §2.

    Parameters
    ----------
    values : mapping of str to float or 1-D array
        Every real SliderModel field (SI units); arrays of one length ``n`` and scalars broadcast.
    friction_law : {"constant", "coulomb", "switch"}
        Friction law (the Coulomb law adds the Stribeck slope and the tanh regularisation; the
        switch law the Stribeck slope).

    Returns
    -------
    numpy.ndarray, shape (n, 6, 6), 1/s and 1/s^2
        ``d rhs / dy`` for the state ``[z, zd, x, xd, phi, phid]``.
    """
    v = {k: np.asarray(values[k], dtype=np.float64) for k in _LINEAR_FIELDS}
    n = int(np.broadcast_shapes(*(a.shape for a in v.values()), (1,))[0])
    v = {k: np.broadcast_to(a, (n,)) for k, a in v.items()}
    f = v["normal_load"]
    k_s = static(v)[1]
    dfz = np.zeros((n, 6))
    dfz[:, 0] = -k_s
    dfz[:, 1] = -v["contact_damping"]
    dfz[:, 4] = v["twist_coupling"]
    s, arm = v["torsion_sign"], v["moment_arm"]
    if friction_law == "constant":
        dfx = dfz * v["mu"][:, None]
    elif friction_law in ("coulomb", "switch"):
        # F_x = mu(v_r) N tanh(v_r/eps) - mu(V) F_st, v_r = V - xd - s L phid (docs/model.md §2); the
        # switch law slips at y = 0 (V > eta) with sign(v_r) = 1 in place of the tanh.
        vel, vs, mus, eps = v["sliding_speed"], v["stribeck_velocity"], v["mu_static"], v["friction_regularization"]
        e = scalar(math.exp)(-vel / vs)
        mu_k = (v["mu"] - mus * e) / (1.0 - e)
        mu_v = mu_k + (mus - mu_k) * e
        th = scalar(math.tanh)(vel / eps) if friction_law == "coulomb" else np.ones_like(vel)
        dmu = -(mus - mu_k) / vs * e
        dg = dmu * th + mu_v * (1.0 - th * th) / eps
        dfx = dfz * (mu_v * th)[:, None]
        dfx[:, 3] -= f * dg
        dfx[:, 5] -= f * dg * s * arm
    else:
        raise ValueError(f"friction_law = {friction_law!r} is not valid: must be 'constant', 'coulomb' or 'switch'")
    m = v["mass"]
    wz, wx, wt = v["omega_normal"], v["omega_friction"], v["omega_torsion"]
    j = np.zeros((n, 6, 6))
    j[:, 0, 1] = j[:, 2, 3] = j[:, 4, 5] = 1.0
    j[:, 1, :] = dfz / m[:, None]
    j[:, 3, :] = dfx / m[:, None]
    j[:, 5, :] = (s * arm / v["inertia"])[:, None] * dfx
    j[:, 1, 0] -= wz * wz
    j[:, 1, 1] -= 2.0 * v["zeta_normal"] * wz
    j[:, 3, 2] -= wx * wx
    j[:, 3, 3] -= 2.0 * v["zeta_friction"] * wx
    j[:, 5, 4] -= wt * wt
    j[:, 5, 5] -= 2.0 * v["zeta_torsion"] * wt
    return j
