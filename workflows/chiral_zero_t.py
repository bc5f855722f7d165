"""Zero-temperature chirality cross-check (dnabraid.validation.chiral_zero_t): the long braid
(2 x 200 nm, 2 pN, tethers 40 nm, capsule contact) at n = +-2 (and +-1) for alpha in
{0.5, 1, 2} pN against the continuum braid at the same contact distance D_c.

Writes workflows/results/chiral_zero_t.md (and .json). ~6-10 min on a shared 2-core machine.

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
                                     "bead_torque_sum_pN_nm", "cont_torque_sum_pN_nm",
                                     "contact_shift_nm")}, flush=True)
    OUT.mkdir(exist_ok=True)
    (OUT / "chiral_zero_t.json").write_text(json.dumps(rows, indent=1))
    lines = [
        "# Zero-temperature chirality cross-check (capsule contact, long braid)",
        "",
        "`python workflows/chiral_zero_t.py`; dnabraid.validation.chiral_zero_t. Bead braid: "
        "2 x 200 nm, 2 pN, tethers 40 nm, 150 mM, contact = capsules (D_c = 4.9 nm), formed "
        "quasi-statically (40 trap increments, L-BFGS after each). Continuum: solve_tweezer "
        "at Delta = D_c. dz = z(+n) - z(-n); Gamma sum = Gamma(+n) + Gamma(-n). Checks: "
        f"(a) |contact(+-n) - contact(alpha=0)| <= {cz.CONTACT_TOL_NM} nm for alpha <= 1; "
        f"(b) sign and |dz_bead - dz_cont| <= {cz.DZ_RTOL:.0%} |dz_cont| + {cz.DZ_ATOL_NM} nm; "
        f"(c) torque sums within {cz.TORQUE_RTOL:.0%}.",
        "",
        "| F (pN) | n | alpha (pN) | dz bead (nm) | dz cont (nm) | contact a=0 / +n / -n (nm) | "
        "Gamma sum bead | Gamma sum cont | Gamma(+n), Gamma(-n) bead | (a) | (b) | (c) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['force_pN']:g} | {r['turns']:g} | {r['alpha_pN']:g} | {r['bead_dz_nm']:+.3f} | "
            f"{r['cont_dz_nm']:+.3f} | {r['contact0_nm']:.3f} / {r['contact_plus_nm']:.3f} / "
            f"{r['contact_minus_nm']:.3f} | {r['bead_torque_sum_pN_nm']:+.3f} | "
            f"{r['cont_torque_sum_pN_nm']:+.3f} | {r['bead_torque_plus_pN_nm']:.3f}, "
            f"{r['bead_torque_minus_pN_nm']:.3f} | {fmt(r['a_ok'])} | {fmt(r['b_ok'])} | "
            f"{fmt(r['c_ok'])} |")
    lines += ["", "Reading (docs/chirality.md): at 2 pN the disfavoured hand (-n) opens where the "
              "chiral weight's decay beyond D_c (range 0.446 nm) outweighs the braid's contact "
              "pressure (~0.046 pN/nm): gap x with (x/rho^2) exp(-x/rho) = p / (alpha "
              "tan(|eta|/2)). The continuum braid stays in hard contact, so dz differs in sign. "
              "At 20 pN the pressure is ~10x larger and the contact holds for alpha <= 1.",
              "", f"Wall time {time.perf_counter() - t0:.0f} s."]
    (OUT / "chiral_zero_t.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
