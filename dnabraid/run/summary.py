"""Point summaries, verdicts, the printed table and sweep rows of a thermal run, read from
the observables' declared columns (:class:`dnabraid.observables.Column`).

The run driver summarises every point with :func:`point_summary` (through the scene, which
may add its own quantities): each column's mean, standard error across replicas and
convergence verdict (:func:`summarise`, :func:`dnabraid.analysis.convergence.replica_summary`);
a point converged when every column declared ``verdict`` did (:func:`point_verdict`). The
table (:func:`print_table`) and sweep rows (:func:`rows`) show the columns declared
``reported``, with the units written in ``summary.json``.
"""

from __future__ import annotations

import math

import numpy as np

from ..observables import error_name
from .reporters import mean_sem_entry

__all__ = ["summarise", "point_summary", "point_verdict", "frozen_replicas", "state_label", "format_mean_sem",
           "print_table", "rows", "reported"]


def format_mean_sem(d: dict | None, p: int = 2) -> str:
    """``mean +- sem`` with at least ``p`` decimals and two significant digits of the SEM
    (at most 4 decimals); ``-`` without a mean."""
    if not d or d.get("mean") is None:
        return "-"
    sem = d.get("sem")
    if sem and sem > 0 and math.isfinite(sem):
        p = min(4, max(p, 1 - math.floor(math.log10(sem))))
    return f"{d['mean']:.{p}f} +- {sem:.{p}f}" if sem is not None else f"{d['mean']:.{p}f}"


def summarise(series: list, rule: dict) -> dict:
    """Mean, error and verdict of one observable from its per-replica series; ``rule`` is
    handed to :func:`~dnabraid.analysis.convergence.replica_summary` (R-hat and ESS bounds,
    equilibration). One replica gives the autocorrelation-corrected SEM and no verdict."""
    series = [np.asarray(x, float) for x in series]
    if not series or any(x.size == 0 or not np.all(np.isfinite(x)) for x in series):
        return {"mean": None, "sem": None}
    if len(series) == 1:
        d = mean_sem_entry(series[0])
        d.update(converged=False, reason="one replica: no between-replica check",
                 n_replicas=1)
        return d
    from ..analysis.convergence import replica_summary

    r = replica_summary(series, **rule)
    return {"mean": float(r["mean"]), "sem": float(r["sem"]),
            "ci_halfwidth": float(r["ci_halfwidth"]), "confidence": r["confidence"],
            "n_replicas": int(r["n_replicas"]), "sem_within": float(r["sem_within"]),
            "rhat": float(r["rhat"]), "ess": float(r["ess"]),
            "equilibration_samples": [int(x) for x in r["equilibration_samples"]],
            "replica_means": [float(x) for x in r["replica_means"]],
            "converged": bool(r["converged"]), "reason": r["reason"]}


def state_label(state: dict) -> str:
    """A point's state in words (notes): ``turns 1``, ``delta_lk -1, alpha_pN 3``."""
    return ", ".join(f"{k} {v:g}" if isinstance(v, (int, float)) else f"{k} {v}"
                     for k, v in state.items())


def point_summary(state: dict, reps: list, columns: dict, rule: dict) -> dict:
    """Per point, from the replicas' (samples, frames): the state keys, every summarised
    column's mean, error and verdict, the counts, and the point's verdict (every column
    declared ``verdict`` converged)."""
    pt = dict(state)
    skip = {"turns", "frame", "step", "time_ns"} | {
        c for c, col in columns.items() if not col.summarised}
    for c in reps[0][0]:
        if c not in skip:
            pt[c] = summarise([s[c] for s, _ in reps], rule)
    for c in reps[0][1]:
        if c not in skip:
            pt[c] = summarise([f[c] for _, f in reps], rule)
    pt["n_samples"] = int(sum(len(s["step"]) for s, _ in reps))
    pt["n_frames"] = int(sum(len(f["step"]) for _, f in reps))
    pt["n_replicas"] = len(reps)
    names = [c for c, col in columns.items() if col.verdict]
    point_verdict(pt, names)
    frozen = frozen_replicas(reps, names)
    if frozen:
        pt["converged"] = False
        why = "; ".join(f"{c}: replica(s) {', '.join(map(str, r))} did not move"
                        for c, r in frozen.items())
        pt["convergence_reason"] = (why if pt["convergence_reason"] == "ok"
                                    else f"{pt['convergence_reason']}; {why}")
    pt["label"] = state_label(state)
    return pt


def frozen_replicas(reps: list, names) -> dict:
    """Verdict columns (name -> replica indices) whose series stayed exactly constant in a
    replica: a replica that did not move says nothing about convergence."""
    out = {}
    for c in names:
        for k, (s, f) in enumerate(reps):
            x = s[c] if c in s else f.get(c)
            if x is None or len(x) < 2:
                continue
            x = np.asarray(x, float)
            if np.all(np.isfinite(x)) and np.ptp(x) == 0.0:
                out.setdefault(c, []).append(k)
    return out


def point_verdict(pt: dict, names) -> None:
    """``converged``, ``convergence_reason`` and ``effective_sample_size`` of a point from
    the columns ``names`` that have a mean; with none, the point is not converged."""
    verdict = [(c, pt[c]) for c in names
               if isinstance(pt.get(c), dict) and pt[c].get("mean") is not None]
    pt["converged"] = bool(verdict) and all(v.get("converged", False) for _, v in verdict)
    pt["convergence_reason"] = "; ".join(f"{c}: {v.get('reason', '')}" for c, v in verdict
                                         if not v.get("converged", False)) or (
        "ok" if verdict else "no column that decides the verdict has a value")
    pt["effective_sample_size"] = {c: v.get("ess") for c, v in verdict}


def reported(summary: dict) -> list[tuple[str, dict]]:
    """The reported columns of a run (name, column dict), in computing order."""
    return [(k, c) for k, c in summary.get("columns", {}).items() if c.get("reported")]


def print_table(summary: dict, state_widths: dict, file) -> None:
    """The time step, the notes, one row per point (state, reported columns as mean +-
    SEM, NOT CONVERGED marks) and the verdict line."""
    if summary.get("total_steps", 1) or not summary.get("points"):
        print(f"time step {summary['time_step_ps']:.4g} ps: {summary['time_step_reason']}",
              file=file)
    else:  # moves only (a ladder): no Brownian step was taken
        print("no Brownian steps: sampled by Metropolis moves alone (no time step applies)",
              file=file)
    for n in summary["notes"]:
        print(f"note: {n}", file=file)
    pts = summary["points"]
    states = [k for k in state_widths if pts and k in pts[0]]
    cols = reported(summary)
    print(" ".join([f"{k:>{state_widths[k]}}" for k in states]
                   + [f"{k:>{c.get('width', 20)}}" for k, c in cols]), file=file)
    for pt in pts:
        mark = "" if pt.get("converged", True) else "  NOT CONVERGED"
        cells = [f"{pt[k]:>{state_widths[k]}g}" for k in states]
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


def rows(summary: dict, state_keys) -> list[dict]:
    """One sweep row per point: the state keys, each reported column's mean and standard
    error (:func:`dnabraid.observables.error_name`), and the number of samples."""
    out = []
    cols = reported(summary)
    for pt in summary["points"]:
        row = {k: pt[k] for k in state_keys if k in pt}
        for k, c in cols:
            d = pt.get(k) or {}
            row[k] = d.get("mean")
            row[error_name(k, c.get("unit", ""))] = d.get("sem")
        row["n_samples"] = pt["n_samples"]
        out.append(row)
    return out
