"""A braid turned through its buckling: extension, torque and the braid axis's writhe
against catenation (issue "Converged at the scale of the experiment": the braid's buckling
torque and the extension slope after it).

For each salt (one ``dnabraid run braid`` per salt, moves on, every turn value built at its
catenation and sampled by its own independent replicas), per turn value n:

* the extension and the trap torque with the run's errors and verdicts (``summary.json``);
* the writhe of the braid's axis, Wr_ax (the strands' midpoint curve m_i = (r1_i + r2_i)/2,
  closed by vertical rays, :func:`dnabraid.geometry.ribbon.writhe_open`) and the strands'
  winding about it, Tw_b = Ca - Wr_ax, from the trajectory frames read through MDAnalysis
  (``topology.pdb`` + each replica's ``trajectory.dcd``): the catenation splits like a
  ribbon's linking number (Calugareanu-White), so a straight braid keeps Wr_ax ~ 0 and a
  buckled ("supercoiled") braid puts the added catenation into the axis's writhe; mean and
  standard error across replicas;
* Sarle's bimodality coefficient of the pooled extension samples
  (:func:`dnabraid.analysis.stats.bimodality`; above 5/9 hints at two states).

The buckling interval is the first pair of neighbouring turn values across which Wr_ax
rises by more than a quarter turn per turn; the slope dz/dn after buckling is a weighted
least-squares line through the points past it (with its standard error), the torque there
their mean (the plateau of the two-phase picture).

Theory. Brahmachari & Marko (Phys. Rev. E 95, 052401 (2017); PMC5505651) model braids in
magnetic tweezers: a catenation-dependent effective twist modulus, buckling into a
"supercoiled braid" of several small plectonemes, a discontinuity in extension at buckling
(the first plectoneme's nucleation), and buckling at lower catenation at lower salt (the
opposite of single supercoiled DNA). Only the abstract and the first figure's caption are in
the project's library (no equations): the comparison here is with those qualitative
predictions, not with the paper's numbers.

Usage:
    python workflows/braid_buckling.py run --salt 150 [--length 100 --force 2 ...]
    python workflows/braid_buckling.py report     # tables and plot from the stored runs
Writes workflows/results/braid_buckling_<tag>.json per run and
workflows/results/braid_buckling.{md,png}. Run directories: --work (default
runs/braid_buckling/, resumed when rerun).
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
RESULTS = HERE / "results"
WR_RISE = 0.25  # turns of axis writhe per turn of catenation that mark the buckling


def tag_of(a) -> str:
    return f"L{a.length:g}_F{a.force:g}_salt{a.salt:g}_seed{a.seed}"


def _val(p, col):
    v = p.get(col)
    if isinstance(v, dict):
        return {"mean": v["mean"], "sem": v["sem"], "rhat": v.get("rhat"),
                "ess": v.get("ess")}
    return None


def split_catenation(p1, p2) -> tuple[float, float]:
    """(Wr_ax, Ca) of two strands (n, 3) in nm with the same bead count: the writhe of the
    midpoint curve and the strands' catenation, both closed by vertical rays; the winding
    about the axis is Tw_b = Ca - Wr_ax (Calugareanu-White for the ribbon m, m + u,
    u = r2 - r1; tests/test_braid_buckling.py checks it against the ribbon's twist)."""
    from dnabraid.geometry.curves import catenation_number
    from dnabraid.geometry.ribbon import writhe_open

    p1, p2 = np.asarray(p1, float), np.asarray(p2, float)
    if p1.shape != p2.shape:
        raise ValueError(f"strands of {len(p1)} and {len(p2)} beads: the axis needs pairs")
    return writhe_open(0.5 * (p1 + p2)), catenation_number(p1, p2)


def axis_writhe(run_dir: pathlib.Path, point_name: str) -> dict:
    """Per replica: the mean over frames of the braid axis's writhe, the strands' winding
    about it and the catenation, read through MDAnalysis."""
    import MDAnalysis as mda

    from dnabraid.analysis.mda import ANGSTROM_TO_NM, select_strands

    top = run_dir / "topology.pdb"
    out = {"wr_axis": [], "tw_braid": [], "catenation": [], "frames": []}
    for rep in sorted((run_dir / "replicas").iterdir()):
        dcd = rep / "points" / point_name / "trajectory.dcd"
        if not dcd.exists():
            continue
        u = mda.Universe(str(top), str(dcd))
        a, b = select_strands(u)
        wr, ca = [], []
        for _ in u.trajectory:
            p1 = a.positions.astype(float) * ANGSTROM_TO_NM
            p2 = b.positions.astype(float) * ANGSTROM_TO_NM
            w, c = split_catenation(p1, p2)
            wr.append(w)
            ca.append(c)
        wr, ca = np.array(wr), np.array(ca)
        out["wr_axis"].append(float(wr.mean()))
        out["catenation"].append(float(ca.mean()))
        out["tw_braid"].append(float((ca - wr).mean()))
        out["frames"].append(int(wr.size))
    return out


def _across(x) -> tuple[float, float]:
    x = np.asarray(x, float)
    if x.size == 0:
        return math.nan, math.nan
    return float(x.mean()), (float(x.std(ddof=1) / math.sqrt(x.size)) if x.size > 1
                             else math.nan)


def pooled_extension(run_dir: pathlib.Path, point_name: str) -> np.ndarray:
    xs = []
    for rep in sorted((run_dir / "replicas").iterdir()):
        f = rep / "points" / point_name / "samples.csv"
        if f.exists():
            d = np.genfromtxt(f, delimiter=",", names=True)
            xs.append(np.atleast_1d(d["extension_nm"]))
    return np.concatenate(xs) if xs else np.empty(0)


def analyse(run_dir: pathlib.Path) -> list[dict]:
    from dnabraid.analysis.stats import bimodality

    s = json.loads((run_dir / "summary.json").read_text())
    # point directories are NNN_turns+X.XXXX: matched to the summary's points by turns
    names = {round(float(q.name.split("_turns")[1]), 6): q.name
             for q in (run_dir / "replicas" / "r00" / "points").iterdir()}
    rows = []
    for p in sorted(s["points"], key=lambda q: q["turns"]):
        name = names[round(float(p["turns"]), 6)]
        w = axis_writhe(run_dir, name)
        z = pooled_extension(run_dir, name)
        bm = bimodality(z) if z.size >= 3 else {"bc": math.nan, "sd": math.nan}
        hist, edges = np.histogram(z, bins=40) if z.size else (np.zeros(0), np.zeros(0))
        rows.append({
            "turns": p["turns"], "point": name, "converged": bool(p["converged"]),
            "reason": p.get("convergence_reason", ""),
            "extension_nm": _val(p, "extension_nm"), "torque_pN_nm": _val(p, "torque_pN_nm"),
            "torque_spread_pN_nm": _val(p, "torque_spread_pN_nm"),
            "wr_axis": _across(w["wr_axis"]), "tw_braid": _across(w["tw_braid"]),
            "catenation": _across(w["catenation"]), "wr_axis_replicas": w["wr_axis"],
            "frames_per_replica": w["frames"], "extension_sd_nm": bm["sd"],
            "bimodality": bm["bc"], "hist": hist.tolist(), "edges": edges.tolist()})
    return rows


def _line_slope(x, rows, col) -> list[float]:
    """Slope and its standard error of the weighted least-squares line through the rows'
    ``col`` means against ``x`` (weights 1 / sem^2)."""
    y = np.array([r[col]["mean"] for r in rows])
    w = 1.0 / np.maximum([r[col]["sem"] for r in rows], 1e-9) ** 2
    X = np.c_[np.ones_like(x), x]
    cov = np.linalg.inv(X.T @ (X * w[:, None]))
    beta = cov @ (X.T @ (w * y))
    return [float(beta[1]), float(math.sqrt(cov[1, 1]))]


def buckling(rows: list[dict]) -> dict:
    """The buckling interval (first rise of Wr_ax by > WR_RISE per turn), the slope dz/dn
    and the mean torque over the points past it."""
    t = [r["turns"] for r in rows]
    wr = [r["wr_axis"][0] for r in rows]
    k = next((i for i in range(len(t) - 1)
              if (wr[i + 1] - wr[i]) / (t[i + 1] - t[i]) > WR_RISE), None)
    out = {"interval": None, "slope_nm_per_turn": None, "torque_after_pN_nm": None,
           "points_after": 0}
    if k is None:
        return out
    out["interval"] = [t[k], t[k + 1]]
    post = rows[k + 1:]
    out["points_after"] = len(post)
    if len(post) >= 2:
        x = np.array([r["turns"] for r in post])
        out["slope_nm_per_turn"] = _line_slope(x, post, "extension_nm")
        tq = np.array([r["torque_pN_nm"]["mean"] for r in post])
        tw = 1.0 / np.maximum([r["torque_pN_nm"]["sem"] for r in post], 1e-9) ** 2
        out["torque_after_pN_nm"] = [float((tw * tq).sum() / tw.sum()),
                                     float(1.0 / math.sqrt(tw.sum()))]
        # a plateau (two phases coexisting at one torque) has zero slope
        out["torque_slope_pN_nm_per_turn"] = _line_slope(x, post, "torque_pN_nm")
    pre = rows[:k + 1]
    tmax = max(pre, key=lambda r: abs(r["torque_pN_nm"]["mean"]))
    out["torque_before_max_pN_nm"] = [tmax["torque_pN_nm"]["mean"],
                                      tmax["torque_pN_nm"]["sem"], tmax["turns"]]
    return out


def cmd_run(a) -> None:
    from dnabraid.scenes import make_scene

    keys = {"length_nm": a.length, "force_pN": a.force, "salt_mM": a.salt,
            "tether_separation_nm": a.separation, "turns": a.turns, "steps": a.steps,
            "equilibration_steps": a.equilibration, "replicas": a.replicas,
            "seed": a.seed, "workers": a.workers, "mc_moves": a.mc_moves,
            "frame_interval": a.frame_interval}
    tag = tag_of(a)
    d = pathlib.Path(a.work) / tag
    t0 = time.perf_counter()
    make_scene("braid", keys).run(str(d))
    wall = time.perf_counter() - t0
    s = json.loads((d / "summary.json").read_text())
    rows = analyse(d)
    res = {"tag": tag, "keys": keys, "wall_s_this_call": wall,
           "wall_s_summary": s.get("wall_time_s"),
           "effective_diameter_nm": s.get("effective_diameter_nm"),
           "time_step_ps": s.get("time_step_ps"), "rows": rows, "buckling": buckling(rows),
           "run_dir": str(d),
           "date": time.strftime("%Y-%m-%d %H:%M")}
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / f"braid_buckling_{tag}.json"
    out.write_text(json.dumps(res, indent=1))
    print(f"wrote {out}")
    print(render([res]))


def _pm(v, digits=2):
    if v is None:
        return "-"
    m, s = (v["mean"], v["sem"]) if isinstance(v, dict) else v
    if s is None or not math.isfinite(s):
        return f"{m:.{digits}f}"
    return f"{m:.{digits}f} +- {s:.{digits}f}"


def render(results: list[dict]) -> str:
    lines = []
    for res in results:
        k = res["keys"]
        lines += [f"## 2 x {k['length_nm']:g} nm at {k['force_pN']:g} pN, "
                  f"{k['salt_mM']:g} mM (D = {res.get('effective_diameter_nm') or 0:.2f} nm), "
                  f"tethers {k['tether_separation_nm']:g} nm apart, seed {k['seed']}", "",
                  f"{k['replicas']} replicas x ({k['equilibration_steps']} + {k['steps']}) "
                  f"steps, {k['mc_moves']} moves per report interval; wall "
                  f"{res.get('wall_s_summary') or res['wall_s_this_call']:.0f} s "
                  f"({res['date']}).", "",
                  "| n | extension nm | trap torque pN nm | spread torque pN nm | Wr axis | "
                  "Tw braid | bimodality | converged (R-hat z, ESS z) |",
                  "|---|---|---|---|---|---|---|---|"]
        for r in res["rows"]:
            z = r["extension_nm"]
            lines.append(
                f"| {r['turns']:g} | {_pm(z)} | {_pm(r['torque_pN_nm'], 1)} | "
                f"{_pm(r['torque_spread_pN_nm'], 1)} | {_pm(r['wr_axis'], 3)} | "
                f"{_pm(r['tw_braid'], 3)} | {r['bimodality']:.2f} | "
                f"{'yes' if r['converged'] else 'NO'} ({z['rhat']:.3f}, {z['ess']:.0f}) |")
        b = res["buckling"]
        lines.append("")
        if b["interval"] is None:
            lines.append("No buckling in the range (Wr_ax never rises by more than "
                         f"{WR_RISE} per turn).")
        else:
            sl = b["slope_nm_per_turn"]
            ta = b["torque_after_pN_nm"]
            tb = b["torque_before_max_pN_nm"]
            lines.append(
                f"Buckling between n = {b['interval'][0]:g} and {b['interval'][1]:g}; "
                f"largest torque before it {tb[0]:.1f} +- {tb[1]:.1f} pN nm (n = {tb[2]:g}); "
                + (f"past it ({b['points_after']} points) dz/dn = {sl[0]:.2f} +- {sl[1]:.2f} "
                   f"nm/turn and dGamma/dn = {b['torque_slope_pN_nm_per_turn'][0]:.1f} +- "
                   f"{b['torque_slope_pN_nm_per_turn'][1]:.1f} pN nm/turn (a plateau: 0; "
                   f"weighted mean torque {ta[0]:.1f} +- {ta[1]:.1f} pN nm)." if sl else
                   f"{b['points_after']} point(s) past it: no slope."))
        lines.append("")
    return "\n".join(lines)


def maxwell_check(results: list[dict]) -> str:
    """Where two or more forces share length, salt and turns: the torque at each force
    predicted from the lowest force's torque and the extensions between
    (:func:`dnabraid.analysis.maxwell.torque_from_extension`, dGamma/dF = -(1/2 pi) dz/dn;
    Mosconi et al. 2009, Eq. 2) against the measured trap torque. The force integral is a
    trapezoid over the measured forces: its curvature error is not in the error bar. At
    alpha = 0 with turns from 0 the grid is mirrored to -n (z even, Gamma odd in n)."""
    from dnabraid.analysis.maxwell import torque_from_extension

    groups = {}
    for res in results:
        k = res["keys"]
        key = (k["length_nm"], k["salt_mM"], k["seed"], tuple(k["turns"]))
        groups.setdefault(key, []).append(res)
    lines = []
    for (L, salt, seed, turns), rs in groups.items():
        if len(rs) < 2:
            continue
        rs = sorted(rs, key=lambda r: r["keys"]["force_pN"])
        F = [r["keys"]["force_pN"] for r in rs]
        z = [[row["extension_nm"]["mean"] for row in r["rows"]] for r in rs]
        ze = [[row["extension_nm"]["sem"] for row in r["rows"]] for r in rs]
        g0 = [row["torque_pN_nm"]["mean"] for row in rs[0]["rows"]]
        g0e = [row["torque_pN_nm"]["sem"] for row in rs[0]["rows"]]
        tt = list(turns)
        mirrored = tt[0] == 0.0 and all(r["keys"].get("alpha", 0.0) == 0.0 for r in rs)
        if mirrored:
            # alpha = 0: z is even and Gamma odd in n, so the grid is extended to -n and
            # dz/dn at n = 0 is a central difference (a one-sided one reads the kink of z
            # at n = 0 as a slope: 4.3 pN nm where Gamma(0) = 0 by symmetry)
            tt = [-t for t in tt[:0:-1]] + tt
            z = [zz[:0:-1] + zz for zz in z]
            ze = [ee[:0:-1] + ee for ee in ze]
            g0 = [-g for g in g0[:0:-1]] + g0
            g0e = g0e[:0:-1] + g0e
        m = torque_from_extension(F, tt, z, g0, extension_sem_nm=ze,
                                  torque_ref_sem_pN_nm=g0e)
        off = len(turns) - 1 if mirrored else 0
        lines += [f"### Maxwell relation, 2 x {L:g} nm, {salt:g} mM: torque at "
                  f"{', '.join(f'{f:g}' for f in F[1:])} pN from {F[0]:g} pN and the "
                  "extensions", "",
                  "| F pN | n | predicted pN nm | measured pN nm | z | every point used "
                  "converged |", "|---|---|---|---|---|---|"]
        for i in range(1, len(F)):
            for j, n in enumerate(turns):
                pr, pe = m["torque_pN_nm"][i, j + off], m["sem_pN_nm"][i, j + off]
                row = rs[i]["rows"][j]
                me, mse = row["torque_pN_nm"]["mean"], row["torque_pN_nm"]["sem"]
                zz = (pr - me) / math.hypot(pe, mse)
                used = [r["rows"][jj]["converged"] for r in rs
                        for jj in range(max(0, j - 1), min(len(turns), j + 2))]
                lines.append(f"| {F[i]:g} | {n:g} | {pr:.1f} +- {pe:.1f} | {me:.1f} +- "
                             f"{mse:.1f} | {zz:+.2f} | {'yes' if all(used) else 'NO'} |")
        lines.append("")
    return "\n".join(lines)


def cmd_report(a) -> None:
    results = [json.loads(f.read_text())
               for f in sorted(RESULTS.glob("braid_buckling_L*.json"))]
    if not results:
        raise SystemExit("no stored runs (workflows/results/braid_buckling_L*.json)")
    head = ("# A braid turned through its buckling\n\n"
            "`python workflows/braid_buckling.py run ...` per row set, "
            "`python workflows/braid_buckling.py report` for this file. Errors: standard "
            "errors across independent replicas. Wr axis: writhe of the strands' midpoint "
            "curve (closed by vertical rays), Tw braid = Ca - Wr axis (both from the "
            "trajectory frames, read through MDAnalysis). Bimodality: Sarle's coefficient of "
            "the pooled extension samples (1/3 Gaussian, > 5/9 two states).\n\n")
    body = render(results) + "\n" + maxwell_check(results)
    (RESULTS / "braid_buckling.md").write_text(head + body + "\n" + (a.reading or ""))
    plot(results, RESULTS / "braid_buckling.png")
    print(head + body)


def plot(results, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    for idx, res in enumerate(results):
        c = f"C{idx}"
        k = res["keys"]
        lab = f"2x{k['length_nm']:g} nm, {k['force_pN']:g} pN, {k['salt_mM']:g} mM"
        t = [r["turns"] for r in res["rows"]]
        for i, col in enumerate(("extension_nm", "torque_pN_nm")):
            m = [r[col]["mean"] for r in res["rows"]]
            e = [r[col]["sem"] for r in res["rows"]]
            ax[i].errorbar(t, m, yerr=e, marker="o", capsize=3, label=lab, color=c)
            bad = [j for j, r in enumerate(res["rows"]) if not r["converged"]]
            ax[i].plot([t[j] for j in bad], [m[j] for j in bad], "o", ls="none", ms=7,
                       markerfacecolor="white", markeredgecolor=c, zorder=5)
        ax[2].errorbar(t, [r["wr_axis"][0] for r in res["rows"]],
                       yerr=[r["wr_axis"][1] for r in res["rows"]], marker="o", capsize=3,
                       label=lab, color=c)
    ax[0].set_ylabel("extension (nm)")
    ax[1].set_ylabel("trap torque (pN nm)")
    ax[2].set_ylabel("writhe of the braid axis (turns)")
    for x in ax:
        x.set_xlabel("turns n (catenation)")
        x.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    ax[0].set_title("open symbols: NOT CONVERGED", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run one braid sweep and store its analysis")
    r.add_argument("--length", type=float, default=100.0, help="nm per strand")
    r.add_argument("--force", type=float, default=2.0, help="pN")
    r.add_argument("--salt", type=float, default=150.0, help="mM")
    r.add_argument("--separation", type=float, default=40.0, help="tether separation, nm")
    r.add_argument("--turns", type=float, nargs="+",
                   default=[0, 0.5, 1, 1.5, 2, 2.5, 3])
    r.add_argument("--steps", type=int, default=200_000)
    r.add_argument("--equilibration", type=int, default=10_000)
    r.add_argument("--replicas", type=int, default=4)
    r.add_argument("--mc-moves", type=int, default=3000)
    r.add_argument("--frame-interval", type=int, default=2000)
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--workers", type=int, default=1)
    r.add_argument("--work", default="runs/braid_buckling")
    p = sub.add_parser("report", help="tables and plot from the stored runs")
    p.add_argument("--reading", default=None, help="text appended to the md")
    a = ap.parse_args(argv)
    cmd_run(a) if a.cmd == "run" else cmd_report(a)


if __name__ == "__main__":
    main()
