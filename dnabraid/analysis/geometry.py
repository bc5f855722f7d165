"""Pure-numpy chain geometry for analysis: re-exported from :mod:`dnabraid.geometry.curves`
(the geometry lives below the forces so that forces never import analysis)."""

from ..geometry.curves import *  # noqa: F401,F403
from ..geometry.curves import (  # noqa: F401
    __all__,
    as_points,
    gauss_sum,
    pair_solid_angles,
    triangle_solid_angle,
)
