"""Parameter sweeps: one scene, a grid over its flat keys, one run directory per point.

A sweep spec is a TOML file (or a dict of the same shape)::

    scene = "braid"                 # a registered scene name or a path to a scene TOML
    out = "runs/salt_sweep"         # optional (default runs/<spec file stem>)
    [fixed]                         # optional: keys set on every point
    steps = 20000
    [grid]                          # the grid: the Cartesian product of these lists
    salt_mM = [10, 150, 1000]
    force_pN = [1, 2]

Any scene of :data:`dnabraid.scenes.SCENES` can be swept. Every grid point is validated
with :func:`dnabraid.scenes.make_scene` before anything runs (a bad key or value fails the
whole sweep with the scene's message), then run by its scene's ``run`` into
``<out>/<point name>`` where the name is built from the point's values
(``salt_mM=10__force_pN=1``). Points run in local processes
(:class:`concurrent.futures.ProcessPoolExecutor`, one per usable core, each pinned to one
core with one OpenMM thread, so a tweezer point runs its replicas one after the other in
its process) or, given a scheduler address or a ``dask.distributed.Client``, on a Dask
cluster.

Sweeps are idempotent: a point whose ``summary.json`` exists is not run again, an
interrupted point resumes from its checkpoints, and a failed point is recorded with its
error in ``sweep_status.json`` while the others go on. The results are gathered into
``results.csv``: the grid keys, then the result columns the scene declares
(``row_columns``: for the tweezer scenes one row per turn value with extension, torque and
catenation; for the knot scene one row per point with loop radius, braid length and wave
number beside the theory), then ``status, error, point``; and one figure, ``sweep.png``.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import itertools
import json
import logging
import math
import os
import time
import traceback
import warnings
from collections.abc import Callable
from typing import Any

from . import rundir, tomlio
from .scenes import SCENES, Scene, SceneError, make_scene, scene_class

log = logging.getLogger(__name__)

__all__ = [
    "SweepError",
    "SweepSpec",
    "SweepPoint",
    "SweepResult",
    "load_spec",
    "run_sweep",
    "gather",
    "format_table",
    "sweep_plot",
    "asymmetry",
    "handedness_across_seeds",
    "analyse_sweep",
    "usable_cores",
]

STATUS_FILE = "sweep_status.json"
RESULTS_FILE = "results.csv"
FIGURE_FILE = "sweep.png"
SPEC_FILE = "sweep.toml"
_SPEC_KEYS = {"scene", "out", "fixed", "grid"}
#: Columns every results.csv row ends with (after the grid keys and the scene's columns).
STATUS_COLUMNS = ("status", "error", "point")


class SweepError(SceneError):
    """A sweep spec is invalid (unknown key, missing file, empty grid, bad grid point)."""


# ---------------------------------------------------------------------------------------
# spec
# ---------------------------------------------------------------------------------------
def _fmt_value(v) -> str:
    """A grid value as it appears in a point's directory name."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "_".join(_fmt_value(x) for x in v)
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def point_name(values: dict) -> str:
    """Readable, deterministic directory name of a grid point: ``key=value__key=value``.

    Names longer than 120 characters are cut and given a hash of the full name.
    """
    if not values:
        return "point"
    name = "__".join(f"{k}={_fmt_value(v)}" for k, v in values.items())
    name = name.replace(os.sep, "-").replace(" ", "")
    if len(name) > 120:
        digest = hashlib.sha1(name.encode()).hexdigest()[:10]
        name = name[:100] + "__" + digest
    return name


@dataclasses.dataclass(frozen=True)
class SweepPoint:
    """One grid point: its values, the flat overrides it adds, its resolved scene."""

    name: str
    values: dict
    scene: Scene

    @property
    def scene_toml(self) -> str:
        return self.scene.to_toml()


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: base scene, fixed keys, grid (key -> tuple of values), out.

    Build with :func:`load_spec`; ``points`` holds every grid point, already validated.
    """

    scene: str
    fixed: dict
    grid: dict
    out: str
    points: tuple

    @property
    def row_columns(self) -> list[str]:
        """The result columns of this sweep's scene that are not grid keys."""
        cols = type(self.points[0].scene).row_columns if self.points else ()
        return [c for c in cols if c not in self.grid]

    @property
    def columns(self) -> list[str]:
        """The header of ``results.csv``: grid keys, the scene's columns, status columns."""
        return list(self.grid) + self.row_columns + list(STATUS_COLUMNS)

    def to_toml(self) -> str:
        v = tomlio.value
        lines = [f"scene = {v(self.scene)}", f"out = {v(self.out)}", "", "[fixed]"]
        lines += [f"{k} = {v(x)}" for k, x in self.fixed.items()]
        lines += ["", "[grid]"]
        lines += [f"{k} = {v(list(x))}" for k, x in self.grid.items()]
        return "\n".join(lines) + "\n"


def _base_class(base: str) -> type[Scene]:
    """The scene class of a sweep's base (a registered name or a scene TOML file)."""
    if base in SCENES:
        return SCENES[base]
    try:
        name = tomlio.load(base).get("scene", "braid")
    except tomlio.TOMLDecodeError as exc:
        raise SweepError(f"sweep scene file {base!r} is not valid TOML: {exc}") from exc
    try:
        return scene_class(name)
    except SceneError as exc:
        raise SweepError(f"sweep scene file {base!r}: {exc}") from exc


def load_spec(spec: str | os.PathLike | dict, *, out: str | None = None) -> SweepSpec:
    """Read and validate a sweep spec; build and validate every grid point's scene.

    Parameters
    ----------
    spec : path or dict
        A TOML file, or a dict with keys ``scene``, ``grid`` and optionally ``fixed``,
        ``out``. A relative scene path in a file is taken relative to the file.
    out : str, optional
        Sweep directory; overrides the spec's ``out``. Default: ``runs/<spec stem>``
        (``runs/sweep`` for a dict).

    Raises
    ------
    SweepError
        Unknown spec key, missing or empty grid, a grid key also in ``fixed``, repeated
        grid values, a list-valued key (e.g. ``turns``) given plain values in the grid, or
        a grid point whose scene does not validate (the SceneError message is included).
    FileNotFoundError
        The spec file or the scene file does not exist.
    """
    if isinstance(spec, dict):
        data = dict(spec)
        base_dir, stem = os.getcwd(), "sweep"
    else:
        path = os.fspath(spec)
        data = tomlio.load_file(path, "sweep spec", SweepError)
        base_dir = os.path.dirname(os.path.abspath(path))
        stem = os.path.splitext(os.path.basename(path))[0]
    unknown = sorted(set(data) - _SPEC_KEYS)
    if unknown:
        raise SweepError(f"unknown sweep spec key(s) {', '.join(unknown)}; allowed: "
                         "scene, out, [fixed], [grid] (scene keys go under [fixed] or [grid])")
    base = data.get("scene", "braid")
    if not isinstance(base, str):
        raise SweepError(f"scene: expected a registered scene name or a path, got {base!r}")
    if base not in SCENES:
        cand = base if os.path.isabs(base) else os.path.join(base_dir, base)
        if not os.path.isfile(cand):
            raise FileNotFoundError(f"sweep scene {base!r} is neither a built-in scene ("
                                    + ", ".join(SCENES) + f") nor a file ({cand} "
                                    "does not exist)")
        base = cand
    infos = _base_class(base).keys()
    fixed = data.get("fixed", {}) or {}
    grid = data.get("grid")
    if not isinstance(fixed, dict):
        raise SweepError(f"[fixed] must be a table of scene keys, got {fixed!r}")
    if not isinstance(grid, dict) or not grid:
        raise SweepError("the sweep has an empty grid: give a [grid] table with at least one "
                         "scene key and a list of values, e.g. salt_mM = [10, 150]")
    norm_grid = {}
    for k, vals in grid.items():
        if not isinstance(vals, (list, tuple)) or len(vals) == 0:
            raise SweepError(f"grid key {k!r}: expected a non-empty list of values, got {vals!r}")
        info = infos.get(k)
        if (info is not None and info.kind == "floats"
                and not all(isinstance(v, (list, tuple)) for v in vals)):
            unit = f" ({info.unit})" if info.unit else ""
            raise SweepError(f"grid key {k!r}: each value is a list, since {k} takes a list"
                             f"{unit}; e.g. {k} = [[0, 1, 2], [0, -1, -2]]")
        names = [_fmt_value(v) for v in vals]
        if len(set(names)) != len(names):
            raise SweepError(f"grid key {k!r}: repeated values {list(vals)!r}")
        norm_grid[k] = tuple(tuple(v) if isinstance(v, list) else v for v in vals)
    both = sorted(set(fixed) & set(norm_grid))
    if both:
        raise SweepError(f"key(s) {', '.join(both)} are both in [fixed] and [grid]")
    out_dir = out or data.get("out") or os.path.join("runs", stem)
    keys = list(norm_grid)
    points = []
    for combo in itertools.product(*(norm_grid[k] for k in keys)):
        values = dict(zip(keys, combo))
        name = point_name(values)
        overrides = {**fixed, **{k: (list(v) if isinstance(v, tuple) else v)
                                 for k, v in values.items()}}
        try:
            s = make_scene(base, overrides)
        except SceneError as exc:
            raise SweepError(f"grid point {name}: {exc}") from exc
        points.append(SweepPoint(name, values, s))
    return SweepSpec(scene=os.fspath(base), fixed=dict(fixed), grid=norm_grid,
                     out=os.fspath(out_dir), points=tuple(points))


# ---------------------------------------------------------------------------------------
# running one point (in a worker process)
# ---------------------------------------------------------------------------------------
_WORKER_CORE: int | None = None


def usable_cores() -> list[int]:
    """CPU cores this process may run on."""
    try:
        return sorted(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return list(range(os.cpu_count() or 1))


def _pin(slot: int | None) -> None:
    """Pin this process to core ``slot`` (modulo the usable cores); cf. engine.pin_to_one_core."""
    if slot is None:
        return
    try:
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[slot % len(cores)]})
    except (AttributeError, OSError):  # pragma: no cover - not on Linux
        pass


def _init_pool_worker(counter) -> None:
    """ProcessPoolExecutor initializer: give each worker its own core."""
    global _WORKER_CORE
    with counter.get_lock():
        _WORKER_CORE = counter.value
        counter.value += 1
    _pin(_WORKER_CORE)


def _dask_slot() -> int | None:
    try:
        from distributed import get_worker

        name = get_worker().name
    except Exception:  # not in a Dask worker
        return None
    return name if isinstance(name, int) else None


def _run_point(name: str, scene_toml: str, out_dir: str, platform: str = "CPU",
               dask: bool = False) -> dict:
    """Run one point; never raises: returns a status record (done or failed)."""
    t0 = time.perf_counter()
    if dask:
        global _WORKER_CORE
        if _WORKER_CORE is None:
            _WORKER_CORE = _dask_slot()
            _pin(_WORKER_CORE)
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
        return {k: v for k, v in self.status.items() if v["status"] == "failed"}


def _write_json(path: str, obj) -> None:
    rundir.atomic_write_text(path, json.dumps(obj, indent=2, default=str))


def _point_dir(spec: SweepSpec, p: SweepPoint) -> str:
    return os.path.join(spec.out, p.name)


def is_finished(spec: SweepSpec, p: SweepPoint) -> bool:
    return os.path.isfile(os.path.join(_point_dir(spec, p), "summary.json"))


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
        Local worker processes (default: usable cores, at most the number of points to run).
        Ignored with ``scheduler``.
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
        status[p.name] = {"name": p.name, "values": p.values, "out": _point_dir(spec, p),
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
    import concurrent.futures as cf
    import multiprocessing as mp

    n = workers or len(usable_cores())
    n = max(1, min(int(n), len(todo)))
    ctx = mp.get_context("spawn")  # no fork after OpenMM has started threads
    counter = ctx.Value("i", 0)
    ex = cf.ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_init_pool_worker,
                                initargs=(counter,))
    futs = {}
    try:
        for p in todo:
            f = ex.submit(_run_point, p.name, p.scene_toml, _point_dir(spec, p), platform)
            futs[f] = p
        for f in cf.as_completed(futs):
            p = futs[f]
            try:
                rec = f.result()
            except Exception as exc:  # the worker process died (e.g. killed, out of memory)
                rec = {"name": p.name, "status": "failed", "wall_time_s": None,
                       "error": {"type": type(exc).__name__, "message": str(exc)}}
            done(rec)
    except BaseException:
        for f in futs:
            f.cancel()
        ex.shutdown(wait=False, cancel_futures=True)
        raise
    ex.shutdown(wait=True)


def _run_dask(spec, todo, scheduler, platform, done) -> None:
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
                              os.path.abspath(_point_dir(spec, p)), platform, True,
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
# gathering
# ---------------------------------------------------------------------------------------
def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, (list, tuple)):
        return " ".join(_fmt_value(x) for x in v)
    return v


def _write_csv(path: str, cols: list[str], rows: list[dict]) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            w.writerow([_cell(r.get(c)) for c in cols])
    os.replace(tmp, path)


def gather(spec: SweepSpec) -> list[dict]:
    """Collect every point's summary into rows and write ``results.csv``.

    The rows of a finished point are its scene's :meth:`~dnabraid.scenes.base.Scene.rows`
    of its ``summary.json``, in grid order; a point without a summary gets one row with
    its status (``failed`` with the error, or ``pending``) and empty result columns.
    Columns (:attr:`SweepSpec.columns`): the grid keys (units are in the key names), the
    scene's ``row_columns`` (for the tweezer scenes ``turns, extension_nm,
    extension_sem_nm, torque_pN_nm, torque_sem_pN_nm, catenation, catenation_sem,
    n_samples``, one row per turn value; for the knot scene the measured and theoretical
    loop radius, braid length and wave number, one row per point), then ``status, error,
    point``. A scene column that is also a grid key (e.g. ``turns``) takes the row's value.
    """
    status_path = os.path.join(spec.out, STATUS_FILE)
    status = {}
    if os.path.isfile(status_path):
        with open(status_path) as fh:
            status = json.load(fh).get("points", {})
    keys = list(spec.grid)
    value_cols = spec.row_columns
    rows = []
    for p in spec.points:
        base = {k: p.values[k] for k in keys}
        summ = os.path.join(_point_dir(spec, p), "summary.json")
        if os.path.isfile(summ):
            with open(summ) as fh:
                summary = json.load(fh)
            for r in p.scene.rows(summary):
                rows.append({**base, **r, "status": "done", "error": "", "point": p.name})
        else:
            st = status.get(p.name, {})
            err = st.get("error") or {}
            row = dict(base)
            row.update({c: None for c in value_cols})
            row.update(status=st.get("status", "pending"),
                       error=f"{err['type']}: {err['message']}" if err else "", point=p.name)
            rows.append(row)
    _write_csv(os.path.join(spec.out, RESULTS_FILE), spec.columns, rows)
    return rows


def _sem_of(col: str, cols: list[str]) -> str | None:
    """The standard-error column that goes with ``col`` (``extension_nm`` ->
    ``extension_sem_nm``, ``catenation`` -> ``catenation_sem``), if the table has one."""
    for c in cols:
        if c != col and "_sem" in c and c.replace("_sem", "", 1) == col:
            return c
    return None


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _fmt_cell(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return _fmt_value(v)


def _fmt_mean_sem(m, s) -> str:
    if m is None or (isinstance(m, float) and math.isnan(m)):
        return "-"
    if s is None or not math.isfinite(s):
        return f"{m:.4g}"
    d = 3 if s <= 0 else max(0, min(3, 1 - math.floor(math.log10(s))))
    return f"{m:.{d}f} +- {s:.{d}f}"


def format_table(rows: list[dict], keys: list[str]) -> str:
    """Fixed-width text table of gathered rows (the CLI prints it).

    Columns: the grid keys, then the scene's result columns as they appear in the rows,
    each mean with its standard error (``x +- sem``) where the scene gives one, then the
    status. When the rows hold extension at +n and -n turns, the handedness asymmetry
    z(+n) - z(-n) of each point follows (:func:`asymmetry`).
    """
    if not rows:
        return "(no points)"
    skip = set(keys) | set(STATUS_COLUMNS)
    cols = [c for c in rows[0] if c not in skip]
    sems = {c: _sem_of(c, cols) for c in cols}
    shown = [c for c in cols if c not in set(sems.values())]
    head = [*keys, *shown, "status"]
    table = []
    for r in rows:
        cells = [_fmt_value(r[k]) for k in keys]
        for c in shown:
            s = sems[c]
            cells.append(_fmt_mean_sem(r.get(c), r.get(s)) if s else _fmt_cell(r.get(c)))
        cells.append(r["status"] + (f" ({r['error']})" if r["error"] else ""))
        table.append(cells)
    widths = [max(8, len(h), *(len(t[i]) for t in table[:200] if i < len(head) - 1))
              for i, h in enumerate(head)]
    lines = [" ".join(h.rjust(w) for h, w in zip(head, widths))]
    lines += [" ".join(c.rjust(w) for c, w in zip(t, widths)) for t in table]
    asym = asymmetry(rows, keys)
    if asym:
        lines += ["", "handedness asymmetry z(+n) - z(-n) at the largest n with both signs:"]
        lines += [f"  {a['point']:<40} n = {a['n']:g}: "
                  f"{_fmt_mean_sem(a['asymmetry_nm'], a['asymmetry_sem_nm'])} nm" for a in asym]
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------
# handedness analysis (tweezer rows: turns and extension)
# ---------------------------------------------------------------------------------------
def _tweezer_rows(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r.get("status") == "done"
            and r.get("turns") is not None and r.get("extension_nm") is not None]


def asymmetry(rows: list[dict], keys: list[str]) -> list[dict]:
    """Handedness asymmetry z(+n) - z(-n) per grid point, for the largest n with both signs.

    Returns one dict per point with ``n``, ``asymmetry_nm``, ``asymmetry_sem_nm`` and the
    grid values; points without a +n/-n pair (or rows without ``turns`` and
    ``extension_nm``, e.g. of the knot scene) are left out.
    """
    by_point: dict = {}
    for r in _tweezer_rows(rows):
        by_point.setdefault(r["point"], []).append(r)
    out = []
    for name, rs in by_point.items():
        z = {r["turns"]: (r["extension_nm"], r.get("extension_sem_nm")) for r in rs}
        pairs = [n for n in z if n > 0 and -n in z]
        if not pairs:
            continue
        n = max(pairs)
        (zp, sp), (zm, sm) = z[n], z[-n]
        out.append({**{k: rs[0][k] for k in keys}, "point": name, "n": n,
                    "asymmetry_nm": zp - zm, "asymmetry_sem_nm": math.hypot(sp or 0, sm or 0)})
    return out


def handedness_across_seeds(rows: list[dict], turns: float, *, group: str = "alpha",
                            seed: str = "seed") -> list[dict]:
    """Handedness of thermal braids with its error from independent seeds.

    Within one run the autocorrelation-corrected SEM of the trap torque is ~1.6x too small
    (a slow component escapes the window), so the error of the handedness comes from a
    sweep over ``seed``: per seed the torque sum Gamma(+n) + Gamma(-n) and the extension
    difference z(+n) - z(-n), then their mean and standard error across seeds. Without a
    chiral term both vanish by mirror symmetry; alpha > 0 favours right-handed braids
    (n > 0), so less torque holds +n (zero-temperature continuum: Gamma(+n) + Gamma(-n)
    ~ -2 r alpha, :func:`dnabraid.crosscheck.compare_tweezer`).

    Parameters
    ----------
    rows : list of dict
        Gathered sweep rows (:func:`gather`) of a tweezer scene whose grid holds ``seed``.
    turns : float
        n (> 0); each seed must have run both +n and -n.
    group : str
        The grid key to group by (default ``alpha``).
    seed : str
        The grid key of the seeds.

    Returns
    -------
    list of dict
        One per value of ``group`` (ascending): ``group``, ``seeds`` (count),
        ``torque_sum_pN_nm``, ``torque_sum_se_pN_nm``, ``t`` (mean / SE),
        ``delta_z_nm``, ``delta_z_se_nm``, ``torque_sums`` (per seed). Means and errors are
        None with fewer than two seeds.
    """
    n = abs(float(turns))
    by: dict = {}
    for r in _tweezer_rows(rows):
        if r.get("torque_pN_nm") is None:
            continue
        key = (float(r[group]), r[seed])
        by.setdefault(key, {})[float(r["turns"])] = (float(r["torque_pN_nm"]),
                                                     float(r["extension_nm"]))
    out = []
    for g in sorted({k[0] for k in by}):
        sums, dz = [], []
        for (gg, _s), pts in sorted(by.items(), key=lambda kv: (kv[0][0], str(kv[0][1]))):
            if gg == g and n in pts and -n in pts:
                sums.append(pts[n][0] + pts[-n][0])
                dz.append(pts[n][1] - pts[-n][1])
        rec = {"group": g, "seeds": len(sums), "torque_sums": sums, "torque_sum_pN_nm": None,
               "torque_sum_se_pN_nm": None, "t": None, "delta_z_nm": None,
               "delta_z_se_nm": None}
        if len(sums) >= 2:
            m, sd = _mean_se(sums)
            mz, sdz = _mean_se(dz)
            rec.update(torque_sum_pN_nm=m, torque_sum_se_pN_nm=sd,
                       t=m / sd if sd > 0 else math.copysign(math.inf, m) if m else 0.0,
                       delta_z_nm=mz, delta_z_se_nm=sdz)
        out.append(rec)
    return out


def _mean_se(x: list[float]) -> tuple[float, float]:
    m = sum(x) / len(x)
    var = sum((v - m) ** 2 for v in x) / (len(x) - 1)
    return m, math.sqrt(var / len(x))


# ---------------------------------------------------------------------------------------
# the figure
# ---------------------------------------------------------------------------------------
def _numeric_grid_keys(spec: SweepSpec) -> list[str]:
    return [k for k in spec.grid if all(_is_number(v) for v in spec.grid[k])]


def sweep_plot(spec: SweepSpec, rows: list[dict], path: str) -> str | None:
    """One figure per sweep, from the scene's result columns.

    A scene with several rows per point (tweezer scenes: one per turn value) gives one
    curve per point of its second result column against its first (extension against
    turns); a scene with one row per point (the knot scene) gives its first varying result
    column against the first numeric grid key, one curve per value of the other keys, with
    its theory column dashed where the scene gives one. Error bars come from the matching ``_sem`` column. If the rows hold +n and -n turns and
    the sweep varies ``alpha`` (or has more than one point), a second panel shows the
    asymmetry z(+n) - z(-n) against the swept key (``alpha`` if swept, else the first
    numeric grid key). Returns the path, or None when no point finished.
    """
    from matplotlib.figure import Figure

    keys = list(spec.grid)
    done = [r for r in rows if r["status"] == "done"]
    if not done:
        return None
    cols = spec.row_columns
    sem_cols = {s for c in cols if (s := _sem_of(c, cols))}
    numeric = [c for c in cols if c not in sem_cols
               and all(_is_number(r.get(c)) for r in done)]
    counts: dict = {}
    for r in done:
        counts[r["point"]] = counts.get(r["point"], 0) + 1
    per_point = max(counts.values()) > 1
    num_keys = _numeric_grid_keys(spec)
    if per_point and numeric:
        xcol = numeric[0]
    else:
        xcol = num_keys[0] if num_keys else None
    ycands = [c for c in numeric if c != xcol]
    varying = [c for c in ycands if len({r[c] for r in done}) > 1]
    ycol = (varying or ycands or [None])[0]
    if ycol is None:
        return None
    asym = asymmetry(rows, keys)
    akey = "alpha" if "alpha" in keys else (num_keys[0] if num_keys else None)
    show_asym = bool(asym) and akey is not None and ("alpha" in keys or len(asym) > 1)
    ncol = 2 if show_asym else 1
    fig = Figure(figsize=(5.2 * ncol, 3.9))
    axes = fig.subplots(1, ncol, squeeze=False)
    ax = axes[0, 0]
    ysem = _sem_of(ycol, cols)
    # a theory column beside the measured one (knot: radius_apex_nm, radius_theory_nm)
    theory = next((c for c in numeric if "theory" in c and c != ycol
                   and c.split("_")[0] == ycol.split("_")[0]), None)

    def bars(rs):
        return [(r.get(ysem) or 0) if ysem else 0 for r in rs]

    if per_point:
        for i, p in enumerate(spec.points):
            rs = sorted((r for r in done if r["point"] == p.name), key=lambda r: r[xcol])
            if not rs:
                continue
            label = ", ".join(f"{k}={_fmt_value(v)}" for k, v in p.values.items())
            ax.errorbar([r[xcol] for r in rs], [r[ycol] for r in rs], yerr=bars(rs), fmt="o-",
                        ms=3, capsize=2, label=label, color=f"C{i % 10}")
    else:
        others = [k for k in keys if k != xcol]
        groups: dict = {}
        for r in done:
            groups.setdefault(tuple(_fmt_value(r[k]) for k in others), []).append(r)
        for j, (g, rs) in enumerate(groups.items()):
            if xcol is None:
                xs = [spec.points.index(next(p for p in spec.points if p.name == r["point"]))
                      for r in rs]
            else:
                rs.sort(key=lambda r: r[xcol])
                xs = [r[xcol] for r in rs]
            label = ", ".join(f"{k}={v}" for k, v in zip(others, g)) or None
            ax.errorbar(xs, [r[ycol] for r in rs], yerr=bars(rs), fmt="o-", ms=3, capsize=2,
                        label=label, color=f"C{j % 10}")
            if theory:
                ax.plot(xs, [r[theory] for r in rs], "--", color=f"C{j % 10}", lw=1,
                        label=f"{theory}" + (f" ({label})" if label else ""))
    ax.set_xlabel(xcol or "point")
    ax.set_ylabel(ycol)
    if ax.get_legend_handles_labels()[1]:
        ax.legend(fontsize=7, frameon=False)
    if show_asym:
        ax2 = axes[0, 1]
        others = [k for k in keys if k != akey]
        agroups: dict = {}
        for a in asym:
            agroups.setdefault(tuple(_fmt_value(a[k]) for k in others), []).append(a)
        for j, (g, items) in enumerate(agroups.items()):
            items.sort(key=lambda a: a[akey])
            label = ", ".join(f"{k}={v}" for k, v in zip(others, g)) or None
            ax2.errorbar([a[akey] for a in items], [a["asymmetry_nm"] for a in items],
                         yerr=[a["asymmetry_sem_nm"] for a in items], fmt="s-", capsize=2,
                         label=label, color=f"C{j % 10}")
        ax2.axhline(0, color="0.7", lw=0.8)
        ns = sorted({a["n"] for a in asym})
        ax2.set_xlabel(akey)
        xs = [a[akey] for a in asym]
        if akey == "salt_mM" and min(xs) > 0 and max(xs) >= 10 * min(xs):
            ax2.set_xscale("log")
        ax2.set_ylabel(f"z(+n) - z(-n) (nm), n = {', '.join(f'{n:g}' for n in ns)}")
        if any(g for g in agroups):
            ax2.legend(fontsize=7, frameon=False)
    fig.suptitle(f"sweep {os.path.basename(os.path.normpath(spec.out))}: scene "
                 f"{spec.points[0].scene.name}", fontsize=9)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110, format="png")
    os.replace(tmp, path)
    return path


# ---------------------------------------------------------------------------------------
# trajectory analysis (MDAnalysis)
# ---------------------------------------------------------------------------------------
def _frame_turns(path: str):
    """The turn value of every frame of a run's ``trajectory.dcd`` (from its ``frames.csv``)."""
    import numpy as np

    with open(path, newline="") as fh:
        return np.array([float(r["turns"]) for r in csv.DictReader(fh)])


def analyse_sweep(sweep_dir: str, *, crossing_cutoff_nm: float | None = None,
                  write: bool = True) -> list[dict]:
    """Analyse every finished point's two-strand trajectory with MDAnalysis.

    Points without a ``trajectory.dcd`` (the knot scene writes none) are left out. Opens ``topology.pdb`` + ``trajectory.dcd`` of each point and runs
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

    from .analysis.mda import Catenation, CrossingAngles, Extension, select_strands

    spec = load_spec(os.path.join(sweep_dir, SPEC_FILE), out=sweep_dir)
    keys = list(spec.grid)
    rows = []
    for p in spec.points:
        d = _point_dir(spec, p)
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
        _write_csv(os.path.join(sweep_dir, "trajectory_analysis.csv"), cols, rows)
    return rows
