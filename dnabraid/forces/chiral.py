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
chain topology. A PythonForce calls an evaluator (a numba-compiled loop, or vectorised
numpy) with its own pair list.

Cost and the pair search
------------------------
Candidates are kept in a Verlet list of segment pairs. It is built by grid hashing of segment
midpoints (cells of side h = reach + l_max, the 27 neighbour cells, sort + binary search:
O(M log M) for M segments, linear in practice, never quadratic) and keeps the pairs whose
midpoints are closer than reach + (l_a + l_b)/2, reach = r_c + 2.5 skin + l_max/2. A point of
segment u interacts with the line of segment v only if |m_u - m_v| < r_c + l_u/2 + l_v (its
foot lies within psi's support, t in (-1/2, 3/2)); the list is rebuilt when some bead has
moved more than skin/2 (skin 2 nm by default) since the last build, so midpoints have moved
< skin/2 and lengths < skin and no pair is missed (tested against brute force). Each call
evaluates both directions of every listed pair that passes that midpoint test.

Two evaluators compute the same numbers (tested against the twin to 1e-10):

* ``numba`` (default when numba is installed): :func:`_pair_loop`, one compiled loop over
  pairs and sample points writing straight into the force array, and :func:`build_pair_loop`
  for the list; compiled on first use with ``cache=True`` (about 8 s the first time on this
  machine, 0.2 s from the on-disk cache afterwards; numba is imported only then);
* ``numpy`` (fallback): :func:`pair_terms_fast`, the twin's vectorised
  :func:`~dnabraid.forces.reference_chiral.pair_terms` over the list.

Since 2026-12-02 (weight flat at contact, point-to-partner-line form, no angular switch) the
kernel is cheaper per sample point (one exp, no atan); on the long braid (2 x 41 beads,
b = 5 nm, q = 3, n = 2, Brownian steps, one thread) alpha = 1 costs 0.18 ms per step against
0.07 without the term with the bead WCA, and 0.21 against 0.14 with the capsule contact. The
numbers below were measured with the earlier kernel.

Measured (CPU time, OpenMM 8.6 CPU platform, one thread; workflows/benchmark_chiral.py; a
2-core shared machine, so +-20 %): one call costs ~0.06-0.09 us per candidate pair and sample
point with numba against 0.5-1.1 us with numpy (2 x 31-bead two-ply, q = 2, 250 pairs: 0.065 against
0.8 ms); per Brownian step, a two-ply of 2 x {50, 200, 800} beads at q = 1 costs 1.0-1.3 x
the bonds + bending + WCA force field (6-12 x with numpy), and 1.6-3.3 x at q = 2. A
PythonForce costs ~25-50 us per step even when it does nothing (OpenMM calling Python and
copying the state); that floor is most of the chiral cost of a small braid out of contact
(the braid scene, 2 x 31 beads: 0.11-0.14 against 0.07 ms per step without the term).
These numbers were measured with the Debye length as the weight's range (cutoff Delta +
6 lambda_D); with the range of the first helical harmonic (docs/chiral_range.md) the cutoff and
the candidate list shrink while the default q can grow (finer sampling of a narrower
weight): docs/chiral_range.md has both, measured side by side.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import openmm

from ..units import PN_NM_IN_KJ_MOL
from .reference_chiral import (
    CUTOFF_RANGES,
    ETA_ON,
    SWITCH_RANGES,
    ChiralKernel,
    chiral_range_nm,
    default_subdivisions,
    pair_allowed,
    pair_terms,
    segments_of,
)

__all__ = ["HAVE_NUMBA", "ChiralEvaluator", "chiral_force", "default_exclusion", "grid_pairs",
           "pair_terms_fast", "pair_terms_numba"]

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


def default_exclusion(bead_spacing_nm, delta_nm, debye_nm, cutoff_ranges=CUTOFF_RANGES, *,
                      range_nm=None):
    """Segments excluded along one chain: k with k b < pi r_c / 2.

    Two points of a chain joined by a half-turn of diameter r_c are pi r_c / 2 apart along
    it; closer pairs along a chain are neighbours on one branch, not two branches facing each
    other, and would only measure the chain's own bending. r_c = Delta + cutoff_ranges rho,
    rho = ``range_nm`` (default
    :func:`~dnabraid.forces.reference_chiral.chiral_range_nm` of ``debye_nm``).
    """
    rho = chiral_range_nm(debye_nm) if range_nm is None else float(range_nm)
    r_c = float(delta_nm) + cutoff_ranges * rho
    return max(1, math.ceil(0.5 * math.pi * r_c / float(bead_spacing_nm)))


def _cross(a, b):
    """Cross product of (3, P) arrays."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def pair_terms_fast(pos, seg, a, b, kernel, q):
    """Same result as :func:`~dnabraid.forces.reference_chiral.pair_terms` (the numpy
    fallback without numba): the twin's vectorised evaluation itself."""
    return pair_terms(np.asarray(pos, float), seg, a, b, kernel, q)


# ---------------------------------------------------------------------------------------------
# Compiled path. The two functions below are plain Python (readable, and runnable as such on a
# few pairs); compile_kernel() compiles them with numba on first use, cached on disk (cache=True), so
# numba is imported only when a chiral force is first evaluated. The numpy pair_terms_fast
# stays the fallback without numba; both are tested against the twin.
# ---------------------------------------------------------------------------------------------


def _pair_loop(pos, seg, a, b, q, delta, rho, r_s, r_c, ncoef, scale, out):
    """Eq. (C1) over candidate segment pairs, both ways, one sample point at a time.

    Computes what :func:`~dnabraid.forces.reference_chiral.pair_terms` computes, with w(r),
    psi(t) and G(c, s) of :class:`~dnabraid.forces.reference_chiral.ChiralKernel` written out
    inline. A direction (points of segment u against the line of segment v) is skipped when
    the midpoints are farther apart than r_c + l_u/2 + l_v (then no point of u has its foot
    within psi's support at a distance below r_c).

    Parameters
    ----------
    pos : (N, 3) float64 array, nm
    seg : (M, 2) int64 array
    a, b : (P,) int64 arrays of candidate segment pairs
    q : int
        Sample points per segment.
    delta, rho, r_s, r_c : float
        Kernel parameters (ChiralKernel ``delta``, ``range``, ``r_s``, ``r_c``).
    ncoef : (D,) float64 array
        N(eta') = polyval(ncoef, eta'^2) (ChiralKernel ``ncoef``; [1.0]: no calibration).
    scale : float
        The gradient is added to ``out`` times ``scale`` (1: dE/dx; -alpha: forces).
    out : (N, 3) float64 array
        Accumulator, written in place.

    Returns
    -------
    e : float
        Energy per unit alpha (nm), not scaled.
    """
    inv_sw = 1.0 / (r_c - r_s)
    inv_rho = 1.0 / rho
    inv_q = 1.0 / q
    nd = ncoef.shape[0]
    use_n = nd > 1 or ncoef[0] != 1.0
    e_tot = 0.0
    for p in range(a.shape[0]):
        for way in range(2):
            if way == 0:
                su = a[p]
                sv = b[p]
            else:
                su = b[p]
                sv = a[p]
            i0 = seg[su, 0]
            i1 = seg[su, 1]
            j0 = seg[sv, 0]
            j1 = seg[sv, 1]
            ea0 = pos[i1, 0] - pos[i0, 0]
            ea1 = pos[i1, 1] - pos[i0, 1]
            ea2 = pos[i1, 2] - pos[i0, 2]
            eb0 = pos[j1, 0] - pos[j0, 0]
            eb1 = pos[j1, 1] - pos[j0, 1]
            eb2 = pos[j1, 2] - pos[j0, 2]
            la = math.sqrt(ea0 * ea0 + ea1 * ea1 + ea2 * ea2)
            L2 = eb0 * eb0 + eb1 * eb1 + eb2 * eb2
            lb = math.sqrt(L2)
            m0 = pos[j0, 0] + 0.5 * eb0 - pos[i0, 0] - 0.5 * ea0
            m1 = pos[j0, 1] + 0.5 * eb1 - pos[i0, 1] - 0.5 * ea1
            m2 = pos[j0, 2] + 0.5 * eb2 - pos[i0, 2] - 0.5 * ea2
            lim = r_c + 0.5 * la + lb
            if m0 * m0 + m1 * m1 + m2 * m2 >= lim * lim:
                continue
            ta0 = ea0 / la
            ta1 = ea1 / la
            ta2 = ea2 / la
            tb0 = eb0 / lb
            tb1 = eb1 / lb
            tb2 = eb2 / lb
            c = ta0 * tb0 + ta1 * tb1 + ta2 * tb2
            cr0 = ta1 * tb2 - ta2 * tb1
            cr1 = ta2 * tb0 - ta0 * tb2
            cr2 = ta0 * tb1 - ta1 * tb0
            # accumulators: dE/dx_a0, dE/dx_a1, dE/dx_b0, dE/dx_b1
            ga00 = ga01 = ga02 = ga10 = ga11 = ga12 = 0.0
            gb00 = gb01 = gb02 = gb10 = gb11 = gb12 = 0.0
            for k in range(q):
                f = (k + 0.5) * inv_q
                w0 = pos[i0, 0] + f * ea0 - pos[j0, 0]
                w1 = pos[i0, 1] + f * ea1 - pos[j0, 1]
                w2 = pos[i0, 2] + f * ea2 - pos[j0, 2]
                t = (w0 * eb0 + w1 * eb1 + w2 * eb2) / L2
                if not (t > -0.5 and t < 1.5):
                    continue
                r0 = t * eb0 - w0
                r1 = t * eb1 - w1
                r2 = t * eb2 - w2
                rn = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
                if not (rn < r_c and rn > 1e-12):
                    continue
                inv_rn = 1.0 / rn
                d0 = r0 * inv_rn
                d1 = r1 * inv_rn
                d2 = r2 * inv_rn
                s = cr0 * d0 + cr1 * d1 + cr2 * d2
                # share psi(t) = sigma(t + 1/2) - sigma(t - 1/2)
                x = t + 0.5
                if x >= 1.0:
                    s1 = 1.0
                    ds1 = 0.0
                else:
                    s1 = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
                    ds1 = 30.0 * x * x * (1.0 - x) * (1.0 - x)
                x = t - 0.5
                if x <= 0.0:
                    s2 = 0.0
                    ds2 = 0.0
                else:
                    s2 = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
                    ds2 = 30.0 * x * x * (1.0 - x) * (1.0 - x)
                psi = s1 - s2
                dpsi = ds1 - ds2
                # weight w(r): flat to delta, (1 + x) exp(-x) beyond, C2 switch r_s..r_c
                if rn <= delta:
                    W = 1.0
                    dW = 0.0
                else:
                    x = (rn - delta) * inv_rho
                    ex = math.exp(-x)
                    W = (1.0 + x) * ex
                    dW = -x * ex * inv_rho
                y = (rn - r_s) * inv_sw
                if y > 0.0:
                    cs = 1.0 - y * y * y * (10.0 - 15.0 * y + 6.0 * y * y)
                    dcs = -30.0 * y * y * (1.0 - y) * (1.0 - y) * inv_sw
                    dW = dW * cs + W * dcs
                    W = W * cs
                # angular factor G = c s rho / (rho + |c|)
                rh = math.sqrt(c * c + s * s)
                if not rh > 1e-12:
                    continue
                A = rh + abs(c)
                G = c * s * rh / A
                sg = 1.0 if c > 0.0 else (-1.0 if c < 0.0 else 0.0)
                dGc = s * rh / A + c * s * (c / rh) / A - G * (c / rh + sg) / A
                dGs = c * rh / A + c * s * (s / rh) / A - G * (s / rh) / A
                if use_n:  # N(eta'), eta' = atan(s/c) folded (Eq. C5)
                    eta = math.atan2(s if c >= 0.0 else -s, abs(c))
                    e2 = eta * eta
                    nn = ncoef[0]
                    dn = 0.0
                    for t_ in range(1, nd):
                        dn = dn * e2 + nn
                        nn = nn * e2 + ncoef[t_]
                    dn = dn * 2.0 * eta
                    r2 = rh * rh
                    dGc = (dGc + G * dn * s / (r2 * nn)) / nn
                    dGs = (dGs - G * dn * c / (r2 * nn)) / nn
                    G = G / nn
                lq = la * inv_q
                e_tot += 0.5 * lq * psi * W * G
                h = 0.5  # each direction carries half
                g_la = h * psi * W * G * inv_q
                g_t = h * lq * dpsi * W * G
                u = h * lq * psi * dW * G
                v = h * lq * psi * W * dGs * inv_rn
                gr0 = u * d0 + v * (cr0 - s * d0)
                gr1 = u * d1 + v * (cr1 - s * d1)
                gr2 = u * d2 + v * (cr2 - s * d2)
                kk = h * lq * psi * W
                # tb x d, d x ta
                bxd0 = tb1 * d2 - tb2 * d1
                bxd1 = tb2 * d0 - tb0 * d2
                bxd2 = tb0 * d1 - tb1 * d0
                dxa0 = d1 * ta2 - d2 * ta1
                dxa1 = d2 * ta0 - d0 * ta2
                dxa2 = d0 * ta1 - d1 * ta0
                gta0 = kk * (dGc * tb0 + dGs * bxd0)
                gta1 = kk * (dGc * tb1 + dGs * bxd1)
                gta2 = kk * (dGc * tb2 + dGs * bxd2)
                gtb0 = kk * (dGc * ta0 + dGs * dxa0)
                gtb1 = kk * (dGc * ta1 + dGs * dxa1)
                gtb2 = kk * (dGc * ta2 + dGs * dxa2)
                g_tt = g_t + gr0 * eb0 + gr1 * eb1 + gr2 * eb2
                iL = g_tt / L2
                gw0 = -gr0 + iL * eb0
                gw1 = -gr1 + iL * eb1
                gw2 = -gr2 + iL * eb2
                pb = gtb0 * tb0 + gtb1 * tb1 + gtb2 * tb2
                geb0 = t * gr0 + iL * (w0 - 2.0 * t * eb0) + (gtb0 - pb * tb0) / lb
                geb1 = t * gr1 + iL * (w1 - 2.0 * t * eb1) + (gtb1 - pb * tb1) / lb
                geb2 = t * gr2 + iL * (w2 - 2.0 * t * eb2) + (gtb2 - pb * tb2) / lb
                pa = gta0 * ta0 + gta1 * ta1 + gta2 * ta2
                gea0 = (gta0 - pa * ta0) / la + g_la * ta0 + f * gw0
                gea1 = (gta1 - pa * ta1) / la + g_la * ta1 + f * gw1
                gea2 = (gta2 - pa * ta2) / la + g_la * ta2 + f * gw2
                ga00 += gw0 - gea0
                ga01 += gw1 - gea1
                ga02 += gw2 - gea2
                ga10 += gea0
                ga11 += gea1
                ga12 += gea2
                gb00 += -gw0 - geb0
                gb01 += -gw1 - geb1
                gb02 += -gw2 - geb2
                gb10 += geb0
                gb11 += geb1
                gb12 += geb2
            out[i0, 0] += scale * ga00
            out[i0, 1] += scale * ga01
            out[i0, 2] += scale * ga02
            out[i1, 0] += scale * ga10
            out[i1, 1] += scale * ga11
            out[i1, 2] += scale * ga12
            out[j0, 0] += scale * gb00
            out[j0, 1] += scale * gb01
            out[j0, 2] += scale * gb02
            out[j1, 0] += scale * gb10
            out[j1, 1] += scale * gb11
            out[j1, 2] += scale * gb12
    return e_tot


def build_pair_loop(pos, seg, chain_id, pos_in_chain, chain_nseg, ring, exclude, reach):
    """Verlet list: segment pairs (a < b) with |m_b - m_a| < reach + (l_a + l_b)/2 that
    :func:`~dnabraid.forces.reference_chiral.pair_allowed` admits.

    The same grid hashing as :func:`grid_pairs` (cells of side reach + l_max, a sort of the
    cell keys and a binary search per neighbour cell: O(M log M)), as one loop.

    Returns
    -------
    a, b : (P,) int64 arrays
    """
    m = seg.shape[0]
    mid = np.empty((m, 3))
    ln = np.empty(m)
    lmax = 0.0
    for i in range(m):
        s0 = 0.0
        for k in range(3):
            x0 = pos[seg[i, 0], k]
            x1 = pos[seg[i, 1], k]
            mid[i, k] = 0.5 * (x0 + x1)
            s0 += (x1 - x0) * (x1 - x0)
        ln[i] = math.sqrt(s0)
        if ln[i] > lmax:
            lmax = ln[i]
    h = reach + lmax
    lo3 = np.empty(3)
    for k in range(3):
        lo3[k] = mid[:, k].min()
    cell = np.empty((m, 3), np.int64)
    dims = np.zeros(3, np.int64)
    for i in range(m):
        for k in range(3):
            c = np.int64(math.floor((mid[i, k] - lo3[k]) / h)) + 1  # one empty layer
            cell[i, k] = c
            if c + 2 > dims[k]:
                dims[k] = c + 2
    key = np.empty(m, np.int64)
    for i in range(m):
        key[i] = (cell[i, 0] * dims[1] + cell[i, 1]) * dims[2] + cell[i, 2]
    order = np.argsort(key)
    skey = key[order]
    cap = 16 * m + 16
    a = np.empty(cap, np.int64)
    b = np.empty(cap, np.int64)
    n = 0
    for i in range(m):
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                for dz in range(-1, 2):
                    ko = key[i] + (dx * dims[1] + dy) * dims[2] + dz
                    lo = np.searchsorted(skey, ko)
                    hi = np.searchsorted(skey, ko, side="right")
                    for t in range(lo, hi):
                        j = order[t]
                        if j <= i:
                            continue
                        d2 = 0.0
                        for k in range(3):
                            d2 += (mid[j, k] - mid[i, k]) ** 2
                        lim = reach + 0.5 * (ln[i] + ln[j])
                        if not d2 < lim * lim:
                            continue
                        if chain_id[i] == chain_id[j]:
                            sep = abs(pos_in_chain[i] - pos_in_chain[j])
                            if ring[i]:
                                sep = min(sep, chain_nseg[i] - sep)
                            if sep <= exclude:
                                continue
                        if n == cap:
                            cap *= 2
                            a2 = np.empty(cap, np.int64)
                            b2 = np.empty(cap, np.int64)
                            a2[:n] = a[:n]
                            b2[:n] = b[:n]
                            a = a2
                            b = b2
                        a[n] = i
                        b[n] = j
                        n += 1
    return a[:n].copy(), b[:n].copy()


def _max_disp2(pos, ref):
    """max_i |pos_i - ref_i|^2 (the Verlet-list rebuild test)."""
    mx = 0.0
    for i in range(pos.shape[0]):
        d0 = pos[i, 0] - ref[i, 0]
        d1 = pos[i, 1] - ref[i, 1]
        d2 = pos[i, 2] - ref[i, 2]
        d = d0 * d0 + d1 * d1 + d2 * d2
        if d > mx:
            mx = d
    return mx


#: numba is present (it is imported, and the kernels compiled, only on first use).
HAVE_NUMBA = importlib.util.find_spec("numba") is not None
_COMPILED = {}


def compile_kernel(fn):
    """``numba.njit(cache=True)(fn)``, made once per process."""
    k = _COMPILED.get(fn.__name__)
    if k is None:
        import numba

        k = _COMPILED[fn.__name__] = numba.njit(cache=True, nogil=True)(fn)
    return k


def pair_terms_numba(pos, seg, a, b, kernel, q):
    """Same result as :func:`pair_terms_fast` with the compiled loop (needs numba).

    Pairs whose midpoints are farther apart than r_c + (l_a + l_b)/2 are skipped, which
    changes nothing (they have no sample points within r_c).
    """
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    grad = np.zeros_like(pos)
    e = compile_kernel(_pair_loop)(pos, np.ascontiguousarray(seg, np.int64),
                         np.ascontiguousarray(a, np.int64), np.ascontiguousarray(b, np.int64),
                         int(q), kernel.delta, kernel.range, kernel.r_s, kernel.r_c,
                         np.ascontiguousarray(kernel.ncoef, np.float64), 1.0, grad)
    return float(e), grad


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
    backend : {"auto", "numba", "numpy"}
        "auto" (default): the compiled loop :func:`pair_terms_numba` where numba is
        installed, else the numpy :func:`pair_terms_fast`.
    """

    def __init__(self, seg, chain_id, pos_in_chain, chain_nseg, ring, kernel,
                 exclude_neighbours, subdivisions, skin_nm, parameter, backend="auto"):
        if backend not in ("auto", "numba", "numpy"):
            raise ValueError(f"backend must be 'auto', 'numba' or 'numpy', got {backend!r}")
        if backend == "numba" and not HAVE_NUMBA:
            raise ImportError("backend='numba' needs the numba package (pip install numba)")
        self.seg = np.ascontiguousarray(seg, np.int64)
        self.chain_id = np.asarray(chain_id)
        self.pos_in_chain = np.asarray(pos_in_chain)
        self.chain_nseg = np.asarray(chain_nseg)
        self.ring = np.asarray(ring, bool)
        # contiguous int64 / bool copies for the compiled build
        self._cid = np.ascontiguousarray(self.chain_id, np.int64)
        self._pic = np.ascontiguousarray(self.pos_in_chain, np.int64)
        self._nseg = np.ascontiguousarray(self.chain_nseg, np.int64)
        self._ring = np.ascontiguousarray(self.ring, np.bool_)
        self.kernel = kernel
        self.exclude_neighbours = int(exclude_neighbours)
        self.q = int(subdivisions)
        self.skin = float(skin_nm)
        self.parameter = parameter
        self.backend = backend
        self.n_calls = 0
        self.n_builds = 0
        self._ref = None
        self._kpar = None
        self._a = np.zeros(0, np.int64)
        self._b = np.zeros(0, np.int64)

    def __getstate__(self):
        st = self.__dict__.copy()
        st["_ref"] = None  # a copy starts with a fresh list
        st["_kpar"] = None
        return st

    def __setstate__(self, st):
        st.setdefault("backend", "auto")  # pickles from before the compiled path
        st["_kpar"] = None
        self.__dict__.update(st)

    def _build(self, pos):
        if self.uses_numba:
            self._a, self._b = compile_kernel(build_pair_loop)(
                pos, self.seg, self._cid, self._pic, self._nseg, self._ring,
                self.exclude_neighbours, self._reach(pos))
            self._ref = pos.copy()
            self.n_builds += 1
            return
        x0, x1 = pos[self.seg[:, 0]], pos[self.seg[:, 1]]
        mid = 0.5 * (x0 + x1)
        ln = np.linalg.norm(x1 - x0, axis=1)
        reach = self._reach(pos)
        a, b = grid_pairs(mid, reach + float(ln.max()))
        d = np.linalg.norm(mid[b] - mid[a], axis=1)
        keep = d < reach + 0.5 * (ln[a] + ln[b])
        a, b = a[keep], b[keep]
        keep = pair_allowed(a, b, self.chain_id, self.pos_in_chain, self.chain_nseg, self.ring,
                            self.exclude_neighbours)
        self._a, self._b = a[keep], b[keep]
        self._ref = pos.copy()
        self.n_builds += 1

    def _reach(self, pos):
        """Verlet reach: a direction needs |m_u - m_v| < r_c + l_u/2 + l_v, and between builds
        midpoints move by < skin/2 and lengths change by < skin; the list keeps
        |m_a - m_b| < reach + (l_a + l_b)/2, reach = r_c + 2.5 skin + l_max/2."""
        e = pos[self.seg[:, 1]] - pos[self.seg[:, 0]]
        lmax = float(np.sqrt(np.max(np.sum(e * e, axis=1)))) if len(e) else 0.0
        return self.kernel.r_c + 2.5 * self.skin + 0.5 * lmax

    @property
    def uses_numba(self):
        """Whether calls go through the compiled loop."""
        return self.backend == "numba" or (self.backend == "auto" and HAVE_NUMBA)

    def candidate_pairs(self, pos):
        """Segment pairs (a, b) in the Verlet list, rebuilt if a bead moved > skin/2."""
        if self._ref is None or self._ref.shape != pos.shape:
            self._build(pos)
        else:
            if self.uses_numba:
                moved2 = compile_kernel(_max_disp2)(pos, self._ref)
            else:
                moved2 = np.max(np.sum((pos - self._ref) ** 2, axis=1))
            if moved2 > 0.25 * self.skin**2:
                self._build(pos)
        return self._a, self._b

    def _compiled(self, pos, scale, out):
        """Energy per unit alpha; adds scale * dE/dx to ``out`` (compiled path)."""
        a, b = self.candidate_pairs(pos)
        k = self.kernel
        if self._kpar is None:
            self._kpar = (k.delta, k.range, k.r_s, k.r_c,
                          np.ascontiguousarray(k.ncoef, np.float64))
        return compile_kernel(_pair_loop)(pos, self.seg, a, b, self.q, *self._kpar, scale, out)

    def energy_grad(self, pos):
        """(E, dE/dx) of Eq. (C1) per unit alpha: nm and dimensionless (N, 3)."""
        pos = np.ascontiguousarray(pos, dtype=np.float64)
        if self.uses_numba:
            grad = np.zeros_like(pos)
            return float(self._compiled(pos, 1.0, grad)), grad
        a, b = self.candidate_pairs(pos)
        if len(a):
            x0, x1 = pos[self.seg[:, 0]], pos[self.seg[:, 1]]
            mid = 0.5 * (x0 + x1)
            ln = np.linalg.norm(x1 - x0, axis=1)
            d2 = np.sum((mid[b] - mid[a]) ** 2, axis=1)
            lim = self.kernel.r_c + ln[a] + ln[b]
            keep = d2 < lim * lim
            a, b = a[keep], b[keep]
        return pair_terms_fast(pos, self.seg, a, b, self.kernel, self.q)

    def __call__(self, state):
        self.n_calls += 1
        pos = np.ascontiguousarray(state.getPositions(asNumpy=True)._value, np.float64)  # nm
        alpha = state.getParameters()[self.parameter]  # kJ/mol/nm
        if self.uses_numba:
            force = np.zeros_like(pos)
            e = self._compiled(pos, -alpha, force)
            return alpha * e, force
        e, g = self.energy_grad(pos)
        return alpha * e, -alpha * g


def chiral_force(chains, alpha_pN, *, delta_nm, debye_nm, exclude_neighbours=None,
                 bead_spacing_nm=None, subdivisions=None, closed=False, skin_nm=2.0,
                 range_nm=None, cutoff_ranges=CUTOFF_RANGES, switch_ranges=SWITCH_RANGES,
                 eta_on_rad=ETA_ON, name="chiral", backend="auto", calibrate_two_ply=False):
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
        Debye length lambda_D of the salt. The weight decays like exp(-(r - Delta)/rho) with
        the range of the charge pattern's first helical harmonic,
        rho = 1/sqrt(lambda_D^-2 + (2 pi / 3.4 nm)^2)
        (:func:`~dnabraid.forces.reference_chiral.chiral_range_nm`; 0.45 nm at 150 mM), and
        vanishes at r_c = Delta + cutoff_ranges rho.
    exclude_neighbours : int, optional
        Segments on one chain at most this many apart do not interact. Default
        :func:`default_exclusion` (needs ``bead_spacing_nm``).
    bead_spacing_nm : float, optional
        Rest bead spacing b, used for the defaults of ``exclude_neighbours`` and
        ``subdivisions``.
    subdivisions : int, optional
        Sample points per segment; default
        :func:`~dnabraid.forces.reference_chiral.default_subdivisions` (b/q <= 1.6
        sqrt(Delta rho)), or 1 without ``bead_spacing_nm``.
    closed : bool or sequence of bool
        Ring chains.
    skin_nm : float
        Verlet-list skin. 2 nm: in Brownian runs at the default time step a 1 nm skin
        rebuilt the list every ~7-10 steps, 2 nm every ~40 for ~6 % more candidate pairs
        (workflows/benchmark_chiral.py, with the old 6 lambda_D cutoff).
    range_nm : float, optional
        Override of rho (default from ``debye_nm``, see above); for studies only.
    cutoff_ranges, switch_ranges, eta_on_rad : float
        Shape of the weight (reference_chiral); eta_on_rad is unused (no angular switch).
    name : str
        Force name; the global parameter ``<name>_alpha`` holds alpha in kJ/mol/nm.
    backend : {"auto", "numba", "numpy"}
        Evaluator of the pair terms (:class:`ChiralEvaluator`); "auto" takes numba when
        installed.
    calibrate_two_ply : bool
        Fit N(eta) so that the ideal two-ply of this bead spacing and q carries exactly
        alpha tan(eta/2) (needs ``bead_spacing_nm``; reference_chiral Eq. C5). Off by
        default: the numpy twin :func:`~dnabraid.forces.reference_chiral.chiral_energy_forces`
        is then the same function without knowing the spacing.

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
                            else default_subdivisions(bead_spacing_nm, delta_nm, debye_nm,
                                                      range_nm=range_nm))
        if exclude_neighbours is None:
            exclude_neighbours = default_exclusion(bead_spacing_nm, delta_nm, debye_nm,
                                                   cutoff_ranges, range_nm=range_nm)
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
    if calibrate_two_ply and bead_spacing_nm is None:
        raise ValueError("chiral_force: calibrate_two_ply needs bead_spacing_nm")
    kernel = ChiralKernel(delta_nm, debye_nm, range_nm=range_nm, cutoff_ranges=cutoff_ranges,
                          switch_ranges=switch_ranges, eta_on_rad=eta_on_rad,
                          bead_spacing_nm=bead_spacing_nm if calibrate_two_ply else None,
                          subdivisions=subdivisions)
    parameter = f"{name}_alpha"
    evaluator = ChiralEvaluator(seg_local, cid, pic, nseg, ring, kernel, exclude_neighbours,
                                subdivisions, skin_nm, parameter, backend=backend)
    force = openmm.PythonForce(evaluator, {parameter: alpha * PN_NM_IN_KJ_MOL})
    force.setParticles([int(p) for p in particles])
    force.setName(name)
    return force
