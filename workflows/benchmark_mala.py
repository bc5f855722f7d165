"""Cost and acceptance of the Brownian integrators on each thermal scene's default model.

For every scene (its defaults; one replica, one Context, one CPU thread) and integrator
('euler': OpenMM's BrownianIntegrator, 'lm', 'mala'), the time per step over a block of
steps after a warm-up, and for 'mala' the acceptance at the default timestep_safety and at
half of it. Prints a table and writes ``workflows/results/benchmark_mala.txt``.

    python workflows/benchmark_mala.py [--steps 5000] [--platform CPU]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import time

from dnabraid.run.engine import Engine
from dnabraid.scenes import make_scene

SCENES = {"braid": {}, "tether": {}, "plectoneme": {}, "catenane": {}}


def measure(name, over, integrator, steps, platform):
    sc = make_scene(name, over)
    model = sc.build()
    eng = Engine.for_model(model, integrator=integrator, seed=2, platform=platform, threads=1)
    eng.advance(min(steps, 2000))
    a0 = eng.mala_acceptance()
    t0 = time.perf_counter()
    eng.advance(steps)
    us = (time.perf_counter() - t0) / steps * 1e6
    acc = None
    if a0 is not None:
        a1 = eng.mala_acceptance()
        acc = (a1[0] - a0[0]) / max(1, a1[1] - a0[1])
    return sc.timestep_safety, model.timestep.time_step_ns * 1e3, us, acc, \
        model.system.getNumParticles()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--platform", default="CPU")
    a = ap.parse_args(argv)
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    except (AttributeError, OSError):
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    head = (f"# Brownian integrators per scene default, {time.strftime('%Y-%m-%d %H:%M')}; "
            f"platform {a.platform}, one pinned core, one thread; {a.steps} steps after a "
            f"warm-up; load average at start {load:.1f}")
    rows = [head, f"{'scene':>11} {'beads':>6} {'safety':>7} {'dt ps':>8} {'euler us':>9} "
            f"{'lm us':>7} {'mala us':>8} {'mala/euler':>10} {'acceptance':>10} "
            f"{'acc. at safety/2':>16}"]
    print(rows[0])
    print(rows[1])
    for name, over in SCENES.items():
        res = {i: measure(name, over, i, a.steps, a.platform) for i in ("euler", "lm", "mala")}
        safety, dt, _, acc, n = res["mala"]
        half = measure(name, dict(over, timestep_safety=safety / 2), "mala", a.steps,
                       a.platform)[3]
        line = (f"{name:>11} {n:>6} {safety:>7g} {dt:>8.3g} {res['euler'][2]:>9.1f} "
                f"{res['lm'][2]:>7.1f} {res['mala'][2]:>8.1f} "
                f"{res['mala'][2] / res['euler'][2]:>10.2f} {acc:>10.3f} {half:>16.3f}")
        print(line, flush=True)
        rows.append(line)
    out = pathlib.Path(__file__).resolve().parent / "results" / "benchmark_mala.txt"
    with open(out, "a") as fh:
        fh.write("\n".join(rows) + "\n\n")
    print(f"appended to {out}")


if __name__ == "__main__":
    main()
