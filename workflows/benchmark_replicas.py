"""Replicas in one OpenMM Context against one Context per replica.

R non-interacting copies of a scene's System are packed into one System
(:func:`dnabraid.run.packing.replicate_system`, which `dnabraid run` uses since 2026-12-01, key
``pack``): particles, bonded terms and external terms copied with an index offset; the
copies' excluded volume is kept apart by placing them ``spacing_nm`` apart along x (beyond
the cutoff, so that the neighbour list never pairs two copies: checked below), centred on
the origin (the CPU platform's nonbonded kernels are single precision). Global parameters (trap angle, force)
are shared, as they are for replicas of one point. Measured: steps/s of the packed Context
and replica-steps/s (= R x steps/s) against R separate single-replica runs, one pinned core
each, which is what `dnabraid run` does today (workers = cores).

Usage: python workflows/benchmark_replicas.py [--scene braid] [--set KEY=VALUE ...]
Writes workflows/results/benchmark_replicas.txt.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import time

import numpy as np
import openmm
from openmm import unit as u

from dnabraid.run.engine import GAMMA_PER_PS
from dnabraid.run.packing import replicate_system
from dnabraid.scenes import make_scene, parse_value

HERE = pathlib.Path(__file__).resolve().parent


def _context(system, positions, dt_ps, temperature_K, threads=1):
    integ = openmm.BrownianIntegrator(temperature_K * u.kelvin, GAMMA_PER_PS / u.picosecond,
                                      dt_ps * u.picoseconds)
    integ.setRandomNumberSeed(3)
    ctx = openmm.Context(system, integ, openmm.Platform.getPlatformByName("CPU"),
                         {"Threads": str(threads)})
    ctx.setPositions(positions * u.nanometer)
    return ctx, integ


def _rate(integ, steps) -> float:
    integ.step(200)
    t0 = time.perf_counter()
    integ.step(steps)
    return steps / (time.perf_counter() - t0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="braid")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--replicas", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--spacing-nm", type=float, default=150.0)
    ap.add_argument("--turns", type=float, default=None,
                    help="start from the scene's built (minimised) start at these turns, e.g. "
                         "1 for a braid in contact, where the chiral term has work to do")
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_replicas.txt"))
    args = ap.parse_args(argv)
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
        pinned = True
    except (AttributeError, OSError):
        pinned = False
    ov = dict(kv.split("=", 1) for kv in args.set)
    scene = make_scene(args.scene, {k: parse_value(v) for k, v in ov.items()})
    model = scene.build()
    pos0 = model.positions
    N = len(pos0)
    dt_ps = model.timestep.time_step_ns * 1e3
    if args.turns is not None:
        pos0 = scene.start_positions(model, args.turns)
        c0, _ = _context(model.system, pos0, dt_ps, scene.temperature_K)
        c0.setParameter("trap_angle", 2 * np.pi * args.turns)
        openmm.LocalEnergyMinimizer.minimize(c0, 1.0, 2000)
        pos0 = c0.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(
            u.nanometer)
    ctx1, integ1 = _context(model.system, pos0, dt_ps, scene.temperature_K)
    if args.turns is not None:
        ctx1.setParameter("trap_angle", 2 * np.pi * args.turns)
    base = _rate(integ1, args.steps)
    lines = [f"# {time.strftime('%Y-%m-%d %H:%M')}: {scene.name} {ov or '(defaults)'}, {N} "
             f"particles per replica; OpenMM {openmm.__version__} CPU, 1 thread, pinned to one "
             f"core: {pinned}; copies {args.spacing_nm:g} nm apart along x"
             + (f"; built start at {args.turns:g} turns, minimised" if args.turns is not None
                else ""),
             f"# one replica per Context: {base:.0f} steps/s ({1e3 / base:.4f} ms/step)",
             f"{'R':>4} {'steps/s':>9} {'ms/step':>8} {'replica-steps/s':>16} "
             f"{'gain vs separate':>17} {'ns/particle/step':>17}"]
    for R in args.replicas:
        sysR = replicate_system(model.system, R, model.rebuild_forces)
        offs = (np.arange(R) - 0.5 * (R - 1)) * args.spacing_nm
        posR = np.concatenate([pos0 + np.array([o, 0.0, 0.0]) for o in offs])
        ctx, integ = _context(sysR, posR, dt_ps, scene.temperature_K)
        if args.turns is not None:
            ctx.setParameter("trap_angle", 2 * np.pi * args.turns)
        rate = _rate(integ, max(200, args.steps // R))
        p = ctx.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(u.nanometer)
        xs = [p[r * N:(r + 1) * N, 0] - offs[r] for r in range(R)]
        # the copies stayed apart (their excluded volume never met)
        gap = min(offs[r + 1] + xs[r + 1].min() - (offs[r] + xs[r].max())
                  for r in range(R - 1)) if R > 1 else float("inf")
        lines.append(f"{R:>4} {rate:>9.0f} {1e3 / rate:>8.4f} {R * rate:>16.0f} "
                     f"{R * rate / base:>17.2f} {1e9 / (rate * R * N):>17.0f}"
                     + ("" if gap > 10 else f"   (copies came within {gap:.1f} nm)"))
        del ctx, integ
    text = "\n".join(lines) + "\n"
    print(text)
    pathlib.Path(args.out).write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
