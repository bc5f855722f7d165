"""Metropolis chain moves with compiled local energies: cost per move, and the tether's
convergence with and without them.

1. Microseconds per move (crankshaft, pivot, bead, and the default mix) of the moves'
   compiled loop (:func:`dnabraid.kernels.chain.run_chain_moves`, no engine) for tethers of
   100, 400 and 1000 nm (21, 81, 201 beads at b = 5 nm; wall and self-avoidance on,
   0.3 pN), from an equilibrated state; CPU time of this process (``time.process_time``:
   the machine is shared), best of 3 repeats.
2. The tether at 600 nm / 0.3 pN (scene defaults otherwise: wall, self-avoidance, 4
   replicas, 180000 + 40000 steps) run by ``dnabraid run`` with ``mc_moves = 0`` (Brownian
   dynamics alone) and with the default moves, same seeds and steps: the verdict,
   extension +- SEM, R-hat, the smallest ESS, wall time and ESS per wall second.
3. The guard: the largest |engine change - kernel change| of the energy over calls of the
   default moves on the CPU platform, for a contact-rich tether (1500 nm at 2 mM salt,
   d = 31 nm, 0.02 pN) at the origin and shifted as a packed copy is.

Usage: python workflows/benchmark_chain_moves.py [--seeds 1 3] [--skip-runs]
Writes workflows/results/benchmark_chain_moves.txt.
"""

from __future__ import annotations

import argparse
import datetime
import os
import pathlib
import shutil
import tempfile
import time
import warnings

import numpy as np

from dnabraid.run.chain_moves import GUARD_ABS_PN_NM, GUARD_REL, KINDS, ChainMoves
from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent


def _defaults() -> dict:
    s = make_scene("tether")
    return {"moves_per_call": s.mc_moves, "crank_angle_rad": s.crank_angle_rad,
            "pivot_angle_rad": s.pivot_angle_rad, "bead_move_nm": s.bead_move_nm}


def per_move(lengths=(100.0, 400.0, 1000.0), force=0.3, n=20000) -> list[str]:
    kw = _defaults()
    kw.pop("moves_per_call")
    lines = [f"# 1. us per move (CPU time, best of 3 x {n} moves), tether at {force} pN, wall "
             "and self-avoidance on; acceptance in brackets",
             f"{'length nm':>9} {'beads':>5} " + " ".join(f"{k:>18}" for k in KINDS)
             + f" {'mix 2:1:1':>18}"]
    for L in lengths:
        m = make_scene("tether", {"length_nm": L, "force_pN": force, "mc_moves": 0}).build()
        eq = ChainMoves.for_model(m, moves_per_call=1, seed=9, **kw)
        pos, _ = eq.run(m.positions, 50 * n)
        cells = []
        for w in ((1, 0, 0), (0, 1, 0), (0, 0, 1), (2, 1, 1)):
            mv = ChainMoves.for_model(m, moves_per_call=1, seed=1, weights=w, **kw)
            p = pos.copy()
            best = np.inf
            for _ in range(3):
                t0 = time.process_time()
                p, _ = mv.run(p, n)
                best = min(best, (time.process_time() - t0) / n * 1e6)
            acc = mv.summary()
            a = "/".join(f"{acc[k]['acceptance']:.2f}" for k in KINDS if k in mv.kinds)
            cells.append(f"{best:8.2f} ({a})")
        lines.append(f"{L:9.0f} {len(m.positions):5d} " + " ".join(f"{c:>18}" for c in cells))
        print(lines[-1], flush=True)
    return lines


def tether_runs(seeds, tmp) -> list[str]:
    lines = ["# 2. dnabraid run tether --set length_nm=600 --set force_pN=0.3 (defaults "
             "otherwise), BD alone (mc_moves=0) vs BD + moves (defaults), same seeds/steps",
             f"{'seed':>4} {'mc_moves':>8} {'verdict':>13} {'extension nm':>15} {'R-hat':>6} "
             f"{'ESS':>7} {'wall s':>7} {'ESS/wall s':>10} {'cpu s':>7} {'acceptance c/p/b':>17}"]
    for seed in seeds:
        for nm in (0, _defaults()["moves_per_call"]):
            s = make_scene("tether", {"length_nm": 600.0, "force_pN": 0.3, "seed": seed,
                                      "mc_moves": nm})
            out = os.path.join(tmp, f"s{seed}_m{nm}")
            c0 = os.times()
            summ = s.run(out)
            c1 = os.times()
            cpu = sum(getattr(c1, a) - getattr(c0, a) for a in
                      ("user", "system", "children_user", "children_system"))
            pt = summ["points"][0]
            e = pt["extension_nm"]
            ess = min(v for v in pt["effective_sample_size"].values())
            wall = summ["wall_time_s"]
            mv = pt.get("rigid_moves") or {}
            acc = "/".join(f"{mv[k]['acceptance']:.2f}" for k in KINDS if k in mv) or "-"
            verdict = "converged" if pt["converged"] else "NOT CONVERGED"
            lines.append(f"{seed:4d} {nm:8d} {verdict:>13} {e['mean']:7.1f} +- {e['sem']:4.1f} "
                         f"{e['rhat']:6.3f} {ess:7.0f} {wall:7.1f} {ess / wall:10.2f} "
                         f"{cpu:7.1f} {acc:>17}")
            print(lines[-1], flush=True)
            shutil.rmtree(out, ignore_errors=True)
    return lines


def guard(calls=100) -> list[str]:
    from dnabraid.run.engine import Engine

    lines = [f"# 3. guard on the CPU platform: max |dE_engine - dE_kernels| over {calls} calls "
             f"of the default moves (tolerance {GUARD_REL:g} x |E| + {GUARD_ABS_PN_NM:g} pN nm)",
             f"{'scene':>42} {'offset nm':>9} {'|E| pN nm':>9} {'wca':>7} {'wall':>7} "
             f"{'max diff':>9} {'tolerance':>9}"]
    kw = _defaults()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 2 mM is below the tabulated salts (extrapolated)
        cases = [("600 nm, 0.3 pN, 150 mM", {"length_nm": 600.0, "force_pN": 0.3}),
                 ("1500 nm, 0.02 pN, 2 mM (d = 31 nm)",
                  {"length_nm": 1500.0, "force_pN": 0.02, "salt_mM": 2.0})]
        for label, keys in cases:
            m = make_scene("tether", dict(keys, mc_moves=0)).build()
            pre = ChainMoves.for_model(m, seed=2, **kw)
            pos, _ = pre.run(m.positions, 200000)
            terms = pre.energy.total_terms(pos)
            for off in (0.0, 3000.0):
                mv = ChainMoves.for_model(m, seed=1, guard_every=1, guard_rel=1.0, **kw)
                eng = Engine.for_model(m, platform="CPU", threads=1)
                o = np.array([off, 0.0, 0.0])
                eng.set_positions(pos + o)
                for _ in range(calls):
                    mv.attempt(lambda eng=eng, o=o: eng.positions() - o,
                               lambda p, eng=eng, o=o: eng.set_positions(p + o),
                               eng.energy_pN_nm)
                e = abs(eng.energy_pN_nm())
                lines.append(f"{label:>42} {off:9.0f} {e:9.1f} {terms.get('wca', 0):7.2f} "
                             f"{terms.get('wall', 0):7.2f} {mv.guard_max_diff:9.2e} "
                             f"{GUARD_REL * e + GUARD_ABS_PN_NM:9.2e}")
                print(lines[-1], flush=True)
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 3])
    ap.add_argument("--skip-runs", action="store_true", help="only parts 1 and 3")
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_chain_moves.txt"))
    args = ap.parse_args(argv)
    d = _defaults()
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    head = [f"# Metropolis chain moves (dnabraid.run.chain_moves), {stamp}; {os.cpu_count()} "
            f"cores shared with other jobs (load average at start {os.getloadavg()[0]:.1f})",
            f"# defaults: mc_moves={d['moves_per_call']} per report interval, crank_angle_rad="
            f"{d['crank_angle_rad']}, pivot_angle_rad={d['pivot_angle_rad']}, bead_move_nm="
            f"{d['bead_move_nm']}, crankshaft arcs of 1-8 beads, kinds 2:1:1"]
    lines = head + [""] + per_move() + [""]
    if not args.skip_runs:
        tmp = tempfile.mkdtemp(prefix="bench_chain_moves_")
        try:
            lines += tether_runs(args.seeds, tmp) + [""]
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    lines += guard()
    text = "\n".join(lines) + "\n"
    print(text)
    pathlib.Path(args.out).write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
