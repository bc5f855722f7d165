"""Open elastic knots in the bead rod (zero temperature) against the continuum theory.

For each (n, eps, b) the knot is relaxed (damped Newton,
dnabraid.statics.open_knot.relax) twice: from a loose start (loop 1.2 x theory: the knot
tightens) and from a tight one (0.85 x: it loosens). The discrete contact between beads pins sliding
(static friction of order P b / (4 h), P the total contact force), so the two ends bracket
the frictionless equilibrium; the bracket narrows with the bead spacing b.

Compared (theory at R = sqrt(B / 2T): Audoly, Clauvelin & Neukirch, PRL 2007, Eq. 1):
  * 2 T R^2 / B with R = R_apex (half the loop's width) and R = Delta L / 2 pi  -> 1
  * braid length l / (2 w_c sqrt(2 h R))  (Audoly, Clauvelin & Neukirch 2007, Eq. 7)  -> 1
  * wave number k sqrt(sqrt(12) h R)      (Jawed, Dieleman, Audoly & Reis, PRL 2015,
                                           Eq. 3; long knots n >= 2)              -> 1
Writes workflows/results/knot_crosscheck.md (+ .json).

Usage: taskset -c 0 python workflows/knot_crosscheck.py [--quick | --long-only --out F]
       [--contact beads|segments]   (default beads: the table of the pinned bead contact)
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

from dnabraid.statics import open_knot as K

HERE = pathlib.Path(__file__).resolve().parent
B_PN_NM2 = 1000.0
H_NM = 1.0

TREFOIL = [(1, 0.3, 0.5), (1, 0.2, 0.5), (1, 0.2, 0.25), (1, 0.15, 0.5)]
LONG = [(n, 0.2, 0.5) for n in (2, 3, 4, 5, 6)]
STARTS = (("tighten", 1.2), ("loosen", 0.85))


def rod_for(n, eps, b, contact="beads"):
    R = H_NM / eps**2
    return K.KnotRod(n=n, thickness_nm=H_NM, bending_stiffness_pN_nm2=B_PN_NM2,
                     tension_pN=B_PN_NM2 / (2 * R * R), bead_spacing_nm=b, contact=contact)


def _write(path, lines, rows) -> None:
    out = pathlib.Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    out.with_suffix(".json").write_text(json.dumps(rows, indent=1, default=float))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="eps = 0.3, 0.2 trefoils only")
    ap.add_argument("--long-only", action="store_true", help="only the long knots n = 2 ... 6")
    ap.add_argument("--contact", choices=K.CONTACT_MODELS, default="beads",
                    help="self-contact model (default beads: this table is the bead "
                         "contact's friction bracket; workflows/knot_band.py has segments)")
    ap.add_argument("--out", default=str(HERE / "results" / "knot_crosscheck.md"))
    args = ap.parse_args(argv)
    out = args.out
    cases = TREFOIL[:2] if args.quick else (LONG if args.long_only else TREFOIL + LONG)
    rows = []
    head = ("| n | eps | b/h | start | beads | 2TR_apex^2/B | 2TR_dL^2/B | l/l_th | k/k_th | "
            "winding (turns) | Newton it | max F OpenMM (pN) | wall (s) |")
    lines = [f"# knot cross-check, {time.strftime('%Y-%m-%d %H:%M')}", "",
             f"h = {H_NM} nm, B = {B_PN_NM2} pN nm^2, T = B eps^4 / (2 h^2); tails 1.5 sqrt(B/T);",
             f"contact ({args.contact}) k = 2000 pN/nm. Theory values are the leading order in eps: "
             "R = sqrt(B / 2T) (Audoly, Clauvelin & Neukirch 2007, Eq. 1), "
             "l_th = 2 w_c sqrt(2 h R) (ibid., Eq. 7), k_th = (sqrt(12) h R)^(-1/2) "
             "(Jawed, Dieleman, Audoly & Reis 2015, Eq. 3).", "",
             head, "|" + "---|" * 13]
    print(head, flush=True)
    for n, eps, b in cases:
        rod = rod_for(n, eps, b, args.contact)
        for name, rf in STARTS:
            try:
                r = K.compare(rod, radius_factor=rf)
            except K.KnotError as exc:
                line = f"| {n} | {eps} | {b} | {name} | - | failed: {exc} |"
                lines.append(line)
                print(line, flush=True)
                continue
            r.pop("x")
            r.update(start=name, b=b)
            rows.append(r)
            line = (f"| {n} | {eps} | {b / H_NM} | {name} | {r['beads']} | "
                    f"{r['tension_ratio_apex']:.3f} | {r['tension_ratio_dL']:.3f} | "
                    f"{r['braid_ratio']:.3f} | {r['wave_number_ratio']:.3f} | "
                    f"{r['winding_turns']:.3f} | {r['iterations']}"
                    f"{'' if r['converged'] else ' (not converged)'} | "
                    f"{r['openmm_max_force_pN']:.1e} | {r['wall_time_s']:.1f} |")
            lines.append(line)
            print(line, flush=True)
            _write(args.out, lines, rows)  # after every row: nothing lost if interrupted
    _write(args.out, lines, rows)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
