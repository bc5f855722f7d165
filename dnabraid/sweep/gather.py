"""Gathering a sweep's results: one row per point (or per turn value), ``results.csv``.

:func:`gather` reads every point's ``summary.json`` into rows through its scene's
:meth:`~dnabraid.scenes.base.Scene.rows` and writes ``results.csv``: the grid keys, then
the result columns the scene declares (``row_columns``: for the tweezer scenes one row per
turn value with extension, torque and catenation; for the knot scene one row per point with
loop radius, braid length and wave number beside the theory), then ``status, error,
point``. :func:`format_table` prints the rows as the CLI shows them.
"""

from __future__ import annotations

import csv
import json
import math
import os

from ..analysis.handedness import asymmetry
from .spec import STATUS_COLUMNS, SweepSpec, format_value, point_dir

__all__ = [
    "RESULTS_FILE",
    "STATUS_FILE",
    "format_table",
    "gather",
    "is_number",
    "sem_column",
    "write_csv",
]

#: Per-point status of a sweep (done, failed with its error, pending), in the sweep directory.
STATUS_FILE = "sweep_status.json"
#: The gathered table, in the sweep directory.
RESULTS_FILE = "results.csv"


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, (list, tuple)):
        return " ".join(format_value(x) for x in v)
    return v


def write_csv(path: str, cols: list[str], rows: list[dict]) -> None:
    """Write ``rows`` (dicts) under the header ``cols`` to ``path``, atomically.

    None and NaN are empty cells, floats are written with ``repr`` (round trip), lists
    as their values separated by spaces; a key missing from a row is an empty cell.
    """
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
        summ = os.path.join(point_dir(spec, p), "summary.json")
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
    write_csv(os.path.join(spec.out, RESULTS_FILE), spec.columns, rows)
    return rows


def sem_column(col: str, cols: list[str]) -> str | None:
    """The standard-error column that goes with ``col`` (``extension_nm`` ->
    ``extension_sem_nm``, ``catenation`` -> ``catenation_sem``), if the table has one."""
    for c in cols:
        if c != col and "_sem" in c and c.replace("_sem", "", 1) == col:
            return c
    return None


def is_number(v) -> bool:
    """True for an int or float that is not a bool (a plottable table value)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _fmt_cell(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return format_value(v)


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
    z(+n) - z(-n) of each point follows
    (:func:`dnabraid.analysis.handedness.asymmetry`).
    """
    if not rows:
        return "(no points)"
    skip = set(keys) | set(STATUS_COLUMNS)
    cols = [c for c in rows[0] if c not in skip]
    sems = {c: sem_column(c, cols) for c in cols}
    shown = [c for c in cols if c not in set(sems.values())]
    head = [*keys, *shown, "status"]
    table = []
    for r in rows:
        cells = [format_value(r[k]) for k in keys]
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

