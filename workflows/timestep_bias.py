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

Writes ``workflows/results/timestep_bias_<scene>.md`` (or ``--out``) and keeps the two run
directories (``--runs``, resumed when run again).
"""

from __future__ import annotations

import argparse
import math
import os

from dnabraid.scenes import make_scene, parse_value

HERE = os.path.dirname(os.path.abspath(__file__))


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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--runs", default=None, help="directory of the two runs")
    ap.add_argument("--out", default=None, help="the table (markdown)")
    a = ap.parse_args(argv)
    over = {k: parse_value(v) for k, v in (x.split("=", 1) for x in a.set)}
    s = make_scene(a.scene, over)
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


if __name__ == "__main__":
    main()
