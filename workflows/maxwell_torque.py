"""Bead torque from extensions (Maxwell relation) against the trap torque, on a force sweep.

Runs the braid (default geometry unless overridden: 2 x 200 nm, tethers 40 nm, 150 mM) at
several forces and turns -2 ... 2, then forms Gamma(n, F) - Gamma(n, F_ref) two ways:

* plain: the measured trap torques' difference, errors added in quadrature;
* Maxwell: -(1/2 pi) int_{F_ref}^{F} dz/dn dF' from the measured extensions
  (dnabraid.analysis.maxwell.torque_from_extension, exact linear error propagation).

Both are differences between forces at fixed n: the relation says nothing about the torque
at the reference force. Every point is NOT CONVERGED (docs/slow_modes.md); the errors are the
scatter of overdispersed replicas, so this compares estimators, not equilibrium answers.

Usage: python workflows/maxwell_torque.py [--forces 1.5 2 2.5 3] [--steps 40000]
Writes workflows/results/maxwell_torque.md and .json.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

import numpy as np

from dnabraid.analysis.maxwell import torque_from_extension
from dnabraid.scenes import make_scene
from dnabraid.scenes.braid import LONG_BRAID

HERE = pathlib.Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--forces", type=float, nargs="+", default=[1.5, 2.0, 2.5, 3.0])
    ap.add_argument("--turns", type=float, nargs="+", default=[-2.0, -1.0, 0.0, 1.0, 2.0])
    ap.add_argument("--steps", type=int, default=40_000)
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--out", default="runs/maxwell_torque")
    ap.add_argument("--table", default=str(HERE / "results" / "maxwell_torque.md"))
    args = ap.parse_args(argv)
    F, n = np.array(args.forces), np.array(args.turns)
    z = np.empty((F.size, n.size))
    zs = np.empty_like(z)
    g = np.empty_like(z)
    gs = np.empty_like(z)
    wall = 0.0
    for i, f in enumerate(F):
        # the long braid (the default before 2026-12-01), which the table was measured on
        sc = make_scene("braid", {**LONG_BRAID, "force_pN": float(f), "turns": list(n),
                                  "steps": args.steps,
                                  "equilibration_steps": args.steps // 4,
                                  "replicas": args.replicas, "seed": 3,
                                  # pinned: the braid's default has moves and K = 2000
                                  # since 2026-12-06; the table is BD in the stiff trap
                                  "mc_moves": 0, "trap_stiffness_pN_nm": 20000.0})
        t0 = time.perf_counter()
        summ = sc.run(str(pathlib.Path(args.out) / f"F{f:g}"))
        wall += time.perf_counter() - t0
        for j, p in enumerate(summ["points"]):
            z[i, j], zs[i, j] = p["extension_nm"]["mean"], p["extension_nm"]["sem"]
            g[i, j], gs[i, j] = p["torque_pN_nm"]["mean"], p["torque_pN_nm"]["sem"]
    mx = torque_from_extension(F, n, z, np.zeros(n.size), extension_sem_nm=zs)
    plain = g - g[0]
    plain_se = np.sqrt(gs**2 + gs[0] ** 2)
    lines = [f"# Torque differences from the Maxwell relation vs the trap ({time.strftime('%Y-%m-%d %H:%M')})",
             "", f"`python workflows/maxwell_torque.py`: default braid, forces {', '.join(f'{x:g}' for x in F)} pN, "
             f"{args.replicas} replicas x ({args.steps // 4} + {args.steps} steps) per point, "
             f"seed 3; wall {wall:.0f} s on 2 cores. Gamma(n, F) - Gamma(n, {F[0]:g} pN) in "
             "pN nm. All points NOT CONVERGED: an estimator comparison, not equilibrium "
             "values.", "",
             "| F (pN) | n | plain (trap) | Maxwell (extensions) | SE ratio plain / Maxwell |",
             "|---|---|---|---|---|"]
    for i in range(1, F.size):
        for j in range(n.size):
            lines.append(f"| {F[i]:g} | {n[j]:+g} | {plain[i, j]:+.1f} +- {plain_se[i, j]:.1f} | "
                         f"{mx['torque_pN_nm'][i, j]:+.2f} +- {mx['sem_pN_nm'][i, j]:.2f} | "
                         f"{plain_se[i, j] / mx['sem_pN_nm'][i, j]:.0f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    p = pathlib.Path(args.table)
    p.write_text(text)
    p.with_suffix(".json").write_text(json.dumps(
        {"forces_pN": F.tolist(), "turns": n.tolist(), "extension_nm": z.tolist(),
         "extension_sem_nm": zs.tolist(), "torque_pN_nm": g.tolist(), "torque_sem_pN_nm": gs.tolist(),
         "maxwell_difference_pN_nm": mx["torque_pN_nm"].tolist(),
         "maxwell_sem_pN_nm": mx["sem_pN_nm"].tolist(), "wall_s": wall}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
