"""Braid extension against turns at several pulling forces (one sweep point per force).

    python workflows/force_sweep.py                     # small defaults, ~1 min on 2 cores
    python workflows/force_sweep.py --force 0.5 1 2 4 --steps 50000 --out runs/force

A larger force stretches the unbraided molecules further and makes each turn of braiding
cost more extension (the hat curve gets steeper). Writes <out>/results.csv and
<out>/sweep.png; rerunning resumes.
"""

import argparse

from dnabraid import sweep
from dnabraid.cli import run_sweep_verbose


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--force", type=float, nargs="+", default=[0.5, 2.0, 8.0], help="force_pN values")
    p.add_argument("--salt", type=float, default=150.0, help="salt_mM")
    p.add_argument("--turns", type=int, default=2, help="turns -N..N")
    p.add_argument("--length", type=float, default=90.0, help="length_nm")
    p.add_argument("--steps", type=int, default=10000, help="sampling steps per turn value")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="runs/force_sweep")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--scheduler", default=None, help="Dask scheduler address")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    a = p.parse_args(argv)
    spec = sweep.load_spec({
        "scene": "braid",
        "fixed": sweep.quick_braid_fixed(turns=a.turns, steps=a.steps, seed=a.seed,
                                   length_nm=a.length, salt_mM=a.salt),
        "grid": {"force_pN": a.force},
    }, out=a.out)
    res = run_sweep_verbose(spec, workers=a.workers, scheduler=a.scheduler, quiet=a.quiet)
    return 1 if res.failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
