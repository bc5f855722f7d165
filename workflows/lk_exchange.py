"""Would replica exchange over the trap angle mix the plectoneme past buckling? A measurement.

The slow mode past buckling is the exchange of contour between the tails and the plectoneme
(docs/validation.md 2.3l, 2.3m); below buckling (n <= 3 on 300 nm at 1 pN) the moves mix
well. Replicas at trap angles theta_k = 2 pi n_k could pass mixed states up a ladder. A bare
swap is refused: the trap holds the bead's angle within ~sqrt(kT / K) = 0.014 rad. This
script measures the acceptance of a swap that maps the configurations: replica j (angle
theta_i + D) receives T_D(x_i), replica i receives T_-D(x_j), where T_D turns the bead's
orientation particle by D about the vertical through its attachment and spins the frame of
bond q about its bond by s D (q + 1/2) / N (s = +1: the frames turn with the bead; s = -1
reported as the control that must fail) (a rotation of each moved particle: Jacobian 1,
T_-D its inverse), so the twist the swap adds is spread along the chain. Acceptance:
min(1, exp(-[U_j(T_D x_i) - U_i(x_i) + U_i(T_-D x_j) - U_j(x_j)] / kT)), energies from the
scene's own LocalEnergy (all terms).

For each D one moves-only chain at theta_0 + D (and one at theta_0), each ramped and
equilibrated as the moves-only reference (``plectoneme_mc_reference.py``), then sampled
every 5000 moves for ``--budget`` CPU s; sample k of one chain is paired with sample k of the
other (samples ~ 1 autocorrelation time of Tw apart, 2.3m). Reported: the mean acceptance
and its spread over pairs, and the replicas a ladder from n = 3 to n needs at that D.

    python workflows/lk_exchange.py --turns 6 --deltas 0.5 1 2 --budget 40

Writes ``workflows/results/lk_exchange_L<L>_F<F>_n<n>.{json,txt}``.
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
import plectoneme_mc_reference as ref  # noqa: E402  (the chains' scene, moves and ramp)
SAMPLE_MOVES = 5000


def _rot(v, axis, ang):
    """v rotated by ang about the unit axis (Rodrigues)."""
    c, s = math.cos(ang), math.sin(ang)
    return v * c + np.cross(axis, v) * s + axis * np.dot(axis, v) * (1 - c)


def swap_map(pos, c, sides, mo, d, sign):
    """T_d: the bead's orientation particle turned by d about z through the attachment, the
    frame of bond q spun about its bond by sign * d (q + 1/2) / N (sign +1:
    :func:`dnabraid.run.ladder.swap_map`; -1 the control: frames against the bead)."""
    from dnabraid.run.ladder import swap_map as lib_map

    if sign == 1.0:
        return lib_map(pos, c, sides, mo, d)
    out = lib_map(pos, c, sides, -1, -d)  # frames turned against the bead
    att = out[c[-1]]
    out[mo] = att + _rot(np.asarray(pos[mo]) - att, np.array([0.0, 0.0, 1.0]), d)
    return out


def chain(args) -> dict:
    """Samples of one moves-only chain at trap angle theta (positions every 5000 moves)."""
    theta, length, force, seed, budget = args
    _, m, mv = ref.moves_chain(theta / (2 * math.pi), length, force, seed)
    pos = ref.ramp(mv, np.array(m.positions), theta)
    out = []
    t0 = time.process_time()
    while time.process_time() - t0 < budget:
        pos, _ = mv.run(pos, SAMPLE_MOVES)
        out.append(np.array(pos))
    return {"theta": theta, "samples": np.array(out), "cpu_s": time.process_time() - t0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--turns", type=float, default=6.0)
    ap.add_argument("--deltas", type=float, nargs="+", default=[0.5, 1.0, 2.0], help="rad")
    ap.add_argument("--length", type=float, default=300.0, help="nm")
    ap.add_argument("--force", type=float, default=1.0, help="pN")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--budget", type=float, default=40.0, help="CPU s of sampling per chain")
    ap.add_argument("--workers", type=int, default=0)
    a = ap.parse_args(argv)
    from dnabraid.geometry.ribbon import tether_twist

    th0 = 2 * math.pi * a.turns
    jobs = [(th0, a.length, a.force, a.seed, a.budget)] + [
        (th0 + d, a.length, a.force, a.seed + 1 + k, a.budget) for k, d in enumerate(a.deltas)]
    workers = a.workers or os.cpu_count() or 1
    with mp.get_context("spawn").Pool(min(workers, len(jobs))) as pool:
        res = pool.map(chain, jobs)
    s, m, mv = ref.moves_chain(a.turns, a.length, a.force, a.seed)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
    kT = m.dna.kT

    def tw(p):
        return tether_twist(p[c], p[sides], p[mo] - p[c[-1]])

    rows = []
    base = res[0]
    for sign, d, r in [(sg, d, r) for sg in (1.0, -1.0) for d, r in zip(a.deltas, res[1:])]:
        n = min(len(base["samples"]), len(r["samples"]))
        acc, dtw = [], []
        for k in range(n):
            xi, xj = base["samples"][k], r["samples"][k]
            mv.energy.set_trap_angle(th0)
            ui, ui_new = mv.energy.total(xi), mv.energy.total(swap_map(xj, c, sides, mo, -d, sign))
            mv.energy.set_trap_angle(th0 + d)
            uj, uj_new = mv.energy.total(xj), mv.energy.total(swap_map(xi, c, sides, mo, d, sign))
            de = (uj_new - ui + ui_new - uj) / kT
            acc.append(min(1.0, math.exp(-de)) if de < 700 else 0.0)
            dtw.append(tw(xj) - tw(xi))
        acc = np.array(acc)
        p = float(acc.mean())
        # replicas from n = 3 to n at this spacing; a swap ladder of K rungs at acceptance p
        # is a random walk that needs ~K^2 / p attempted swaps per round trip
        rungs = int(math.ceil(2 * math.pi * (a.turns - 3) / d)) + 1
        rows.append({"spin_sign": sign, "delta_rad": d, "pairs": n, "acceptance": p,
                     "acceptance_sem": float(acc.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan,
                     "mean_dTw_between_chains": float(np.mean(dtw)),
                     "rungs_from_n3": rungs, "cpu_s": r["cpu_s"]})
    lines = [f"# swap acceptance of mapped replica exchange (workflows/lk_exchange.py): "
             f"plectoneme L = {a.length} nm, F = {a.force} pN, n = {a.turns}; {a.budget} CPU s "
             f"per chain, samples every {SAMPLE_MOVES} moves; spin sign +1: the frames turn "
             "with the bead (right-handed about the bond pointing up, as the bead about +z)",
             f"{'sign':>4} {'D (rad)':>8} {'pairs':>6} {'acceptance':>18} {'<Tw_j - Tw_i>':>14} "
             f"{'rungs n=3..':>12}"]
    for r in rows:
        lines.append(f"{r['spin_sign']:+4.0f} {r['delta_rad']:8.2f} {r['pairs']:6d} "
                     f"{r['acceptance']:10.4f} +- "
                     f"{r['acceptance_sem']:.4f} {r['mean_dTw_between_chains']:14.4f} "
                     f"{r['rungs_from_n3']:12d}")
    print("\n".join(lines))
    out = os.path.join(HERE, "results", f"lk_exchange_L{a.length:g}_F{a.force:g}_n{a.turns:g}")
    with open(out + ".json", "w") as fh:
        json.dump({"length_nm": a.length, "force_pN": a.force, "turns": a.turns,
                   "rows": rows}, fh, indent=1)
    with open(out + ".txt", "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
