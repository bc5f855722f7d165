"""Twist-aware Metropolis moves of the plectoneme with compiled local energies: cost per
move, the independent reference, and the 1-um plectoneme at 0.5 pN with and without moves.

1. Microseconds per move (crankshaft, pivot, frame, particle, and the default mix) of the
   compiled loop (:func:`dnabraid.kernels.twist.run_twist_moves`, no engine) for the 1000-nm
   plectoneme at 0.5 pN, n = 0 (201 beads, 200 side particles), from a state equilibrated
   by the moves; CPU time of this process (``time.process_time``: the machine is shared),
   best of 3; acceptance and the fraction refused by the passage check.
2. The reference: exact draws of the free discrete WLC under the force
   (:func:`dnabraid.continuum.wlc.sample_discrete_wlc`) weighted by
   exp(-(U_wall + U_wca + U_beadplane) / kT) (the scene's own terms, by their numba twins)
   and by the twist at Lk = n: exp(-(2 pi (n - Wr))^2 / (2 (L / C + kT / K))) (the frames
   integrated out: Gaussian joint angles whose sum is 2 pi (Lk - Wr), the harmonic trap in
   series; tests/test_twist_moves.py checks this identity against the moves on a short
   chain). Gives <z>, <Wr> and <Tw> = n - <Wr> with batch standard errors, and the free
   chain's <z> (794.5 nm: the quoted exact discrete WLC without wall, excluded volume or
   twist).
3. ``dnabraid run plectoneme --set length_nm=1000 --set force_pN=0.5 --set 'turns=[0]'``
   with ``mc_moves = 0`` and with the default moves, seeds 1 and 3: verdict, extension
   +- SEM, R-hat, smallest ESS, wall, ESS per wall second, CPU seconds, <Tw> and the twist
   torque (both 0 at n = 0 by symmetry), and the largest guard difference.

Usage: python workflows/benchmark_plectoneme_moves.py [--seeds 1 3] [--skip-runs]
       [--runs DIR ...] (read finished run directories named s<seed>_m<mc_moves> instead)
Writes workflows/results/benchmark_plectoneme_moves.txt.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import pathlib
import shutil
import tempfile
import time

import numpy as np

from dnabraid.run.twist_moves import TWIST_KINDS, PlectonemeMoves
from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent
#: The case and the sampling its stored results were measured with (the plectoneme's
#: defaults until 2026-12-04; since then the scene samples by 20 000 moves per 50 steps).
MOVES = 500
CASE = {"length_nm": 1000.0, "force_pN": 0.5, "turns": [0.0], "steps": 180000,
        "equilibration_steps": 40000, "report_interval": 100, "frame_interval": 5000,
        "turn_rate": 5e-5, "mc_moves": MOVES}


def per_move(n=20000) -> list[str]:
    s = make_scene("plectoneme", dict(CASE, mc_moves=0))
    m = s.build()
    kw = dict(crank_angle_rad=s.crank_angle_rad, pivot_angle_rad=s.pivot_angle_rad,
              frame_angle_rad=s.frame_angle_rad, ball_nm=s.bead_move_nm, sweep_nm=s.sweep_nm)
    eq = PlectonemeMoves.for_model(m, moves_per_call=1, seed=9, **kw)
    eq.energy.set_trap_angle(0.0)
    pos, _ = eq.run(m.positions, 200000)
    lines = [f"# 1. us per move (CPU time, best of 3 x {n} moves), plectoneme {CASE}; "
             "acceptance, refused by the passage check",
             f"{'kind':>12} {'us/move':>8} {'acceptance':>10} {'refused':>8}"]
    for k, w in zip(TWIST_KINDS + ("mix 1:6:1:1",),
                    ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1), (1, 6, 1, 1))):
        mv = PlectonemeMoves.for_model(m, moves_per_call=1, seed=1, weights=w, **kw)
        mv.energy.set_trap_angle(0.0)
        p = pos.copy()
        best = np.inf
        for _ in range(3):
            t0 = time.process_time()
            p, _ = mv.run(p, n)
            best = min(best, (time.process_time() - t0) / n * 1e6)
        att = sum(v.attempted for v in mv.stats.values())
        acc = sum(v.accepted for v in mv.stats.values()) / att
        ref = sum(v.refused for v in mv.stats.values()) / att
        lines.append(f"{k:>12} {best:8.2f} {acc:10.3f} {ref:8.4f}")
        print(lines[-1], flush=True)
    return lines


def reference(n_draws=6000, batches=20, seed=12345, n_turns=0.0) -> tuple[list[str], dict]:
    from dnabraid.continuum.wlc import sample_discrete_wlc
    from dnabraid.geometry.ribbon import writhe_open
    from dnabraid.kernels import LocalEnergy

    s = make_scene("plectoneme", dict(CASE, mc_moves=0))
    model = s.build()
    le = LocalEnergy(model)
    d = model.dna
    chain = np.asarray(model.chains[0])
    pos = np.array(model.positions, float)
    var_s = s.length_nm / s.twist_persistence_nm + d.kT / s.trap_stiffness_pN_nm
    rng = np.random.default_rng(seed)
    per = int(math.ceil(n_draws / batches))
    z, wr, logw = [], [], []
    for _ in range(batches):
        for x in sample_discrete_wlc(s.force_pN, s.n_beads - 1, s.bead_spacing_nm, d.kappa_kT,
                                     d.kT, stretch_k_pN_per_nm=d.k_bond, n_samples=per,
                                     rng=rng):
            pos[chain] = x
            t = le.total_terms(pos)
            w_r = writhe_open(x)
            logw.append(-(t["wall"] + t["wca"] + t["beadwall"]) / d.kT
                        - (2 * math.pi * (n_turns - w_r)) ** 2 / (2 * var_s))
            z.append(x[-1, 2] - x[0, 2])
            wr.append(w_r)
    z, wr, logw = map(np.asarray, (z, wr, logw))
    w = np.exp(logw - logw.max())
    est = []
    for b in range(batches):
        sl = slice(b * per, (b + 1) * per)
        est.append((np.sum(w[sl] * z[sl]) / w[sl].sum(), np.sum(w[sl] * wr[sl]) / w[sl].sum(),
                    np.sum(w[sl] * wr[sl] ** 2) / w[sl].sum()))
    est = np.asarray(est)
    mean = est.mean(axis=0)
    sem = est.std(axis=0, ddof=1) / math.sqrt(batches)
    kish = w.sum() ** 2 / np.sum(w * w)
    ref = {"z": mean[0], "z_sem": sem[0], "wr": mean[1], "wr_sem": sem[1],
           "wr2": mean[2], "wr2_sem": sem[2], "free_z": z.mean(),
           "free_z_sem": z.std() / math.sqrt(z.size),
           "kish": kish / z.size}
    lines = [f"# 2. reference at n = {n_turns}: {z.size} exact free-WLC draws weighted by wall, "
             "WCA, bead plane and twist (Lk fixed; trap in series)",
             f"<z> = {ref['z']:.1f} +- {ref['z_sem']:.1f} nm (free discrete WLC "
             f"{ref['free_z']:.1f} +- {ref['free_z_sem']:.1f} nm); <Wr> = {ref['wr']:.4f} +- "
             f"{ref['wr_sem']:.4f}, <Tw> = {n_turns - ref['wr']:.4f}, <Wr^2> = {ref['wr2']:.4f} +- "
             f"{ref['wr2_sem']:.4f} turns^2 (= <Tw^2> at n = 0 up to the trap's "
             f"{d.kT / s.trap_stiffness_pN_nm / 4 / math.pi**2:.1e}; a free end: L / (4 pi^2 C) "
             f"= {s.length_nm / (4 * math.pi**2 * s.twist_persistence_nm):.4f}); "
             f"Kish fraction {ref['kish']:.2f}"]
    print("\n".join(lines), flush=True)
    return lines, ref


def twist_square(out) -> tuple[float, float]:
    """<Tw^2> (turns^2) over every replica's samples (Tw from the twist torque
    2 pi Tw C kT / L), and its standard error from each replica's blocking SEM."""
    import glob

    from dnabraid.analysis.stats import blocking_sem

    s = make_scene("plectoneme", CASE)
    f = 2 * math.pi * s.twist_persistence_nm * s.kT / s.length_nm
    means, sems = [], []
    for path in sorted(glob.glob(os.path.join(out, "replicas", "r*", "points", "*",
                                              "samples.csv"))):
        tq = np.genfromtxt(path, delimiter=",", names=True)["twist_torque_pN_nm"]
        r = blocking_sem((tq / f) ** 2)
        means.append(np.mean((tq / f) ** 2))
        sems.append(r["sem"])
    return float(np.mean(means)), float(np.sqrt(np.sum(np.square(sems))) / len(sems))


def _row(seed, nm, out, ref, cpu=None) -> str:
    summ = json.load(open(os.path.join(out, "summary.json")))
    pt = summ["points"][0]
    e = pt["extension_nm"]
    ess = min(v for v in pt["effective_sample_size"].values() if v is not None)
    wall = summ.get("wall_time_s", float("nan"))
    mv = pt.get("rigid_moves") or {}
    acc = "/".join(f"{mv[k]['acceptance']:.2f}" for k in TWIST_KINDS if k in mv) or "-"
    verdict = "converged" if pt["converged"] else "NOT CONVERGED"
    tw, tq = pt["twist"], pt["twist_torque_pN_nm"]
    dev = 100 * (e["mean"] - ref["z"]) / ref["z"] if ref else float("nan")
    g = mv.get("guard_max_diff_pN_nm")
    t2, t2s = twist_square(out)
    return (f"{seed:4d} {nm:8d} {verdict:>13} {e['mean']:7.1f} +- {e['sem']:4.1f} {dev:+6.2f} "
            f"{e['rhat']:6.3f} {ess:6.0f} {wall:7.1f} {ess / wall:8.2f} "
            f"{'-' if cpu is None else f'{cpu:7.0f}':>7} {tw['mean']:+.3f}+-{tw['sem']:.3f} "
            f"{tq['mean']:+6.2f}+-{tq['sem']:4.2f} {t2:.4f}+-{t2s:.4f} {acc:>19} "
            f"{'-' if g is None else f'{g:.1e}':>8}")


def runs(seeds, tmp, ref, existing=None) -> list[str]:
    lines = ["# 3. dnabraid run plectoneme --set length_nm=1000 --set force_pN=0.5 --set "
             "'turns=[0]' (4 replicas x 1.8e5 + 4e4 steps, report_interval 100), BD alone "
             f"(mc_moves=0) vs BD + moves (mc_moves={MOVES}); dev = (extension - reference) "
             "/ reference",
             f"{'seed':>4} {'mc_moves':>8} {'verdict':>13} {'extension nm':>15} {'dev %':>6} "
             f"{'R-hat':>6} {'ESS':>6} {'wall s':>7} {'ESS/s':>8} {'cpu s':>7} "
             f"{'<Tw> turns':>13} {'torque pN nm':>13} {'<Tw^2> turns^2':>15} "
             f"{'acc c/p/f/p':>19} {'guard':>8}"]
    for seed in seeds:
        for nm in (0, MOVES):
            name = f"s{seed}_m{nm}"
            found = [os.path.join(dd, name) for dd in (existing or [])
                     if os.path.exists(os.path.join(dd, name, "summary.json"))]
            if found:
                lines.append(_row(seed, nm, found[0], ref))
            else:
                s = make_scene("plectoneme", dict(CASE, seed=seed, mc_moves=nm))
                out = os.path.join(tmp, name)
                c0 = os.times()
                s.run(out)
                c1 = os.times()
                cpu = sum(getattr(c1, a) - getattr(c0, a) for a in
                          ("user", "system", "children_user", "children_system"))
                lines.append(_row(seed, nm, out, ref, cpu))
                shutil.rmtree(out, ignore_errors=True)
            print(lines[-1], flush=True)
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 3])
    ap.add_argument("--skip-runs", action="store_true", help="only parts 1 and 2")
    ap.add_argument("--runs", nargs="*", default=None,
                    help="directories holding finished runs s<seed>_m<mc_moves>")
    ap.add_argument("--wait", action="store_true",
                    help="with --runs: wait for the runs' summary.json to appear")
    ap.add_argument("--draws", type=int, default=6000)
    ap.add_argument("--out", default=str(HERE / "results" / "benchmark_plectoneme_moves.txt"))
    args = ap.parse_args(argv)
    s = make_scene("plectoneme", CASE)
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    head = [f"# Twist-aware moves (dnabraid.run.twist_moves), {stamp}; {os.cpu_count()} cores "
            f"shared with other jobs (load average at start {os.getloadavg()[0]:.1f})",
            f"# defaults: mc_moves={s.mc_moves} per report interval, crank_angle_rad="
            f"{s.crank_angle_rad} (arcs of 1-12 beads, amplitude <= sweep_nm / rho), "
            f"pivot_angle_rad={s.pivot_angle_rad} (passage check), "
            f"frame_angle_rad={s.frame_angle_rad} (runs of 1-40 frames), bead_move_nm="
            f"{s.bead_move_nm}, sweep_nm={s.sweep_nm}, kinds 1:6:1:1"]
    lines = head + [""] + per_move() + [""]
    ref_lines, ref = reference(n_draws=args.draws)
    lines += ref_lines + [""]
    if args.wait and args.runs:
        names = [f"s{sd}_m{nm}" for sd in args.seeds for nm in (0, MOVES)]
        while not all(any(os.path.exists(os.path.join(dd, n, "summary.json"))
                          for dd in args.runs) for n in names):
            time.sleep(10)
    if not args.skip_runs:
        tmp = tempfile.mkdtemp(prefix="bench_plect_moves_")
        try:
            lines += runs(args.seeds, tmp, ref, args.runs)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    text = "\n".join(lines) + "\n"
    print(text)
    pathlib.Path(args.out).write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
