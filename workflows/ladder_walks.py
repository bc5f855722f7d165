"""How far the states of a ladder run walk over its rungs, against independent swaps.

A ladder run (``dnabraid run plectoneme --set sampler=ladder``) saves, per replica, the state
on every rung after each round (``replicas/rNN/ladder_who.npy``, rounds x rungs) and the
pooled swap acceptance per neighbour pair (``ladder.json``). This script follows each state
over the rounds and compares its walk with the walk it would make if every swap attempt
were accepted independently of the state with the measured acceptance of its pair (the
"ideal" ladder of the non-reversible even/odd scheme; Okabe et al., Chem. Phys. Lett. 335,
435 (2001); Syed, Bouchard-Cote, Deligiannidis & Doucet, J. R. Stat. Soc. B 84, 321 (2022),
whose round-trip rate for it, all states together, is 1 / (2 + 2 sum_k r_k / (1 - r_k)) per
round, r_k the rejection rate of pair k).

Why the two can differ: the swap between rungs n and n + d of states with writhe W_lo and W_hi
costs (4 pi^2 C d / L) (W_hi - W_lo) kT in the twist energy 2 pi^2 C kT (Lk - Wr)^2 / L
(no trap compliance): a state can only sit at rungs whose equilibrium writhe lies within its
own writhe's spread, so past buckling a state's rung follows its writhe, which only the
moves change. Then the ladder's round trips take as long as the moves take to carry a
state's writhe across the ladder, and the acceptance alone does not predict them.

Reported per run: per ladder the round trips (measured and ideal), and over the states the
median range of rungs visited and the rung's mean squared displacement at lags of 1, 10,
100 rounds, and at 100 rounds from rungs in the upper half of the ladder (past buckling on
the default hat curve), measured and ideal.

    python workflows/ladder_walks.py RUN_DIR [RUN_DIR ...]

Writes ``workflows/results/ladder_walks_<run dir name>.{json,txt}``.
"""

from __future__ import annotations

import argparse
import json
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
LAGS = (1, 10, 100)


def state_rungs(who: np.ndarray) -> np.ndarray:
    """(rounds, states): the rung each state sits on after each round, from ``who``
    (rounds, rungs): the state on each rung."""
    R, K = who.shape
    out = np.empty((R, K), np.int64)
    for t in range(R):
        out[t, who[t]] = np.arange(K)
    return out


def round_trips(rungs: np.ndarray) -> int:
    """Round trips in (rounds, states) rung trajectories: a state that reached the lowest
    rung, then the highest, then the lowest again counts one (as TrapLadder counts)."""
    K = rungs.shape[1]
    total = 0
    for s in range(K):
        state = None  # None: not yet at the bottom; True: heading up; False: heading down
        for k in rungs[:, s]:
            if k == 0:
                if state is False:
                    total += 1
                state = True
            elif k == K - 1 and state is True:
                state = False
    return total


def ideal_walk(acc, K: int, rounds: int, rng) -> np.ndarray:
    """(rounds, states) rung trajectories of the even/odd ladder with independent swaps
    accepted with probabilities ``acc`` (per neighbour pair), from the identity."""
    who = np.arange(K)
    trace = np.empty((rounds, K), np.int64)
    for t in range(rounds):
        for k in range(t % 2, K - 1, 2):
            if rng.random() < acc[k]:
                who[k], who[k + 1] = who[k + 1], who[k]
        trace[t] = who
    return state_rungs(trace)


def msd(rungs: np.ndarray, lag: int) -> float | None:
    if lag >= rungs.shape[0]:
        return None
    d = rungs[lag:] - rungs[:-lag]
    return float(np.mean(d.astype(float) ** 2))


def msd_from(rungs: np.ndarray, lag: int, lo: int) -> float | None:
    """As :func:`msd`, only over starting points at rungs >= ``lo``."""
    if lag >= rungs.shape[0]:
        return None
    a, b = rungs[:-lag], rungs[lag:]
    sel = a >= lo
    return float(np.mean((b[sel] - a[sel]).astype(float) ** 2)) if sel.any() else None


def walks(run: str, seed: int = 1) -> dict:
    rdirs = sorted(d for d in os.listdir(os.path.join(run, "replicas")) if d.startswith("r"))
    rng = np.random.default_rng(seed)
    out = {"run": os.path.abspath(run), "ladders": []}
    for d in rdirs:
        base = os.path.join(run, "replicas", d)
        who = np.load(os.path.join(base, "ladder_who.npy")).astype(np.int64)
        with open(os.path.join(base, "ladder.json")) as fh:
            info = json.load(fh)
        acc = [0.0 if a is None else float(a) for a in info["swap_acceptance"]]
        K = who.shape[1]
        meas = state_rungs(who)
        ideal = ideal_walk(acc, K, who.shape[0], rng)
        rej = [1 - a for a in acc]
        lam = sum(r / (1 - r) for r in rej if r < 1)
        out["ladders"].append({
            "replica": d, "start": info.get("start", "up"), "rungs": K,
            "rounds": int(who.shape[0]),
            "acceptance_min": min(acc), "acceptance_mean": float(np.mean(acc)),
            "round_trips": round_trips(meas), "round_trips_ideal": round_trips(ideal),
            "round_trips_syed": who.shape[0] / (2 + 2 * lam) if K > 1 else None,
            "range_median": float(np.median(meas.max(0) - meas.min(0))),
            "range_median_ideal": float(np.median(ideal.max(0) - ideal.min(0))),
            "msd": {str(g): msd(meas, g) for g in LAGS},
            "msd_ideal": {str(g): msd(ideal, g) for g in LAGS},
            "msd_upper_half_100": msd_from(meas, 100, K // 2),
            "msd_upper_half_100_ideal": msd_from(ideal, 100, K // 2)})
    return out


def _f(x) -> str:
    return "-" if x is None else f"{x:.1f}"


def table(res: dict) -> str:
    lines = [f"# {res['run']}",
             "| ladder | start | rungs x rounds | acceptance min / mean | round trips "
             "(ideal; Syed) | median rungs visited (ideal) | MSD rungs^2 at 1, 10, 100 rounds "
             "(ideal) | MSD at 100 rounds from the upper half (ideal) |",
             "|---|---|---|---|---|---|---|---|"]
    for x in res["ladders"]:
        m = ", ".join("-" if x["msd"][str(g)] is None else f"{x['msd'][str(g)]:.2f}"
                      for g in LAGS)
        mi = ", ".join("-" if x["msd_ideal"][str(g)] is None
                       else f"{x['msd_ideal'][str(g)]:.2f}" for g in LAGS)
        lines.append(f"| {x['replica']} | {x['start']} | {x['rungs']} x {x['rounds']} | "
                     f"{x['acceptance_min']:.2f} / {x['acceptance_mean']:.2f} | "
                     f"{x['round_trips']} ({x['round_trips_ideal']}; "
                     f"{x['round_trips_syed']:.0f}) | "
                     f"{x['range_median']:.0f} ({x['range_median_ideal']:.0f}) | "
                     f"{m} ({mi}) | {_f(x['msd_upper_half_100'])} "
                     f"({_f(x['msd_upper_half_100_ideal'])}) |")
    lines.append("ideal: the same acceptances, each swap accepted independently of the "
                 "state (seeded); round trips counted as TrapLadder counts them")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", help="ladder run directories")
    ap.add_argument("--seed", type=int, default=1, help="seed of the ideal walks")
    ap.add_argument("--out", default=os.path.join(HERE, "results"))
    a = ap.parse_args(argv)
    for run in a.runs:
        res = walks(run, a.seed)
        txt = table(res)
        print(txt)
        name = os.path.basename(os.path.normpath(run))
        with open(os.path.join(a.out, f"ladder_walks_{name}.json"), "w") as fh:
            json.dump(res, fh, indent=1)
        with open(os.path.join(a.out, f"ladder_walks_{name}.txt"), "w") as fh:
            fh.write(txt)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
