"""Analysis: pure-numpy geometry and statistics, plus thin MDAnalysis classes.

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
]
