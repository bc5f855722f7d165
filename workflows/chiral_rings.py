"""The seed's chiral linked rings at T = 0 (issue 22 item 5; van der Heijden slides 31-32).

Two rings of length L linked once (Hopf link, Lk_12 = -1, left-handed: the Villarceau
start of slide 14), Delta/L = 0.02, C/B = 1.5, bilateral contact, chiral term
phi = alpha tan(eta/2) (dnabraid.statics.chiral_rings). For each ring linking number
Lk_i in (-1, 1, 3, 5): continue in Lk_i at alpha = 0 from the twist-free rings, then in
alpha from 0 up to 3500 B/L^2, recording T1 = 2 pi C (Lk_1 - Wr_1)/L (ring 1's twisting
moment, B/L), the writhes, the contact's braid angle eta and the lowest eigenvalue of the
Hessian (rigid and sliding modes projected out). The branches run in parallel processes;
each writes its rows as it goes.

Writes workflows/results/chiral_rings.json, chiral_rings.md, chiral_rings.png.
Run: nice -n 5 python workflows/chiral_rings.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import pathlib
import sys
import time

import numpy as np

from dnabraid.statics import chiral_rings as cr

OUT = pathlib.Path(__file__).parent / "results"
WORK = OUT / "chiral_rings.work"   # per-branch logs and bead positions (not committed)
LADDER = (-1.0, 1.0, 3.0, 5.0)
ALPHAS = (0.0, 500.0, 1000.0, 2000.0, 3500.0)
ALPHAS_LK_M1 = (0.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 3500.0)

#: Slide 32 read off by eye from the talk's plot (axes: alpha -1000 ... 3500 B/L^2,
#: T1 0 ... -12; inset alpha 1000-3500, T1 -1 ... -2). The seed is a text extraction
#: without the curves: only the axis ranges and branch labels are certain. These points
#: are the inset's range (the branch drawn through it) and are labelled "read-off".
SLIDE32_READ_OFF = {
    "axes": {"alpha_B_per_L2": [-1000, 3500], "T1_B_per_L": [-12, 0]},
    "inset": {"alpha_B_per_L2": [1000, 3500], "T1_B_per_L": [-2.0, -1.0]},
    "branches": ["a", "b", "c", "d", "e", "f"],
    "note": "text extraction of the slide: tick labels and branch letters only",
}


def row(lk, alpha, r, prob) -> dict:
    return {
        "lk_ring": lk, "alpha_B_per_L2": alpha,
        "T1_B_per_L": r["torque_per_ring_B_per_L"][0],
        "T2_B_per_L": r["torque_per_ring_B_per_L"][1],
        "twist_per_ring": r["twist_per_ring"], "writhe_per_ring": r["writhe_per_ring"],
        "linking_number": r["linking_number"],
        "eta_mean_rad": r["eta_mean_rad"], "eta_min_rad": r["eta_min_rad"],
        "eta_max_rad": r["eta_max_rad"], "contact_fraction": r["contact_fraction"],
        "pulling_fraction": r["pulling_fraction"],
        "lowest_eigenvalues_B_per_L3": r.get("lowest_eigenvalues_B_per_L3"),
        "energy_B_per_L": r["energy_B_per_L"],
        "energy_terms_B_per_L": r["energy_terms_B_per_L"],
        "converged": r["converged"], "iterations": r["iterations"],
        "max_gradient_B_per_L2": r["max_gradient_B_per_L2"],
        "wall_time_s": r["wall_time_s"],
    }


def branch(args) -> list:
    lk_target, alphas, quick = args
    WORK.mkdir(parents=True, exist_ok=True)
    log = WORK / f"branch_{lk_target:+.0f}.jsonl"
    log.write_text("")
    t0 = time.perf_counter()
    max_iter = 60 if quick else 120

    def say(msg):
        print(f"[Lk={lk_target:+.0f} {time.perf_counter() - t0:6.0f}s] {msg}", flush=True)

    m = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=0.0)
    r = cr.solve(m, stability=False, max_iter=max_iter)
    x = r["x"]
    say(f"twist-free rings: Wr = {r['writhe_per_ring'][0]:+.4f}, eta = "
        f"{r['eta_mean_rad']:+.4f} rad, {r['iterations']} it")
    # the twisted circles are an equilibrium for every Lk_i; past Michell's threshold
    # (Tw C/B > sqrt 3) they are a saddle, which solve() leaves along its negative mode
    rows = []
    prob = None
    for a in alphas:
        m = cr.ChiralRings(lk_ring=lk_target, alpha_B_per_L2=a)
        r = cr.solve(m, x, max_iter=max_iter)
        x = r["x"]
        rw = row(lk_target, a, r, prob)
        rows.append(rw)
        with log.open("a") as fh:
            fh.write(json.dumps(rw) + "\n")
        np.save(WORK / f"x_{lk_target:+.0f}_{a:.0f}.npy", x)
        say(f"alpha {a:6.0f}: T1 = {rw['T1_B_per_L']:+.3f} B/L, Wr = "
            f"{rw['writhe_per_ring'][0]:+.3f}, eta = {rw['eta_mean_rad']:+.4f} rad "
            f"[{rw['eta_min_rad']:+.3f}, {rw['eta_max_rad']:+.3f}], lam_min = "
            f"{rw['lowest_eigenvalues_B_per_L3'][0]:.3g} B/L^3, conv {rw['converged']} "
            f"({rw['iterations']} it)")
    return rows


def buckling(rows) -> dict:
    """First alpha bracket where lam_min changes sign or the writhe jumps (> 0.2 turns)."""
    for a, b in zip(rows[:-1], rows[1:]):
        la, lb = a["lowest_eigenvalues_B_per_L3"][0], b["lowest_eigenvalues_B_per_L3"][0]
        jump = abs(b["writhe_per_ring"][0] - a["writhe_per_ring"][0])
        if la > 0 >= lb or jump > 0.2:
            alpha_lin = (a["alpha_B_per_L2"] + (b["alpha_B_per_L2"] - a["alpha_B_per_L2"])
                         * la / (la - lb)) if la > 0 > lb else None
            return {"bracket_B_per_L2": [a["alpha_B_per_L2"], b["alpha_B_per_L2"]],
                    "writhe_jump": jump, "lam_min_zero_interpolated_B_per_L2": alpha_lin}
    return {"bracket_B_per_L2": None, "note": "no sign change or writhe jump on the "
            "alphas reached"}


def write_md(res) -> str:
    L = ["# The seed's chiral linked rings at T = 0 (`workflows/chiral_rings.py`)", "",
         "Two rings of length L, Hopf link (Lk_12 = -1, left-handed), Delta/L = 0.02, "
         f"C/B = {cr.DNA_TWIST_OVER_BEND}, bilateral contact, b = Delta/2 (100 beads per "
         "ring), phi = alpha tan(eta/2) per unit contact length (weight 1 at contact, C^2 "
         "decay over Delta/2). T1 = 2 pi C (Lk_1 - Wr_1)/L (ring 1's twisting moment, B/L); "
         "eta: mean braid angle over ring 1's beads in contact (rad, > 0 left-handed); "
         "lam_min: lowest Hessian eigenvalue (B/L^3) with rigid and sliding modes projected "
         "out. Units B = L = 1.", ""]
    for lk, rows in res["branches"].items():
        L += [f"## Lk_i = {lk}", "",
              "| alpha (B/L^2) | T1 (B/L) | Tw_1 | Wr_1 | eta mean | eta min | eta max | "
              "lam_min | E (B/L) | conv |", "|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            L.append(f"| {r['alpha_B_per_L2']:.0f} | {r['T1_B_per_L']:+.3f} | "
                     f"{r['twist_per_ring'][0]:+.3f} | {r['writhe_per_ring'][0]:+.3f} | "
                     f"{r['eta_mean_rad']:+.4f} | {r['eta_min_rad']:+.3f} | "
                     f"{r['eta_max_rad']:+.3f} | {r['lowest_eigenvalues_B_per_L3'][0]:.3g} | "
                     f"{r['energy_B_per_L']:.2f} | {r['converged']} |")
        L += ["", f"Buckling: {json.dumps(res['buckling'][lk])}", ""]
    L += ["## Ladder", "", "| Lk_i | eta at alpha=0 (rad) | Tw_1 at alpha=0 | T1 at alpha=0 "
          "(B/L) | buckling alpha bracket (B/L^2) |", "|---|---|---|---|---|"]
    for lk, rows in res["branches"].items():
        r0 = rows[0]
        L.append(f"| {lk} | {r0['eta_mean_rad']:+.4f} | {r0['twist_per_ring'][0]:+.3f} | "
                 f"{r0['T1_B_per_L']:+.3f} | {res['buckling'][lk]['bracket_B_per_L2']} |")
    L += ["", f"Wall time {res['wall_time_s']:.0f} s (summed solver time of the longest "
          "branch when assembled from the logs). "
          + ("" if res.get("complete", True) else "PARTIAL: assembled from the branch logs of "
             "an interrupted run; the missing alphas were not reached."), ""]
    return "\n".join(L)


def plot(res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for lk, rows in res["branches"].items():
        a = [r["alpha_B_per_L2"] for r in rows]
        ax[0].plot(a, [r["T1_B_per_L"] for r in rows], "o-", label=f"Lk_i = {lk}")
        ax[1].plot(a, [r["eta_mean_rad"] for r in rows], "o-", label=f"Lk_i = {lk}")
    s = SLIDE32_READ_OFF
    ax[0].add_patch(matplotlib.patches.Rectangle(
        (s["inset"]["alpha_B_per_L2"][0], s["inset"]["T1_B_per_L"][0]),
        s["inset"]["alpha_B_per_L2"][1] - s["inset"]["alpha_B_per_L2"][0],
        s["inset"]["T1_B_per_L"][1] - s["inset"]["T1_B_per_L"][0], fill=False, ls="--",
        color="k", label="slide 32 inset range (read-off)"))
    ax[0].axhspan(-12, 0, color="0.9", zorder=-1, label="slide 32 T1 axis range (read-off)")
    ax[0].set_xlabel("alpha (B/L^2)")
    ax[0].set_ylabel("T1 = 2 pi C (Lk_1 - Wr_1)/L (B/L)")
    ax[0].legend(fontsize=7)
    ax[1].axhline(0, color="k", lw=0.5)
    ax[1].set_xlabel("alpha (B/L^2)")
    ax[1].set_ylabel("mean contact eta (rad)")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def finish(branches: dict, wall_time_s: float, complete: bool) -> None:
    res = {"model": {"diameter_over_length": 0.02, "twist_over_bend": cr.DNA_TWIST_OVER_BEND,
                     "contact": "bilateral", "spacing_over_diameter": 0.5,
                     "n": 1, "handedness": "left"},
           "branches": branches, "complete": complete, "slide32_read_off": SLIDE32_READ_OFF}
    res["buckling"] = {k: buckling(v) for k, v in branches.items()}
    res["wall_time_s"] = wall_time_s
    (OUT / "chiral_rings.json").write_text(json.dumps(res, indent=1))
    (OUT / "chiral_rings.md").write_text(write_md(res))
    plot(res, OUT / "chiral_rings.png")
    print(f"wrote {OUT / 'chiral_rings.json'} ({'complete' if complete else 'partial'})",
          flush=True)


def assemble() -> int:
    branches = {}
    wall = 0.0
    for lk in LADDER:
        f = WORK / f"branch_{lk:+.0f}.jsonl"
        rows = [json.loads(t) for t in f.read_text().splitlines() if t.strip()] \
            if f.exists() else []
        if rows:
            branches[f"{lk:+.0f}"] = rows
            wall = max(wall, sum(r["wall_time_s"] for r in rows))
    finish(branches, wall, complete=False)
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer alphas and iterations")
    ap.add_argument("--workers", type=int, default=4)
    ap.add_argument("--assemble", action="store_true",
                    help="only write the results from the branch logs already written "
                         "(chiral_rings.work/branch_*.jsonl), e.g. of an interrupted run")
    a = ap.parse_args(argv)
    OUT.mkdir(exist_ok=True)
    if a.assemble:
        return assemble()
    t0 = time.perf_counter()
    jobs = []
    for lk in LADDER:
        al = ALPHAS_LK_M1 if lk == -1 else ALPHAS
        if a.quick:
            al = al[::2]
        jobs.append((lk, al, a.quick))
    with mp.get_context("fork").Pool(a.workers) as pool:
        out = pool.map(branch, jobs, chunksize=1)
    finish({f"{lk:+.0f}": rows for lk, rows in zip(LADDER, out)},
           time.perf_counter() - t0, complete=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
