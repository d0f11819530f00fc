"""Progress of a sweep: plain periodic lines in a log (no carriage returns), a final summary."""

from __future__ import annotations

import io
import re

import tribosweep as ts
from tribosweep._sweep import progress as _progress


def test_a_log_gets_plain_lines_with_rate_and_eta_and_a_summary(monkeypatch):
    monkeypatch.setattr(_progress, "LOG_INTERVAL", 0.0)  # a line per chunk
    stream = io.StringIO()  # not a terminal
    monkeypatch.setattr("sys.stderr", stream)
    ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], strategy="linear", chunk_size=2, progress=True)
    text = stream.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    # The load x arm box's boundary curves first (computed before any point, so the wait is named),
    # then one meter line per chunk (3 chunks of 2 points), then the summary.
    assert re.fullmatch(r"sweep: stability boundary curves of the load x arm box \(boundaries=False, "
                        r"--no-boundaries: none\) \.\.\. \d+\.\d s", lines[0])  # fmt: skip
    lines = lines[1:]
    assert [re.search(r"(\d+)%", line).group(1) for line in lines[:3]] == ["33", "67", "100"]
    assert "2/6" in lines[0] and "6/6" in lines[2] and "pt/s" in lines[2]
    assert lines[3].startswith("sweep: 6 points in ") and lines[3].endswith("points/s")
    assert len(lines) == 4
    # Without the curves, no such line.
    stream.truncate(0)
    stream.seek(0)
    ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], strategy="linear", chunk_size=2, progress=True,
             boundaries=False)  # fmt: skip
    assert not stream.getvalue().startswith("sweep: stability") and len(stream.getvalue().splitlines()) == 4
    # Nor with a third axis swept (no curves then).
    stream.truncate(0)
    stream.seek(0)
    ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], sliding_speed=[0.3, 0.5], strategy="linear",
             chunk_size=12, progress=True)  # fmt: skip
    assert "boundary curves" not in stream.getvalue(), stream.getvalue()


def test_a_resumed_sweep_counts_only_this_runs_points_in_its_rate():
    stream = io.StringIO()
    p = _progress.Progress(True, 10, 4, stream=stream, interval=1e9)
    p.update(6)  # the last update always writes a line
    p.close()
    lines = stream.getvalue().splitlines()
    assert "10/10" in lines[0]
    assert lines[1].startswith("sweep: 6 points in ") and lines[1].endswith("(4 saved before)")


def test_disabled_progress_writes_nothing():
    stream = io.StringIO()
    p = _progress.Progress(False, 10, 0, stream=stream)
    p.update(10)
    p.close()
    assert stream.getvalue() == ""
