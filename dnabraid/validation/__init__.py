"""Validation of the bead model: zero-temperature cross-checks against the continuum theory
(:mod:`.crosscheck`) and the stiff-and-extreme case matrix (:mod:`.extremes`).

These modules run scenes end to end; nothing in the simulation layers imports them.
"""
