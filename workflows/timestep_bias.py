"""Time-step bias of a scene's reported observables: the default step against half of it.

For a scene (its defaults plus ``--set`` overrides) the run is repeated with
``timestep_safety`` halved, every step count (``steps``, ``equilibration_steps``) doubled
and the sampling intervals (``report_interval``, ``frame_interval``) doubled, so both runs
cover the same physical time with the same number of samples and the same seeds. For every
reported observable of every point the table gives the two means, their difference with
its standard error (the two runs' SEMs in quadrature) and the difference over the default
run's SEM: the default step is good enough when |bias| < SEM / 3 (the bias of
Euler-Maruyama is first order in dt, so the difference estimates the default's bias).

    python workflows/timestep_bias.py braid
    python workflows/timestep_bias.py tether --set surface=false --set self_avoidance=false

With ``--reference`` the half-step run is compared instead with a stored study of the
default over independent seeds (``workflows/default_seeds.py`` writes one): the scene is run
at half the safety with the same step counts (equilibrium averages do not depend on the
physical time covered) for each of ``--seeds``, pooled, and each row gets a verdict that can
fail: ``bound holds`` (|bias| + 2 SE(bias) < SE_run / 3, SE_run the rms SEM of one default
run), ``bias exceeds the bound`` (|bias| - 2 SE(bias) > SE_run / 3) or ``undecided``.

    python workflows/timestep_bias.py braid --reference workflows/results/default_seeds.json \
        --seeds 11 12

With ``--mala SAFETY`` the comparison runs are instead Metropolis-adjusted
(``integrator = mala`` at ``timestep_safety = SAFETY``), which have no time-step bias at
all: bias = m(default) - m(mala) is then the default's whole bias, not a first-order
estimate of it.

    python workflows/timestep_bias.py braid --reference workflows/results/default_seeds.json \
        --mala 0.3 --seeds 21 22 --out workflows/results/timestep_bias_braid_mala.md

Writes ``workflows/results/timestep_bias_<scene>.md`` (or ``--out``) and keeps the two run
directories (``--runs``, resumed when run again).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import time

import numpy as np

from dnabraid.scenes import make_scene, parse_value

HERE = os.path.dirname(os.path.abspath(__file__))
OBS = ("extension_nm", "torque_pN_nm")


def halved(scene) -> dict:
    """The overrides of the half-step run: same physical time and samples, half the step."""
    return {"timestep_safety": scene.timestep_safety / 2, "steps": 2 * scene.steps,
            "equilibration_steps": 2 * scene.equilibration_steps,
            "report_interval": 2 * scene.report_interval,
            "frame_interval": 2 * scene.frame_interval}


def compare(full: dict, half: dict) -> list[dict]:
    """One row per point and reported column: the means at dt and dt/2, the difference
    and its error, and the difference in units of the default run's SEM."""
    rows = []
    cols = [k for k, c in full["columns"].items() if c.get("reported")]
    if not cols:  # a scene that marks no column reported (the catenane): every averaged one
        cols = [k for k, v in full["points"][0].items()
                if isinstance(v, dict) and "mean" in v and "sem" in v]
    for p, q in zip(full["points"], half["points"]):
        for c in cols:
            a, b = p.get(c) or {}, q.get(c) or {}
            if a.get("mean") is None or b.get("mean") is None:
                continue
            diff = a["mean"] - b["mean"]
            err = math.hypot(a["sem"], b["sem"])
            rows.append({"point": p.get("label", ""), "column": c, "dt": a["mean"],
                         "dt_sem": a["sem"], "dt_half": b["mean"], "dt_half_sem": b["sem"],
                         "bias": diff, "bias_err": err,
                         "bias_over_sem": diff / a["sem"] if a["sem"] else math.nan,
                         "converged": bool(p["converged"] and q["converged"])})
    return rows


def pool(summaries: list[dict]) -> dict:
    """{(observable, turns): (mean, SE, rms SEM)} over the runs, weighted equally: each run
    has the same design, and its SEM (from 4 replica means) is too noisy to weight by (an
    inverse-variance pool leans on the runs whose replicas agreed by chance; measured:
    one run's SEM of 0.023 nm where its points' quarter means scatter by 0.7 nm)."""
    out = {}
    for c in OBS:
        for k, p0 in enumerate(summaries[0]["points"]):
            m = np.array([s["points"][k][c]["mean"] for s in summaries])
            e = np.array([s["points"][k][c]["sem"] for s in summaries])
            out[(c, float(p0["turns"]))] = (float(m.mean()),
                                            float(np.sqrt((e**2).sum()) / len(e)),
                                            float(np.sqrt(np.mean(e**2))))
    return out


def compare_pooled(summaries: list[dict], ref: dict) -> list[dict]:
    """Rows of bias = m(default) - m(half step) against the stored default pool."""
    half = pool(summaries)
    rows = []
    for r in ref["rows"]:
        key = (r["observable"], float(r["turns"]))
        if key not in half:
            continue
        mh, eh, _ = half[key]
        bias = r["pooled"] - mh
        # the stored reference is an inverse-variance pool; its error is taken as the larger
        # of its own and the equal-weight one, rms SEM / sqrt(seeds)
        e_ref = max(r["pooled_sem"], r["rms_sem"] / np.sqrt(ref.get("K", 1)))
        se = float(np.hypot(e_ref, eh))
        bound = r["rms_sem"] / 3.0
        if abs(bias) + 2 * se < bound:
            verdict = "bound holds"
        elif abs(bias) - 2 * se > bound:
            verdict = "bias exceeds the bound"
        else:
            verdict = "undecided"
        rows.append({"observable": key[0], "turns": key[1], "default": r["pooled"],
                     "default_sem": e_ref, "half": mh, "half_sem": eh,
                     "bias": bias, "bias_sem": se, "z": bias / se, "se_run": r["rms_sem"],
                     "bound": bound, "verdict": verdict})
    return rows


def write_pooled(rows, summaries, safety, path: pathlib.Path, cmd: str,
                 mala: bool = False) -> None:
    conv = sum(p["converged"] for s in summaries for p in s["points"])
    npts = sum(len(s["points"]) for s in summaries)
    walls = [s["wall_time_s"] for s in summaries]
    z2 = float(sum(r["z"] ** 2 for r in rows))
    what = (f"the default scene with Metropolis-adjusted steps (integrator = mala, no "
            f"time-step bias at any step; acceptance {_mala_range(summaries)}) at "
            f"timestep_safety = {safety:g}" if mala else
            f"the default scene at timestep_safety = {safety:g} (the default is "
            f"{2 * safety:g})")
    other = "mala" if mala else "half step"
    lines = [f"# Time-step bias of the default braid ({time.strftime('%Y-%m-%d %H:%M')})", "",
             f"`{cmd}`: {what} for seeds {[s['seed'] for s in summaries]}, "
             f"{summaries[0]['points'][0]['extension_nm'].get('n_replicas')} replicas each, "
             f"wall {min(walls):.0f}-{max(walls):.0f} s per run; {conv} of {npts} points "
             "converged. Compared with the pooled six seeds of the default "
             "(`default_seeds.json`; its error the larger of the pooled SEM and rms SEM / "
             f"sqrt(6)); the {other} runs weighted equally. bias = m(default step) - "
             f"m({other}); SE_run = the rms SEM "
             "of one default run; the bound is SE_run / 3 (issue 21, item 4). "
             + ("The mala runs are unbiased, so the difference is the default's whole bias."
                if mala else "Euler-Maruyama is first order, so the true bias at the default "
                "step may be up to twice the measured difference."), "",
             f"Sum of z^2 over the {len(rows)} rows: {z2:.1f} (rows are independent "
             "between points, not between the two observables of a point).", "",
             f"| observable | turns | default (6 seeds) | {other} | bias | SE(bias) | z "
             "| SE_run / 3 | verdict |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['observable']} | {r['turns']:+g} | {r['default']:.3f} +- "
                     f"{r['default_sem']:.3f} | {r['half']:.3f} +- {r['half_sem']:.3f} | "
                     f"{r['bias']:+.3f} | {r['bias_sem']:.3f} | {r['z']:+.2f} | "
                     f"{r['bound']:.3f} | {r['verdict']} |")
    path.with_suffix(".md").write_text("\n".join(lines) + "\n")
    path.with_suffix(".json").write_text(json.dumps(
        {"safety": safety, "integrator": "mala" if mala else None,
         "seeds": [s["seed"] for s in summaries], "walls": walls,
         "n_converged": conv, "n_points": npts, "sum_z2": z2, "rows": rows}, indent=1))


def _mala_range(summaries) -> str:
    acc = [p["mala"]["acceptance"] for s in summaries for p in s["points"] if p.get("mala")]
    return f"{min(acc):.2f}-{max(acc):.2f}" if acc else "-"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--runs", default=None, help="directory of the two runs")
    ap.add_argument("--out", default=None, help="the table (markdown)")
    ap.add_argument("--reference", default=None,
                    help="a stored seed study of the default (default_seeds.json)")
    ap.add_argument("--seeds", type=int, nargs="*", default=[11, 12],
                    help="seeds of the half-step runs (with --reference)")
    ap.add_argument("--mala", type=float, default=None, metavar="SAFETY",
                    help="with --reference: compare with Metropolis-adjusted runs "
                         "(integrator = mala) at this timestep_safety instead of half steps")
    a = ap.parse_args(argv)
    over = {k: parse_value(v) for k, v in (x.split("=", 1) for x in a.set)}
    s = make_scene(a.scene, over)
    if a.reference:
        return pooled_main(a, over, s)
    s2 = make_scene(a.scene, {**over, **halved(s)})
    runs = a.runs or os.path.join(HERE, "results", f"timestep_bias_{a.scene}_runs")
    full = s.run(os.path.join(runs, "dt"))
    half = s2.run(os.path.join(runs, "dt_half"))
    rows = compare(full, half)
    lines = [f"# Time-step bias: `{a.scene}` {' '.join('--set ' + x for x in a.set)}",
             "",
             f"dt = {full['time_step_ps']:.4g} ps (timestep_safety {s.timestep_safety}) "
             f"against dt/2 = {half['time_step_ps']:.4g} ps, same physical time and samples; "
             f"wall {full['wall_time_s']:.0f} s + {half['wall_time_s']:.0f} s. "
             f"`python workflows/timestep_bias.py {a.scene} "
             f"{' '.join('--set ' + x for x in a.set)}`",
             "",
             "| point | observable | at dt | at dt/2 | bias (dt - dt/2) | bias / SEM(dt) | "
             "converged |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['point']} | {r['column']} | {r['dt']:.4g} +- {r['dt_sem']:.2g} | "
                     f"{r['dt_half']:.4g} +- {r['dt_half_sem']:.2g} | {r['bias']:+.3g} +- "
                     f"{r['bias_err']:.2g} | {r['bias_over_sem']:+.2f} | {r['converged']} |")
    ok = [r for r in rows if r["dt_sem"] > 0]
    worst = max((abs(r["bias_over_sem"]) for r in ok), default=math.nan)
    ratio = (sorted(r["bias_err"] / r["dt_sem"] for r in ok)[len(ok) // 2] if ok
             else math.nan)
    zmax = max((abs(r["bias"]) / r["bias_err"] for r in ok if r["bias_err"] > 0),
               default=math.nan)
    lines += ["", f"largest |bias| / SEM(dt): {worst:.2f}; largest |bias| / its own error: "
              f"{zmax:.2f}. The criterion |bias| < SEM / 3 can be shown only where the "
              f"difference's own error is well below SEM / 3; here it is (median) {ratio:.2f} x "
              "SEM, so this table bounds the bias at about 2 x that error, no tighter."]
    text = "\n".join(lines) + "\n"
    print(text)
    out = a.out or os.path.join(HERE, "results", f"timestep_bias_{a.scene}.md")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as fh:
        fh.write(text)
    return rows


def pooled_main(a, over, s):
    """Half-step runs of several seeds against a stored seed study of the default."""
    runs = a.runs or os.path.join(HERE, "results", f"timestep_bias_{a.scene}_runs")
    mala = a.mala is not None
    safety = a.mala if mala else s.timestep_safety / 2
    extra = {"integrator": "mala"} if mala else {}
    summaries = []
    for seed in a.seeds:
        print(f"seed {seed}: timestep_safety {safety:g} {extra}", flush=True)
        sc = make_scene(a.scene, {**over, **extra, "timestep_safety": safety, "seed": seed})
        name = f"mala{safety:g}_s{seed}" if mala else f"half_s{seed}"
        summaries.append(sc.run(os.path.join(runs, name)))
    ref = json.loads(pathlib.Path(a.reference).read_text())
    rows = compare_pooled(summaries, ref)
    out = a.out or os.path.join(HERE, "results", f"timestep_bias_{a.scene}.md")
    cmd = (f"python workflows/timestep_bias.py {a.scene} --reference "
           f"{os.path.relpath(a.reference)} " + (f"--mala {a.mala:g} " if mala else "")
           + f"--seeds {' '.join(map(str, a.seeds))}")
    write_pooled(rows, summaries, safety, pathlib.Path(out), cmd, mala=mala)
    print(pathlib.Path(out).with_suffix(".md").read_text())
    return rows


if __name__ == "__main__":
    main()
