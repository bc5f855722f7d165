"""Bonded terms along a strand: stretching and bending."""

from __future__ import annotations

import numpy as np
import openmm

from ..units import PN_NM_IN_KJ_MOL


def stretch_force(bonds, k_pN_per_nm, r0_nm, *, name: str = "stretch") -> openmm.HarmonicBondForce:
    """Harmonic stretching U = k/2 (r - r0)^2 for each bond.

    Parameters
    ----------
    bonds : array_like of int, shape (n, 2)
    k_pN_per_nm : float or array_like, shape (n,)
        Spring constant; for DNA k = S / b with S the stretch modulus.
    r0_nm : float or array_like, shape (n,)
        Rest lengths.
    """
    bonds = np.asarray(bonds, dtype=int).reshape(-1, 2)
    k = np.broadcast_to(np.asarray(k_pN_per_nm, float), (len(bonds),))
    r0 = np.broadcast_to(np.asarray(r0_nm, float), (len(bonds),))
    f = openmm.HarmonicBondForce()
    f.setName(name)
    for (i, j), kk, rr in zip(bonds, k, r0):
        f.addBond(int(i), int(j), float(rr), float(kk) * PN_NM_IN_KJ_MOL)
    return f


def bending_force(triplets, kappa_pN_nm, *, name: str = "bend") -> openmm.CustomAngleForce:
    """Discrete worm-like-chain bending U = kappa (1 - cos beta) per hinge.

    beta = pi - theta is the angle between consecutive bonds, theta the OpenMM angle at
    the middle bead, so U = kappa (1 + cos theta). kappa follows from the persistence
    length through the exact mapping in :func:`dnabraid.forcefield.bending_stiffness_kT`.

    Parameters
    ----------
    triplets : array_like of int, shape (n, 3)
    kappa_pN_nm : float
        Hinge stiffness (global parameter ``<name>_kappa``, kJ/mol inside OpenMM).
    """
    triplets = np.asarray(triplets, dtype=int).reshape(-1, 3)
    f = openmm.CustomAngleForce(f"{name}_kappa*(1+cos(theta))")
    f.setName(name)
    f.addGlobalParameter(f"{name}_kappa", float(kappa_pN_nm) * PN_NM_IN_KJ_MOL)
    for i, j, k in triplets:
        f.addAngle(int(i), int(j), int(k), [])
    return f
