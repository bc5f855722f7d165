"""Continuum reference for closed braids: links n = 1..5, knots (3,2)..(9,2).

For each case at Delta/L = 0.02: the uniform closed ply, the torus helix corrected to
O(eps^2), and the relaxed (Ritz) ply of :func:`dnabraid.continuum.closed_ply.relax_closed_ply`,
with its equilibrium residuals; then the rows against the seed's slides 21 and 23.  Writes
``workflows/results/closed_continuum.md`` (and ``.json``).

Usage: python workflows/closed_continuum.py [--harmonics 2] [--diameter-over-length 0.02]
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

from dnabraid.continuum import closed_ply as cc

HERE = pathlib.Path(__file__).resolve().parent
CASES = [("link", n) for n in (1, 2, 3, 4, 5)] + [("knot", n) for n in (3, 5, 7, 9)]


def _f(v, digits=6):
    if v is None:
        return ""
    return f"{v:.{digits}g}" if isinstance(v, float) else str(v)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--harmonics", type=int, default=2)
    ap.add_argument("--diameter-over-length", type=float, default=0.02)
    ap.add_argument("--out", default=str(HERE / "results" / "closed_continuum"))
    args = ap.parse_args(argv)
    d = args.diameter_over_length
    t0 = time.perf_counter()
    cols = ["topology", "n", "theta_rad", "eta_rad", "relaxed_eta_min_rad",
            "relaxed_eta_max_rad", "pressure_uniform_B_per_L3", "pressure_mean_B_per_L3",
            "relaxed_pressure_mean_B_per_L3", "relaxed_pressure_min_B_per_L3",
            "relaxed_pressure_max_B_per_L3", "relaxed_contact_curvature_min_per_L",
            "relaxed_contact_curvature_max_per_L", "relaxed_pressure_harmonic",
            "relaxed_eta_harmonic", "writhe_per_ring_fuller", "relaxed_out_of_plane_rel",
            "relaxed_newton3_rel"]
    lines = [f"# Closed two-ply, continuum reference (Delta/L = {d:g}, "
             f"{args.harmonics} harmonics), {time.strftime('%Y-%m-%d %H:%M')}", "",
             "Units: pressure B/L^3 (per unit length of strand 1), angles rad, curvature 1/L. "
             "`pressure_mean` is the torus helix's (O(eps^2)); `relaxed_*` the Ritz "
             "equilibrium; residuals are relative to the mean pressure (meaningless for the "
             "Hopf link, whose pressure is 0). Harmonics: dominant periods along a link's "
             "ring / a knot's whole ring.", "",
             " | ".join(cols), " | ".join("---" for _ in cols)]
    everything = {"cases": [], "seed": []}
    for topology, n in CASES:
        res = cc.closed_ply(n, d, topology, harmonics=args.harmonics)
        v = res.values
        everything["cases"].append(res.to_dict())
        lines.append(" | ".join(_f(v.get(c)) for c in cols))
        print(lines[-1], flush=True)
    if abs(d - 0.02) < 1e-12:
        rows = cc.seed_comparison_table(harmonics=args.harmonics)
        everything["seed"] = rows
        keys = ["case", "quantity", "unit", "uniform", "corrected", "relaxed", "seed", "slide"]
        lines += ["", "## Against the seed (slides 21, 23; seed = plot axis range ends)", "",
                  " | ".join(keys), " | ".join("---" for _ in keys)]
        for r in rows:
            lines.append(" | ".join(_f(r[k]) for k in keys))
    lines += ["", f"wall time {time.perf_counter() - t0:.1f} s"]
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    out.with_suffix(".json").write_text(json.dumps(everything, indent=1, default=str))
    print(f"written {out.with_suffix('.md')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
