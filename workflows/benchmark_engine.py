"""Benchmark the engine: steps/s, ms/step and ns per bead per step.

For braids of 2 x {50, 200, 800} beads: the full nicked-braid force field (bonds, bending,
WCA, wall, pull, trap) against the same beads with bonds only; also rigid-bond
constraints instead of springs, and the WCA neighbour-list cutoff. Twisted rows: one
torsionally constrained tether of {50, 200, 800} beads (plectoneme scene: side particle
per bond, twist energy, bead frame) against the same scene with the twist terms and
frame springs removed (the cost of twist). Prints a table and
writes it to workflows/results/benchmark_engine.txt.

Run pinned to one core for the numbers the CLI uses (it pins itself):
    taskset -c 0 python workflows/benchmark_engine.py
"""

from __future__ import annotations

import argparse
import os
import time

import openmm
from openmm import unit as u

from dnabraid.scenes import make_scene

KEEP_BONDS_ONLY = {"stretch", "link"}


TWIST_TERMS = ("twist", "twist_anchor", "twist_bead", "frame")


def time_model(model, keep=None, steps=2000, platform="CPU", wca_cutoff=None, drop=()):
    system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(model.system))
    for i in reversed(range(system.getNumForces())):
        f = system.getForce(i)
        if (keep is not None and f.getName() not in keep) or f.getName() in drop:
            system.removeForce(i)
        elif wca_cutoff and f.getName() == "wca":
            f.setCutoffDistance(wca_cutoff * model.params["diameter_nm"])
    dt = model.timestep.time_step_ns * 1e3
    integ = openmm.BrownianIntegrator(298.15 * u.kelvin, 1 / u.picosecond, dt * u.picoseconds)
    props = {"Threads": "1"} if platform == "CPU" else {}
    ctx = openmm.Context(system, integ, openmm.Platform.getPlatformByName(platform), props)
    ctx.setPositions(model.positions * u.nanometer)
    openmm.LocalEnergyMinimizer.minimize(ctx, 1.0, 500)
    integ.step(300)
    ctx.getState(getPositions=True)
    t = time.perf_counter()
    integ.step(steps)
    ctx.getState(getPositions=True)
    el = time.perf_counter() - t
    return el / steps


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--sizes", default="50,200,800")
    ap.add_argument("--platform", default="CPU")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "results",
                                                  "benchmark_engine.txt"))
    a = ap.parse_args(argv)
    rows = []
    header = (f"{'beads':>9} {'variant':<34} {'steps/s':>9} {'ms/step':>9} "
              f"{'ns/bead/step':>13} {'dt_ps':>7} {'ns_sim/s':>9}")
    print(header)
    for n in map(int, a.sizes.split(",")):
        b = 5.0
        variants = [
            ("full, bonds (default)", {}, None, None),
            ("bonds only", {}, KEEP_BONDS_ONLY, None),
            ("full, constraints", {"stretch": "constraints"}, None, None),
            ("full, bonds, WCA list cutoff 1.2s", {}, None, 1.2),
        ]
        for name, over, keep, cut in variants:
            # pinned: the braid's default has moves since 2026-12-06; this benchmark times
            # Brownian dynamics (and moves refuse stretch = 'constraints')
            s = make_scene("braid", {"length_nm": (n - 1) * b, "bead_spacing_nm": b,
                                     "mc_moves": 0, **over})
            m = s.build()
            sec = time_model(m, keep=keep, steps=a.steps, platform=a.platform, wca_cutoff=cut)
            npart = m.system.getNumParticles()
            dt_ps = m.timestep.time_step_ns * 1e3
            row = (f"{'2x' + str(n):>9} {name:<34} {1 / sec:>9.0f} {sec * 1e3:>9.4f} "
                   f"{sec / npart * 1e9:>13.0f} {dt_ps:>7.1f} {dt_ps * 1e-3 / sec:>9.1f}")
            print(row, flush=True)
            rows.append(row)
        for name, drop in (("plectoneme (twisted)", ()),
                           ("plectoneme, twist+frame removed", TWIST_TERMS)):
            s = make_scene("plectoneme", {"length_nm": (n - 1) * b, "bead_spacing_nm": b})
            m = s.build()
            sec = time_model(m, steps=a.steps, platform=a.platform, drop=drop)
            npart = m.system.getNumParticles()
            dt_ps = m.timestep.time_step_ns * 1e3
            row = (f"{'1x' + str(n):>9} {name:<34} {1 / sec:>9.0f} {sec * 1e3:>9.4f} "
                   f"{sec / npart * 1e9:>13.0f} {dt_ps:>7.1f} {dt_ps * 1e-3 / sec:>9.1f}")
            print(row, flush=True)
            rows.append(row)
    pinned = len(os.sched_getaffinity(0)) == 1
    with open(a.out, "w") as fh:
        fh.write(f"# platform {a.platform}, OpenMM {openmm.__version__}, pinned to one core: "
                 f"{pinned}; ns_sim/s = simulated ns per wall second\n")
        fh.write(header + "\n" + "\n".join(rows) + "\n")
    print(f"written to {a.out}")


if __name__ == "__main__":
    main()
