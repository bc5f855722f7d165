"""Scene ``closed``: closed elastic braids at zero temperature: two rings linked as the
``(2, 2n)`` torus link (Lk = -+n) or one ring tied as the ``(n, 2)`` torus knot (n odd),
in hard frictionless contact of diameter Delta, relaxed to equilibrium.

The closed braids of van der Heijden's talk "Equilibrium theory of elastic braids" (and
Starostin & van der Heijden, JMPS 64, 83 (2014)): torus links with Lk = -n, n = 1..5 at
Delta/L = 0.02 (slides 19-20), the 4-link's contact pressure and braid angle (slide 21),
torus knots (n, 2) (slide 22) and the pentafoil's pressure and contact-curve curvature
(slide 23). No tweezer bead, surface, electrostatics, twist or temperature: bead rings with
bending and stiff bonds (:mod:`dnabraid.statics.closed_braid`), relaxed by the damped Newton
method of :mod:`dnabraid.statics.newton`. L is the length of each of the braid's two strands
(a ring for a link, half the ring for a knot). Outputs: braid angle eta(s), contact pressure
p(s) in B/L^3, the contact curve's curvature (knots, 1/L), Gauss linking number and writhe
per ring, the dominant harmonics of p and eta (their symmetry, found from a perturbed
start), figures like slides 21/23.
"""

from __future__ import annotations

import dataclasses
import os
import time
from typing import ClassVar

import numpy as np

from .. import rundir
from .base import Scene, SceneError, key

#: Largest total bead count (each Newton iteration factorises a 3N x 3N sparse matrix).
MAX_CLOSED_BEADS = 8000

#: The seed's numbers (van der Heijden, "Equilibrium theory of elastic braids"):
#: the extreme tick labels of the seed's plot axes (the curves span a little beyond them, so
#: they are not the data's extremes) at Delta/L = 0.02 (left-handed, Lk = -n): slide 21
#: (4-link) and slide 23 (pentafoil; p on the ring [0, L + L2], kappa_c on [0, L]).
SEED_VALUES = {
    ("link", 4): {"eta": (0.50910, 0.50935), "pressure": (3200.0, 3900.0),
                  "source": "van der Heijden, elastic braids, slide 21 (4-link, Delta/L = 0.02)"},
    ("knot", 5): {"pressure": (400.0, 550.0), "contact_curvature": (6.2, 6.8),
                  "source": "van der Heijden, elastic braids, slide 23 (pentafoil, Delta/L = 0.02)"},
}


@dataclasses.dataclass(frozen=True)
class Closed(Scene):
    name: ClassVar[str] = "closed"
    help: ClassVar[str] = (
        "closed braids at zero temperature: two rings linked as the (2, 2n) torus link or "
        "one ring tied as the (n, 2) torus knot, hard contact of diameter Delta, relaxed by "
        "Newton's method; braid angle, contact pressure (B/L^3), contact-curve curvature, "
        "linking and writhe along the contact (van der Heijden, elastic braids, slides 19-23)")

    topology: str = key("link", "", "'link': two rings as the (2, 2n) torus link (Lk = -+n); "
                        "'knot': one ring (length 2L) as the (n, 2) torus knot, n odd")
    n: int = key(4, "", "the link's |Lk| (1..), or the knot's odd n (3 trefoil, 5 pentafoil...)")
    handedness: str = key("left", "", "'left' (Lk = -n, the seed's) or 'right'")
    diameter_over_length: float = key(0.02, "", "Delta / L, L each strand's length (a ring of "
                                      "the link, half the knot's ring)")
    diameter_nm: float = key(2.0, "nm", "contact diameter Delta (sets the scale only)")
    bending_stiffness_pN_nm2: float = key(1000.0, "pN nm^2", "bending stiffness B (scale only: "
                                          "outputs are in B/L^3 and 1/L)")
    spacing_over_radius: float = key(0.25, "", "bead spacing b / h, h = Delta/2. 0.25: eta, "
                                     "p_mean, kappa_c within 0.05 % of b/h = 0.125 (4-link, "
                                     "pentafoil) and the pentafoil in contact (p_min 296 B/L^3; "
                                     "0 at 0.5): workflows/results/closed_spacing.md")
    contact: str = key("segments", "", "'segments' (smooth capsule contact) or 'beads'")
    start_noise: float = key(0.02, "", "smooth random perturbation of the uniform-ply start, "
                             "x Delta (breaks its symmetry)")
    seed: int = key(1, "", "random seed of the start perturbation")

    def validate(self) -> None:
        need = self.need
        need(self.topology in ("link", "knot"), "topology", "must be 'link' or 'knot'")
        need(self.handedness in ("left", "right"), "handedness", "must be 'left' or 'right'")
        need(self.contact in ("segments", "beads"), "contact", "must be 'segments' or 'beads'")
        need(self.n >= 1, "n", "must be >= 1")
        need(self.topology == "link" or (self.n % 2 == 1 and self.n >= 3), "n",
             "a (n, 2) torus knot needs an odd n >= 3 (3 trefoil, 5 pentafoil, ...): an even n "
             "gives a two-component link (topology='link'), n = 1 the unknot")
        need(0 < self.diameter_over_length < 1, "diameter_over_length", "must be in (0, 1)")
        need(self.diameter_nm > 0, "diameter_nm", "must be > 0")
        need(self.bending_stiffness_pN_nm2 > 0, "bending_stiffness_pN_nm2", "must be > 0")
        need(0 < self.spacing_over_radius <= 1, "spacing_over_radius",
             "must be in (0, 1] (b <= h = Delta/2; coarser beads let the strands slip through "
             "each other)")
        need(0 <= self.start_noise <= 0.2, "start_noise", "must be in [0, 0.2]")
        need(0 <= self.seed < 2**31, "seed", "must be in [0, 2^31)")
        try:
            br = self.braid()
        except ValueError as exc:
            raise SceneError(str(exc)) from exc
        beads = sum(br.ring_beads)
        need(beads <= MAX_CLOSED_BEADS, "spacing_over_radius",
             f"needs {beads} beads (> {MAX_CLOSED_BEADS}) at diameter_over_length = "
             f"{self.diameter_over_length}: raise spacing_over_radius")

    def braid(self):
        from ..statics.closed_braid import ClosedBraid

        return ClosedBraid(topology=self.topology, n=self.n, handedness=self.handedness,
                           diameter_nm=self.diameter_nm,
                           diameter_over_length=self.diameter_over_length,
                           bending_stiffness_pN_nm2=self.bending_stiffness_pN_nm2,
                           spacing_over_radius=self.spacing_over_radius, contact=self.contact,
                           start_noise=self.start_noise, seed=self.seed)

    def run(self, out: str, *, platform: str = "CPU", threads: int | None = None,
            progress_factory=None) -> dict:
        """Relax the braid; write scene.toml, topology.pdb, closed.npz, summary.json, closed.png."""
        from openmm import app

        from ..statics.closed_braid import solve

        t0 = time.perf_counter()
        rundir.prepare_out_dir(self, out)
        br = self.braid()
        r = solve(br)
        x = r.pop("x")
        x0 = r.pop("x0")
        arrays = {k: r.pop(k) for k in list(r) if isinstance(r[k], np.ndarray)}
        tmp = os.path.join(out, "closed.tmp.npz")
        np.savez(tmp, x_nm=x, x0_nm=x0, **arrays)
        os.replace(tmp, os.path.join(out, "closed.npz"))
        top = app.Topology()
        for k, m in enumerate(br.ring_beads):
            chain = top.addChain("AB"[k])
            for _ in range(m):
                top.addAtom("C", app.element.carbon, top.addResidue("ROD", chain))
        rundir.write_topology(os.path.join(out, "topology.pdb"), top, x)
        seed_ref = SEED_VALUES.get((self.topology, self.n)) if abs(
            self.diameter_over_length - 0.02) < 1e-12 else None
        notes = [f"contact model: {self.contact}; pressure_min/max are of p smoothed over "
                 f"{r['pressure_smoothing_window_beads']} beads (~Delta of strand), "
                 "pressure_raw_* per bead",
                 "eta > 0 for a left-handed braid (the seed's slide 21: Lk = -4, eta ~ +0.509)"]
        if r["contact_lost_fraction"] > 0:
            notes.append(f"no contact pressure along {100 * r['contact_lost_fraction']:.1f} % "
                         "of the strand (p < 1e-3 p0 over ~Delta): the strands touch without "
                         "pressing or separate there, so p >= 0 holds but not p > 0 (the "
                         "braid in continuous contact is not the minimum found)")
            if self.topology == "link" and self.n == 1:
                notes.append("Hopf link without twist: two linked round rings need no contact "
                             "force (energy 2 x 2 pi^2 B/L, the seed's Villarceau circles); "
                             "only twist or an interaction presses them together")
        if not r["converged"]:
            notes.append(f"Newton did not reach the force tolerance: largest force left "
                         f"{r['max_force_pN']:.3g} pN")
        summary = {
            "scene": self.to_dict(), "topology": self.topology, "n": self.n,
            "beads": r["beads"], "bead_spacing_nm": r["bead_spacing_nm"],
            "strand_length_nm": br.length_nm, "wall_time_s": time.perf_counter() - t0,
            "newton_iterations": r["iterations"], "converged": r["converged"],
            "max_force_pN": r["max_force_pN"], "saddle_escapes": r["saddle_escapes"],
            "lowest_curvature_pN_per_nm": r["lowest_curvature_pN_per_nm"],
            "measured": {k: v for k, v in r.items()
                         if k not in ("reference", "beads", "bead_spacing_nm", "iterations",
                                      "converged", "max_force_pN", "saddle_escapes",
                                      "lowest_curvature_pN_per_nm", "wall_time_s")},
            "continuum": r["reference"],
            "seed": seed_ref,
            "units": {"pressure": "B/L^3", "contact_curvature": "1/L", "eta": "rad",
                      "s": "L", "energy": "B/L", "harmonics": "(k, |c_k|/|c_0|): k periods "
                      "along strand 1 (link) or the whole ring of length 2L (knot)"},
            "notes": notes,
            "versions": rundir.versions(),
        }
        rundir.write_summary(os.path.join(out, "summary.json"), summary)
        closed_plot(arrays, summary, os.path.join(out, "closed.png"))
        return summary

    def report(self, summary: dict, out: str, file) -> None:
        m, c, sd = summary["measured"], summary["continuum"], summary["seed"] or {}
        p = lambda *a: print(*a, file=file)  # noqa: E731
        p(f"{summary['topology']} n = {summary['n']}, {summary['beads']} beads (b = "
          f"{summary['bead_spacing_nm']:.3g} nm), {summary['newton_iterations']} Newton "
          f"iterations, largest force left {summary['max_force_pN']:.2g} pN")

        def rng(t):
            return f"{t[0]:g}-{t[1]:g}" if t else "-"

        p(f"{'':<26} {'bead model':>22} {'uniform ply':>12} {'seed':>14}")
        p(f"{'eta mean (min-max) rad':<26} {m['eta_mean']:>9.5f} ({m['eta_min']:.4f}-"
          f"{m['eta_max']:.4f}) {c['eta_uniform']:>8.5f} {rng(sd.get('eta')):>14}")
        p(f"{'p mean (min-max) B/L^3':<26} {m['pressure_mean']:>9.1f} ({m['pressure_min']:.0f}-"
          f"{m['pressure_max']:.0f}) {c['pressure_uniform_torque_free']:>8.1f} "
          f"{rng(sd.get('pressure')):>14}")
        if "contact_curvature_mean" in m:
            p(f"{'kappa_c mean (min-max) 1/L':<26} {m['contact_curvature_mean']:>9.3f} "
              f"({m['contact_curvature_min']:.2f}-{m['contact_curvature_max']:.2f}) "
              f"{'':>8} {rng(sd.get('contact_curvature')):>14}")
        if m.get("linking_number") is not None:
            p(f"Gauss linking number {m['linking_number']:+.4f}")
        p("writhe per ring " + ", ".join(f"{w:+.4f}" for w in m["writhe_per_ring"]))
        p(f"dominant harmonics: p {m['pressure_smooth_harmonics'][:2]}, eta "
          f"{m['eta_harmonics'][:2]}")
        for n in summary["notes"]:
            p(f"note: {n}")
        p(f"wall time {summary['wall_time_s']:.1f} s; results in {out}/")

    row_columns: ClassVar[tuple] = ("eta_mean", "eta_min", "eta_max", "pressure_mean",
                                    "pressure_min", "pressure_max", "contact_curvature_mean",
                                    "linking_number", "writhe_ring_1", "p_harmonic",
                                    "eta_harmonic", "converged")

    def rows(self, summary: dict) -> list[dict]:
        m = summary["measured"]
        return [{"eta_mean": m["eta_mean"], "eta_min": m["eta_min"], "eta_max": m["eta_max"],
                 "pressure_mean": m["pressure_mean"], "pressure_min": m["pressure_min"],
                 "pressure_max": m["pressure_max"],
                 "contact_curvature_mean": m.get("contact_curvature_mean"),
                 "linking_number": m.get("linking_number"),
                 "writhe_ring_1": m["writhe_per_ring"][0],
                 "p_harmonic": m["pressure_smooth_harmonics"][0][0],
                 "eta_harmonic": m["eta_harmonics"][0][0], "converged": summary["converged"]}]

    def default_short_run(self) -> dict:
        return {"n": 2}


def closed_plot(arrays: dict, summary: dict, path: str) -> str:
    """p(s) and eta(s) (and kappa_c(s) for knots) along the contact, like the seed's slides
    21 and 23 (PNG; matplotlib's Figure API, as :mod:`dnabraid.plots`)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    s = arrays["s_over_L"]
    knot = "contact_curvature" in arrays
    fig = Figure(figsize=(10 if knot else 9, 3.6))
    FigureCanvasAgg(fig)
    ax = fig.subplots(1, 3 if knot else 2)
    ax[0].plot(s, arrays["pressure"], ".", ms=2, color="0.6", label="per bead")
    ax[0].plot(s, arrays["pressure_smooth"], "-", color="C3", label="smoothed over ~Delta")
    ax[0].set_xlabel("s / L")
    ax[0].set_ylabel("p (B / L$^3$)")
    ax[0].legend(fontsize=7, loc="lower right")
    ax[1].plot(s, arrays["eta"], ".", ms=2, color="0.6", label="per bead")
    ax[1].plot(s, arrays["eta_smooth"], "-", color="C0", label="smoothed over ~Delta")
    ax[1].legend(fontsize=7, loc="lower right")
    ax[1].set_xlabel("s / L")
    ax[1].set_ylabel("braid angle eta (rad)")
    if knot:
        ax[2].plot(s, arrays["contact_curvature"], "-", color="C2")
        ax[2].set_xlabel("s / L (ring)")
        ax[2].set_ylabel("contact-curve curvature (1 / L)")
    fig.suptitle(f"closed {summary['topology']} n = {summary['n']}, Delta/L = "
                 f"{summary['scene']['diameter_over_length']}, b/h = "
                 f"{summary['scene']['spacing_over_radius']}", fontsize=10)
    fig.tight_layout()
    root, ext = os.path.splitext(path)
    tmp = root + ".tmp" + (ext or ".png")
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)
    return path
