"""Local energies of the segment-pair terms, compiled with numba: the capsule contact and
the chiral term of a scene, reproduced from their OpenMM ``PythonForce`` s, and their change
when a few particles move.

Twins (dnabraid units: nm, pN, pN nm), read by :class:`dnabraid.kernels.chain.LocalEnergy`
from the pickled evaluator that the force carries (``openmm.XmlSerializer`` holds it as
hex; :func:`read_python_force`):

* ``capsule`` (:func:`dnabraid.forces.segment_contact.capsule_force`):
  U = k/2 (D_c - d)^2 for d < D_c, d the closest distance of two segments on different
  chains (Ericson 2005, Sec. 5.1.9, the same clamped minimiser as
  :func:`~dnabraid.forces.segment_contact._capsule_loop`);
* ``chiral`` (:func:`dnabraid.forces.chiral.chiral_force`): Eq. (C1) of
  :mod:`dnabraid.forces.reference_chiral`, alpha times the sum over the allowed segment
  pairs (different chains, or more than ``exclude`` segments apart along one) of both
  directions' sample points against the partner's line, with the weight w(r), the share
  psi(t), the angular factor G(c, s) and the two-ply calibration N(eta') of
  :func:`~dnabraid.forces.chiral._pair_loop`, energy only.

The energy change of a move: every segment with a moved end is paired with every other
segment (a pair of two moved segments once); a rigid move skips the pairs whose four ends
all moved (their distances and angles are kept). No pair list: the cost is
(moved segments) x (all segments) midpoint tests, a few us for the 80 segments of the long
braid; a cell list would be needed for chains of thousands of segments.
"""

from __future__ import annotations

import math
import re

import numba
import numpy as np

from ..units import PN_NM_IN_KJ_MOL

__all__ = ["read_python_force", "segment_fields", "capsule_params", "chiral_params"]


def read_python_force(f):
    """The callable (evaluator) a ``openmm.PythonForce`` carries, unpickled."""
    import pickle

    import openmm

    xml = openmm.XmlSerializer.serialize(f)
    m = re.search(r'function="([0-9a-fA-F]+)"', xml)
    if m is None:
        raise ValueError(f"LocalEnergy: cannot read the function of PythonForce {f.getName()!r}")
    return pickle.loads(bytes.fromhex(m.group(1)))


def _global(f, name: str) -> float:
    g = f.getGlobalParameters()
    if name not in g:
        raise ValueError(f"LocalEnergy: PythonForce {f.getName()!r} has no parameter {name!r}")
    return float(g[name])


def segment_fields(n: int) -> dict:
    """The empty capsule and chiral fields of the kernels' parameters (``n`` particles)."""
    z = np.zeros(0, np.int64)
    return dict(has_cap=False, cap_seg=np.zeros((0, 2), np.int64), cap_cid=z, cap_D=0.0,
                cap_k=0.0, has_chi=False, chi_seg=np.zeros((0, 2), np.int64), chi_cid=z,
                chi_pic=z, chi_nseg=z, chi_ring=np.zeros(0, np.uint8), chi_excl=0, chi_q=1,
                chi_delta=0.0, chi_rho=1.0, chi_rs=0.0, chi_rc=1.0, chi_ncoef=np.ones(1),
                chi_alpha=0.0)


def _global_segments(f, seg_local) -> np.ndarray:
    parts = np.asarray(list(f.getParticles()), np.int64)
    return np.ascontiguousarray(parts[np.asarray(seg_local, np.int64)], np.int64).reshape(-1, 2)


def capsule_params(f) -> dict:
    """The capsule fields from a ``capsule`` PythonForce."""
    from ..forces.segment_contact import CapsuleEvaluator

    ev = read_python_force(f)
    if not isinstance(ev, CapsuleEvaluator):
        raise ValueError(f"LocalEnergy: PythonForce {f.getName()!r} holds {type(ev).__name__}, "
                         "not the CapsuleEvaluator the kernel reproduces")
    return dict(has_cap=len(ev.seg) > 0, cap_seg=_global_segments(f, ev.seg),
                cap_cid=np.ascontiguousarray(ev.chain_id, np.int64), cap_D=float(ev.contact),
                cap_k=_global(f, ev.parameter) / PN_NM_IN_KJ_MOL)


def chiral_params(f) -> dict:
    """The chiral fields from a ``chiral`` PythonForce."""
    from ..forces.chiral import ChiralEvaluator

    ev = read_python_force(f)
    if not isinstance(ev, ChiralEvaluator):
        raise ValueError(f"LocalEnergy: PythonForce {f.getName()!r} holds {type(ev).__name__}, "
                         "not the ChiralEvaluator the kernel reproduces")
    k = ev.kernel
    return dict(has_chi=len(ev.seg) > 0, chi_seg=_global_segments(f, ev.seg),
                chi_cid=np.ascontiguousarray(ev.chain_id, np.int64),
                chi_pic=np.ascontiguousarray(ev.pos_in_chain, np.int64),
                chi_nseg=np.ascontiguousarray(ev.chain_nseg, np.int64),
                chi_ring=np.ascontiguousarray(ev.ring, np.uint8),
                chi_excl=int(ev.exclude_neighbours), chi_q=int(ev.q),
                chi_delta=float(k.delta), chi_rho=float(k.range), chi_rs=float(k.r_s),
                chi_rc=float(k.r_c), chi_ncoef=np.ascontiguousarray(k.ncoef, np.float64),
                chi_alpha=_global(f, ev.parameter) / PN_NM_IN_KJ_MOL)


# ------------------------------------------------------------------------------ pair terms
@numba.njit(cache=True)
def _fill(pos, new, moved, i0, i1, j0, j1, after, x):
    """x[0:3], x[3:6] the ends of segment (i0, i1), x[6:9], x[9:12] those of (j0, j1),
    after the move if ``after`` (written out: a helper returning one coordinate per call
    made this 35x slower)."""
    ai0 = moved[i0] - 1 if after else -1
    ai1 = moved[i1] - 1 if after else -1
    aj0 = moved[j0] - 1 if after else -1
    aj1 = moved[j1] - 1 if after else -1
    for c in range(3):
        x[c] = new[ai0, c] if ai0 >= 0 else pos[i0, c]
        x[3 + c] = new[ai1, c] if ai1 >= 0 else pos[i1, c]
        x[6 + c] = new[aj0, c] if aj0 >= 0 else pos[j0, c]
        x[9 + c] = new[aj1, c] if aj1 >= 0 else pos[j1, c]


@numba.njit(cache=True)
def _closest_d2(u0, u1, u2, v0, v1, v2, w0, w1, w2, aa, ee):
    """Squared closest distance of the segments p0 + s u and q0 + t v (s, t in [0, 1]),
    w = p0 - q0, aa = |u|^2, ee = |v|^2: the clamped minimiser of Ericson (2005, Sec.
    5.1.9), as :func:`dnabraid.forces.segment_contact.segment_distance`."""
    bb = u0 * v0 + u1 * v1 + u2 * v2
    cc = u0 * w0 + u1 * w1 + u2 * w2
    ff = v0 * w0 + v1 * w1 + v2 * w2
    den = aa * ee - bb * bb
    s = (bb * ff - cc * ee) / den if den > 1e-14 * aa * ee else 0.0
    s = min(1.0, max(0.0, s))
    t = min(1.0, max(0.0, (bb * s + ff) / ee)) if ee > 1e-300 else 0.0
    s = min(1.0, max(0.0, (bb * t - cc) / aa)) if aa > 1e-300 else 0.0
    r0 = w0 + s * u0 - t * v0
    r1 = w1 + s * u1 - t * v1
    r2 = w2 + s * u2 - t * v2
    return r0 * r0 + r1 * r1 + r2 * r2


@numba.njit(cache=True)
def _ext_dist2(x):
    """Squared closest distance of the two segments x[0:6], x[6:12], each extended by half
    its length beyond both ends (t in [-1/2, 3/2]: the support of the chiral share psi), so
    that no sample point of either is closer than this to the other's line within psi's
    support (Ericson 2005, Sec. 5.1.9, as :func:`capsule_pair`)."""
    u0 = x[3] - x[0]
    u1 = x[4] - x[1]
    u2 = x[5] - x[2]
    v0 = x[9] - x[6]
    v1 = x[10] - x[7]
    v2 = x[11] - x[8]
    w0 = x[0] - 0.5 * u0 - x[6] + 0.5 * v0
    w1 = x[1] - 0.5 * u1 - x[7] + 0.5 * v1
    w2 = x[2] - 0.5 * u2 - x[8] + 0.5 * v2
    u0 *= 2.0
    u1 *= 2.0
    u2 *= 2.0
    v0 *= 2.0
    v1 *= 2.0
    v2 *= 2.0
    aa = u0 * u0 + u1 * u1 + u2 * u2
    ee = v0 * v0 + v1 * v1 + v2 * v2
    return _closest_d2(u0, u1, u2, v0, v1, v2, w0, w1, w2, aa, ee)


@numba.njit(cache=True)
def capsule_pair(x, D, k):
    """k/2 (D - d)^2 for d < D (pN nm), d the closest distance of segments x[0:6], x[6:12]."""
    u0 = x[3] - x[0]
    u1 = x[4] - x[1]
    u2 = x[5] - x[2]
    v0 = x[9] - x[6]
    v1 = x[10] - x[7]
    v2 = x[11] - x[8]
    w0 = x[0] - x[6]
    w1 = x[1] - x[7]
    w2 = x[2] - x[8]
    aa = u0 * u0 + u1 * u1 + u2 * u2
    ee = v0 * v0 + v1 * v1 + v2 * v2
    # midpoints farther apart than D + (l_a + l_b)/2 cannot touch
    m0 = w0 + 0.5 * (u0 - v0)
    m1 = w1 + 0.5 * (u1 - v1)
    m2 = w2 + 0.5 * (u2 - v2)
    lim = D + 0.5 * (math.sqrt(aa) + math.sqrt(ee))
    if m0 * m0 + m1 * m1 + m2 * m2 >= lim * lim:
        return 0.0
    d = math.sqrt(_closest_d2(u0, u1, u2, v0, v1, v2, w0, w1, w2, aa, ee))
    if not d < D:
        return 0.0
    return 0.5 * k * (D - d) * (D - d)


@numba.njit(cache=True)
def _chiral_way(x, o, q, delta, rho, r_s, r_c, ncoef):
    """Sample points of the segment x[o:o+6] against the line of the other one (per unit
    alpha, nm): the energy of one direction of :func:`dnabraid.forces.chiral._pair_loop`."""
    p = 6 - o
    ea0 = x[o + 3] - x[o]
    ea1 = x[o + 4] - x[o + 1]
    ea2 = x[o + 5] - x[o + 2]
    eb0 = x[p + 3] - x[p]
    eb1 = x[p + 4] - x[p + 1]
    eb2 = x[p + 5] - x[p + 2]
    la = math.sqrt(ea0 * ea0 + ea1 * ea1 + ea2 * ea2)
    L2 = eb0 * eb0 + eb1 * eb1 + eb2 * eb2
    lb = math.sqrt(L2)
    m0 = x[p] + 0.5 * eb0 - x[o] - 0.5 * ea0
    m1 = x[p + 1] + 0.5 * eb1 - x[o + 1] - 0.5 * ea1
    m2 = x[p + 2] + 0.5 * eb2 - x[o + 2] - 0.5 * ea2
    lim = r_c + 0.5 * la + lb
    if m0 * m0 + m1 * m1 + m2 * m2 >= lim * lim:
        return 0.0
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
    inv_sw = 1.0 / (r_c - r_s)
    inv_rho = 1.0 / rho
    inv_q = 1.0 / q
    nd = ncoef.shape[0]
    use_n = nd > 1 or ncoef[0] != 1.0
    e = 0.0
    for k in range(q):
        f = (k + 0.5) * inv_q
        w0 = x[o] + f * ea0 - x[p]
        w1 = x[o + 1] + f * ea1 - x[p + 1]
        w2 = x[o + 2] + f * ea2 - x[p + 2]
        t = (w0 * eb0 + w1 * eb1 + w2 * eb2) / L2
        if not (t > -0.5 and t < 1.5):
            continue
        r0 = t * eb0 - w0
        r1 = t * eb1 - w1
        r2 = t * eb2 - w2
        rn = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
        if not (rn < r_c and rn > 1e-12):
            continue
        s = (cr0 * r0 + cr1 * r1 + cr2 * r2) / rn
        y = t + 0.5
        s1 = 1.0 if y >= 1.0 else y * y * y * (10.0 - 15.0 * y + 6.0 * y * y)
        y = t - 0.5
        s2 = 0.0 if y <= 0.0 else y * y * y * (10.0 - 15.0 * y + 6.0 * y * y)
        psi = s1 - s2
        if rn <= delta:
            W = 1.0
        else:
            y = (rn - delta) * inv_rho
            W = (1.0 + y) * math.exp(-y)
        y = (rn - r_s) * inv_sw
        if y > 0.0:
            W *= 1.0 - y * y * y * (10.0 - 15.0 * y + 6.0 * y * y)
        rh = math.sqrt(c * c + s * s)
        if not rh > 1e-12:
            continue
        G = c * s * rh / (rh + abs(c))
        if use_n:
            eta = math.atan2(s if c >= 0.0 else -s, abs(c))
            e2 = eta * eta
            nn = ncoef[0]
            for t_ in range(1, nd):
                nn = nn * e2 + ncoef[t_]
            G = G / nn
        e += 0.5 * la * inv_q * psi * W * G
    return e


@numba.njit(cache=True)
def chiral_pair(x, q, delta, rho, r_s, r_c, ncoef):
    """Both directions of a segment pair, per unit alpha (nm)."""
    return (_chiral_way(x, 0, q, delta, rho, r_s, r_c, ncoef)
            + _chiral_way(x, 6, q, delta, rho, r_s, r_c, ncoef))


# --------------------------------------------------------------------------- totals, deltas
@numba.njit(cache=True)
def _term_total(pos, S, cid, pic, nseg, ring, excl, which, cut, k, q, delta, rho, r_s,
                ncoef):
    """The whole capsule (``which`` 0, pN nm) or chiral (1, per unit alpha, nm) energy:
    every pair the term admits (parameters as :func:`_term_delta`)."""
    x = np.empty(12)
    none = np.zeros(0, np.int64)
    e = 0.0
    for u in range(S.shape[0]):
        for v in range(u + 1, S.shape[0]):
            if which == 0:
                if cid[u] != cid[v]:
                    _fill(pos, pos, none, S[u, 0], S[u, 1], S[v, 0], S[v, 1], False, x)
                    e += capsule_pair(x, cut, k)
            elif _allowed(cid, pic, nseg, ring, excl, u, v):
                _fill(pos, pos, none, S[u, 0], S[u, 1], S[v, 0], S[v, 1], False, x)
                e += chiral_pair(x, q, delta, rho, r_s, cut, ncoef)
    return e


@numba.njit(cache=True)
def capsule_total(pos, P):
    """Capsule energy (pN nm) of the whole model."""
    return _term_total(pos, P.cap_seg, P.cap_cid, P.cap_cid, P.cap_cid, P.chi_ring, 0, 0,
                       P.cap_D, P.cap_k, 1, 0.0, 1.0, 0.0, P.chi_ncoef)


@numba.njit(cache=True)
def chiral_total(pos, P):
    """Chiral energy (pN nm) of the whole model."""
    return P.chi_alpha * _term_total(pos, P.chi_seg, P.chi_cid, P.chi_pic, P.chi_nseg,
                                     P.chi_ring, P.chi_excl, 1, P.chi_rc, 0.0, P.chi_q,
                                     P.chi_delta, P.chi_rho, P.chi_rs, P.chi_ncoef)


@numba.njit(cache=True)
def _allowed(cid, pic, nseg, ring, excl, u, v):
    """Whether the pair (u, v) is in the term: different chains, or more than ``excl``
    segments apart along one (around a ring the shorter way)."""
    if cid[u] != cid[v]:
        return True
    sep = abs(pic[u] - pic[v])
    if ring[u]:
        sep = min(sep, nseg[u] - sep)
    return sep > excl


@numba.njit(cache=True)
def _geometry(S, pos, new, moved, after, mid, hl):
    """Midpoints and half-lengths of the segments (after the move if ``after``); returns
    the largest half-length."""
    hmax = 0.0
    for s in range(S.shape[0]):
        i = S[s, 0]
        j = S[s, 1]
        ai = moved[i] - 1 if after else -1
        aj = moved[j] - 1 if after else -1
        l2 = 0.0
        for c in range(3):
            a = new[ai, c] if ai >= 0 else pos[i, c]
            b = new[aj, c] if aj >= 0 else pos[j, c]
            mid[s, c] = 0.5 * (a + b)
            l2 += (b - a) * (b - a)
        hl[s] = 0.5 * math.sqrt(l2)
        if hl[s] > hmax:
            hmax = hl[s]
    return hmax


@numba.njit(cache=True)
def _near(mid, hl, u, v, cut):
    """Whether segments u and v can interact: midpoints closer than cut + h_u + h_v +
    max(h_u, h_v) (the chiral term's direction test r_c + l_a/2 + l_b, taken both ways;
    the capsule contact needs only D + h_u + h_v)."""
    d0 = mid[u, 0] - mid[v, 0]
    d1 = mid[u, 1] - mid[v, 1]
    d2 = mid[u, 2] - mid[v, 2]
    lim = cut + hl[u] + hl[v] + max(hl[u], hl[v])
    return d0 * d0 + d1 * d1 + d2 * d2 < lim * lim


#: Above this share of moved segments a move's change is summed by sweeps along z.
_SWEEP_SHARE = 0.25


@numba.njit(cache=True)
def _term_delta(pos, new, moved, rigid, S, cid, pic, nseg, ring, excl, which, cut, k, q,
                delta, rho, r_s, ncoef):
    """Change of the capsule (``which`` 0: D_c = ``cut``, stiffness ``k``; pN nm) or chiral
    (1: r_c = ``cut``; per unit alpha, nm) energy when the particles with ``moved[p] > 0``
    go to ``new[moved[p] - 1]``: the pairs with a moved segment (a rigid move: not both
    wholly moved), before and after. Few moved segments: each against all, midpoints
    tested first; many: sweeps of the midpoints sorted by z (Baraff 1992), each
    configuration on its own. (The parameters come unpacked: a call that passes the whole
    parameter tuple per pair cost ~0.2 us.)"""
    M = S.shape[0]
    mark = np.empty(M, np.int64)
    nmk = 0
    for s in range(M):
        mark[s] = (1 if moved[S[s, 0]] > 0 else 0) + (1 if moved[S[s, 1]] > 0 else 0)
        if mark[s] > 0:
            nmk += 1
    if nmk == 0:
        return 0.0
    x = np.empty(12)
    mid = np.empty((M, 3))
    hl = np.empty(M)
    de = 0.0
    sweep = nmk > _SWEEP_SHARE * M
    for cfg in range(2):
        after = cfg == 0
        sign = 1.0 if after else -1.0
        hmax = _geometry(S, pos, new, moved, after, mid, hl)
        order = np.argsort(mid[:, 2]) if sweep else np.arange(M)
        win = cut + 3.0 * hmax
        for ai in range(M):
            u = order[ai]
            if not sweep and mark[u] == 0:
                continue
            for bi in range(ai + 1 if sweep else 0, M):
                v = order[bi]
                if sweep:
                    if mid[v, 2] - mid[u, 2] > win:
                        break
                    if mark[u] == 0 and mark[v] == 0:
                        continue
                elif v == u or (mark[v] > 0 and v < u):
                    continue
                if rigid and mark[u] == 2 and mark[v] == 2:
                    continue
                if which == 0:
                    if cid[u] == cid[v]:
                        continue
                elif not _allowed(cid, pic, nseg, ring, excl, u, v):
                    continue
                if not _near(mid, hl, u, v, cut):
                    continue
                _fill(pos, new, moved, S[u, 0], S[u, 1], S[v, 0], S[v, 1], after, x)
                if which == 0:
                    de += sign * capsule_pair(x, cut, k)
                elif _ext_dist2(x) < cut * cut:
                    de += sign * chiral_pair(x, q, delta, rho, r_s, cut, ncoef)
    return de


@numba.njit(cache=True)
def capsule_delta(pos, new, moved, rigid, P):
    """Change of the capsule energy (pN nm) when the particles with ``moved[p] > 0`` go to
    ``new[moved[p] - 1]`` (``rigid``: the move is a rigid motion of the moved set)."""
    return _term_delta(pos, new, moved, rigid, P.cap_seg, P.cap_cid, P.cap_cid, P.cap_cid,
                       P.chi_ring, 0, 0, P.cap_D, P.cap_k, 1, 0.0, 1.0, 0.0, P.chi_ncoef)


@numba.njit(cache=True)
def chiral_delta(pos, new, moved, rigid, P):
    """Change of the chiral energy (pN nm), as :func:`capsule_delta`."""
    return P.chi_alpha * _term_delta(pos, new, moved, rigid, P.chi_seg, P.chi_cid, P.chi_pic,
                                     P.chi_nseg, P.chi_ring, P.chi_excl, 1, P.chi_rc, 0.0,
                                     P.chi_q, P.chi_delta, P.chi_rho, P.chi_rs, P.chi_ncoef)
