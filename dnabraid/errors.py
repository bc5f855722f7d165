"""The errors dnabraid raises on purpose: one base class, and one for bad input.

Every error the package raises deliberately derives from :class:`DnabraidError`. Errors that
mean "the input cannot be done" (an unknown key, a value out of range, a platform this
machine lacks, an output directory holding another run) derive from :class:`UserError`,
which is also a :class:`ValueError`; the command line prints those as one line without a
traceback. Numerical failures of a run (a blow-up, packed copies that could interact) derive
from :class:`DnabraidError` and :class:`RuntimeError`.
"""

from __future__ import annotations

__all__ = ["DnabraidError", "UserError"]


class DnabraidError(Exception):
    """Base of every error dnabraid raises on purpose."""


class UserError(DnabraidError, ValueError):
    """The input cannot be done as given; the message says what was expected and what came."""
