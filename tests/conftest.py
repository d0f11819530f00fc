"""Shared fixtures: the seed reference values of ../shared/reference/seed_values.json."""

from __future__ import annotations

import json
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
_CANDIDATES = [ROOT / "tests" / "data" / "seed_values.json", ROOT.parent / "shared" / "reference" / "seed_values.json"]


@pytest.fixture(scope="session")
def seed_values() -> dict:
    """Reference values of MODEL.md, computed independently (scipy, tight tolerances)."""
    for p in _CANDIDATES:
        if p.exists():
            return json.loads(p.read_text())
    raise FileNotFoundError(f"seed_values.json not found in {_CANDIDATES}")
