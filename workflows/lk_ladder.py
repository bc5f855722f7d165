"""Replica exchange over the trap angle for the plectoneme past buckling: a prototype run.

One ladder of moves-only chains (the scene's own moves and energy, as in
``plectoneme_mc_reference.py``) at trap angles theta_k = 2 pi n_low + k D, D = 2 pi / per_turn,
up to 2 pi n_high, so the integer turns sit on rungs. Each rung's chain is ramped from 0 to
theta_k (400 stages) from the seed's exact WLC start and equilibrated; then rounds of
``--round-moves`` moves per rung alternate with swap attempts between neighbouring rungs
(even pairs, then odd), each swap mapped so that the bead's turn is spread over the frames
(:func:`dnabraid.run.ladder.swap_map`, :class:`dnabraid.run.ladder.TrapLadder`; acceptance
on the full energy, detailed balance kept: the map is volume-preserving and T_-D is its
inverse). The stored results (docs/validation.md 2.3n) were made by this script's own copy
of the loop before it moved into the library (same moves, map and schedule; other swap
draws). ``dnabraid run plectoneme --set sampler=ladder`` runs ladders as replicas with
verdicts (2.3o). Below buckling the moves mix well, so
states mixed at n_low climb the ladder; the slow tail-plectoneme exchange at n_high is
bypassed.

Reported per rung: <z>, its error from batch means (``--batches`` of the sampling rounds;
a lower bound where a batch is shorter than the rung's slow mode), <Tw>, the swap
acceptance to the next rung, and the number of ladder round trips (a replica that went from
the lowest rung to the highest and back). Integer turns are compared with the stored
moves-only reference (``plectoneme_mc_reference_L<L>_F<F>.json``), where present.

    python workflows/lk_ladder.py --seeds 1 2 --budget 1200

Writes ``workflows/results/lk_ladder_L<L>_F<F>.{json,txt}`` (a seed's ladder replaced on a
rerun).
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
EQ_MOVES = 200_000  # per rung after the reference's ramp (plectoneme_mc_reference.ramp)


def ladder(args) -> dict:
    from dnabraid.geometry.ribbon import tether_twist, writhe_open
    from dnabraid.run.ladder import TrapLadder

    n_low, n_high, per_turn, length, force, seed, budget, round_moves, batches = args
    d = 2 * math.pi / per_turn
    rungs = int(round((n_high - n_low) * per_turn)) + 1
    turns = [n_low + k * d / (2 * math.pi) for k in range(rungs)]
    K = len(turns)
    import plectoneme_mc_reference as ref

    _, m, mv = ref.moves_chain(n_high, length, force, seed)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
    # the library's ladder (dnabraid.run.ladder; the frames turn with the bead, sign +1 of
    # lk_exchange.py); swap draws seeded 1000 + seed
    lad = TrapLadder(mv, c, sides, mo, turns, m.dna.kT, seed=1000 + seed)
    start = np.array(m.positions)
    t0 = time.process_time()
    lad.pos = [ref.ramp(mv, start.copy(), th, EQ_MOVES) for th in lad.thetas]
    t_ramp = time.process_time() - t0
    z, tw = [], []
    t1 = time.process_time()
    while time.process_time() - t1 < budget:
        lad.round(round_moves)
        z.append([float(p[c[-1], 2] - p[c[0], 2]) for p in lad.pos])
        if lad.rounds % 5 == 1:
            tw.append([tether_twist(p[c], p[sides], p[mo] - p[c[-1]]) for p in lad.pos])
    cpu = time.process_time() - t1
    r = lad.rounds
    # Tw + Wr on each rung at the end must equal its turns (no strand passage, no slip)
    lk_end = [tether_twist(p[c], p[sides], p[mo] - p[c[-1]]) + writhe_open(p[c])
              for p in lad.pos]
    z = np.array(z)
    nb = len(z) // batches
    bm = z[:nb * batches].reshape(batches, nb, K).mean(axis=1)
    return {"seed": seed, "thetas": lad.thetas, "turns": turns,
            "rounds": r, "round_moves": round_moves, "cpu_s": cpu, "cpu_ramp_eq_s": t_ramp,
            "z_mean": z.mean(axis=0).tolist(),
            "z_sem_batches": (bm.std(axis=0, ddof=1) / math.sqrt(batches)).tolist(),
            "tw_mean": np.array(tw).mean(axis=0).tolist(),
            "acceptance": [a or 0.0 for a in lad.acceptance()],
            "round_trips": lad.round_trips, "lk_end": lk_end,
            "sign": 1.0, "us_per_move": 1e6 * cpu / (r * round_moves * K)}


def table(store: dict, ref: dict | None) -> list[str]:
    lines = [f"# replica-exchange ladder over the trap angle (workflows/lk_ladder.py): "
             f"plectoneme L = {store['length_nm']} nm, F = {store['force_pN']} pN; z in nm, "
             "+- from batch means (a lower bound if a batch is shorter than the slow mode); "
             "acc: swap acceptance to the next rung; reference: moves-only chains (2.3l)"]
    for lad in sorted(store["ladders"], key=lambda x: x["seed"]):
        lines.append(f"seed {lad['seed']}: {len(lad['turns'])} rungs, {lad['rounds']} rounds of "
                     f"{lad['round_moves']} moves per rung, {lad['cpu_s']:.0f} CPU s sampling "
                     f"(+{lad['cpu_ramp_eq_s']:.0f} ramp), {lad['us_per_move']:.1f} us/move, "
                     f"{lad['round_trips']} round trips")
        lines.append(f"{'n':>6} {'<z>':>8} {'+-':>5} {'<Tw>':>7} {'acc':>5} {'Lk end':>7} "
                     f"{'reference':>15}")
        for k, n in enumerate(lad["turns"]):
            acc = f"{lad['acceptance'][k]:5.2f}" if k < len(lad["acceptance"]) else f"{'':5}"
            rf = ""
            key = f"{n:g}"
            if ref and abs(n - round(n)) < 1e-9 and key in ref:
                rf = f"{ref[key][0]:8.2f} +-{ref[key][1]:4.2f}"
            lines.append(f"{n:6.3f} {lad['z_mean'][k]:8.2f} {lad['z_sem_batches'][k]:5.2f} "
                         f"{lad['tw_mean'][k]:7.4f} {acc} {lad['lk_end'][k]:7.3f} {rf:>15}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-low", type=float, default=3.0)
    ap.add_argument("--n-high", type=float, default=6.0)
    ap.add_argument("--per-turn", type=int, default=6, help="rungs per turn (D = 2 pi / this)")
    ap.add_argument("--length", type=float, default=300.0, help="nm")
    ap.add_argument("--force", type=float, default=1.0, help="pN")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--budget", type=float, default=1200.0, help="CPU s of sampling per ladder")
    ap.add_argument("--round-moves", type=int, default=1000)
    ap.add_argument("--batches", type=int, default=10)
    a = ap.parse_args(argv)
    base = os.path.join(HERE, "results", f"lk_ladder_L{a.length:g}_F{a.force:g}")
    store = {"length_nm": a.length, "force_pN": a.force, "ladders": []}
    if os.path.exists(base + ".json"):
        with open(base + ".json") as fh:
            store = json.load(fh)
    jobs = [(a.n_low, a.n_high, a.per_turn, a.length, a.force, sd, a.budget, a.round_moves,
             a.batches) for sd in a.seeds]
    with mp.get_context("spawn").Pool(min(os.cpu_count() or 1, len(jobs))) as pool:
        for res in pool.imap(ladder, jobs):
            store["ladders"] = [x for x in store["ladders"] if x["seed"] != res["seed"]] + [res]
            with open(base + ".json", "w") as fh:  # no lost results: after every ladder
                json.dump(store, fh)
            print(f"ladder seed {res['seed']} done", flush=True)
    ref = None
    rpath = os.path.join(HERE, "results",
                         f"plectoneme_mc_reference_L{a.length:g}_F{a.force:g}.json")
    if os.path.exists(rpath):
        import plectoneme_mc_reference as pr
        with open(rpath) as fh:
            rs = json.load(fh)
        ref = {}
        for key, pt in rs["points"].items():
            p = pr.pooled(pt["chains"])
            ref[key] = (p["z_mean"], p["z_sem"])
    lines = table(store, ref)
    print("\n".join(lines))
    with open(base + ".txt", "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
