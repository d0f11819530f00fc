"""Progress of a sweep on stderr: tqdm's bar on a terminal, plain periodic lines in a log, a summary at the end.

On a terminal the bar shows rate and ETA. Where stderr is not a terminal (a log file, a batch
job) carriage returns would pile up into one unreadable line, so the same meter (tqdm's own
``format_meter``: count, percentage, elapsed, ETA, rate) is written as a plain line every
``LOG_INTERVAL`` seconds. Either way the sweep ends with one line: points, total time, points/s.
"""

from __future__ import annotations

import sys
import time

#: Seconds between two plain progress lines when stderr is not a terminal.
LOG_INTERVAL: float = 30.0


class Progress:
    """Progress of ``total`` points, ``initial`` of them already done (a resumed sweep); silent when disabled."""

    def __init__(self, enabled: bool, total: int, initial: int, *, stream=None, interval: float | None = None):
        self.enabled, self.total, self.initial, self.done = enabled, total, initial, initial
        self.stream = sys.stderr if stream is None else stream
        self.interval = LOG_INTERVAL if interval is None else interval
        self.t0 = self.last = time.perf_counter()
        self.bar = None
        if not enabled:
            return
        from tqdm import tqdm

        self._meter = tqdm.format_meter
        if _isatty(self.stream):
            self.bar = tqdm(total=total, initial=initial, unit="pt", desc="sweep", file=self.stream, dynamic_ncols=True)

    def update(self, n: int) -> None:
        self.done += n
        if self.bar is not None:
            self.bar.update(n)
        elif self.enabled:
            now = time.perf_counter()
            if now - self.last >= self.interval or self.done >= self.total:
                self.last = now
                self._line(now)

    def _line(self, now: float) -> None:
        # The rate counts only this run's points (a resumed sweep's saved ones took no time now).
        elapsed = now - self.t0
        rate = (self.done - self.initial) / elapsed if elapsed > 0 else None
        meter = self._meter(self.done, self.total, elapsed, prefix="sweep", unit="pt", rate=rate, ncols=0)
        self.stream.write(meter + "\n")
        self.stream.flush()

    def close(self) -> None:
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.close()
        n = self.done - self.initial
        dt = time.perf_counter() - self.t0
        rate = f", {n / dt:.4g} points/s" if dt > 0 and n else ""
        resumed = f" ({self.initial} saved before)" if self.initial else ""
        self.stream.write(f"sweep: {n} points in {dt:.1f} s{rate}{resumed}\n")
        self.stream.flush()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False
