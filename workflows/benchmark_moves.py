"""Brownian dynamics alone against BD with Metropolis rigid-body and crankshaft moves.

The catenane (two linked 144-nm rings, Delta Lk_i = -1, alpha = 0) at equal steps, with
`rigid_moves` = 0 (BD alone) and a few move counts per report interval (100 steps);
replicas half started apart, half in contact. For each setting: wall time, replica-steps
per second, and the between-replica diagnostics (split R-hat, bulk ESS) of the slow
observables: the contact length (relative position of the rings: BD needs the rings'
diffusion across their radius, ~39 us = 3e6 steps of 12 ps) and the writhes (the rings'
shapes). The figure of merit is ESS per wall second (error^2 x wall time is 1 / that, up to
the variance). Equilibrium averages are the same in every setting (tests/test_moves.py,
tests/test_catenane.py); only the cost of an independent sample differs.

Usage: python workflows/benchmark_moves.py [--steps 80000] [--replicas 4]
       [--moves 0 3 10 30]
Writes workflows/results/benchmark_moves.txt.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import shutil
import tempfile
import time

from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=80_000)
    ap.add_argument("--equilibration", type=int, default=8_000)
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--moves", type=int, nargs="+", default=[0, 3, 10, 30])
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_moves.txt"))
    args = ap.parse_args(argv)
    rows = []
    tmp = tempfile.mkdtemp(prefix="bench_moves_")
    try:
        for nm in args.moves:
            s = make_scene("catenane", {
                "alpha": 0.0, "delta_lk": -1, "start": "mixed", "timestep_safety": 0.6,
                "steps": args.steps, "equilibration_steps": args.equilibration,
                "replicas": args.replicas, "frame_interval": args.steps, "rigid_moves": nm})
            t0 = time.perf_counter()
            summ = s.run(os.path.join(tmp, f"m{nm}"))
            wall = time.perf_counter() - t0
            pt = summ["points"][0]
            row = {"moves": nm, "wall": wall,
                   "rs": args.replicas * (args.steps + args.equilibration) / wall}
            for c in ("contact_length_nm", "writhe_1", "writhe_2"):
                row[c] = (pt[c].get("rhat"), pt[c].get("ess"))
            mv = pt.get("rigid_moves") or {}
            row["acc"] = "/".join(f"{mv[k]['acceptance']:.2f}" for k in ("shift", "turn", "arc")
                                  if k in mv) or "-"
            rows.append(row)
            print(row, flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    lines = [f"# BD alone vs BD + Metropolis moves, catenane (2 x 144 nm, Delta Lk = -1, "
             f"alpha = 0), {args.replicas} replicas x ({args.equilibration} + {args.steps}) "
             f"steps, dt = 12 ps, {time.strftime('%Y-%m-%d %H:%M')}",
             f"# {os.cpu_count()} cores; replicas packed and spread over them as `dnabraid run` "
             "does; acceptance shift/turn/arc",
             f"{'moves/100 steps':>15} {'wall s':>8} {'replica-steps/s':>16} "
             f"{'contact R-hat':>13} {'contact ESS':>11} {'ESS/s':>7} {'Wr_1 R-hat':>10} "
             f"{'Wr_1 ESS':>8} {'Wr_2 R-hat':>10} {'Wr_2 ESS':>8} {'acceptance':>15}"]
    for r in rows:
        cr, ce = r["contact_length_nm"]
        w1, w2 = r["writhe_1"], r["writhe_2"]
        lines.append(f"{r['moves']:>15} {r['wall']:>8.1f} {r['rs']:>16.0f} {cr:>13.3f} "
                     f"{ce:>11.0f} {ce / r['wall']:>7.2f} {w1[0]:>10.3f} {w1[1]:>8.0f} "
                     f"{w2[0]:>10.3f} {w2[1]:>8.0f} {r['acc']:>15}")
    text = "\n".join(lines) + "\n"
    print(text)
    with open(args.out, "w") as fh:
        fh.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
