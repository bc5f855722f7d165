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

from ..chains import MIN_PASSAGE_BARRIER_KT, max_bead_spacing_nm, passage_barrier_kT
from ..run import driver
from ..run import summary as run_summary
from ..run.contract import StartError, ThermalContract
from ..run.driver import MAX_REPLICAS
from ..run.engine import INTEGRATORS, MAX_SEED
from .base import DNAQuantities, Scene

__all__ = ["ThermalScene"]


class ThermalScene(DNAQuantities, Scene, ThermalContract):
    """Base of the thermal scenes (OpenMM Brownian dynamics, replicas, verdicts)."""

    #: Width and format of the state columns in the printed table.
    state_widths: ClassVar[dict] = {}

    # -- checks --------------------------------------------------------------------------
    def check_run_keys(self) -> None:
        """The keys every thermal run has: sampling intervals, seed, replicas, packing,
        workers, time-step safety and integrator."""
        need = self.need
        need(self.report_interval >= 1, "report_interval", "must be >= 1")
        need(self.steps >= self.report_interval, "steps",
             f"must be >= report_interval={self.report_interval}")
        need(self.equilibration_steps >= 0, "equilibration_steps", "must be >= 0")
        need(self.frame_interval >= self.report_interval
             and self.frame_interval % self.report_interval == 0, "frame_interval",
             f"must be a multiple of report_interval={self.report_interval}")
        need(0 <= self.seed <= MAX_SEED // MAX_REPLICAS, "seed",
             f"must be in [0, {MAX_SEED // MAX_REPLICAS}] (replica r runs seed x "
             f"{MAX_REPLICAS} + r)")
        need(1 <= self.replicas <= MAX_REPLICAS, "replicas", f"must be in [1, {MAX_REPLICAS}]")
        need(0 <= self.pack <= MAX_REPLICAS, "pack", f"must be in [0, {MAX_REPLICAS}] (0 = auto)")
        need(self.workers >= 0, "workers", "must be >= 0 (0 = one per usable core)")
        need(0 < self.timestep_safety <= 0.9, "timestep_safety", "must be in (0, 0.9]")
        need(self.integrator in INTEGRATORS, "integrator", f"allowed: {', '.join(INTEGRATORS)}")

    def check_passage_barrier(self) -> None:
        """DNA must not pass through DNA: the excluded-volume barrier of two crossing bonds
        (bond stretch included, :func:`dnabraid.chains.passage_barrier_kT`) must be at least
        MIN_PASSAGE_BARRIER_KT, else the bead spacing is refused with the largest allowed."""
        d = self.effective_diameter_nm
        k_kT = (self.stretch_modulus_pN / self.bead_spacing_nm / self.kT
                if self.stretch == "bonds" else None)
        barrier = passage_barrier_kT(self.bead_spacing_nm, d, k_kT)
        if barrier >= MIN_PASSAGE_BARRIER_KT:
            return
        s_kT = None if k_kT is None else self.stretch_modulus_pN / self.kT
        self.need(False, "bead_spacing_nm",
                  f"too coarse for the effective DNA diameter {d:.2f} nm at {self.salt_mM} mM "
                  f"salt: DNA could pass through DNA (barrier {barrier:.1f} kT < "
                  f"{MIN_PASSAGE_BARRIER_KT} kT, bond stretch included). Use bead_spacing_nm "
                  f"<= {max_bead_spacing_nm(d, s_kT):.2f}")

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
