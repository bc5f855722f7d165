"""Catenane handedness from alpha = 0 runs reweighted to every alpha, with hybrid BD/MC.

The chiral energy is linear in alpha, U_chiral = alpha W(x) (W the contact integral of
tan(eta/2), the numpy twin with alpha = 1), so one ensemble at alpha_0 gives every other
alpha exactly by reweighting (Zwanzig 1954; Shirts & Chodera 2008 for the multistate form):

    <A>_alpha = <A exp(-(alpha - alpha_0) W / kT)>_alpha_0 / <exp(-(alpha - alpha_0) W / kT)>_alpha_0

as long as the weights do not collapse (their effective sample size is reported per alpha).
Runs (scene ``catenane`` with its Metropolis rigid-body and crankshaft moves,
dnabraid.moves; 8 replicas, half started apart, half in contact):

1. ``a0_dlk-1``: alpha = 0, Delta Lk_i = -1, Lk_12 = +1;
2. ``a0_dlk+1``: its mirror image, alpha = 0, Delta Lk_i = +1, Lk_12 = -1;
3. ``a+3_dlk-1``, ``a+6_dlk-1``: alpha = +3 and +6 pN, Delta Lk_i = -1, run directly (check
   the reweighting; at +3 the weights keep ~74 % of the frames: the sharp check, as long as
   the ensembles; at +6 ~3 %: a short, weak check);
4. ``ring``: one 144-nm ring at the same time step, <dTw_half^2> against L / (4 pi^2 C)
   (exact for the model: the moves and the step leave it unbiased).

From the frames (``frame_interval`` steps apart) it computes W, the contact length, the
contact-averaged folded braid angle eta and both writhes, reweights them to a grid of alpha,
and reports per alpha: <eta>_contact, the contact fraction, <Wr_i>, the weights' ESS; the
handedness switch alpha* where <eta>_contact(alpha) = 0 (errors from the scatter of the
replicas' own reweighted curves, each replica an independent run); the exact symmetry
<Wr>(alpha, -1) = -<Wr>(-alpha, +1) from the two independent ensembles; and the direct run
against the reweighted prediction. Writes workflows/results/catenane_reweight.md/.json/.png.

Usage: python workflows/catenane_reweight.py [--steps 400000] [--replicas 8]
       [--out runs/catenane_rw] [--runs-only]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import time

import numpy as np

from dnabraid.scenes import make_scene
from dnabraid.sweep import run_or_load

HERE = pathlib.Path(__file__).resolve().parent

POINTS = {
    "a0_dlk-1": {"alpha": 0.0, "delta_lk": -1, "link": 1},
    "a0_dlk+1": {"alpha": 0.0, "delta_lk": 1, "link": -1},
    "a+6_dlk-1": {"alpha": 6.0, "delta_lk": -1, "link": 1},
    "a+3_dlk-1": {"alpha": 3.0, "delta_lk": -1, "link": 1},
}
#: the direct runs: tag -> alpha (pN)
DIRECT = {"a+6_dlk-1": 6.0, "a+3_dlk-1": 3.0}
#: the rings: 424 bp at 1 M (the scene's default, Delta/L = 0.02) with every run; 720 bp at
#: 150 mM (Delta = 4.9 nm, Delta/L = 0.02 too; 50 beads of 4.896 nm) with the two alpha = 0
#: ensembles (no direct run, no ring)
SYSTEMS = {
    "424bp": ({}, tuple(POINTS), True),
    "720bp": ({"length_nm": 244.8, "salt_mM": 150.0, "bead_spacing_nm": 4.896},
              ("a0_dlk-1", "a0_dlk+1"), False),
}


def common_keys(args) -> dict:
    return {"steps": args.steps, "equilibration_steps": args.equilibration,
            "replicas": args.replicas, "integrator": "lm", "start": "mixed",
            "timestep_safety": args.safety, "frame_interval": args.frame_interval,
            "report_interval": 100}


def run_all(args, log) -> dict:
    out = {}
    geometry, tags, with_ring = SYSTEMS[args.system]
    c = {**common_keys(args), **geometry}
    for tag in tags:
        keys = {**c, **POINTS[tag]}
        if tag == "a+6_dlk-1":  # the weak check, where the weights collapse: short
            keys["steps"] = args.direct_steps
        out[tag] = run_or_load("catenane", keys, os.path.join(args.out, tag), report=log)
        print(f"{tag}: done ({out[tag]['wall_time_s']:.0f} s)", flush=True)
    if not with_ring:
        return out
    ring = {**c, "rings": 1, "steps": args.ring_steps, "replicas": 4, "start": "apart"}
    out["ring"] = run_or_load("catenane", ring, os.path.join(args.out, "ring"), report=log)
    print(f"ring: done ({out['ring']['wall_time_s']:.0f} s)", flush=True)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=400_000)
    ap.add_argument("--direct-steps", type=int, default=120_000)
    ap.add_argument("--ring-steps", type=int, default=100_000)
    ap.add_argument("--equilibration", type=int, default=40_000)
    ap.add_argument("--replicas", type=int, default=8)
    ap.add_argument("--safety", type=float, default=0.6)
    ap.add_argument("--frame-interval", type=int, default=1000)
    ap.add_argument("--system", default="424bp", choices=sorted(SYSTEMS))
    ap.add_argument("--out", default=None, help="default runs/catenane_rw[_720bp]")
    ap.add_argument("--runs-only", action="store_true")
    ap.add_argument("--stride", type=int, default=2, help="use every stride-th frame")
    ap.add_argument("--table", default=None,
                    help="default workflows/results/catenane_reweight[_720bp].md")
    args = ap.parse_args(argv)
    suffix = "" if args.system == "424bp" else f"_{args.system}"
    args.out = args.out or f"runs/catenane_rw{suffix}"
    args.table = args.table or str(HERE / "results" / f"catenane_reweight{suffix}.md")
    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    with open(os.path.join(args.out, "reports.md"), "a") as log:
        runs = run_all(args, log)
    if args.runs_only:
        return 0
    write_report(runs, args, time.perf_counter() - t0)
    return 0


# -- analysis ----------------------------------------------------------------------------
BURN_IN = 0.2  # fraction of each replica's frames dropped (>> the writhe's ~5e3 steps)
#: reweighted values whose weights keep less than this fraction of the frames are flagged,
#: and the switch alpha* is sought only where they keep more
MIN_ESS_FRACTION = 0.1


def replica_frames(run_dir: str, scene, stride: int) -> list[dict]:
    """Per replica: W (chiral energy per unit alpha, pN nm / pN), contact length c (nm), the
    contact-averaged folded braid angle eta (0 without contact) and both writhes, at every
    ``stride``-th frame after the burn-in."""
    import glob

    from dnabraid.forces.reference_chiral import chiral_energy_forces
    from dnabraid.run import reporters
    from dnabraid.scenes.catenane import ChiralEnergy

    model = scene.build()
    d = model.dna
    rings = model.rings
    kw = ChiralEnergy(rings, 1.0, d.diameter_nm, d.debye_nm, d.bead_spacing_nm).kw
    out = []
    for rd in sorted(glob.glob(os.path.join(run_dir, "replicas", "r*", "points", "*"))):
        samples, _ = reporters.read_point(rd)
        step = samples["step"]
        frames = list(reporters._dcd_frames(os.path.join(rd, "trajectory.dcd")))
        fsteps = reporters.read_csv(os.path.join(rd, "frames.csv"))["step"]
        first = int(BURN_IN * len(frames))
        rows = {k: [] for k in ("W", "c", "eta", "wr1", "wr2", "incontact", "step")}
        for i in range(first, len(frames), stride):
            j = int(np.searchsorted(step, fsteps[i]))
            assert step[j] == fsteps[i]
            c = float(samples["contact_length_nm"][j])
            eta = float(samples["braid_angle_rad"][j]) if c > 0 else 0.0
            rows["W"].append(chiral_energy_forces(frames[i], rings, 1.0, **kw)[0])
            rows["c"].append(c)
            rows["eta"].append(eta)
            rows["incontact"].append(float(c > 0))
            rows["wr1"].append(float(samples["writhe_1"][j]))
            rows["wr2"].append(float(samples["writhe_2"][j]))
            rows["step"].append(float(fsteps[i]))
        r = {k: np.asarray(v, float) for k, v in rows.items()}
        r["wr"] = 0.5 * (r["wr1"] + r["wr2"])
        out.append(r)
    return out


def _verdict(reps, col) -> dict:
    from dnabraid.analysis.convergence import (
        MIN_ESS_RELAXED,
        RHAT_MAX_RELAXED,
        replica_summary,
    )

    r = replica_summary([x[col] for x in reps], rhat_max=RHAT_MAX_RELAXED,
                        min_ess=MIN_ESS_RELAXED, equilibration=None)
    return {"mean": r["mean"], "sem": r["sem"], "rhat": r["rhat"], "ess": r["ess"],
            "converged": bool(r["converged"])}


def write_report(runs: dict, args, wall: float) -> None:
    from dnabraid.analysis.reweight import ReplicaReweighting
    from dnabraid.analysis.stats import bimodality

    grid = np.round(np.arange(-10.0, 10.0001, 0.5), 6)
    tags = [t for t in POINTS if t in runs]
    mirror = "a0_dlk+1" in runs
    scene = {t: make_scene("catenane", {k: v for k, v in runs[t]["scene"].items()
                                        if k != "scene"}) for t in tags}
    kT = scene["a0_dlk-1"].kT
    t0 = time.perf_counter()
    frames = {t: replica_frames(runs[t]["_out"], scene[t], args.stride) for t in tags}
    t_frames = time.perf_counter() - t0
    rw = {t: ReplicaReweighting(frames[t], float(runs[t]["scene"]["alpha"]), kT)
          for t in tags}
    cols = {"eta": ("eta*c", "c"), "contact": ("incontact", None), "wr": ("wr", None),
            "c": ("c", None)}
    curves = {}
    for t in [t for t in ("a0_dlk-1", "a0_dlk+1") if t in runs]:
        curves[t] = {k: [rw[t].mean(a, *v) for a in grid] for k, v in cols.items()}
        curves[t]["ess"] = [rw[t].ess(a) for a in grid]
    def trusted(t):
        # the contiguous alphas about alpha_0 whose weights keep >= MIN_ESS_FRACTION of the
        # frames (beyond, a few frames carry the average: not a result)
        n = sum(len(r["W"]) for r in frames[t])
        ok = np.asarray(curves[t]["ess"]) >= MIN_ESS_FRACTION * n
        i0 = int(np.argmin(abs(grid)))
        lo, hi = i0, i0
        while lo > 0 and ok[lo - 1]:
            lo -= 1
        while hi < len(grid) - 1 and ok[hi + 1]:
            hi += 1
        return grid[lo:hi + 1]

    root_m, root_se = rw["a0_dlk-1"].root(trusted("a0_dlk-1"), "eta*c", "c")
    root_p, root_p_se = (rw["a0_dlk+1"].root(trusted("a0_dlk+1"), "eta*c", "c") if mirror
                         else (math.nan, math.nan))
    # direct runs against the reweighted alpha = 0 ensemble
    direct = {f"{a:g}": {"direct": {k: rw[t].mean(a, *v) for k, v in cols.items()},
                         "reweighted": {k: rw["a0_dlk-1"].mean(a, *v) for k, v in cols.items()},
                         "ess_fraction": rw["a0_dlk-1"].ess(a)
                         / sum(len(r["W"]) for r in frames["a0_dlk-1"])}
              for t, a in DIRECT.items() if t in runs}
    verdicts = {t: {c: _verdict(frames[t], c) for c in ("wr1", "wr2", "c", "W")}
                for t in tags}
    ring = runs["ring"]["points"][0] if "ring" in runs else None
    sc = scene["a0_dlk-1"]
    B = sc.persistence_nm * kT
    L = sc.length_nm
    res = {"grid_pN": grid.tolist(), "kT_pN_nm": kT, "B_pN_nm2": B, "L_nm": L,
           "system": args.system, "salt_mM": sc.salt_mM,
           "diameter_nm": sc.effective_diameter_nm,
           "curves": {t: {k: [list(x) if isinstance(x, tuple) else x for x in v]
                          for k, v in c.items()} for t, c in curves.items()},
           "alpha_star_pN": {"dlk-1": [root_m, root_se], "dlk+1_mirrored": [-root_p,
                                                                              root_p_se]},
           "direct": direct, "verdicts": verdicts,
           "ring_twist_half_variance": ring and ring["twist_half_variance_1"],
           "ring_twist_half_variance_theory": ring and ring["twist_half_variance_theory"],
           "rigid_moves": {t: runs[t]["points"][0].get("rigid_moves") for t in tags},
           "wall_s": {t: runs[t]["wall_time_s"] for t in runs}, "frames_s": t_frames,
           "n_frames": {t: int(sum(len(r["W"]) for r in frames[t])) for t in tags},
           "writhe_bimodality": {t: bimodality(np.concatenate([r["wr1"] for r in frames[t]]
                                                               + [r["wr2"] for r in frames[t]]))
                                 for t in tags}}
    base = os.path.splitext(args.table)[0]
    with open(base + ".json", "w") as fh:
        json.dump(res, fh, indent=1, default=float)
    _plot(res, base + ".png")
    _write_md(res, args, wall, base + ".md")
    print(open(base + ".md").read())


def _f(x, p=3):
    m, s = x
    return f"{m:+.{p}f} +- {s:.{p}f}" if np.isfinite(m) else "-"


def _write_md(res, args, wall, path) -> None:
    g = np.asarray(res["grid_pN"])
    cm = res["curves"]["a0_dlk-1"]
    cp = res["curves"].get("a0_dlk+1")
    idx = {a: int(np.argmin(abs(g - a))) for a in (-8, -6, -4, -2, -1, 0, 1, 2, 4, 6, 8)}
    n0 = res["n_frames"]["a0_dlk-1"]
    L, B = res["L_nm"], res["B_pN_nm2"]
    lines = [f"# catenane: handedness by reweighting in alpha, {time.strftime('%Y-%m-%d %H:%M')}",
             "", f"Two linked {L:g}-nm rings ({L / 0.34:.0f} bp) at {res['salt_mM']:g} mM NaCl "
             f"(Delta = {res['diameter_nm']:.2f} nm, Delta/L = {res['diameter_nm'] / L:.3f}), "
             "A = 50 nm, C = 100 nm, "
             f"Brownian dynamics (Leimkuhler-Matthews, safety {args.safety}) with Metropolis "
             "rigid-body and crankshaft moves (`dnabraid.run.moves`), "
             f"{args.replicas} replicas per run (half started apart, half in contact), "
             f"{args.steps} sampling steps each after "
             f"{args.equilibration}; frames every {args.frame_interval} steps, the first "
             f"{BURN_IN:.0%} dropped, one frame in {args.stride} used. Reweighting "
             "is exact because U_chiral = alpha W (`dnabraid.analysis.reweight`); +- is the "
             "jackknife standard error over the independent replicas.", "",
             "## Convergence (split R-hat and bulk ESS over replicas, frame series)", "",
             "| run | Wr_1 | Wr_2 | contact length (nm) | W (pN nm/pN) | converged |",
             "|---|---|---|---|---|---|"]
    for t, v in res["verdicts"].items():
        cells = [f"{v[c]['mean']:+.3f} +- {v[c]['sem']:.3f} (R-hat {v[c]['rhat']:.3f}, "
                 f"ESS {v[c]['ess']:.0f})" for c in ("wr1", "wr2", "c", "W")]
        lines.append(f"| {t} | " + " | ".join(cells) + " | "
                     f"{all(v[c]['converged'] for c in v)} |")
    lines += ["", "Moves (acceptance over equilibration and sampling):", ""]
    for t, m in res["rigid_moves"].items():
        if m:
            lines.append(f"- {t}: " + ", ".join(
                f"{k} {m[k]['acceptance']:.2f} ({m[k]['attempted']} tried, "
                f"{m[k]['refused_by_constraint']} refused by the topology check)"
                for k in ("shift", "turn", "arc") if k in m))
    lines += ["", "Writhe distribution per ring, both rings pooled (buckling shows as two modes, "
              "Sarle's BC > 5/9):", ""]
    for t, b in res["writhe_bimodality"].items():
        lines.append(f"- {t}: <Wr> {b['mean']:+.3f}, sd {b['sd']:.3f}, skew {b['skew']:+.2f}, "
                     f"BC {b['bc']:.3f}")
    title = ("## Reweighted from alpha = 0 (Delta Lk_i = -1, Lk_12 = +1)"
             + (" and its mirror image (Delta Lk_i = +1, Lk_12 = -1, read at -alpha)"
                if cp else ""))
    lines += ["", title, "",
              "| alpha (pN) | alpha L^2/B | <eta>_contact (rad) | mirror: -<eta>(-alpha) | "
              "in contact | <Wr> per ring | mirror: -<Wr>(-alpha) | symmetry z (Wr) | "
              "weights' ESS / frames |", "|---|---|---|---|---|---|---|---|---|"]
    for a, i in idx.items():
        eta, wr = cm["eta"][i], cm["wr"][i]
        if cp:
            j = int(np.argmin(abs(g + a)))
            etam, wrm = cp["eta"][j], cp["wr"][j]
            z = (wr[0] + wrm[0]) / math.hypot(wr[1], wrm[1])
            mir = (f"{_f((-etam[0], etam[1]))}", f"{_f((-wrm[0], wrm[1]))}", f"{z:+.2f}")
        else:
            mir = ("-", "-", "-")
        lines.append(f"| {a:+g} | {a * L * L / B:+.0f} | {_f(eta)} | {mir[0]} "
                     f"| {_f(cm['contact'][i], 2)} | {_f(wr)} | {mir[1]} | {mir[2]} | "
                     f"{cm['ess'][i] / n0:.2f}"
                     f"{' (too few: not a result)' if cm['ess'][i] < MIN_ESS_FRACTION * n0 else ''}"
                     " |")
    am, ap = res["alpha_star_pN"]["dlk-1"], res["alpha_star_pN"]["dlk+1_mirrored"]
    lines += ["", "## Where the link's handedness switches (<eta>_contact = 0)", "",
              f"(sought where the weights keep >= {MIN_ESS_FRACTION:.0%} of the frames)", "",
              f"- from the Delta Lk = -1 ensemble: alpha* = {am[0]:+.2f} +- {am[1]:.2f} pN "
              f"({am[0] * L * L / B:+.0f} +- {am[1] * L * L / B:.0f} B/L^2)"]
    if cp:
        lines.append(f"- from its mirror image (Delta Lk = +1, sign reversed): alpha* = "
                     f"{ap[0]:+.2f} +- {ap[1]:.2f} pN")
    if cp and np.isfinite(am[1]) and np.isfinite(ap[1]) and am[1] > 0 and ap[1] > 0:
        w1, w2 = 1 / am[1] ** 2, 1 / ap[1] ** 2
        comb = (am[0] * w1 + ap[0] * w2) / (w1 + w2)
        lines += [f"- the two agree within {abs(am[0] - ap[0]) / math.hypot(am[1], ap[1]):.2f}"
                  f" SE; combined alpha* = {comb:+.2f} +- {1 / math.sqrt(w1 + w2):.2f} pN "
                  f"({comb * L * L / B:+.0f} B/L^2)"]
    for a, dd in res["direct"].items():
        d, p = dd["direct"], dd["reweighted"]
        lines += ["", f"## Direct run at alpha = {a} pN against the reweighted alpha = 0 "
                  f"ensemble (weights keep {dd['ess_fraction']:.0%} of the frames)", "",
                  "| observable | direct | reweighted from alpha = 0 | z |", "|---|---|---|---|"]
        for k, name in (("eta", "<eta>_contact (rad)"), ("contact", "in contact"),
                        ("wr", "<Wr> per ring"), ("c", "contact length (nm)")):
            z = (d[k][0] - p[k][0]) / math.hypot(d[k][1], p[k][1])
            lines.append(f"| {name} | {_f(d[k])} | {_f(p[k])} | {z:+.2f} |")
    r = res["ring_twist_half_variance"]
    if r:
        lines += ["", f"Single {L:g}-nm ring at the same step and moves: <dTw_half^2> = "
                  f"{r['mean']:.4f} +- {r['sem']:.4f} turns^2 against L/(4 pi^2 C) = "
                  f"{res['ring_twist_half_variance_theory']:.4f}."]
    lines += ["", "Wall time (s): " + ", ".join(f"{t} {w:.0f}" for t, w in res["wall_s"].items())
              + f"; chiral integral W on the frames {res['frames_s']:.0f} s; this report "
              f"{wall:.0f} s in all (finished runs are loaded, not rerun)."]
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def _plot(res, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = np.asarray(res["grid_pN"])
    fig, axs = plt.subplots(1, 3, figsize=(13, 3.8))
    for t, lab, sgn in (("a0_dlk-1", "Delta Lk = -1", 1), ("a0_dlk+1", "mirror (+1), -alpha", -1)):
        c = res["curves"].get(t)
        if c is None:
            continue
        for ax, k in zip(axs, ("eta", "contact", "wr")):
            m = np.array([x[0] for x in c[k]])
            s = np.array([x[1] for x in c[k]])
            sk = sgn if k in ("eta", "wr") else 1
            x = g * sgn
            o = np.argsort(x)
            ax.plot(x[o], sk * m[o], label=lab)
            ax.fill_between(x[o], (sk * m - 2 * s)[o], (sk * m + 2 * s)[o], alpha=0.25)
    for ax, k in zip(axs, ("eta", "contact", "wr")):
        for a, dd in res["direct"].items():
            d = dd["direct"][k]
            ax.errorbar([float(a)], [d[0]], yerr=[2 * d[1]], fmt="ko",
                        label="direct runs" if a == next(iter(res["direct"])) else None)
        ax.set_xlabel("alpha (pN)")
    axs[0].axhline(0, color="grey", lw=0.5)
    axs[0].set_ylabel("contact-averaged eta (rad; < 0 right-handed)")
    axs[1].set_ylabel("fraction of frames in contact")
    axs[2].set_ylabel("<Wr> per ring (turns)")
    axs[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    raise SystemExit(main())
