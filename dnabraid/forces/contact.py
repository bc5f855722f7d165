"""Hard-ish self-contact of an elastic rod: a stiff one-sided harmonic wall between beads."""

from __future__ import annotations

import math

import openmm

from ..units import PN_NM_IN_KJ_MOL


def contact_exclusion_range(thickness_nm: float, bead_spacing_nm: float) -> int:
    """Beads at most this many apart along the rod do not interact.

    A rod of radius h bent to radii >> h holds beads k apart at distance ~ k b, so pairs
    closer than ~2.5 h along the contour are neighbours, not contacts (Audoly et al. 2007, Eq. 3:
    "|s1 - s2| / h large enough to exclude neighbouring points").
    """
    return max(1, int(math.ceil(2.5 * thickness_nm / bead_spacing_nm)))


def contact_force(n_particles: int, thickness_nm: float, k_pN_per_nm: float, *,
                  exclusion_range: int, name: str = "contact") -> openmm.CustomNonbondedForce:
    """U = k/2 (2h - r)^2 for r < 2h between beads of a rod of radius h (0 beyond).

    The zero-temperature stand-in for the non-penetration condition |r(s1) - r(s2)| >= 2h
    (Audoly et al. 2007, Eq. 3): a penalty whose overlap under a contact force f is f / k. Beads
    closer than ``exclusion_range`` along the rod are excluded. Numpy twin:
    :func:`dnabraid.forces.reference.contact`.
    """
    d0 = 2.0 * float(thickness_nm)
    f = openmm.CustomNonbondedForce(f"0.5*{name}_k*({name}_d0-r)^2*step({name}_d0-r)")
    f.setName(name)
    f.addGlobalParameter(f"{name}_k", float(k_pN_per_nm) * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_d0", d0)
    f.setNonbondedMethod(openmm.CustomNonbondedForce.CutoffNonPeriodic)
    f.setCutoffDistance(d0)
    f.setUseSwitchingFunction(False)
    f.setUseLongRangeCorrection(False)
    for _ in range(n_particles):
        f.addParticle([])
    for i in range(n_particles):
        for j in range(i + 1, min(n_particles, i + exclusion_range + 1)):
            f.addExclusion(i, j)
    return f
