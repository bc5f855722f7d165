"""Excluded volume between DNA beads: the WCA (purely repulsive Lennard-Jones) potential."""

from __future__ import annotations

import math

import numpy as np
import openmm

from ..units import PN_NM_IN_KJ_MOL

WCA_RC_FACTOR = 2.0 ** (1.0 / 6.0)


def wca_exclusions(chains, bead_spacing_nm: float, sigma_nm: float, extra_pairs=()):
    """Pairs along a chain that do not interact.

    Beads k apart along a chain are excluded when k b < r_c + b/2 with r_c = 2^(1/6) sigma,
    i.e. pairs that a straight chain would already hold inside the WCA range; nearer pairs
    are kept apart by the bonds and the bending stiffness, and repelling them would
    stiffen the chain artificially.

    Parameters
    ----------
    chains : list of int arrays
    bead_spacing_nm, sigma_nm : float
    extra_pairs : iterable of (i, j)

    Returns
    -------
    list of (int, int)
    """
    rc = WCA_RC_FACTOR * sigma_nm
    m = max(1, int(math.ceil(rc / bead_spacing_nm + 0.5)) - 1)
    pairs = set()
    for chain in chains:
        chain = list(map(int, chain))
        for a in range(len(chain)):
            for k in range(1, m + 1):
                if a + k < len(chain):
                    i, j = chain[a], chain[a + k]
                    pairs.add((min(i, j), max(i, j)))
    for i, j in extra_pairs:
        pairs.add((min(int(i), int(j)), max(int(i), int(j))))
    return sorted(pairs)


def wca_force(n_particles: int, sigma_nm: float, epsilon_pN_nm: float, *, particles=None,
              exclusions=(), list_cutoff_factor: float = 2.5,
              name: str = "wca") -> openmm.CustomNonbondedForce:
    """WCA repulsion U = 4 eps [(s/r)^12 - (s/r)^6] + eps for r < 2^(1/6) s, else 0.

    The energy and its slope vanish at r_c = 2^(1/6) sigma. The force's own cutoff (the
    neighbour-list range) is ``list_cutoff_factor`` x sigma, larger than r_c, and the
    expression carries ``step(rc - r)``: OpenMM's list padding is a fraction of the
    cutoff, and a tiny cutoff makes it rebuild the list almost every Brownian step
    (measured 2-3x slower; see workflows/benchmark_engine.py).

    Parameters
    ----------
    n_particles : int
        Particles in the System (all get a slot; only ``particles`` interact).
    sigma_nm : float
        Effective DNA diameter.
    epsilon_pN_nm : float
        Usually kT.
    particles : array_like of int, optional
        Interacting particles (default: all).
    exclusions : iterable of (i, j)
    """
    rc = WCA_RC_FACTOR * sigma_nm
    expr = (f"step({name}_rc-r)*(4*{name}_eps*(sr6*sr6-sr6)+{name}_eps);"
            f"sr6=({name}_sigma/r)^6")
    if particles is not None:
        # A per-particle switch instead of an interaction group: OpenMM's CPU platform
        # evaluates interaction groups without its neighbour list (measured 7x slower for
        # a 800-bead twisted tether whose frame particles are left out).
        expr = "on1*on2*" + expr
    f = openmm.CustomNonbondedForce(expr)
    f.setName(name)
    f.addGlobalParameter(f"{name}_eps", float(epsilon_pN_nm) * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_sigma", float(sigma_nm))
    f.addGlobalParameter(f"{name}_rc", float(rc))
    f.setNonbondedMethod(openmm.CustomNonbondedForce.CutoffNonPeriodic)
    f.setCutoffDistance(max(list_cutoff_factor, WCA_RC_FACTOR) * sigma_nm)
    f.setUseSwitchingFunction(False)
    f.setUseLongRangeCorrection(False)
    parts = None if particles is None else set(map(int, np.asarray(particles).ravel()))
    if parts is not None:
        f.addPerParticleParameter("on")
    for k in range(n_particles):
        f.addParticle([] if parts is None else [1.0 if k in parts else 0.0])
    for i, j in exclusions:
        f.addExclusion(int(i), int(j))
    return f
