"""Force factories: one module per physical term, each returning a named ``openmm.Force``.

Inputs are plain arrays and numbers in dnabraid units (nm, pN, pN nm); energies are
converted to OpenMM's kJ/mol here, once. Global parameters carry the force's name as a
prefix (``bend_kappa``, ``pull_f``, ``trap_angle``...) so a protocol can set exactly the
one it means. Every energy has a numpy twin in :mod:`dnabraid.forces.reference`
(the twist terms in :mod:`dnabraid.forces.reference_twist`).
"""

from .bonded import bending_force, stretch_force
from .contact import contact_exclusion_range, contact_force
from .excluded import wca_exclusions, wca_force
from .external import bead_exclusion_force, pull_force, trap_force, wall_force
from .twist_frames import frame_springs, twist_anchor_force, twist_bead_force, twist_force

__all__ = [
    "bending_force",
    "stretch_force",
    "wca_force",
    "wca_exclusions",
    "contact_force",
    "contact_exclusion_range",
    "wall_force",
    "pull_force",
    "trap_force",
    "bead_exclusion_force",
    "twist_force",
    "twist_anchor_force",
    "twist_bead_force",
    "frame_springs",
]
