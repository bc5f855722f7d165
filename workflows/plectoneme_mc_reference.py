"""Moves-only reference of the plectoneme: no time step, no Brownian dynamics.

Independent Markov chains of the scene's own twist-aware Metropolis moves
(:class:`dnabraid.run.twist_moves.PlectonemeMoves`, the default mix and amplitudes) on the
scene's own energy (the same System's terms through their numba twins), one chain per seed:

1. the chain starts from the seed's own exact discrete-WLC draw (the scene's
   ``equilibrium_start``, Lk = 0);
2. the trap angle is ramped 0 -> 2 pi n in 400 stages of 2000 moves (8e5 moves), then 1e6
   moves of equilibration (``--approach up``, the default); with ``--approach down`` it is
   ramped at the same speed (n/400 turn per ``--ramp-moves`` moves) to n + ``--overshoot``
   turns (further from 0), held there for 1e6 moves and ramped back to n, then 1e6 moves;
3. it samples for ``--budget`` CPU seconds (``time.process_time``): the extension every 500
   moves, Tw and Wr every 5000 moves.

Metropolis moves sample exp(-U/kT) exactly; Euler-Maruyama's bias (first order in dt)
does not enter, so this is the check of a run's extension past buckling that the time-step
halving (``workflows/timestep_bias.py``) cannot afford. Reported per chain: <z>, its
integrated autocorrelation time (samples of 500 moves), <Tw>, the twist torque
2 pi <Tw> C kT / L and Tw + Wr at the end (must equal n: no strand passage); pooled: the
mean of the chain means with its standard error across chains (chains are independent),
the chain means' chi^2/dof against their own errors, and split R-hat over the chains
thinned by their tau and cut to the shortest. Where a point has chains from both approaches
it also reports down - up of their means (Welch) and flags the point APPROACHES DISAGREE at
|t| > ``APPROACH_T``: a ramp's memory that outlives the sampling (a lag of the writhe behind
the trap angle, docs/validation.md 2.3p) shows as such a difference, which the spread of
chains that all came the same way cannot see.

    python workflows/plectoneme_mc_reference.py --turns 5 --seeds 1 2 3 4 --budget 200
    python workflows/plectoneme_mc_reference.py --turns 5 --seeds 11 12 13 14 --approach down
    python workflows/plectoneme_mc_reference.py --turns 5 --compare RUN/summary.json

``--compare`` puts a finished run's points (same length and force) beside the stored
reference: difference and z = difference / sqrt(SEM_run^2 + SEM_ref^2).

Writes ``workflows/results/plectoneme_mc_reference_L<L>_F<F>.json`` (per chain summaries,
merged over calls: a chain with a seed already stored is replaced) and ``.txt`` (table).
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLE_MOVES = 500
RAMP_STAGES, RAMP_MOVES, EQ_MOVES = 400, 2000, 1_000_000
#: A chain whose Tw + Wr at the end differs from n by more than this passed a strand through
#: itself: it is reported and left out of the pooled reference.
LK_TOL = 0.05
#: |Welch t| of the two approaches' means above which a point is flagged.
APPROACH_T = 3.0
APPROACHES = ("up", "down")


def moves_chain(n_turns, length, force, seed, spread=False):
    """(scene, model, moves) of one moves-only chain: the plectoneme scene's System and its
    default move amplitudes, move seed 100 + seed (shared with lk_exchange.py, lk_ladder.py)."""
    from dnabraid.run.twist_moves import PlectonemeMoves
    from dnabraid.scenes import make_scene

    s = make_scene("plectoneme", {"length_nm": length, "force_pN": force,
                                  "turns": [n_turns], "mc_moves": 0, "seed": seed})
    m = s.build()
    mv = PlectonemeMoves.for_model(m, moves_per_call=1, seed=100 + seed,
                                   crank_angle_rad=s.crank_angle_rad,
                                   pivot_angle_rad=s.pivot_angle_rad,
                                   frame_angle_rad=s.frame_angle_rad,
                                   ball_nm=s.bead_move_nm, sweep_nm=s.sweep_nm,
                                   twist_spread=spread)
    return s, m, mv


def ramp(mv, pos, theta, eq_moves=EQ_MOVES, ramp_moves=RAMP_MOVES):
    """The trap angle ramped 0 -> theta in RAMP_STAGES stages of ``ramp_moves`` moves, then
    ``eq_moves`` moves at theta; returns the positions."""
    for k in range(RAMP_STAGES + 1):
        mv.energy.set_trap_angle(theta * k / RAMP_STAGES)
        pos, _ = mv.run(pos, ramp_moves)
    pos, _ = mv.run(pos, eq_moves)
    return pos


def ramp_between(mv, pos, n_from, n_to, stage_turns, ramp_moves=RAMP_MOVES,
                 eq_moves=EQ_MOVES):
    """The trap angle ramped from n_from to n_to turns in stages of ``stage_turns`` turns
    and ``ramp_moves`` moves each, then ``eq_moves`` moves."""
    k = max(1, int(round(abs(n_to - n_from) / stage_turns)))
    for i in range(k + 1):
        mv.energy.set_trap_angle(2 * math.pi * (n_from + (n_to - n_from) * i / k))
        pos, _ = mv.run(pos, ramp_moves)
    pos, _ = mv.run(pos, eq_moves)
    return pos


def approach(mv, pos, n_turns, how="up", overshoot=1.0, ramp_moves=RAMP_MOVES):
    """Positions at n_turns reached from below (``up``: :func:`ramp`, 0 -> n in RAMP_STAGES
    stages) or from above (``down``: 0 -> n + overshoot, 1e6 moves there, -> n), every
    ramp of ``down`` at the speed of ``up``'s (n / RAMP_STAGES turn per stage; overshoot /
    RAMP_STAGES at n = 0)."""
    if how == "up":
        return ramp(mv, pos, 2 * math.pi * n_turns, ramp_moves=ramp_moves)
    if how == "down":
        if overshoot <= 0:
            raise ValueError(f"overshoot={overshoot!r} turns: must be > 0 for approach down")
        stage = (abs(n_turns) or overshoot) / RAMP_STAGES
        top = n_turns + math.copysign(overshoot, n_turns or 1.0)
        pos = ramp_between(mv, pos, 0.0, top, stage, ramp_moves)
        return ramp_between(mv, pos, top, n_turns, stage, ramp_moves)
    raise ValueError(f"approach must be one of {APPROACHES}, not {how!r}")


def chain(args) -> dict:
    n_turns, length, force, seed, budget, spread, how, overshoot, ramp_moves = args
    from dnabraid.analysis.stats import integrated_autocorrelation_time
    from dnabraid.geometry.ribbon import tether_twist, writhe_open

    s, m, mv = moves_chain(n_turns, length, force, seed, spread)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), m.bead_orientation
    t_start = time.process_time()
    pos = approach(mv, np.array(m.positions), n_turns, how, overshoot, ramp_moves)
    t_eq = time.process_time() - t_start
    z, tw, wr = [], [], []
    t0 = time.process_time()
    while time.process_time() - t0 < budget:
        pos, _ = mv.run(pos, SAMPLE_MOVES)
        z.append(float(pos[c[-1], 2] - pos[c[0], 2]))
        if len(z) % 10 == 0:
            tw.append(tether_twist(pos[c], pos[sides], pos[mo] - pos[c[-1]]))
            wr.append(writhe_open(pos[c]))
    cpu = time.process_time() - t0
    z = np.array(z)
    tau, _ = integrated_autocorrelation_time(z)
    tw_mean = float(np.mean(tw))
    tau_tw, _ = integrated_autocorrelation_time(np.asarray(tw))
    return {"turns": n_turns, "seed": seed, "samples": len(z), "moves": len(z) * SAMPLE_MOVES,
            "cpu_s": cpu, "cpu_ramp_eq_s": t_eq, "z_mean": float(z.mean()),
            "z_sd": float(z.std()), "tau_samples": float(tau),
            "z_sem": float(z.std() * math.sqrt(tau / len(z))),
            "tw_mean": tw_mean, "wr_mean": float(np.mean(wr)),
            # Tw's own time in samples of 5000 moves: the twist-writhe partition is the
            # slow mode past buckling (docs/validation.md 2.3l)
            "tau_tw_samples": float(tau_tw), "twist_spread": bool(spread),
            "us_per_move": 1e6 * cpu / (len(z) * SAMPLE_MOVES),
            "twist_torque_pN_nm": 2 * math.pi * tw_mean * s.twist_persistence_nm * m.dna.kT
            / length,
            "lk_end": float(tw[-1] + wr[-1]), "approach": how,
            "overshoot_turns": overshoot if how == "down" else 0.0,
            "ramp_moves_per_stage": ramp_moves,
            "z_thin": z[::max(1, int(math.ceil(tau)))].tolist()}


def _same_chain(c, res) -> bool:
    """A stored chain that ``res`` replaces: same seed, approach and ramp."""
    return (c["seed"] == res["seed"] and c.get("approach", "up") == res["approach"]
            and c.get("ramp_moves_per_stage", RAMP_MOVES) == res["ramp_moves_per_stage"])


def approach_split(chains: list[dict]) -> dict | None:
    """down - up of the chain means of the two approaches (Welch SE and t); None unless
    both have >= 2 chains. Chains ramped at another speed than RAMP_MOVES count by their
    direction."""
    g = {h: np.array([c["z_mean"] for c in chains if c.get("approach", "up") == h])
         for h in APPROACHES}
    if min(len(v) for v in g.values()) < 2:
        return None
    se = math.sqrt(sum(v.var(ddof=1) / len(v) for v in g.values()))
    d = float(g["down"].mean() - g["up"].mean())
    return {"up_mean": float(g["up"].mean()), "down_mean": float(g["down"].mean()),
            "up_chains": len(g["up"]), "down_chains": len(g["down"]), "diff": d, "se": se,
            "t": d / se if se > 0 else math.inf, "disagree": bool(abs(d) > APPROACH_T * se)}


def pooled(chains: list[dict]) -> dict:
    from dnabraid.analysis.convergence import split_rhat

    n_turns = chains[0]["turns"]
    lost = [c["seed"] for c in chains if abs(c["lk_end"] - n_turns) > LK_TOL]
    chains = [c for c in chains if c["seed"] not in lost]
    means = np.array([c["z_mean"] for c in chains])
    k = len(means)
    out = {"chains": k, "lk_lost_seeds": lost, "z_mean": float(means.mean()),
           "z_sem": float(means.std(ddof=1) / math.sqrt(k)) if k > 1 else math.nan,
           "tw_mean": float(np.mean([c["tw_mean"] for c in chains])),
           "twist_torque_pN_nm": float(np.mean([c["twist_torque_pN_nm"] for c in chains])),
           # chain means against their own (Sokal) errors: chi^2 / dof > 1 says the
           # chains have a mode slower than their estimated tau (the pooled error, from
           # the spread of independent chains, does not rely on tau)
           "chi2_dof": float(np.sum(((means - means.mean()) / np.array(
               [c["z_sem"] for c in chains])) ** 2) / (k - 1)) if k > 1 else math.nan,
           "moves": int(sum(c["moves"] for c in chains)),
           "cpu_s": float(sum(c["cpu_s"] for c in chains))}
    thin = [np.asarray(c["z_thin"]) for c in chains]
    nmin = min(len(t) for t in thin)
    if k > 1 and nmin >= 8:
        arr = np.array([t[:nmin] for t in thin])
        out["rhat"] = float(split_rhat(arr))
    out["approach_split"] = approach_split(chains)
    return out


def table(store: dict) -> list[str]:
    lines = [f"# moves-only reference (workflows/plectoneme_mc_reference.py): plectoneme "
             f"L = {store['length_nm']} nm, F = {store['force_pN']} pN, default moves"
             + (" with twist_spread" if store.get("twist_spread") else "") + "; "
             "z in nm, tau in samples of 500 moves (Sokal), a chain's +- from that tau "
             "(too small where the chain has a slower mode: see chi2/dof), torque in pN nm; "
             "tau Tw in samples of 5000 moves (- where not stored)",
             f"{'turns':>5} {'seed':>4} {'from':>4} {'moves':>9} {'cpu s':>6} {'<z>':>7} {'+-':>5} "
             f"{'tau':>6} {'<Tw>':>7} {'torque':>7} {'Lk end':>7} {'tau Tw':>6}"]
    for key in sorted(store["points"], key=float):
        pt = store["points"][key]
        for c in sorted(pt["chains"], key=lambda c: c["seed"]):
            lines.append(f"{float(key):5g} {c['seed']:4d} {c.get('approach', 'up'):>4} "
                         f"{c['moves']:9.2e} {c['cpu_s']:6.0f} "
                         f"{c['z_mean']:7.2f} {c['z_sem']:5.2f} {c['tau_samples']:6.1f} "
                         f"{c['tw_mean']:7.4f} {c['twist_torque_pN_nm']:7.2f} "
                         f"{c['lk_end']:7.3f} "
                         + (f"{c['tau_tw_samples']:6.1f}" if "tau_tw_samples" in c
                            else f"{'-':>6}"))
        p = pooled(pt["chains"])
        extra = (f", split R-hat {p['rhat']:.3f} (thinned chains)" if "rhat" in p else "")
        if p["lk_lost_seeds"]:
            extra += f"; LEFT OUT (linking number lost): seeds {p['lk_lost_seeds']}"
        sp = p["approach_split"]
        if sp:
            extra += (f"; from below {sp['up_mean']:.2f} ({sp['up_chains']}), from above "
                      f"{sp['down_mean']:.2f} ({sp['down_chains']}): down - up "
                      f"{sp['diff']:+.2f} +- {sp['se']:.2f} nm, t = {sp['t']:+.1f}"
                      + (" APPROACHES DISAGREE" if sp["disagree"] else ""))
        lines.append(f"{float(key):5g} pooled: <z> = {p['z_mean']:.2f} +- {p['z_sem']:.2f} nm "
                     f"(spread of {p['chains']} independent chains; chain means' chi2/dof "
                     f"{p['chi2_dof']:.1f} against their Sokal errors{extra}); <Tw> "
                     f"{p['tw_mean']:.4f}, twist torque {p['twist_torque_pN_nm']:.2f} pN nm; "
                     f"{p['moves']:.2e} moves, {p['cpu_s']:.0f} CPU s of sampling")
    return lines


def compare(store: dict, summary_path: str) -> list[str]:
    with open(summary_path) as fh:
        summ = json.load(fh)
    sc = summ["scene"]
    if (abs(sc["length_nm"] - store["length_nm"]) > 1e-9
            or abs(sc["force_pN"] - store["force_pN"]) > 1e-9):
        raise SystemExit(f"{summary_path}: L = {sc['length_nm']} nm, F = {sc['force_pN']} pN "
                         f"do not match the reference's {store['length_nm']} nm, "
                         f"{store['force_pN']} pN")
    lines = [f"# run {summary_path} against the moves-only reference",
             f"{'turns':>5} {'run z':>14} {'verdict':>14} {'reference z':>14} {'diff':>7} "
             f"{'z-score':>7}"]
    for pt in summ["points"]:
        key = f"{float(pt['turns']):g}"
        if key not in store["points"]:
            continue
        ref = pooled(store["points"][key]["chains"])
        e = pt["extension_nm"]
        d = e["mean"] - ref["z_mean"]
        zz = d / math.hypot(e["sem"], ref["z_sem"])
        verdict = "converged" if pt.get("converged") else "NOT CONVERGED"
        lines.append(f"{float(key):5g} {e['mean']:8.2f} +-{e['sem']:4.2f} {verdict:>14} "
                     f"{ref['z_mean']:8.2f} +-{ref['z_sem']:4.2f} {d:+7.2f} {zz:+7.2f}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--turns", type=float, nargs="+", default=[5.0])
    ap.add_argument("--length", type=float, default=300.0, help="nm")
    ap.add_argument("--force", type=float, default=1.0, help="pN")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--budget", type=float, default=200.0,
                    help="CPU seconds of sampling per chain")
    ap.add_argument("--workers", type=int, default=0, help="processes (0 = one per core)")
    ap.add_argument("--compare", default=None,
                    help="a finished run's summary.json: its points against the reference")
    ap.add_argument("--out", default=None)
    ap.add_argument("--twist-spread", action="store_true",
                    help="moves with twist_spread (docs/validation.md 2.3m); stored apart "
                         "(file name ends in _spread)")
    ap.add_argument("--approach", choices=APPROACHES, default="up",
                    help="reach each n from below (0 -> n) or from above (0 -> n + overshoot "
                         "-> n), at the same ramp speed")
    ap.add_argument("--overshoot", type=float, default=1.0, help="turns, for --approach down")
    ap.add_argument("--ramp-moves", type=int, default=RAMP_MOVES,
                    help="moves per ramp stage of n/400 turn (the default: the reference's)")
    a = ap.parse_args(argv)
    base = a.out or os.path.join(HERE, "results",
                                 f"plectoneme_mc_reference_L{a.length:g}_F{a.force:g}"
                                 + ("_spread" if a.twist_spread else ""))
    store = {"length_nm": a.length, "force_pN": a.force, "points": {},
             "twist_spread": a.twist_spread}
    if os.path.exists(base + ".json"):
        with open(base + ".json") as fh:
            store = json.load(fh)
    if a.compare:
        lines = compare(store, a.compare)
        print("\n".join(lines))
        with open(base + "_compare.txt", "a") as fh:
            fh.write("\n".join(lines) + "\n\n")
        return 0
    jobs = [(n, a.length, a.force, sd, a.budget, a.twist_spread, a.approach, a.overshoot,
             a.ramp_moves) for n in a.turns for sd in a.seeds]
    workers = a.workers or os.cpu_count() or 1
    done = 0
    with mp.get_context("spawn").Pool(min(workers, len(jobs))) as pool:
        for job, res in zip(jobs, pool.imap(chain, jobs)):
            key = f"{job[0]:g}"
            pt = store["points"].setdefault(key, {"chains": []})
            pt["chains"] = [c for c in pt["chains"] if not _same_chain(c, res)] + [res]
            done += 1
            print(f"[{done}/{len(jobs)}] n = {key}, seed {res['seed']}: <z> "
                  f"{res['z_mean']:.2f} +- {res['z_sem']:.2f} nm, tau {res['tau_samples']:.0f}"
                  f", Lk end {res['lk_end']:.3f}", flush=True)
            with open(base + ".json", "w") as fh:  # no lost results: after every chain
                json.dump(store, fh)
    lines = table(store)
    print("\n".join(lines))
    with open(base + ".txt", "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
