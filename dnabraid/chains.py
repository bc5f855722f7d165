"""The chain force kit: bead chains of DNA (open or closed) and the terms every scene shares.

A scene makes a :class:`ChainKit` from typed :class:`DNAParameters`, adds its strands
(:meth:`ChainKit.add_chain`), the shared terms (stretch, bend, excluded volume, wall) and
then only its own attachments (tweezer bead, trap, frames) through
:meth:`ChainKit.add_particle` and :meth:`ChainKit.add_force`. Every term records its
largest relaxation rate (1/ns) so that :meth:`ChainKit.time_step` can choose the
Brownian time step from the stiffest mode; :meth:`ChainKit.finish` returns the
:class:`Model` the engine runs.

Relaxation-rate bounds (Euler-Maruyama is stable for dt < 2 / (mu lambda_max), mu the
mobility, lambda_max the largest Hessian eigenvalue): bonds 4 k (chain Laplacian; 2 k for a
bead against a fixed point), bending 16 kappa / b^2 (second difference squared), WCA contact
2 U''(sigma) = 2 x 456 eps / sigma^2, the wall U''. Rates of terms acting on the same
particles add (:meth:`ChainKit.bound`); the time step is ``safety`` x 2 / (largest sum).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import numpy as np
import openmm
import openmm.app as app

from . import forcefield, units
from .forces import bending_force, stretch_force, wall_force, wca_exclusions, wca_force

__all__ = ["DNAParameters", "ChainKit", "Model", "ForceRebuild", "TimeStep", "GROUPS",
           "passage_barrier_kT", "max_bead_spacing_nm", "MIN_PASSAGE_BARRIER_KT"]

#: Force groups, one per physical term, so blow-ups and benchmarks can name the term.
GROUPS = {"stretch": 0, "bend": 1, "wca": 2, "wall": 3, "pull": 4, "trap": 5, "link": 6,
          "beadwall": 7, "chiral": 8, "twist": 9, "frame": 10}

#: Ring frames (:meth:`ChainKit.add_ring_twist`): spring constant / bond spring constant and
#: side-particle friction / bead friction.
RING_FRAME_K_FRACTION = 0.2
RING_FRAME_FRICTION_FRACTION = 0.2

#: WCA curvature at contact, U''(sigma) = 456 eps / sigma^2 (4 eps [156 - 42] / sigma^2 ... at
#: r = sigma: 4 eps (12*13 - 6*7) / sigma^2 = 456 eps / sigma^2).
WCA_CONTACT_CURVATURE = 456.0


@dataclasses.dataclass(frozen=True)
class DNAParameters:
    """DNA's mechanics at one salt and temperature, as the bead model uses them.

    All lengths nm, forces pN, energies pN nm, frictions pN ns/nm.
    """

    kT: float
    temperature_K: float
    bead_spacing_nm: float
    persistence_nm: float
    kappa_kT: float
    stretch_modulus_pN: float
    diameter_nm: float
    debye_nm: float
    zeta_bead: float
    salt_mM: float

    @property
    def kappa(self) -> float:
        """Hinge stiffness kappa of kappa (1 - cos beta) (pN nm)."""
        return self.kappa_kT * self.kT

    @property
    def k_bond(self) -> float:
        """Bond spring constant S / b (pN/nm)."""
        return self.stretch_modulus_pN / self.bead_spacing_nm

    @property
    def wall_k(self) -> float:
        """Wall stiffness = U''_WCA(sigma): as stiff as bead contact (pN/nm)."""
        return WCA_CONTACT_CURVATURE * self.kT / self.diameter_nm**2

    @classmethod
    def make(cls, *, temperature_K: float, bead_spacing_nm: float, persistence_nm: float,
             stretch_modulus_pN: float, salt_mM: float, diameter_nm: float = 0.0
             ) -> DNAParameters:
        """From scene keys; ``diameter_nm = 0`` takes Stigter's diameter at ``salt_mM``."""
        salt = forcefield.salt_parameters(salt_mM)
        kT = units.kT(temperature_K)
        b = bead_spacing_nm
        zeta = units.stokes_friction(forcefield.mechanics()["hydrodynamic_radius_fraction"] * b)
        return cls(kT=kT, temperature_K=float(temperature_K), bead_spacing_nm=b,
                   persistence_nm=persistence_nm,
                   kappa_kT=forcefield.bending_stiffness_kT(b, persistence_nm),
                   stretch_modulus_pN=stretch_modulus_pN,
                   diameter_nm=float(diameter_nm) if diameter_nm > 0 else salt.diameter_nm,
                   debye_nm=salt.debye_nm, zeta_bead=zeta, salt_mM=salt_mM)


@dataclasses.dataclass(frozen=True)
class TimeStep:
    """The Brownian time step and why."""

    rates_per_ns: dict
    rate_max_per_ns: float
    stiffest_term: str
    time_step_ns: float
    reason: str


@dataclasses.dataclass(frozen=True)
class ForceRebuild:
    """How to build a force anew over several packed copies (a force OpenMM cannot copy,
    such as the chiral ``PythonForce``): ``make(chains)`` returns the force over ``chains``
    (one int array per strand, particle indices of one copy)."""

    make: Callable[[list], openmm.Force]
    chains: tuple


@dataclasses.dataclass
class Model:
    """A built scene: the OpenMM System plus the bookkeeping the run layer and observables
    need. It carries no scene: everything the run driver, engine, packing and moves use is
    a typed field here.

    Attributes
    ----------
    system : openmm.System
    topology : openmm.app.Topology
    positions : ndarray (N, 3), nm
    chains : list of int arrays (one per strand, surface -> bead)
    attachments : list of int (bead attachment particles)
    fixed : list of int (immobile particles)
    bonds : ndarray (n, 2) along the strands (checked for blow-ups)
    params : dict of derived numbers written to ``summary.json`` (kappa, k_bond, frictions,
        diameter, rates, time step ...)
    forces : dict name -> force group of the terms actually present
    sides : int array (n_bonds,) or None
        Side particle of each bond (torsionally constrained scenes only).
    bead_orientation : int or None
        The bead's orientation particle (torsionally constrained scenes only).
    dna : DNAParameters
    timestep : TimeStep
    length_nm : float
        Contour length of each strand (nm); with ``force_pN`` it sizes a packed copy's cell.
    force_pN : float
        Force pulling the strands (pN); 0 when nothing pulls.
    rebuild_forces : dict name -> ForceRebuild
        Forces that packing builds anew over every copy instead of copying.
    moves : dnabraid.run.moves.RigidMoves or None
        Metropolis moves the driver interleaves with the Brownian steps.
    exact_start : bool
        True when ``positions`` is a thermal draw, or a start spread on purpose, that
        minimising would undo: the run starts from it as it is.
    rings, ring_sides : list of int arrays
        Beads of each closed ring and the side particle of each of its bonds.
    bead_center : int or None
        The magnetic bead's centre particle (tweezer scenes with a bead).
    """

    system: openmm.System
    topology: app.Topology
    positions: np.ndarray
    chains: list
    attachments: list
    fixed: list
    bonds: np.ndarray
    params: dict
    forces: dict
    sides: np.ndarray | None = None
    bead_orientation: int | None = None
    dna: DNAParameters | None = None
    timestep: TimeStep | None = None
    length_nm: float = 0.0
    force_pN: float = 0.0
    rebuild_forces: dict = dataclasses.field(default_factory=dict)
    moves: object | None = None
    exact_start: bool = False
    rings: list = dataclasses.field(default_factory=list)
    ring_sides: list = dataclasses.field(default_factory=list)
    bead_center: int | None = None


class ChainKit:
    """Assemble an OpenMM System from bead chains and named force terms.

    Parameters
    ----------
    dna : DNAParameters
    """

    def __init__(self, dna: DNAParameters):
        self.dna = dna
        self.system = openmm.System()
        self.topology = app.Topology()
        self._pos: list = []
        self.chains: list = []
        self.closed: list = []
        self.present: dict = {}
        self.rates: dict = {}
        self._bounds: list = []
        self.fixed: list = []
        self.attachments: list = []
        self.sides = None
        self.bead_orientation = None
        self.bead_center: int | None = None
        self.rebuild_forces: dict = {}
        self.moves = None
        self.exact_start = False
        self.rings: list = []
        self.ring_sides: list = []
        self._ring_forces = None

    # -- particles ---------------------------------------------------------------------
    @property
    def n_particles(self) -> int:
        return self.system.getNumParticles()

    @property
    def positions(self) -> np.ndarray:
        return np.array(self._pos, float).reshape(-1, 3)

    def set_positions(self, idx, pos) -> None:
        for i, p in zip(np.atleast_1d(idx), np.atleast_2d(pos)):
            self._pos[int(i)] = tuple(map(float, p))

    def add_particle(self, chain_id: str, residue: str, atom: str, friction: float | None,
                     position, element=None) -> int:
        """One particle in its own chain/residue; ``friction`` None = immobile."""
        chain = self.topology.addChain(id=chain_id)
        return self._add(chain, residue, atom, friction, position, element)

    def add_particles(self, chain_id: str, residue: str, atom: str, friction: float | None,
                      positions) -> np.ndarray:
        """Several particles in one chain (a residue each), e.g. twist frame particles."""
        chain = self.topology.addChain(id=chain_id)
        return np.array([self._add(chain, residue, atom, friction, p)
                         for p in np.atleast_2d(positions)], int)

    def _add(self, chain, residue, atom, friction, position, element=None) -> int:
        res = self.topology.addResidue(residue, chain)
        # coarse-grained particles carry a placeholder element (DNA beads carbon, the others
        # iron): without one OpenMM writes "EP" and MDAnalysis warns on every load
        self.topology.addAtom(atom, element or app.element.iron, res)
        mass = 0.0 if friction is None else units.friction_to_mass_amu(friction)
        i = self.system.addParticle(mass)
        if friction is None:
            self.fixed.append(i)
        self._pos.append(tuple(map(float, position)))
        for f in self.system.getForces():  # per-particle forces need a slot for everyone
            if isinstance(f, openmm.CustomNonbondedForce):
                f.addParticle([0.0] * f.getNumPerParticleParameters())
        return i

    def add_chain(self, positions, chain_id: str, *, closed: bool = False,
                  fixed_first: bool = True, last_friction: float | None = None,
                  residue: str = "DNA") -> np.ndarray:
        """A strand of DNA beads at ``positions`` (n, 3) nm.

        ``fixed_first`` makes bead 0 immobile (a surface tether); ``last_friction`` gives
        the last bead another friction (an attachment). A ``closed`` chain is a ring:
        its last bead bonds to its first, and bending runs around it.
        """
        positions = np.asarray(positions, float)
        if closed and fixed_first:
            raise ValueError("a closed chain (ring) has no fixed tether bead")
        chain = self.topology.addChain(id=chain_id)
        idx = []
        n = len(positions)
        for i, p in enumerate(positions):
            if i == 0 and fixed_first:
                fr = None
            elif i == n - 1 and last_friction is not None:
                fr = last_friction
            else:
                fr = self.dna.zeta_bead
            idx.append(self._add(chain, residue, "C", fr, p, app.element.carbon))
        idx = np.array(idx, int)
        self.chains.append(idx)
        self.closed.append(bool(closed))
        return idx

    # -- topology helpers ----------------------------------------------------------------
    def bonds(self) -> np.ndarray:
        out = []
        for c, cl in zip(self.chains, self.closed):
            out += [(c[i], c[i + 1]) for i in range(len(c) - 1)]
            if cl:
                out.append((c[-1], c[0]))
        return np.array(out, int).reshape(-1, 2)

    def triplets(self) -> np.ndarray:
        out = []
        for c, cl in zip(self.chains, self.closed):
            n = len(c)
            rng = range(n) if cl else range(n - 2)
            out += [(c[i % n], c[(i + 1) % n], c[(i + 2) % n]) for i in rng]
        return np.array(out, int).reshape(-1, 3)

    def dna_particles(self) -> list:
        return [int(i) for c in self.chains for i in c]

    def mobile_dna(self) -> list:
        fixed = set(self.fixed)
        return [i for i in self.dna_particles() if i not in fixed]

    # -- forces --------------------------------------------------------------------------
    def add_force(self, force: openmm.Force, name: str, *, rate: float | None = None,
                  group: str | None = None) -> openmm.Force:
        """Add a named term (force group from :data:`GROUPS`); record its rate (1/ns)."""
        g = GROUPS[group or name]
        force.setForceGroup(g)
        self.system.addForce(force)
        if group is None:
            self.present[name] = g
        if rate is not None:
            self.rates[name] = float(rate)
        return force

    def bound(self, *terms) -> None:
        """Declare that the rates of ``terms`` (names or numbers) act on the same particles
        and add up; the time step uses the largest such sum."""
        self._bounds.append(terms)

    def add_stretch(self, mode: str = "bonds") -> None:
        """Harmonic bonds k = S / b, or rigid constraints (tether bonds stay springs:
        OpenMM cannot constrain an immobile particle)."""
        d = self.dna
        bonds = self.bonds()
        mu = 1.0 / d.zeta_bead
        if mode == "bonds":
            self.add_force(stretch_force(bonds, d.k_bond, d.bead_spacing_nm, name="stretch"),
                           "stretch", rate=4.0 * d.k_bond * mu)
            return
        if mode != "constraints":
            raise ValueError(f"stretch mode must be 'bonds' or 'constraints', got {mode!r}")
        fixed = set(self.fixed)
        springs = [(i, j) for i, j in bonds if int(i) in fixed or int(j) in fixed]
        self.add_force(stretch_force(springs, d.k_bond, d.bead_spacing_nm, name="stretch"),
                       "stretch", rate=2.0 * d.k_bond * mu)
        for i, j in bonds:
            if int(i) not in fixed and int(j) not in fixed:
                self.system.addConstraint(int(i), int(j), d.bead_spacing_nm)

    def add_bend(self) -> None:
        """Discrete WLC hinges kappa (1 - cos beta)."""
        d = self.dna
        self.add_force(bending_force(self.triplets(), d.kappa, name="bend"), "bend",
                       rate=16.0 * d.kappa / d.bead_spacing_nm**2 / d.zeta_bead)

    def add_excluded_volume(self, extra_exclusions=(), *, dna_only: bool = False) -> int:
        """WCA between DNA beads at the effective diameter; returns the exclusion count."""
        d = self.dna
        excl = wca_exclusions(self.chains, d.bead_spacing_nm, d.diameter_nm,
                              extra_pairs=extra_exclusions)
        for c, cl in zip(self.chains, self.closed):
            if cl:  # exclude near neighbours across the ring's seam too
                m = max(1, int(math.ceil(2 ** (1 / 6) * d.diameter_nm / d.bead_spacing_nm
                                         + 0.5)) - 1)
                n = len(c)
                for a in range(n):
                    for k in range(1, m + 1):
                        if a + k >= n:
                            i, j = int(c[a]), int(c[(a + k) % n])
                            excl.append((min(i, j), max(i, j)))
                excl = sorted(set(excl))
        self.add_force(wca_force(self.n_particles, d.diameter_nm, d.kT,
                                 particles=self.dna_particles() if dna_only else None,
                                 exclusions=excl, name="wca"), "wca",
                       rate=2.0 * WCA_CONTACT_CURVATURE * d.kT / d.diameter_nm**2 / d.zeta_bead)
        return len(excl)

    def add_ring_twist(self, ring, twist_persistence_nm: float, *, delta_lk: int = 0,
                       chain_id: str = "F", arm_fraction: float = 1.0,
                       friction_fraction: float = RING_FRAME_FRICTION_FRACTION,
                       k_fraction: float = RING_FRAME_K_FRACTION) -> np.ndarray:
        """Material frames and twist around a closed chain, closed with Lk = ``delta_lk``.

        One side particle per bond (:mod:`dnabraid.forces.twist_frames`; no excluded volume), at
        ``arm_fraction`` x b from its bead, friction ``friction_fraction`` x the bead's,
        held by frame springs of ``k_fraction`` x the bond stiffness. Stiffer springs than
        the plectoneme scene's (0.05): with those, a side particle of a 144-nm ring at
        b = 3 nm slid (once in ~1e6 steps) to |u| = 1.2 nm of its bond's axis, where the
        twist's stiffness g / |u|^2 outgrew the time step and the run blew up; with 0.2 the
        axial and radial wobble is ~0.3 nm. The heavier side particle keeps the frame rates
        below the beads' so the time step does not shrink. The frames start parallel-transported around the ring and turned evenly
        so that the ribbon's linking number Tw + Wr is ``delta_lk``
        (:func:`~dnabraid.geometry.ribbon.ring_side_positions`); the n twist joints include
        the seam, each with g = C kT / b, so that a free stretch of ring has
        <omega^2> = b / C per joint. Lk is conserved by the dynamics (a ring passing through
        itself, or a joint angle through pi, would change it: the scenes check it).
        Returns the side particles.
        """
        from .forces.twist_frames import frame_springs, ring_joints, twist_force
        from .geometry.ribbon import ring_side_positions

        ring = np.asarray(ring, int)
        if not any(len(c) == len(ring) and np.array_equal(c, ring) and cl
                   for c, cl in zip(self.chains, self.closed)):
            raise ValueError("add_ring_twist: the particles are not a closed chain of this kit "
                             "(add it with add_chain(..., closed=True) first)")
        for name, v in (("twist_persistence_nm", twist_persistence_nm),
                        ("arm_fraction", arm_fraction), ("k_fraction", k_fraction),
                        ("friction_fraction", friction_fraction)):
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"add_ring_twist: {name} must be finite and > 0, got {v!r}")
        d = self.dna
        b = d.bead_spacing_nm
        arm = arm_fraction * b
        zeta_f = friction_fraction * d.zeta_bead
        k_f = k_fraction * d.k_bond
        g = float(twist_persistence_nm) * d.kT / b
        side_pos = ring_side_positions(self.positions[ring], arm, delta_lk)
        sides = self.add_particles(chain_id, "FRM", "F", zeta_f, side_pos)
        springs = frame_springs(np.r_[ring, ring[:1]], sides, arm, b, k_f, name="frame")
        joints = twist_force(ring_joints(ring, sides), g, name="twist")
        if self._ring_forces is None:
            # one force per term for all rings (a Context compiles each custom force once)
            self._ring_forces = (self.add_force(springs, "frame"),
                                 self.add_force(joints, "twist"))
        else:
            f_springs, f_twist = self._ring_forces
            for k in range(springs.getNumBonds()):
                f_springs.addBond(*springs.getBondParameters(k))
            for k in range(joints.getNumBonds()):
                f_twist.addBond(*joints.getBondParameters(k))
        # the stiffest ring sets the rates (several rings may differ)
        for term, rate in (("frame", 4.0 * k_f / zeta_f),
                           ("twist", 6.0 * g / (arm * arm * zeta_f)),
                           # on the DNA beads: the frame springs' reaction 4 k_f and the
                           # twist through the tangents, bounded by 12 g / b^2 (three joints)
                           ("twist_on_dna", (4.0 * k_f + 12.0 * g / b**2) / d.zeta_bead)):
            self.rates[term] = max(rate, self.rates.get(term, 0.0))
        return sides

    def add_wall(self) -> None:
        """A wall at z = d/2 keeps mobile DNA above the surface."""
        d = self.dna
        self.add_force(wall_force(self.mobile_dna(), 0.5 * d.diameter_nm, d.wall_k, name="wall"),
                       "wall", rate=d.wall_k / d.zeta_bead)

    # -- time step and result ------------------------------------------------------------
    def time_step(self, safety: float) -> TimeStep:
        """Largest summed relaxation rate over the declared bounds, and dt = safety x 2/rate."""
        rates = dict(self.rates)
        totals = []
        for terms in self._bounds or [tuple(rates)]:
            totals.append(sum(t if isinstance(t, (int, float)) else rates.get(t, 0.0)
                              for t in terms))
        total = max(totals)
        stiff = max(rates, key=rates.get)
        dt_ns = safety * 2.0 / total
        reason = (f"stiffest term '{stiff}' (rate {rates[stiff]:.3g}/ns); summed bound "
                  f"{total:.3g}/ns; dt = {safety} x 2/rate = {dt_ns * 1e3:.4g} ps "
                  f"(Euler-Maruyama stability limit 2/rate = {2e3 / total:.4g} ps)")
        return TimeStep(rates, total, stiff, dt_ns, reason)

    def add_rebuildable_force(self, make, chains, name: str, *, rate: float | None = None
                              ) -> openmm.Force:
        """Add ``make(chains)`` as term ``name`` and remember how to build it over packed
        copies (:class:`ForceRebuild`): for forces OpenMM cannot copy."""
        chains = tuple(np.asarray(c, int).copy() for c in chains)
        self.rebuild_forces[name] = ForceRebuild(make, chains)
        return self.add_force(make(list(chains)), name, rate=rate)

    def add_chiral(self, alpha_pN: float, chains, *, closed: bool = False) -> openmm.Force:
        """The Kornyshev chiral term alpha tan(eta/2) per unit contact length between the
        facing segments of ``chains`` (:func:`dnabraid.forces.chiral.chiral_force`;
        docs/chirality.md), rebuilt over every copy when replicas are packed. Its weight is
        flat (1) up to the contact distance: the capsule contact's D_c where
        :meth:`add_capsule_contact` was called (with the two-ply calibration N(eta) of this
        bead spacing), else the effective diameter (uncalibrated, as the numpy twin the
        catenane scene reports). Its curvature
        per unit alpha is at most ~0.1 A / lambda_D^2 per nm of partner (A ~ 1/(2 Delta)),
        summed over ~2 Delta of partner and both ends: that bounds its rate."""
        from .forces.chiral import chiral_force

        d = self.dna
        capsules = getattr(self, "capsule_contact_nm", None) is not None
        contact = float(self.capsule_contact_nm) if capsules else d.diameter_nm

        def make(chs, d=d, alpha=float(alpha_pN), closed=bool(closed), contact=contact,
                 calibrate=capsules):
            return chiral_force(chs, alpha, delta_nm=contact, debye_nm=d.debye_nm,
                                bead_spacing_nm=d.bead_spacing_nm, closed=closed,
                                name="chiral", calibrate_two_ply=calibrate)

        return self.add_rebuildable_force(
            make, chains, "chiral",
            rate=abs(alpha_pN) * 0.1 / d.debye_nm**2 * 4.0 / d.zeta_bead)

    def add_capsule_contact(self, chains, *, contact_nm: float | None = None,
                            k_pN_per_nm: float | None = None) -> openmm.Force:
        """Capsule (segment-segment) excluded volume between different ``chains``
        (:func:`dnabraid.forces.segment_contact.capsule_force`): k/2 (D_c - d)^2 for
        d < D_c, d the closest distance of two segments. D_c defaults to the effective
        diameter, k to the bead contact's stiffness (``wall_k`` = U''_WCA(sigma)). The
        caller removes the bead WCA between these chains. Records ``capsule_contact_nm``,
        which :meth:`add_chiral` then uses as its contact distance. Rebuilt over packed
        copies (a PythonForce). Its rate: 2 k / zeta, as the WCA contact's."""
        from .forces.segment_contact import capsule_force

        d = self.dna
        D = float(contact_nm) if contact_nm is not None else d.diameter_nm
        k = float(k_pN_per_nm) if k_pN_per_nm is not None else d.wall_k
        self.capsule_contact_nm = D

        def make(chs, D=D, k=k):
            return capsule_force(chs, D, k, name="capsule")

        chains = tuple(np.asarray(c, int).copy() for c in chains)
        self.rebuild_forces["capsule"] = ForceRebuild(make, chains)
        # no group of its own in GROUPS: it shares the excluded volume's
        f = self.add_force(make(list(chains)), "capsule", rate=2.0 * k / d.zeta_bead,
                           group="wca")
        self.present["capsule"] = GROUPS["wca"]
        self.bound("stretch", "bend", "wca", "capsule", "chiral")
        return f

    def finish(self, *, safety: float, params=None, length_nm: float = 0.0,
               force_pN: float = 0.0) -> Model:
        """The :class:`Model`: the time step from the stiffest mode at ``safety``, the
        derived numbers (plus ``params``), and this kit's typed extras."""
        ts = self.time_step(safety)
        d = self.dna
        p = {
            "kT_pN_nm": d.kT,
            "kappa_kT": d.kappa_kT,
            "kappa_pN_nm": d.kappa,
            "k_bond_pN_per_nm": d.k_bond,
            "diameter_nm": d.diameter_nm,
            "zeta_dna_pN_ns_per_nm": d.zeta_bead,
            "debye_nm": d.debye_nm,
            "rates_per_ns": ts.rates_per_ns,
            "rate_max_per_ns": ts.rate_max_per_ns,
            "stiffest_term": ts.stiffest_term,
            "time_step_ns": ts.time_step_ns,
            "time_step_reason": ts.reason,
        }
        p.update(params or {})
        return Model(self.system, self.topology, self.positions, self.chains,
                     list(self.attachments), list(self.fixed), self.bonds(), p,
                     dict(self.present), self.sides, self.bead_orientation, d, ts,
                     length_nm=float(length_nm), force_pN=float(force_pN),
                     rebuild_forces=dict(self.rebuild_forces), moves=self.moves,
                     exact_start=bool(self.exact_start), rings=list(self.rings),
                     ring_sides=list(self.ring_sides), bead_center=self.bead_center)


# ------------------------------------------------------------------------- strand passage
#: Smallest barrier (in kT) against strand passage that a scene may have.
MIN_PASSAGE_BARRIER_KT = 20.0


def _wca_kT(r: float, sigma: float) -> float:
    if r >= 2 ** (1 / 6) * sigma:
        return 0.0
    sr6 = (sigma / r) ** 6
    return 4.0 * (sr6 * sr6 - sr6) + 1.0


@functools.lru_cache(maxsize=256)
def passage_barrier_kT(bead_spacing_nm: float, diameter_nm: float,
                       bond_k_kT_per_nm2: float | None = None) -> float:
    """Excluded-volume barrier (kT) against two strands passing through each other.

    Worst case: two bonds crossing at right angles through each other's midpoints. With
    rigid bonds the four inter-strand bead pairs are b / sqrt(2) apart, each costing the
    WCA energy (epsilon = kT, sigma = diameter). With harmonic bonds of stiffness k the
    two crossing bonds stretch to the length l that minimises
    E(l) = 2 (k/2) (l - b)^2 + 4 U_WCA(l / sqrt(2)), which lowers the barrier
    (default scene: about 108 kT instead of 682).

    Parameters
    ----------
    bead_spacing_nm, diameter_nm : float
    bond_k_kT_per_nm2 : float, optional
        Bond stiffness S / b in kT/nm^2; None for rigid bonds.
    """
    b = bead_spacing_nm
    rigid = 4.0 * _wca_kT(b / math.sqrt(2.0), diameter_nm)
    if bond_k_kT_per_nm2 is None:
        return rigid
    k = float(bond_k_kT_per_nm2)
    l_max = max(b, math.sqrt(2.0) * 2 ** (1 / 6) * diameter_nm)
    ls = np.linspace(b, l_max, 4001)
    e = [k * (x - b) ** 2 + 4.0 * _wca_kT(x / math.sqrt(2.0), diameter_nm) for x in ls]
    return float(min(min(e), rigid))


@functools.lru_cache(maxsize=256)
def max_bead_spacing_nm(diameter_nm: float, stretch_modulus_kT_per_nm: float | None = None,
                        ) -> float:
    """Largest bead spacing whose passage barrier is at least MIN_PASSAGE_BARRIER_KT
    (a bisection of ~60 barrier evaluations, ~0.7 s: memoised, being a pure function).

    ``stretch_modulus_kT_per_nm`` = S / kT (bonds of stiffness S / b); None = rigid bonds.
    """
    def barrier(b):
        k = None if stretch_modulus_kT_per_nm is None else stretch_modulus_kT_per_nm / b
        return passage_barrier_kT(b, diameter_nm, k)

    lo, hi = 1e-3 * diameter_nm, 10 * diameter_nm
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if barrier(mid) >= MIN_PASSAGE_BARRIER_KT:
            lo = mid
        else:
            hi = mid
    return lo
