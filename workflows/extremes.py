"""Run the stiff-and-extreme matrix of dnabraid.validation.extremes and write its outcome table.

Each case runs a few thousand Brownian steps (force 0.05-150 pN, salt 1 mM-3 M, bead spacing
1 nm, turns near lock-up, fast ramps, strong chirality, time step at the stability limit) and
is reported as ok (invariants kept), refused (validation error naming the key) or stopped
(blow-up error naming the step and term), beside the outcome the case expects. Each case
runs with its scene's short-run settings (Scene.default_short_run) and the matrix's common
ones (dnabraid.validation.extremes.MATRIX). Writes workflows/results/extremes.md.

Usage: taskset -c 0 python workflows/extremes.py [--steps N] [--cases NAME ...]
"""

from __future__ import annotations

import argparse
import pathlib
import time

from dnabraid.validation.extremes import CASES, run_case

HERE = pathlib.Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=None,
                    help="sampling steps per turn value (default: each scene's short run)")
    ap.add_argument("--cases", nargs="+", default=None, metavar="NAME",
                    help="run only the cases whose name contains one of these strings")
    ap.add_argument("--out", default=str(HERE / "results" / "extremes.md"))
    args = ap.parse_args(argv)
    short = {"steps": args.steps} if args.steps else None
    cases = [c for c in CASES if not args.cases or any(w in c.name for w in args.cases)]
    head = ("| case | scene | expected | outcome | dt (ps) | stiffest | max bond/b | "
            "catenation err | E/particle (kT) | wall (s) | detail |")
    steps = f"{args.steps} steps" if args.steps else "each scene's short run"
    lines = [f"# extremes matrix, {time.strftime('%Y-%m-%d %H:%M')}, {steps}",
             "", head, "|" + "---|" * 11]
    print(head)
    unexpected = 0
    for case in cases:
        r = run_case(case, short=short)
        as_expected = r["outcome"] == case.expect and case.message in r["detail"]
        unexpected += not as_expected
        line = (f"| {r['case']} | {r['scene']} | {r['expect']} | **{r['outcome']}**"
                f"{'' if as_expected else ' (UNEXPECTED)'} | {r['time_step_ps']:.3g} | "
                f"{r['stiffest_term']} | {r['max_bond_ratio']:.3f} | "
                f"{r['catenation_error']:.3g} | {r['energy_per_bead_kT']:.3g} | "
                f"{r['wall_time_s']:.1f} | {r['detail'][:160].replace('|', '/')} |")
        lines.append(line)
        print(line, flush=True)
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"written {out}; {unexpected} case(s) not as expected")
    return 1 if unexpected else 0


if __name__ == "__main__":
    raise SystemExit(main())
