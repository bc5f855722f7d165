"""Chiral interaction between DNA segments that face each other (an ``openmm.PythonForce``).

Energy (docs/chirality.md; seed slides 5 and 32, after Kornyshev et al. 2007): two strands in
contact carry alpha tan(eta/2) per unit contact length, eta the braid angle. The bead model
sums over pairs of segments on different strands and on distant parts of one strand
(plectoneme branches); the discretisation, distance weight, apolar fold and normalisation are
documented in :mod:`dnabraid.forces.reference_chiral` (Eqs. C1-C5), which is also the numpy
twin the tests use as an oracle.

Why a PythonForce
-----------------
The term couples four particles (two segments) chosen by distance at run time. OpenMM's
custom forces cannot express that at linear cost: a CustomCompoundBondForce would need every
segment pair listed in advance (N^2 terms), CustomNonbondedForce is two-body only, and a
CustomManyParticleForce enumerates all particle quadruples within a cutoff whatever the
chain topology. A PythonForce calls a vectorised numpy evaluator with its own pair list.

Cost and the pair search
------------------------
Candidates are kept in a Verlet list of segment pairs. It is built by grid hashing of segment
midpoints (cells of side h = r_c + skin + l_max, 14 half-shell neighbour cells, sort +
searchsorted: O(M log M) for M segments, linear in practice, never quadratic) and keeps the
pairs whose midpoints are closer than r_c + skin + (l_a + l_b)/2. It is rebuilt only when
some bead has moved more than skin/2 since the last build: then two sample points that are
now within r_c were within r_c + skin at the build, so their segments are in the list (no
pair is missed; tested against brute force). Each call filters the list by the current
midpoint distance and evaluates the sample-point pairs, all in numpy, so a step costs
O(number of segments near another strand) plus the PythonForce overhead (~100 us).
See workflows/benchmark_chiral.py for measured costs.
"""

from __future__ import annotations

import math

import numpy as np
import openmm

from ..units import PN_NM_IN_KJ_MOL
from .reference_chiral import (
    CUTOFF_DEBYE,
    ETA_ON,
    SWITCH_DEBYE,
    ChiralKernel,
    default_subdivisions,
    pair_allowed,
    segments_of,
)

__all__ = ["ChiralEvaluator", "chiral_force", "default_exclusion", "grid_pairs"]

# The 13 half-shell neighbour offsets plus the home cell (handled with i < j).
_HALF_SHELL = [(dx, dy, dz) for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)
               if (dx, dy, dz) > (0, 0, 0)]


def grid_pairs(points, cutoff):
    """All pairs (i < j) of ``points`` closer than ``cutoff``, by grid hashing.

    Parameters
    ----------
    points : (M, 3) float array
    cutoff : float
        Also the cell side.

    Returns
    -------
    i, j : int arrays, i < j
    """
    pts = np.asarray(points, float)
    m = len(pts)
    if m < 2:
        e = np.zeros(0, np.int64)
        return e, e
    cell = np.floor((pts - pts.min(0)) / cutoff).astype(np.int64)
    dims = cell.max(0) + 3  # one empty layer on each side
    cell += 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    skey = key[order]
    idx = np.arange(m)
    out_i, out_j = [], []
    for off in [(0, 0, 0)] + _HALF_SHELL:
        okey = key + (off[0] * dims[1] + off[1]) * dims[2] + off[2]
        lo = np.searchsorted(skey, okey, "left")
        hi = np.searchsorted(skey, okey, "right")
        cnt = hi - lo
        tot = int(cnt.sum())
        if tot == 0:
            continue
        ii = np.repeat(idx, cnt)
        starts = np.repeat(lo - (np.cumsum(cnt) - cnt), cnt)
        jj = order[starts + np.arange(tot)]
        if off == (0, 0, 0):
            keep = ii < jj
            ii, jj = ii[keep], jj[keep]
        d2 = np.sum((pts[jj] - pts[ii]) ** 2, axis=1)
        keep = d2 < cutoff * cutoff
        ii, jj = ii[keep], jj[keep]
        out_i.append(np.minimum(ii, jj))
        out_j.append(np.maximum(ii, jj))
    if not out_i:
        e = np.zeros(0, np.int64)
        return e, e
    return np.concatenate(out_i), np.concatenate(out_j)


def default_exclusion(bead_spacing_nm, delta_nm, debye_nm, cutoff_debye=CUTOFF_DEBYE):
    """Segments excluded along one chain: k with k b < pi r_c / 2.

    Two points of a chain joined by a half-turn of diameter r_c are pi r_c / 2 apart along
    it; closer pairs along a chain are neighbours on one branch, not two branches facing each
    other, and would only measure the chain's own bending.
    """
    r_c = float(delta_nm) + cutoff_debye * float(debye_nm)
    return max(1, math.ceil(0.5 * math.pi * r_c / float(bead_spacing_nm)))


def _cross(a, b):
    """Cross product of (3, P) arrays."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def pair_terms_fast(pos, seg, a, b, kernel, q):
    """Same result as :func:`~dnabraid.forces.reference_chiral.pair_terms`, written for speed.

    Component-major (3, P) arrays, no masking (the weight is exactly zero beyond r_c) and
    scatter by ``np.bincount``; an independent implementation, tested against the twin.
    """
    n = len(pos)
    grad = np.zeros((n, 3))
    if len(a) == 0:
        return 0.0, grad
    X = np.ascontiguousarray(pos.T)
    i0, i1, j0, j1 = seg[a, 0], seg[a, 1], seg[b, 0], seg[b, 1]
    xa, xb = X[:, i0], X[:, j0]
    ea, eb = X[:, i1] - xa, X[:, j1] - xb
    la = np.sqrt((ea * ea).sum(0))
    lb = np.sqrt((eb * eb).sum(0))
    ta, tb = ea / la, eb / lb
    npair = len(a)
    if q == 1:
        fk = fm = np.full(npair, 0.5)
        rep = slice(None)
        r = (xb + 0.5 * eb) - (xa + 0.5 * ea)
    else:
        fr = (np.arange(q) + 0.5) / q
        fk = np.tile(np.repeat(fr, q), npair)
        fm = np.tile(np.tile(fr, q), npair)
        rep = np.repeat(np.arange(npair), q * q)
        r = (xb[:, rep] + fm * eb[:, rep]) - (xa[:, rep] + fk * ea[:, rep])
    rn = np.sqrt((r * r).sum(0))
    d = r / rn
    tap, tbp = ta[:, rep], tb[:, rep]
    cr = _cross(tap, tbp)
    c = (tap * tbp).sum(0)
    s = (cr * d).sum(0)
    K, dK = kernel.weight(rn)
    G, dGc, dGs = kernel.angular(c, s)
    w = (la * lb / (q * q))[rep] if q > 1 else la * lb
    wK = w * K
    e = float(np.dot(wK, G))
    sd = (cr * d).sum(0)
    dE_dr = (w * dK * G) * d + (wK * dGs / rn) * (cr - sd * d)
    dE_dta = wK * (dGc * tbp + dGs * _cross(tbp, d))
    dE_dtb = wK * (dGc * tap + dGs * _cross(d, tap))
    KG = K * G / (q * q)
    if q > 1:
        dE_dta = dE_dta.reshape(3, npair, q * q).sum(2)
        dE_dtb = dE_dtb.reshape(3, npair, q * q).sum(2)
        KG = KG.reshape(npair, q * q).sum(1)
    dE_dea = (dE_dta - (dE_dta * ta).sum(0) * ta) / la + (lb * KG) * ta
    dE_deb = (dE_dtb - (dE_dtb * tb).sum(0) * tb) / lb + (la * KG) * tb
    if q == 1:
        ga0 = -dE_dea - 0.5 * dE_dr
        ga1 = dE_dea - 0.5 * dE_dr
        gb0 = -dE_deb + 0.5 * dE_dr
        gb1 = dE_deb + 0.5 * dE_dr
    else:
        ga0 = -dE_dea - ((1.0 - fk) * dE_dr).reshape(3, npair, q * q).sum(2)
        ga1 = dE_dea - (fk * dE_dr).reshape(3, npair, q * q).sum(2)
        gb0 = -dE_deb + ((1.0 - fm) * dE_dr).reshape(3, npair, q * q).sum(2)
        gb1 = dE_deb + (fm * dE_dr).reshape(3, npair, q * q).sum(2)
    idx = np.concatenate([i0, i1, j0, j1])
    val = np.concatenate([ga0, ga1, gb0, gb1], axis=1)
    for k in range(3):
        grad[:, k] = np.bincount(idx, val[k], minlength=n)
    return e, grad


class ChiralEvaluator:
    """Picklable callable computing the chiral energy and forces for a PythonForce.

    Works in local particle numbering (the particles passed to ``setParticles``) and keeps a
    Verlet list of candidate segment pairs (see the module docstring). Counters
    ``n_calls`` and ``n_builds`` are public for diagnostics.

    Parameters
    ----------
    seg : (M, 2) int array
        Segments in local numbering.
    chain_id, pos_in_chain, chain_nseg, ring : (M,) arrays
        From :func:`dnabraid.forces.reference_chiral.segments_of`.
    kernel : ChiralKernel
    exclude_neighbours, subdivisions : int
    skin_nm : float
    parameter : str
        Name of the global parameter holding alpha in kJ/mol/nm.
    """

    def __init__(self, seg, chain_id, pos_in_chain, chain_nseg, ring, kernel,
                 exclude_neighbours, subdivisions, skin_nm, parameter):
        self.seg = np.asarray(seg, np.int64)
        self.chain_id = np.asarray(chain_id)
        self.pos_in_chain = np.asarray(pos_in_chain)
        self.chain_nseg = np.asarray(chain_nseg)
        self.ring = np.asarray(ring, bool)
        self.kernel = kernel
        self.exclude_neighbours = int(exclude_neighbours)
        self.q = int(subdivisions)
        self.skin = float(skin_nm)
        self.parameter = parameter
        self.n_calls = 0
        self.n_builds = 0
        self._ref = None
        self._a = np.zeros(0, np.int64)
        self._b = np.zeros(0, np.int64)

    def __getstate__(self):
        st = self.__dict__.copy()
        st["_ref"] = None  # a copy starts with a fresh list
        return st

    def _build(self, pos):
        x0, x1 = pos[self.seg[:, 0]], pos[self.seg[:, 1]]
        mid = 0.5 * (x0 + x1)
        ln = np.linalg.norm(x1 - x0, axis=1)
        reach = self.kernel.r_c + self.skin
        a, b = grid_pairs(mid, reach + float(ln.max()))
        d = np.linalg.norm(mid[b] - mid[a], axis=1)
        keep = d < reach + 0.5 * (ln[a] + ln[b])
        a, b = a[keep], b[keep]
        keep = pair_allowed(a, b, self.chain_id, self.pos_in_chain, self.chain_nseg, self.ring,
                            self.exclude_neighbours)
        self._a, self._b = a[keep], b[keep]
        self._ref = pos.copy()
        self.n_builds += 1

    def candidate_pairs(self, pos):
        """Segment pairs (a, b) in the Verlet list, rebuilt if a bead moved > skin/2."""
        if (self._ref is None or self._ref.shape != pos.shape
                or np.max(np.sum((pos - self._ref) ** 2, axis=1)) > 0.25 * self.skin**2):
            self._build(pos)
        return self._a, self._b

    def energy_grad(self, pos):
        """(E, dE/dx) of Eq. (C1) per unit alpha: nm and dimensionless (N, 3)."""
        pos = np.asarray(pos, float)
        a, b = self.candidate_pairs(pos)
        if len(a):
            x0, x1 = pos[self.seg[:, 0]], pos[self.seg[:, 1]]
            mid = 0.5 * (x0 + x1)
            ln = np.linalg.norm(x1 - x0, axis=1)
            d2 = np.sum((mid[b] - mid[a]) ** 2, axis=1)
            lim = self.kernel.r_c + 0.5 * (ln[a] + ln[b])
            keep = d2 < lim * lim
            a, b = a[keep], b[keep]
        return pair_terms_fast(pos, self.seg, a, b, self.kernel, self.q)

    def __call__(self, state):
        self.n_calls += 1
        pos = state.getPositions(asNumpy=True)._value  # nm
        alpha = state.getParameters()[self.parameter]  # kJ/mol/nm
        e, g = self.energy_grad(pos)
        return alpha * e, -alpha * g


def chiral_force(chains, alpha_pN, *, delta_nm, debye_nm, exclude_neighbours=None,
                 bead_spacing_nm=None, subdivisions=None, closed=False, skin_nm=1.0,
                 cutoff_debye=CUTOFF_DEBYE, switch_debye=SWITCH_DEBYE, eta_on_rad=ETA_ON,
                 name="chiral"):
    """Chiral interaction alpha tan(eta/2) per unit contact length, as a named PythonForce.

    Parameters
    ----------
    chains : list of int arrays
        Ordered particle indices of each strand (global System numbering).
    alpha_pN : float
        alpha in pN (= pN nm of energy per nm of contact). alpha > 0 favours eta < 0:
        right-handed braids, i.e. positive bead turns (docs/chirality.md). Zero returns None:
        the term is then left out of the System.
    delta_nm : float
        Effective diameter Delta (the contact distance of the normalisation).
    debye_nm : float
        Debye length: the weight decays like exp(-(r - Delta)/lambda_D) and vanishes at
        r_c = Delta + cutoff_debye lambda_D.
    exclude_neighbours : int, optional
        Segments on one chain at most this many apart do not interact. Default
        :func:`default_exclusion` (needs ``bead_spacing_nm``).
    bead_spacing_nm : float, optional
        Rest bead spacing b, used for the defaults of ``exclude_neighbours`` and
        ``subdivisions``.
    subdivisions : int, optional
        Sample points per segment; default
        :func:`~dnabraid.forces.reference_chiral.default_subdivisions` (b/q <= sqrt(Delta
        lambda_D)), or 1 without ``bead_spacing_nm``.
    closed : bool or sequence of bool
        Ring chains.
    skin_nm : float
        Verlet-list skin.
    cutoff_debye, switch_debye, eta_on_rad : float
        Shape of the weight and of the angular switch (reference_chiral).
    name : str
        Force name; the global parameter ``<name>_alpha`` holds alpha in kJ/mol/nm.

    Returns
    -------
    openmm.PythonForce or None
    """
    alpha = float(alpha_pN)
    if not math.isfinite(alpha):
        raise ValueError(f"alpha_pN must be finite, got {alpha_pN!r}")
    if alpha == 0.0:
        return None
    if exclude_neighbours is None or subdivisions is None:
        if bead_spacing_nm is None and exclude_neighbours is None:
            raise ValueError("chiral_force: give exclude_neighbours or bead_spacing_nm")
        if subdivisions is None:
            subdivisions = (1 if bead_spacing_nm is None
                            else default_subdivisions(bead_spacing_nm, delta_nm, debye_nm))
        if exclude_neighbours is None:
            exclude_neighbours = default_exclusion(bead_spacing_nm, delta_nm, debye_nm,
                                                   cutoff_debye)
    if int(subdivisions) < 1 or int(exclude_neighbours) < 0:
        raise ValueError(f"subdivisions must be >= 1 and exclude_neighbours >= 0, got "
                         f"{subdivisions!r}, {exclude_neighbours!r}")
    if not skin_nm > 0:
        raise ValueError(f"skin_nm must be > 0, got {skin_nm!r}")
    chains = [np.asarray(c, dtype=np.int64).ravel() for c in chains]
    particles = np.unique(np.concatenate(chains)) if chains else np.zeros(0, np.int64)
    local = {int(p): k for k, p in enumerate(particles)}
    seg, cid, pic, nseg, ring = segments_of(chains, closed)
    seg_local = np.vectorize(local.__getitem__, otypes=[np.int64])(seg) if len(seg) else seg
    kernel = ChiralKernel(delta_nm, debye_nm, cutoff_debye=cutoff_debye,
                          switch_debye=switch_debye, eta_on_rad=eta_on_rad)
    parameter = f"{name}_alpha"
    evaluator = ChiralEvaluator(seg_local, cid, pic, nseg, ring, kernel, exclude_neighbours,
                                subdivisions, skin_nm, parameter)
    force = openmm.PythonForce(evaluator, {parameter: alpha * PN_NM_IN_KJ_MOL})
    force.setParticles([int(p) for p in particles])
    force.setName(name)
    return force
