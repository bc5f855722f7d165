"""Which slow modes of the braid the Metropolis moves reach: moves alone (no dynamics) on
a built braid, integrated autocorrelation times (in samples) of the bead centre's height
and horizontal position, each strand's end-to-end distance and the distance between the
strands' midpoints, with each kind's acceptance and the cost per move.

Usage: python workflows/braid_move_modes.py [--turns 0] [--moves 200] [--samples 2000]
       [--set key=value ...]   (braid keys; default the long braid, 2 x 200 nm at 2 pN)
Appends to workflows/results/braid_move_modes.txt.
"""

from __future__ import annotations

import argparse
import datetime
import pathlib
import time

import numpy as np
import tomllib

from dnabraid.scenes import make_scene
from dnabraid.scenes.braid import LONG_BRAID

HERE = pathlib.Path(__file__).resolve().parent


def tau_int(x) -> float:
    """Integrated autocorrelation time (samples), summed to the first lag below 0.05."""
    x = np.asarray(x, float) - np.mean(x)
    n = len(x)
    ac = np.correlate(x, x, "full")[n - 1:] / (x.var() * np.arange(n, 0, -1))
    cut = int(np.argmax(ac < 0.05)) if (ac < 0.05).any() else n // 3
    return float(1 + 2 * ac[1:cut].sum())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--turns", type=float, default=0.0)
    ap.add_argument("--moves", type=int, default=200, help="moves per sample")
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--out", default=str(HERE / "results" / "braid_move_modes.txt"))
    a = ap.parse_args(argv)
    # trap pinned: the braid's default is K = 2000 since 2026-12-06; the stored rows were
    # measured in the stiff trap of the time
    keys = dict(LONG_BRAID, turns=[a.turns], mc_moves=a.moves, trap_stiffness_pN_nm=20000.0)
    for kv in a.set:
        k, v = kv.split("=", 1)
        keys[k] = tomllib.loads(f"v = {v}")["v"]
    sc = make_scene("braid", keys)
    m = sc.build()
    pos = np.array(sc.start_positions(m, a.turns), float)
    mv = m.moves
    mv.guard_every = 0
    if mv.energy.trap_angle is not None:
        mv.energy.set_trap_angle(2 * np.pi * a.turns)
    c1, c2 = (np.asarray(c) for c in m.chains)
    for _ in range(a.samples // 20):
        pos, _ = mv.run(pos)
    obs = []
    t0 = time.process_time()
    for _ in range(a.samples):
        pos, _ = mv.run(pos)
        top = pos[m.bead_center]
        obs.append((top[2], top[0], top[1], np.linalg.norm(pos[c1[-1]] - pos[c1[0]]),
                    np.linalg.norm(pos[c2[-1]] - pos[c2[0]]),
                    np.linalg.norm(pos[c1[len(c1) // 2]] - pos[c2[len(c2) // 2]])))
    cpu = time.process_time() - t0
    obs = np.array(obs)
    lines = [f"# braid move modes, {datetime.datetime.now():%Y-%m-%d %H:%M}; keys {keys}; "
             f"{a.samples} samples of {a.moves} moves; {cpu / a.samples / a.moves * 1e6:.1f} "
             "us CPU per move",
             "# acceptance " + ", ".join(f"{k} {v.to_dict()['acceptance']:.2f}"
                                         for k, v in mv.stats.items()),
             f"{'observable':>14} {'mean nm':>9} {'sd nm':>7} {'tau (samples)':>14}"]
    for name, col in zip(("centre z", "centre x", "centre y", "end-end 1", "end-end 2",
                          "mid distance"), obs.T):
        lines.append(f"{name:>14} {col.mean():9.2f} {col.std():7.2f} {tau_int(col):14.1f}")
    print("\n".join(lines))
    out = pathlib.Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "a") as fh:
        fh.write("\n".join(lines) + "\n\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
