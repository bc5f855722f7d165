"""Parameter sweeps: one scene, a grid over its flat keys, one run directory per point.

A sweep spec is a TOML file (or a dict of the same shape)::

    scene = "braid"                 # built-in name or path to a scene TOML
    out = "runs/salt_sweep"         # optional (default runs/<spec file stem>)
    [fixed]                         # optional: keys set on every point
    steps = 20000
    [grid]                          # the grid: the Cartesian product of these lists
    salt_mM = [10, 150, 1000]
    force_pN = [1, 2]

Every grid point is validated with :func:`dnabraid.scene.make_scene` before anything runs
(a bad key or value fails the whole sweep with the scene's message), then run by
:func:`dnabraid.runner.run_scene` into ``<out>/<point name>`` where the name is built from
the point's values (``salt_mM=10__force_pN=1``). Points run in local processes
(:class:`concurrent.futures.ProcessPoolExecutor`, one per usable core, each pinned to one
core with one OpenMM thread) or, given a scheduler address or a ``dask.distributed.Client``,
on a Dask cluster.

Sweeps are idempotent: a point whose ``summary.json`` exists is not run again, an
interrupted point resumes from its checkpoints, and a failed point is recorded with its
error in ``sweep_status.json`` while the others go on. The results are gathered into
``results.csv`` (one row per point and turn value, units in the headers) and one figure,
``sweep.png``.
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
import sys
import time
import traceback
import warnings
from collections.abc import Callable
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from . import scene as scn
from .scene import SceneError

log = logging.getLogger(__name__)

__all__ = [
    "SweepError",
    "SweepSpec",
    "SweepPoint",
    "SweepResult",
    "load_spec",
    "run_sweep",
    "gather",
    "sweep_plot",
    "analyse_sweep",
    "usable_cores",
]

STATUS_FILE = "sweep_status.json"
RESULTS_FILE = "results.csv"
FIGURE_FILE = "sweep.png"
SPEC_FILE = "sweep.toml"
_SPEC_KEYS = {"scene", "out", "fixed", "grid"}


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
    scene: scn.Scene

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

    def to_toml(self) -> str:
        lines = [f"scene = {scn._toml_value(self.scene)}", f"out = {scn._toml_value(self.out)}",
                 "", "[fixed]"]
        lines += [f"{k} = {scn._toml_value(v)}" for k, v in self.fixed.items()]
        lines += ["", "[grid]"]
        lines += [f"{k} = {scn._toml_value(list(v))}" for k, v in self.grid.items()]
        return "\n".join(lines) + "\n"


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
        grid values, or a grid point whose scene does not validate (the SceneError
        message is included).
    FileNotFoundError
        The spec file or the scene file does not exist.
    """
    if isinstance(spec, dict):
        data = dict(spec)
        base_dir, stem = os.getcwd(), "sweep"
    else:
        path = os.fspath(spec)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"sweep spec {path!r} does not exist")
        with open(path, "rb") as fh:
            try:
                data = tomllib.load(fh)
            except tomllib.TOMLDecodeError as exc:
                raise SweepError(f"sweep spec {path!r} is not valid TOML: {exc}") from exc
        base_dir = os.path.dirname(os.path.abspath(path))
        stem = os.path.splitext(os.path.basename(path))[0]
    unknown = sorted(set(data) - _SPEC_KEYS)
    if unknown:
        raise SweepError(f"unknown sweep spec key(s) {', '.join(unknown)}; allowed: "
                         "scene, out, [fixed], [grid] (scene keys go under [fixed] or [grid])")
    base = data.get("scene", "braid")
    if not isinstance(base, str):
        raise SweepError(f"scene: expected a built-in scene name or a path, got {base!r}")
    if base not in scn.BUILTIN:
        cand = base if os.path.isabs(base) else os.path.join(base_dir, base)
        if not os.path.isfile(cand):
            raise FileNotFoundError(f"sweep scene {base!r} is neither a built-in scene ("
                                    + ", ".join(scn.BUILTIN) + f") nor a file ({cand} "
                                    "does not exist)")
        base = cand
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
        if k == "turns" and not all(isinstance(v, (list, tuple)) for v in vals):
            raise SweepError("grid key 'turns': each value is a list of turn values, "
                             "e.g. turns = [[0, 1, 2], [0, -1, -2]]")
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
            s = scn.make_scene(base, overrides)
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
    """Pin this process to core ``slot`` (modulo the usable cores); see cli._pin_to_one_core."""
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
        from .runner import run_scene

        data = tomllib.loads(scene_toml)
        s = scn.make_scene(data.pop("scene"), data)
        run_scene(s, out_dir, platform=platform, threads=1 if platform == "CPU" else None)
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
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(obj, fh, indent=2, default=str)
    os.replace(tmp, path)


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
    with open(os.path.join(spec.out, SPEC_FILE), "w") as fh:
        fh.write(spec.to_toml())
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
_OBS = [("extension_nm", "extension_nm", "extension_sem_nm"),
        ("torque_pN_nm", "torque_pN_nm", "torque_sem_pN_nm"),
        ("catenation", "catenation", "catenation_sem")]


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, (list, tuple)):
        return " ".join(_fmt_value(x) for x in v)
    return v


def gather(spec: SweepSpec) -> list[dict]:
    """Collect every point's summary into rows and write ``results.csv``.

    One row per grid point and turn value (grid order, then turns ascending); a point
    without a summary gets one row with its status (``failed`` with the error, or
    ``pending``). Columns: the grid keys (units are in the key names), ``turns``,
    ``extension_nm, extension_sem_nm, torque_pN_nm, torque_sem_pN_nm, catenation,
    catenation_sem, n_samples, status, error, point``.
    """
    status_path = os.path.join(spec.out, STATUS_FILE)
    status = {}
    if os.path.isfile(status_path):
        with open(status_path) as fh:
            status = json.load(fh).get("points", {})
    keys = list(spec.grid)
    rows = []
    for p in spec.points:
        base = {k: p.values[k] for k in keys}
        summ = os.path.join(_point_dir(spec, p), "summary.json")
        if os.path.isfile(summ):
            with open(summ) as fh:
                summary = json.load(fh)
            for pt in summary["points"]:
                row = dict(base, turns=pt["turns"])
                for key, mcol, scol in _OBS:
                    row[mcol] = pt[key]["mean"]
                    row[scol] = pt[key]["sem"]
                row.update(n_samples=pt["n_samples"], status="done", error="", point=p.name)
                rows.append(row)
        else:
            st = status.get(p.name, {})
            err = st.get("error") or {}
            row = dict(base, turns=None)
            for _, mcol, scol in _OBS:
                row[mcol] = row[scol] = None
            row.update(n_samples=None, status=st.get("status", "pending"),
                       error=f"{err['type']}: {err['message']}" if err else "", point=p.name)
            rows.append(row)
    cols = keys + ["turns"] + [c for _, m, s in _OBS for c in (m, s)] + [
        "n_samples", "status", "error", "point"]
    path = os.path.join(spec.out, RESULTS_FILE)
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            w.writerow([_cell(r[c]) for c in cols])
    os.replace(tmp, path)
    return rows


def format_table(rows: list[dict], keys: list[str]) -> str:
    """Fixed-width text table of gathered rows (for the CLI)."""
    cols = keys + ["turns", "extension_nm", "torque_pN_nm", "catenation", "status"]
    head = [*keys, "turns", "extension_nm", "torque_pN_nm", "catenation", "status"]

    def ms(r, m, s, p):
        if r[m] is None:
            return "-"
        return f"{r[m]:.{p}f} +- {r[s]:.{p}f}"

    lines = []
    widths = [max(len(h), 8) for h in head]
    widths[len(keys) + 1:len(keys) + 4] = [20, 20, 18]
    lines.append(" ".join(h.rjust(w) for h, w in zip(head, widths)))
    for r in rows:
        cells = [_fmt_value(r[k]) for k in keys]
        cells.append("-" if r["turns"] is None else f"{r['turns']:g}")
        cells.append(ms(r, "extension_nm", "extension_sem_nm", 1))
        cells.append(ms(r, "torque_pN_nm", "torque_sem_pN_nm", 1))
        cells.append(ms(r, "catenation", "catenation_sem", 3))
        cells.append(r["status"] + (f" ({r['error']})" if r["error"] else ""))
        lines.append(" ".join(c.rjust(w) for c, w in zip(cells, widths)))
    del cols
    return "\n".join(lines)


def quick_braid_fixed(*, turns: int, steps: int, seed: int, length_nm: float = 90.0,
                      **keys) -> dict:
    """The ``[fixed]`` table of the small braid sweeps in ``workflows/``.

    Turns -N..N, 3 nm beads (fine enough up to 1 M salt), equilibration steps/5 unless
    given, a frame every tenth of the sampling; ``keys`` add or override flat scene keys
    (``None`` drops a key, e.g. one that the sweep's grid varies).
    """
    fixed = {"length_nm": length_nm, "bead_spacing_nm": 3.0,
             "turns": list(range(-turns, turns + 1)), "steps": steps,
             "equilibration_steps": steps // 5, "turn_rate": 1e-4, "seed": seed,
             "frame_interval": max(100, steps // 10 // 100 * 100)}
    fixed.update(keys)
    return {k: v for k, v in fixed.items() if v is not None}


def asymmetry(rows: list[dict], keys: list[str]) -> list[dict]:
    """Handedness asymmetry z(+n) - z(-n) per grid point, for the largest n with both signs.

    Returns one dict per point with ``n``, ``asymmetry_nm``, ``asymmetry_sem_nm`` and the
    grid values; points without a +n/-n pair are left out.
    """
    by_point: dict = {}
    for r in rows:
        if r["status"] == "done" and r["extension_nm"] is not None:
            by_point.setdefault(r["point"], []).append(r)
    out = []
    for name, rs in by_point.items():
        z = {r["turns"]: (r["extension_nm"], r["extension_sem_nm"]) for r in rs}
        pairs = [n for n in z if n > 0 and -n in z]
        if not pairs:
            continue
        n = max(pairs)
        (zp, sp), (zm, sm) = z[n], z[-n]
        out.append({**{k: rs[0][k] for k in keys}, "point": name, "n": n,
                    "asymmetry_nm": zp - zm, "asymmetry_sem_nm": math.hypot(sp or 0, sm or 0)})
    return out


def sweep_plot(spec: SweepSpec, rows: list[dict], path: str) -> str | None:
    """One figure per sweep: extension against turns per grid point; and, if the sweep
    varies ``alpha`` or holds +n and -n turn values, the asymmetry z(+n) - z(-n) against
    the swept key (``alpha`` if swept, else the first numeric grid key)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = list(spec.grid)
    done = [r for r in rows if r["status"] == "done"]
    if not done:
        return None
    asym = asymmetry(rows, keys)
    numeric = [k for k in keys if all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                      for v in spec.grid[k])]
    xkey = "alpha" if "alpha" in keys else (numeric[0] if numeric else None)
    show_asym = bool(asym) and xkey is not None and ("alpha" in keys or len(asym) > 1)
    ncol = 2 if show_asym else 1
    fig, axes = plt.subplots(1, ncol, figsize=(5.2 * ncol, 3.9), squeeze=False)
    ax = axes[0, 0]
    for i, p in enumerate(spec.points):
        rs = [r for r in done if r["point"] == p.name]
        if not rs:
            continue
        label = ", ".join(f"{k}={_fmt_value(v)}" for k, v in p.values.items())
        ax.errorbar([r["turns"] for r in rs], [r["extension_nm"] for r in rs],
                    yerr=[r["extension_sem_nm"] or 0 for r in rs], fmt="o-", ms=3, capsize=2,
                    label=label, color=f"C{i % 10}")
    ax.set_xlabel("bead turns n")
    ax.set_ylabel("extension (nm)")
    ax.legend(fontsize=7, frameon=False)
    if show_asym:
        ax2 = axes[0, 1]
        others = [k for k in keys if k != xkey]
        groups: dict = {}
        for a in asym:
            groups.setdefault(tuple(_fmt_value(a[k]) for k in others), []).append(a)
        for j, (g, items) in enumerate(groups.items()):
            items.sort(key=lambda a: a[xkey])
            label = ", ".join(f"{k}={v}" for k, v in zip(others, g)) or None
            ax2.errorbar([a[xkey] for a in items], [a["asymmetry_nm"] for a in items],
                         yerr=[a["asymmetry_sem_nm"] for a in items], fmt="s-", capsize=2,
                         label=label, color=f"C{j % 10}")
        ax2.axhline(0, color="0.7", lw=0.8)
        ns = sorted({a["n"] for a in asym})
        ax2.set_xlabel(xkey)
        xs = [a[xkey] for a in asym]
        if xkey == "salt_mM" and min(xs) > 0 and max(xs) >= 10 * min(xs):
            ax2.set_xscale("log")
        ax2.set_ylabel(f"z(+n) - z(-n) (nm), n = {', '.join(f'{n:g}' for n in ns)}")
        if any(g for g in groups):
            ax2.legend(fontsize=7, frameon=False)
    sc = spec.points[0].scene
    fig.suptitle(f"sweep {os.path.basename(os.path.normpath(spec.out))}: {sc.scene}, "
                 f"L = {sc.length_nm:g} nm", fontsize=9)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    os.replace(tmp, path)
    return path


# ---------------------------------------------------------------------------------------
# trajectory analysis (MDAnalysis)
# ---------------------------------------------------------------------------------------
def analyse_sweep(sweep_dir: str, *, crossing_cutoff_nm: float | None = None,
                  write: bool = True) -> list[dict]:
    """Analyse every finished point's trajectory with MDAnalysis.

    Opens ``topology.pdb`` + ``trajectory.dcd`` of each point and runs
    :class:`~dnabraid.analysis.mda.Extension`, :class:`~dnabraid.analysis.mda.Catenation`
    and :class:`~dnabraid.analysis.mda.CrossingAngles` over its frames; the frames are
    split per turn value with the frame counts in ``summary.json``.

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
        files = [os.path.join(d, f) for f in ("topology.pdb", "trajectory.dcd", "summary.json")]
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
        start = 0
        for pt in summary["points"]:
            nf = pt["n_frames"]
            sl = slice(start, start + nf)
            sel = (cross.results.frame_index >= start) & (cross.results.frame_index < start + nf)
            eta = cross.results.eta[sel]
            rows.append({**{k: p.values[k] for k in keys}, "turns": pt["turns"],
                         "n_frames": nf,
                         "extension_nm": float(np.mean(ext.results.extension_nm[sl])) if nf else None,
                         "catenation": float(np.mean(cat.results.catenation[sl])) if nf else None,
                         "crossings_per_frame": eta.size / nf if nf else None,
                         "mean_abs_crossing_angle_deg":
                             float(np.degrees(np.mean(np.abs(eta)))) if eta.size else None,
                         "point": p.name})
            start += nf
    if write:
        cols = keys + ["turns", "n_frames", "extension_nm", "catenation", "crossings_per_frame",
                       "mean_abs_crossing_angle_deg", "point"]
        path = os.path.join(sweep_dir, "trajectory_analysis.csv")
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            for r in rows:
                w.writerow([_cell(r[c]) for c in cols])
    return rows
