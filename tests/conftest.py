"""Shared fixtures: the seed reference values of ../shared/reference/seed_values.json; the pixel size of a
PNG file and the Figures behind the images a function saves (to check a chart's content, not its bytes)."""

from __future__ import annotations

import json
import pathlib
import struct

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


def _png_size(path) -> tuple[int, int]:
    """(width, height) in pixels from a PNG file's IHDR chunk; fails if the file is not a PNG."""
    head = pathlib.Path(path).read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", f"{path} is not a PNG file"
    return struct.unpack(">II", head[16:24])


@pytest.fixture
def png_size():
    """The function ``png_size(path) -> (width, height)``."""
    return _png_size


@pytest.fixture
def saved_figures(monkeypatch) -> dict:
    """Every matplotlib Figure saved during the test, by the saved file's name (the Figure itself, to read
    its artists' data)."""
    from matplotlib.figure import Figure

    real = Figure.savefig
    figures = {}

    def savefig(self, fname, *args, **kwargs):
        figures[pathlib.Path(fname).name] = self
        return real(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return figures
