"""Independent seeds of the default braid: do they scatter as their error bars say?

Runs `dnabraid run` (the default scene) for seeds 1 ... K (or reads finished run
directories with --from-runs) and reports:

* per point and observable (extension, trap torque), the inverse-variance pooled mean over
  the seeds and chi^2 = sum_s (m_s - pooled)^2 / sem_s^2 on K - 1 dof; the total chi^2 over
  all points (reduced chi^2 ~ 1 when the reported errors are honest; the per-seed errors
  are sample SEMs of 8 replica means, so honest errors give E[chi^2 / dof] ~ 7/5, not 1:
  the p-values are computed for that model by Monte Carlo);
* the mirror symmetry of alpha = 0: z(+n) - z(-n), Gamma(+n) + Gamma(-n) and Gamma(0)
  vanish exactly in equilibrium; their z-scores against the reported errors;
* the pooled means, written to the .json for workflows/convergence.py part C.

Usage: python workflows/default_seeds.py [--seeds 6] [--out runs/default_seeds]
       python workflows/default_seeds.py --from-runs runs/default_seeds/s*
Writes workflows/results/default_seeds.md and .json.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
import time

import numpy as np
from scipy import stats

HERE = pathlib.Path(__file__).resolve().parent
OBS = ("extension_nm", "torque_pN_nm")


def _t_model_p(chi2: float, K: int, P: int, R: int, sym_chi2: float, n_pair: int,
               n_single: int, draws: int = 20000, seed: int = 0) -> tuple[float, float]:
    """p-values of the scatter chi^2 and the symmetry sum of z^2 under honest errors: each
    reported SEM is the sample SEM of R independent normal replica means (so it scatters
    as sqrt(chi^2_{R-1} / (R - 1)) around the true one), simulated (Monte Carlo)."""
    rng = np.random.default_rng(seed)
    m = rng.standard_normal((draws, P, K))
    e = np.sqrt(rng.chisquare(R - 1, (draws, P, K)) / (R - 1))
    w = 1.0 / e**2
    mu = (w * m).sum(-1, keepdims=True) / w.sum(-1, keepdims=True)
    c = ((m - mu) ** 2 * w).sum((1, 2))
    a, b = rng.standard_normal((2, draws, n_pair))
    sa, sb = rng.chisquare(R - 1, (2, draws, n_pair)) / (R - 1)
    z2 = ((a - b) ** 2 / (sa + sb)).sum(-1)
    g = rng.standard_normal((draws, n_single))
    z2 = z2 + (g**2 / (rng.chisquare(R - 1, (draws, n_single)) / (R - 1))).sum(-1)
    return float(np.mean(c >= chi2)), float(np.mean(z2 >= sym_chi2))


def analyse(summaries: list[dict]) -> dict:
    turns = [p["turns"] for p in summaries[0]["points"]]
    K = len(summaries)
    rows, chi2, dof = [], 0.0, 0
    pooled = [{"turns": n} for n in turns]
    for c in OBS:
        for k, n in enumerate(turns):
            m = np.array([s["points"][k][c]["mean"] for s in summaries])
            e = np.array([s["points"][k][c]["sem"] for s in summaries])
            w = 1.0 / e**2
            mu = float((w * m).sum() / w.sum())
            x = float(((m - mu) ** 2 * w).sum())
            chi2 += x
            dof += K - 1
            pooled[k][c] = mu
            pooled[k][c.replace("_", "_sem_", 1)] = float(np.sqrt(1.0 / w.sum()))
            rows.append({"observable": c, "turns": n, "pooled": mu,
                         "pooled_sem": float(np.sqrt(1.0 / w.sum())), "chi2": x,
                         "scatter_sd": float(m.std(ddof=1)),
                         "rms_sem": float(np.sqrt(np.mean(e**2)))})
    sym = []
    for i, s in enumerate(summaries):
        P = {p["turns"]: p for p in s["points"]}
        for n in sorted(t for t in turns if t > 0):
            if -n not in P:
                continue
            a, b = P[n], P[-n]
            dz = a["extension_nm"]["mean"] - b["extension_nm"]["mean"]
            ez = float(np.hypot(a["extension_nm"]["sem"], b["extension_nm"]["sem"]))
            dg = a["torque_pN_nm"]["mean"] + b["torque_pN_nm"]["mean"]
            eg = float(np.hypot(a["torque_pN_nm"]["sem"], b["torque_pN_nm"]["sem"]))
            sym += [{"seed_run": i, "what": f"z(+{n:g}) - z(-{n:g})", "value": dz, "sem": ez},
                    {"seed_run": i, "what": f"G(+{n:g}) + G(-{n:g})", "value": dg, "sem": eg}]
        if 0.0 in P:
            g = P[0.0]["torque_pN_nm"]
            sym.append({"seed_run": i, "what": "G(0)", "value": g["mean"], "sem": g["sem"]})
    zs = np.array([r["value"] / r["sem"] for r in sym])
    R = int(summaries[0]["points"][0]["extension_nm"].get("n_replicas", 8))
    n_single = sum(r["what"] == "G(0)" for r in sym)
    p_t, sym_p_t = _t_model_p(chi2, K, len(rows), R, float((zs**2).sum()),
                              len(sym) - n_single, n_single)
    return {"p_chi2_t": p_t, "sym_p_t": sym_p_t, "R": R,"K": K, "rows": rows, "chi2": chi2, "dof": dof,
            "p_chi2": float(stats.chi2(dof).sf(chi2)), "symmetry": sym,
            "sym_chi2": float((zs**2).sum()), "sym_n": int(zs.size),
            "sym_p": float(stats.chi2(zs.size).sf((zs**2).sum())),
            "sym_max_abs_z": float(np.abs(zs).max()),
            "walls": [s["wall_time_s"] for s in summaries],
            "seeds": [s["seed"] for s in summaries],
            "all_converged": all(p["converged"] for s in summaries for p in s["points"]),
            "n_converged": sum(p["converged"] for s in summaries for p in s["points"]),
            "n_points": sum(len(s["points"]) for s in summaries),
            "unconverged": [f"seed {s['seed']}, n = {p['turns']:g}: {p['convergence_reason']}"
                            for s in summaries for p in s["points"] if not p["converged"]],
            "min_ess": min(v for s in summaries for p in s["points"]
                           for v in p["effective_sample_size"].values()),
            "max_rhat": max(p[c]["rhat"] for s in summaries for p in s["points"] for c in OBS),
            "pooled": pooled}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--out", default="runs/default_seeds")
    ap.add_argument("--from-runs", nargs="*", default=None, help="finished run directories")
    ap.add_argument("--table", default=str(HERE / "results" / "default_seeds.md"))
    args = ap.parse_args(argv)
    if args.from_runs:
        dirs = [pathlib.Path(d) for d in args.from_runs]
    else:
        dirs = []
        for s in range(1, args.seeds + 1):
            d = pathlib.Path(args.out) / f"s{s}"
            subprocess.run([sys.executable, "-m", "dnabraid.cli", "run", "--seed", str(s),
                            "--out", str(d), "--quiet"], check=True)
            dirs.append(d)
    summaries = [json.loads((d / "summary.json").read_text()) for d in dirs]
    r = analyse(summaries)
    sc = summaries[0]["scene"]
    lines = [f"# Independent seeds of the default braid ({time.strftime('%Y-%m-%d %H:%M')})", "",
             f"`python workflows/default_seeds.py`: `dnabraid run` (braid 2 x "
             f"{sc['length_nm']:g} nm, F = {sc['force_pN']:g} pN, {sc['replicas']} replicas x "
             f"{sc['steps']} steps per turn value) with seeds {r['seeds']}; wall "
             f"{min(r['walls']):.0f}-{max(r['walls']):.0f} s each on 2 cores. Converged: "
             f"{r['n_converged']} of {r['n_points']} points (largest R-hat "
             f"{r['max_rhat']:.3f}, smallest ESS {r['min_ess']:.0f})"
             + ("." if not r["unconverged"] else "; not: " + "; ".join(r["unconverged"])
                + "."), "",
             f"**Scatter against the reported errors:** chi^2 = {r['chi2']:.1f} on {r['dof']} "
             f"dof (reduced {r['chi2'] / r['dof']:.2f}). Each seed's SEM is the sample SEM of "
             f"{r['R']} replica means, so honest errors give a reduced value near "
             f"{(r['R'] - 1) / (r['R'] - 3):.2f}, not 1: p = {r['p_chi2_t']:.2f} under that "
             f"model (Monte Carlo), {r['p_chi2']:.3f} against a plain chi^2.",
             "",
             f"**Mirror symmetry at alpha = 0** ({r['sym_n']} values: z(+n) - z(-n), "
             f"G(+n) + G(-n), G(0) per seed): sum of z^2 = {r['sym_chi2']:.1f} on "
             f"{r['sym_n']} values (p = {r['sym_p_t']:.2f} under the same model, "
             f"{r['sym_p']:.3f} against a plain chi^2), largest |z| {r['sym_max_abs_z']:.2f}.",
             "",
             "| observable | turns | pooled mean | pooled SEM | chi^2 (dof " f"{r['K'] - 1}) | "
             "SD of seed means | rms reported SEM |", "|---|---|---|---|---|---|---|"]
    for x in r["rows"]:
        lines.append(f"| {x['observable']} | {x['turns']:+g} | {x['pooled']:.3f} | "
                     f"{x['pooled_sem']:.3f} | {x['chi2']:.1f} | {x['scatter_sd']:.3f} | "
                     f"{x['rms_sem']:.3f} |")
    lines += ["", "| seed run | symmetry check | value | SEM | z |", "|---|---|---|---|---|"]
    for x in r["symmetry"]:
        lines.append(f"| {x['seed_run']} | {x['what']} | {x['value']:+.3f} | {x['sem']:.3f} | "
                     f"{x['value'] / x['sem']:+.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    p = pathlib.Path(args.table)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    p.with_suffix(".json").write_text(json.dumps(r, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
