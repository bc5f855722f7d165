"""Thin MDAnalysis ``AnalysisBase`` classes over :mod:`dnabraid.analysis.geometry`.

Reading a dnabraid trajectory
-----------------------------
The engine writes a PDB topology (``openmm.app.PDBFile``) and a DCD trajectory
(``openmm.app.DCDFile``); strand 1 is chain ``A``, strand 2 is chain ``B``, one residue
per bead, atom name ``C``, beads in order from the surface attachment to the magnetic
bead. Open them with ``MDAnalysis.Universe(pdb, dcd)``.

OpenMM writes the chain identifier into PDB column 22 and leaves the segment-identifier
columns 73-76 blank. MDAnalysis 2.11 reads column 22 into the ``chainIDs`` topology
attribute and, because the segid columns are blank, also uses the chain IDs as
``segids`` (checked with OpenMM 8.6.1 + MDAnalysis 2.11). Hence both
``u.select_atoms("chainID A")`` and ``u.select_atoms("segid A")`` pick strand 1; we use
``chainID`` (see :func:`select_strands`). Selections are ordered by atom index, which is
the bead order surface -> bead.

Units: MDAnalysis positions are in Angstrom; every result here is in nm (or rad, or
dimensionless turns), converted once with :data:`ANGSTROM_TO_NM`.
"""

from __future__ import annotations

import numpy as np
from MDAnalysis.analysis.base import AnalysisBase

from . import geometry, stats

__all__ = [
    "ANGSTROM_TO_NM",
    "BendingPersistence",
    "Catenation",
    "CrossingAngles",
    "Extension",
    "select_strands",
]

#: MDAnalysis length unit (Angstrom) in nm.
ANGSTROM_TO_NM = 0.1


def select_strands(universe, chains=("A", "B")):
    """Atom groups of the two strands of a dnabraid trajectory.

    Parameters
    ----------
    universe : MDAnalysis.Universe
        Universe built from the engine's PDB (+ DCD).
    chains : tuple of str, optional
        Chain IDs of strand 1 and strand 2.

    Returns
    -------
    tuple of AtomGroup
        ``(u.select_atoms("chainID A"), u.select_atoms("chainID B"))``.
    """
    groups = tuple(universe.select_atoms(f"chainID {c}") for c in chains)
    for c, g in zip(chains, groups):
        if len(g) == 0:
            raise ValueError(f"no atoms with chainID {c!r} in this universe")
    return groups


def _check_group(ag, name: str, min_atoms: int = 2):
    if not hasattr(ag, "positions") or not hasattr(ag, "universe"):
        raise TypeError(f"{name} must be an MDAnalysis AtomGroup; got {type(ag).__name__}")
    if len(ag) < min_atoms:
        raise ValueError(f"{name} needs at least {min_atoms} atoms; got {len(ag)}")


def _check_same_universe(ag1, ag2):
    if ag1.universe is not ag2.universe:
        raise ValueError("strand1_atoms and strand2_atoms must belong to the same Universe")


def _nm(ag) -> np.ndarray:
    """Positions of an AtomGroup in nm as float64, shape (n, 3)."""
    return ag.positions.astype(np.float64) * ANGSTROM_TO_NM


class Extension(AnalysisBase):
    """Tether extension: z of the last atom (bead attachment) minus a reference, per frame.

    Parameters
    ----------
    atomgroup : AtomGroup
        A strand, ordered surface -> bead; its last atom is the bead attachment.
    reference_z_nm : float, optional
        z of the surface in nm.

    Attributes
    ----------
    results.extension_nm : ndarray, shape (n_frames,)
        Extension in nm.
    results.mean, results.sem : float
        Mean extension and its autocorrelation-corrected SEM in nm
        (:func:`dnabraid.analysis.stats.mean_sem`, Sokal window).
    results.stats : dict
        The full :func:`~dnabraid.analysis.stats.mean_sem` output.
    """

    def __init__(self, atomgroup, reference_z_nm: float = 0.0, **kwargs):
        _check_group(atomgroup, "atomgroup", min_atoms=1)
        super().__init__(atomgroup.universe.trajectory, **kwargs)
        self._ag = atomgroup
        self._z0 = float(reference_z_nm)

    def _prepare(self):
        self.results.extension_nm = np.full(self.n_frames, np.nan)

    def _single_frame(self):
        z_nm = float(self._ag.positions[-1, 2]) * ANGSTROM_TO_NM
        self.results.extension_nm[self._frame_index] = z_nm - self._z0

    def _conclude(self):
        s = stats.mean_sem(self.results.extension_nm)
        self.results.stats = s
        self.results.mean = s["mean"]
        self.results.sem = s["sem"]


class Catenation(AnalysisBase):
    """Catenation number of two tethered strands per frame (:func:`geometry.catenation_number`).

    Positive for a right-handed braid; continuous across frames (no unwrapping needed).

    Parameters
    ----------
    strand1_atoms, strand2_atoms : AtomGroup
        The two strands, each ordered surface -> bead.

    Attributes
    ----------
    results.catenation : ndarray, shape (n_frames,)
        Catenation number (turns).
    results.mean, results.sem : float
        Mean and autocorrelation-corrected SEM (turns).
    """

    def __init__(self, strand1_atoms, strand2_atoms, **kwargs):
        _check_group(strand1_atoms, "strand1_atoms")
        _check_group(strand2_atoms, "strand2_atoms")
        _check_same_universe(strand1_atoms, strand2_atoms)
        super().__init__(strand1_atoms.universe.trajectory, **kwargs)
        self._s1, self._s2 = strand1_atoms, strand2_atoms

    def _prepare(self):
        self.results.catenation = np.full(self.n_frames, np.nan)

    def _single_frame(self):
        self.results.catenation[self._frame_index] = geometry.catenation_number(
            _nm(self._s1), _nm(self._s2)
        )

    def _conclude(self):
        s = stats.mean_sem(self.results.catenation)
        self.results.stats = s
        self.results.mean = s["mean"]
        self.results.sem = s["sem"]


class CrossingAngles(AnalysisBase):
    """Braid (crossing) angles between two strands (:func:`geometry.crossing_angles`).

    Sign convention: angle from t1 to t2 about the chord d1 from strand 1 to strand 2,
    folded into (-pi/2, pi/2]; a right-handed ply gives negative eta (= -2 x helix angle).

    Parameters
    ----------
    strand1_atoms, strand2_atoms : AtomGroup
        The two strands.
    cutoff_nm : float
        Largest closest-approach distance (nm) for a crossing to count.
    bins : int or array_like, optional
        Histogram bins (``np.histogram``); default 36 equal bins over [-pi/2, pi/2].

    Attributes
    ----------
    results.eta : ndarray, shape (k,)
        All braid angles in rad, concatenated over frames.
    results.distance_nm : ndarray, shape (k,)
        The corresponding closest distances in nm.
    results.frame_index : ndarray of int, shape (k,)
        Index (into the analysed frames) of the frame each angle comes from.
    results.histogram : tuple (bins, counts)
        ``bins`` the bin edges in rad, shape (nbins + 1,), and ``counts`` shape (nbins,).
    """

    def __init__(self, strand1_atoms, strand2_atoms, cutoff_nm: float, bins=36, **kwargs):
        _check_group(strand1_atoms, "strand1_atoms")
        _check_group(strand2_atoms, "strand2_atoms")
        _check_same_universe(strand1_atoms, strand2_atoms)
        cutoff_nm = float(cutoff_nm)
        if not cutoff_nm > 0.0:
            raise ValueError(f"cutoff_nm must be positive; got {cutoff_nm}")
        super().__init__(strand1_atoms.universe.trajectory, **kwargs)
        self._s1, self._s2 = strand1_atoms, strand2_atoms
        self._cutoff = cutoff_nm
        self._bins = bins

    def _prepare(self):
        self._eta, self._dist, self._frame = [], [], []

    def _single_frame(self):
        eta, dist = geometry.crossing_angles(_nm(self._s1), _nm(self._s2), self._cutoff)
        self._eta.append(eta)
        self._dist.append(dist)
        self._frame.append(np.full(eta.size, self._frame_index, dtype=int))

    def _conclude(self):
        self.results.eta = np.concatenate(self._eta) if self._eta else np.empty(0)
        self.results.distance_nm = np.concatenate(self._dist) if self._dist else np.empty(0)
        self.results.frame_index = (
            np.concatenate(self._frame) if self._frame else np.empty(0, dtype=int)
        )
        counts, edges = np.histogram(
            self.results.eta, bins=self._bins, range=(-0.5 * np.pi, 0.5 * np.pi)
        )
        self.results.histogram = (edges, counts)


class BendingPersistence(AnalysisBase):
    """Bending persistence length from bond-bond cosines, averaged over bonds and frames.

    ``Lp = -b / ln <cos>`` (:func:`geometry.persistence_length_from_cosines`), with ``b``
    the mean bond length. Only meaningful for a free worm-like chain; under tension or in
    a braid the result is an apparent, force-stiffened value.

    Parameters
    ----------
    strand_atoms : AtomGroup
        One strand (at least 3 beads).

    Attributes
    ----------
    results.mean_cos : float
        Mean cosine between consecutive bonds.
    results.mean_cos_per_frame : ndarray, shape (n_frames,)
    results.bond_length_nm : float
        Mean bond length in nm.
    results.persistence_nm : float
        Persistence length in nm (NaN if the mean cosine is not positive).
    """

    def __init__(self, strand_atoms, **kwargs):
        _check_group(strand_atoms, "strand_atoms", min_atoms=3)
        super().__init__(strand_atoms.universe.trajectory, **kwargs)
        self._ag = strand_atoms

    def _prepare(self):
        self.results.mean_cos_per_frame = np.full(self.n_frames, np.nan)
        self._bond_sum = np.zeros(self.n_frames)

    def _single_frame(self):
        x = _nm(self._ag)
        self.results.mean_cos_per_frame[self._frame_index] = geometry.bending_cosines(x).mean()
        self._bond_sum[self._frame_index] = geometry.bond_lengths(x).mean()

    def _conclude(self):
        self.results.mean_cos = float(np.mean(self.results.mean_cos_per_frame))
        self.results.bond_length_nm = float(np.mean(self._bond_sum))
        mc = self.results.mean_cos
        self.results.persistence_nm = (
            geometry.persistence_length_from_cosines(mc, self.results.bond_length_nm)
            if 0.0 < mc <= 1.0
            else float("nan")  # no exponential decay to fit
        )
