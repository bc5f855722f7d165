"""Braid extension against turns at several salt concentrations (one sweep point per salt).

    python workflows/salt_sweep.py                      # small defaults, ~1-2 min on 2 cores
    python workflows/salt_sweep.py --salt 10 100 1000 --steps 50000 --out runs/salt

Higher salt screens the DNA charge: a thinner effective diameter (Stigter 1977) lets the
strands wrap more tightly, so the braid shortens less per turn. Writes <out>/results.csv
and <out>/sweep.png; rerunning resumes (finished points are not run again).
"""

import argparse

from dnabraid import sweep
from dnabraid.cli import run_sweep_verbose


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--salt", type=float, nargs="+", default=[50, 150, 1000], help="salt_mM values")
    p.add_argument("--force", type=float, default=2.0, help="force_pN")
    p.add_argument("--turns", type=int, default=2, help="turns -N..N")
    p.add_argument("--length", type=float, default=90.0, help="length_nm")
    p.add_argument("--steps", type=int, default=10000, help="sampling steps per turn value")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="runs/salt_sweep")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address")
    a = p.parse_args(argv)
    spec = sweep.load_spec({
        "scene": "braid",
        "fixed": sweep.quick_braid_fixed(turns=a.turns, steps=a.steps, seed=a.seed,
                                   length_nm=a.length, force_pN=a.force),
        "grid": {"salt_mM": a.salt},
    }, out=a.out)
    res = run_sweep_verbose(spec, workers=a.workers, scheduler=a.scheduler, quiet=a.quiet)
    return 1 if res.failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
