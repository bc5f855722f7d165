"""Calibration that tests the dynamics and the verdict: tethers started away from
equilibrium must reach the exact discrete WLC, and the verdict must say when they have not.

The ``tether`` scene without wall and excluded volume (``surface = false``,
``self_avoidance = false``) is exactly the discrete worm-like chain under an end force,
whose mean extension :func:`dnabraid.continuum.wlc.discrete_wlc_exact` gives by a transfer
matrix. Here each replica starts from its own exact draw at *another* force
(``start = 'force'``, ``start_force_pN``: a chain stretched at 10 F or coiled at F / 10), so
the replica means are biased by the start unless the run forgets it, and the data-driven
equilibration cut (Chodera 2016), split R-hat and bulk ESS (Vehtari et al. 2021) decide
the verdict. Unlike the exact-start calibration (``workflows/calibration.py``), nothing
here is unbiased by construction.

Per case (length, force, start force, Metropolis moves per report interval, steps), K
independent studies (own seeds), each one ``Tether.run`` of R = 4 replicas in this process:

* the share of studies called converged;
* among the converged: coverage of the reported 95 % intervals (Clopper-Pearson interval),
  <z^2> (t-scores through the Student-t CDF; 1 for honest error bars, 95 % band
  chi^2_K / K) and the bias of the means;
* among the NOT CONVERGED: the same, to show what the verdict caught.

"Short" cases (few moves) are chosen so that the start is not always forgotten: a
verdict that can fail must fail there, and the converged studies must still cover.

Usage: python workflows/calibration_dynamics.py [--studies 20] [--quick] [--jobs 2]
Writes workflows/results/calibration_dynamics.md (+ .json).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import datetime
import json
import math
import os
import pathlib
import tempfile
import time

import numpy as np

from dnabraid.analysis.calibration import calib_stats, z2_band

HERE = pathlib.Path(__file__).resolve().parent

#: (length nm, force pN, start force pN, mc_moves, steps[, equilibration steps, default 0])
CASES = ((600.0, 0.3, 3.0, 500, 40000), (600.0, 0.3, 0.03, 500, 40000),
         (600.0, 0.3, 3.0, 500, 8000), (300.0, 1.0, 10.0, 500, 8000),
         (300.0, 1.0, 0.1, 500, 8000), (300.0, 1.0, 10.0, 0, 20000),
         # the first case with the tether's default equilibration (40000 steps) before
         # the samples: the stretched start's memory must be gone
         (600.0, 0.3, 3.0, 500, 40000, 40000))
QUICK = ((600.0, 0.3, 3.0, 500, 4000), (300.0, 1.0, 0.1, 500, 2000))
R = 4


def scene_values(L, F, F0, moves, steps, seed, eq=0) -> dict:
    return {"length_nm": L, "force_pN": F, "replicas": R, "workers": 1, "surface": False,
            "self_avoidance": False, "steps": steps, "equilibration_steps": eq,
            "frame_interval": steps, "seed": seed, "mc_moves": moves, "start": "force",
            "start_force_pN": F0}


def exact_for(L, F) -> float:
    from dnabraid.continuum.wlc import discrete_wlc_exact
    from dnabraid.scenes import make_scene

    s = make_scene("tether", scene_values(L, F, F, 0, 100, 1))
    d = s.dna()
    e = discrete_wlc_exact(F, s.n_beads - 1, s.bead_spacing_nm, d.kappa_kT, d.kT,
                           stretch_k_pN_per_nm=d.k_bond)
    return float(e["extension_nm"])


def one_study(values: dict) -> dict:
    from dnabraid.scenes import make_scene

    with tempfile.TemporaryDirectory(prefix="calibdyn_") as td:
        t0 = time.perf_counter()
        summ = make_scene("tether", values).run(td)
        wall = time.perf_counter() - t0
    pt = summ["points"][0]
    e = pt["extension_nm"]
    starts = pt.get("starts") or []
    return {"seed": values["seed"], "mean": e["mean"], "sem": e["sem"],
            "ci_halfwidth": e["ci_halfwidth"], "rhat": e.get("rhat"),
            "ess": min(pt["effective_sample_size"].values()),
            "converged": bool(pt["converged"]), "reason": pt["convergence_reason"],
            "start_kinds": sorted({s.get("kind", "?") for s in starts}), "wall_s": wall}


def summarise(studies, exact) -> dict:
    out = {"K": len(studies), "n_converged": sum(s["converged"] for s in studies)}
    for name, sel in (("converged", True), ("not_converged", False)):
        ss = [s for s in studies if s["converged"] == sel]
        if len(ss) >= 2:
            c = calib_stats([s["mean"] for s in ss], [s["sem"] for s in ss],
                            [s["ci_halfwidth"] for s in ss], exact, R)
            c.pop("t")
            c.pop("z")
            out[name] = c
        else:
            out[name] = {"K": len(ss)}
            if ss:
                out[name]["covered"] = int(abs(ss[0]["mean"] - exact) <= ss[0]["ci_halfwidth"])
    out["wall_s"] = float(np.mean([s["wall_s"] for s in studies]))
    return out


def _cell(c) -> str:
    if c.get("K", 0) < 2:
        return f"{c.get('K', 0)} | {c.get('covered', '-')} | - | -"
    lo, hi = z2_band(c["K"])
    return (f"{c['K']} | {c['coverage']:.2f} ({c['coverage_ci'][0]:.2f}-"
            f"{c['coverage_ci'][1]:.2f}) | {c['z2']:.2f} [{lo:.2f}-{hi:.2f}] | "
            f"{c['bias']:+.2f} +- {c['bias_err']:.2f}")


def table(rows) -> list[str]:
    out = ["| L nm | F pN | start drawn at pN | mc_moves | equilibration + steps | exact <z> nm | K | "
           "converged | converged: K, coverage (95% CI), <z^2> [band], bias nm | "
           "NOT CONVERGED: K, coverage, <z^2>, bias nm | wall / study s |",
           "|" + "---|" * 11]
    for r in rows:
        s = r["stats"]
        out.append(f"| {r['L']:g} | {r['F']:g} | {r['F0']:g} | {r['moves']} | "
                   f"{r.get('eq', 0)} + {r['steps']} | "
                   f"{r['exact']:.2f} | {s['K']} | {s['n_converged'] / s['K']:.2f} | "
                   f"{_cell(s['converged'])} | {_cell(s['not_converged'])} | "
                   f"{s['wall_s']:.1f} |")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", type=int, default=20)
    ap.add_argument("--quick", action="store_true", help="two cases, 4 studies")
    ap.add_argument("--jobs", type=int, default=2, help="studies run in parallel processes")
    ap.add_argument("--out", default=str(HERE / "results" / "calibration_dynamics"))
    a = ap.parse_args(argv)
    cases = QUICK if a.quick else CASES
    K = 4 if a.quick else a.studies
    t_all = time.perf_counter()
    rows = []
    with cf.ProcessPoolExecutor(max_workers=a.jobs) as ex:
        for ci, (L, F, F0, moves, steps, *eq) in enumerate(cases):
            eq = eq[0] if eq else 0
            exact = exact_for(L, F)
            vals = [scene_values(L, F, F0, moves, steps, 5000 + 100 * ci + k, eq)
                    for k in range(K)]
            studies = list(ex.map(one_study, vals))
            rows.append({"L": L, "F": F, "F0": F0, "moves": moves, "steps": steps, "eq": eq,
                         "exact": exact, "stats": summarise(studies, exact),
                         "studies": studies})
            print("\n".join(table(rows)[-1:]), flush=True)
    wall = time.perf_counter() - t_all
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    pooled = [s for r in rows for s in r["studies"]]
    conv = [s for s in pooled if s["converged"]]
    cov_c = sum(abs(s["mean"] - r["exact"]) <= s["ci_halfwidth"]
                for r in rows for s in r["studies"] if s["converged"])
    cov_n = sum(abs(s["mean"] - r["exact"]) <= s["ci_halfwidth"]
                for r in rows for s in r["studies"] if not s["converged"])
    nn = len(pooled) - len(conv)
    lines = ["# Calibration of the dynamics and the verdict: tethers started away from "
             "equilibrium", "",
             f"Run {stamp} by `workflows/calibration_dynamics.py{' --quick' if a.quick else ''}"
             f" --studies {K} --jobs {a.jobs}`, {os.cpu_count()} cores; {wall / 60:.1f} min. "
             f"Each study: `tether` with replicas = {R}, surface = false, self_avoidance = "
             "false, equilibration_steps = 0 unless given (the cut is the data's), start = 'force' (each "
             "replica its own exact draw at the start force), default moves' amplitudes; "
             "exact value: `discrete_wlc_exact` of the same bead model.", "",
             *table(rows), "",
             f"Pooled: {len(conv)} of {len(pooled)} studies converged; their 95 % intervals "
             f"cover the exact value in {cov_c} of {len(conv)}"
             + (f" ({cov_c / len(conv):.3f})" if conv else "")
             + f"; the NOT CONVERGED ones in {cov_n} of {nn}"
             + (f" ({cov_n / nn:.3f})" if nn else "") + "."]
    out = pathlib.Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    out.with_suffix(".json").write_text(json.dumps({"rows": rows, "wall_s": wall}, indent=1))
    print("\n".join(lines[-1:]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
