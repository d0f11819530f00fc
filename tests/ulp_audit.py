"""A pytest plugin that moves every model input the core sees by a few ulps: an audit of the suite's
machine independence, run by hand (not by CI).

    AUDIT_ULP=1 PYTHONPATH=tests python -m pytest -q -p ulp_audit tests     # also -1, 2, -2

Every real parameter of ``SliderModel.values()`` (what the core gets) except ``torsion_sign`` and
zeros is moved by ``AUDIT_ULP`` ulps (``np.nextafter``), for the whole session, module fixtures
included. A different libm or CPU that computed a derived input (a natural frequency from the
apparatus power laws) one ulp apart would do the same. It is a stronger test than another CPU:
the census draws its samples from a Halton sequence shifted by a hash of the inputs, so every
census gets other samples. A test of physics or statistics must pass under it.

Failures that are the audit's own, by design (2026-11-27: 18-23 failures at +-1 and +-2 ulps, all of these kinds):

- tests that compare ``values()`` or a written file's attributes with the model's fields, or an
  error message with the value given (``test_validation``, ``test_cli``, ``test_faults``,
  ``test_switch``'s arguments, ``test_simulate``'s decoupled limit, resume's configuration check);
- tests that compare a sweep with a standalone computation bit for bit
  (``test_a_sweep_point_has_the_standalone_census``, ``..._says_how_its_irregular_samples_...``,
  ``test_batched_orbits_equal_single_solves_...``): the sweep passes some inputs as point arrays,
  which the audit does not move, so the two sides get different inputs; and tests that compare a
  sweep run in a subprocess (which the plugin does not reach) with one run here (``test_faults``'
  crash and full-disk resumes).
"""

from __future__ import annotations

import os

ULPS: int = int(os.environ.get("AUDIT_ULP", "0"))


def pytest_configure(config):
    if not ULPS:
        return
    from conftest import moved
    from tribosweep import _model

    values = _model.SliderModel.values

    def moved_values(self):
        return {k: (float(moved(v, ULPS)) if isinstance(v, float) and v != 0.0 and k != "torsion_sign" else v)
                for k, v in values(self).items()}  # fmt: skip

    _model.SliderModel.values = moved_values
