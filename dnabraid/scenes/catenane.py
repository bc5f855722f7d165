"""Scene ``catenane``: two linked DNA minicircles (or one ring) at room temperature.

Two closed, torsionally constrained DNA rings (no nick) linked once (the Hopf link, Gauss
Lk_12 = +-1), with bending, twist (one side particle per bond, closed material frames,
:meth:`dnabraid.chains.ChainKit.add_ring_twist`), excluded volume and the chiral
interaction alpha tan(eta/2) per unit contact length (seed: van der Heijden, *Equilibrium
theory of elastic braids*, slides 31-32, the buckling of two linked rings driven by the
chiral term; the term is left out at alpha = 0). Each ring's own linking number is set by
``delta_lk`` (the frames close with that many extra turns): Lk_i = Tw_i + Wr_i = delta_lk
(White 1969) for all time, as is Lk_12, unless DNA passes through DNA; both are checked at
every sample and a change stops the run with a clear error. No tweezer bead, no wall.

Sizes. The seed's linked rings have Delta/L = 0.02 (Delta the diameter, L each ring's
length): at 1 M NaCl (Delta = 2.9 nm, Stigter) that is L = 144 nm = 424 bp, the default;
the bead spacing 3 nm is the coarsest whose strand-passage barrier stays >= 20 kT at that
diameter (2.9 nm; :func:`dnabraid.chains.max_bead_spacing_nm` = 3.5 nm). 720 bp at 150 mM
(L = 245 nm, Delta = 4.9 nm, Delta/L = 0.02 too) is a run with ``length_nm = 245``,
``salt_mM = 150``, ``bead_spacing_nm = 5``.

Observables (every sample unless said): ``lk12`` (Gauss linking number of the rings),
``twist_i``, ``writhe_i`` (turns; Tw from the joint angles, seam included; Wr the exact
Gauss self-integral), ``lk_error`` (max_i |Tw_i + Wr_i - delta_lk|: the discrete White
theorem holds to round-off, so this is ~1e-12 unless the topology changed), ``dtw_half_i``
(twist of the first half of ring i minus that of the second half, turns, see below),
``contact_length_nm`` (ring-1 segments whose closest ring-2 segment is nearer than the
contact distance, times b), ``braid_angle_rad`` (their mean folded braid angle eta,
:func:`dnabraid.geometry.curves.crossing_angles`: eta < 0 right-handed, > 0 left-handed;
NaN without contact) and, every frame, ``chiral_energy_pN_nm`` (the term's numpy twin).

Twist fluctuations of a closed ring. With Lk fixed, Tw = Lk - Wr: the ring's total twist
fluctuates only with its writhe, <dTw^2> = <dWr^2>, not L/(4 pi^2 C). What is exact for the
model whatever the writhe: given the shape, the n joint angles are Gaussian (stiffness
g = C kT / b each, flat frame measure) on the plane sum(omega) = 2 pi (Lk - Wr), so their
deviations from the mean do not depend on the shape, and the difference of the two halves'
twists, dTw_half = (sum_{j < n/2} omega_j - sum_{j >= n/2} omega_j) / 2 pi, has
<dTw_half^2> = n b / (4 pi^2 C) = L / (4 pi^2 C) exactly (n even). That is the ring's
twist-persistence check (``twist_half_variance`` in the summary, with its theory value).

Run length and time scales (144-nm rings, b = 3 nm, zeta = 25 pN ns/nm per bead; measured
2026-12-01). Brownian dynamics alone is slow in two ways. (1) The rings' relative position:
the rings slide through each other only by moving as wholes, and a ring diffuses with
D = kT / (zeta_l L) = 3.4e-3 nm^2/ns, so crossing its radius (23 nm) takes ~39 us, ~3e6
steps of 12 ps; from a start in contact the rings stayed in contact (44-48 % of samples)
and from the start apart they touched in 0-2 % after 2e5 steps. (2) The rings' shapes and
writhes (slowest bending modes, ~1e4-1e5 steps; the 2026-12-01 alpha sweep had writhe
R-hat 1.4). Hence the Metropolis moves after every report interval (``rigid_moves``, cycled:
a relative shift of the rings, a turn of one ring about its centre, a crankshaft turn of an
arc of up to half a ring; :mod:`dnabraid.run.moves`), which keep the Boltzmann distribution
exactly and never change Lk_12 or Lk_i (a move that would is refused). With 10 moves per
100 steps the contact length's bulk ESS over 4 replicas x 8.8e4 steps rose from 13 to
1217 (workflows/results/benchmark_moves.txt); the single ring's <dTw_half^2> stays exact
(tests/test_catenane.py). ``rigid_moves = 0`` is plain Brownian dynamics (whose time
correlations are physical; the moves' are not).
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import numpy as np

from .. import forcefield
from ..chains import (
    ChainKit,
    Model,
)
from ..forces.chiral import default_exclusion
from ..forces.reference_chiral import chiral_energy_forces, default_subdivisions
from ..geometry.curves import crossing_angles, gauss_linking_number, writhe
from ..geometry.ribbon import ring_twist
from ..observables import Column, Observable
from ..run.driver import MAX_REPLICAS
from ..run.engine import MAX_SEED
from ..run.moves import RigidMoves
from ..run.states import Schedule
from ..units import TWO_PI
from .base import key, resolve_salt_alpha
from .thermal import ThermalScene
from .tweezer_base import PACK_HELP

__all__ = ["Catenane", "RingObservables", "ChiralEnergy", "hopf_start"]

_MECH = forcefield.mechanics()
#: Smallest number of beads per ring.
MIN_RING_BEADS = 12
#: Most beads per ring (time stays sane).
MAX_RING_BEADS = 2000


def hopf_start(n: int, bead_spacing_nm: float, rings: int = 2, link: int = 1,
               gap_nm: float | None = None) -> list:
    """Regular n-gons of side b: one in the xy plane about the origin; with ``rings = 2`` a
    second one in the xz plane, oriented so that the Gauss linking number is ``link``
    (+1 or -1). ``gap_nm`` None: ring 2 centred at (R, 0, 0), each ring through the other's
    centre (their closest points R apart, out of contact); else centred at
    (2 R - gap, 0, 0), so that ring 2 passes ``gap_nm`` inside ring 1's strand at (R, 0, 0),
    crossing it at right angles (a start in contact). The frames are added by the kit.

    Returns
    -------
    list of ndarray, shape (n, 3), nm
    """
    R = bead_spacing_nm / (2.0 * math.sin(math.pi / n))
    s = TWO_PI * np.arange(n) / n
    r1 = np.c_[R * np.cos(s), R * np.sin(s), np.zeros(n)]
    if rings == 1:
        return [r1]
    c = R if gap_nm is None else 2.0 * R - float(gap_nm)
    # half a bead step off the axes, so that no bead of one ring sits on the other's plane
    s2 = s + math.pi + (0.0 if gap_nm is None else math.pi / n)
    r2 = np.c_[c + R * np.cos(s2), np.zeros(n), R * np.sin(s2)]
    if round(gauss_linking_number(r1, r2)) != link:
        r2 = r2[::-1].copy()
    return [r1, r2]


def spread_ring(ring, min_dist_nm: float, angle_rad: float, rng, *, moves: int | None = None,
                tries: int = 200, other=None, other_gap_nm: tuple | None = None) -> np.ndarray:
    """A closed ring deformed by random crankshafts: ``moves`` (default: its bead count)
    arcs of 2 ... n/3 beads, each turned about the line through its two neighbours by an
    angle uniform in [-``angle_rad``, ``angle_rad``]; bond lengths are kept exactly, and a
    turn that brings two beads three or more apart along the ring within ``min_dist_nm`` is
    drawn again (at most ``tries`` times per move; then the ring keeps its last allowed
    shape). The result is non-planar, with a writhe that differs from replica to replica:
    starts that begin apart in the slowest coordinate, so that R-hat can see an unforgotten
    start. With ``other`` (the linked ring's beads), a turn must also keep the Gauss
    linking number of the two and their closest distance within ``other_gap_nm`` = (lo,
    hi): the start stays linked, and apart or in contact as it was built."""
    x = np.array(ring, float, copy=True)
    n = len(x)
    if other is not None:
        other = np.asarray(other, float)
        link = round(gauss_linking_number(x, other))
    sep = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    far = np.minimum(sep, n - sep) >= 3
    for _ in range(n if moves is None else int(moves)):
        for _ in range(tries):
            m = int(rng.integers(2, max(3, n // 3) + 1))
            i = int(rng.integers(n))
            arc = (i + np.arange(m)) % n
            a, b = x[(i - 1) % n], x[(i + m) % n]
            ax = b - a
            if np.linalg.norm(ax) < 1e-9:
                continue
            ax /= np.linalg.norm(ax)
            th = angle_rad * (2.0 * rng.random() - 1.0)
            v = x[arc] - a
            par = np.outer(v @ ax, ax)
            perp = v - par
            y = x.copy()
            y[arc] = a + par + perp * np.cos(th) + np.cross(ax, perp) * np.sin(th)
            d = np.linalg.norm(y[:, None] - y[None], axis=-1)
            if not np.all(d[far] > min_dist_nm):
                continue
            if other is not None:
                gap = np.linalg.norm(y[:, None] - other[None], axis=-1).min()
                if not other_gap_nm[0] <= gap <= other_gap_nm[1] or \
                        round(gauss_linking_number(y, other)) != link:
                    continue
            x = y
            break
    return x


def ring_tw_wr(ring_pos, side_pos) -> tuple[np.ndarray, float, float]:
    """(joint twist angles omega_j (rad, seam included), Tw, Wr) of one framed ring (turns)."""
    om = ring_twist(ring_pos, side_pos, per_joint=True)
    return om, float(np.sum(om)) / TWO_PI, writhe(ring_pos)


def _closed(p):
    return np.vstack([p, p[:1]])


class RingObservables(Observable):
    """Tw, Wr, Lk checks of every ring, Lk_12, contact length and braid angle (turns, nm, rad).

    Parameters
    ----------
    rings : list of int arrays
        Beads of each ring.
    sides : list of int arrays
        Side particle of each bond of each ring.
    delta_lk : int
        Every ring's linking number.
    link : int or None
        Gauss Lk_12 of the two rings (None for one ring).
    contact_nm : float
        Largest closest distance of two segments in contact.
    bead_spacing_nm : float
    """

    def __init__(self, rings, sides, delta_lk, link, contact_nm, bead_spacing_nm):
        self.rings = [np.asarray(r, int) for r in rings]
        self.sides = [np.asarray(s, int) for s in sides]
        self.lk = float(delta_lk)
        self.link = link
        self.contact = float(contact_nm)
        self.b = float(bead_spacing_nm)
        cols = {}
        for k in range(1, len(self.rings) + 1):
            cols[f"twist_{k}"] = Column("turns", f"Tw of ring {k} (joint angles / 2 pi, seam "
                                        "included)")
            cols[f"writhe_{k}"] = Column("turns", f"Wr of ring {k} (Gauss self-integral)",
                                         verdict=True)
            cols[f"dtw_half_{k}"] = Column("turns", f"Tw of ring {k}'s first half minus its "
                                           "second half; <dtw_half^2> = L / (4 pi^2 C) "
                                           "exactly", summarised=False)
        cols["lk_error"] = Column("turns", "max over rings of |Tw + Wr - delta_lk| (White's "
                                  "theorem; round-off unless the topology changed)",
                                  summarised=False)
        if len(self.rings) == 2:
            cols["lk12"] = Column("", "Gauss linking number of the two rings",
                                  summarised=False)
            cols["contact_length_nm"] = Column("nm", "b x ring-1 segments with a ring-2 "
                                               "segment closer than the contact distance",
                                               verdict=True)
            cols["braid_angle_rad"] = Column("rad", "contact-averaged folded braid angle eta "
                                             "(< 0 right-handed, folded into (-pi/2, pi/2]); "
                                             "NaN without contact", summarised=False)
        self.columns = cols

    def __call__(self, pos, ctx, values):
        out = {}
        err = 0.0
        for k, (r, s) in enumerate(zip(self.rings, self.sides), 1):
            om, tw, wr = ring_tw_wr(pos[r], pos[s])
            h = len(om) // 2
            out[f"twist_{k}"] = tw
            out[f"writhe_{k}"] = wr
            out[f"dtw_half_{k}"] = float(np.sum(om[:h]) - np.sum(om[h:2 * h])) / TWO_PI
            err = max(err, abs(tw + wr - self.lk))
        out["lk_error"] = err
        if len(self.rings) == 2:
            p1, p2 = pos[self.rings[0]], pos[self.rings[1]]
            out["lk12"] = gauss_linking_number(p1, p2)
            eta, _ = crossing_angles(_closed(p1), _closed(p2), self.contact)
            out["contact_length_nm"] = self.b * len(eta)
            out["braid_angle_rad"] = float(np.mean(eta)) if len(eta) else math.nan
        return out

    def check(self, values, ctx):
        if values["lk_error"] > 0.5:
            return (f"a ring's linking number changed: max |Tw + Wr - delta_lk| = "
                    f"{values['lk_error']:.3f} turns (delta_lk = {self.lk:g}): DNA passed "
                    "through itself or a joint's twist angle passed through pi")
        if self.link is not None and abs(values["lk12"] - self.link) > 0.5:
            return (f"the rings' linking number changed from {self.link:+d} to "
                    f"{values['lk12']:.3f}: one ring passed through the other (strand passage; "
                    "lower timestep_safety or the bead spacing)")
        return None


class ChiralEnergy(Observable):
    """The chiral term's energy (pN nm) from its numpy twin, every frame (0 at alpha = 0)."""

    every = "frame"

    def __init__(self, rings, alpha_pN, delta_nm, debye_nm, bead_spacing_nm):
        self.rings = [np.asarray(r, int) for r in rings]
        self.alpha = float(alpha_pN)
        self.kw = dict(delta_nm=delta_nm, debye_nm=debye_nm,
                       exclude_neighbours=default_exclusion(bead_spacing_nm, delta_nm, debye_nm),
                       subdivisions=default_subdivisions(bead_spacing_nm, delta_nm, debye_nm),
                       closed=True)
        self.columns = {"chiral_energy_pN_nm": Column("pN nm", "alpha tan(eta/2) summed over "
                                                      "contacts (numpy twin of the force)")}

    def __call__(self, pos, ctx, values):
        if self.alpha == 0.0:
            return {"chiral_energy_pN_nm": 0.0}
        e, _ = chiral_energy_forces(pos, self.rings, self.alpha, **self.kw)
        return {"chiral_energy_pN_nm": float(e)}


def _between(means) -> dict:
    """Mean and standard error (scatter of replica means / sqrt R) of per-replica values."""
    m = np.asarray([x for x in means if x is not None and np.isfinite(x)], float)
    if m.size == 0:
        return {"mean": None, "sem": None, "n_replicas": 0}
    sem = float(np.std(m, ddof=1) / math.sqrt(m.size)) if m.size > 1 else None
    return {"mean": float(m.mean()), "sem": sem, "n_replicas": int(m.size),
            "replica_means": [float(x) for x in m]}


@dataclasses.dataclass(frozen=True)
class Catenane(ThermalScene):
    """Two linked DNA minicircles (or one ring) at room temperature; keys in nm, pN, K."""

    name: ClassVar[str] = "catenane"
    help: ClassVar[str] = ("two linked DNA minicircles (Hopf link) at room temperature: "
                           "bending, twist with each ring's own linking number, excluded "
                           "volume and the chiral term; Tw, Wr, Lk_12, contact and braid angle")

    length_nm: float = key(144.0, "nm", "contour length of each ring (144 nm = 424 bp: "
                           "Delta/L = 0.02 at 1 M, the seed's slides 31-32)")
    salt_mM: float = key(1000.0, "mM", "monovalent salt; sets the effective DNA diameter "
                         "(Stigter 1977) and Debye length")
    bead_spacing_nm: float = key(3.0, "nm", "distance b between beads along a ring")
    rings: int = key(2, "", "2: two linked rings; 1: a single ring (twist checks)")
    link: int = key(1, "", "sign of the rings' Gauss linking number Lk_12 (+1 or -1; for "
                    "apolar DNA both orientations are the same Hopf link)")
    start: str = key("mixed", "", "'apart': each ring through the other's centre (strands R "
                     "apart); 'contact': ring 2's strand 1.3 diameters from ring 1's; 'mixed': "
                     "even replicas apart, odd ones in contact (starts far apart for the "
                     "between-replica convergence check)")
    start_spread: float = key(1.0, "rad", "each replica's rings start from the regular ones "
                              "('start') deformed by its own random crankshafts (largest angle "
                              "start_spread; bond lengths kept, no beads closer than the "
                              "diameter; two rings stay linked, and apart or in contact as "
                              "built): replicas begin apart in shape and writhe, so that R-hat "
                              "can see an unforgotten start. 0 = the regular rings for every "
                              "replica (replicas then share starts, and the verdict says so)")
    rigid_moves: int = key(10, "", "Metropolis moves after every report interval, cycling a "
                           "relative shift of the rings, a turn of one ring about its centre "
                           "and a crankshaft turn of an arc (dnabraid.run.moves); 0 = Brownian "
                           "dynamics alone, whose rings take ~3e6 steps to slide through each "
                           "other")
    move_shift_nm: float = key(8.0, "nm", "radius of the rings' relative shift (a ball)")
    move_angle_rad: float = key(0.3, "rad", "largest angle of a ring's turn about its centre")
    arc_angle_rad: float = key(0.5, "rad", "largest crankshaft angle (an arc of up to half a "
                               "ring turned about the line through its ends; 0 = none): the "
                               "rings' shapes and writhes, ~1e5 Brownian steps otherwise")
    delta_lk: int = key(0, "turns", "each ring's own linking number Delta Lk_i = Tw_i + Wr_i "
                        "(an integer: the model has no intrinsic helical twist, so a closed "
                        "ribbon's Lk is a whole number of turns)")
    persistence_nm: float = key(float(_MECH["persistence_nm"]), "nm",
                                "bending persistence length (forcefields/dna.toml)")
    twist_persistence_nm: float = key(float(_MECH["twist_persistence_nm"]), "nm",
                                      "twist persistence length C (50-100 nm for DNA)")
    alpha: float = key(0.0, "pN", "chiral strength alpha of phi = alpha tan(eta/2) (pN = pN "
                       "nm per nm of contact); 0 = no chiral term; 'salt' = the estimate at "
                       "salt_mM (forcefields/chiral.toml); > 0 favours right-handed contacts")
    contact_nm: float = key(0.0, "nm", "largest distance of two segments in contact (contact "
                            "length, braid angle); 0 = diameter + 2 Debye lengths")
    temperature_K: float = key(298.15, "K", "temperature")
    diameter_nm: float = key(0.0, "nm", "effective DNA diameter; 0 = from salt (Stigter 1977)")
    stretch_modulus_pN: float = key(float(_MECH["stretch_modulus_pN"]), "pN",
                                    "stretch modulus S (bond stiffness S/b)")
    stretch: str = key("bonds", "", "'bonds' (harmonic springs) or 'constraints' (rigid bonds)")
    steps: int = key(100000, "steps", "sampling steps per replica (after equilibration)")
    equilibration_steps: int = key(20000, "steps", "equilibration steps per replica")
    report_interval: int = key(100, "steps", "steps between observable samples")
    frame_interval: int = key(5000, "steps", "steps between trajectory frames (multiple of "
                              "report_interval)")
    seed: int = key(1, "", f"random seed (0 ... {MAX_SEED // MAX_REPLICAS})")
    replicas: int = key(2, "", "independent replicas (their scatter is the error bar)")
    workers: int = key(0, "", "processes running replicas at once; 0 = one per usable core")
    pack: int = key(0, "", PACK_HELP)
    timestep_safety: float = key(0.3, "", "time step = safety x 2 / (mobility x largest "
                                 "stiffness)")
    integrator: str = key("lm", "", "'lm' (Leimkuhler-Matthews: per-joint twist variance "
                          "within 1 % of b/C at the default step) or 'euler' (Euler-Maruyama: "
                          "+2 to +11 % measured) or 'mala' (Metropolis-adjusted steps: "
                          "no time-step bias at any step)")

    state_widths: ClassVar[dict] = {"delta_lk": 9, "alpha_pN": 9}

    # -- derived -----------------------------------------------------------------------
    @property
    def n_beads(self) -> int:
        """Beads per ring (= bonds per ring)."""
        return int(round(self.length_nm / self.bead_spacing_nm))

    @property
    def contact_distance_nm(self) -> float:
        if self.contact_nm > 0:
            return float(self.contact_nm)
        return self.effective_diameter_nm + 2.0 * forcefield.salt_parameters(self.salt_mM).debye_nm

    @property
    def start_of_replica(self) -> str:
        """'apart' or 'contact': with ``start = 'mixed'``, by the parity of the replica index
        (a replica's scene carries seed = base seed x MAX_REPLICAS + index)."""
        if self.start != "mixed":
            return self.start
        return "contact" if self.seed % MAX_REPLICAS % 2 else "apart"

    # -- keys ----------------------------------------------------------------------------
    @classmethod
    def resolve(cls, values: dict) -> dict:
        return resolve_salt_alpha(values, cls.salt_mM)

    def validate(self) -> None:
        need = self.need
        need(0 < self.salt_mM <= 5000, "salt_mM", "salt must be in (0, 5000] mM")
        need(self.bead_spacing_nm > 0, "bead_spacing_nm", "must be > 0")
        need(self.length_nm > 0, "length_nm", "must be > 0")
        need(abs(self.n_beads - self.length_nm / self.bead_spacing_nm) < 1e-6, "length_nm",
             f"must be a whole multiple of bead_spacing_nm={self.bead_spacing_nm}")
        need(self.n_beads >= MIN_RING_BEADS, "length_nm",
             f"gives {self.n_beads} beads per ring; need >= {MIN_RING_BEADS}")
        need(self.n_beads <= MAX_RING_BEADS, "length_nm",
             f"gives {self.n_beads} beads per ring (> {MAX_RING_BEADS}): too large")
        need(self.n_beads % 2 == 0, "length_nm",
             f"gives {self.n_beads} beads per ring; need an even number (the twist check "
             "compares the two halves of a ring)")
        need(self.rings in (1, 2), "rings", "must be 1 or 2")
        need(self.link in (1, -1), "link", "must be +1 or -1 (a Hopf link)")
        need(self.start in ("apart", "contact", "mixed"), "start",
             "allowed: 'apart', 'contact', 'mixed'")
        need(self.rigid_moves >= 0, "rigid_moves", "must be >= 0 (0 = none)")
        need(0 <= self.start_spread <= math.pi, "start_spread", "must be in [0, pi] rad")
        need(self.move_shift_nm >= 0, "move_shift_nm", "must be >= 0")
        need(0 <= self.move_angle_rad <= math.pi, "move_angle_rad", "must be in [0, pi]")
        need(0 <= self.arc_angle_rad <= math.pi, "arc_angle_rad", "must be in [0, pi]")
        need(self.rigid_moves == 0 or self.move_shift_nm > 0 or self.move_angle_rad > 0
             or self.arc_angle_rad > 0, "rigid_moves",
             "needs move_shift_nm, move_angle_rad or arc_angle_rad > 0")
        need(self.persistence_nm >= self.bead_spacing_nm, "persistence_nm",
             "must be >= bead_spacing_nm")
        need(self.bead_spacing_nm <= self.twist_persistence_nm <= 1000.0,
             "twist_persistence_nm", "must be in [bead_spacing_nm, 1000] nm (DNA: 50-100 nm)")
        need(abs(TWO_PI * self.delta_lk / self.n_beads) < math.pi / 4, "delta_lk",
             f"{self.delta_lk} turns over {self.n_beads} joints is more than 45 deg per "
             "joint: a bead chain cannot hold it (use more beads)")
        need(abs(self.delta_lk) <= 0.1 * self.length_nm / 3.4 + 1, "delta_lk",
             "|delta_lk| must be <= 10 % of the ring's helical turns (+1): sigma beyond "
             "that melts DNA")
        need(abs(self.alpha) <= 50.0, "alpha", "|alpha| must be <= 50 pN")
        need(150 <= self.temperature_K <= 400, "temperature_K", "must be in [150, 400] K")
        need(self.diameter_nm >= 0, "diameter_nm", "must be >= 0 (0 = from salt)")
        need(self.contact_nm >= 0, "contact_nm", "must be >= 0 (0 = diameter + 2 Debye)")
        need(self.stretch in ("bonds", "constraints"), "stretch",
             "allowed: 'bonds', 'constraints'")
        need(self.stretch_modulus_pN > 0, "stretch_modulus_pN", "must be > 0")
        self.check_run_keys()
        d = self.effective_diameter_nm
        R = self.length_nm / TWO_PI
        need(R > 2.0 * d, "length_nm", f"a ring of radius {R:.2f} nm cannot hold a linked ring "
             f"of diameter {d:.2f} nm (need L > 4 pi Delta = {4 * math.pi * d:.1f} nm)")
        self.check_passage_barrier()

    # -- build ---------------------------------------------------------------------------
    def build(self) -> Model:
        kit = ChainKit(self.dna())
        d = kit.dna
        gap = 1.3 * d.diameter_nm if self.start_of_replica == "contact" else None
        starts = hopf_start(self.n_beads, self.bead_spacing_nm, self.rings, self.link, gap)
        if self.start_spread > 0:
            rng = np.random.default_rng([self.seed, 17])
            if self.rings == 1:
                starts = [spread_ring(starts[0], d.diameter_nm, self.start_spread, rng)]
            else:
                # each ring in turn, the other held; linked, and as apart or in contact as
                # built: a contact start's closest distance kept within half a bead step
                # of its own, an apart start's above half of its own (R)
                g0 = float(np.linalg.norm(starts[0][:, None] - starts[1][None], axis=-1).min())
                band = (g0, g0 + 0.5 * self.bead_spacing_nm) if gap is not None \
                    else (0.5 * g0, np.inf)
                r1 = spread_ring(starts[0], d.diameter_nm, self.start_spread, rng,
                                 other=starts[1], other_gap_nm=band)
                r2 = spread_ring(starts[1], d.diameter_nm, self.start_spread, rng,
                                 other=r1, other_gap_nm=band)
                starts = [r1, r2]
            kit.exact_start = True  # minimising would take it back to the circles
        rings = [kit.add_chain(p, "AB"[k], closed=True, fixed_first=False)
                 for k, p in enumerate(starts)]
        kit.add_stretch(self.stretch)
        kit.add_bend()
        n_excl = kit.add_excluded_volume(dna_only=True)
        sides = [kit.add_ring_twist(r, self.twist_persistence_nm, delta_lk=self.delta_lk,
                                    chain_id="FG"[k]) for k, r in enumerate(rings)]
        if self.alpha != 0.0:
            # Kornyshev chiral term between facing segments, the rings closed (seam
            # segments included; packed replicas build one over every copy's rings)
            kit.add_chiral(self.alpha, rings, closed=True)
        kit.bound("stretch", "bend", "wca", "chiral", "twist_on_dna")
        kit.bound("frame", "twist")
        kit.sides = np.concatenate(sides)
        if self.rigid_moves and (self.rings == 2 or self.arc_angle_rad > 0):
            ring_idx = [np.asarray(r, int) for r in rings]
            side_idx = [np.asarray(sd, int) for sd in sides]
            two = self.rings == 2

            def same_topology(pos, kind, ri=ring_idx, si=side_idx, lk=self.delta_lk,
                              link=self.link):
                # no move may pass DNA through DNA or a joint's twist through pi: each ring's
                # Tw + Wr and the rings' Gauss linking number stay what they were
                if two and abs(gauss_linking_number(pos[ri[0]], pos[ri[1]]) - link) > 0.5:
                    return False
                if kind != "arc":  # a rigid motion keeps each ring's Tw and Wr
                    return True
                return all(abs(sum(ring_tw_wr(pos[r], pos[sd])[1:]) - lk) < 0.5
                           for r, sd in zip(ri, si))

            kit.moves = RigidMoves(
                [np.concatenate([r, sd]) for r, sd in zip(ring_idx, side_idx)], d.kT,
                shift_nm=self.move_shift_nm if two else 0.0,
                angle_rad=self.move_angle_rad if two else 0.0, pivots=ring_idx,
                allowed=same_topology, moves_per_call=self.rigid_moves, seed=self.seed,
                rings=list(zip(ring_idx, side_idx)), arc_angle_rad=self.arc_angle_rad)
        kit.rings = [np.asarray(r, int) for r in rings]
        kit.ring_sides = [np.asarray(s, int) for s in sides]
        g = self.twist_persistence_nm * d.kT / self.bead_spacing_nm
        params = {"n_exclusions": n_excl, "twist_g_pN_nm": g, "alpha_pN": self.alpha,
                  "beads_per_ring": self.n_beads, "length_bp": self.length_nm / 0.34,
                  "diameter_over_length": d.diameter_nm / self.length_nm,
                  "contact_distance_nm": self.contact_distance_nm}
        return kit.finish(safety=self.timestep_safety, params=params, length_nm=self.length_nm)

    def observables(self, model: Model) -> list:
        d = model.dna
        rings = model.rings
        return [RingObservables(rings, model.ring_sides, self.delta_lk,
                                self.link if self.rings == 2 else None,
                                self.contact_distance_nm, self.bead_spacing_nm),
                ChiralEnergy(rings, self.alpha, d.diameter_nm, d.debye_nm, d.bead_spacing_nm)]

    def states(self) -> Schedule:
        """One state, fixed by the keys (each ring's Delta Lk, alpha, Lk_12): equilibrate,
        then sample."""
        return Schedule.single(equilibration_steps=self.equilibration_steps,
                               sample_steps=self.steps, report_interval=self.report_interval)

    def state_of(self, segment) -> dict:
        return {"delta_lk": self.delta_lk, "alpha_pN": self.alpha}

    def notes(self, model: Model) -> list[str]:
        return [f"rings of {self.n_beads} beads ({self.length_nm / 0.34:.0f} bp), "
                f"Delta/L = {model.params['diameter_over_length']:.4f}; contact distance "
                f"{self.contact_distance_nm:.2f} nm"]

    # -- summary -------------------------------------------------------------------------
    def twist_half_variance_theory(self) -> float:
        """<dTw_half^2> = L / (4 pi^2 C) (turns^2), exact for the model (module docstring)."""
        return self.n_beads * self.bead_spacing_nm / (4 * math.pi**2 * self.twist_persistence_nm)

    def point_summary(self, segment, reps: list, columns: dict) -> dict:
        """The generic means, errors and verdict (writhes and contact length decide it),
        plus the ring checks: the half-twist variance against its exact value (no
        equilibration cut: squared fluctuations are chi^2-like, and the detector would cut
        their rare large values as a "transient", biasing the mean low; measured on a 144-nm
        ring: 0.0258 with detection, 0.0347 without, theory 0.0365), the between-replica
        variances, Lk conservation, contact fraction, the contact-averaged braid angle and
        the handedness it implies."""
        S = [s for s, _ in reps]
        pt = super().point_summary(segment, reps, columns)
        for k in range(1, self.rings + 1):
            pt[f"twist_half_variance_{k}"] = self.summarise(
                [s[f"dtw_half_{k}"] ** 2 for s in S], equilibration=None)
            pt[f"writhe_variance_{k}"] = _between([np.var(s[f"writhe_{k}"]) for s in S])
            pt[f"twist_variance_{k}"] = _between([np.var(s[f"twist_{k}"]) for s in S])
            pt[f"writhe_abs_{k}"] = self.summarise([np.abs(s[f"writhe_{k}"]) for s in S])
        pt["twist_half_variance_theory"] = self.twist_half_variance_theory()
        pt["lk_error_max"] = float(max(np.max(s["lk_error"]) for s in S))
        pt["lk_conserved"] = bool(pt["lk_error_max"] < 1e-6)
        if self.rings == 2:
            lk12 = np.concatenate([s["lk12"] for s in S])
            pt["lk12_min"], pt["lk12_max"] = float(lk12.min()), float(lk12.max())
            pt["lk12_conserved"] = bool(np.all(np.abs(lk12 - self.link) < 1e-6))
            pt["contact_fraction"] = _between([np.mean(s["contact_length_nm"] > 0) for s in S])
            # contact-averaged braid angle: per replica, over the samples in contact
            # (weighted by contact length), then mean and error across replicas
            per = []
            for s in S:
                w = s["contact_length_nm"]
                eta = s["braid_angle_rad"]
                ok = w > 0
                per.append(float(np.sum(w[ok] * eta[ok]) / np.sum(w[ok])) if ok.any()
                           else None)
            pt["braid_angle_rad"] = _between(per)
            pt["handedness"] = self.handedness(pt["braid_angle_rad"])
        return pt

    @staticmethod
    def handedness(eta: dict) -> str:
        """'right' (eta < 0), 'left' (eta > 0) when the mean braid angle is 2 standard errors
        from 0, else 'undetermined' (or 'no contact')."""
        if eta["mean"] is None:
            return "no contact"
        if eta["sem"] is None or abs(eta["mean"]) < 2.0 * eta["sem"]:
            return "undetermined"
        return "right" if eta["mean"] < 0 else "left"

    # -- CLI and sweeps ------------------------------------------------------------------
    def report(self, summary: dict, out: str, file) -> None:
        pt = summary["points"][0]

        def fmt(d, p=3):
            if d is None or d.get("mean") is None:
                return "-"
            sem = d.get("sem")
            return f"{d['mean']:.{p}f}" + (f" +- {sem:.{p}f}" if sem is not None else "")

        print(f"time step {summary['time_step_ps']:.4g} ps: {summary['time_step_reason']}",
              file=file)
        for n in summary["notes"]:
            print(f"note: {n}", file=file)
        print(f"delta_lk = {self.delta_lk:+d} per ring, alpha = {self.alpha:g} pN", file=file)
        for k in range(1, self.rings + 1):
            print(f"ring {k}: Tw = {fmt(pt[f'twist_{k}'])}, Wr = {fmt(pt[f'writhe_{k}'])} turns; "
                  f"<dTw_half^2> = {fmt(pt[f'twist_half_variance_{k}'], 4)} turns^2 (theory "
                  f"L/(4 pi^2 C) = {pt['twist_half_variance_theory']:.4f})", file=file)
        print(f"Tw + Wr = Lk_i: largest deviation {pt['lk_error_max']:.2e} turns", file=file)
        if self.rings == 2:
            print(f"Lk_12 stayed in [{pt['lk12_min']:.6f}, {pt['lk12_max']:.6f}]", file=file)
            print(f"contact length {fmt(pt['contact_length_nm'], 1)} nm (in contact "
                  f"{fmt(pt['contact_fraction'], 2)} of the time); braid angle "
                  f"{fmt(pt['braid_angle_rad'])} rad -> handedness {pt['handedness']}; chiral "
                  f"energy {fmt(pt['chiral_energy_pN_nm'], 2)} pN nm", file=file)
        mv = pt.get("rigid_moves")
        if mv:
            print("Metropolis moves accepted: " + ", ".join(
                f"{k} {mv[k]['acceptance']:.2f} of {mv[k]['attempted']}"
                for k in ("shift", "turn", "arc") if k in mv and mv[k]["attempted"]), file=file)
        print(f"converged: {pt['converged']} ({pt['convergence_reason']}); "
              "+- : standard error across independent replicas", file=file)
        print(f"wall time {summary['wall_time_s']:.1f} s on {summary['platform']}; results in "
              f"{out}/", file=file)

    row_columns: ClassVar[tuple] = ("delta_lk", "alpha_pN", "writhe_1", "writhe_1_sem",
                                    "writhe_2", "writhe_2_sem", "braid_angle_rad",
                                    "braid_angle_sem_rad", "handedness", "contact_length_nm",
                                    "lk_conserved", "lk12_conserved", "converged", "n_samples")

    def rows(self, summary: dict) -> list[dict]:
        pt = summary["points"][0]

        def g(c, f="mean"):
            return pt.get(c, {}).get(f) if isinstance(pt.get(c), dict) else None

        return [{"delta_lk": pt["delta_lk"], "alpha_pN": pt["alpha_pN"],
                 "writhe_1": g("writhe_1"), "writhe_1_sem": g("writhe_1", "sem"),
                 "writhe_2": g("writhe_2"), "writhe_2_sem": g("writhe_2", "sem"),
                 "braid_angle_rad": g("braid_angle_rad"),
                 "braid_angle_sem_rad": g("braid_angle_rad", "sem"),
                 "handedness": pt.get("handedness"),
                 "contact_length_nm": g("contact_length_nm"),
                 "lk_conserved": pt["lk_conserved"], "lk12_conserved": pt.get("lk12_conserved"),
                 "converged": pt["converged"], "n_samples": pt["n_samples"]}]

    def default_short_run(self) -> dict:
        return {"steps": 4000, "equilibration_steps": 1000, "frame_interval": 1000}
