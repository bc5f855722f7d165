"""Error against run time (work-precision) for the bead model's cross-checks.

A. Zero-temperature braid vs the continuum tweezer braid (dnabraid.validation.crosscheck): the default
   braid geometry (2 x 200 nm, tethers 40 nm, F = 2 pN, n = 2), bead spacing b = 5, 4, 2.5,
   2 nm; error = relative difference of extension and of torque from the continuum at the
   bead model's own contact distance.
B. Thermal tether vs the exact discrete worm-like chain (dnabraid.continuum.wlc, transfer
   matrix, stretching included): F = 3 pN, L = 25 nm, no wall and no excluded volume (the
   exact answer's own model); time step (timestep_safety 0.1 ... 0.9 of the Euler-Maruyama
   limit) x sampling length, 4 replicas from exact equilibrium draws run one after another in
   this process; error = |<z> - exact| / exact, with the SEM across replicas beside it.

C. Thermal default braid (since 2026-12-06: 2 x 100 nm, 2 pN, turns -1 ... 1 in half turns,
   4 replicas, 3000 moves per report interval) at 1e4 ... 1e5 sampling steps, against the pooled means of independent seeds
   of the default scene (``--reference``, written by workflows/default_seeds.py: no exact
   answer exists); error = the largest relative torque deviation over n != 0 (the torque is
   the observable that costs), the extension's beside it. The rows of the old default (2 x 60
   nm, 20 pN, 8 replicas x 5e4 ... 3.5e5 steps, Brownian dynamics alone) are kept in
   results/convergence_braid_toy.md.

Writes workflows/results/convergence.md and convergence.png (error against wall time) and
names the cheapest settings that reach 1 %, 5 % and 10 %.

Usage: taskset -c 0 python workflows/convergence.py [--quick] [--parts A|B|AB] [--out PATH]
(workflows/results/convergence.md: part A of 2026-11-22; convergence_tether.md: part B redone
2026-11-30 with replicas from exact starts)
"""

from __future__ import annotations

import argparse
import pathlib
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent


def part_a(spacings):
    from dnabraid.validation.crosscheck import compare_tweezer

    rows = []
    for b in spacings:
        t0 = time.perf_counter()
        r = compare_tweezer(2.0, 0.0, {"bead_spacing_nm": b})
        p = r["plus"]
        ez = abs(p["bead_extension_nm"] - p["continuum_extension_nm"]) / p["continuum_extension_nm"]
        eg = abs(p["bead_torque_pN_nm"] - p["continuum_torque_pN_nm"]) / abs(p["continuum_torque_pN_nm"])
        rows.append({"check": "zeroT braid vs continuum", "setting": f"b={b} nm",
                     "error_extension": ez, "error_torque": eg, "error": max(ez, eg),
                     "sem_rel": 0.0, "wall_time_s": time.perf_counter() - t0,
                     "detail": f"z {p['bead_extension_nm']:.2f}/{p['continuum_extension_nm']:.2f} nm, "
                               f"G {p['bead_torque_pN_nm']:.2f}/{p['continuum_torque_pN_nm']:.2f} pN nm, "
                               f"contact {r['contact_nm']:.2f} nm"})
        print(rows[-1], flush=True)
    return rows


def part_b(safeties, steps_list, replicas=4):
    """Tether without wall and excluded volume (the exact discrete WLC's own model), R
    replicas from exact equilibrium draws, serial in this process; error against the exact
    transfer-matrix mean, the reported error the Student-t interval across replicas."""
    from dnabraid.continuum.wlc import discrete_wlc_exact
    from dnabraid.scenes import make_scene

    rows = []
    for sf in safeties:
        for steps in steps_list:
            s = make_scene("tether", {"force_pN": 3.0, "length_nm": 25.0, "steps": steps,
                                      "equilibration_steps": 0, "surface": False,
                                      "self_avoidance": False, "seed": 7,
                                      "frame_interval": 10_000, "timestep_safety": sf,
                                      "replicas": replicas, "workers": 1})
            m = s.build()
            p = m.params
            theory = discrete_wlc_exact(s.force_pN, s.n_beads - 1, s.bead_spacing_nm,
                                        p["kappa_kT"], p["kT_pN_nm"],
                                        stretch_k_pN_per_nm=p["k_bond_pN_per_nm"])["extension_nm"]
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                pt = s.run(tmp, threads=1)["points"][0]
                wall = time.perf_counter() - t0
            ext = pt["extension_nm"]
            covered = abs(ext["mean"] - theory) <= ext["ci_halfwidth"]
            rows.append({"check": "tether vs exact discrete WLC",
                         "setting": f"safety={sf}, {replicas} x {steps} steps",
                         "error": abs(ext["mean"] - theory) / theory, "sem_rel": ext["sem"] / theory,
                         "wall_time_s": wall,
                         "detail": f"<z> {ext['mean']:.3f}+-{ext['sem']:.3f} vs {theory:.3f} nm "
                                   f"({'covered' if covered else 'NOT covered'} by the 95% "
                                   f"interval), dt {m.timestep.time_step_ns * 1e3:.3g} ps, "
                                   f"{'converged' if pt['converged'] else 'NOT CONVERGED'}"})
            print(rows[-1], flush=True)
    return rows


def part_c(steps_list, reference: str, replicas=None, seed=11):
    """The default braid at several run lengths against the pooled seeds' reference
    (``replicas``: None = the scene's default)."""
    import json

    from dnabraid.scenes import make_scene

    ref = {p["turns"]: p for p in json.loads(pathlib.Path(reference).read_text())["pooled"]}
    rows = []
    for k, steps in enumerate(steps_list):
        # a seed per row: rows of one seed would share their start and random prefix
        over = {"steps": steps, "seed": seed + k}
        if replicas:
            over["replicas"] = replicas
        s = make_scene("braid", over)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            summ = s.run(tmp)
            wall = time.perf_counter() - t0
        eg, sg, ez, sz = [], [], [], []
        for pt in summ["points"]:
            r = ref[pt["turns"]]
            z, g = pt["extension_nm"], pt["torque_pN_nm"]
            ez.append(abs(z["mean"] - r["extension_nm"]) / r["extension_nm"])
            sz.append(z["sem"] / r["extension_nm"])
            if pt["turns"] != 0.0:
                eg.append(abs(g["mean"] - r["torque_pN_nm"]) / abs(r["torque_pN_nm"]))
                sg.append(g["sem"] / abs(r["torque_pN_nm"]))
        conv = sum(pt["converged"] for pt in summ["points"])
        rows.append({"check": "default braid vs pooled seeds", "setting":
                     f"{s.replicas} x {steps} steps, seed {seed + k}", "error": max(eg),
                     "sem_rel": max(sg),
                     "wall_time_s": wall,
                     "detail": f"extension: error {max(ez):.2g}, SEM {max(sz):.2g}; "
                               f"{conv}/{len(summ['points'])} points converged"})
        print(rows[-1], flush=True)
    return rows


def cheapest(rows, level):
    """Cheapest row whose error and 2 x SEM both stay below ``level``."""
    ok = [r for r in rows if r["error"] + 2 * r["sem_rel"] < level]
    return min(ok, key=lambda r: r["wall_time_s"]) if ok else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer settings (a few minutes)")
    ap.add_argument("--out", default=str(HERE / "results" / "convergence"))
    ap.add_argument("--parts", default="AB", help="which checks to run (A, B, C or a mix)")
    ap.add_argument("--reference", default=str(HERE / "results" / "default_seeds.json"),
                    help="pooled seeds of the default braid (part C)")
    args = ap.parse_args(argv)
    spac = [5.0, 2.5] if args.quick else [5.0, 4.0, 2.5, 2.0]
    saf = [0.3, 0.9] if args.quick else [0.1, 0.3, 0.6, 0.9]
    stp = [25_000, 100_000] if args.quick else [12_500, 50_000, 200_000]
    checks = {}
    if "A" in args.parts:
        checks["A"] = part_a(spac)
    if "B" in args.parts:
        checks["B"] = part_b(saf, stp)
    if "C" in args.parts:
        # the default since 2026-12-06: 4 replicas x 5e4 steps with moves (the toy default's
        # rows, 8 x 5e4 ... 3.5e5 steps, are in results/convergence_braid_toy.md)
        checks["C"] = part_c([10_000, 50_000] if args.quick
                             else [10_000, 25_000, 50_000, 100_000], args.reference)
    lines = [f"# work-precision, {time.strftime('%Y-%m-%d %H:%M')}", ""]
    for name, rows in checks.items():
        lines += [f"## {rows[0]['check']}", "",
                  "| setting | error | 2 SEM (rel) | wall (s) | detail |", "|---|---|---|---|---|"]
        lines += [f"| {r['setting']} | {r['error']:.3g} | {2 * r['sem_rel']:.2g} | "
                  f"{r['wall_time_s']:.1f} | {r['detail']} |" for r in rows]
        lines.append("")
        for lvl in (0.01, 0.05, 0.10):
            c = cheapest(rows, lvl)
            lines.append(f"- cheapest reaching {lvl:.0%}: "
                         + (f"{c['setting']} ({c['wall_time_s']:.1f} s)" if c else "none tried"))
        lines.append("")
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4))
    ax = fig.subplots()
    for name, rows in checks.items():
        ax.errorbar([r["wall_time_s"] for r in rows], [r["error"] for r in rows],
                    yerr=[2 * r["sem_rel"] for r in rows], fmt="o", label=rows[0]["check"])
    for lvl in (0.01, 0.05, 0.10):
        ax.axhline(lvl, color="0.8", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("relative error")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=120)
    print(f"written {out.with_suffix('.md')} and .png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
