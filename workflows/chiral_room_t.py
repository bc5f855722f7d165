"""Room-temperature handedness asymmetry of the long braid against the continuum x <w>
(issue "Chirality that agrees with its theory", item 4).

For each alpha: one thermal run of the long braid (2 x 200 nm, 2 pN, tethers 40 nm apart,
capsule contact, 150 mM) at turns -n and +n (each point built at its catenation, its own
replicas), Brownian dynamics interleaved with the compiled Metropolis moves, which now
carry the capsule contact and the chiral term (dnabraid.kernels.segment_terms). Reported per
alpha: z(+n) - z(-n) and Gamma(+n) + Gamma(-n) with their standard errors (the two
points' across-replica errors in quadrature), the convergence verdicts, the strands'
distance and the mean chiral weight <w(d)> over the ply (strand 1's segments closer
than 2 D_c to strand 2) at each hand, and the ply's length (observable ``StrandDistance``), and three continuum columns:

* hard x <w>: the hard-contact continuum braid (dnabraid.continuum.tweezer, Delta = D_c)
  at each hand with alpha replaced by alpha <w>_hand (the issue's "continuum x <w(d)> over
  the measured distance distribution");
* hard: the same at alpha (w = 1: strands held at contact);
* soft, T = 0: the soft-range continuum of item 3 (dnabraid.continuum.soft_tweezer, the
  disfavoured hand free to open; quasi-static branch);
* hard at d x <w>: the hard-contact braid at each hand with Delta = that hand's measured mean
  strand distance in the ply and alpha <w>_hand (the thermal braid's own radius: how much of
  the asymmetry the measured tightening or loosening of the ply explains geometrically).

Usage: python workflows/chiral_room_t.py [--alpha 0 1 3 6] [--steps 40000] ...
       python workflows/chiral_room_t.py --from-json workflows/results/chiral_room_t.json
Writes workflows/results/chiral_room_t.{md,json,png}.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import time

HERE = pathlib.Path(__file__).resolve().parent


def _val(pt, col):
    v = pt[col]
    return (v["mean"], v["sem"]) if isinstance(v, dict) else (float(v), math.nan)


def run_alpha(alpha: float, args) -> dict:
    from dnabraid.scenes import make_scene

    keys = {"length_nm": args.length, "force_pN": args.force,
            "tether_separation_nm": args.separation, "contact": "capsules",
            "timestep_safety": args.safety, "turns": [-args.turns, args.turns],
            "mc_moves": args.mc_moves, "steps": args.steps,
            "equilibration_steps": args.equilibration, "replicas": args.replicas,
            "seed": args.seed, "alpha": alpha, "workers": args.workers,
            # pinned: the braid's default trap is K = 2000 since 2026-12-06; the stored
            # table was measured in the stiff trap of the time
            "trap_stiffness_pN_nm": 20000.0}
    sc = make_scene("braid", keys)
    d = pathlib.Path(args.out) / f"alpha{alpha:g}"
    t0 = time.perf_counter()
    sc.run(str(d))
    wall = time.perf_counter() - t0
    s = json.loads((d / "summary.json").read_text())
    pts = {round(p["turns"], 6): p for p in s["points"]}
    out = {"alpha_pN": alpha, "turns": args.turns, "wall_s": wall, "keys": keys,
           "out": str(d)}
    for tag, n in (("plus", args.turns), ("minus", -args.turns)):
        p = pts[round(n, 6)]
        out[tag] = {c: _val(p, c) for c in ("extension_nm", "torque_pN_nm",
                                            "axis_distance_nm", "chiral_weight",
                                            "ply_length_nm")}
        out[tag]["converged"] = bool(p["converged"])
        out[tag]["reason"] = p.get("convergence_reason", "")
        out[tag]["ess"] = p.get("effective_sample_size")
    zp, sp = out["plus"]["extension_nm"]
    zm, sm = out["minus"]["extension_nm"]
    tp, stp = out["plus"]["torque_pN_nm"]
    tm, stm = out["minus"]["torque_pN_nm"]
    out["dz_nm"] = (zp - zm, math.hypot(sp, sm))
    out["torque_sum_pN_nm"] = (tp + tm, math.hypot(stp, stm))
    return out


def continuum(r: dict, args) -> None:
    """The three continuum columns of one row (in place)."""
    from dnabraid.continuum.soft_tweezer import soft_handedness_asymmetry
    from dnabraid.continuum.tweezer import solve_tweezer
    from dnabraid.scenes import make_scene

    s = make_scene("braid", dict(r["keys"], turns=[r["turns"]]))
    D = s.effective_diameter_nm
    B = s.kT * s.persistence_nm
    n, a = abs(r["turns"]), r["alpha_pN"]
    geo = (s.force_pN, s.length_nm, s.tether_separation_nm, D)

    def pair(a_plus, a_minus, d_plus=D, d_minus=D):
        cp = solve_tweezer(n, *geo[:3], d_plus, bending_pN_nm2=B, alpha_pN=a_plus)
        cm = solve_tweezer(-n, *geo[:3], d_minus, bending_pN_nm2=B, alpha_pN=a_minus)
        if not (cp.success and cm.success):
            return math.nan, math.nan
        return (cp["extension_nm"] - cm["extension_nm"],
                cp["torque_pN_nm"] + cm["torque_pN_nm"])

    wp = r["plus"]["chiral_weight"][0]
    wm = r["minus"]["chiral_weight"][0]
    r["contact_nm"] = D
    r["hard_w"] = pair(a * wp, a * wm)
    r["hard"] = pair(a, a)
    r["hard_d_w"] = pair(a * wp, a * wm, r["plus"]["axis_distance_nm"][0],
                         r["minus"]["axis_distance_nm"][0])
    if a == 0.0:
        r["soft"] = (0.0, 0.0)
    else:
        so = soft_handedness_asymmetry(n, s.force_pN, s.length_nm, s.tether_separation_nm, D,
                                       debye_nm=s.dna().debye_nm, bending_pN_nm2=B,
                                       alpha_pN=a, branch="path")
        r["soft"] = (so["delta_z_nm"], so["torque_sum_pN_nm"])


def _f(x, d=2):
    return "nan" if x is None or not math.isfinite(x) else f"{x:+.{d}f}"


def render(res: list, args) -> str:
    k = res[0]["keys"]
    lines = [f"# Room-temperature handedness asymmetry of the long braid against the continuum "
             f"x <w> ({time.strftime('%Y-%m-%d %H:%M')})", "",
             f"`python workflows/chiral_room_t.py` (one `dnabraid run braid` per alpha): "
             f"2 x {k['length_nm']:g} nm, {k['force_pN']:g} pN, tethers "
             f"{k['tether_separation_nm']:g} nm apart, capsule contact (D_c = "
             f"{res[0].get('contact_nm', float('nan')):.3f} nm), turns +-{res[0]['turns']:g} "
             f"each built at its catenation, {k['replicas']} replicas x ({k['equilibration_steps']}"
             f" + {k['steps']}) Brownian steps at timestep_safety {k['timestep_safety']:g}, "
             f"{k['mc_moves']} compiled Metropolis moves (capsules and chiral term included) "
             f"per report interval, seed {k['seed']}. dz = z(+n) - z(-n), torque sum = "
             "Gamma(+n) + Gamma(-n) (trap torque), errors: the two points' standard errors in "
             "quadrature. <w>, d: the mean chiral weight (1 at contact) and strand distance over the "
             "ply (strand 1's segments closer than 2 D_c to strand 2), ply: its contour length. Continuum: hard x <w> = the hard-contact braid at each hand with "
             "alpha <w>_hand; hard = the same at w = 1; soft T = 0 = item 3's soft-range "
             "continuum (quasi-static branch); hard at d x <w> = the hard-contact braid at each "
             "hand with Delta = its measured ply distance d and alpha <w>.", "",
             "| alpha pN | dz bead nm | dz hard x <w> | dz hard | dz soft T=0 | dz hard at d x <w> "
             "| torque sum bead pN nm | hard x <w> | hard | soft T=0 | hard at d x <w> | "
             "<w> +n / -n | d ply +n / -n nm | ply +n / -n nm | converged +n / -n (ESS) | "
             "wall s |",
             "|" + "---|" * 16]
    for r in res:
        p, m = r["plus"], r["minus"]
        lines.append(
            f"| {r['alpha_pN']:g} | {_f(r['dz_nm'][0])} +- {r['dz_nm'][1]:.2f} | "
            f"{_f(r['hard_w'][0])} | {_f(r['hard'][0])} | {_f(r['soft'][0])} | "
            f"{_f(r['hard_d_w'][0])} | "
            f"{_f(r['torque_sum_pN_nm'][0], 1)} +- {r['torque_sum_pN_nm'][1]:.1f} | "
            f"{_f(r['hard_w'][1], 1)} | {_f(r['hard'][1], 1)} | {_f(r['soft'][1], 1)} | "
            f"{_f(r['hard_d_w'][1], 1)} | "
            f"{p['chiral_weight'][0]:.3f} / {m['chiral_weight'][0]:.3f} | "
            f"{p['axis_distance_nm'][0]:.2f} / {m['axis_distance_nm'][0]:.2f} | "
            f"{p['ply_length_nm'][0]:.0f} / {m['ply_length_nm'][0]:.0f} | "
            f"{'yes' if p['converged'] else 'NO'} / {'yes' if m['converged'] else 'NO'} "
            f"({_ess(p)} / {_ess(m)}) | {r['wall_s']:.0f} |")
    lines += ["", "Wall: each alpha's run on the 2 cores, shared with other work (a test suite "
              "and a one-core study ran beside it): read it as an upper bound. Reproduce: "
              "`python workflows/chiral_room_t.py` (re-render: `--from-json "
              "workflows/results/chiral_room_t.json`).", ""]
    return "\n".join(lines)


def _ess(p):
    e = p.get("ess")
    if isinstance(e, dict):
        e = e.get("extension_nm", min(e.values()) if e else None)
    return "-" if e is None else f"{float(e):.0f}"


def plot(res: list, path: pathlib.Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a = [r["alpha_pN"] for r in res]
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.6))
    conv = [r["plus"]["converged"] and r["minus"]["converged"] for r in res]
    for ok, lab, face in ((True, "bead model, 298 K", "C0"),
                          (False, "bead model, NOT CONVERGED", "none")):
        sel = [i for i, c in enumerate(conv) if c == ok]
        if not sel:
            continue
        for k, key in enumerate(("dz_nm", "torque_sum_pN_nm")):
            ax[k].errorbar([a[i] for i in sel], [res[i][key][0] for i in sel],
                           [res[i][key][1] for i in sel], fmt="o", color="C0",
                           markerfacecolor=face, label=lab)
    for key, lab, st in (("hard_w", "continuum x <w>", "s--"), ("hard", "continuum (w = 1)", "^:"),
                         ("soft", "soft continuum, T = 0", "v-."),
                         ("hard_d_w", "continuum at measured d, x <w>", "d-")):
        ax[0].plot(a, [r[key][0] for r in res], st, label=lab)
        ax[1].plot(a, [r[key][1] for r in res], st, label=lab)
    ax[0].set_xlabel("alpha (pN)")
    ax[0].set_ylabel("z(+n) - z(-n) (nm)")
    ax[1].set_xlabel("alpha (pN)")
    ax[1].set_ylabel("Gamma(+n) + Gamma(-n) (pN nm)")
    ax[0].axhline(0, color="0.7", lw=0.5)
    ax[1].axhline(0, color="0.7", lw=0.5)
    ax[0].legend(fontsize=7)
    fig.suptitle(f"long braid, n = +-{res[0]['turns']:g}: handedness asymmetry against alpha",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--alpha", type=float, nargs="+", default=[0.0, 1.0, 3.0, 6.0])
    ap.add_argument("--turns", type=float, default=2.0)
    ap.add_argument("--length", type=float, default=200.0, help="strand length (nm)")
    ap.add_argument("--force", type=float, default=2.0, help="pulling force (pN)")
    ap.add_argument("--separation", type=float, default=40.0, help="tether separation (nm)")
    ap.add_argument("--safety", type=float, default=0.3, help="timestep_safety")
    ap.add_argument("--mc-moves", type=int, default=2500)
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--equilibration", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=0)
    ap.add_argument("--out", default="runs/chiral_room_t")
    ap.add_argument("--table", default=str(HERE / "results" / "chiral_room_t.md"))
    ap.add_argument("--from-json", default="")
    args = ap.parse_args(argv)
    table = pathlib.Path(args.table)
    if args.from_json:
        res = json.loads(pathlib.Path(args.from_json).read_text())
    else:
        res = []
        for a in args.alpha:
            res.append(run_alpha(a, args))
            table.with_suffix(".json").write_text(json.dumps(res, indent=1))  # no lost runs
    for r in res:
        continuum(r, args)
    table.with_suffix(".json").write_text(json.dumps(res, indent=1))
    md = render(res, args)
    table.write_text(md)
    plot(res, table.with_suffix(".png"))
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
