"""Evaluate one OpenMM force on the Reference platform (double precision), for the tests."""

import numpy as np
import openmm
from openmm import unit as u

from dnabraid import units


def openmm_energy_forces(force, pos, n=None):
    """Energy (pN nm) and forces (pN, shape (n, 3)) of ``force`` at ``pos`` (nm)."""
    n = len(pos) if n is None else n
    system = openmm.System()
    for _ in range(n):
        system.addParticle(1.0)
    system.addForce(force)
    ctx = openmm.Context(system, openmm.VerletIntegrator(0.001),
                         openmm.Platform.getPlatformByName("Reference"))
    ctx.setPositions(pos * u.nanometer)
    st = ctx.getState(getEnergy=True, getForces=True)
    e = units.energy_from_openmm(st.getPotentialEnergy().value_in_unit(u.kilojoule_per_mole))
    f = units.force_from_openmm(
        st.getForces(asNumpy=True).value_in_unit(u.kilojoule_per_mole / u.nanometer))
    return e, np.asarray(f)
