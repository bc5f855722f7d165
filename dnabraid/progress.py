"""Progress for people and for log files.

On a terminal, :func:`progress_bar` is a tqdm bar. When the output is not a terminal (CI, a
``nohup`` log, a Dask worker) a redrawn bar is a stream of carriage returns; there it is
:class:`LineProgress`: one plain line every ``every`` of the work (5 % by default) with the
rate and the time left, and one at the end.
"""

from __future__ import annotations

import sys
import time

__all__ = ["LineProgress", "progress_bar"]


def _duration(s: float) -> str:
    s = max(0.0, float(s))
    if s < 90:
        return f"{s:.0f} s"
    if s < 5400:
        return f"{s / 60:.1f} min"
    return f"{s / 3600:.1f} h"


class LineProgress:
    """A progress report of plain lines (``update(n)``, ``close()``, ``write(msg)``, like
    tqdm's), for output that is not a terminal.

    Parameters
    ----------
    total : float
        The amount of work.
    unit : str
    desc : str
    every : float
        Fraction of ``total`` between two lines.
    file : text stream (default sys.stderr)
    disable : bool
    """

    def __init__(self, total: float, *, unit: str = "it", desc: str = "", every: float = 0.05,
                 file=None, disable: bool = False):
        self.total = float(total)
        self.unit = unit
        self.desc = desc
        self.every = float(every)
        self.file = file if file is not None else sys.stderr
        self.disable = disable
        self.n = 0.0
        self._t0 = time.perf_counter()
        self._next = self.every * self.total
        self._closed = False

    def _line(self) -> str:
        dt = time.perf_counter() - self._t0
        rate = self.n / dt if dt > 0 else 0.0
        frac = self.n / self.total if self.total > 0 else 1.0
        left = (self.total - self.n) / rate if rate > 0 else float("nan")
        eta = _duration(left) if left == left else "?"
        return (f"{self.desc + ': ' if self.desc else ''}{100 * frac:5.1f} % "
                f"({self.n:.4g}/{self.total:.4g} {self.unit}), {rate:.4g} {self.unit}/s, "
                f"{_duration(dt)} elapsed, {eta} left")

    def update(self, n: float = 1) -> None:
        self.n += n
        if self.disable:
            return
        if self.n >= self._next and self.n < self.total:
            print(self._line(), file=self.file, flush=True)
            while self._next <= self.n:
                self._next += self.every * self.total

    def write(self, msg: str, file=None) -> None:
        print(msg, file=file or self.file, flush=True)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if not self.disable:
            print(self._line(), file=self.file, flush=True)


def progress_bar(total: float, *, unit: str = "it", desc: str = "", disable: bool = False,
                 file=None):
    """A tqdm bar on a terminal, :class:`LineProgress` otherwise."""
    file = file if file is not None else sys.stderr
    if hasattr(file, "isatty") and file.isatty():
        from tqdm import tqdm

        return tqdm(total=total, unit=unit, unit_scale=True, desc=desc, disable=disable,
                    dynamic_ncols=True, file=file)
    return LineProgress(total, unit=unit, desc=desc, disable=disable, file=file)
