"""dnabraid: coarse-grained DNA braids on OpenMM, cross-checked against elastic-rod theory."""

import logging

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())
