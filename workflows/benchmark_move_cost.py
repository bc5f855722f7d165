"""Cost per twist-aware Metropolis move of the plectoneme, per kind, from a given state.

Microseconds per move (wall of this process, 1e5 moves after 2e3 of warm-up; run it
pinned to one core, e.g. ``taskset -c 0``) of crankshaft, pivot, frame and particle moves
alone and of the default mix 1:6:1:1 (:class:`dnabraid.run.twist_moves.PlectonemeMoves`,
the compiled loop, no engine), with their acceptance. The state is the last frame of a
finished plectoneme run's point (``--run DIR --replica r02 --point 004_turns+012.0000``:
a buckled 1-um molecule) or, without ``--run``, the scene's built start. The seeds are
fixed, so two source trees give the same acceptances when their energies agree: to
compare kernels, run it once per tree (``PYTHONPATH=TREE``) and compare ratios from runs
made one after the other.

    taskset -c 0 python workflows/benchmark_move_cost.py --run RUN --replica r02 \\
        --point 004_turns+012.0000 --length 1000 --force 1 --turns 12 --label new

Appends its table to ``--out`` (default workflows/results/benchmark_move_cost.txt).
"""

from __future__ import annotations

import argparse
import datetime
import os
import pathlib
import time

import numpy as np

from dnabraid.run.twist_moves import PlectonemeMoves
from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent
MIXES = ((1, 6, 1, 1), (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1))
NAMES = ("mix 1:6:1:1", "crankshaft", "pivot", "frame", "particle")


def state(scene, model, run, replica, point):
    if run is None:
        return np.array(model.positions, float)
    import MDAnalysis as mda

    u = mda.Universe(os.path.join(run, "topology.pdb"),
                     os.path.join(run, "replicas", replica, "points", point, "trajectory.dcd"))
    u.trajectory[-1]
    pos = np.array(model.positions, float)
    pos[:] = u.atoms.positions / 10.0  # MDAnalysis: Angstrom
    return pos


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", default=None)
    ap.add_argument("--replica", default="r00")
    ap.add_argument("--point", default=None)
    ap.add_argument("--length", type=float, default=1000.0)
    ap.add_argument("--force", type=float, default=1.0)
    ap.add_argument("--turns", type=float, default=0.0)
    ap.add_argument("--moves", type=int, default=100000)
    ap.add_argument("--label", default="")
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_move_cost.txt"))
    a = ap.parse_args(argv)
    s = make_scene("plectoneme", {"length_nm": a.length, "force_pN": a.force,
                                  "turns": [a.turns], "mc_moves": 0})
    m = s.build()
    pos0 = state(s, m, a.run, a.replica, a.point)
    kw = dict(crank_angle_rad=s.crank_angle_rad, pivot_angle_rad=s.pivot_angle_rad,
              frame_angle_rad=s.frame_angle_rad, ball_nm=s.bead_move_nm, sweep_nm=s.sweep_nm)
    import dnabraid

    lines = [f"# {datetime.datetime.now():%Y-%m-%d %H:%M} {a.label} (dnabraid from "
             f"{os.path.dirname(dnabraid.__file__)}); plectoneme {a.length:g} nm, "
             f"{a.force:g} pN, n = {a.turns:g}; state: "
             f"{'built start' if a.run is None else f'{a.run} {a.replica} {a.point} (last frame)'}"
             f"; load average {os.getloadavg()[0]:.1f}",
             f"{'kind':>12} {'us/move':>8}  acceptance"]
    for w, name in zip(MIXES, NAMES):
        mv = PlectonemeMoves.for_model(m, moves_per_call=1, seed=3, weights=w,
                                       guard_every=10**9, **kw)
        mv.energy.set_trap_angle(2 * np.pi * a.turns)
        pos, _ = mv.run(pos0.copy(), 2000)
        t0 = time.perf_counter()
        pos, _ = mv.run(pos, a.moves)
        dt = time.perf_counter() - t0
        acc = "/".join(f"{v.accepted / max(v.attempted, 1):.3f}" for v in mv.stats.values())
        lines.append(f"{name:>12} {dt / a.moves * 1e6:8.2f}  {acc}")
    text = "\n".join(lines) + "\n"
    print(text)
    with open(a.out, "a") as f:
        f.write(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
