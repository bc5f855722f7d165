"""Scene ``knot``: an open (2, 2n+1) knot (trefoil, cinquefoil, ...) tied in an elastic rod
pulled by a tension T at both ends, relaxed at zero temperature.

No tweezer bead, surface, electrostatics or temperature: the rod is made of beads
(harmonic bonds, hinges (B/b)(1 - cos beta)) with self-contact at 2h (key ``contact``: between
the segments joining the beads, a smooth tube (default), or between the beads, a corrugated
one that pins the loop), relaxed by the damped Newton method of
:mod:`dnabraid.statics.newton` (the model: :mod:`dnabraid.statics.open_knot`). Measured loop
radius, braid length and wave number are compared with the continuum theory:
T = EI / (2 R^2) and l = 2 w_c sqrt(2 h R) (Audoly, Clauvelin & Neukirch 2007, Eqs. 1 and 7)
and k = (sqrt(12) h R)^(-1/2) (Jawed, Dieleman, Audoly & Reis 2015, Eq. 3).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from typing import ClassVar

import numpy as np

from .. import rundir
from .base import Scene, key

#: Largest eps = sqrt(h / R): Audoly, Clauvelin & Neukirch (2007, Fig. 6) compute a tight
#: trefoil at eps = 0.52; beyond, the loop is shorter than the braid around it.
MAX_KNOT_EPS = 0.55
#: Largest bead count (the Newton solve is ~O(N) per iteration).
MAX_KNOT_BEADS = 20000


_CONTACT_NOTES = {
    "beads": "zero temperature: Newton minimum of the bead rod; the bead-bead contact pins "
             "sliding, so the loop radius depends on the start (start_loop_factor); see "
             "workflows/results/knot_crosscheck.md",
    "segments": "zero temperature: Newton minimum of the bead rod with segment-segment contact "
                "(frictionless sliding: the start does not matter); the theory is the leading "
                "order in eps, see workflows/results/knot_band.md for its O(eps) corrections",
}


@dataclasses.dataclass(frozen=True)
class Knot(Scene):
    name: ClassVar[str] = "knot"
    help: ClassVar[str] = (
        "an open (2, 2n+1) knot (trefoil, cinquefoil, ...) tied in an elastic rod pulled by a "
        "tension, relaxed at zero temperature (no tweezer bead, surface or electrostatics): "
        "loop radius, braid length and wave number against the continuum theory (Audoly, "
        "Clauvelin & Neukirch 2007; Jawed, Dieleman, Audoly & Reis 2015)")

    knot_n: int = key(1, "", "unknotting number n of the open (2, 2n+1) torus knot (1 trefoil, "
                      "2 cinquefoil, ...; Jawed et al. 2015)")
    tension_pN: float = key(0.8, "pN", "tension T pulling both ends")
    rod_radius_nm: float = key(1.0, "nm", "rod radius h (contact at 2h)")
    bending_stiffness_pN_nm2: float = key(1000.0, "pN nm^2", "bending stiffness B = EI")
    bead_spacing_nm: float = key(0.5, "nm", "distance b between beads along the rod")
    start_loop_factor: float = key(1.0, "", "loop radius of the starting shape / sqrt(B / 2T) "
                                   "(> 1 tightens, < 1 loosens; the bead contact pins sliding)")
    contact: str = key("segments", "", "self-contact model: 'segments' (closest distance "
                       "between the straight segments joining the beads: a smooth tube, the "
                       "loop slides freely; default) or 'beads' (between beads: a corrugated "
                       "surface whose static friction ~ b/(4h) pins the loop)")

    def validate(self) -> None:
        need = self.need
        need(1 <= self.knot_n <= 10, "knot_n", "must be 1 (trefoil) ... 10")
        need(self.tension_pN > 0, "tension_pN", "must be > 0 pN")
        need(self.rod_radius_nm > 0, "rod_radius_nm", "must be > 0")
        need(self.bending_stiffness_pN_nm2 > 0, "bending_stiffness_pN_nm2", "must be > 0")
        need(self.bead_spacing_nm > 0, "bead_spacing_nm", "must be > 0")
        need(0.5 <= self.start_loop_factor <= 2.0, "start_loop_factor", "must be in [0.5, 2]")
        from ..statics.open_knot import CONTACT_MODELS

        need(self.contact in CONTACT_MODELS, "contact",
             f"must be one of {', '.join(map(repr, CONTACT_MODELS))}")
        need(self.bead_spacing_nm <= self.rod_radius_nm, "bead_spacing_nm",
             f"must be <= rod_radius_nm={self.rod_radius_nm} (coarser beads let the strands "
             "slip through each other and corrugate the contact)")
        R = math.sqrt(self.bending_stiffness_pN_nm2 / (2.0 * self.tension_pN))
        eps = math.sqrt(self.rod_radius_nm / R)
        need(eps <= MAX_KNOT_EPS, "tension_pN",
             f"gives eps = sqrt(h/R) = {eps:.3f} > {MAX_KNOT_EPS} (loop radius R = sqrt(B/2T) "
             f"= {R:.3g} nm): tighter than the tightest elastic knot computed (Audoly, "
             "Clauvelin & Neukirch 2007, Fig. 6: eps = 0.52); lower the tension")
        length = (2 * math.pi * R * 1.5
                  + 3.0 * math.sqrt(self.bending_stiffness_pN_nm2 / self.tension_pN)
                  + 4 * (self.knot_n + 1) * 3.5 * math.sqrt(2 * self.rod_radius_nm * R))
        beads = length / self.bead_spacing_nm
        need(beads <= MAX_KNOT_BEADS, "tension_pN",
             f"needs ~{beads:.0f} beads (> {MAX_KNOT_BEADS}): the knot is too loose for this "
             "bead spacing; raise the tension or bead_spacing_nm")

    def rod(self):
        from ..statics.open_knot import KnotRod

        return KnotRod(n=self.knot_n, thickness_nm=self.rod_radius_nm,
                       bending_stiffness_pN_nm2=self.bending_stiffness_pN_nm2,
                       tension_pN=self.tension_pN, bead_spacing_nm=self.bead_spacing_nm,
                       contact=self.contact)

    def run(self, out: str, *, platform: str = "CPU", threads: int | None = None,
            progress_factory=None) -> dict:
        """Relax the knot; write scene.toml, topology.pdb, knot.npy, summary.json, knot.png."""
        from openmm import app

        from .. import plots
        from ..statics.open_knot import compare

        t0 = time.perf_counter()
        rundir.prepare_out_dir(self, out)
        rod = self.rod()
        r = compare(rod, radius_factor=self.start_loop_factor)
        x = r.pop("x")
        tmp = os.path.join(out, "knot.tmp.npy")
        np.save(tmp, x)
        os.replace(tmp, os.path.join(out, "knot.npy"))
        top = app.Topology()
        chain = top.addChain("A")
        for _ in range(len(x)):
            top.addAtom("C", app.element.carbon, top.addResidue("ROD", chain))
        rundir.write_topology(os.path.join(out, "topology.pdb"), top, x)
        summary = {
            "scene": self.to_dict(), "knot_n": rod.n, "eps": rod.eps, "beads": r["beads"],
            "wall_time_s": time.perf_counter() - t0, "newton_iterations": r["iterations"],
            "converged": r["converged"], "max_force_pN": r["max_force_pN"],
            "openmm_max_force_pN": r["openmm_max_force_pN"],
            "contact": rod.contact,
            "measured": {k: r[k] for k in ("radius_apex_nm", "radius_dL_nm",
                                           "radius_curvature_nm", "braid_length_nm",
                                           "wave_number_per_nm", "winding_turns",
                                           "shortening_nm", "max_overlap_nm", "crossings")},
            "theory": {"radius_nm": rod.radius_theory_nm,
                       "braid_length_nm": r["braid_length_theory_nm"],
                       "wave_number_per_nm": r["wave_number_theory_per_nm"],
                       "winding_turns": rod.n,
                       "sources": "R = sqrt(B/2T) (Audoly, Clauvelin & Neukirch 2007, Eq. 1), "
                                  "l = 2 w_c sqrt(2hR) (ibid., Eq. 7), k = (sqrt(12) h R)^(-1/2)"
                                  " (Jawed, Dieleman, Audoly & Reis 2015, Eq. 3)"},
            "ratios": {"2TR_apex^2/B": r["tension_ratio_apex"],
                       "2TR_dL^2/B": r["tension_ratio_dL"],
                       "2TR_curv^2/B": r["tension_ratio_curvature"],
                       "l/l_theory": r["braid_ratio"], "k/k_theory": r["wave_number_ratio"]},
            "units": {"lengths": "nm", "forces": "pN", "wave_number": "1/nm",
                      "winding": "turns of the strands' half-difference between the outermost "
                                 "apparent crossings"},
            "notes": [_CONTACT_NOTES[self.contact]],
            "versions": rundir.versions(),
        }
        rundir.write_summary(os.path.join(out, "summary.json"), summary)
        plots.knot_plot(x, summary, os.path.join(out, "knot.png"))
        return summary

    def report(self, summary: dict, out: str, file) -> None:
        m, t = summary["measured"], summary["theory"]
        p = lambda *a: print(*a, file=file)  # noqa: E731
        p(f"knot n = {summary['knot_n']}, eps = {summary['eps']:.3f}, {summary['beads']} beads, "
          f"{summary['newton_iterations']} Newton iterations, largest OpenMM force left "
          f"{summary['openmm_max_force_pN']:.2g} pN")
        p(f"{'':<24} {'bead model':>12} {'theory':>12}")
        p(f"{'loop radius (apex) nm':<24} {m['radius_apex_nm']:>12.2f} {t['radius_nm']:>12.2f}")
        p(f"{'shortening / 2 pi nm':<24} {m['radius_dL_nm']:>12.2f} {t['radius_nm']:>12.2f}")
        p(f"{'braid length nm':<24} {m['braid_length_nm']:>12.2f} "
          f"{t['braid_length_nm']:>12.2f}")
        p(f"{'wave number 1/nm':<24} {m['wave_number_per_nm']:>12.4f} "
          f"{t['wave_number_per_nm']:>12.4f}")
        p(f"{'winding turns':<24} {m['winding_turns']:>12.3f} {t['winding_turns']:>12d}")
        for n in summary["notes"]:
            p(f"note: {n}")
        p(f"wall time {summary['wall_time_s']:.1f} s; results in {out}/")

    row_columns: ClassVar[tuple] = ("radius_apex_nm", "radius_theory_nm", "braid_length_nm",
                                    "braid_length_theory_nm", "wave_number_per_nm",
                                    "wave_number_theory_per_nm", "winding_turns", "converged")

    def rows(self, summary: dict) -> list[dict]:
        m, t = summary["measured"], summary["theory"]
        return [{"radius_apex_nm": m["radius_apex_nm"], "radius_theory_nm": t["radius_nm"],
                 "braid_length_nm": m["braid_length_nm"],
                 "braid_length_theory_nm": t["braid_length_nm"],
                 "wave_number_per_nm": m["wave_number_per_nm"],
                 "wave_number_theory_per_nm": t["wave_number_per_nm"],
                 "winding_turns": m["winding_turns"], "converged": summary["converged"]}]
