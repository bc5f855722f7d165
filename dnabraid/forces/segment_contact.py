"""Smooth self-contact of an elastic rod: a one-sided harmonic penalty on the closest distance
between two *segments* of the bead chain (capsules), not between two beads.

Why segments
------------
A penalty between beads, ``U = k/2 (2h - r)^2`` (:mod:`dnabraid.forces.contact`), sees the
rod as a string of spheres: two strands sliding along each other ride over bumps of period
``b`` (the bead spacing), and the bumps' slope acts as static friction (found 2026-11-30:
it pins the trefoil's loop). The non-penetration condition of the continuum rod is
``|r(s1) - r(s2)| >= 2h`` for all ``s1, s2`` far enough apart along the rod (Audoly,
Clauvelin & Neukirch 2007, Eq. 3; the same condition is used by Jawed, Dieleman, Audoly &
Reis 2015): here the rod's centreline is the polyline through the beads and the distance
is the closest distance between two of its straight pieces,

    d(i, j) = min_{s, t in [0, 1]} |p0 + s (p1 - p0) - q0 - t (q1 - q0)|,
    U = sum_{pairs} k/2 (D - d)^2  for d < D (0 beyond),   D = 2h.

What is here
------------
* :func:`segment_distance` - vectorised closest points (d, s, t) of segment pairs (the
  clamped minimiser of the convex quadratic, Ericson 2005, *Real-Time Collision
  Detection*, Sec. 5.1.9; robust for parallel segments);
* :func:`segment_pairs` - candidate pairs (cKDTree on the segments' midpoints) closer than
  a cutoff, with neighbours along the chain excluded (open chains, rings, several chains:
  see :func:`chain_exclusion`);
* :func:`contact_energy`, :func:`contact_gradient_hessian` - the numpy energy, its exact
  gradient (Danskin's / the envelope theorem: the box constraints on ``s, t`` do not depend
  on the positions, so dd/dx is the partial derivative at the minimiser, clamped or not)
  and a sparse Hessian (Gauss-Newton ``k J^T J``, positive semidefinite, or the exact one,
  with the closest-point parameters' own response eliminated by a Schur complement);
* :func:`segment_contact_force` - the OpenMM twin, a ``CustomCompoundBondForce`` over the
  four beads of each listed pair computing the same clamped closest distance in Lepton.
* :func:`capsule_force` - the thermal variant between the strands of a scene
  (``contact = "capsules"``): an ``openmm.PythonForce`` over a Verlet list of segment pairs
  on different chains (:class:`CapsuleEvaluator`, numba loop :func:`_capsule_loop` or numpy),
  the same energy as :func:`contact_energy`; it compiles in no time and costs ~0.07 ms per
  step on the long braid (2 x 41 beads; mostly the PythonForce's call overhead).

The closest distance is C^1 in the positions except where a closest-point parameter
switches between clamped and free (a jump in the Hessian, not in the force) and for
exactly parallel segments (a kink of measure zero).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..units import PN_NM_IN_KJ_MOL

__all__ = [
    "segment_distance",
    "segment_pairs",
    "chain_exclusion",
    "chain_segments",
    "contact_energy",
    "contact_gradient_hessian",
    "segment_contact_force",
    "capsule_force",
    "CapsuleEvaluator",
]

_TINY = 1e-300


def _dot(a, b):
    return np.einsum("...k,...k->...", a, b)


def segment_distance(p0, p1, q0, q1):
    """Closest distance between segments [p0, p1] and [q0, q1] and the closest points.

    Parameters
    ----------
    p0, p1, q0, q1 : array_like, shape (..., 3), nm
        Ends of the two segments (broadcast together).

    Returns
    -------
    d : ndarray, shape (...), nm
        ``min_{s, t in [0, 1]} |p0 + s (p1 - p0) - q0 - t (q1 - q0)|``.
    s, t : ndarray, shape (...)
        A minimiser (the unique one unless the segments are parallel and their
        projections overlap; then the one the clamping picks, at the same distance).

    Notes
    -----
    Ericson (2005), *Real-Time Collision Detection*, Sec. 5.1.9: the unconstrained ``s``
    of the two lines, clamped to [0, 1]; ``t`` for that ``s``, clamped; ``s`` again for the
    clamped ``t``. For parallel segments (``a e - b^2 <= 1e-14 a e``) the first ``s`` is 0,
    which the two later steps make a minimiser. Degenerate (zero-length) segments are
    handled as points.
    """
    p0, p1, q0, q1 = (np.asarray(v, float) for v in (p0, p1, q0, q1))
    u = p1 - p0
    v = q1 - q0
    w = p0 - q0
    a = _dot(u, u)
    e = _dot(v, v)
    b = _dot(u, v)
    c = _dot(u, w)
    f = _dot(v, w)
    den = a * e - b * b
    ok = den > 1e-14 * a * e
    s = np.where(ok, (b * f - c * e) / np.where(ok, den, 1.0), 0.0)
    s = np.clip(s, 0.0, 1.0)
    t = np.clip(np.where(e > _TINY, (b * s + f) / np.where(e > _TINY, e, 1.0), 0.0), 0.0, 1.0)
    s = np.clip(np.where(a > _TINY, (b * t - c) / np.where(a > _TINY, a, 1.0), 0.0), 0.0, 1.0)
    r = w + s[..., None] * u - t[..., None] * v
    return np.sqrt(_dot(r, r)), s, t


def chain_segments(n_beads: int, *, closed: bool = False) -> np.ndarray:
    """Segments (i, i+1) of one chain of ``n_beads`` beads, (M, 2) int; a ring adds (N-1, 0)."""
    i = np.arange(n_beads - (0 if closed else 1))
    return np.column_stack([i, (i + 1) % n_beads])


def chain_exclusion(chains: Sequence[tuple[int, bool]], min_separation: int
                    ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """Exclusion rule for segments listed chain after chain.

    Parameters
    ----------
    chains : sequence of (n_segments, closed)
        The segment list is the concatenation of these chains, in order (an open chain of
        N beads has N - 1 segments, a ring of N beads has N).
    min_separation : int
        Segments of the same chain at most this many segments apart (counted the short
        way round a ring) are excluded; segments of different chains never are.

    Returns
    -------
    callable
        ``exclude(s, t) -> bool mask`` (True: drop the pair), for :func:`segment_pairs`.
    """
    sizes = np.array([int(n) for n, _ in chains], int)
    closed = np.array([bool(c) for _, c in chains], bool)
    if np.any(sizes < 1):
        raise ValueError(f"chain_exclusion: every chain needs >= 1 segment, got {sizes.tolist()}")
    if min_separation < 1:
        raise ValueError("chain_exclusion: min_separation must be >= 1 (segments that share a "
                         f"bead are always in contact), got {min_separation}")
    start = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    total = int(sizes.sum())

    def exclude(s, t):
        s = np.asarray(s, int)
        t = np.asarray(t, int)
        if np.any((s < 0) | (s >= total) | (t < 0) | (t >= total)):
            raise IndexError(f"segment index outside the {total} segments of the chains")
        cs = np.searchsorted(start, s, side="right") - 1
        ct = np.searchsorted(start, t, side="right") - 1
        sep = np.abs(s - t)
        per = sizes[cs]
        sep = np.where(closed[cs], np.minimum(sep, per - sep), sep)
        return (cs == ct) & (sep <= min_separation)

    return exclude


def segment_pairs(x, segments, cutoff_nm: float, *, min_separation: int = 1,
                  closed: bool = False,
                  exclude: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
                  ) -> np.ndarray:
    """Segment pairs (s < t) whose closest distance is below ``cutoff_nm``.

    Parameters
    ----------
    x : array_like, shape (N, 3), nm
        Bead positions.
    segments : array_like, shape (M, 2), int
        Bead index pairs of the segments (may wrap round for rings: ``(N-1, 0)``).
    cutoff_nm : float
        Pairs with closest distance ``d < cutoff_nm`` are returned (the contact
        diameter ``D`` for the energy; larger for a neighbour list).
    min_separation : int, default 1
        Default exclusion rule (a single chain whose segments are listed in order along
        it): pairs with ``|s - t| <= min_separation`` are dropped; with ``closed`` the
        separation is counted the short way round the ring of ``M`` segments.
        Must be >= 1: segments that share a bead are at distance 0.
    closed : bool, default False
        The segments form one ring (see ``min_separation``).
    exclude : callable, optional
        ``exclude(s, t) -> bool mask`` (True: drop) used *instead of* the default rule,
        for several chains or any other topology (:func:`chain_exclusion` builds one).

    Returns
    -------
    ndarray, shape (P, 2), int
        Segment indices, ``s < t``, sorted.

    Notes
    -----
    Candidates come from a cKDTree on the segments' midpoints queried at ``cutoff + l_max``
    (``l_max`` the longest segment: two segments closer than ``cutoff`` have midpoints
    closer than that), then the exact closest distance decides.
    """
    x = np.asarray(x, float)
    seg = np.asarray(segments, int).reshape(-1, 2)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"segment_pairs: x must be (N, 3) nm, got shape {x.shape}")
    if len(seg) and (seg.min() < 0 or seg.max() >= len(x)):
        raise IndexError(f"segment_pairs: segment bead indices outside 0..{len(x) - 1}")
    if not cutoff_nm > 0:
        raise ValueError(f"segment_pairs: cutoff_nm must be > 0, got {cutoff_nm}")
    if exclude is None and min_separation < 1:
        raise ValueError("segment_pairs: min_separation must be >= 1 (segments that share a "
                         f"bead are at distance 0), got {min_separation}")
    empty = np.zeros((0, 2), int)
    if len(seg) < 2:
        return empty
    p0, p1 = x[seg[:, 0]], x[seg[:, 1]]
    lmax = float(np.linalg.norm(p1 - p0, axis=1).max())
    mid = 0.5 * (p0 + p1)
    cand = cKDTree(mid).query_pairs(float(cutoff_nm) + lmax, output_type="ndarray")
    if len(cand) == 0:
        return empty
    cand = np.sort(cand, axis=1)
    s, t = cand[:, 0], cand[:, 1]
    if exclude is None:
        sep = t - s
        if closed:
            sep = np.minimum(sep, len(seg) - sep)
        drop = sep <= min_separation
    else:
        drop = np.asarray(exclude(s, t), bool)
    cand = cand[~drop]
    if len(cand) == 0:
        return empty
    d, _, _ = segment_distance(x[seg[cand[:, 0], 0]], x[seg[cand[:, 0], 1]],
                               x[seg[cand[:, 1], 0]], x[seg[cand[:, 1], 1]])
    cand = cand[d < cutoff_nm]
    return cand[np.lexsort((cand[:, 1], cand[:, 0]))]


def _pair_geometry(x, segments, pairs):
    x = np.asarray(x, float)
    seg = np.asarray(segments, int).reshape(-1, 2)
    pr = np.asarray(pairs, int).reshape(-1, 2)
    nodes = np.column_stack([seg[pr[:, 0], 0], seg[pr[:, 0], 1],
                             seg[pr[:, 1], 0], seg[pr[:, 1], 1]])  # (P, 4)
    p0, p1, q0, q1 = (x[nodes[:, k]] for k in range(4))
    d, s, t = segment_distance(p0, p1, q0, q1)
    return nodes, (p0, p1, q0, q1), d, s, t


def contact_energy(x, segments, pairs, diameter_nm: float, k_pN_per_nm: float) -> float:
    """U = sum_pairs k/2 (D - d)^2 for d < D (pN nm); ``d`` the segments' closest distance.

    ``pairs`` (P, 2) index ``segments`` (M, 2); pairs at ``d >= D`` contribute nothing, so a
    neighbour list from :func:`segment_pairs` at any cutoff >= D gives the same energy.
    """
    if len(np.asarray(pairs).reshape(-1, 2)) == 0:
        return 0.0
    _, _, d, _, _ = _pair_geometry(x, segments, pairs)
    pen = np.clip(float(diameter_nm) - d, 0.0, None)
    return float(0.5 * float(k_pN_per_nm) * np.sum(pen * pen))


def contact_gradient_hessian(x, segments, pairs, diameter_nm: float, k_pN_per_nm: float, *,
                             gauss_newton: bool = True):
    """Gradient and sparse Hessian of :func:`contact_energy`.

    Parameters
    ----------
    x : (N, 3) nm; segments : (M, 2) int; pairs : (P, 2) int (indices into ``segments``)
    diameter_nm : float
        Contact distance ``D`` (2h for a rod of radius h).
    k_pN_per_nm : float
        Penalty stiffness ``k``.
    gauss_newton : bool, default True
        True: ``H = k sum J^T J`` with ``J = dd/dx`` (positive semidefinite; what a damped
        Newton relaxation wants). False: the exact Hessian
        ``k J^T J - k (D - d) d_xx``, where ``d_xx`` includes the response of the free
        closest-point parameters (``e = d^2``, ``e_xx = g_xx - g_xw g_ww^{-1} g_wx`` over the
        unclamped ones ``w``); exact away from the clamping transitions, parallel
        segments and ``d = D``.

    Returns
    -------
    grad : ndarray, shape (N, 3), pN
        dU/dx (the force is ``-grad``).
    H : scipy.sparse.csr_matrix, shape (3N, 3N), pN/nm
    """
    x = np.asarray(x, float)
    N = len(x)
    grad = np.zeros((N, 3))
    pr = np.asarray(pairs, int).reshape(-1, 2)
    if len(pr) == 0:
        return grad, sp.csr_matrix((3 * N, 3 * N))
    k = float(k_pN_per_nm)
    D = float(diameter_nm)
    nodes, (p0, p1, q0, q1), d, s, t = _pair_geometry(x, segments, pr)
    act = d < D
    nodes, p0, p1, q0, q1, d, s, t = (a[act] for a in (nodes, p0, p1, q0, q1, d, s, t))
    P = len(d)
    if P == 0:
        return grad, sp.csr_matrix((3 * N, 3 * N))
    r = (p0 + s[:, None] * (p1 - p0)) - (q0 + t[:, None] * (q1 - q0))  # P - Q
    dd = np.maximum(d, 1e-12 * D)
    nvec = r / dd[:, None]
    c = np.column_stack([1.0 - s, s, -(1.0 - t), -t])  # r = sum_i c_i x_i
    J = c[:, :, None] * nvec[:, None, :]  # (P, 4, 3): dd/dx_i (Danskin)
    pen = D - d
    gcoef = -k * pen  # dU/dd
    np.add.at(grad, nodes.ravel(), (gcoef[:, None, None] * J).reshape(-1, 3))
    Jf = J.reshape(P, 12)
    H = k * Jf[:, :, None] * Jf[:, None, :]
    if not gauss_newton:
        I3 = np.eye(3)
        u = p1 - p0
        v = q1 - q0
        # e = |r|^2 as a function of x (12) and w = (s, t)
        gxx = 2.0 * np.einsum("pi,pj,ab->piajb", c, c, I3).reshape(P, 12, 12)
        dcs = np.array([-1.0, 1.0, 0.0, 0.0])
        dct = np.array([0.0, 0.0, 1.0, -1.0])
        gxs = 2.0 * (dcs[None, :, None] * r[:, None, :] + c[:, :, None] * u[:, None, :])
        gxt = 2.0 * (dct[None, :, None] * r[:, None, :] - c[:, :, None] * v[:, None, :])
        G = np.stack([gxs.reshape(P, 12), gxt.reshape(P, 12)], axis=2)  # (P, 12, 2)
        a_ = _dot(u, u)
        e_ = _dot(v, v)
        b_ = _dot(u, v)
        W = 2.0 * np.stack([np.stack([a_, -b_], -1), np.stack([-b_, e_], -1)], -2)  # (P,2,2)
        free = np.column_stack([(s > 0.0) & (s < 1.0), (t > 0.0) & (t < 1.0)])
        # restrict to the free parameters: zero the clamped rows/columns, unit diagonal there
        Gm = G * free[:, None, :]
        Wm = W * (free[:, :, None] & free[:, None, :]) + np.eye(2) * (~free)[:, :, None]
        exx = gxx - np.einsum("pia,pab,pjb->pij", Gm, np.linalg.inv(Wm), Gm)
        ex = 2.0 * np.einsum("pi,pa->pia", c, r).reshape(P, 12)
        dxx = exx / (2.0 * dd)[:, None, None] - ex[:, :, None] * ex[:, None, :] / (
            4.0 * dd**3)[:, None, None]
        H = H - (k * pen)[:, None, None] * dxx
    idx = (3 * nodes[:, :, None] + np.arange(3)[None, None, :]).reshape(P, 12)
    rows = np.broadcast_to(idx[:, :, None], (P, 12, 12)).ravel()
    cols = np.broadcast_to(idx[:, None, :], (P, 12, 12)).ravel()
    Hs = sp.coo_matrix((H.ravel(), (rows, cols)), shape=(3 * N, 3 * N)).tocsr()
    return grad, Hs


def segment_contact_force(segment_pairs_4body, diameter_nm: float, k_pN_per_nm: float, *,
                          name: str = "segcontact", frozen_at=None):
    """OpenMM twin: U = k/2 (D - d)^2 step(D - d), d the closest distance of two segments.

    Parameters
    ----------
    segment_pairs_4body : array_like, shape (P, 4), int
        ``(i0, i1, j0, j1)``: the beads of the first segment and of the second.
    diameter_nm : float
        Contact distance ``D``.
    k_pN_per_nm : float
        Penalty stiffness.
    name : str
        Force name and prefix of its global parameters (``{name}_k``, ``{name}_D``).
    frozen_at : array_like, shape (N, 3), nm, optional
        None (default): the general force, the clamped closest-point computation of
        :func:`segment_distance` in Lepton (valid everywhere; Lepton differentiates through
        ``s`` and ``t``, whose partial derivatives of ``d`` vanish at the minimiser, so the
        forces are the exact gradient of :func:`contact_energy`). Its derivative
        expressions are large: building a Context takes ~10 s (Reference) to minutes (CPU)
        on one core, independent of the number of pairs.
        Given positions: each pair's clamping case at those positions is frozen (both
        closest points interior: line-line distance ``|w . (u x v)| / |u x v|``; one end
        clamped: that end's distance to the other segment's line; both: end-to-end
        distance), a small expression that builds in milliseconds. It equals the general
        force (energy and forces) at ``frozen_at`` and wherever no pair changes case: the
        check of a relaxed configuration, not a force for a simulation.

    Returns
    -------
    openmm.CustomCompoundBondForce
        The list of pairs is fixed: a relaxation or a simulation whose contacts change must
        rebuild it (or list every pair that can come within ``D`` during the run).
    """
    import openmm

    quads = np.asarray(segment_pairs_4body, int).reshape(-1, 4)
    pre = [f"0.5*{name}_k*pen^2*step(pen)", f"pen = {name}_D - dist"]
    if frozen_at is not None:
        return _frozen_force(quads, np.asarray(frozen_at, float), name, pre,
                             float(diameter_nm), float(k_pN_per_nm))
    expr = "; ".join(pre + [
        "dist = sqrt(rx*rx + ry*ry + rz*rz)",
        "rx = wx + s*ux - t*vx", "ry = wy + s*uy - t*vy", "rz = wz + s*uz - t*vz",
        "s = min(1, max(0, (bb*t - cc)/aa))",
        "t = min(1, max(0, (bb*s0 + ff)/ee))",
        "s0 = min(1, max(0, select(step(den - 1e-14*aa*ee), (bb*ff - cc*ee)/den, 0)))",
        # den is >= 0; the select keeps a parallel pair from dividing by zero
        "den = aa*ee - bb*bb",
        "aa = ux*ux + uy*uy + uz*uz", "ee = vx*vx + vy*vy + vz*vz",
        "bb = ux*vx + uy*vy + uz*vz", "cc = ux*wx + uy*wy + uz*wz",
        "ff = vx*wx + vy*wy + vz*wz",
        "ux = x2 - x1", "uy = y2 - y1", "uz = z2 - z1",
        "vx = x4 - x3", "vy = y4 - y3", "vz = z4 - z3",
        "wx = x1 - x3", "wy = y1 - y3", "wz = z1 - z3",
    ])
    f = openmm.CustomCompoundBondForce(4, expr)
    f.setName(name)
    f.addGlobalParameter(f"{name}_k", float(k_pN_per_nm) * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_D", float(diameter_nm))
    for q in quads:
        f.addBond([int(i) for i in q], [])
    return f


def _frozen_force(quads, x, name, pre, D, k):
    """One CustomCompoundBondForce(4); per-bond ``kind``: 0 line-line (p0 p1 q0 q1),
    1 point-line (point, line0, line1, any), 2 point-point (point, point, any, any)."""
    import openmm

    expr = "; ".join(pre + [
        "dist = sqrt(max(0, select(kind, select(kind - 1, pp, pl), ll)))",
        "ll = trip*trip/den",
        "trip = wx*(uy*vz - uz*vy) + wy*(uz*vx - ux*vz) + wz*(ux*vy - uy*vx)",
        "den = (uy*vz - uz*vy)^2 + (uz*vx - ux*vz)^2 + (ux*vy - uy*vx)^2",
        "pl = ((ay*gz - az*gy)^2 + (az*gx - ax*gz)^2 + (ax*gy - ay*gx)^2)/(gx*gx + gy*gy + gz*gz)",
        "pp = (x2 - x1)^2 + (y2 - y1)^2 + (z2 - z1)^2",
        "ax = x1 - x2", "ay = y1 - y2", "az = z1 - z2",
        "gx = x3 - x2", "gy = y3 - y2", "gz = z3 - z2",
        "ux = x2 - x1", "uy = y2 - y1", "uz = z2 - z1",
        "vx = x4 - x3", "vy = y4 - y3", "vz = z4 - z3",
        "wx = x1 - x3", "wy = y1 - y3", "wz = z1 - z3",
    ])
    f = openmm.CustomCompoundBondForce(4, expr)
    f.setName(name)
    f.addGlobalParameter(f"{name}_k", k * PN_NM_IN_KJ_MOL)
    f.addGlobalParameter(f"{name}_D", D)
    f.addPerBondParameter("kind")
    if len(quads) == 0:
        return f
    _, s, t = segment_distance(x[quads[:, 0]], x[quads[:, 1]], x[quads[:, 2]], x[quads[:, 3]])
    for q, si, ti in zip(quads, s, t):
        fs, ft = 0.0 < si < 1.0, 0.0 < ti < 1.0
        p_end = int(q[0] if si == 0.0 else q[1])
        q_end = int(q[2] if ti == 0.0 else q[3])
        if fs and ft:
            f.addBond([int(i) for i in q], [0.0])
        elif ft:  # an end of the first segment against the second's line
            f.addBond([p_end, int(q[2]), int(q[3]), int(q[0])], [1.0])
        elif fs:
            f.addBond([q_end, int(q[0]), int(q[1]), int(q[2])], [1.0])
        else:
            f.addBond([p_end, q_end, int(q[0]), int(q[2])], [2.0])
    return f


# ------------------------------------------------------------------------------------------
# Thermal variant: the same one-sided harmonic capsule contact as an openmm.PythonForce with
# a Verlet list of segment pairs on different chains (the excluded volume between strands of
# the tweezer scenes, contact="capsules"). The Lepton force above lists its pairs once and
# takes minutes to compile on the CPU platform; this one evaluates only the listed
# candidates with a compiled loop (numba, as the chiral force) or numpy.
# ------------------------------------------------------------------------------------------


def _capsule_loop(pos, seg, a, b, D, k, scale, out):
    """U = sum k/2 (D - d)^2 over the pairs (a, b) with d < D; adds scale * dU/dx to ``out``.

    The closest points are those of :func:`segment_distance` (Ericson 2005, Sec. 5.1.9), and
    dd/dx is the partial derivative at the minimiser (Danskin). Returns U (pN nm if k is in
    pN/nm)."""
    e_tot = 0.0
    for p in range(a.shape[0]):
        i0 = seg[a[p], 0]
        i1 = seg[a[p], 1]
        j0 = seg[b[p], 0]
        j1 = seg[b[p], 1]
        u0 = pos[i1, 0] - pos[i0, 0]
        u1 = pos[i1, 1] - pos[i0, 1]
        u2 = pos[i1, 2] - pos[i0, 2]
        v0 = pos[j1, 0] - pos[j0, 0]
        v1 = pos[j1, 1] - pos[j0, 1]
        v2 = pos[j1, 2] - pos[j0, 2]
        w0 = pos[i0, 0] - pos[j0, 0]
        w1 = pos[i0, 1] - pos[j0, 1]
        w2 = pos[i0, 2] - pos[j0, 2]
        aa = u0 * u0 + u1 * u1 + u2 * u2
        ee = v0 * v0 + v1 * v1 + v2 * v2
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
        d = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
        if not d < D:
            continue
        pen = D - d
        e_tot += 0.5 * k * pen * pen
        dd = max(d, 1e-12 * D)
        g = -k * pen / dd * scale  # dU/dd times the unit vector's 1/d
        n0 = g * r0
        n1 = g * r1
        n2 = g * r2
        out[i0, 0] += (1.0 - s) * n0
        out[i0, 1] += (1.0 - s) * n1
        out[i0, 2] += (1.0 - s) * n2
        out[i1, 0] += s * n0
        out[i1, 1] += s * n1
        out[i1, 2] += s * n2
        out[j0, 0] -= (1.0 - t) * n0
        out[j0, 1] -= (1.0 - t) * n1
        out[j0, 2] -= (1.0 - t) * n2
        out[j1, 0] -= t * n0
        out[j1, 1] -= t * n1
        out[j1, 2] -= t * n2
    return e_tot


class CapsuleEvaluator:
    """Picklable callable for the capsule PythonForce (local particle numbering).

    Keeps a Verlet list of segment pairs on different chains with midpoints closer than
    D + 2.5 skin + l_max/2 + (l_a + l_b)/2 (a pair can touch only if
    |m_a - m_b| < D + (l_a + l_b)/2; between builds no bead moves more than skin/2, so
    midpoints move < skin/2 and lengths change < skin). Counters ``n_calls``, ``n_builds``.
    """

    def __init__(self, seg, chain_id, contact_nm, skin_nm, parameter, backend="auto"):
        from .chiral import HAVE_NUMBA

        if backend not in ("auto", "numba", "numpy"):
            raise ValueError(f"backend must be 'auto', 'numba' or 'numpy', got {backend!r}")
        self.seg = np.ascontiguousarray(seg, np.int64)
        self.chain_id = np.ascontiguousarray(chain_id, np.int64)
        self.contact = float(contact_nm)
        self.skin = float(skin_nm)
        self.parameter = parameter
        self.numba = backend == "numba" or (backend == "auto" and HAVE_NUMBA)
        self.n_calls = 0
        self.n_builds = 0
        self._ref = None
        self._a = self._b = np.zeros(0, np.int64)

    def __getstate__(self):
        st = self.__dict__.copy()
        st["_ref"] = None
        return st

    def _build(self, pos):
        x0, x1 = pos[self.seg[:, 0]], pos[self.seg[:, 1]]
        ln = np.linalg.norm(x1 - x0, axis=1)
        reach = self.contact + 2.5 * self.skin + 0.5 * float(ln.max())
        if self.numba:
            from .chiral import build_pair_loop, compile_kernel

            zero = np.zeros(len(self.seg), np.int64)
            self._a, self._b = compile_kernel(build_pair_loop)(
                pos, self.seg, self.chain_id, zero, zero, np.zeros(len(self.seg), np.bool_),
                2**62, reach)
        else:
            from .chiral import grid_pairs

            mid = 0.5 * (x0 + x1)
            a, b = grid_pairs(mid, reach + float(ln.max()))
            d = np.linalg.norm(mid[b] - mid[a], axis=1)
            keep = (d < reach + 0.5 * (ln[a] + ln[b])) & (self.chain_id[a] != self.chain_id[b])
            self._a, self._b = a[keep], b[keep]
        self._ref = pos.copy()
        self.n_builds += 1

    def candidate_pairs(self, pos):
        if self._ref is None or self._ref.shape != pos.shape:
            self._build(pos)
        elif np.max(np.sum((pos - self._ref) ** 2, axis=1)) > 0.25 * self.skin**2:
            self._build(pos)
        return self._a, self._b

    def energy_grad(self, pos, k_pN_per_nm):
        """(U in pN nm, dU/dx in pN) at stiffness ``k_pN_per_nm``."""
        pos = np.ascontiguousarray(pos, np.float64)
        a, b = self.candidate_pairs(pos)
        grad = np.zeros_like(pos)
        if self.numba:
            from .chiral import compile_kernel

            e = compile_kernel(_capsule_loop)(pos, self.seg, a, b, self.contact, float(k_pN_per_nm),
                                    1.0, grad)
            return float(e), grad
        pairs = np.column_stack([a, b])
        e = contact_energy(pos, self.seg, pairs, self.contact, k_pN_per_nm)
        if len(pairs):
            nodes, (p0, p1, q0, q1), d, s, t = _pair_geometry(pos, self.seg, pairs)
            act = d < self.contact
            r = (p0 + s[:, None] * (p1 - p0)) - (q0 + t[:, None] * (q1 - q0))
            coef = np.where(act, -float(k_pN_per_nm) * (self.contact - d)
                            / np.maximum(d, 1e-12 * self.contact), 0.0)
            n = coef[:, None] * r
            for col, c in enumerate((1.0 - s, s, -(1.0 - t), -t)):
                np.add.at(grad, nodes[:, col], c[:, None] * n)
        return e, grad

    def __call__(self, state):
        self.n_calls += 1
        pos = np.ascontiguousarray(state.getPositions(asNumpy=True)._value, np.float64)
        k = state.getParameters()[self.parameter]  # kJ/mol/nm^2
        e, g = self.energy_grad(pos, k)  # kJ/mol, kJ/mol/nm
        return e, -g


def capsule_force(chains, contact_nm: float, k_pN_per_nm: float, *, skin_nm: float = 1.0,
                  name: str = "capsule", backend: str = "auto"):
    """Capsule excluded volume between the segments of different ``chains``: a PythonForce.

    U = sum k/2 (D_c - d)^2 for d < D_c, d the closest distance of two segments on different
    chains (:func:`contact_energy` is its numpy twin). Unloaded, two strands touch at exactly
    D_c whatever the beads' register: the contact distance of the chiral weight and of the
    continuum cross-checks.

    Parameters
    ----------
    chains : list of int arrays
        Ordered particle indices of each strand (global numbering).
    contact_nm : float
        D_c (nm).
    k_pN_per_nm : float
        Stiffness; the global parameter ``<name>_k`` holds it in kJ/mol/nm^2.
    skin_nm : float
        Verlet-list skin.
    backend : {"auto", "numba", "numpy"}

    Returns
    -------
    openmm.PythonForce
    """
    import openmm

    from .reference_chiral import segments_of

    if not (contact_nm > 0 and k_pN_per_nm > 0 and skin_nm > 0):
        raise ValueError(f"capsule_force: contact_nm, k_pN_per_nm and skin_nm must be > 0, got "
                         f"{contact_nm!r}, {k_pN_per_nm!r}, {skin_nm!r}")
    chains = [np.asarray(c, dtype=np.int64).ravel() for c in chains]
    particles = np.unique(np.concatenate(chains))
    local = {int(p): i for i, p in enumerate(particles)}
    seg, cid, _, _, _ = segments_of(chains)
    seg_local = np.vectorize(local.__getitem__, otypes=[np.int64])(seg)
    parameter = f"{name}_k"
    ev = CapsuleEvaluator(seg_local, cid, contact_nm, skin_nm, parameter, backend=backend)
    force = openmm.PythonForce(ev, {parameter: float(k_pN_per_nm) * PN_NM_IN_KJ_MOL})
    force.setParticles([int(p) for p in particles])
    force.setName(name)
    return force
