"""The attractor census where sliding is unstable.

There the transient from the unstable mode reaches one motion, which stays the point's regime; the
census runs K disturbances to their attractors and says what else coexists. Nothing can return to
sliding (it is unstable: an analytic zero). Fractions are asserted with their standard errors,
never one run's fate: the regime itself is only asserted to be some motion.
"""

from __future__ import annotations

import math

import numpy as np

import tribosweep as ts
from tribosweep._codes import BISTABLE, REGIME

LAW = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3)
#: A point of the Stribeck sweep (25.6 N, 12.7 cm, 0.4 m/s) where a contact-loss cycle coexists
#: with irregular motion: 50 and 14 of 64 disturbances when written (15 of 64 at rtol 1e-8).
POINT = dict(normal_load=[np.linspace(10, 150, 10)[1]], arm_length=[0.127], sliding_speed=[0.4])
CYCLES = [REGIME[k] for k in ("self_excited", "contact_loss", "stick_slip")]
MOTIONS = [*CYCLES, REGIME["irregular"], REGIME["diverged"]]
SLIDING, CYCLE, IRREGULAR = 0, 1, 2


def test_census_at_an_unstable_point_sees_the_motions_that_coexist():
    k = 64
    ds = ts.sweep(LAW, **POINT, samples=k, t_max=20.0, progress=False).squeeze()
    assert float(ds.growth_rate) > 0  # sliding is linearly unstable
    assert int(ds.regime) in MOTIONS
    assert int(ds.census_samples) == k and int(ds.census_failed) == 0
    frac, low = ds.basin_fraction.values, ds.basin_fraction_low.values
    # Nothing returns to unstable sliding.
    assert frac[SLIDING] == 0.0 and float(ds.basin_stability) == 0.0
    # A cycle and irregular motion both, each seen beyond doubt: the 95 % Wilson intervals exclude
    # 0 (with p about 0.22, no irregular sample among 64 has probability 0.78^64, about 1e-7).
    assert low[CYCLE] > 0.0 and low[IRREGULAR] > 0.0, frac
    assert int(ds.n_attractors) >= 2 and int(ds.bistable) == BISTABLE["coexisting"]
    assert "coexisting attractors (census): cycle" in str(ds.reason.values), str(ds.reason.values)
    # The sweep's census is the point's own census (the standalone one, bit for bit).
    m = ts.apparatus_model(POINT["normal_load"][0], POINT["arm_length"][0], POINT["sliding_speed"][0], base=LAW)
    alone = ts.census(m, samples=k)
    np.testing.assert_array_equal(alone.basin_fraction.values, frac)
    # A property of the point, not of the integration's last bits: at rtol 1e-8 (against the
    # census's 1e-6) the irregular fraction agrees within 3 combined standard errors.
    tight = ts.census(m, samples=k, rtol=1e-8)
    se = math.hypot(float(ds.basin_fraction_se[IRREGULAR]), float(tight.basin_fraction_se[IRREGULAR]))
    assert abs(float(tight.basin_fraction[IRREGULAR]) - frac[IRREGULAR]) <= 3 * se + 1e-12, (
        tight.basin_fraction.values, frac)  # fmt: skip


def test_every_unstable_point_that_reached_a_motion_has_a_census():
    # Constant friction, unilateral contact: loads on both sides of the Hopf load (24.9 N at the
    # seed) at two arm lengths. Stable points get the census where a saddle cycle is predicted;
    # unstable ones wherever their transient reached a motion, and their regime is that motion.
    ds = ts.sweep(ts.SliderModel(contact="unilateral"), normal_load=[10.0, 15.0, 60.0, 120.0],
                  arm_length=[0.06, 0.072], samples=8, t_max=20.0, progress=False)  # fmt: skip
    unstable = ds.growth_rate.values > 0
    motion = np.isin(ds.regime.values, MOTIONS)
    assert (unstable & motion).sum() >= 3, ts.labels(ds.regime).values
    assert np.all(ds.census_samples.values[unstable & motion] == 8)
    assert np.all(ds.bistable.values[unstable & motion] != BISTABLE["not_checked"])
    # Their fractions are fractions of 8 that sum to 1, none back to sliding.
    f = ds.basin_fraction.values[unstable & motion]
    np.testing.assert_allclose(f.sum(axis=-1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(f[..., SLIDING], 0.0)
    np.testing.assert_allclose(f * 8, np.rint(f * 8), atol=1e-9)


def test_regime_fraction_says_how_many_disturbances_reach_the_label():
    # Stable and unstable points of the switch law (loads on both sides of the Hopf curve; speeds
    # where the friction curve falls and where it is nearly flat).
    k = 16
    ds = ts.sweep(LAW, normal_load=[25.6, 87.8, 134.4], arm_length=[0.0757, 0.127], sliding_speed=[0.2, 0.6],
                  samples=k, t_max=20.0, progress=False)  # fmt: skip
    st = ds.stack(p=ds.regime.dims).transpose("p", ...)
    rf, se = st.regime_fraction.values, st.regime_fraction_se.values
    frac, n = st.basin_fraction.values, st.census_samples.values
    regime, stable = st.regime.values, st.growth_rate.values < 0
    censused = n > 0
    assert censused.sum() >= 6 and (stable & censused).any() and (~stable & censused).any()
    assert np.all(np.isnan(rf[~censused]))
    c = censused
    # Binomial standard errors, fractions of the counted disturbances.
    np.testing.assert_allclose(se[c], np.sqrt(rf[c] * (1 - rf[c]) / n[c]), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(rf[c] * n[c], np.rint(rf[c] * n[c]), atol=1e-9)
    # Steady sliding: the fraction that returns to it, basin_stability.
    slide = c & (regime == REGIME["steady_sliding"])
    np.testing.assert_array_equal(rf[slide], st.basin_stability.values[slide])
    # Irregular motion: the fraction reaching it (an escape's, likewise, reads the escape fraction).
    irr = c & (regime == REGIME["irregular"])
    assert irr.any()
    np.testing.assert_array_equal(rf[irr], frac[irr, IRREGULAR])
    # A cycle: the samples on the transient's own cycle, at most all cycle samples.
    cyc = c & np.isin(regime, CYCLES)
    assert cyc.any() and np.all(rf[cyc] <= frac[cyc, CYCLE] + 1e-12)
    # Without the census it is unknown.
    off = ts.sweep(LAW, normal_load=[87.8], arm_length=[0.0757], sliding_speed=[0.2], census=False, t_max=20.0,
                   progress=False)  # fmt: skip
    assert np.isnan(float(off.regime_fraction.squeeze()))
