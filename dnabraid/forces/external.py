"""External terms of the tweezer: the surface wall, the pulling force, the rotational trap."""

from __future__ import annotations

import numpy as np
import openmm

from ..units import PN_NM_IN_KJ_MOL


def wall_force(particles, z_wall_nm: float, k_pN_per_nm: float, *,
               name: str = "wall") -> openmm.CustomExternalForce:
    """One-sided harmonic wall U = k/2 (z_w - z)^2 for z < z_w (the surface)."""
    f = openmm.CustomExternalForce(
        f"0.5*{name}_k*({name}_z-z)^2*step({name}_z-z)")
    f.setName(name)
    f.addGlobalParameter(f"{name}_k", float(k_pN_per_nm) * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_z", float(z_wall_nm))
    for i in np.asarray(particles, dtype=int).ravel():
        f.addParticle(int(i), [])
    return f


def pull_force(particles, shares, force_pN: float, *, name: str = "pull") -> openmm.CustomExternalForce:
    """Constant force F along +z shared by ``particles``: U = -F share_i z_i.

    The magnetic force on the bead is transmitted to the DNA through its attachment
    points; ``shares`` (summing to 1) split it among them.
    """
    f = openmm.CustomExternalForce(f"-{name}_f*share*z")
    f.setName(name)
    f.addGlobalParameter(f"{name}_f", float(force_pN) * PN_NM_IN_KJ_MOL)
    f.addPerParticleParameter("share")
    for i, s in zip(np.asarray(particles, dtype=int).ravel(), np.asarray(shares, float).ravel()):
        f.addParticle(int(i), [float(s)])
    return f


def trap_force(p1: int, p2: int, stiffness_pN_nm: float, angle_rad: float = 0.0,
               tilt_k_pN_per_nm: float = 0.0, *, name: str = "trap") -> openmm.CustomCompoundBondForce:
    """Rotational magnetic trap on the bead axis u = r2 - r1 (the two attachment points).

    U = -K cos(phi - phi0) + k_tilt/2 (z2 - z1)^2, phi = atan2(u_y, u_x), written without
    atan2 as -K (u_x cos phi0 + u_y sin phi0) / |u_xy|. The torque about z the trap exerts
    on the bead is -dU/dphi = -K sin(phi - phi0); it is periodic in phi as a magnet is,
    the number of turns being kept by the history of phi0 (global ``<name>_angle``).
    The tilt term keeps the bead level, as the magnetic field does.
    """
    expr = (f"-{name}_K*(dx*cos({name}_angle)+dy*sin({name}_angle))/sqrt(dx*dx+dy*dy)"
            f"+0.5*{name}_ktilt*dz*dz;"
            "dx=x2-x1; dy=y2-y1; dz=z2-z1")
    f = openmm.CustomCompoundBondForce(2, expr)
    f.setName(name)
    f.addGlobalParameter(f"{name}_K", float(stiffness_pN_nm) * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_angle", float(angle_rad))
    f.addGlobalParameter(f"{name}_ktilt", float(tilt_k_pN_per_nm) * PN_NM_IN_KJ_MOL)
    f.addBond([int(p1), int(p2)], [])
    return f


def bead_exclusion_force(center: int, particles, radius_nm: float, k_pN_per_nm: float, *,
                         name: str = "beadwall") -> openmm.CustomBondForce:
    """Hard sphere of the magnetic bead: U = k/2 (R - r)^2 for r < R, r = |r_i - r_C|.

    One bond-like term (centre, DNA bead) per bead: a ``CustomBondForce`` needs no
    cutoff, and all nonbonded forces of a System must agree on cutoffs.
    """
    f = openmm.CustomBondForce(f"0.5*{name}_k*({name}_R-r)^2*step({name}_R-r)")
    f.setName(name)
    f.addGlobalParameter(f"{name}_k", float(k_pN_per_nm) * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_R", float(radius_nm))
    for i in np.asarray(particles, dtype=int).ravel():
        f.addBond(int(center), int(i), [])
    return f
