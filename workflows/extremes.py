"""Run the stiff-and-extreme matrix of dnabraid.extremes and write its outcome table.

Each case runs a few thousand Brownian steps (force 0.05-150 pN, salt 1 mM-3 M, bead spacing
1 nm, turns near lock-up, fast ramps, strong chirality, time step at the stability limit) and
is reported as ok (invariants kept), refused (validation error naming the key) or stopped
(blow-up error naming the step and term). Writes workflows/results/extremes.md.

Usage: taskset -c 0 python workflows/extremes.py [--steps 2000]
"""

from __future__ import annotations

import argparse
import pathlib
import time

from dnabraid.extremes import CASES, SHORT, run_case

HERE = pathlib.Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=SHORT["steps"])
    ap.add_argument("--out", default=str(HERE / "results" / "extremes.md"))
    args = ap.parse_args(argv)
    short = dict(SHORT, steps=args.steps)
    head = ("| case | expected | outcome | dt (ps) | stiffest | max bond/b | catenation err "
            "| E/bead (kT) | wall (s) | detail |")
    lines = [f"# extremes matrix, {time.strftime('%Y-%m-%d %H:%M')}, {args.steps} steps",
             "", head, "|" + "---|" * 10]
    print(head)
    for case in CASES:
        r = run_case(case, short=short)
        line = (f"| {r['case']} | {r['expect']} | **{r['outcome']}** | {r['time_step_ps']:.3g} | "
                f"{r['stiffest_term']} | {r['max_bond_ratio']:.3f} | {r['catenation_error']:.3g} | "
                f"{r['energy_per_bead_kT']:.3g} | {r['wall_time_s']:.1f} | "
                f"{r['detail'][:160].replace('|', '/')} |")
        lines.append(line)
        print(line, flush=True)
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"written {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
