"""The run directory: preparation, atomic writes, and the ``summary.json`` schema.

Every file is written to a temporary name and renamed, so a crash never leaves a
half-written result. A directory holding a run of another scene is never overwritten.
"""

from __future__ import annotations

import dataclasses
import json
import os
import platform as _platform
import sys

import numpy as np

from . import tomlio
from .errors import UserError

__all__ = ["RunDirError", "Summary", "atomic_write_bytes", "atomic_write_text",
           "prepare_out_dir", "versions", "write_summary", "write_topology"]


class RunDirError(UserError):
    """The output directory cannot take this run (it holds something else)."""


def atomic_write_text(path: str, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename."""
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)


def atomic_write_bytes(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    tmp = path + ".tmp"
    with open(tmp, "wb") as fh:
        fh.write(data)
    os.replace(tmp, path)


def prepare_out_dir(scene, out: str) -> bool:
    """Create ``out`` for ``scene``; return True if it resumes an earlier run of the same scene.

    ``scene`` is any scene object with ``to_toml()`` and ``to_dict()``. The resolved
    scene is written to ``out/scene.toml``.

    Raises
    ------
    RunDirError
        If ``out`` is not empty and holds no ``scene.toml`` or a different scene.
    """
    path = os.path.join(out, "scene.toml")
    new = tomlio.loads(scene.to_toml())
    if os.path.isdir(out) and os.listdir(out):
        if not os.path.exists(path):
            raise RunDirError(f"output directory {out!r} exists, is not empty and holds no "
                              "scene.toml: choose another --out")
        old = tomlio.load(path)
        if old != new:
            diff = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
            raise RunDirError(f"output directory {out!r} holds a run of a different scene "
                              f"(differs in: {', '.join(diff)}); choose another --out")
        return True
    os.makedirs(out, exist_ok=True)
    atomic_write_text(path, scene.to_toml())
    return False


def versions() -> dict:
    """Versions of dnabraid and what it runs on (for a self-describing result)."""
    import openmm
    import scipy

    from . import __version__

    return {"dnabraid": __version__, "openmm": openmm.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "python": sys.version.split()[0],
            "machine": _platform.platform()}


def write_topology(path: str, topology, positions_nm) -> None:
    """PDB topology (MDAnalysis reads it with the DCD)."""
    from openmm import app
    from openmm import unit as u

    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        app.PDBFile.writeFile(topology, np.asarray(positions_nm) * u.nanometer, fh)
    os.replace(tmp, path)


@dataclasses.dataclass
class Summary:
    """The schema of a thermal run's ``summary.json`` (all fields are written).

    Attributes
    ----------
    scene : dict
        The resolved scene (as in ``scene.toml``).
    wall_time_s : float
        Wall time of this invocation (a resumed run counts only its own part).
    platform : str
        OpenMM platform.
    time_step_ps : float
        Brownian time step.
    time_step_reason : str
        Which term set the time step and how (Euler-Maruyama stability bound).
    relaxation_rates_per_ns : dict
        Largest relaxation rate of each force term (1/ns).
    total_steps : int
        Steps of the whole schedule.
    steps_per_second, ns_per_bead_per_step : float or None
        Speed; None for a resumed run.
    n_particles : int
    forces : list of str
        The force terms present in the System.
    effective_diameter_nm : float
    bending_kappa_kT : float
    units : dict
        Unit and meaning of every observable.
    notes : list of str
    versions : dict
    points : list of dict
        Per turn value: ``turns`` and, per observable, ``{"mean", "sem", ...}``.
    seed : int
        The scene's seed and ``integrator_seed``, the seed OpenMM was given.
    integrator_seed : int
    columns : dict
        Per observable column: ``unit``, ``meaning``, ``reported`` (a result: in the table,
        the sweep rows and the plots) and ``verdict`` (decides convergence).
    """

    scene: dict
    wall_time_s: float
    platform: str
    time_step_ps: float
    time_step_reason: str
    relaxation_rates_per_ns: dict
    total_steps: int
    steps_per_second: float | None
    ns_per_bead_per_step: float | None
    n_particles: int
    forces: list
    effective_diameter_nm: float
    bending_kappa_kT: float
    units: dict
    notes: list
    versions: dict
    points: list
    seed: int = 0
    integrator_seed: int = 0
    columns: dict = dataclasses.field(default_factory=dict)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def write_summary(path: str, summary) -> None:
    """Write a :class:`Summary` (or a plain dict, e.g. the knot scene's) as JSON."""
    d = summary.to_dict() if hasattr(summary, "to_dict") else summary
    atomic_write_text(path, json.dumps(d, indent=2, default=float) + "\n")
