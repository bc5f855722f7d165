"""Low-level pure geometry of bead chains (numpy only).

Used by forces, scenes and analysis alike; it imports nothing else from dnabraid, so
no force ever imports :mod:`dnabraid.analysis`.

* :mod:`.curves`: Gauss linking, writhe, catenation, crossing angles, bending.
* :mod:`.ribbon`: the framed chain as a ribbon: frames, parallel transport, twist,
  open-chain writhe and linking (Lk = Tw + Wr), plectonemes.
* :mod:`.starts`: starting conformations.
"""

from .starts import random_tether, random_wlc

__all__ = ["random_tether", "random_wlc"]
