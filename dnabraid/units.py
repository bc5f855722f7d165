"""Units: the one place where physical units are converted and stripped.

dnabraid works internally in plain floats with

* length in nm, force in pN, energy in pN nm, torque in pN nm, time in ns,
  salt in mM, temperature in K, friction in pN ns / nm.

OpenMM works in nm, ps, kJ/mol and amu; the helpers below convert between the two.
Inputs may be ``openmm.unit.Quantity`` objects or bare numbers in the documented unit.
"""

from __future__ import annotations

import math

#: Boltzmann constant in pN nm / K (CODATA 2018: 1.380649e-23 J/K).
KB_PN_NM = 1.380649e-2
#: Avogadro constant (CODATA 2018), 1/mol.
AVOGADRO = 6.02214076e23
#: 1 pN nm expressed in kJ/mol.
PN_NM_IN_KJ_MOL = 1e-21 * AVOGADRO / 1e3  # = 0.602214...
#: 1 pN ns / nm expressed in amu / ps (OpenMM's mass x friction unit).
PN_NS_PER_NM_IN_AMU_PER_PS = 1e-12 / (1.66053906660e-27 / 1e-12)  # = 602.214...
#: Viscosity of water at 25 C in pN ns / nm^2 (0.89 mPa s).
WATER_VISCOSITY_PN_NS_NM2 = 0.89
#: One turn in radians (every module that converts turns to angles uses this one).
TWO_PI = 2.0 * math.pi


def kT(temperature_K: float) -> float:
    """Thermal energy in pN nm at ``temperature_K``."""
    return KB_PN_NM * float(temperature_K)


def energy_to_openmm(e_pn_nm: float) -> float:
    """pN nm -> kJ/mol."""
    return e_pn_nm * PN_NM_IN_KJ_MOL


def energy_from_openmm(e_kj_mol: float) -> float:
    """kJ/mol -> pN nm."""
    return e_kj_mol / PN_NM_IN_KJ_MOL


def force_to_openmm(f_pn: float) -> float:
    """pN -> kJ/mol/nm."""
    return f_pn * PN_NM_IN_KJ_MOL


def force_from_openmm(f_kj_mol_nm):
    """kJ/mol/nm -> pN (works on arrays)."""
    return f_kj_mol_nm / PN_NM_IN_KJ_MOL


def ns_to_ps(t_ns: float) -> float:
    return t_ns * 1e3


def stokes_friction(radius_nm: float, viscosity=WATER_VISCOSITY_PN_NS_NM2) -> float:
    """Stokes friction 6 pi eta a of a sphere, in pN ns / nm."""
    return 6.0 * math.pi * viscosity * radius_nm


def friction_to_mass_amu(zeta_pn_ns_nm: float, gamma_per_ps: float = 1.0) -> float:
    """Mass (amu) that gives friction ``zeta`` in OpenMM's BrownianIntegrator.

    OpenMM's Brownian integrator moves particle i with diffusion D = kT / (m_i gamma);
    with a global gamma, the particle mass carries the per-particle friction.
    """
    return zeta_pn_ns_nm * PN_NS_PER_NM_IN_AMU_PER_PS / gamma_per_ps


def strip(value, unit, name: str = "value") -> float:
    """Return ``value`` as a float in ``unit`` (an ``openmm.unit.Unit``).

    A bare number is taken to be in ``unit`` already. Raises ``TypeError`` for a
    quantity whose unit is incompatible.
    """
    try:
        from openmm import unit as u
    except ImportError:  # pragma: no cover
        return float(value)
    if isinstance(value, u.Quantity):
        if not value.unit.is_compatible(unit):
            raise TypeError(f"{name}: expected a quantity compatible with {unit}, got {value.unit}")
        return float(value.value_in_unit(unit))
    return float(value)
