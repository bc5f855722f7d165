"""Packed replicas: R non-interacting copies of one scene in one OpenMM System and Context.

OpenMM's CPU platform pays a fixed cost per step and force (~0.1 ms for the default braid's
83 particles, most of its step), so R small replicas in one Context cost far less than R
Contexts (measured 2.0x at R = 2, 2.3x at R = 4 replica-steps per second on one core;
``workflows/benchmark_replicas.py``). Each replica keeps its own start (built from its own
seed), observables, writers and blow-up checks (:func:`dnabraid.run.segments.run_members`);
only the integrator's random stream is shared, and it draws independent numbers for every particle,
so the copies stay statistically independent.

Layout: copy r sits at the x-y offset of cell r of a square grid of side ``spacing`` centred
on the origin (the CPU platform's nonbonded kernels are single precision), heights
unchanged. Bonded and external terms are copied with an index offset, so they never couple
copies; nonbonded terms (excluded volume) would, if two copies came within the cutoff: the
spacing leaves every copy's particles a margin of several thermal widths, and
:meth:`Pack.check_apart` is run at every sample, so a copy that strays out of its cell stops
the run with a clear error instead of interacting silently.

Global parameters (trap angle, force, stiffnesses) are shared: replicas of one point hold
the same values. A force that cannot be copied makes a scene unpackable (:func:`packable`;
it then runs one Context per replica) unless the model says how to build it over every
copy (``model.rebuild_forces``): the chiral ``PythonForce`` is built once over all
copies' strands, its own distance-based pair search never pairing two copies.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import openmm

from ..errors import DnabraidError

__all__ = ["replicate_system", "packable", "pack_models", "Pack", "PackError", "grid_offsets",
           "group_replicas"]


class PackError(DnabraidError, RuntimeError):
    """A packed copy left its cell (the copies could interact) or cannot be packed."""


_COPYABLE = ("HarmonicBondForce", "CustomBondForce", "CustomAngleForce", "CustomExternalForce",
             "CustomCompoundBondForce", "CustomNonbondedForce", "HarmonicAngleForce")


def packable(system: openmm.System, rebuild: dict | None = None) -> tuple[bool, str]:
    """Whether :func:`replicate_system` can copy every force of ``system`` (and why not);
    forces named in ``rebuild`` are built anew over all copies instead of copied."""
    for f in system.getForces():
        name = type(f).__name__
        if rebuild and f.getName() in rebuild:
            continue
        if name not in _COPYABLE:
            return False, f"force {f.getName()!r} ({name}) cannot be copied"
        if name == "CustomNonbondedForce" and f.getNumInteractionGroups():
            return False, f"force {f.getName()!r} uses interaction groups"
    return True, ""


def _clone(f: openmm.Force) -> openmm.Force:
    return openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(f))


def replicate_system(system: openmm.System, R: int, rebuild: dict | None = None
                     ) -> openmm.System:
    """R non-interacting copies of ``system``: particle i of copy r is i + r N.

    Bonded, angle, compound-bond and external terms are copied with the index offset; a
    ``CustomNonbondedForce`` gets every copy's particles (same per-particle parameters) and
    exclusions. Force groups, names and global parameters are kept (shared by the copies).
    ``rebuild`` maps a force's name to a :class:`dnabraid.chains.ForceRebuild`: that force
    (a ``PythonForce``, such as the chiral term) is made anew by ``rebuild.make(all_chains)``
    over every copy's chains (``rebuild.chains`` offset by r N), its own pair search keeping
    the copies apart.
    """
    ok, why = packable(system, rebuild)
    if not ok:
        raise PackError(f"cannot pack this system: {why}")
    R = int(R)
    N = system.getNumParticles()
    out = openmm.System()
    for r in range(R):
        for i in range(N):
            out.addParticle(system.getParticleMass(i))
    for r in range(R):
        for k in range(system.getNumConstraints()):
            i, j, d = system.getConstraintParameters(k)
            out.addConstraint(i + r * N, j + r * N, d)
    for f in system.getForces():
        if rebuild and f.getName() in rebuild:
            rb = rebuild[f.getName()]
            g = rb.make([np.asarray(c, int) + r * N for r in range(R) for c in rb.chains])
            g.setForceGroup(f.getForceGroup())
            out.addForce(g)
            continue
        g = _clone(f)
        name = type(f).__name__
        for r in range(1, R):
            o = r * N
            if name == "HarmonicBondForce":
                for k in range(f.getNumBonds()):
                    i, j, d, kk = f.getBondParameters(k)
                    g.addBond(i + o, j + o, d, kk)
            elif name == "CustomBondForce":
                for k in range(f.getNumBonds()):
                    i, j, p = f.getBondParameters(k)
                    g.addBond(i + o, j + o, p)
            elif name == "HarmonicAngleForce":
                for k in range(f.getNumAngles()):
                    i, j, m, a, kk = f.getAngleParameters(k)
                    g.addAngle(i + o, j + o, m + o, a, kk)
            elif name == "CustomAngleForce":
                for k in range(f.getNumAngles()):
                    i, j, m, p = f.getAngleParameters(k)
                    g.addAngle(i + o, j + o, m + o, p)
            elif name == "CustomExternalForce":
                for k in range(f.getNumParticles()):
                    i, p = f.getParticleParameters(k)
                    g.addParticle(i + o, p)
            elif name == "CustomCompoundBondForce":
                for k in range(f.getNumBonds()):
                    idx, p = f.getBondParameters(k)
                    g.addBond([i + o for i in idx], p)
            elif name == "CustomNonbondedForce":
                for k in range(N):
                    g.addParticle(f.getParticleParameters(k))
                for k in range(f.getNumExclusions()):
                    i, j = f.getExclusionParticles(k)
                    g.addExclusion(i + o, j + o)
        out.addForce(g)
    return out


def group_replicas(replicas, size: int, workers: int, platform: str, can_pack: bool
                   ) -> list[tuple]:
    """Replicas grouped into packs (one OpenMM Context each): ``size`` per group, or with
    ``size = 0`` as many as spread the replicas evenly over the workers (one worker off
    the CPU platform); one per group when the scene cannot be packed."""
    reps = list(replicas)
    if not can_pack:
        size = 1
    if size == 0:
        w = max(1, workers if platform == "CPU" else 1)
        size = max(1, math.ceil(len(reps) / w))
    return [tuple(reps[i:i + size]) for i in range(0, len(reps), size)]


def grid_offsets(R: int, spacing_nm: float) -> np.ndarray:
    """(R, 3) x-y offsets of a square grid of cells of side ``spacing_nm``, centred."""
    m = int(math.ceil(math.sqrt(R)))
    rows = int(math.ceil(R / m))
    ij = [(r % m, r // m) for r in range(R)]
    return np.array([[(i - 0.5 * (m - 1)) * spacing_nm, (j - 0.5 * (rows - 1)) * spacing_nm,
                      0.0] for i, j in ij])


def nonbonded_cutoff_nm(system: openmm.System) -> float:
    """The largest nonbonded cutoff of ``system`` (0 when it has no nonbonded term)."""
    cut = 0.0
    for f in system.getForces():
        if isinstance(f, openmm.CustomNonbondedForce):
            cut = max(cut, f.getCutoffDistance().value_in_unit(openmm.unit.nanometer))
    return cut


def interacting_particles(system: openmm.System) -> np.ndarray:
    """Mask of the particles that some nonbonded term lets interact: every particle of a
    ``CustomNonbondedForce`` unless its per-particle switch ``on`` is 0 (the WCA's) or it is
    in none of the force's interaction groups. Only these can make packed copies interact
    (the magnetic bead's centre, 500 nm above its strands and swinging by tens of nm, is
    bound to its own copy by bonds alone)."""
    n = system.getNumParticles()
    mask = np.zeros(n, bool)
    for f in system.getForces():
        if not isinstance(f, openmm.CustomNonbondedForce):
            continue
        if f.getNumInteractionGroups():
            for g in range(f.getNumInteractionGroups()):
                a, b = f.getInteractionGroupParameters(g)
                mask[list(a)] = True
                mask[list(b)] = True
        elif f.getNumPerParticleParameters() and f.getPerParticleParameterName(0) == "on":
            for k in range(n):
                if f.getParticleParameters(k)[0] != 0.0:
                    mask[k] = True
        else:
            mask[:] = True
    return mask


@dataclasses.dataclass
class Pack:
    """R copies of a model in one System.

    Attributes
    ----------
    model : dnabraid.chains.Model
        The packed model (its ``system`` holds the R copies, ``positions`` the copies at
        their offsets, ``bonds`` every copy's bonds); the engine runs it.
    members : list of Model
        The replicas' own models (indices 0 ... N-1), as built from their seeds.
    offsets : ndarray (R, 3), nm
    half_cell_nm : float
        A copy's interacting particles must stay within this x-y distance of its offset.
    interacting : ndarray of bool, shape (particles per copy,), or None
        The particles :meth:`check_apart` watches (:func:`interacting_particles`; None:
        all).
    """

    model: object
    members: list
    offsets: np.ndarray
    half_cell_nm: float
    interacting: np.ndarray | None = None

    @property
    def n_per_copy(self) -> int:
        return len(self.members[0].positions)

    def slice(self, r: int) -> slice:
        n = self.n_per_copy
        return slice(r * n, (r + 1) * n)

    def split(self, pos) -> list:
        """Each copy's positions in its own frame (offset removed)."""
        pos = np.asarray(pos, float)
        return [pos[self.slice(r)] - self.offsets[r] for r in range(len(self.members))]

    def join(self, positions: list) -> np.ndarray:
        """Packed positions from each copy's positions in its own frame."""
        return np.concatenate([np.asarray(p, float) + o for p, o in zip(positions,
                                                                      self.offsets)])

    def check_apart(self, split_positions: list) -> None:
        """Raise :class:`PackError` when a copy's interacting particles have left its cell
        (copies could interact)."""
        for r, p in enumerate(split_positions):
            p = np.asarray(p)
            if self.interacting is not None:
                p = p[self.interacting]
            if not len(p):
                continue
            reach = float(np.max(np.abs(p[:, :2])))
            if reach > self.half_cell_nm:
                raise PackError(
                    f"packed replica {r} reached {reach:.0f} nm from its cell centre (cell "
                    f"half-width {self.half_cell_nm:.0f} nm less the cutoff): packed copies "
                    "could interact. Run with pack = 1 (one Context per replica)")


def pack_models(members: list, *, spacing_nm: float | None = None,
                reach_nm: float | None = None, line: bool = False) -> Pack:
    """Pack the replicas' models (same scene but seed) into one :class:`Pack`.

    ``line``: copies along x only (offsets with y = z = 0), so that the y -> -y mirror of
    the packed System is the pack of the mirrored copies, exactly: mirror-coupled pairs
    (:mod:`dnabraid.analysis.mirror`) pack this way.

    ``reach_nm``: how far in x-y a copy's particles may go from its origin (default: its
    start's extent plus 8 thermal widths of the pivot, sqrt(kT L / F), and 20 nm, at most
    the contour length plus the start's extent); the cells are 2 reach + cutoff wide.
    """
    m0 = members[0]
    dt = {round(m.timestep.time_step_ns, 15) for m in members}
    if len(dt) != 1:
        raise PackError(f"replicas to pack have different time steps {sorted(dt)}")
    n = {len(m.positions) for m in members}
    if len(n) != 1:
        raise PackError("replicas to pack have different particle counts")
    cut = nonbonded_cutoff_nm(m0.system)
    if reach_nm is None:
        ext = max(float(np.max(np.abs(m.positions[:, :2]))) for m in members)
        L, F, kT = m0.length_nm, m0.force_pN, m0.dna.kT
        thermal = 8.0 * math.sqrt(kT * L / F) + 20.0 if F > 0 else L
        reach_nm = ext + min(L, thermal) if L > 0 else ext + 50.0
    spacing = spacing_nm if spacing_nm is not None else 2.0 * reach_nm + cut
    if line:
        offsets = np.array([[(r - 0.5 * (len(members) - 1)) * spacing, 0.0, 0.0]
                            for r in range(len(members))])
    else:
        offsets = grid_offsets(len(members), spacing)
    system = replicate_system(m0.system, len(members), m0.rebuild_forces)
    N = len(m0.positions)
    bonds = np.concatenate([m.bonds + r * N for r, m in enumerate(members)]) \
        if len(m0.bonds) else m0.bonds
    packed = dataclasses.replace(
        m0, system=system, positions=np.concatenate([m.positions + o for m, o in
                                                     zip(members, offsets)]),
        bonds=bonds)
    return Pack(model=packed, members=list(members), offsets=offsets,
                half_cell_nm=0.5 * spacing - 0.5 * cut,
                interacting=interacting_particles(m0.system))
