"""What every thermal scene shares: the run driver's contract with its usual defaults, and the
point summary, table, sweep rows and verdict read from the observables' declared columns.

A thermal scene subclasses :class:`ThermalScene`, declares its keys (frozen dataclass
fields; those the driver reads are listed in :class:`dnabraid.run.contract.ThermalContract`),
and implements :meth:`build` (a :class:`dnabraid.chains.Model`), :meth:`observables`,
:meth:`states` and :meth:`state_of`. Everything else has a default here that a scene
overrides only when it means something else: the run itself is
:func:`dnabraid.run.driver.run`.
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

from ..run import driver
from ..run import summary as run_summary
from ..run.contract import StartError, ThermalContract
from ..run.driver import MAX_REPLICAS
from .base import DNAQuantities, Scene

__all__ = ["ThermalScene"]


class ThermalScene(DNAQuantities, Scene, ThermalContract):
    """Base of the thermal scenes (OpenMM Brownian dynamics, replicas, verdicts)."""

    #: Width and format of the state columns in the printed table.
    state_widths: ClassVar[dict] = {}

    # -- run -----------------------------------------------------------------------------
    def run(self, out: str, *, platform: str = "CPU", threads: int | None = None,
            progress_factory=None) -> dict:
        return driver.run(self, out, platform=platform, threads=threads,
                          progress_factory=progress_factory)

    def replica_seed(self, r: int) -> int:
        """Seed of replica ``r``: seed x MAX_REPLICAS + r (distinct for every replica)."""
        return self.seed * MAX_REPLICAS + r

    def replica(self, r: int) -> ThermalScene:
        return dataclasses.replace(self, seed=self.replica_seed(r))

    def start(self, model, segment):
        raise StartError(f"scene {self.name!r} builds no start for {segment.tag}")

    @property
    def noise_sign(self):
        return None

    @property
    def mirror_axis(self):
        return None

    @property
    def pack_along_line(self) -> bool:
        return False

    def notes(self, model) -> list[str]:
        return []

    def has_targets(self) -> bool:
        return False

    def replicas_needed(self, points: list, replicas: int) -> int:
        return replicas

    @property
    def max_replicas(self) -> int:
        return self.replicas

    def finish_point(self, point: dict, stopped_by: str) -> None:
        return None

    def plot(self, summary: dict, out: str) -> None:
        return None

    # -- statistics ----------------------------------------------------------------------
    def verdict_rule(self) -> dict:
        """Keyword arguments of :func:`~dnabraid.analysis.convergence.replica_summary`:
        the relaxed R-hat <= 1.05 and ESS >= 100 with a data-driven equilibration."""
        from ..analysis.convergence import MIN_ESS_RELAXED, RHAT_MAX_RELAXED

        return {"rhat_max": RHAT_MAX_RELAXED, "min_ess": MIN_ESS_RELAXED}

    def summarise(self, series: list, **rule) -> dict:
        """Mean, error and verdict of one observable from its per-replica series
        (``rule`` overrides :meth:`verdict_rule`; :func:`dnabraid.run.summary.summarise`)."""
        return run_summary.summarise(series, {**self.verdict_rule(), **rule})

    def point_summary(self, segment, reps: list, columns: dict) -> dict:
        """Per point: every column's mean, error and verdict; the point converged when
        every column declared ``verdict`` did (:func:`dnabraid.run.summary.point_summary`).
        Scenes add their own quantities by extending this."""
        return run_summary.point_summary(self.state_of(segment), reps, columns,
                                     self.verdict_rule())

    # -- CLI and sweeps ------------------------------------------------------------------
    def report(self, summary: dict, out: str, file) -> None:
        run_summary.print_table(summary, self.state_widths, file)
        self.report_extra(summary, file)
        print(f"wall time {summary['wall_time_s']:.1f} s on {summary['platform']}; results in "
              f"{out}/", file=file)

    def report_extra(self, summary: dict, file) -> None:
        """Lines a scene adds to the table's foot (e.g. its precision targets)."""
        return None

    def rows(self, summary: dict) -> list[dict]:
        """One sweep row per point (:func:`dnabraid.run.summary.rows`)."""
        return run_summary.rows(summary, self.state_widths)
