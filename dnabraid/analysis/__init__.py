"""Analysis: pure-numpy geometry, twist/writhe and statistics, plus thin MDAnalysis classes.

``geometry`` and ``stats`` depend only on numpy/scipy; ``mda`` (MDAnalysis
``AnalysisBase`` subclasses) is imported lazily so the pure functions stay cheap.
"""

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
from .twist import (
    find_plectonemes,
    linking_number,
    tether_twist,
    twist_angles,
    writhe_open,
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
