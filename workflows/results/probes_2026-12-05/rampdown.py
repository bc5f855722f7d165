"""Moves-only chains at 300 nm, 1 pN, n = 3 reached from above: ramped 0 -> 4 turns at the
reference's speed (3/400 turn per 2000 moves), 1e6 moves at n = 4, ramped 4 -> 3 at the same
speed, 1e6 moves at n = 3, then sampled for BUDGET CPU seconds (z every 500 moves, Tw and
Wr every 5000).  The other side of the ramp-memory question of docs/validation.md 2.3p:
chains ramped up at this speed read 180.15-180.19 nm, ten 10-25x slower ramps 181.29 +- 0.30.

    python rampdown.py BUDGET SEED...      (writes rampdown.json beside this script)
"""
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
import plectoneme_mc_reference as ref  # noqa: E402

BUD = float(sys.argv[1])
SEEDS = [int(x) for x in sys.argv[2:]]
STAGE_TURNS = 3.0 / ref.RAMP_STAGES


def ramp_between(mv, pos, n_from, n_to):
    return ref.ramp_between(mv, pos, n_from, n_to, STAGE_TURNS)


def run(seed):
    from dnabraid.geometry.ribbon import tether_twist, writhe_open
    from dnabraid.analysis.stats import integrated_autocorrelation_time

    s, m, mv = ref.moves_chain(3.0, 300.0, 1.0, seed)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), m.bead_orientation
    t = time.process_time()
    pos = ramp_between(mv, np.array(m.positions), 0.0, 4.0)
    pos = ramp_between(mv, pos, 4.0, 3.0)
    t_ramp = time.process_time() - t
    z, tw, wr = [], [], []
    t0 = time.process_time()
    while time.process_time() - t0 < BUD:
        pos, _ = mv.run(pos, ref.SAMPLE_MOVES)
        z.append(float(pos[c[-1], 2] - pos[c[0], 2]))
        if len(z) % 10 == 0:
            tw.append(tether_twist(pos[c], pos[sides], pos[mo] - pos[c[-1]]))
            wr.append(writhe_open(pos[c]))
    z = np.array(z)
    tau, _ = integrated_autocorrelation_time(z)
    q = len(z) // 4
    out = {"seed": seed, "z_mean": float(z.mean()), "z_sem": float(z.std() * math.sqrt(tau / len(z))),
           "tau_samples": float(tau), "quarters": [float(z[i * q:(i + 1) * q].mean()) for i in range(4)],
           "samples": len(z), "wr_mean": float(np.mean(wr)), "tw_mean": float(np.mean(tw)),
           "lk_end": float(tw[-1] + wr[-1]), "cpu_ramp_s": t_ramp}
    print(json.dumps(out), flush=True)
    return out


if __name__ == "__main__":
    res = [run(sd) for sd in SEEDS]
    M = np.array([r["z_mean"] for r in res])
    print("ramped down 4 -> 3: mean %.2f +- %.2f nm (%d chains)"
          % (M.mean(), M.std(ddof=1) / math.sqrt(len(M)), len(M)))
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "rampdown.json"), "w") as fh:
        json.dump({"budget_cpu_s": BUD, "chains": res}, fh, indent=1)
