"""Error against mesh/tolerance and wall time for every continuum problem.

Each problem module of :mod:`dnabraid.continuum` provides ``convergence_table()``: rows
with the setting (mesh size or tolerance), the error against an exact solution or a
refined reference, and the wall time. This script prints them as one table and writes it
to ``workflows/results/continuum_convergence.txt`` (and ``.json``).

Usage: python workflows/continuum_convergence.py [--problems ply knot overhand tweezer]
"""

from __future__ import annotations

import argparse
import json
import pathlib
import platform
import time

from dnabraid.continuum.commands import PROBLEMS, problem_module

HERE = pathlib.Path(__file__).resolve().parent


def _fmt(v):
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--problems", nargs="+", default=list(PROBLEMS), choices=list(PROBLEMS))
    ap.add_argument("--out", default=str(HERE / "results" / "continuum_convergence"))
    args = ap.parse_args(argv)
    lines = [f"# continuum convergence, {time.strftime('%Y-%m-%d %H:%M')}, "
             f"{platform.node()}, python {platform.python_version()}"]
    everything = {}
    for name in args.problems:
        t0 = time.perf_counter()
        rows = problem_module(name).convergence_table()
        everything[name] = rows
        keys = []
        for r in rows:
            keys += [k for k in r if k not in keys]
        lines.append("")
        lines.append(f"## {name} ({time.perf_counter() - t0:.1f} s)")
        lines.append(" | ".join(keys))
        lines.append(" | ".join("---" for _ in keys))
        for r in rows:
            lines.append(" | ".join(_fmt(r.get(k, "")) for k in keys))
        print("\n".join(lines[-len(rows) - 3:]), flush=True)
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".txt").write_text("\n".join(lines) + "\n")
    out.with_suffix(".json").write_text(json.dumps(everything, indent=1, default=str))
    print(f"\nwritten {out.with_suffix('.txt')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
