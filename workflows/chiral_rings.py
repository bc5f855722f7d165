"""The seed's chiral linked rings at T = 0 (issue 22 item 5; van der Heijden slides 31-32).

Two rings of length L linked once (Hopf link, Lk_12 = -1, left-handed: the Villarceau
start of slide 14), Delta/L = 0.02, C/B = 1.5, bilateral contact, chiral term
phi = alpha tan(eta/2) along the contact (dnabraid.statics.chiral_rings). Natural-parameter
continuation (``chiral_rings.continuation``):

* the Lk scans: at alpha = 0, each ring's Lk_i from 0 to +5, -5, -1, +1 in steps of 1/4
  (halved where Newton does not converge); the circles buckle at Michell's threshold and
  the pair jumps to a writhed, self-touching branch;
* the alpha scans: from the alpha = 0 state at Lk_i = +-5 (the slide's case), -1 and +1,
  alpha up to 3500 B/L^2 and down to -1000 (slide 32's axis) in steps of 250.

Each row: T1 = 2 pi C (Lk_1 - Wr_1)/L (ring 1's twisting moment, B/L), the writhes, the
contact's braid angle eta, the lowest eigenvalue of the Hessian (rigid and sliding modes
projected out), whether the branch was left (a jump). The scans run in parallel processes
and write their rows as they go (``chiral_rings.work/*.jsonl``); ``--assemble`` writes the
results from those logs.

Writes workflows/results/chiral_rings.json, chiral_rings.md, chiral_rings.png,
chiral_rings_shapes.png.
Run: OMP_NUM_THREADS=1 python workflows/chiral_rings.py [--workers 2]
     OMP_NUM_THREADS=1 python workflows/chiral_rings.py --continue lk_minus5_up2 -5 375 3500 62.5
     OMP_NUM_THREADS=1 python workflows/chiral_rings.py --continue lk_down_up -1 0 625 62.5 62.5
     OMP_NUM_THREADS=1 python workflows/chiral_rings.py --mirror   (the other hand at +3)
     python workflows/chiral_rings.py --assemble
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import pathlib
import sys
import time

import numpy as np

from dnabraid.statics import chiral_rings as cr

OUT = pathlib.Path(__file__).parent / "results"
WORK = OUT / "chiral_rings.work"   # per-scan logs and bead positions (not committed)
LK_STEP = 0.25
ALPHA_STEP = 250.0
ALPHA_MAX, ALPHA_MIN = 3500.0, -1000.0
#: (name, Lk_i targets of the alpha = 0 scan, the Lk_i whose alpha scans follow)
SCANS = (("lk_up", (3.0, 5.0), (5.0,)), ("lk_minus5", (-5.0,), (-5.0,)),
         ("lk_down", (-1.0,), (-1.0,)), ("lk_one", (1.0,), (1.0,)))

#: Slide 32 as far as the seed's text extraction carries it: tick labels and branch letters,
#: no curve data. Main axes alpha -1000 ... 3500 B/L^2, T1 0 ... -12; inset alpha
#: 1000-3500, T1 -1 ... -2; branches a-f; "Material frames closed with linking numbers
#: Lk_i = 5"; "Transition from left-handed (Lk = -1) to right-handed link (Lk = 1);
#: Lk_i = 5 + 2 = 7".
SLIDE32_READ_OFF = {
    "axes": {"alpha_B_per_L2": [-1000, 3500], "T1_B_per_L": [-12, 0]},
    "inset": {"alpha_B_per_L2": [1000, 3500], "T1_B_per_L": [-2.0, -1.0]},
    "branches": ["a", "b", "c", "d", "e", "f"],
    "note": "text extraction of the slide: tick labels and branch letters only",
}


def row(phase, r) -> dict:
    lam = r.get("lowest_eigenvalues_B_per_L3")
    return {
        "phase": phase, "lk_ring": r["lk"], "alpha_B_per_L2": r["alpha"],
        "T1_B_per_L": r["torque_per_ring_B_per_L"][0],
        "T2_B_per_L": r["torque_per_ring_B_per_L"][1],
        "twist_per_ring": r["twist_per_ring"], "writhe_per_ring": r["writhe_per_ring"],
        "linking_number": r["linking_number"],
        "eta_mean_rad": r["eta_mean_rad"], "eta_min_rad": r["eta_min_rad"],
        "eta_max_rad": r["eta_max_rad"],
        "eta_folded_mean_rad": r.get("eta_folded_mean_rad"),
        "contact_fraction": r["contact_fraction"],
        "pulling_fraction": r["pulling_fraction"],
        "max_overlap_over_diameter": r["max_overlap_over_diameter"],
        "lowest_eigenvalues_B_per_L3": lam,
        "energy_B_per_L": r["energy_B_per_L"],
        "energy_terms_B_per_L": r["energy_terms_B_per_L"],
        "converged": r["converged"], "iterations": r["iterations"],
        "max_gradient_B_per_L2": r["max_gradient_B_per_L2"],
        "saddle_escapes": r.get("saddle_escapes", 0), "jump": r.get("jump", 0.0),
        "branch_left": r.get("branch_left", False), "step": r.get("step"),
        "gtol_B_per_L2": r.get("gtol_B_per_L2"), "wall_time_s": r["wall_time_s"],
    }


def _log(name):
    return WORK / f"{name}.jsonl"


def scan(job) -> str:
    """One process: the alpha = 0 Lk scan to each target, then the alpha scans."""
    name, lk_targets, alpha_lks = job
    WORK.mkdir(parents=True, exist_ok=True)
    log = _log(name)
    log.write_text("")
    t0 = time.perf_counter()

    def say(msg):
        print(f"[{name} {time.perf_counter() - t0:6.0f}s] {msg}", flush=True)

    def keep(phase, r, lk, alpha):
        r["lk"], r["alpha"] = lk, alpha
        rw = row(phase, r)
        with log.open("a") as fh:
            fh.write(json.dumps(rw) + "\n")
        lam = rw["lowest_eigenvalues_B_per_L3"]
        say(f"{phase} Lk {lk:+.3f} alpha {alpha:7.1f}: T1 {rw['T1_B_per_L']:+.3f} B/L, "
            f"Wr {rw['writhe_per_ring'][0]:+.3f}/{rw['writhe_per_ring'][1]:+.3f}, eta "
            f"{rw['eta_mean_rad']:+.4f} [{rw['eta_min_rad']:+.3f}, {rw['eta_max_rad']:+.3f}]"
            f", lam {lam[0] if lam else float('nan'):.3g}, conv {rw['converged']} "
            f"({rw['iterations']} it, g {rw['max_gradient_B_per_L2']:.2g}), "
            f"left {rw['branch_left']}")

    m, r = _lk_walk(None, None, 0.0)
    keep("lk", r, 0.0, 0.0)
    states = {}
    for lk in lk_targets:
        m, r = _lk_walk(m, r, lk, lambda q: keep("lk", q, q["parameter_value"], 0.0))
        states[lk] = r
        _save_state(lk, 0.0, r)
    for lk in alpha_lks:
        m0 = cr.ChiralRings(lk_ring=lk, alpha_B_per_L2=0.0)
        for target, phase in ((ALPHA_MAX, "alpha_up"), (ALPHA_MIN, "alpha_down")):
            for q in cr.continuation(m0, states[lk], "alpha_B_per_L2", target, ALPHA_STEP,
                                     max_iter=300):
                keep(phase, q, lk, q["parameter_value"])
                _save_state(lk, q["parameter_value"], q)
    return name


def _lk_walk(m, r, lk, each=None):
    """From state ``r`` of model ``m`` (None: the relaxed Lk_i = 0 circles) at alpha = 0 to
    Lk_i = ``lk`` in steps of :data:`LK_STEP`, ``each`` called on every row; returns the
    model at ``lk`` and its state."""
    if m is None:
        m = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=0.0)
        r = cr.solve(m)
    if lk != m.lk_ring:
        for q in cr.continuation(m, r, "lk_ring", lk, LK_STEP, max_iter=300):
            if each is not None:
                each(q)
            r = q
    return cr.ChiralRings(lk_ring=lk, alpha_B_per_L2=0.0), r


def _save_state(lk, alpha, q, tag=""):
    """A state and its contact partners, for :func:`continue_scan` (``tag``: a branch other
    than the scans' own, e.g. ``"mirror_"``, so that it never overwrites theirs)."""
    np.save(WORK / f"{tag}x_lk{lk:+.0f}_a{alpha:.0f}.npy", q["x"])
    np.save(WORK / f"{tag}partner_lk{lk:+.0f}_a{alpha:.0f}.npy", q["partner"])


def instabilities(rows) -> list:
    """Where a scan left its branch: the two parameter values bracketing it and the zero of
    the lowest eigenvalue extrapolated linearly from the last two rows before it."""
    out = []
    for k, b in enumerate(rows):
        if not b["branch_left"]:
            continue
        # the state each step came from: the row before it in its own phase, or for an
        # alpha scan's first row the alpha = 0 row of its Lk_i (the phases interleave)
        before = [r for r in rows[:k] if r["phase"] == b["phase"]]
        if not before and b["phase"] != "lk":
            before = [r for r in rows[:k] if r["phase"] == "lk"
                      and abs(r["lk_ring"] - b["lk_ring"]) < 1e-9]
        if not before:
            continue
        a = before[-1]
        par = "lk_ring" if b["phase"] == "lk" else "alpha_B_per_L2"
        rec = {"phase": b["phase"], "bracket": [a[par], b[par]], "parameter": par,
               "writhe_before": a["writhe_per_ring"][0], "writhe_after": b["writhe_per_ring"][0]}
        if len(before) >= 2 and before[-2]["phase"] == a["phase"]:
            p0, p1 = before[-2][par], a[par]
            l0 = before[-2]["lowest_eigenvalues_B_per_L3"][0]
            l1 = a["lowest_eigenvalues_B_per_L3"][0]
            if l0 != l1 and p1 != p0:
                z = float(p1 - l1 * (p1 - p0) / (l1 - l0))
                lo, hi = sorted((p0, b[par]))
                # a zero inside the bracket: the branch lost stability there; elsewhere
                # lam_min did not head for zero (the jump is a fold or a new self-contact
                # that the lowest eigenvalue of the state before does not announce)
                rec["lam_zero_extrapolated"] = z if lo <= z <= hi else None
        out.append(rec)
    return out


def eta_folded(r):
    """A row's mean apolar braid angle (rad, folded into (-pi/2, pi/2]): stored since
    2026-12-05; for an older row its plain mean where every contact lies within +-pi/2
    (the two agree there), else None (not recoverable from the row)."""
    if r.get("eta_folded_mean_rad") is not None:
        return r["eta_folded_mean_rad"]
    if -math.pi / 2 < r["eta_min_rad"] and r["eta_max_rad"] <= math.pi / 2:
        return r["eta_mean_rad"]
    return None


def lk_ladder(scans) -> list:
    """One row per Lk_i with an alpha > 0 scan, from every scan's rows (the scans of one
    Lk_i merged by alpha; where two rows share an alpha the converged one, then the later
    one): the circles or writhed state at alpha = 0, where the branch was first left or
    Newton first failed, and the last converged row before that."""
    by_lk = {}
    zero = {}
    for rows in scans.values():
        if any("mirror_of_lk" in r for r in rows):
            continue  # the other hand: its own table (:func:`mirror_md`)
        for r in rows:
            if r["phase"] == "lk":
                zero[round(r["lk_ring"], 6)] = r
            elif r["phase"] == "alpha_up":
                by_lk.setdefault(round(r["lk_ring"], 6), {})
                a = r["alpha_B_per_L2"]
                old = by_lk[round(r["lk_ring"], 6)].get(a)
                if old is None or r["converged"] or not old["converged"]:
                    by_lk[round(r["lk_ring"], 6)][a] = r
    out = []
    for lk in sorted(by_lk):
        z = zero.get(lk)
        rows = [by_lk[lk][a] for a in sorted(by_lk[lk])]
        if z is not None:
            rows = [z] + rows
        first_bad, last_good = None, None
        for k, r in enumerate(rows):
            if r["branch_left"] or not r["converged"]:
                first_bad = (rows[k - 1]["alpha_B_per_L2"] if k else None, r)
                break
            last_good = r
        lam0 = (z or {}).get("lowest_eigenvalues_B_per_L3") or [float("nan")]
        end = last_good or rows[0]
        out.append({
            "lk_ring": lk, "alpha_max_scanned": rows[-1]["alpha_B_per_L2"],
            "T1_0": z["T1_B_per_L"] if z else None,
            "Wr1_0": z["writhe_per_ring"][0] if z else None,
            "eta_0": eta_folded(z) if z else None, "lam_min_0": lam0[0],
            "stable_to": end["alpha_B_per_L2"], "T1_end": end["T1_B_per_L"],
            "Wr1_end": end["writhe_per_ring"][0], "eta_end": eta_folded(end),
            "lam_min_end": (end.get("lowest_eigenvalues_B_per_L3") or [float("nan")])[0],
            "left_at": None if first_bad is None else [first_bad[0],
                                                       first_bad[1]["alpha_B_per_L2"]],
            "left_how": None if first_bad is None else (
                "branch left" if first_bad[1]["branch_left"] else "not converged"),
            "after": None if first_bad is None else {
                k: first_bad[1][k] for k in ("T1_B_per_L", "converged",
                                             "max_gradient_B_per_L2")}
            | {"Wr1": first_bad[1]["writhe_per_ring"][0], "eta": eta_folded(first_bad[1]),
               "lam_min": (first_bad[1].get("lowest_eigenvalues_B_per_L3") or [None])[0]},
            "branch_left_at": next(([rows[k - 1]["alpha_B_per_L2"], r["alpha_B_per_L2"],
                                     rows[k - 1]["writhe_per_ring"][0], r["writhe_per_ring"][0]]
                                    for k, r in enumerate(rows) if k and r["branch_left"]), None),
        })
    return out


def ladder_md(ladder, gtol: float) -> list:
    L = ["## The Lk_i ladder at alpha > 0 (all alpha_up rows, merged per Lk_i)", "",
         "Per Lk_i: the alpha = 0 state (circles for |Lk_i| < 1.16, writhed beyond); the "
         "last converged row before the branch is first left or Newton first fails "
         "(`converged to`, alpha in B/L^2, and that row's T1, Wr_1, eta, lam_min in B/L^3); "
         "`then`: the first row that is not converged or left its branch (its largest force, "
         f"target gtol = {gtol:.2g} B/L^2, and its lam_min if converged); eta: the mean "
         "apolar braid "
         "angle at contact (folded into (-pi/2, pi/2]); `branch left`: where the scan first jumped "
         "to another branch, with Wr_1 before and after.", "",
         "| Lk_i | T1(0) (B/L) | Wr_1(0) | eta(0) (rad) | lam_min(0) | converged to | "
         "T1 | Wr_1 | eta (rad) | lam_min | then | branch left | scanned to |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]

    f = _f
    for r in ladder:
        then = "-" if r["left_at"] is None else (
            f"{r['left_how']} at {r['left_at'][1]:.1f}: largest force "
            f"{r['after']['max_gradient_B_per_L2']:.2g} B/L^2"
            # the lowest eigenvalue is a stability statement only at an equilibrium
            + (f", lam_min {f(r['after']['lam_min'], '.3g')}" if r["after"]["converged"] else
               ""))
        bl = r["branch_left_at"]
        left = "-" if bl is None else (f"({bl[0]:.1f}, {bl[1]:.1f}]: Wr_1 {bl[2]:+.3f} -> "
                                       f"{bl[3]:+.3f}")
        L.append(f"| {r['lk_ring']:+.0f} | {f(r['T1_0'], '+.3f')} | {f(r['Wr1_0'], '+.3f')} | "
                 f"{f(r['eta_0'], '+.4f')} | {f(r['lam_min_0'], '.3g')} | "
                 f"{r['stable_to']:.1f} | {r['T1_end']:+.3f} | {r['Wr1_end']:+.3f} | "
                 f"{f(r['eta_end'], '+.4f')} | {f(r['lam_min_end'], '.3g')} | {then} | {left} | "
                 f"{r['alpha_max_scanned']:.1f} |")
    return L + [""]


def mirror_pairs(scans) -> list:
    """Rows of the mirror scan beside the rows of its source Lk_i at the same alpha (the
    converged one where two share an alpha): the handedness asymmetry on the ladder."""
    mir = [r for rows in scans.values() for r in rows if "mirror_of_lk" in r]
    if not mir:
        return []
    src_lk = mir[0]["mirror_of_lk"]
    src = {}
    for name, rows in scans.items():
        for r in rows:
            if "mirror_of_lk" in r or abs(r["lk_ring"] - src_lk) > 1e-9:
                continue
            if r["phase"] == "lk" or r["phase"] == "alpha_up":
                old = src.get(r["alpha_B_per_L2"])
                if old is None or r["converged"] or not old["converged"]:
                    src[r["alpha_B_per_L2"]] = r
    return [(src.get(r["alpha_B_per_L2"]), r) for r in mir]


def mirror_md(pairs) -> list:
    if not pairs:
        return []
    lk = pairs[0][1]["mirror_of_lk"]
    L = [f"## The two hands at |Lk_i| = {abs(lk):.0f}: Lk_i = {lk:+.0f} (left-handed link) "
         f"and its mirror image at {-lk:+.0f} (right-handed; `--mirror`)", "",
         "At alpha = 0 one state seen in a mirror (E equal, T1, Wr_1, eta opposite); "
         "sum T1 = T1(left) + T1(right) and sum eta are zero there and measure the "
         "handedness asymmetry of the chiral term at alpha != 0. eta: folded mean (rad). "
         "'*': not converged or branch left.", "",
         f"| alpha (B/L^2) | T1 ({lk:+.0f}) | Wr_1 | eta | T1 (mirror) | Wr_1 | eta | "
         "sum T1 | sum eta | E (left) | E (mirror) |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]

    def ok(r):
        return r["converged"] and not r["branch_left"]

    for a, b in pairs:
        fa = "-" if a is None else (f"{a['T1_B_per_L']:+.3f}{'' if ok(a) else '*'} | "
                                    f"{a['writhe_per_ring'][0]:+.3f} | "
                                    f"{_f(eta_folded(a), '+.4f')}")
        if a is None:
            fa = "- | - | -"
        fb = (f"{b['T1_B_per_L']:+.3f}{'' if ok(b) else '*'} | "
              f"{b['writhe_per_ring'][0]:+.3f} | {_f(eta_folded(b), '+.4f')}")
        both = a is not None and ok(a) and ok(b)
        st = f"{a['T1_B_per_L'] + b['T1_B_per_L']:+.3f}" if both else "-"
        se = (f"{eta_folded(a) + eta_folded(b):+.4f}" if both and eta_folded(a) is not None
              and eta_folded(b) is not None else "-")
        ea = "-" if a is None else f"{a['energy_B_per_L']:.3f}"
        L.append(f"| {b['alpha_B_per_L2']:.1f} | {fa} | {fb} | {st} | {se} | {ea} | "
                 f"{b['energy_B_per_L']:.3f} |")
    return L + [""]


def _f(v, fmt):
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)


def _nan(v):
    return float("nan") if v is None else v


def _fmt_row(r, par):
    lam = r["lowest_eigenvalues_B_per_L3"]
    # the Hessian's lowest eigenvalue is a stability statement only at an equilibrium
    lam_s = f"{lam[0]:.3g}" if (lam and r["converged"]) else "-"
    note = ", ".join(([] if r["converged"] else ["NOT CONVERGED"])
                     + (["branch left"] if r["branch_left"] else []))
    return (f"| {r[par]:+.3f} | {r['T1_B_per_L']:+.3f} | {r['twist_per_ring'][0]:+.3f} | "
            f"{r['writhe_per_ring'][0]:+.3f} | {_f(eta_folded(r), '+.4f')} | "
            f"{r['eta_min_rad']:+.3f} / {r['eta_max_rad']:+.3f} | {lam_s} | "
            f"{r['energy_B_per_L']:.2f} | {r['max_gradient_B_per_L2']:.1e} | {note} |")


def write_md(res) -> str:
    head = ("| {p} | T1 (B/L) | Tw_1 | Wr_1 | eta mean, folded (rad) | "
            "eta min / max (unfolded) | lam_min (B/L^3) "
            "| E (B/L) | max grad (B/L^2) | note |")
    sep = "|---|---|---|---|---|---|---|---|---|---|"
    L = ["# The seed's chiral linked rings at T = 0 (`workflows/chiral_rings.py`)", "",
         "Two rings of length L, Hopf link (Lk_12 = -1, left-handed), Delta/L = 0.02, "
         f"C/B = {cr.DNA_TWIST_OVER_BEND}, bilateral contact, b = Delta/2 (100 beads per "
         "ring), phi = alpha tan(eta/2) per unit contact length (weight 1 at contact, "
         "apolar fold, pairs along the contact partners). T1 = 2 pi C (Lk_1 - Wr_1)/L "
         "(ring 1's twisting moment, B/L); eta: mean braid angle over ring 1's beads in "
         "contact with their partners (rad, > 0 left-handed); lam_min: lowest Hessian "
         "eigenvalue with rigid and sliding modes projected out; max grad: the largest "
         f"force component left (target {res['gtol']:.1e} B/L^2; a row is "
         "accepted below 100x the target when Newton stalls). Units B = L = 1.", ""]
    for name, rows in res["scans"].items():
        lk_rows = [r for r in rows if r["phase"] == "lk"]
        if lk_rows:
            L += [f"## {name}: Lk_i at alpha = 0", "", head.format(p="Lk_i"), sep]
            L += [_fmt_row(r, "lk_ring") for r in lk_rows]
            L.append("")
        for phase in ("alpha_up", "alpha_down"):
            ar = [r for r in rows if r["phase"] == phase]
            if ar:
                L += [f"## {name}: alpha at Lk_i = {ar[0]['lk_ring']:+.0f} ({phase})", "",
                      head.format(p="alpha (B/L^2)"), sep]
                L += [_fmt_row(r, "alpha_B_per_L2") for r in ar]
                L.append("")
        L += [f"Branches left ({name}): {json.dumps(res['instabilities'][name])}", ""]
    L += ladder_md(res["ladder"], res["gtol"])
    L += mirror_md(mirror_pairs(res["scans"]))
    L += [f"Wall time {res['wall_time_s']:.0f} s (the longest scan). "
          + ("" if res.get("complete", True) else "PARTIAL: assembled from the logs of an "
             "interrupted run; the missing rows were not reached."), ""]
    return "\n".join(L)


def plot(res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(20, 4.8), gridspec_kw={"wspace": 0.55})
    labelled = False
    for name, rows in res["scans"].items():
        lk_rows = [r for r in rows if r["phase"] == "lk"]
        if len(lk_rows) > 2:
            ax[0].plot([r["lk_ring"] for r in lk_rows], [r["writhe_per_ring"][0] for r in lk_rows],
                       "o-", ms=3, label=f"Wr_1 ({name})")
            ax[0].plot([r["lk_ring"] for r in lk_rows],
                       [r["T1_B_per_L"] / (2 * math.pi) for r in lk_rows],
                       "s--", ms=3, label=f"T1/(2 pi) ({name})")
        for phase, mk in (("alpha_up", "o-"), ("alpha_down", "o-")):
            ar = sorted([r for r in rows if r["phase"] == phase] + [
                r for r in lk_rows if r is lk_rows[-1]], key=lambda r: r["alpha_B_per_L2"])
            ar = [r for r in ar if r["phase"] != "lk" or any(
                q["phase"] == phase for q in rows)]
            if len(ar) > 1:
                lk = ar[-1]["lk_ring"]
                a = [r["alpha_B_per_L2"] for r in ar]
                # the mirror scan is the other hand of the link: dashed, named
                lab = (f"Lk_i = {lk:+.0f}, mirror of {ar[-1]['mirror_of_lk']:+.0f} "
                       "(right-handed link)" if "mirror_of_lk" in ar[-1]
                       else f"Lk_i = {lk:+.0f} ({phase})")
                mk = "s--" if "mirror_of_lk" in ar[-1] else mk
                ln, = ax[1].plot(a, [r["T1_B_per_L"] for r in ar], mk, ms=3, label=lab)
                ax[2].plot(a, [_nan(eta_folded(r)) for r in ar], mk, ms=3, color=ln.get_color(),
                           label=lab)
                bad = [r for r in ar if not r["converged"]]
                for k, get in ((1, lambda r: r["T1_B_per_L"]), (2, lambda r: _nan(eta_folded(r)))):
                    ax[k].plot([r["alpha_B_per_L2"] for r in bad], [get(r) for r in bad], "x",
                               ms=5, color="k", label=None if (labelled or not bad) else
                               "not converged")
                labelled = labelled or bool(bad)
    for sgn in (1, -1):
        ax[0].axvline(sgn * math.sqrt(3) / cr.DNA_TWIST_OVER_BEND, color="k", lw=0.6, ls=":",
                      label="Michell: |Tw| = sqrt(3) B/C" if sgn > 0 else None)
    ax[0].set_xlabel("Lk_i")
    ax[0].set_ylabel("turns")
    ax[0].legend(fontsize=6)
    s = SLIDE32_READ_OFF
    ax[1].add_patch(matplotlib.patches.Rectangle(
        (s["inset"]["alpha_B_per_L2"][0], s["inset"]["T1_B_per_L"][0]),
        s["inset"]["alpha_B_per_L2"][1] - s["inset"]["alpha_B_per_L2"][0],
        s["inset"]["T1_B_per_L"][1] - s["inset"]["T1_B_per_L"][0], fill=False, ls="--",
        color="k", label="slide 32 inset range (axis labels)"))
    ax[1].axhspan(-12, 0, color="0.9", zorder=-1, label="slide 32 T1 axis (axis labels)")
    ax[1].set_xlabel("alpha (B/L^2)")
    ax[1].set_ylabel("T1 = 2 pi C (Lk_1 - Wr_1)/L (B/L)")
    ax[1].legend(fontsize=5, loc="center left", bbox_to_anchor=(1.0, 0.5))
    ax[2].axhline(0, color="k", lw=0.5)
    ax[2].set_xlabel("alpha (B/L^2)")
    ax[2].set_ylabel("mean contact eta, folded (rad)")
    ax[2].legend(fontsize=5, loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.subplots_adjust(left=0.04, right=0.90, bottom=0.12, top=0.95)
    fig.savefig(path, dpi=120)


def plot_shapes(path) -> list:
    """Top and side views of the saved states at alpha = 0 and at the scans' ends."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = []
    for lk in (3, 5, -5):
        for a in (ALPHA_MIN, 0.0, ALPHA_MAX):
            f = WORK / f"x_lk{lk:+.0f}_a{a:.0f}.npy"
            if f.exists():
                names.append((lk, a, f))
    if not names:
        return []
    fig, ax = plt.subplots(len(names), 2, figsize=(11, 1.9 * len(names)), squeeze=False)
    ax = ax.T
    for c, (lk, a, f) in enumerate(names):
        x = np.load(f)
        x = x - x.mean(axis=0)
        # principal axes: view along the smallest (top) and the middle one (side)
        _, _, vt = np.linalg.svd(x, full_matrices=False)
        y = x @ vt.T
        half = len(x) // 2
        for r, (i, j) in enumerate(((0, 1), (0, 2))):
            for k, col in ((0, "C0"), (1, "C3")):
                seg = y[k * half:(k + 1) * half]
                seg = np.vstack([seg, seg[:1]])
                ax[r, c].plot(seg[:, i], seg[:, j], "-", color=col, lw=1.2)
            ax[r, c].set_aspect("equal")
            ax[r, c].set_xticks([])
            ax[r, c].set_yticks([])
        ax[0, c].set_ylabel(f"Lk_i = {lk:+d}\nalpha = {a:.0f}", fontsize=8)
    ax[0, 0].set_title("top (principal axes 1-2); ring 1 blue, ring 2 red", fontsize=8)
    ax[1, 0].set_title("side (principal axes 1-3)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return [f"Lk {lk:+d}, alpha {a:.0f}" for lk, a, _ in names]


def finish(scans: dict, wall_time_s: float, complete: bool) -> None:
    res = {"model": {"diameter_over_length": 0.02, "twist_over_bend": cr.DNA_TWIST_OVER_BEND,
                     "contact": "bilateral", "spacing_over_diameter": 0.5,
                     "n": 1, "handedness": "left"},
           "lk_step": LK_STEP, "alpha_step_B_per_L2": ALPHA_STEP,
           "scans": scans, "complete": complete, "slide32_read_off": SLIDE32_READ_OFF,
           "michell_lk": math.sqrt(3) / cr.DNA_TWIST_OVER_BEND}
    res["instabilities"] = {k: instabilities(v) for k, v in scans.items()}
    res["ladder"] = lk_ladder(scans)
    res["wall_time_s"] = wall_time_s
    res["gtol"] = _default_gtol()
    (OUT / "chiral_rings.json").write_text(json.dumps(res, indent=1))
    (OUT / "chiral_rings.md").write_text(write_md(res))
    plot(res, OUT / "chiral_rings.png")
    plot_shapes(OUT / "chiral_rings_shapes.png")
    print(f"wrote {OUT / 'chiral_rings.json'} ({'complete' if complete else 'partial'})",
          flush=True)


def _default_gtol() -> float:
    """relax's default gradient target for the scanned model (B/L^2)."""
    return cr.default_gtol(cr.make_problem(cr.ChiralRings()))


def assemble() -> int:
    """Results from every log in chiral_rings.work (the scans of :data:`SCANS` and any
    scan continued separately by :func:`continue_scan`)."""
    scans, wall = {}, 0.0
    for f in sorted(WORK.glob("*.jsonl")):
        rows = [json.loads(t) for t in f.read_text().splitlines() if t.strip()]
        if rows:
            scans[f.stem] = rows
            wall = max(wall, sum(r["wall_time_s"] for r in rows))
    # the logs are not committed: a scan stored in the results but without a log here (a
    # fresh checkout) is kept as stored, never dropped
    stored = OUT / "chiral_rings.json"
    if stored.exists():
        old = json.loads(stored.read_text())
        for name, rows in old["scans"].items():
            if name not in scans:
                print(f"assemble: {name} has no log in {WORK}; kept as stored", flush=True)
                scans[name] = rows
                wall = max(wall, sum(r["wall_time_s"] for r in rows))
    finish(scans, wall, complete=False)
    return 0


def _rebuild_alpha0(lk: float) -> None:
    """The alpha = 0 state at ``lk`` by the Lk scan of :func:`scan` (seconds), for a
    continuation from alpha = 0 in a checkout whose logs and states are gone."""
    _, r = _lk_walk(None, None, lk)
    print(f"rebuilt the alpha = 0 state at Lk_i = {lk:+g}: T1 "
          f"{r['torque_per_ring_B_per_L'][0]:+.3f}, conv {r['converged']}", flush=True)
    _save_state(lk, 0.0, r)


def continue_scan(name: str, lk: float, alpha_from: float, alpha_to: float,
                  step: float = ALPHA_STEP, min_step: float | None = None) -> None:
    """An alpha scan at ``lk`` from a saved state (``x_lk{lk}_a{alpha_from}.npy``), logged as
    ``name``: a second process on a branch (``--continue``). It starts from the partners
    saved with that state, or (states saved before 2026-12-05 have none) those saved at
    alpha = 0, which :func:`~dnabraid.statics.chiral_rings.update_partners` re-centres."""
    WORK.mkdir(parents=True, exist_ok=True)
    if alpha_from == 0.0 and not (WORK / f"x_lk{lk:+.0f}_a0.npy").exists():
        _rebuild_alpha0(lk)
    x = np.load(WORK / f"x_lk{lk:+.0f}_a{alpha_from:.0f}.npy")
    own = WORK / f"partner_lk{lk:+.0f}_a{alpha_from:.0f}.npy"
    partner = np.load(own if own.exists() else WORK / f"partner_lk{lk:+.0f}_a0.npy")
    m0 = cr.ChiralRings(lk_ring=lk, alpha_B_per_L2=alpha_from)
    start = cr.solve(m0, x, partner=partner, max_iter=300)
    log = _log(name)
    phase = "alpha_up" if alpha_to > alpha_from else "alpha_down"
    # the start is a row too: at alpha = 0 it is the ladder's alpha = 0 state (phase "lk")
    start["lk"], start["alpha"] = lk, alpha_from
    log.write_text(json.dumps(row("lk" if alpha_from == 0.0 else phase, start)) + "\n")
    for q in cr.continuation(m0, start, "alpha_B_per_L2", alpha_to, step, max_iter=300,
                             min_step=min_step):
        q["lk"], q["alpha"] = lk, q["parameter_value"]
        with log.open("a") as fh:
            fh.write(json.dumps(row(phase, q)) + "\n")
        _save_state(lk, q["parameter_value"], q)
        print(f"[{name}] alpha {q['parameter_value']:.0f}: T1 "
              f"{q['torque_per_ring_B_per_L'][0]:+.3f}, conv {q['converged']}", flush=True)


MIRROR_NAME = "mirror_plus3"


def mirror_scan(lk_from: float = -3.0, alpha_to: float = ALPHA_MAX,
                step: float = ALPHA_STEP) -> None:
    """The handedness asymmetry on the ladder: the alpha scan of the mirror image
    (:func:`~dnabraid.statics.chiral_rings.mirror_image`) of the alpha = 0 state at
    ``lk_from``, logged as :data:`MIRROR_NAME` (``--mirror``). At alpha = 0 the two are one state seen in a mirror
    (energy equal, T1 and Wr opposite, eta opposite); alpha != 0 tells the hands apart."""
    WORK.mkdir(parents=True, exist_ok=True)
    if not (WORK / f"x_lk{lk_from:+.0f}_a0.npy").exists():
        _rebuild_alpha0(lk_from)
    x = np.load(WORK / f"x_lk{lk_from:+.0f}_a0.npy")
    partner = np.load(WORK / f"partner_lk{lk_from:+.0f}_a0.npy")
    m_src = cr.ChiralRings(lk_ring=lk_from, alpha_B_per_L2=0.0)
    src = cr.solve(m_src, x, partner=partner, max_iter=300)
    y, p2 = cr.mirror_image(src["x"], src["partner"], cr.make_problem(m_src))
    lk = -lk_from
    m0 = cr.ChiralRings(lk_ring=lk, alpha_B_per_L2=0.0)
    start = cr.solve(m0, y, partner=p2, max_iter=300)
    print(f"mirror of Lk_i {lk_from:+g}: E {src['energy_B_per_L']:.6f} -> "
          f"{start['energy_B_per_L']:.6f} B/L, T1 {src['torque_per_ring_B_per_L'][0]:+.4f} "
          f"-> {start['torque_per_ring_B_per_L'][0]:+.4f}, eta (folded) "
          f"{src['eta_folded_mean_rad']:+.4f} -> {start['eta_folded_mean_rad']:+.4f}",
          flush=True)
    log = _log(MIRROR_NAME)
    start["lk"], start["alpha"] = lk, 0.0
    log.write_text(json.dumps(row("lk", start) | {"mirror_of_lk": lk_from}) + "\n")
    for q in cr.continuation(m0, start, "alpha_B_per_L2", alpha_to, step, max_iter=300):
        q["lk"], q["alpha"] = lk, q["parameter_value"]
        with log.open("a") as fh:
            fh.write(json.dumps(row("alpha_up", q) | {"mirror_of_lk": lk_from}) + "\n")
        _save_state(lk, q["parameter_value"], q, tag="mirror_")
        print(f"[{MIRROR_NAME}] alpha {q['parameter_value']:.0f}: T1 "
              f"{q['torque_per_ring_B_per_L'][0]:+.3f}, Wr "
              f"{q['writhe_per_ring'][0]:+.3f}, eta (folded) "
              f"{q['eta_folded_mean_rad']:+.4f}, conv {q['converged']}", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--assemble", action="store_true",
                    help="only write the results from the logs already written "
                         "(chiral_rings.work/*.jsonl), e.g. of an interrupted run")
    ap.add_argument("--continue", dest="cont", nargs="+", default=None,
                    metavar="NAME LK ALPHA_FROM ALPHA_TO STEP [MIN_STEP]",
                    help="continue the alpha scan at Lk_i = LK from its saved state at "
                         "ALPHA_FROM to ALPHA_TO (B/L^2), logged as NAME (a missing alpha = 0 "
                         "state is rebuilt); then --assemble")
    ap.add_argument("--mirror", action="store_true",
                    help="the alpha scan of the mirror image of the Lk_i = -3 state "
                         f"(logged as {MIRROR_NAME}); then --assemble")
    a = ap.parse_args(argv)
    OUT.mkdir(exist_ok=True)
    if a.mirror:
        mirror_scan()
        return 0
    if a.assemble:
        return assemble()
    if a.cont:
        if len(a.cont) not in (5, 6):
            ap.error("--continue takes NAME LK ALPHA_FROM ALPHA_TO STEP [MIN_STEP]")
        continue_scan(a.cont[0], *(float(v) for v in a.cont[1:]))
        return 0
    t0 = time.perf_counter()
    with mp.get_context("fork").Pool(a.workers) as pool:
        pool.map(scan, SCANS, chunksize=1)
    scans = {name: [json.loads(t) for t in _log(name).read_text().splitlines() if t.strip()]
             for name, _, _ in SCANS}
    finish(scans, time.perf_counter() - t0, complete=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
