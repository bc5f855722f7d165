"""Parameter sweeps: one scene, a grid over its flat keys, one run directory per point.

* :mod:`~dnabraid.sweep.spec`: the sweep spec (TOML or dict), its validation
  (:func:`load_spec`, :class:`SweepError`) and the points' names and directories;
* :mod:`~dnabraid.sweep.execute`: running the points locally
  (:func:`dnabraid.run.workers.run_jobs`) or on Dask, resuming, recording failures
  (:func:`run_sweep`);
* :mod:`~dnabraid.sweep.gather`: the rows of ``results.csv`` (:func:`gather`) and the
  text table (:func:`format_table`).

The handedness statistics of the rows live in :mod:`dnabraid.analysis.handedness`, the
figure in :func:`dnabraid.plots.sweep_plot`, the trajectory analysis in
:mod:`dnabraid.analysis.sweep_trajectories`; they are re-exported here.
"""

from ..analysis.handedness import asymmetry, handedness_across_seeds
from ..analysis.sweep_trajectories import analyse_sweep
from ..plots import sweep_plot
from .execute import FIGURE_FILE, SweepResult, is_finished, run_or_load, run_sweep
from .gather import RESULTS_FILE, STATUS_FILE, format_table, gather
from .spec import (
    SPEC_FILE,
    STATUS_COLUMNS,
    SweepError,
    SweepPoint,
    SweepSpec,
    load_spec,
    point_dir,
    point_name,
)

__all__ = [
    "FIGURE_FILE",
    "RESULTS_FILE",
    "SPEC_FILE",
    "STATUS_COLUMNS",
    "STATUS_FILE",
    "SweepError",
    "SweepPoint",
    "SweepResult",
    "SweepSpec",
    "analyse_sweep",
    "asymmetry",
    "format_table",
    "gather",
    "handedness_across_seeds",
    "is_finished",
    "load_spec",
    "point_dir",
    "point_name",
    "run_or_load",
    "run_sweep",
    "sweep_plot",
]
