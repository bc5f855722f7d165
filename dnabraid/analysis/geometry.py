"""Pure-numpy chain geometry for analysis: re-exported from :mod:`dnabraid.geometry.curves`
(the geometry lives below the forces so that forces never import analysis)."""

from ..geometry.curves import *  # noqa: F401,F403
from ..geometry.curves import (  # noqa: F401
    __all__,
    _as_points,
    _gauss_sum,
    _pair_solid_angles,
    _triangle_solid_angle,
)
