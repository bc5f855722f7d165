"""The hat curve of torsionally constrained DNA: extension and torque against turns.

Runs the ``plectoneme`` scene over a turn range, then compares with rod theory
(:func:`dnabraid.analysis.hat_curve.hat_curve`):

* below buckling, the torque slope gives an effective twist stiffness
  C_eff = (dGamma/dn) L / (2 pi kT), against Moroz & Nelson (PNAS 94, 14418 (1997), Eq. 12):
  C_eff(F) = C (1 - (C / 4A) sqrt(kT / (A F))) (A, C persistence lengths in nm);
* the buckling point (first turn value with a plectoneme in more than half the frames) and
  the torque plateau after it, against the classical buckling torque
  Gamma_b = sqrt(2 kT A F) (kT A the bending stiffness in pN nm^2).

The torque is the twist torque 2 pi Tw C kT / L (exact in the mean, low noise; the trap's
torque is printed beside it). Prints the table and writes it to
workflows/results/plectoneme_hat.txt (the run directory is kept and resumed).

    taskset -c 0 python workflows/plectoneme_hat.py --force 1 --length 100

Measured (defaults, F = 1 pN, L = 100 nm, one loaded core, 220 s): C_eff = 93.8 +- 0.8 nm
from the slope (dominated by n = 0.5; n = 1 alone gives 88 +- 3) against Moroz-Nelson's
85.7 nm; plectonemes from n = 1.5 (28 % of frames) to 2 (all frames); plateau torque
26.5 +- 0.7 pN nm against sqrt(2 kT A F) = 20.3 pN nm. The SEMs assume the sampling spans
many correlation times of the bending modes (~1e6 steps for 100 nm at 1 pN, see
tests/test_tweezer.py): treat them as lower bounds.
"""

from __future__ import annotations

import argparse
import os

from dnabraid.analysis.hat_curve import hat_curve
from dnabraid.scenes import make_scene


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--force", type=float, default=1.0)
    ap.add_argument("--length", type=float, default=100.0)
    ap.add_argument("--turns", default="0,0.5,1,1.5,2,2.5,3")
    ap.add_argument("--steps", type=int, default=150000)
    ap.add_argument("--equilibration", type=int, default=50000)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--replicas", type=int, default=None,
                    help="independent replicas per turn value (default: the scene's)")
    # the sampling of the stored results (workflows/results/plectoneme_hat*.txt): the
    # scene's defaults until 2026-12-04, before they became 20 000 moves per 50 steps
    ap.add_argument("--mc-moves", type=int, default=500,
                    help="twist-aware moves per report interval")
    ap.add_argument("--report-interval", type=int, default=100, help="steps between samples")
    ap.add_argument("--protocol", default="independent", choices=("independent", "ramp"))
    ap.add_argument("--turn-rate", type=float, default=5e-5, help="turns per step of the ramp")
    ap.add_argument("--frame-interval", type=int, default=2000)
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--run", default=None, help="run directory (default results/plectoneme_F..)")
    ap.add_argument("--out", default=os.path.join(here, "results", "plectoneme_hat.txt"))
    ap.add_argument("--summary", default=None,
                    help="analyse the summary.json of a finished run instead of running")
    a = ap.parse_args(argv)
    s = make_scene("plectoneme", {
        "force_pN": a.force, "length_nm": a.length,
        "turns": [float(x) for x in a.turns.split(",")], "steps": a.steps,
        "equilibration_steps": a.equilibration, "frame_interval": a.frame_interval,
        "seed": a.seed, "protocol": a.protocol,
        **({"replicas": a.replicas} if a.replicas else {}),
        "mc_moves": a.mc_moves, "report_interval": a.report_interval,
        "turn_rate": a.turn_rate})
    run = a.run or os.path.join(here, "results", f"plectoneme_F{a.force:g}_L{a.length:g}")
    if a.summary:
        import json
        with open(a.summary) as fh:
            summ = json.load(fh)
        run = os.path.dirname(os.path.abspath(a.summary))
        a.force, a.length = summ["scene"]["force_pN"], summ["scene"]["length_nm"]
        s = make_scene("plectoneme", {k: v for k, v in summ["scene"].items() if k != "scene"})
    else:
        summ = s.run(run)
    pts, res = hat_curve(summ)
    lines = [f"# plectoneme scene F = {a.force} pN, L = {a.length} nm, A = {s.persistence_nm} nm, "
             f"C = {s.twist_persistence_nm} nm, {s.salt_mM} mM; run {run}; wall "
             f"{summ['wall_time_s']:.0f} s, {summ['ns_per_bead_per_step'] or float('nan'):.0f} "
             f"ns/particle/step, dt {summ['time_step_ps']:.2f} ps",
             f"{'turns':>6} {'ext_nm':>8} {'+-':>5} {'twist_tq':>9} {'+-':>5} {'trap_tq':>8} "
             f"{'+-':>6} {'Tw':>6} {'Wr':>6} {'Lk':>6} {'plect':>6} {'L_pl_nm':>8}"]
    for p in pts:
        e, t, tr = p["extension_nm"], p["twist_torque_pN_nm"], p["torque_pN_nm"]
        lines.append(f"{p['turns']:>6.2f} {e['mean']:>8.2f} {e['sem']:>5.2f} {t['mean']:>9.2f} "
                     f"{t['sem']:>5.2f} {tr['mean']:>8.1f} {tr['sem']:>6.1f} "
                     f"{p['twist']['mean']:>6.3f} {p['writhe']['mean']:>6.3f} "
                     f"{p['linking']['mean']:>6.3f} {p['plectoneme_fraction']:>6.2f} "
                     f"{p['plectoneme_length_nm']['mean']:>8.1f}")
    lines.append(f"C_eff (Moroz & Nelson 1997, Eq. 12) = {res['ceff_theory']:.1f} nm; simulated "
                 + (f"{res['ceff_sim']:.1f} +- {res['ceff_sim_err']:.1f} nm (torque slope below "
                    "buckling)" if "ceff_sim" in res else "n/a (fewer than 2 unbuckled points)"))
    lines.append(f"buckling torque sqrt(2 kT A F) = {res['gamma_b_theory']:.1f} pN nm; simulated "
                 f"plateau torque " + (f"{res['plateau_torque']:.1f} +- "
                                       f"{res['plateau_torque_err']:.1f} pN nm" if
                                       "plateau_torque" in res else "n/a (no buckling)")
                 + f"; buckling at n = {res['n_buckle']} turns")
    if "slope_sim" in res and "slope_two_phase" in res:
        lines.append(
            f"slope after buckling {res['slope_sim']:.1f} +- {res['slope_sim_err']:.1f} nm/turn; "
            f"two-phase coexistence (Marko 2007) -pi x tau / g at the plateau torque: "
            f"{res['slope_two_phase']:.1f} +- {res['slope_two_phase_err']:.1f} nm/turn; "
            f"implied plectoneme twist stiffness P = {res['P_implied']:.1f} nm; two-phase onset "
            f"at n = {res['n_onset_two_phase']:.2f} turns")
    n_conv = sum(1 for p in pts if p.get("converged"))
    lines.append(f"converged points: {n_conv} of {len(pts)}")
    text = "\n".join(lines)
    print(text)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as fh:
        fh.write(text + "\n")
    from dnabraid.plots import hat_curve_plot
    png = hat_curve_plot(pts, res, os.path.splitext(a.out)[0] + ".png",
                         f"plectoneme {a.length:g} nm, {a.force:g} pN")
    print(f"plot: {png}")
    return res


if __name__ == "__main__":
    main()
