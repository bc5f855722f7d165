"""Reporters: observables and frames streamed to disk while a point runs.

Each point of a schedule writes, as it runs, into its own directory
``points/<index>_turns<value>/``:

* ``samples.csv``: step, time and every per-sample observable (units in the header);
* ``frames.csv``: frame number, step, time and every per-frame observable;
* ``trajectory.dcd``: one frame per ``frame_interval`` (OpenMM's ``DCDFile``).

Nothing is held in memory for the whole run. When a point finishes, the runner writes the
engine checkpoint and ``done.json``; a point without ``done.json`` is rerun from the
previous checkpoint. :func:`combine` writes the run directory's ``observables.csv``,
``frames.csv`` and ``trajectory.dcd`` from the finished points, reading them back from
disk. Numbers are written with ``repr`` precision, so statistics computed from the files
are the same whether or not the run was interrupted.
"""

from __future__ import annotations

import csv
import math
import os
import warnings

import numpy as np

__all__ = ["PointWriter", "combine", "read_csv", "read_point", "MIN_N_EFF", "mean_sem_entry"]

#: An autocorrelation-corrected SEM is trusted when the run holds this many correlation times.
MIN_N_EFF = 20


def _num(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    return repr(float(v))


def _header(cols: dict) -> list[str]:
    return list(cols)


class PointWriter:
    """Stream one point's samples, frames and trajectory (a context manager).

    Parameters
    ----------
    path : str
        The point's directory (created).
    topology : openmm.app.Topology
    dt_ps : float
    frame_interval : int
    sample_columns, frame_columns : dict name -> (unit, meaning)
    turns : float
    """

    def __init__(self, path, topology, dt_ps, frame_interval, sample_columns, frame_columns,
                 turns):
        self.path = path
        self.topology = topology
        self.dt_ps = float(dt_ps)
        self.frame_interval = int(frame_interval)
        self.sc = list(sample_columns)
        self.fc = list(frame_columns)
        self.turns = float(turns)
        self._files = []

    def __enter__(self):
        from openmm import app

        os.makedirs(self.path, exist_ok=True)
        self._s = open(os.path.join(self.path, "samples.csv"), "w", newline="")  # noqa: SIM115
        self._f = open(os.path.join(self.path, "frames.csv"), "w", newline="")  # noqa: SIM115
        self._d = open(os.path.join(self.path, "trajectory.dcd"), "wb")  # noqa: SIM115
        self._files = [self._s, self._f, self._d]
        self.sw = csv.writer(self._s)
        self.fw = csv.writer(self._f)
        self.sw.writerow(["turns", "step", "time_ns"] + self.sc)
        self.fw.writerow(["turns", "frame", "step", "time_ns"] + self.fc)
        self.dcd = app.DCDFile(self._d, self.topology, self.dt_ps, 0,
                               max(1, self.frame_interval))
        self.n_frames = 0
        return self

    def sample(self, step: int, values: dict) -> None:
        t = step * self.dt_ps * 1e-3
        self.sw.writerow([repr(self.turns), int(step), repr(t)]
                         + [_num(values.get(c)) for c in self.sc])

    def frame(self, step: int, pos_nm, values: dict) -> None:
        from openmm import unit as u

        t = step * self.dt_ps * 1e-3
        self.fw.writerow([repr(self.turns), self.n_frames, int(step), repr(t)]
                         + [_num(values.get(c)) for c in self.fc])
        self.dcd.writeModel(np.asarray(pos_nm, float) * u.nanometer)
        self.n_frames += 1

    def __exit__(self, *exc):
        for fh in self._files:
            fh.close()
        return False


def read_csv(path) -> dict:
    """A run's CSV file as column -> float ndarray (empty cells NaN; text columns such as
    ``point`` are left out)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    head, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(head):
        try:
            out[name] = np.array([float(r[j]) if r[j] != "" else np.nan for r in body])
        except ValueError:  # a text column
            pass
    return out


def read_point(path: str) -> tuple[dict, dict]:
    """The samples and frames of a finished point: two dicts column -> ndarray."""
    return (read_csv(os.path.join(path, "samples.csv")),
            read_csv(os.path.join(path, "frames.csv")))


def mean_sem_entry(x) -> dict:
    """Mean and autocorrelation-corrected SEM of one series (the single-run diagnostic)."""
    from ..analysis.stats import mean_sem

    x = np.asarray(x, float)
    if x.size == 0 or not np.all(np.isfinite(x)):
        return {"mean": None, "sem": None}
    r = mean_sem(x)
    return {"mean": float(r["mean"]), "sem": float(r["sem"]),
            "tau_int_samples": float(r["tau_int"]), "n_eff": float(r["n_eff"]),
            "sem_reliable": bool(r["n_eff"] >= MIN_N_EFF)}


def combine(out: str, point_dirs: list[str], topology, dt_ps: float, frame_interval: int,
            sample_columns: dict, frame_columns: dict) -> None:
    """Write ``observables.csv``, ``frames.csv`` and ``trajectory.dcd`` of the whole run.

    ``observables.csv`` has one row per sample (per-frame observables filled in at the
    samples that coincide with a frame); ``frames.csv`` says which turn value and step
    each frame of ``trajectory.dcd`` belongs to.
    """
    from openmm import app
    from openmm import unit as u

    sc, fc = list(sample_columns), list(frame_columns)
    tmp_obs = os.path.join(out, "observables.csv.tmp")
    tmp_fr = os.path.join(out, "frames.csv.tmp")
    tmp_dcd = os.path.join(out, "trajectory.dcd.tmp")
    frame_no = 0
    with open(tmp_obs, "w", newline="") as fo, open(tmp_fr, "w", newline="") as ff, \
            open(tmp_dcd, "wb") as fd:
        wo, wf = csv.writer(fo), csv.writer(ff)
        wo.writerow(["turns", "step", "time_ns"] + sc + fc)
        wf.writerow(["frame", "turns", "step", "time_ns", "point"] + fc)
        dcd = app.DCDFile(fd, topology, dt_ps, 0, max(1, int(frame_interval)))
        for pdir in point_dirs:
            s, f = read_point(pdir)
            at = {int(st): i for i, st in enumerate(f["step"])}
            for i in range(len(s["step"])):
                st = int(s["step"][i])
                j = at.get(st)
                wo.writerow([repr(float(s["turns"][i])), st, repr(float(s["time_ns"][i]))]
                            + [_num(s[c][i]) for c in sc]
                            + [_num(f[c][j]) if j is not None else "" for c in fc])
            for j in range(len(f["step"])):
                wf.writerow([frame_no, repr(float(f["turns"][j])), int(f["step"][j]),
                             repr(float(f["time_ns"][j])), os.path.basename(pdir)]
                            + [_num(f[c][j]) for c in fc])
                frame_no += 1
            if len(f["step"]):
                for xyz in _dcd_frames(os.path.join(pdir, "trajectory.dcd")):
                    dcd.writeModel(xyz * u.nanometer)
    os.replace(tmp_obs, os.path.join(out, "observables.csv"))
    os.replace(tmp_fr, os.path.join(out, "frames.csv"))
    os.replace(tmp_dcd, os.path.join(out, "trajectory.dcd"))


def _dcd_frames(path):
    """Yield the frames (nm) of a DCD file one at a time (MDAnalysis' reader)."""
    import logging

    # the library stays quiet: MDAnalysis announces a missing netCDF4 (AMBER writer, unused
    # here) when imported, and its DCDReader warns on every read that its timestep copying
    # will change in 3.0 (MDAnalysis issue 3889; the frames are copied here anyway). The
    # filter goes in after the import, which installs MDAnalysis' own filters.
    logging.getLogger("MDAnalysis").setLevel(logging.ERROR)
    from MDAnalysis.coordinates.DCD import DCDReader

    warnings.filterwarnings("ignore", message="DCDReader currently makes independent",
                            category=DeprecationWarning)

    r = DCDReader(path)
    try:
        for ts in r:
            yield ts.positions.astype(float) / 10.0  # MDAnalysis works in Angstrom
    finally:
        r.close()


