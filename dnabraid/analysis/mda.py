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

from ..geometry import ribbon as _twist
from . import geometry, stats

__all__ = [
    "ANGSTROM_TO_NM",
    "BendingPersistence",
    "Catenation",
    "CrossingAngles",
    "Extension",
    "Plectonemes",
    "RingLinking",
    "RingWrithe",
    "TwistWrithe",
    "select_rings",
    "select_strands",
    "select_twisted_tether",
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


def select_twisted_tether(universe):
    """Atom groups of a twisted tether (plectoneme scene): DNA (residues ``DNA``), side
    particles (``FRM``, one per bond) and the bead's orientation particle (``BEO``).

    Selected by residue name: OpenMM's PDB writer renames chains A, B, C... in order.
    """
    groups = tuple(universe.select_atoms(f"resname {c}") for c in ("DNA", "FRM", "BEO"))
    for c, g in zip(("DNA", "FRM", "BEO"), groups):
        if len(g) == 0:
            raise ValueError(f"no atoms with resname {c!r}: not a plectoneme trajectory")
    return groups


class TwistWrithe(AnalysisBase):
    """Twist, writhe and linking number of a twisted tether, per frame.

    Tw includes the surface clamp (+z, +x) and the bead clamp (+z, horizontal part of the
    bead orientation vector); Wr closes the chain by vertical rays
    (:mod:`dnabraid.geometry.ribbon`). Lk = Tw + Wr equals the bead's turns.

    Parameters
    ----------
    dna_atoms, side_atoms, bead_orientation_atoms : AtomGroup
        From :func:`select_twisted_tether`; ``len(side_atoms) == len(dna_atoms) - 1``.

    Attributes
    ----------
    results.twist, results.writhe, results.linking : ndarray, shape (n_frames,)
        Turns.
    results.twist_torque_pN_nm : ndarray, shape (n_frames,), only with ``twist_persistence_nm``
        and ``kT_pN_nm`` given: 2 pi Tw C kT / L with L the rest contour length.
    """

    def __init__(self, dna_atoms, side_atoms, bead_orientation_atoms, *,
                 twist_persistence_nm=None, kT_pN_nm=None, contour_nm=None, **kwargs):
        _check_group(dna_atoms, "dna_atoms", min_atoms=3)
        _check_group(side_atoms, "side_atoms")
        _check_group(bead_orientation_atoms, "bead_orientation_atoms", min_atoms=1)
        if len(side_atoms) != len(dna_atoms) - 1:
            raise ValueError(f"need one side particle per bond: {len(dna_atoms) - 1}; got "
                             f"{len(side_atoms)}")
        super().__init__(dna_atoms.universe.trajectory, **kwargs)
        self._dna, self._sides, self._bead = dna_atoms, side_atoms, bead_orientation_atoms
        self._C, self._kT, self._L = twist_persistence_nm, kT_pN_nm, contour_nm

    def _prepare(self):
        self.results.twist = np.full(self.n_frames, np.nan)
        self.results.writhe = np.full(self.n_frames, np.nan)

    def _single_frame(self):
        x = _nm(self._dna)
        bead = _nm(self._bead)[0] - x[-1]
        i = self._frame_index
        self.results.twist[i] = _twist.tether_twist(x, _nm(self._sides), bead)
        self.results.writhe[i] = _twist.writhe_open(x)

    def _conclude(self):
        self.results.linking = self.results.twist + self.results.writhe
        if self._C is not None and self._kT is not None:
            L = self._L
            if L is None:
                L = float(np.sum(geometry.bond_lengths(_nm(self._dna))))
            self.results.twist_torque_pN_nm = (2 * np.pi * self._C * self._kT / L
                                               * self.results.twist)


class Plectonemes(AnalysisBase):
    """Plectonemes per frame (:func:`dnabraid.geometry.ribbon.find_plectonemes`).

    Parameters
    ----------
    dna_atoms : AtomGroup
    **finder : keyword arguments of ``find_plectonemes`` (contact_nm, min_separation_nm,
        tip_tolerance_nm, min_length_nm); other keywords go to AnalysisBase.

    Attributes
    ----------
    results.count : ndarray of int, shape (n_frames,)
    results.length_nm : ndarray, shape (n_frames,)
        DNA in plectonemes.
    results.tip_nm : ndarray, shape (n_frames,)
        Tip (contour position from the first bead) of the longest; NaN without one.
    results.plectonemes : list of lists of Plectoneme
    results.fraction : float
        Fraction of frames with at least one plectoneme.
    """

    _FINDER = ("contact_nm", "min_separation_nm", "tip_tolerance_nm", "min_length_nm")

    def __init__(self, dna_atoms, **kwargs):
        _check_group(dna_atoms, "dna_atoms", min_atoms=3)
        self._kw = {k: kwargs.pop(k) for k in self._FINDER if k in kwargs}
        super().__init__(dna_atoms.universe.trajectory, **kwargs)
        self._dna = dna_atoms

    def _prepare(self):
        self.results.count = np.zeros(self.n_frames, dtype=int)
        self.results.length_nm = np.zeros(self.n_frames)
        self.results.tip_nm = np.full(self.n_frames, np.nan)
        self.results.plectonemes = [None] * self.n_frames

    def _single_frame(self):
        pl = _twist.find_plectonemes(_nm(self._dna), **self._kw)
        i = self._frame_index
        self.results.plectonemes[i] = pl
        self.results.count[i] = len(pl)
        if pl:
            self.results.length_nm[i] = sum(q.length_nm for q in pl)
            self.results.tip_nm[i] = max(pl, key=lambda q: q.length_nm).tip_nm

    def _conclude(self):
        self.results.fraction = float(np.mean(self.results.count > 0)) if self.n_frames else 0.0


# ----------------------------------------------------------------------------- closed rings
def select_rings(universe):
    """Beads and side particles of each ring of a catenane trajectory.

    The catenane scene adds ring 1, ring 2 (residues ``DNA``) and then the side particles of
    ring 1, ring 2 (residues ``FRM``), each as its own chain; OpenMM's PDB writer renames
    the chains A, B, C, D in that order. Returns ``(rings, sides)``: two lists of AtomGroups
    (one per ring; ``sides`` empty when the trajectory has no frames).
    """
    rings, sides = [], []
    ids: list = []
    for c in universe.atoms.chainIDs:
        if c not in ids:
            ids.append(c)
    for c in ids:
        ag = universe.select_atoms(f"chainID {c}")
        names = set(ag.resnames)
        if names == {"DNA"}:
            rings.append(ag)
        elif names == {"FRM"}:
            sides.append(ag)
    if not rings:
        raise ValueError("no chains of resname 'DNA' in this universe: not a ring trajectory")
    if sides and len(sides) != len(rings):
        raise ValueError(f"{len(rings)} rings but {len(sides)} chains of side particles")
    return rings, sides


class RingWrithe(AnalysisBase):
    """Writhe (and, with side particles, twist) of a closed ring per frame.

    Wr is the exact Gauss self-integral of the closed polygon
    (:func:`dnabraid.geometry.curves.writhe`); Tw sums the joint angles of the ring's bond
    frames, seam included (:func:`dnabraid.geometry.ribbon.ring_twist`), so that
    Tw + Wr = Lk, an integer (White 1969).

    Parameters
    ----------
    ring_atoms : AtomGroup
        The ring's beads in order (the last joins the first), at least 4.
    side_atoms : AtomGroup, optional
        One side particle per bond (as many as beads).

    Attributes
    ----------
    results.writhe : ndarray, shape (n_frames,)
        Turns.
    results.twist, results.linking : ndarray, shape (n_frames,), only with ``side_atoms``
        Turns; ``linking`` = twist + writhe.
    results.mean, results.sem : float
        Mean writhe and its autocorrelation-corrected SEM (turns).
    """

    def __init__(self, ring_atoms, side_atoms=None, **kwargs):
        _check_group(ring_atoms, "ring_atoms", min_atoms=4)
        if side_atoms is not None:
            _check_group(side_atoms, "side_atoms", min_atoms=4)
            _check_same_universe(ring_atoms, side_atoms)
            if len(side_atoms) != len(ring_atoms):
                raise ValueError(f"a ring of {len(ring_atoms)} beads has {len(ring_atoms)} "
                                 f"bonds: need as many side particles; got {len(side_atoms)}")
        super().__init__(ring_atoms.universe.trajectory, **kwargs)
        self._ring, self._sides = ring_atoms, side_atoms

    def _prepare(self):
        self.results.writhe = np.full(self.n_frames, np.nan)
        if self._sides is not None:
            self.results.twist = np.full(self.n_frames, np.nan)

    def _single_frame(self):
        x = _nm(self._ring)
        i = self._frame_index
        self.results.writhe[i] = geometry.writhe(x)
        if self._sides is not None:
            self.results.twist[i] = _twist.ring_twist(x, _nm(self._sides))

    def _conclude(self):
        if self._sides is not None:
            self.results.linking = self.results.twist + self.results.writhe
        s = stats.mean_sem(self.results.writhe)
        self.results.stats = s
        self.results.mean = s["mean"]
        self.results.sem = s["sem"]


class RingLinking(AnalysisBase):
    """Gauss linking number of two closed rings per frame
    (:func:`dnabraid.geometry.curves.gauss_linking_number`): an integer while the rings do
    not pass through each other.

    Parameters
    ----------
    ring1_atoms, ring2_atoms : AtomGroup
        Each ring's beads in order, at least 3 each, from one Universe.

    Attributes
    ----------
    results.linking : ndarray, shape (n_frames,)
    results.conserved : bool
        Every frame within 1e-3 of the first frame's integer.
    """

    def __init__(self, ring1_atoms, ring2_atoms, **kwargs):
        _check_group(ring1_atoms, "ring1_atoms", min_atoms=3)
        _check_group(ring2_atoms, "ring2_atoms", min_atoms=3)
        _check_same_universe(ring1_atoms, ring2_atoms)
        super().__init__(ring1_atoms.universe.trajectory, **kwargs)
        self._r1, self._r2 = ring1_atoms, ring2_atoms

    def _prepare(self):
        self.results.linking = np.full(self.n_frames, np.nan)

    def _single_frame(self):
        self.results.linking[self._frame_index] = geometry.gauss_linking_number(
            _nm(self._r1), _nm(self._r2))

    def _conclude(self):
        lk = self.results.linking
        self.results.conserved = bool(lk.size == 0 or np.all(np.abs(lk - np.round(lk[0]))
                                                             < 1e-3))
