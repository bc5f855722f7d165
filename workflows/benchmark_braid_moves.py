"""Metropolis braid moves (dnabraid.run.chain_moves.BraidMoves): the long braid's
convergence with and without them.

The long braid (:data:`dnabraid.scenes.braid.LONG_BRAID`: 2 x 200 nm at 2 pN, tethers 40 nm
apart, timestep_safety 0.3) run by ``Scene.run`` at turns [0] and at [-2, 2], Brownian
dynamics alone (``mc_moves = 0``) against BD + moves (``mc_moves = --moves``, the scene's
default amplitudes), same seeds and steps: per point the verdict, extension +- SEM, R-hat,
the smallest ESS, wall time, ESS per wall second and the acceptance of each kind
(crankshaft/bead/shear/twist), with the number refused by the topology check.

Usage: python workflows/benchmark_braid_moves.py [--steps 60000] [--replicas 4]
       [--moves 1000] [--seed 1]
Writes workflows/results/benchmark_braid_moves.txt (appends with --append).
"""

from __future__ import annotations

import argparse
import datetime
import os
import pathlib
import shutil
import tempfile

from dnabraid.run.chain_moves import BRAID_KINDS
from dnabraid.scenes import make_scene
from dnabraid.scenes.braid import LONG_BRAID

HERE = pathlib.Path(__file__).resolve().parent


def runs(turn_sets, steps, eq, replicas, moves, seed, tmp) -> list[str]:
    lines = [f"{'turns':>6} {'mc_moves':>8} {'verdict':>13} {'extension nm':>15} {'R-hat':>6} "
             f"{'ESS':>6} {'wall s':>7} {'ESS/wall s':>10} {'acc c/b/s/t':>20} {'topo ref':>8}"]
    for turns in turn_sets:
        for nm in (0, moves):
            s = make_scene("braid", dict(LONG_BRAID, turns=list(turns), steps=steps,
                                         equilibration_steps=eq, replicas=replicas,
                                         seed=seed, mc_moves=nm,
                                         # pinned: the braid's default trap is K = 2000
                                         # since 2026-12-06; the stored rows had K = 2e4
                                         trap_stiffness_pN_nm=20000.0))
            out = os.path.join(tmp, f"t{len(turns)}_m{nm}")
            summ = s.run(out)
            wall = summ["wall_time_s"]
            for pt in summ["points"]:
                e = pt["extension_nm"]
                ess = min(v for v in pt["effective_sample_size"].values())
                mv = pt.get("rigid_moves") or {}
                acc = "/".join(f"{mv[k]['acceptance']:.2f}" for k in BRAID_KINDS if k in mv) \
                    or "-"
                ref = sum(mv[k]["refused_by_constraint"] for k in BRAID_KINDS if k in mv)
                verdict = "converged" if pt["converged"] else "NOT CONVERGED"
                lines.append(f"{pt['turns']:6.1f} {nm:8d} {verdict:>13} {e['mean']:7.1f} +- "
                             f"{e['sem']:4.1f} {e['rhat']:6.3f} {ess:6.0f} {wall:7.1f} "
                             f"{ess / wall:10.2f} {acc:>20} {ref:8d}")
                print(lines[-1], flush=True)
            shutil.rmtree(out, ignore_errors=True)
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=60000)
    ap.add_argument("--eq", type=int, default=20000)
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--moves", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--turns", default="0;-2,2", help="turn sets, ';'-separated")
    ap.add_argument("--append", action="store_true")
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_braid_moves.txt"))
    args = ap.parse_args(argv)
    turn_sets = [[float(x) for x in t.split(",")] for t in args.turns.split(";")]
    s = make_scene("braid")
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    head = [f"# braid moves, long braid {LONG_BRAID}, {stamp}; {os.cpu_count()} cores shared "
            f"(load average at start {os.getloadavg()[0]:.1f})",
            f"# replicas={args.replicas} steps={args.steps} equilibration_steps={args.eq} "
            f"seed={args.seed}; moves: mc_moves={args.moves} per report interval, "
            f"crank_angle_rad={s.crank_angle_rad}, bead_move_nm={s.bead_move_nm}, "
            f"shear_nm={s.shear_nm}, shear_z_nm={s.shear_z_nm}, twist_rad={s.twist_rad}, "
            "kinds 4:4:0.5:0.5:1:2:1:2 (BraidMoves default); wall = the whole run (all its points)"]
    tmp = tempfile.mkdtemp(prefix="bench_braid_moves_")
    try:
        lines = head + runs(turn_sets, args.steps, args.eq, args.replicas, args.moves,
                            args.seed, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    text = "\n".join(lines) + "\n"
    print(text)
    p = pathlib.Path(args.out)
    if args.append and p.exists():
        text = p.read_text() + "\n" + text
    p.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
