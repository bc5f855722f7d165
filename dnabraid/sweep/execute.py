"""Running a sweep: every unfinished grid point in local processes or on a Dask cluster.

:func:`run_sweep` runs each point of a :class:`~dnabraid.sweep.spec.SweepSpec` by its
scene's ``run`` into ``<out>/<point name>``. Points run in local processes
(:func:`dnabraid.run.workers.run_jobs`: one per usable core, each pinned to one core with
one OpenMM thread, so a tweezer point runs its replicas one after the other in its
process; with one worker in this process) or, given a scheduler address or a
``dask.distributed.Client``, on a Dask cluster.

Sweeps are idempotent: a point whose ``summary.json`` exists is not run again, an
interrupted point resumes from its checkpoints, and a failed point is recorded with its
error in ``sweep_status.json`` while the others go on. The results are then gathered into
``results.csv`` (:func:`dnabraid.sweep.gather.gather`) and drawn in ``sweep.png``
(:func:`dnabraid.plots.sweep_plot`).

:func:`run_or_load` is the same idempotence for one scene outside a grid (workflows that
run a few named points).
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import logging
import os
import time
import traceback
from collections.abc import Callable
from typing import Any, TextIO

from .. import rundir, tomlio
from ..plots import sweep_plot
from ..run.workers import pin_to_core, run_jobs, usable_cores
from ..scenes import make_scene
from .gather import RESULTS_FILE, STATUS_FILE, gather
from .spec import SPEC_FILE, SweepPoint, SweepSpec, load_spec, point_dir

log = logging.getLogger(__name__)

__all__ = ["FIGURE_FILE", "SweepResult", "is_finished", "run_or_load", "run_sweep"]

#: The sweep's figure, in the sweep directory.
FIGURE_FILE = "sweep.png"

# the core a Dask worker process pinned itself to (None: not yet, or not in Dask)
_WORKER_CORE: int | None = None


# ---------------------------------------------------------------------------------------
# running one point (in a worker process)
# ---------------------------------------------------------------------------------------
def _dask_slot() -> int | None:
    """The integer name of the Dask worker this runs in (its core), else None."""
    try:
        from distributed import get_worker

        name = get_worker().name
    except Exception:  # not in a Dask worker
        return None
    return name if isinstance(name, int) else None


def _run_point(name: str, scene_toml: str, out_dir: str, platform: str = "CPU",
               dask: bool = False) -> dict:
    """Run one point; never raises: returns a status record (done or failed).

    The traceback of a failure goes to ``<out_dir>/error.txt``. In a Dask worker
    (``dask``) the process first pins itself to the core of its worker number.
    """
    t0 = time.perf_counter()
    if dask:
        global _WORKER_CORE
        if _WORKER_CORE is None:
            _WORKER_CORE = _dask_slot()
            if _WORKER_CORE is not None:
                pin_to_core(_WORKER_CORE)
    rec: dict[str, Any] = {"name": name, "out": out_dir, "status": "done", "error": None}
    try:
        data = tomlio.loads(scene_toml)
        s = make_scene(data.pop("scene"), data)
        s.run(out_dir, platform=platform, threads=1 if platform == "CPU" else None)
    except BaseException as exc:  # noqa: BLE001 - recorded, the sweep goes on
        if isinstance(exc, KeyboardInterrupt):
            raise
        rec["status"] = "failed"
        rec["error"] = {"type": type(exc).__name__, "message": str(exc)}
        try:
            os.makedirs(out_dir, exist_ok=True)
            with open(os.path.join(out_dir, "error.txt"), "w") as fh:
                fh.write(traceback.format_exc())
        except OSError:  # pragma: no cover
            pass
    rec["wall_time_s"] = time.perf_counter() - t0
    return rec


def _point_job(job: tuple, report) -> dict:
    """:func:`~dnabraid.run.workers.run_jobs` job: (name, scene TOML, out, platform)."""
    return _run_point(*job)


# ---------------------------------------------------------------------------------------
# the sweep
# ---------------------------------------------------------------------------------------
@dataclasses.dataclass
class SweepResult:
    """What a sweep did.

    Attributes
    ----------
    out : str
        Sweep directory.
    status : dict
        Point name -> record (``status`` done | failed | skipped-as-done, ``error`` with
        ``type`` and ``message``, ``wall_time_s``).
    rows : list of dict
        The ``results.csv`` rows.
    table : str
        Path of ``results.csv``.
    figure : str or None
        Path of ``sweep.png``.
    wall_time_s : float
    """

    out: str
    status: dict
    rows: list
    table: str
    figure: str | None
    wall_time_s: float

    @property
    def failed(self) -> dict:
        """The status records of the points that failed (name -> record)."""
        return {k: v for k, v in self.status.items() if v["status"] == "failed"}


def _write_json(path: str, obj) -> None:
    """Write ``obj`` as indented JSON to ``path``, atomically."""
    rundir.atomic_write_text(path, json.dumps(obj, indent=2, default=str))


def is_finished(spec: SweepSpec, p: SweepPoint) -> bool:
    """Whether point ``p`` has finished (its ``summary.json`` exists)."""
    return os.path.isfile(os.path.join(point_dir(spec, p), "summary.json"))


def run_sweep(spec: SweepSpec | str | os.PathLike | dict, *, out: str | None = None,
              workers: int | None = None, scheduler: str | Any = None,
              platform: str = "CPU", progress: Callable[[dict], None] | None = None,
              figure: bool = True) -> SweepResult:
    """Run every unfinished grid point of ``spec`` and gather the results.

    Parameters
    ----------
    spec : SweepSpec, path or dict
        See :func:`load_spec`. Every point is validated before anything runs.
    out : str, optional
        Sweep directory (overrides the spec's).
    workers : int, optional
        Local worker processes (default: usable cores, at most the number of points to run),
        each pinned to its own core; 1 runs the points in this process, pinned to one core
        meanwhile. Ignored with ``scheduler``.
    scheduler : str or dask.distributed.Client, optional
        Run on a Dask cluster: a scheduler address (``tcp://host:8786``) or a Client.
    platform : str
        OpenMM platform of every point.
    progress : callable(record), optional
        Called in this process after each point (also for points already finished); the
        CLI uses it for a progress bar. An exception it raises stops the sweep (points
        that are running in local processes are left to finish their current turn value;
        rerun to resume).
    figure : bool
        Write ``sweep.png``.

    Returns
    -------
    SweepResult
    """
    t0 = time.perf_counter()
    if not isinstance(spec, SweepSpec):
        spec = load_spec(spec, out=out)
    elif out:
        spec = dataclasses.replace(spec, out=out)
    os.makedirs(spec.out, exist_ok=True)
    rundir.atomic_write_text(os.path.join(spec.out, SPEC_FILE), spec.to_toml())
    status_path = os.path.join(spec.out, STATUS_FILE)
    status: dict = {}
    for p in spec.points:
        status[p.name] = {"name": p.name, "values": p.values, "out": point_dir(spec, p),
                          "status": "pending", "error": None}
    todo = []
    for p in spec.points:
        if is_finished(spec, p):
            status[p.name]["status"] = "done"
            status[p.name]["skipped"] = True
        else:
            todo.append(p)
    _write_json(status_path, {"spec": spec.to_toml(), "points": status})
    log.info("sweep %s: %d points, %d to run", spec.out, len(spec.points), len(todo))
    for p in spec.points:
        if status[p.name]["status"] == "done" and progress:
            progress(status[p.name])

    def done(rec):
        st = status[rec["name"]]
        st.update({k: rec[k] for k in ("status", "error", "wall_time_s")})
        st["skipped"] = False
        _write_json(status_path, {"spec": spec.to_toml(), "points": status})
        if rec["status"] == "failed":
            log.warning("sweep point %s failed: %s: %s", rec["name"], rec["error"]["type"],
                        rec["error"]["message"])
        if progress:
            progress(st)

    if todo:
        if scheduler is not None:
            _run_dask(spec, todo, scheduler, platform, done)
        else:
            _run_local(spec, todo, workers, platform, done)
    rows = gather(spec)
    fig = None
    if figure:
        try:
            fig = sweep_plot(spec, rows, os.path.join(spec.out, FIGURE_FILE))
        except Exception as exc:  # pragma: no cover - a figure never fails a sweep
            log.warning("sweep figure not written: %s", exc)
    return SweepResult(spec.out, status, rows, os.path.join(spec.out, RESULTS_FILE), fig,
                       time.perf_counter() - t0)


def _run_local(spec, todo, workers, platform, done) -> None:
    """Run the points ``todo`` in ``workers`` local processes (default: usable cores)."""
    n = workers or len(usable_cores())
    n = max(1, min(int(n), len(todo)))
    jobs = [(p.name, p.scene_toml, point_dir(spec, p), platform) for p in todo]

    def on_done(i, rec):
        if isinstance(rec, BaseException):  # the worker process died (killed, out of memory)
            rec = {"name": todo[i].name, "status": "failed", "wall_time_s": None,
                   "error": {"type": type(rec).__name__, "message": str(rec)}}
        done(rec)

    if n > 1:
        run_jobs(_point_job, jobs, n, on_done=on_done, errors="return")
        return
    # one worker: in this process, pinned to one core meanwhile (one OpenMM thread)
    try:
        before = os.sched_getaffinity(0)
    except AttributeError:  # pragma: no cover - not on Linux
        before = None
    pin_to_core(0)
    try:
        run_jobs(_point_job, jobs, 1, on_done=on_done, errors="return")
    finally:
        if before is not None:
            os.sched_setaffinity(0, before)


def _run_dask(spec, todo, scheduler, platform, done) -> None:
    """Run the points ``todo`` on a Dask cluster (scheduler address or Client)."""
    try:
        from distributed import Client, as_completed
    except ImportError as exc:
        raise ImportError("running a sweep on a Dask cluster needs dask.distributed: "
                          "pip install 'dnabraid[distributed]'") from exc
    own = not isinstance(scheduler, Client)
    try:
        client = Client(scheduler) if own else scheduler
    except OSError as exc:
        raise ConnectionError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from exc
    try:
        futs = {}
        for p in todo:
            f = client.submit(_run_point, p.name, p.scene_toml,
                              os.path.abspath(point_dir(spec, p)), platform, True,
                              key=f"dnabraid-{p.name}-{hashlib.sha1(p.scene_toml.encode()).hexdigest()[:8]}",
                              pure=False)
            futs[f] = p
        for f in as_completed(list(futs)):
            p = futs[f]
            try:
                rec = f.result()
            except Exception as exc:  # the task was lost (worker died, ...)
                rec = {"name": p.name, "status": "failed", "wall_time_s": None,
                       "error": {"type": type(exc).__name__, "message": str(exc)}}
            done(rec)
    finally:
        if own:
            client.close()


# ---------------------------------------------------------------------------------------
# one scene outside a grid
# ---------------------------------------------------------------------------------------
def run_or_load(scene: str, keys: dict, out_dir: str, *,
                report: TextIO | None = None) -> dict:
    """Run a scene into ``out_dir``, or load its summary if it finished there already.

    A finished run is reused when its ``summary.json`` holds the same scene (keys added to
    the scene since it ran take their defaults); otherwise the scene runs (resuming from
    its checkpoints, if any).

    Parameters
    ----------
    scene : str
        A registered scene name.
    keys : dict
        The scene's keys (as for :func:`dnabraid.scenes.make_scene`).
    out_dir : str
        The run directory.
    report : file-like, optional
        Where a fresh run's report goes, under the heading ``## <out_dir name> (<wall> s)``.

    Returns
    -------
    dict
        The run's summary, with ``"_out"`` set to ``out_dir``.
    """
    path = os.path.join(out_dir, "summary.json")
    want = make_scene(scene, keys)
    if os.path.exists(path):
        with open(path) as fh:
            summ = json.load(fh)
        have = {**make_scene(scene).to_dict(), **summ["scene"]}
        if have == want.to_dict():
            summ["_out"] = out_dir
            return summ
        log.info("%s: the finished run is of another scene; running again", out_dir)
    t0 = time.perf_counter()
    summ = want.run(out_dir)
    if report is not None:
        buf = io.StringIO()
        want.report(summ, out_dir, buf)
        report.write(f"## {os.path.basename(os.path.normpath(out_dir))} "
                     f"({time.perf_counter() - t0:.0f} s)\n{buf.getvalue()}\n")
        report.flush()
    summ["_out"] = out_dir
    return summ
