"""Twist, writhe and plectonemes for analysis: re-exported from :mod:`dnabraid.geometry.twist`
(the geometry lives below the forces so that forces never import analysis)."""

from ..geometry.twist import *  # noqa: F401,F403
from ..geometry.twist import X, Z, __all__  # noqa: F401
