"""Bead-spacing convergence of the ``closed`` scene's defaults (how its default
``spacing_over_radius`` = b/h, h = Delta/2, was chosen).

Runs the scene exactly as ``dnabraid run closed --set spacing_over_radius=B`` (the default
4-link) and ``dnabraid run closed --set topology=knot --set n=5 --set spacing_over_radius=B``
(the pentafoil) for B = 0.5, 0.25, 0.125 (and 0.0625 with --finest), all other keys at their
defaults, and tabulates eta, p (mean, min, max), the contact curve's curvature (knots only:
the scene measures it for knots), Lk / writhe, the contact lost and the wall time, with the
relative change of eta, p_mean and kappa_c against the next finer spacing.

Results: workflows/results/closed_spacing.md (+ closed_spacing.json; finished cases are kept
and not run again unless --fresh).

Usage: python workflows/closed_spacing.py [--finest] [--fresh] [--only link|knot]
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import tempfile
import time

from dnabraid import scenes as scn

HERE = pathlib.Path(__file__).resolve().parent
OUT = HERE / "results" / "closed_spacing.md"
CASES = {"link": {}, "knot": {"topology": "knot", "n": 5}}
SPACINGS = (0.5, 0.25, 0.125)
FINEST = 0.0625
#: the criterion: eta, p_mean and kappa_c change by less than this against the next finer b
TOL = 0.01


def cli(over: dict, b: float) -> str:
    sets = "".join(f" --set {k}={v}" for k, v in over.items())
    return f"dnabraid run closed{sets} --set spacing_over_radius={b:g}"


def run_case(over: dict, b: float) -> dict:
    scene = scn.make_scene("closed", {**over, "spacing_over_radius": b})
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        s = scene.run(os.path.join(tmp, "run"))
        wall = time.perf_counter() - t0
    m = s["measured"]
    keys = ("eta_mean", "eta_min", "eta_max", "pressure_mean", "pressure_min", "pressure_max",
            "contact_lost_fraction", "contact_curvature_mean", "contact_curvature_min",
            "contact_curvature_max", "linking_number", "writhe_per_ring",
            "energy_over_B_per_L", "max_overlap_over_diameter")
    row = {k: m.get(k) for k in keys}
    row.update(b_over_h=b, beads=s["beads"], iterations=s["newton_iterations"],
               converged=s["converged"], max_force_pN=s["max_force_pN"],
               saddle_escapes=s["saddle_escapes"], wall_time_s=s["wall_time_s"], wall_total_s=wall,
               command=cli(over, b))
    return row


def _rel(a, b):
    return None if a is None or b is None else abs(a - b) / abs(b)


def _pct(v):
    return "-" if v is None else f"{100 * v:.2f}"


def changes(rows: list) -> list:
    """Relative change of (eta_mean, p_mean, kappa_c mean, kappa_c min, kappa_c max) of each
    row against the next finer row (None for the finest)."""
    out = []
    for i, r in enumerate(rows):
        f = rows[i + 1] if i + 1 < len(rows) else None
        out.append({k: (_rel(r[k], f[k]) if f else None)
                    for k in ("eta_mean", "pressure_mean", "contact_curvature_mean",
                              "contact_curvature_min", "contact_curvature_max")})
    return out


def _unconverged(r: dict) -> str:
    f = r.get("max_force_pN")
    return " (not converged" + ("" if f is None else f": largest force left {f:.2g} pN") + ")"


def passes(r: dict, d: dict, knot: bool) -> bool:
    ks = ["eta_mean", "pressure_mean"] + (["contact_curvature_mean", "contact_curvature_min",
                                            "contact_curvature_max"] if knot else [])
    return all(d[k] is not None and d[k] < TOL for k in ks) and r["pressure_min"] > 0


def write_md(data: dict) -> None:
    L = [f"# closed scene: bead-spacing convergence of the defaults, "
         f"{time.strftime('%Y-%m-%d %H:%M')}", "",
         "Scene `closed` (dnabraid/scenes/closed.py on dnabraid/statics/closed_braid.py), all "
         "keys at their defaults (Delta/L = 0.02, segment contact, start noise 0.02 Delta, "
         "seed 1) except `spacing_over_radius` = b/h (h = Delta/2). p in B/L^3 (min/max of p "
         "smoothed over ~Delta of strand), eta in rad, kappa_c (curvature of the contact "
         "curve, measured for knots only) in 1/L. d = relative change against the next finer "
         "b/h, in %. Wall: the scene's own time (relaxation + output), on a shared 2-core "
         "machine (varies ~2-3x with its load).", "",
         "Reproduce: `python workflows/closed_spacing.py` (add `--finest` for b/h = 0.0625), "
         "or one row with the command in its last column.", ""]
    verdicts, chosen = [], {}
    for name, title in (("link", "default 4-link (Lk = -4)"),
                        ("knot", "pentafoil (5, 2): `--set topology=knot --set n=5`")):
        rows = sorted(data.get(name, {}).values(), key=lambda r: -r["b_over_h"])
        if not rows:
            continue
        knot = name == "knot"
        L += [f"## {title}", "",
              "| b/h | beads | eta mean (min-max) | p mean | p min-max | contact lost | "
              "kappa_c mean (min-max) | " + ("Wr" if knot else "Lk / Wr ring 1") +
              " | E (B/L) | Newton it | d eta | d p mean | d kappa_c mean (min, max) | "
              "wall (s) | command |", "|" + "---|" * 15]
        for r, d in zip(rows, changes(rows)):
            kc = ("-" if r["contact_curvature_mean"] is None else
                  f"{r['contact_curvature_mean']:.4f} ({r['contact_curvature_min']:.3f}-"
                  f"{r['contact_curvature_max']:.3f})")
            lw = (f"{r['writhe_per_ring'][0]:+.5f}" if knot else
                  f"{r['linking_number']:+.4f} / {r['writhe_per_ring'][0]:+.5f}")
            dk = ("-" if not knot else f"{_pct(d['contact_curvature_mean'])} "
                  f"({_pct(d['contact_curvature_min'])}, {_pct(d['contact_curvature_max'])})")
            L.append(
                f"| {r['b_over_h']:g} | {r['beads']} | {r['eta_mean']:.5f} ({r['eta_min']:.5f}-"
                f"{r['eta_max']:.5f}) | {r['pressure_mean']:.1f} | {r['pressure_min']:.1f}-"
                f"{r['pressure_max']:.1f} | {r['contact_lost_fraction']:.3f} | {kc} | {lw} | "
                f"{r['energy_over_B_per_L']:.4f} | {r['iterations']}"
                f"{'' if r['converged'] else _unconverged(r)} | {_pct(d['eta_mean'])} | "
                f"{_pct(d['pressure_mean'])} | {dk} | {r['wall_time_s']:.0f} | "
                f"`{r['command']}` |")
        ok = [r["b_over_h"] for r, d in zip(rows, changes(rows)) if passes(r, d, knot)]
        verdicts.append(
            f"* {title.split(':')[0]}: coarsest b/h with eta, p_mean"
            + (", kappa_c (mean, min, max)" if knot else "")
            + f" within {100 * TOL:g} % of the next finer one and p_min > 0: "
            + (f"{max(ok):g}" if ok else "none in the table")
            + "; contact lost (p_min = 0) at b/h = "
            + (", ".join(f"{r['b_over_h']:g}" for r in rows if r["pressure_min"] <= 0)
               or "none") + ".")
        L.append("")
        chosen[name] = (max(ok) if ok else None, rows)
    if chosen and all(c[0] is not None for c in chosen.values()):
        b = min(c[0] for c in chosen.values())
        verdicts.append(f"* both: default spacing_over_radius = {b:g} (the finer of the two).")
        for name, (_, rows) in chosen.items():
            i = [r["b_over_h"] for r in rows].index(b)
            if i + 1 < len(rows):
                r, f = rows[i], rows[i + 1]
                verdicts.append(
                    f"* {name} at b/h = {b:g} against {f['b_over_h']:g}: the smoothed extremes "
                    f"converge more slowly than the means: p_min {r['pressure_min']:.0f} vs "
                    f"{f['pressure_min']:.0f} ({100 * (r['pressure_min'] / f['pressure_min'] - 1):+.1f} %), "
                    f"p_max {r['pressure_max']:.0f} vs {f['pressure_max']:.0f} "
                    f"({100 * (r['pressure_max'] / f['pressure_max'] - 1):+.1f} %).")
    bad = [f"{n} b/h = {r['b_over_h']:g} (largest force left {r.get('max_force_pN', float('nan')):.2g} pN)"
           for n, c in chosen.items() for r in c[1] if not r["converged"]]
    if bad:
        verdicts.append("* Newton stopped on a stall before its force tolerance (1e-6 of the "
                        "contact force per bead) in: " + ", ".join(bad) + " (compare its row "
                        "with the neighbouring spacings).")
    L += ["## Verdict (generated from the rows above)", ""] + verdicts
    OUT.write_text("\n".join(L) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--finest", action="store_true", help=f"also b/h = {FINEST}")
    ap.add_argument("--fresh", action="store_true", help="ignore finished cases")
    ap.add_argument("--only", choices=tuple(CASES), help="one of the two cases")
    args = ap.parse_args(argv)
    js = OUT.with_suffix(".json")
    data = {} if args.fresh or not js.exists() else json.loads(js.read_text())
    spacings = SPACINGS + ((FINEST,) if args.finest else ())
    for name, over in CASES.items():
        if args.only and name != args.only:
            continue
        for b in spacings:
            key = f"{b:g}"
            if key in data.get(name, {}):
                continue
            r = run_case(over, b)
            data.setdefault(name, {})[key] = r
            print(f"{name} b/h = {b:g}: {r['wall_time_s']:.0f} s, p_min {r['pressure_min']:.1f}",
                  flush=True)
            js.write_text(json.dumps(data, indent=1, default=float))
            write_md(data)
    write_md(data)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
