"""Calibration of the tether's reported error bars against the exact discrete WLC.

The ``tether`` scene with ``surface = false`` and ``self_avoidance = false`` is exactly the
discrete worm-like chain with harmonic bonds under an end force, whose mean extension
:func:`dnabraid.continuum.wlc.discrete_wlc_exact` computes by a transfer matrix,
independently of the simulation. Every replica starts from an exact equilibrium draw, so
replica means are unbiased whatever the run length (the run length sets only their
variance), and the reported 95 % interval (Student t across ``replicas``) should cover the
exact value in ~95 % of independent studies.

1. Calibration table: lengths x forces; per case K independent studies (own seeds), each
   one ``Tether.run`` of R replicas of S steps in this process (``workers = 1``). Columns:
   exact <z>, bias of the study means, coverage of the reported 95 % intervals (with its
   Clopper-Pearson 95 % interval), t-scores t = (mean - exact) / sem (their mean square
   against the Student-t value (R-1)/(R-3) and a Monte-Carlo 95 % band for K draws), the
   t-scores mapped to normal z-scores through the Student-t CDF (mean square 1, chi^2_K/K
   band), the between-study scatter over the mean reported sem^2, the share of studies
   called ``converged``, wall time per study. The same statistics without the data-driven
   truncation (every sample kept) are given beside, from the replicas' raw series.
2. Shift table: how much the wall (``surface``) and self-avoidance move the mean
   extension, each alone and together, at a few cases (no exact answer: sim(with) -
   sim(without), errors from the scatter of all replica means). The start is then the
   exact free-chain draw conditioned on being allowed (rejection), so these runs are
   longer; the drift between the first and last quarter of the replicas is shown.
3. Cost: the per-study wall time split into its parts. Each study (``make_scene`` and
   ``Tether.run``) runs under ``cProfile.Profile()``; the parts are the cumulative times
   of the library's functions in ``pstats.Stats(profile).stats`` (nothing in the library
   is replaced or wrapped). The profiler slows the Python parts of a study (exact draws,
   reports, combine), so the wall times are those of a profiled run. The exact / fallback start counts of the shift table
   come from the same statistics: calls of ``Tether.equilibrium_start`` and calls of
   ``random_tether`` made by ``Tether.attach`` (the fallback when no draw is allowed).

The scene validation's strand-passage check (``dnabraid.chains.passage_barrier_kT``) is
memoised in the library; its uncached cost is measured through ``__wrapped__`` and shown.

Usage: taskset -c 0 python workflows/calibration.py [--quick] [--studies 30] [--out DIR]
Writes DIR/calibration.md (+ .json, .png; DIR defaults to workflows/results); the table
after every case.
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import datetime
import inspect
import json
import math
import os
import pathlib
import platform
import pstats
import sys
import tempfile
import time
import warnings

import numpy as np
from scipy import stats

from dnabraid.analysis.calibration import calib_stats, pooled, t2_band, untruncated, z2_band

HERE = pathlib.Path(__file__).resolve().parent

LENGTHS = (100.0, 300.0, 1000.0, 2000.0)
FORCES = (0.1, 1.0, 10.0)
#: (length, force) of the shift table.
SHIFT_CASES = ((300.0, 0.1), (1000.0, 0.1), (300.0, 1.0))
SHIFT_VARIANTS = (("none", False, False), ("wall", True, False),
                  ("self-avoidance", False, True), ("wall + self-avoidance", True, True))
#: Option values of a full run and of ``--quick`` (options given explicitly win).
FULL = {"studies": 30, "steps": 2000, "lengths": list(LENGTHS), "forces": list(FORCES),
        "shift_studies": 10, "shift_steps": 4000,
        "shift_cases": [f"{L:g}:{F:g}" for L, F in SHIFT_CASES]}
QUICK = {"studies": 4, "steps": 500, "lengths": [100.0, 300.0], "forces": [1.0],
         "shift_studies": 2, "shift_steps": 1000, "shift_cases": ["300:1"]}


# ----------------------------------------------------------------------------- timing
PARTS = (("scene validation (passage check)", "validate"),
         ("build incl. exact start draws", "build"),
         ("  of which exact start draws", "start"),
         ("OpenMM Context + integrator", "context"),
         ("integrator steps", "step"),
         ("state checks per report (advance - steps)", "advance_extra"),
         ("combine run dir (csv, dcd)", "combine"),
         ("plot png", "plot"),
         ("other (run dir, checkpoints, csv, summary)", "other"))


def code_key(fn) -> tuple:
    """The pstats key (filename, first line, name) of a Python function."""
    c = inspect.unwrap(fn).__code__
    return c.co_filename, c.co_firstlineno, c.co_name


def profiled_keys(scene) -> dict:
    """part -> the pstats key of the library function whose cumulative time it is."""
    from dnabraid import plots
    from dnabraid.run import engine, reporters
    from dnabraid.scenes import tether

    cls = type(scene)
    return {"validate": code_key(cls.check_passage_barrier), "build": code_key(cls.build),
            "start": code_key(tether.Tether.equilibrium_start),
            "context": code_key(engine.Engine.__init__),
            "advance": code_key(engine.Engine.advance),
            "combine": code_key(reporters.combine),
            "plot": code_key(plots.extension_torque_plot)}


def is_openmm_step(key) -> bool:
    """The ``step`` method of an OpenMM integrator (the Python wrapper of openmm's SWIG
    module; its C call below it is counted inside it)."""
    return key[2] == "step" and "openmm" in pathlib.PurePath(key[0]).parts


def split(st: dict, keys: dict, total: float) -> dict:
    """The wall-time split of one study from its pstats table ``st``."""
    ct = {part: st[k][3] if k in st else 0.0 for part, k in keys.items()}
    ct["step"] = sum(v[3] for k, v in st.items() if is_openmm_step(k))
    out = {"validate": ct["validate"], "build": ct["build"], "start": ct["start"],
           "context": ct["context"], "step": ct["step"],
           "advance_extra": ct["advance"] - ct["step"],
           "combine": ct["combine"], "plot": ct["plot"]}
    out["other"] = total - sum(v for k, v in out.items() if k != "start")
    out["total"] = total
    return out


def start_counts(st: dict) -> tuple[int, int]:
    """(starts, fallback starts) of one study: calls of ``Tether.equilibrium_start``, and
    calls of ``random_tether`` made by ``Tether.attach`` (equilibrium_start gave None)."""
    from dnabraid.geometry import starts
    from dnabraid.scenes import tether

    es = st.get(code_key(tether.Tether.equilibrium_start))
    rt = st.get(code_key(starts.random_tether))
    n = es[1] if es else 0
    fb = rt[4].get(code_key(tether.Tether.attach), (0, 0))[1] if rt else 0
    return int(n), int(fb)


def uncached_validation_s(length_nm: float) -> float:
    """Wall time of one scene validation's passage check without the library's memo."""
    from dnabraid import chains
    from dnabraid.scenes import make_scene

    s = make_scene("tether", {"length_nm": length_nm, "surface": False,
                              "self_avoidance": False})
    d = s.effective_diameter_nm
    k_kT = s.stretch_modulus_pN / s.bead_spacing_nm / s.kT
    t0 = time.perf_counter()
    chains.passage_barrier_kT.__wrapped__(s.bead_spacing_nm, d, k_kT)
    return time.perf_counter() - t0


# ----------------------------------------------------------------------------- studies
def scene_values(L, F, *, replicas, steps, seed, surface=False, self_avoidance=False):
    return {"length_nm": L, "force_pN": F, "replicas": replicas, "workers": 1,
            "surface": surface, "self_avoidance": self_avoidance, "steps": steps,
            "equilibration_steps": 0, "frame_interval": steps, "seed": seed}


def exact_for(L, F):
    from dnabraid.continuum.wlc import discrete_wlc_exact
    from dnabraid.scenes import make_scene

    s = make_scene("tether", scene_values(L, F, replicas=4, steps=100, seed=1))
    d = s.dna()
    e = discrete_wlc_exact(F, s.n_beads - 1, s.bead_spacing_nm, d.kappa_kT, d.kT,
                           stretch_k_pN_per_nm=d.k_bond)
    return s.n_beads - 1, float(e["extension_nm"]), float(e["extension_var_nm2"])


def one_study(values: dict) -> dict:
    """``make_scene`` and ``Tether.run`` (profiled) in a scratch directory: its reported extension, the
    replicas' raw series (every sample), the verdict, the timing split and the starts."""
    from dnabraid.run import reporters
    from dnabraid.scenes import make_scene

    with tempfile.TemporaryDirectory(prefix="calib_") as td:
        prof = cProfile.Profile()
        t0 = time.perf_counter()
        prof.enable()
        try:
            s = make_scene("tether", values)  # validates the scene (the replicas are copies)
            summ = s.run(td)
        finally:
            prof.disable()
        wall = time.perf_counter() - t0
        series = []
        for r in range(s.replicas):
            rdir = os.path.join(td, "replicas", f"r{r:02d}", "points")
            (pdir,) = [os.path.join(rdir, p) for p in os.listdir(rdir)]
            series.append(reporters.read_point(pdir)[0]["extension_nm"].tolist())
    st = pstats.Stats(prof).stats
    n_starts, n_fallback = start_counts(st)
    pt = summ["points"][0]
    e = pt["extension_nm"]
    return {"seed": values["seed"], "mean": e["mean"], "sem": e["sem"],
            "ci_halfwidth": e["ci_halfwidth"], "converged": bool(pt["converged"]),
            "reason": pt["convergence_reason"], "cut": e.get("equilibration_samples"),
            "series": series, "wall_s": wall, "split": split(st, profiled_keys(s), wall),
            "starts": n_starts, "fallback_starts": n_fallback}


# ----------------------------------------------------------------------------- output
def fmt_pm(x, e, p=2):
    return f"{x:+.{p}f} ± {e:.{p}f}"


def calib_table(rows, R) -> list[str]:
    t_ref = (R - 1) / (R - 3) if R > 3 else float("inf")
    out = [f"| L (nm) | F (pN) | N bonds | studies K | exact <z> (nm) | exact sd(z) / √R (nm) | "
           f"mean of study means − exact (nm) | coverage (95% CI) | <t²> (Student {t_ref:.3g}; "
           "95% band for K) | <z²> (1; 95% band for K) | scatter² / <sem²> | mean sem (nm) | "
           "converged | coverage, no cut | <z²>, no cut | wall / study (s) |",
           "|" + "---|" * 16]
    for r in rows:
        c, u = r["reported"], r["no_cut"]
        K = c["K"]
        lo_t, hi_t = t2_band(K, R - 1)
        lo_z, hi_z = z2_band(K)
        out.append(
            f"| {r['L']:g} | {r['F']:g} | {r['n_bonds']} | {K} | {r['exact']:.2f} | "
            f"{r['exact_sd'] / math.sqrt(R):.2f} | {fmt_pm(c['bias'], c['bias_err'])} | "
            f"{c['coverage']:.3f} ({c['coverage_ci'][0]:.2f}–{c['coverage_ci'][1]:.2f}) | "
            f"{c['t2']:.2f} [{lo_t:.2f}–{hi_t:.2f}] | {c['z2']:.2f} [{lo_z:.2f}–{hi_z:.2f}] | "
            f"{c['scatter_over_sem2']:.2f} | {c['mean_sem']:.2f} | {r['converged']:.2f} | "
            f"{u['coverage']:.3f} | {u['z2']:.2f} | {r['wall_s']:.2f} |")
    return out


def shift_table(srows) -> list[str]:
    out = ["| L (nm) | F (pN) | variant | steps | studies × R | exact starts | <z> (nm) | "
           "sim − exact free chain (nm) | shift vs none (nm) | drift last − first quarter (nm) "
           "| wall / study (s) |", "|" + "---|" * 11]
    for r in srows:
        sh = ("—" if r["variant"] == "none" or r.get("shift") is None
              else fmt_pm(r["shift"], r["shift_err"]))
        out.append(
            f"| {r['L']:g} | {r['F']:g} | {r['variant']} | {r['steps']} | "
            f"{r['K']} × {r['R']} | {r['exact_starts']}/{r['starts']} | "
            f"{r['mean']:.2f} ± {r['err']:.2f} | {fmt_pm(r['mean'] - r['exact'], r['err'])} | "
            f"{sh} | {fmt_pm(r['drift'], r['drift_err'])} | {r['wall_s']:.1f} |")
    return out


def timing_table(rows, srows, uncached) -> list[str]:
    groups = {}
    for r in rows:
        groups.setdefault(("calibration", r["L"], r["steps"], r["R"]), []).append(r["split"])
    for r in srows:
        groups.setdefault((f"shift: {r['variant']}", r["L"], r["steps"], r["R"]),
                          []).append(r["split"])
    head = "| run | L (nm) | steps × R | " + " | ".join(p for p, _ in PARTS) + \
        " | total (s) | steps / s (all replicas) |"
    out = [head, "|" + "---|" * (len(PARTS) + 5)]
    for (kind, L, S, R), sp in groups.items():
        avg = {k: float(np.mean([x[k] for x in sp])) for k in sp[0]}
        rate = S * R / avg["step"] if avg["step"] > 0 else float("nan")
        out.append(f"| {kind} | {L:g} | {S} × {R} | " +
                   " | ".join(f"{avg[k]:.3f}" for _, k in PARTS) +
                   f" | {avg['total']:.2f} | {rate:,.0f} |")
    if uncached:
        out.append("")
        out.append("Uncached passage check per scene validation (L > 3 P; a study "
                   "validates its scene once, the replicas are copies): " + ", ".join(f"L = {L:g} nm: {t:.3f} s" for L, t in
                                           uncached.items()) + ".")
    return out


def write(out: pathlib.Path, meta: dict, rows, srows, pending, pending_shift, uncached,
          reading: list[str]) -> None:
    R, K = meta["replicas"], meta["studies"]
    lines = ["# Calibration of the tether's error bars against the exact discrete WLC",
             "",
             f"Run {meta['date']} by `workflows/calibration.py {meta['argv']}` on "
             f"{meta['machine']}; one core used (studies run serially in-process, "
             f"`workers = 1`). Total wall time so far {meta['wall_total_s'] / 60:.1f} min.",
             "",
             f"Each case: up to K = {K} independent studies (seeds {meta['seed_base']} + 100 × case "
             f"+ k), each one `tether` run with `replicas = {R}`, `workers = 1`, "
             f"`surface = false`, `self_avoidance = false`, `steps = {meta['steps']}`, "
             "`equilibration_steps = 0` (every replica starts from an exact equilibrium "
             "draw), default bead model (b = 5 nm, P = 50 nm, S = 1100 pN, 150 mM). "
             "Exact value: `discrete_wlc_exact` of the same bead model. The reported "
             "interval is `points[0].extension_nm.ci_halfwidth` (Student t, R − 1 dof)."
             + (f" A case stops early once it has used {meta['case_budget_s']:g} s and has "
                f"at least {meta['min_studies']} studies (the K column says how many ran)."
                if meta.get("case_budget_s") else ""),
             "",
             "Columns: *exact sd(z)/√R* is the sem if each replica mean were a single "
             "independent draw (runs much shorter than the slow modes); *t* = (mean − exact)"
             "/sem; *z* = the t-score mapped through the Student-t(R − 1) CDF to a normal "
             "score, so <z²> = 1 for honest error bars (95 % band χ²_K/K); <t²> is compared "
             "with the Student-t variance and a Monte-Carlo band for K draws; "
             "*scatter² / <sem²>* = variance of the K study means over the mean squared "
             "reported sem (1 if honest); *converged* = share of studies the run called "
             "converged; *no cut* = the same statistics keeping every sample (no Chodera "
             "truncation), from the replicas' raw series.",
             ""]
    if reading:
        lines += ["## Reading", ""] + reading + [""]
    lines += ["## Calibration (no wall, no self-avoidance)", ""]
    lines += calib_table(rows, R)
    if pending:
        lines += ["", "Not yet run / dropped: " + ", ".join(f"{L:g} nm at {F:g} pN"
                                                           for L, F in pending) + "."]
    p = pooled(rows, R)
    if p:
        lines += ["", "Pooled over the cases above:", ""]
        for key, name in (("reported", "reported (as the scene reports)"),
                          ("no_cut", "no cut (every sample kept)")):
            q = p[key]
            lines.append(
                f"- {name}: coverage {q['covered']}/{q['n']} = {q['coverage']:.3f} "
                f"(95 % CI {q['coverage_ci'][0]:.3f}–{q['coverage_ci'][1]:.3f}); <z²> = "
                f"{q['z2']:.3f} (band {q['z2_band'][0]:.2f}–{q['z2_band'][1]:.2f}); "
                f"Kolmogorov-Smirnov of z against N(0,1): p = {q['ks_p']:.3g}; case biases "
                f"in units of their error: χ² = {q['bias_chi2']:.1f} on {q['bias_dof']} dof "
                f"(p = {q['bias_chi2_p']:.3g}).")
    lines += ["", "## Shift of the mean extension by the wall and by self-avoidance", ""]
    if srows:
        lines += [f"Up to K = {meta['shift_studies']} studies × R = {R} replicas per variant, "
                  f"`steps = {meta['shift_steps']}` ({meta['shift_steps'] // meta['steps']} x "
                  "the calibration runs) because with the wall or self-avoidance the start is "
                  "the exact free-chain draw *conditioned on being allowed* (rejection, up to "
                  "64 draws; beads above z = d/2, non-neighbours ≥ 0.8 d apart), which is not "
                  "exactly the interacting model's distribution (soft wall, WCA at d), and falls "
                  "back to a random non-equilibrium tether when no draw is allowed (*exact "
                  "starts* counts the starts that got an allowed draw (from the profile: calls of "
                  "`Tether.equilibrium_start` less the `random_tether` fallbacks), R + 1 per "
                  "study: each "
                  "replica's and the run's own model's). These runs are still far shorter "
                  "than the slowest transverse mode, so a start bias would remain: the *drift* "
                  "column (mean of the last quarter minus the first quarter of each replica, "
                  "averaged) shows whether the replicas move away from their starts. Errors: "
                  "standard error from the scatter of all K × R replica means (every sample "
                  "kept); shifts: sim(with) − sim(none) at the same run length, errors "
                  "combined in quadrature.", ""]
        lines += shift_table(srows)
    if pending_shift:
        lines += ["", "Not yet run / dropped: " + ", ".join(
            f"{L:g} nm at {F:g} pN {v}" for L, F, v in pending_shift) + "."]
    lines += ["", "## Where the wall time goes (mean per study, s)", "",
              "Each study runs under `cProfile`; the parts are the cumulative times "
              "(pstats) of `TweezerScene.check_passage_barrier`, `TweezerScene.build`, "
              "`Tether.equilibrium_start`, `Engine.__init__`, the OpenMM integrator's "
              "`step`, `Engine.advance`, `reporters.combine` and "
              "`plots.extension_torque_plot`; the total is the wall time of the profiled "
              "`make_scene` + `Tether.run` (the profiler slows their Python parts). The passage check is memoised in "
              "the library (`dnabraid.chains`; its uncached cost below). A study of R "
              "replicas builds R + 1 models (the run's own and one per replica) and draws "
              "R + 1 exact starts.", ""]
    lines += timing_table(rows, srows, uncached)
    lines.append("")
    out.write_text("\n".join(lines))
    js = {"meta": meta, "calibration": rows, "pooled": p, "shift": srows,
          "uncached_validation_s": uncached}
    out.with_suffix(".json").write_text(json.dumps(js, indent=1, default=float))


def plot(out: pathlib.Path, rows, R) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not rows:
        return
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    x = np.arange(len(rows))
    c = [r["reported"]["coverage"] for r in rows]
    lo = [r["reported"]["coverage"] - r["reported"]["coverage_ci"][0] for r in rows]
    hi = [r["reported"]["coverage_ci"][1] - r["reported"]["coverage"] for r in rows]
    ax[0].errorbar(x, c, yerr=[lo, hi], fmt="o", capsize=3, label="reported interval")
    ax[0].plot(x + 0.15, [r["no_cut"]["coverage"] for r in rows], "s", ms=4, alpha=0.6,
               label="no cut")
    ax[0].axhspan(0.9, 0.99, color="g", alpha=0.15, label="0.90–0.99")
    ax[0].axhline(0.95, color="k", lw=0.8)
    ax[0].set_xticks(x, [f"{r['L']:g}/{r['F']:g}" for r in rows], rotation=60, fontsize=8)
    ax[0].set_xlabel("L (nm) / F (pN)")
    ax[0].set_ylabel("coverage of 95 % intervals (Clopper-Pearson CI)")
    ax[0].legend(fontsize=8)
    z = np.sort(np.concatenate([r["reported"]["z"] for r in rows]))
    q = stats.norm.ppf((np.arange(1, z.size + 1) - 0.5) / z.size)
    ax[1].plot(q, z, ".", ms=3)
    ax[1].plot([-3.5, 3.5], [-3.5, 3.5], "k-", lw=0.8)
    ax[1].set_xlabel("N(0,1) quantile")
    ax[1].set_ylabel("z-score (t through Student-t CDF), pooled")
    ax[1].set_title(f"{z.size} studies, R = {R}")
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------- main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="a ~1-minute smoke run (options given explicitly still apply)")
    ap.add_argument("--studies", type=int, help="independent studies per case (30; quick 4)")
    ap.add_argument("--replicas", type=int, default=4, help="replicas per study (R)")
    ap.add_argument("--steps", type=int, help="steps per replica (2000; quick 500)")
    ap.add_argument("--lengths", type=float, nargs="+", help="contour lengths (nm)")
    ap.add_argument("--forces", type=float, nargs="+", help="forces (pN)")
    ap.add_argument("--shift-studies", type=int, help="studies per shift variant (10; quick 2)")
    ap.add_argument("--shift-steps", type=int, help="steps per replica of the shift table")
    ap.add_argument("--shift-cases", nargs="+", help="L:F pairs (nm:pN) of the shift table")
    ap.add_argument("--shift-variants", nargs="+", default=[v for v, _, _ in SHIFT_VARIANTS],
                    choices=[v for v, _, _ in SHIFT_VARIANTS], metavar="VARIANT",
                    help="variants of the shift table (shifts are against 'none'): "
                         + ", ".join(repr(v) for v, _, _ in SHIFT_VARIANTS))
    ap.add_argument("--no-shift", action="store_true", help="skip the shift table")
    ap.add_argument("--seed-base", type=int, default=1000)
    ap.add_argument("--case-budget-s", type=float, default=0.0,
                    help="stop a case after this many seconds once it has --min-studies "
                         "studies (0: no limit)")
    ap.add_argument("--min-studies", type=int, default=12)
    ap.add_argument("--shift-budget-s", type=float, default=0.0,
                    help="the same per shift variant (at least 4 studies)")
    ap.add_argument("--resume", action="store_true",
                    help="keep the cases already in --out's calibration.json (same R, steps, "
                         "seeds)")
    ap.add_argument("--table-only", action="store_true",
                    help="rewrite the .md and .png from --out's calibration.json; run nothing")
    ap.add_argument("--out", default=str(HERE / "results"), metavar="DIR",
                    help="directory of calibration.md, .json, .png (default: %(default)s)")
    ap.set_defaults(**(QUICK if ap.parse_known_args(argv)[0].quick else FULL))
    args = ap.parse_args(argv)
    shift_cases = [tuple(float(v) for v in c.split(":")) for c in args.shift_cases]
    out = pathlib.Path(args.out) / "calibration.md"
    js_path = out.with_suffix(".json")
    if args.table_only:
        js = json.loads(js_path.read_text())
        meta, rows, srows = js["meta"], js["calibration"], js["shift"]
        for k, v in (("case_budget_s", 0.0), ("min_studies", 0)):
            meta.setdefault(k, v)
        unc = {float(k): v for k, v in js["uncached_validation_s"].items()}
        write(out, meta, rows, srows, [], [], unc,
              auto_reading(rows, srows, meta["replicas"]))
        plot(out, rows, meta["replicas"])
        return 0
    from tqdm import tqdm

    warnings.filterwarnings("ignore", category=DeprecationWarning)
    out.parent.mkdir(parents=True, exist_ok=True)
    R, K, S = args.replicas, args.studies, args.steps
    cases = [(L, F) for L in args.lengths for F in args.forces]
    shifts = [] if args.no_shift else [(L, F, v) for L, F in shift_cases
                                       for v, _, _ in SHIFT_VARIANTS
                                       if v in args.shift_variants]
    try:
        cpu = next(ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo")
                   if ln.startswith("model name"))
    except (OSError, StopIteration):
        cpu = platform.processor()
    meta = {"date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
            "argv": " ".join(argv if argv is not None else sys.argv[1:]),
            "machine": f"{cpu}, {os.cpu_count()} cores shared with other work",
            "replicas": R, "studies": K, "steps": S, "seed_base": args.seed_base,
            "shift_studies": args.shift_studies, "shift_steps": args.shift_steps,
            "timing": "cProfile", "wall_total_s": 0.0,
            "case_budget_s": args.case_budget_s, "min_studies": args.min_studies,
            "shift_budget_s": args.shift_budget_s, "wall_previous_s": 0.0}
    done, sdone = {}, {}
    if args.resume and js_path.exists():
        old = json.loads(js_path.read_text())
        om = old["meta"]
        if (om["replicas"], om["steps"], om["seed_base"]) == (R, S, args.seed_base):
            done = {(r["L"], r["F"]): r for r in old["calibration"]}
            meta["wall_previous_s"] = om["wall_total_s"]
            meta["date"] = om["date"] + " (resumed " + meta["date"] + ")"
            meta["argv"] = (om["argv"] + "`, then `workflows/calibration.py "
                            + meta["argv"]).replace("  ", " ")
        if (om["replicas"], om["shift_steps"], om["seed_base"]) == (R, args.shift_steps,
                                                                    args.seed_base):
            sdone = {(r["L"], r["F"], r["variant"]): r for r in old["shift"]}
    uncached = {}
    for L in sorted(set(args.lengths)):
        from dnabraid.scenes import make_scene

        s = make_scene("tether", {"length_nm": L, "surface": False, "self_avoidance": False})
        if s.length_nm > 3 * s.persistence_nm:
            uncached[L] = uncached_validation_s(L)
    t_start = time.perf_counter()
    rows, srows = [], []
    total = len(cases) * K + len(shifts) * args.shift_studies
    bar = tqdm(total=total, unit="study", smoothing=0.1)

    def flush(pending, pending_shift, reading=()):
        meta["wall_total_s"] = meta["wall_previous_s"] + time.perf_counter() - t_start
        write(out, meta, rows, srows, pending, pending_shift, uncached, list(reading))
        with contextlib.suppress(Exception):
            plot(out, rows, R)

    for ci, (L, F) in enumerate(cases):
        if (L, F) in done:
            rows.append(done[(L, F)])
            bar.update(K)
            continue
        n_bonds, exact, var = exact_for(L, F)
        bar.set_description(f"{L:g} nm {F:g} pN")
        studies = []
        t_case = time.perf_counter()
        for k in range(K):
            studies.append(one_study(scene_values(L, F, replicas=R, steps=S,
                                                  seed=args.seed_base + 100 * ci + k)))
            bar.update(1)
            if (args.case_budget_s and k + 1 >= args.min_studies
                    and time.perf_counter() - t_case > args.case_budget_s):
                bar.update(K - k - 1)
                break
        m = [s["mean"] for s in studies]
        rep = calib_stats(m, [s["sem"] for s in studies], [s["ci_halfwidth"] for s in studies],
                          exact, R)
        nc = calib_stats(*untruncated(studies, R), exact, R)
        sp = {k: float(np.mean([s["split"][k] for s in studies])) for k in studies[0]["split"]}
        rows.append({"L": L, "F": F, "n_bonds": n_bonds, "exact": exact,
                     "exact_sd": math.sqrt(var), "R": R, "steps": S, "reported": rep,
                     "no_cut": nc,
                     "converged": float(np.mean([s["converged"] for s in studies])),
                     "wall_s": float(np.mean([s["wall_s"] for s in studies])), "split": sp,
                     "studies": [{k: v for k, v in s.items() if k not in ("series", "split")}
                                 for s in studies]})
        tqdm.write(f"{L:g} nm {F:g} pN: exact {exact:.2f}, bias {rep['bias']:+.2f} ± "
                   f"{rep['bias_err']:.2f}, coverage {rep['coverage']:.2f}, <z²> "
                   f"{rep['z2']:.2f} (no cut {nc['coverage']:.2f}, {nc['z2']:.2f}), "
                   f"{rows[-1]['wall_s']:.2f} s/study")
        flush(cases[ci + 1:], shifts)
    base = {}
    for si, (L, F, variant) in enumerate(shifts):
        _, surf, sa = next(v for v in SHIFT_VARIANTS if v[0] == variant)
        if (L, F, variant) in sdone:
            row = sdone[(L, F, variant)]
            if variant == "none":
                base[(L, F)] = row
            srows.append(row)
            bar.update(args.shift_studies)
            continue
        n_bonds, exact, _ = exact_for(L, F)
        bar.set_description(f"shift {L:g} nm {F:g} pN {variant}")
        studies = []
        t_case = time.perf_counter()
        for k in range(args.shift_studies):
            studies.append(one_study(scene_values(
                L, F, replicas=R, steps=args.shift_steps, surface=surf, self_avoidance=sa,
                seed=args.seed_base + 5000 + 100 * si + k)))
            bar.update(1)
            if (args.shift_budget_s and k + 1 >= 4
                    and time.perf_counter() - t_case > args.shift_budget_s):
                bar.update(args.shift_studies - k - 1)
                break
        rm = np.array([np.mean(x) for s in studies for x in s["series"]])
        ser = [np.asarray(x) for s in studies for x in s["series"]]
        dr = np.array([np.mean(x[-max(1, len(x) // 4):]) - np.mean(x[:max(1, len(x) // 4)])
                       for x in ser])
        n_starts = sum(s["starts"] for s in studies)
        row = {"L": L, "F": F, "variant": variant, "steps": args.shift_steps, "R": R,
               "K": len(studies), "exact": exact, "mean": float(rm.mean()),
               "err": float(rm.std(ddof=1) / math.sqrt(rm.size)),
               "drift": float(dr.mean()), "drift_err": float(dr.std(ddof=1) / math.sqrt(dr.size)),
               "exact_starts": n_starts - sum(s["fallback_starts"] for s in studies),
               "starts": n_starts,
               "converged": float(np.mean([s["converged"] for s in studies])),
               "wall_s": float(np.mean([s["wall_s"] for s in studies])),
               "split": {k: float(np.mean([s["split"][k] for s in studies]))
                         for k in studies[0]["split"]},
               "studies": [{k: v for k, v in s.items() if k not in ("series", "split")}
                           for s in studies]}
        if variant == "none":
            base[(L, F)] = row
        b = base.get((L, F))
        if b is not None:
            row["shift"] = row["mean"] - b["mean"]
            row["shift_err"] = math.hypot(row["err"], b["err"])
        srows.append(row)
        tqdm.write(f"shift {L:g} nm {F:g} pN {variant}: {row['mean']:.2f} ± {row['err']:.2f} "
                   f"(exact free {exact:.2f}), drift {row['drift']:+.2f} ± "
                   f"{row['drift_err']:.2f}, exact starts {row['exact_starts']}/{n_starts}")
        flush([], shifts[si + 1:])
    bar.close()
    flush([], [], reading=auto_reading(rows, srows, R))
    print(f"wrote {out} ({(time.perf_counter() - t_start) / 60:.1f} min)")
    return 0


def auto_reading(rows, srows, R) -> list[str]:
    """Plain statements computed from the numbers (the author's reading is added by hand
    below the generated table when the full run is kept)."""
    if not rows:
        return []
    p = pooled(rows, R)["reported"]
    inside = [r for r in rows if 0.9 <= r["reported"]["coverage"] <= 0.99]
    out = [f"- Pooled coverage of the reported 95 % intervals: {p['coverage']:.3f} "
           f"(95 % CI {p['coverage_ci'][0]:.3f}–{p['coverage_ci'][1]:.3f}) over {p['n']} "
           f"studies; {len(inside)}/{len(rows)} cases have a point estimate in 0.90–0.99 "
           "(with K studies per case the binomial scatter alone is ±"
           f"{2 * math.sqrt(0.95 * 0.05 / rows[0]['reported']['K']):.2f} at 2σ).",
           f"- Pooled <z²> = {p['z2']:.3f} (1 expected; 95 % band {p['z2_band'][0]:.3f}–"
           f"{p['z2_band'][1]:.3f}); KS p = {p['ks_p']:.3g}.",
           f"- Case biases against the exact value: χ² = {p['bias_chi2']:.1f} on "
           f"{p['bias_dof']} dof (p = {p['bias_chi2_p']:.3g})."]
    return out


if __name__ == "__main__":
    raise SystemExit(main())
