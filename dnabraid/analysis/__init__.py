"""Analysis: pure-numpy geometry, twist/writhe and statistics, plus thin MDAnalysis classes.

``geometry`` and ``stats`` depend only on numpy/scipy; the twist, writhe and plectoneme
functions come from :mod:`dnabraid.geometry.ribbon`. Not imported here (import the module):
``mda`` (MDAnalysis ``AnalysisBase`` subclasses), ``sweep_trajectories`` (MDAnalysis over a
sweep's points), ``handedness`` (sweep-row statistics), ``slow_modes`` (the linearised
bead-spring model of the slow modes), ``calibration`` (error-bar calibration statistics),
``convergence``, ``reweight``, ``maxwell``, ``mirror``.
"""

from ..geometry.ribbon import (
    find_plectonemes,
    linking_number,
    tether_twist,
    twist_angles,
    writhe_open,
)
from .geometry import (
    bending_cosines,
    bond_lengths,
    catenation_number,
    chord_angle,
    crossing_angles,
    extension,
    gauss_linking_number,
    persistence_length_from_cosines,
    unwrap_angle,
    writhe,
)

__all__ = [
    "bending_cosines",
    "bond_lengths",
    "catenation_number",
    "chord_angle",
    "crossing_angles",
    "extension",
    "gauss_linking_number",
    "persistence_length_from_cosines",
    "unwrap_angle",
    "writhe",
    "find_plectonemes",
    "linking_number",
    "tether_twist",
    "twist_angles",
    "writhe_open",
]
