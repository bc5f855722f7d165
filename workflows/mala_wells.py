"""Time-step bias of the three Brownian integrators on wells with exact answers.

Euler-Maruyama ('euler'), Leimkuhler-Matthews ('lm') and Metropolis-adjusted Euler-
Maruyama ('mala': Rossky, Doll & Friedman, J. Chem. Phys. 69, 4628 (1978)) sample
<x^2> in three wells whose Boltzmann moment is known exactly:

* harmonic, U = k r^2 / 2: kT / k (Euler-Maruyama's variance is inflated by exactly
  1 / (1 - h / 2), h = dt mu k; LM is exact here);
* log-cosh, U = c sum ln cosh(x / w): quadrature (anharmonic, bounded force: Euler-
  Maruyama stays stable at any step);
* quartic, U = a sum x^4: (kT / a)^(1/2) G(3/4) / G(1/4) (cubic force: Euler-Maruyama and
  LM blow up at large steps).

h is dt times the mobility times the largest (log-cosh: c / w^2) or the mean (quartic:
12 a <x^2>) curvature. Four particles (12 degrees of freedom), OpenMM's Reference platform,
errors from 40 blocks. Writes ``workflows/results/mala_wells.md``.

    python workflows/mala_wells.py [--samples 16000] [--seed 11]
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from test_mala import (KT, MOB, blocked_mean_se, boltzmann_x2,  # noqa: E402
                       harmonic_system, logcosh_system, quartic_system, sample_x2)


def wells():
    k = 1000.0
    c, w = 4.0 * KT, 0.1
    a = 2.0e4
    lc = boltzmann_x2(lambda x: c * (abs(x / w) + math.log1p(math.exp(-2 * abs(x / w)))
                                     - math.log(2.0)))
    q = math.sqrt(KT / a) * math.gamma(0.75) / math.gamma(0.25)
    return [("harmonic", lambda: harmonic_system(4, k), KT / k, k),
            ("log-cosh", lambda: logcosh_system(4, c, w), lc, c / w**2),
            ("quartic", lambda: quartic_system(4, a), q, 12 * a * q)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--samples", type=int, default=16000)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--steps", type=float, nargs="+", default=[0.3, 0.7, 1.0, 1.5])
    a = ap.parse_args(argv)
    from dnabraid.run.engine import SimulationBlowUp

    lines = ["# Time-step bias of the Brownian integrators on exact wells", "",
             f"`python workflows/mala_wells.py --samples {a.samples} --seed {a.seed}` "
             f"({time.strftime('%Y-%m-%d %H:%M')}): <x^2> / exact, +- its blocked standard "
             "error (40 blocks), 4 particles, 5 steps per sample; acceptance of mala's "
             "steps in brackets. 'blew up': SimulationBlowUp (non-finite positions); 'stuck': "
             "mala refused (nearly) every proposal from the start, its mean is the start's "
             "(a run's verdict refuses a replica whose observable stayed constant).", "",
             "| well | h | euler | lm | mala (acceptance) |", "|---|---|---|---|---|"]
    for name, make, exact, curv in wells():
        start = np.random.default_rng(3).normal(size=(4, 3)) * math.sqrt(exact)
        for h in a.steps:
            cells = []
            for integ in ("euler", "lm", "mala"):
                try:
                    x2, eng = sample_x2(make(), start, h / (MOB * curv), integ, a.samples, 5,
                                        seed=a.seed)
                except SimulationBlowUp:
                    cells.append("blew up")
                    continue
                m, se = blocked_mean_se(x2)
                cell = f"{m / exact:.4f} +- {se / exact:.4f}"
                if integ == "mala":
                    acc, tried = eng.mala_acceptance()
                    cell += f" ({acc / tried:.2f})"
                    if acc < 0.01 * tried:
                        # every proposal from the start overshoots: the chain has not
                        # moved, its "mean" is the start (a run's verdict refuses it)
                        cell = f"stuck at the start ({acc / tried:.3f})"
                cells.append(cell)
            row = f"| {name} | {h:g} | " + " | ".join(cells) + " |"
            print(row, flush=True)
            lines.append(row)
    out = HERE / "results" / "mala_wells.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
