"""Hat curves (extension against turns) at a slow and a fast turn ramp, to expose hysteresis.

    python workflows/turns_sweep.py                     # small defaults, ~1 min on 2 cores
    python workflows/turns_sweep.py --max-turns 4 --turn-rate 2e-5 1e-3 --steps 50000

Forward and backward: the tweezer protocol (dnabraid/protocols.py) runs a scene's turn
values as branches that start at the value nearest 0 and go outwards (0 -> +N, then from
the saved state at 0 -> -N), and a scene's turn values are a *set* (distinct, order
ignored). A reversed turn list therefore runs exactly the same schedule, and a descending
branch (+N -> 0) cannot be expressed as a sweep point. What this script does instead:
each point is a full hat curve -N..+N whose two branches are both ramped away from 0, so
the curve compares winding right-handed with winding left-handed; and the ramp speed
(turn_rate, grid key) is swept, so a branch that lags the trap (out of equilibrium) shows
up as a rate-dependent extension. A true unwinding branch needs an ordered-schedule option
in protocols.py (not part of the sweep machinery).
"""

import argparse

from dnabraid import sweep
from dnabraid.cli import run_sweep_verbose


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--max-turns", type=int, default=3, help="turns -N..N")
    p.add_argument("--turn-rate", type=float, nargs="+", default=[5e-5, 3e-4],
                   help="turn_rate values (turns/step)")
    p.add_argument("--force", type=float, default=2.0, help="force_pN")
    p.add_argument("--salt", type=float, default=150.0, help="salt_mM")
    p.add_argument("--length", type=float, default=90.0, help="length_nm")
    p.add_argument("--steps", type=int, default=5000, help="sampling steps per turn value")
    p.add_argument("--equilibration", type=int, default=0,
                   help="equilibration steps after each ramp (0 exposes the lag)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="runs/turns_sweep")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--scheduler", default=None, help="Dask scheduler address")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    a = p.parse_args(argv)
    n = a.max_turns
    spec = sweep.load_spec({
        "scene": "braid",
        "fixed": sweep.quick_braid_fixed(turns=n, steps=a.steps, seed=a.seed, length_nm=a.length,
                                   force_pN=a.force, salt_mM=a.salt,
                                   equilibration_steps=a.equilibration, turn_rate=None),
        "grid": {"turn_rate": a.turn_rate},
    }, out=a.out)
    res = run_sweep_verbose(spec, workers=a.workers, scheduler=a.scheduler, quiet=a.quiet)
    return 1 if res.failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
