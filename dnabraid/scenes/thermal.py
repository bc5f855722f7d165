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
import math
from typing import ClassVar

import numpy as np

from ..observables import error_name
from ..run import driver
from ..run.contract import StartError, ThermalContract
from ..run.driver import MAX_REPLICAS
from ..run.reporters import mean_sem_entry
from .base import DNAQuantities, Scene

__all__ = ["ThermalScene", "format_mean_sem"]


def format_mean_sem(d: dict | None, p: int = 2) -> str:
    """``mean +- sem`` with at least ``p`` decimals and two significant digits of the SEM
    (at most 4 decimals); ``-`` without a mean."""
    if not d or d.get("mean") is None:
        return "-"
    sem = d.get("sem")
    if sem and sem > 0 and math.isfinite(sem):
        p = min(4, max(p, 1 - math.floor(math.log10(sem))))
    return f"{d['mean']:.{p}f} +- {sem:.{p}f}" if sem is not None else f"{d['mean']:.{p}f}"


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
        (``rule`` overrides :meth:`verdict_rule`)."""
        series = [np.asarray(x, float) for x in series]
        if not series or any(x.size == 0 or not np.all(np.isfinite(x)) for x in series):
            return {"mean": None, "sem": None}
        if len(series) == 1:
            d = mean_sem_entry(series[0])
            d.update(converged=False, reason="one replica: no between-replica check",
                     n_replicas=1)
            return d
        from ..analysis.convergence import replica_summary

        r = replica_summary(series, **{**self.verdict_rule(), **rule})
        return {"mean": float(r["mean"]), "sem": float(r["sem"]),
                "ci_halfwidth": float(r["ci_halfwidth"]), "confidence": r["confidence"],
                "n_replicas": int(r["n_replicas"]), "sem_within": float(r["sem_within"]),
                "rhat": float(r["rhat"]), "ess": float(r["ess"]),
                "equilibration_samples": [int(x) for x in r["equilibration_samples"]],
                "replica_means": [float(x) for x in r["replica_means"]],
                "converged": bool(r["converged"]), "reason": r["reason"]}

    def state_label(self, state: dict) -> str:
        """A point's state in words (notes): ``turns 1``, ``delta_lk -1, alpha_pN 3``."""
        return ", ".join(f"{k} {v:g}" if isinstance(v, (int, float)) else f"{k} {v}"
                         for k, v in state.items())

    def point_summary(self, segment, reps: list, columns: dict) -> dict:
        """Per point, from the replicas' (samples, frames): every column's mean, error and
        verdict; the point converged when every column declared ``verdict`` did."""
        state = self.state_of(segment)
        pt = dict(state)
        skip = {"turns", "frame", "step", "time_ns"} | {
            c for c, col in columns.items() if not col.summarised}
        for c in reps[0][0]:
            if c not in skip:
                pt[c] = self.summarise([s[c] for s, _ in reps])
        for c in reps[0][1]:
            if c not in skip:
                pt[c] = self.summarise([f[c] for _, f in reps])
        pt["n_samples"] = int(sum(len(s["step"]) for s, _ in reps))
        pt["n_frames"] = int(sum(len(f["step"]) for _, f in reps))
        pt["n_replicas"] = len(reps)
        self.point_verdict(pt, [c for c, col in columns.items() if col.verdict])
        pt["label"] = self.state_label(state)
        return pt

    @staticmethod
    def point_verdict(pt: dict, names) -> None:
        """``converged``, ``convergence_reason`` and ``effective_sample_size`` of a point
        from the columns ``names`` that have a mean."""
        verdict = [(c, pt[c]) for c in names
                   if isinstance(pt.get(c), dict) and pt[c].get("mean") is not None]
        pt["converged"] = bool(verdict) and all(v.get("converged", False) for _, v in verdict)
        pt["convergence_reason"] = "; ".join(f"{c}: {v.get('reason', '')}" for c, v in verdict
                                             if not v.get("converged", False)) or (
            "ok" if verdict else "no column that decides the verdict has a value")
        pt["effective_sample_size"] = {c: v.get("ess") for c, v in verdict}

    # -- CLI and sweeps ------------------------------------------------------------------
    def reported(self, summary: dict) -> list[tuple[str, dict]]:
        """The reported columns of a run (name, column dict), in computing order."""
        return [(k, c) for k, c in summary.get("columns", {}).items() if c.get("reported")]

    def report(self, summary: dict, out: str, file) -> None:
        print(f"time step {summary['time_step_ps']:.4g} ps: {summary['time_step_reason']}",
              file=file)
        for n in summary["notes"]:
            print(f"note: {n}", file=file)
        pts = summary["points"]
        states = [k for k in self.state_widths if pts and k in pts[0]]
        cols = self.reported(summary)
        print(" ".join([f"{k:>{self.state_widths[k]}}" for k in states]
                       + [f"{k:>{c.get('width', 20)}}" for k, c in cols]), file=file)
        for pt in pts:
            mark = "" if pt.get("converged", True) else "  NOT CONVERGED"
            cells = [f"{pt[k]:>{self.state_widths[k]}g}" for k in states]
            cells += [f"{format_mean_sem(pt.get(k), c.get('digits', 2)):>{c.get('width', 20)}}"
                      for k, c in cols]
            print(" ".join(cells) + mark, file=file)
        print("+- : standard error of the mean across independent replicas (Student-t 95% "
              "intervals in summary.json)", file=file)
        if pts and all(pt.get("converged", False) for pt in pts):
            ess = [v for pt in pts for v in pt.get("effective_sample_size", {}).values()
                   if v is not None]
            print(f"all {len(pts)} points converged (split R-hat and bulk ESS across "
                  f"replicas; smallest ESS {min(ess):.0f})" if ess else
                  f"all {len(pts)} points converged", file=file)
        self.report_extra(summary, file)
        print(f"wall time {summary['wall_time_s']:.1f} s on {summary['platform']}; results in "
              f"{out}/", file=file)

    def report_extra(self, summary: dict, file) -> None:
        """Lines a scene adds to the table's foot (e.g. its precision targets)."""
        return None

    def rows(self, summary: dict) -> list[dict]:
        """One sweep row per point: the state keys, each reported column's mean and
        standard error (``error_name``), and the number of samples."""
        out = []
        cols = self.reported(summary)
        for pt in summary["points"]:
            row = {k: pt[k] for k in self.state_widths if k in pt}
            for k, c in cols:
                d = pt.get(k) or {}
                row[k] = d.get("mean")
                row[error_name(k, c.get("unit", ""))] = d.get("sem")
            row["n_samples"] = pt["n_samples"]
            out.append(row)
        return out
