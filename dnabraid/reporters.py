"""Reporters: a self-describing run directory.

``scene.toml`` (resolved scene), ``topology.pdb`` + ``trajectory.dcd`` (open with
``MDAnalysis.Universe``), ``observables.csv`` (units in headers), ``summary.json``,
``extension_torque.png``. Files are written to a temporary name and renamed, so a
crash never leaves a half-written result.
"""

from __future__ import annotations

import csv
import json
import math
import os
import platform as _platform
import sys

import numpy as np

from .analysis.stats import mean_sem


def atomic_write_text(path: str, text: str) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)


#: An autocorrelation-corrected SEM is trusted when the run holds this many correlation times.
MIN_N_EFF = 20


def _ms(x) -> dict:
    x = np.asarray(x, float)
    if x.size == 0 or not np.all(np.isfinite(x)):
        return {"mean": None, "sem": None}
    r = mean_sem(x)
    return {"mean": float(r["mean"]), "sem": float(r["sem"]),
            "tau_int_samples": float(r["tau_int"]), "n_eff": float(r["n_eff"]),
            "sem_reliable": bool(r["n_eff"] >= MIN_N_EFF)}


def summarise_points(results) -> list[dict]:
    """Per turn value: mean and autocorrelation-corrected SEM of each observable."""
    pts = []
    for r in results:
        pts.append({
            "turns": float(r.turns),
            "extension_nm": _ms(r.extension_nm),
            "torque_pN_nm": _ms(r.torque_pN_nm),
            "catenation": _ms(r.catenation),
            "bead_angle_turns": _ms(r.bead_angle_turns),
            "n_samples": int(len(r.step)),
            "n_frames": int(len(r.frame_step)),
        })
    return pts


def write_topology(path: str, topology, positions_nm) -> None:
    from openmm import app
    from openmm import unit as u

    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        app.PDBFile.writeFile(topology, np.asarray(positions_nm) * u.nanometer, fh)
    os.replace(tmp, path)


def write_dcd(path: str, topology, frames_nm, dt_ps: float, interval: int) -> None:
    from openmm import app
    from openmm import unit as u

    tmp = path + ".tmp"
    with open(tmp, "wb") as fh:
        dcd = app.DCDFile(fh, topology, dt_ps, 0, max(1, int(interval)))
        for fr in frames_nm:
            dcd.writeModel(np.asarray(fr, float) * u.nanometer)
    os.replace(tmp, path)


def write_observables(path: str, results, dt_ns: float) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["turns", "step", "time_ns", "extension_nm", "torque_pN_nm",
                    "bead_angle_turns", "catenation"])
        for r in results:
            cat = dict(zip(r.frame_step.astype(int).tolist(), r.catenation.tolist()))
            for i in range(len(r.step)):
                st = int(r.step[i])
                c = cat.get(st, "")
                w.writerow([r.turns, st, f"{st * dt_ns:.6g}", f"{r.extension_nm[i]:.6g}",
                            "" if math.isnan(r.torque_pN_nm[i]) else f"{r.torque_pN_nm[i]:.6g}",
                            "" if math.isnan(r.bead_angle_turns[i]) else
                            f"{r.bead_angle_turns[i]:.6g}",
                            "" if c == "" or (isinstance(c, float) and math.isnan(c)) else
                            f"{c:.6g}"])
    os.replace(tmp, path)


def versions() -> dict:
    import openmm
    import scipy

    from . import __version__

    return {"dnabraid": __version__, "openmm": openmm.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "python": sys.version.split()[0],
            "machine": _platform.platform()}


def write_summary(path: str, summary: dict) -> None:
    atomic_write_text(path, json.dumps(summary, indent=2, default=float) + "\n")
