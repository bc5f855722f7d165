"""MDAnalysis analysis of a sweep's trajectories: extension, catenation, crossings per point.

:func:`analyse_sweep` opens every finished point's ``topology.pdb`` + ``trajectory.dcd``
(two-strand tweezer scenes) and runs the :mod:`dnabraid.analysis.mda` classes over its
frames, split per turn value with the point's ``frames.csv``. The sweep package is
imported inside the function (it imports the scenes; dnabraid.sweep re-exports
:func:`analyse_sweep`).
"""

from __future__ import annotations

import csv
import json
import os
import warnings

__all__ = ["analyse_sweep"]


def _frame_turns(path: str):
    """The turn value of every frame of a run's ``trajectory.dcd`` (from its ``frames.csv``)."""
    import numpy as np

    with open(path, newline="") as fh:
        return np.array([float(r["turns"]) for r in csv.DictReader(fh)])


def analyse_sweep(sweep_dir: str, *, crossing_cutoff_nm: float | None = None,
                  write: bool = True) -> list[dict]:
    """Analyse every finished point's two-strand trajectory with MDAnalysis.

    Points without a ``trajectory.dcd`` (the knot scene writes none) are left out. Opens
    ``topology.pdb`` + ``trajectory.dcd`` of each point and runs
    :class:`~dnabraid.analysis.mda.Extension`, :class:`~dnabraid.analysis.mda.Catenation`
    and :class:`~dnabraid.analysis.mda.CrossingAngles` over its frames; the frames are
    split per turn value with the run's ``frames.csv`` (which names each frame's turn value,
    whatever the order of replicas and turn values in the trajectory).

    Parameters
    ----------
    sweep_dir : str
        A sweep directory (holds ``sweep.toml``).
    crossing_cutoff_nm : float, optional
        Closest-approach cutoff of a crossing; default 2 x the effective DNA diameter.
    write : bool
        Also write ``<sweep_dir>/trajectory_analysis.csv``.

    Returns
    -------
    list of dict
        One row per point and turn value: the grid values, ``turns``, ``n_frames``,
        ``extension_nm`` (strand A's bead end, frame mean), ``catenation`` (frame mean),
        ``crossings_per_frame``, ``mean_abs_crossing_angle_deg``, ``point``.
    """
    import MDAnalysis as mda
    import numpy as np

    from ..sweep.gather import write_csv
    from ..sweep.spec import SPEC_FILE, load_spec, point_dir
    from .mda import Catenation, CrossingAngles, Extension, select_strands

    spec = load_spec(os.path.join(sweep_dir, SPEC_FILE), out=sweep_dir)
    keys = list(spec.grid)
    rows = []
    for p in spec.points:
        d = point_dir(spec, p)
        files = [os.path.join(d, f) for f in ("topology.pdb", "trajectory.dcd", "summary.json",
                                              "frames.csv")]
        if not all(os.path.isfile(f) for f in files):
            continue
        with open(files[2]) as fh:
            summary = json.load(fh)
        with warnings.catch_warnings():  # beads have no element or mass; DCD reader notes
            warnings.filterwarnings("ignore", module="MDAnalysis")
            u = mda.Universe(files[0], files[1])
            s1, s2 = select_strands(u)
            cutoff = crossing_cutoff_nm or 2.0 * summary["effective_diameter_nm"]
            ext = Extension(s1).run()
            cat = Catenation(s1, s2).run()
            cross = CrossingAngles(s1, s2, cutoff_nm=cutoff).run()
        frame_turns = _frame_turns(os.path.join(d, "frames.csv"))
        for pt in summary["points"]:
            idx = np.flatnonzero(frame_turns == pt["turns"])
            nf = int(idx.size)
            eta = cross.results.eta[np.isin(cross.results.frame_index, idx)]
            rows.append({**{k: p.values[k] for k in keys}, "turns": pt["turns"],
                         "n_frames": nf,
                         "extension_nm": float(np.mean(ext.results.extension_nm[idx]))
                         if nf else None,
                         "catenation": float(np.mean(cat.results.catenation[idx]))
                         if nf else None,
                         "crossings_per_frame": eta.size / nf if nf else None,
                         "mean_abs_crossing_angle_deg":
                             float(np.degrees(np.mean(np.abs(eta)))) if eta.size else None,
                         "point": p.name})
    if write:
        cols = keys + ["turns", "n_frames", "extension_nm", "catenation", "crossings_per_frame",
                       "mean_abs_crossing_angle_deg", "point"]
        write_csv(os.path.join(sweep_dir, "trajectory_analysis.csv"), cols, rows)
    return rows
