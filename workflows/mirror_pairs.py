"""Handedness asymmetry from mirror-coupled replica pairs against the plain estimator.

For each alpha, two runs with one seed: ``mirror = "original"`` at turns +n and
``mirror = "image"`` at -n (the image starts from and is driven by the y -> -y mirror of the
original's start and noise; dnabraid.analysis.mirror). The paired estimator of
z(+n) - z(-n) and Gamma(+n) + Gamma(-n) is the mean of the per-replica differences with
their standard error; the plain estimator combines the two runs' own across-replica errors
in quadrature (what independent runs at +n and -n would give). At alpha = 0 the pair is an
exact mirror: the paired asymmetry must vanish to round-off.

Usage: python workflows/mirror_pairs.py [--alpha 0 1 3 6] [--replicas 4] [--steps 60000]
       [--mc-moves 2500 --contact capsules --equilibration 10000 --length 200
        --separation 40 --table workflows/results/mirror_pairs_long.md]
Writes workflows/results/mirror_pairs.md (and .json).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

from dnabraid.analysis.mirror import paired_asymmetry
from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent


def run_pair(alpha: float, n: float, args) -> dict:
    fixed = {"force_pN": args.force, "length_nm": args.length,
             "tether_separation_nm": args.separation,
             "steps": args.steps, "equilibration_steps": args.steps // 4,
             "frame_interval": 10_000, "replicas": args.replicas, "seed": args.seed,
             "alpha": alpha, "workers": args.workers}
    # always given: the braid's default has moves since 2026-12-06, so 0 must be said
    fixed["mc_moves"] = args.mc_moves
    if args.trap_stiffness:
        fixed["trap_stiffness_pN_nm"] = args.trap_stiffness
    if args.contact != "beads":
        fixed["contact"] = args.contact
    if args.equilibration:
        fixed["equilibration_steps"] = args.equilibration
    if args.safety:
        fixed["timestep_safety"] = args.safety
    out = {}
    wall = 0.0
    for mode, turns in (("original", [n]), ("image", [-n])):
        sc = make_scene("braid", dict(fixed, mirror=mode, turns=turns))
        d = pathlib.Path(args.out) / f"alpha{alpha:g}_{mode}"
        t0 = time.perf_counter()
        sc.run(str(d))
        wall += time.perf_counter() - t0
        out[mode] = json.loads((d / "summary.json").read_text())
    rows = {c: paired_asymmetry(out["original"], out["image"], c)[0]
            for c in ("extension_nm", "torque_pN_nm")}
    conv = all(p["converged"] for s in out.values() for p in s["points"])
    return {"alpha_pN": alpha, "turns": n, "wall_s": wall, "converged": conv, **rows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--alpha", type=float, nargs="+", default=[0.0, 1.0, 3.0, 6.0])
    ap.add_argument("--turns", type=float, default=2.0)
    ap.add_argument("--length", type=float, default=150.0, help="strand length (nm)")
    ap.add_argument("--force", type=float, default=2.0, help="pulling force (pN)")
    ap.add_argument("--separation", type=float, default=30.0, help="tether separation (nm)")
    ap.add_argument("--safety", type=float, default=0.0,
                    help="timestep_safety (0: the braid's default, 0.6 since 2026-12-01; "
                         "mirror_pairs.md of 2026-11-30 ran at 0.3)")
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--steps", type=int, default=60_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=0)
    ap.add_argument("--mc-moves", type=int, default=0,
                    help="compiled Metropolis moves per report interval (0: Brownian dynamics "
                         "alone); the image draws the mirrored moves (mirror_random)")
    ap.add_argument("--trap-stiffness", type=float, default=0.0,
                    help="trap K in pN nm (0: the braid's default, 2000 since 2026-12-06; "
                         "the tables before ran at 20000)")
    ap.add_argument("--contact", default="beads", help="'beads' or 'capsules'")
    ap.add_argument("--equilibration", type=int, default=0,
                    help="equilibration steps (0: steps / 4)")
    ap.add_argument("--out", default="runs/mirror_pairs")
    ap.add_argument("--table", default=str(HERE / "results" / "mirror_pairs.md"))
    ap.add_argument("--contact-nm", type=float, default=5.48,
                    help="Delta of the zero-temperature continuum column: the bead model's "
                         "contact distance at alpha = 0 (tests/test_handedness.py)")
    ap.add_argument("--from-json", default="",
                    help="re-render the table from a previous run's .json (no simulation)")
    args = ap.parse_args(argv)
    if args.from_json:
        res = json.loads(pathlib.Path(args.from_json).read_text())
    else:
        res = [run_pair(a, args.turns, args) for a in args.alpha]
    from dnabraid.continuum.tweezer import handedness_asymmetry

    for r in res:
        h = handedness_asymmetry(r["turns"], args.force, args.length, args.separation,
                                 args.contact_nm,
                                 alpha_pN=r["alpha_pN"])
        r["continuum"] = {"delta_z_nm": h["delta_z_nm"],
                          "torque_sum_pN_nm": h["torque_sum_pN_nm"]}
    n = args.turns
    lines = [f"# Mirror-coupled pairs vs the plain estimator ({time.strftime('%Y-%m-%d %H:%M')})",
             "",
             f"`python workflows/mirror_pairs.py`: braid 2 x {args.length:g} nm, tethers "
             f"{args.separation:g} nm, F = {args.force:g} pN, 150 mM, n = +-{n:g} built at their "
             f"catenation, {args.replicas} replica "
             f"pairs x ({args.equilibration or args.steps // 4} + {args.steps} steps), "
             f"contact {args.contact}, {args.mc_moves} moves per report interval, seed "
             f"{args.seed}. Paired: mean "
             "and standard error of the per-replica differences (original at +n minus/plus its "
             "mirror image at -n, driven by the mirrored noise). Plain: the two runs' own "
             "across-replica errors in quadrature (independent runs at +n and -n). Variance "
             "reduction = plain^2 / paired^2 (its own sampling error is large with few "
             "pairs: with R = 4 a variance ratio is uncertain by a factor ~3). Continuum: the "
             "zero-temperature tweezer braid (dnabraid.continuum.tweezer, Delta = "
             f"{args.contact_nm:g} nm). Converged: every point of both members passed the "
             "R-hat/ESS verdict; where it did not, the paired error is the scatter over the "
             "overdispersed starts of a finite-time asymmetry and does not cover what the "
             "runs have not forgotten.", "",
             "| alpha (pN) | z(+n) - z(-n) paired (nm) | plain SE (nm) | var. reduction | "
             "continuum (nm) | Gamma(+n) + Gamma(-n) paired (pN nm) | plain SE (pN nm) | "
             "var. reduction | continuum (pN nm) | converged | wall (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in res:
        z, g = r["extension_nm"], r["torque_pN_nm"]
        lines.append(f"| {r['alpha_pN']:g} | {z['asymmetry']:+.3g} +- {z['sem']:.2g} | "
                     f"{z['sem_unpaired']:.2g} | {z['variance_reduction']:.3g} | "
                     f"{r['continuum']['delta_z_nm']:+.2f} | "
                     f"{g['asymmetry']:+.3g} +- {g['sem']:.2g} | {g['sem_unpaired']:.2g} | "
                     f"{g['variance_reduction']:.3g} | {r['continuum']['torque_sum_pN_nm']:+.1f} | "
                     f"{'yes' if r['converged'] else 'NO'} | "
                     f"{r['wall_s']:.0f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    p = pathlib.Path(args.table)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    if not args.from_json:
        p.with_suffix(".json").write_text(json.dumps(res, indent=1))
    plot(res, p.with_suffix(".png"), n)
    return 0


def plot(res, path, n) -> None:
    """The paired asymmetries against alpha with their 95 % intervals, beside the
    zero-temperature continuum; open markers: not converged."""
    from matplotlib.figure import Figure
    from scipy import stats

    fig = Figure(figsize=(8, 3.4))
    axes = fig.subplots(1, 2)
    a = [r["alpha_pN"] for r in res]
    for ax, c, cc, lab in ((axes[0], "extension_nm", "delta_z_nm",
                            f"z(+{n:g}) - z(-{n:g}) (nm)"),
                           (axes[1], "torque_pN_nm", "torque_sum_pN_nm",
                            f"Gamma(+{n:g}) + Gamma(-{n:g}) (pN nm)")):
        for r in res:
            d = r[c]
            t = stats.t(max(1, d.get("n_pairs", 4) - 1)).ppf(0.975)
            ax.errorbar([r["alpha_pN"]], [d["asymmetry"]], yerr=[t * d["sem"]], fmt="o",
                        color="C0", mfc="C0" if r["converged"] else "white", capsize=3)
        ax.plot(a, [r["continuum"][cc] for r in res], "s--", color="C1", mfc="white",
                label="continuum, T = 0")
        ax.axhline(0.0, color="0.7", lw=0.8)
        ax.set_xlabel("alpha (pN)")
        ax.set_ylabel(lab)
    axes[1].plot([], [], "o", color="C0", label="bead model, mirror pairs (95 %)")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    raise SystemExit(main())
