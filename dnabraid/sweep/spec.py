"""The sweep spec: reading a sweep TOML (or dict), validating it, naming its grid points.

A sweep spec is a TOML file (or a dict of the same shape)::

    scene = "braid"                 # a registered scene name or a path to a scene TOML
    out = "runs/salt_sweep"         # optional (default runs/<spec file stem>)
    [fixed]                         # optional: keys set on every point
    steps = 20000
    [grid]                          # the grid: the Cartesian product of these lists
    salt_mM = [10, 150, 1000]
    force_pN = [1, 2]

Any scene of :data:`dnabraid.scenes.SCENES` can be swept. :func:`load_spec` validates every
grid point with :func:`dnabraid.scenes.make_scene` before anything runs (a bad key or value
fails the whole sweep with the scene's message); each point runs into
``<out>/<point name>`` (:func:`point_dir`), the name built from the point's values
(``salt_mM=10__force_pN=1``, :func:`point_name`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import os

from .. import tomlio
from ..scenes import SCENES, Scene, SceneError, make_scene, scene_class

__all__ = [
    "SPEC_FILE",
    "STATUS_COLUMNS",
    "SweepError",
    "SweepPoint",
    "SweepSpec",
    "format_value",
    "load_spec",
    "point_dir",
    "point_name",
]

#: The spec as the sweep ran it, written into the sweep directory.
SPEC_FILE = "sweep.toml"
_SPEC_KEYS = {"scene", "out", "fixed", "grid"}
#: Columns every results.csv row ends with (after the grid keys and the scene's columns).
STATUS_COLUMNS = ("status", "error", "point")


class SweepError(SceneError):
    """A sweep spec is invalid (unknown key, missing file, empty grid, bad grid point)."""


def format_value(v) -> str:
    """A grid value as it appears in a point's directory name and in tables.

    Booleans are ``true``/``false``, floats use ``%g``, lists join their items with ``_``.
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "_".join(format_value(x) for x in v)
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def point_name(values: dict) -> str:
    """Readable, deterministic directory name of a grid point: ``key=value__key=value``.

    Names longer than 120 characters are cut and given a hash of the full name.
    """
    if not values:
        return "point"
    name = "__".join(f"{k}={format_value(v)}" for k, v in values.items())
    name = name.replace(os.sep, "-").replace(" ", "")
    if len(name) > 120:
        digest = hashlib.sha1(name.encode()).hexdigest()[:10]
        name = name[:100] + "__" + digest
    return name


@dataclasses.dataclass(frozen=True)
class SweepPoint:
    """One grid point: its name, its grid values, its resolved and validated scene."""

    name: str
    values: dict
    scene: Scene

    @property
    def scene_toml(self) -> str:
        """The point's scene as a scene TOML (what a worker rebuilds it from)."""
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
        """The spec as a sweep TOML that :func:`load_spec` reads back to the same spec."""
        v = tomlio.value
        lines = [f"scene = {v(self.scene)}", f"out = {v(self.out)}", "", "[fixed]"]
        lines += [f"{k} = {v(x)}" for k, x in self.fixed.items()]
        lines += ["", "[grid]"]
        lines += [f"{k} = {v(list(x))}" for k, x in self.grid.items()]
        return "\n".join(lines) + "\n"


def point_dir(spec: SweepSpec, p: SweepPoint) -> str:
    """The run directory of point ``p``: ``<spec.out>/<p.name>``."""
    return os.path.join(spec.out, p.name)


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
        names = [format_value(v) for v in vals]
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

