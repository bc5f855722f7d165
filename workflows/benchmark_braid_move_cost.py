"""Cost of each braid move kind on the long braid (moves alone, one core), with and without
the topology pre-test (dnabraid.kernels.braid_moves.no_passage), interleaved in one
process so that the ratio is measured under the same load.

Each kind is run alone (weight 1, the others 0) from one configuration equilibrated by
all kinds; both variants take the same seed, so they make the same decisions (the
pre-test only skips Gauss sums whose answer it knows: tests/test_kernels_braid.py) and
differ only in time. Printed and written: us per attempted move for each variant, their
ratio, acceptance and the number refused by the topology check, and the mixture's mean
cost at the scene's kind weights.

With ``--segments``: instead of the pre-test comparison, each kind's cost with the bead
WCA between the strands, with the capsule contact, and with the capsule contact and the
chiral term (alpha = ``--alpha``; dnabraid.kernels.segment_terms), the three interleaved per kind.

Usage: python workflows/benchmark_braid_move_cost.py [--turns 0 2] [--moves 20000]
       [--repeats 3] [--segments [--alpha 2]]
Writes workflows/results/benchmark_braid_move_cost.txt (appends).
"""

from __future__ import annotations

import argparse
import datetime
import os
import pathlib
import time

import numpy as np

from dnabraid.run.chain_moves import BRAID_KINDS, BraidMoves
from dnabraid.scenes import make_scene
from dnabraid.scenes.braid import LONG_BRAID

HERE = pathlib.Path(__file__).resolve().parent
WEIGHTS = (4.0, 4.0, 0.5, 0.5, 1.0, 2.0, 1.0, 2.0, 2.0)  # BraidMoves' default mixture


def _amps(sc) -> dict:
    return dict(crank_angle_rad=sc.crank_angle_rad, bead_move_nm=sc.bead_move_nm,
                shear_nm=sc.shear_nm, shear_z_nm=sc.shear_z_nm, twist_rad=sc.twist_rad,
                sway_rad=sc.sway_rad, pivot_rad=sc.pivot_rad, tilt_rad=sc.tilt_rad,
                stretch_eps=sc.stretch_eps, breathe_eps=sc.breathe_eps,
                breathe_max_beads=sc.breathe_max_beads, crank_max_beads=sc.crank_max_beads)


def _equilibrated(turns: float, **keys):
    """The long braid at ``turns`` (scene ``keys`` added), its model, a state after 1e5
    moves of all kinds, and its local energy."""
    # pinned: the braid's default trap is K = 2000 since 2026-12-06; the stored costs and
    # acceptances were measured in the stiff trap of the time
    sc = make_scene("braid", dict(LONG_BRAID, turns=[turns], replicas=1,
                                  trap_stiffness_pN_nm=20000.0, **keys))
    m = sc.build()
    pos = np.array(sc.start_positions(m, turns), float)
    mv = BraidMoves.for_model(m, moves_per_call=2000, seed=1, guard_every=0, **_amps(sc))
    mv.energy.set_trap_angle(2 * np.pi * turns)
    for _ in range(50):
        pos, _ = mv.run(pos)
    return sc, m, pos, mv.energy


def table(turns: float, moves: int, repeats: int) -> list[str]:
    sc, m, pos, _ = _equilibrated(turns)
    lines = [f"turns {turns:g}: {'kind':>10} {'us/move pre-test':>16} {'us/move Gauss only':>18} "
             f"{'ratio':>6} {'acceptance':>10} {'refused':>8}"]
    cost = {True: 0.0, False: 0.0}
    for k, name in enumerate(BRAID_KINDS):
        w = [0.0] * len(BRAID_KINDS)
        w[k] = 1.0
        best = {True: np.inf, False: np.inf}
        stats = None
        for _ in range(repeats):
            for pt in (True, False):
                mk = BraidMoves.for_model(m, moves_per_call=moves, seed=2, guard_every=0,
                                          weights=w, passage_test=pt, **_amps(sc))
                mk.energy.set_trap_angle(2 * np.pi * turns)
                mk.run(pos.copy(), 200)  # compile, warm
                t0 = time.perf_counter()
                mk.run(pos.copy(), moves)
                best[pt] = min(best[pt], (time.perf_counter() - t0) / moves * 1e6)
                stats = mk.stats[name].to_dict()
        for pt in cost:
            cost[pt] += WEIGHTS[k] * best[pt] / sum(WEIGHTS)
        lines.append(f"{'':8}{name:>10} {best[True]:16.1f} {best[False]:18.1f} "
                     f"{best[False] / best[True]:6.2f} {stats['acceptance']:10.2f} "
                     f"{stats['refused_by_constraint']:8d}")
    lines.append(f"{'':8}{'mixture':>10} {cost[True]:16.1f} {cost[False]:18.1f} "
                 f"{cost[False] / cost[True]:6.2f}   (kind weights {WEIGHTS})")
    return lines


def segments_table(turns: float, moves: int, repeats: int, alpha: float) -> list[str]:
    """Per kind: us per move with the bead WCA, the capsules, the capsules + chiral term."""
    variants = {"beads": {}, "capsules": {"contact": "capsules"},
                f"capsules+chiral {alpha:g} pN": {"contact": "capsules", "alpha": alpha}}
    built = {name: _equilibrated(turns, **kw) for name, kw in variants.items()}
    names = list(variants)
    lines = [f"turns {turns:g}: {'kind':>10} " + " ".join(f"{n:>24}" for n in names)
             + "  (us per move; acceptance)"]
    cost = dict.fromkeys(names, 0.0)
    for k, kind in enumerate(BRAID_KINDS):
        w = [0.0] * len(BRAID_KINDS)
        w[k] = 1.0
        best = dict.fromkeys(names, np.inf)
        acc = {}
        for _ in range(repeats):
            for name in names:
                sc, m, pos, le = built[name]
                mk = BraidMoves(le, m.chains, m.fixed, m.bead_center, m.dna.kT,
                                moves_per_call=moves, seed=2, guard_every=0, weights=w,
                                **_amps(sc))
                mk.run(pos.copy(), 200)
                t0 = time.perf_counter()
                mk.run(pos.copy(), moves)
                best[name] = min(best[name], (time.perf_counter() - t0) / moves * 1e6)
                acc[name] = mk.stats[kind].to_dict()["acceptance"]
        for name in names:
            cost[name] += WEIGHTS[k] * best[name] / sum(WEIGHTS)
        lines.append(f"{'':8}{kind:>10} " + " ".join(f"{best[n]:17.1f} ({acc[n]:.2f})"
                                                     for n in names))
    lines.append(f"{'':8}{'mixture':>10} " + " ".join(f"{cost[n]:24.1f}" for n in names)
                 + f"   (kind weights {WEIGHTS})")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--turns", type=float, nargs="+", default=[0.0, 2.0])
    ap.add_argument("--moves", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=3, help="best of this many timings")
    ap.add_argument("--segments", action="store_true",
                    help="compare bead WCA, capsules, capsules + chiral term instead")
    ap.add_argument("--alpha", type=float, default=2.0, help="alpha of --segments (pN)")
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_braid_move_cost.txt"))
    a = ap.parse_args(argv)
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    head = [f"# braid move cost, long braid {LONG_BRAID}, {stamp}; {os.cpu_count()} cores (load average at start {os.getloadavg()[0]:.1f}); "
            f"{a.moves} moves per kind and variant, best of {a.repeats}; WCA change of "
            "non-rigid moves of > 24 particles by z sweeps (kernels.chain) in both variants"]
    print(head[0], flush=True)
    lines = list(head)
    for n in a.turns:
        t = (segments_table(n, a.moves, a.repeats, a.alpha) if a.segments
             else table(n, a.moves, a.repeats))
        print("\n".join(t), flush=True)
        lines += t
    out = pathlib.Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "a") as fh:
        fh.write("\n".join(lines) + "\n\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
