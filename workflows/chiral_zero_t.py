"""Zero-temperature chirality cross-check (dnabraid.validation.chiral_zero_t): the long braid
(2 x 200 nm, 2 pN, tethers 40 nm, capsule contact) at n = +-2 (and +-1) for alpha in
{0.5, 1, 2} pN against two continuum braids at the same contact distance D_c: hard contact
(solve_tweezer at Delta = D_c) and the soft chiral range (solve_soft_tweezer: the bead model's
weight w(d), the axis distance free, on the quasi-static branch).

Writes workflows/results/chiral_zero_t.md (and .json). ~8-12 min on a shared 2-core machine.

    python workflows/chiral_zero_t.py [--turns 2 1] [--forces 2 20]

The 20 pN rows (n = 2) are the same braid at ten times the force: a contact pressure high
enough that the disfavoured hand stays in contact (docs/chirality.md).
"""

import argparse
import json
import pathlib
import time

from dnabraid.validation import chiral_zero_t as cz

OUT = pathlib.Path(__file__).parent / "results"


def fmt(x, nd=3):
    return "-" if x is None else (f"{x:.{nd}f}" if isinstance(x, float) else str(x))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--turns", type=float, nargs="+", default=[2.0, 1.0])
    ap.add_argument("--alphas", type=float, nargs="+", default=[0.5, 1.0, 2.0])
    ap.add_argument("--forces", type=float, nargs="+", default=[2.0, 20.0])
    args = ap.parse_args()
    t0 = time.perf_counter()
    rows = []
    runs = [(2.0, n) for n in args.turns] + [(f, 2.0) for f in args.forces if f != 2.0]
    for force, n in runs:
        rows += [r | {"force_pN": force}
                 for r in cz.table(n, args.alphas, overrides={"force_pN": force})]
        for r in rows[-len(args.alphas):]:
            print({k: r[k] for k in ("turns", "alpha_pN", "bead_dz_nm", "cont_dz_nm",
                                     "soft_dz_nm", "bead_torque_sum_pN_nm",
                                     "soft_torque_sum_pN_nm", "contact_minus_nm",
                                     "soft_axis_minus_nm")}, flush=True)
    OUT.mkdir(exist_ok=True)
    (OUT / "chiral_zero_t.json").write_text(json.dumps(rows, indent=1))
    lines = [
        "# Zero-temperature chirality cross-check (capsule contact, long braid)",
        "",
        "`python workflows/chiral_zero_t.py`; dnabraid.validation.chiral_zero_t. Bead braid: "
        "2 x 200 nm, tethers 40 nm, 150 mM, contact = capsules (D_c = 4.9 nm), formed "
        "quasi-statically (40 trap increments, L-BFGS after each). Continua at D_c: *hard* = "
        "solve_tweezer at Delta = D_c (strands in contact); *soft* = solve_soft_tweezer, the "
        "bead model's chiral weight w(d) (flat to D_c, range rho = 0.446 nm beyond), the axis "
        "distance d >= D_c free, quasi-static branch. dz = z(+n) - z(-n); Gamma sum = "
        "Gamma(+n) + Gamma(-n); bead contact = mean closest segment distance over the middle "
        "third; soft d = the soft continuum's axis distance. Checks: "
        f"(a) |contact(+-n) - contact(alpha=0)| <= {cz.CONTACT_TOL_NM} nm for alpha <= 1 "
        "(the issue's, reported); (a') |contact(+-n) - soft d(+-n)| <= tol (compression "
        "p b/k + chords 2 kappa b^2/8 + the gap's response to a "
        f"{cz.GAP_FORCE_RTOL:.0%} force mismatch; per hand in the json); "
        f"(b) sign and |dz_bead - dz_soft| <= {cz.DZ_RTOL:.0%} |dz_soft| + {cz.DZ_ATOL_NM} nm; "
        f"(c) torque sums within {cz.TORQUE_RTOL:.0%} of the soft continuum's; (b-hard), "
        "(c-hard) the same against the hard continuum.",
        "",
        "| F (pN) | n | alpha (pN) | dz bead / hard / soft (nm) | contact a=0 / +n / -n "
        "(nm) | soft d +n / -n (nm) | (a') tol +n / -n (nm) | Gamma sum bead / hard / soft "
        "(pN nm) | (a) | (a') | (b) | (c) | (b-hard) | (c-hard) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['force_pN']:g} | {r['turns']:g} | {r['alpha_pN']:g} | "
            f"{r['bead_dz_nm']:+.3f} / {r['cont_dz_nm']:+.3f} / {r['soft_dz_nm']:+.3f} | "
            f"{r['contact0_nm']:.3f} / {r['contact_plus_nm']:.3f} / "
            f"{r['contact_minus_nm']:.3f} | {r['soft_axis_plus_nm']:.3f} / "
            f"{r['soft_axis_minus_nm']:.3f} | {r['contact_tol_plus_nm']['total']:.3f} / "
            f"{r['contact_tol_minus_nm']['total']:.3f} | {r['bead_torque_sum_pN_nm']:+.3f} / "
            f"{r['cont_torque_sum_pN_nm']:+.3f} / {r['soft_torque_sum_pN_nm']:+.3f} | "
            f"{fmt(r['a_ok'])} | {fmt(r['a2_ok'])} | {fmt(r['b_ok'])} | {fmt(r['c_ok'])} | "
            f"{fmt(r['b_hard_ok'])} | {fmt(r['c_hard_ok'])} |")
    two = [r for r in rows if len(r["soft_minima_minus"]) > 1]
    lines += ["", "Soft continuum at -n with two minima over the gap (gap nm, E pN nm; lowest "
              "first) and the branch the table uses:", ""]
    for r in two:
        mins = ", ".join(f"{m['gap_nm']:.3f} ({m['energy_pN_nm']:.2f})"
                         for m in r["soft_minima_minus"])
        lines.append(f"* F = {r['force_pN']:g} pN, n = -{r['turns']:g}, alpha = "
                     f"{r['alpha_pN']:g}: {mins}; used gap "
                     f"{r['soft_axis_minus_nm'] - r['D_c_nm']:.3f} nm "
                     f"({r['soft_branch_minus']})")
    lines += ["", "Reading (docs/chirality.md): at 2 pN the disfavoured hand (-n) opens where the "
              "chiral weight's decay beyond D_c (range 0.446 nm) outweighs the braid's contact "
              "pressure (~0.05 pN/nm); the soft continuum opens by the same gap, the hard one "
              "cannot, so only the soft continuum is the reference for dz and the torque sum.",
              "", f"Wall time {time.perf_counter() - t0:.0f} s."]
    (OUT / "chiral_zero_t.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
