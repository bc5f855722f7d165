"""Compiled (numba) twins of the OpenMM energy terms, for Monte Carlo moves that need the
energy change of a few particles in microseconds instead of a whole-Context evaluation.

:class:`~dnabraid.kernels.chain.LocalEnergy` reproduces the terms of a bead chain
(harmonic bonds, bending hinges, WCA excluded volume, wall, pull) from a built
:class:`dnabraid.chains.Model`; :mod:`dnabraid.run.chain_moves` drives Metropolis
crankshaft, pivot and bead moves with it. :mod:`~dnabraid.kernels.twist` adds the terms of
torsionally constrained DNA (twist joints and clamps, frame springs, the bead's plane) and
the twist-aware move loop of :mod:`dnabraid.run.twist_moves`;
:mod:`~dnabraid.kernels.segment_terms` the segment-pair terms (the capsule contact between
strands and the chiral term).
"""

from .chain import TERMS, LocalEnergy

__all__ = ["LocalEnergy", "TERMS"]
