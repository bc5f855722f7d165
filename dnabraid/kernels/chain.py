"""Local energies of a bead chain, compiled with numba: the OpenMM terms of a tether
reproduced exactly, and their change when a few particles move.

Terms (dnabraid units: nm, pN, pN nm), each read from the Force of the same name in the
model's ``openmm.System`` (its parameters converted from kJ/mol once, with
:data:`dnabraid.units.PN_NM_IN_KJ_MOL`):

* ``stretch`` (``HarmonicBondForce``, :func:`dnabraid.forces.stretch_force`):
  U = k/2 (r - r0)^2 per bond;
* ``bend`` (``CustomAngleForce``, :func:`dnabraid.forces.bending_force`):
  U = kappa (1 + cos theta) = kappa (1 - cos beta) per hinge, theta the angle at the middle
  bead, beta = pi - theta the angle between consecutive bonds;
* ``wca`` (``CustomNonbondedForce``, :func:`dnabraid.forces.wca_force`):
  U = 4 eps [(s/r)^12 - (s/r)^6] + eps for r <= r_c = 2^(1/6) s (the force's own
  ``wca_rc``), over every pair that is not one of the force's exclusions (near neighbours
  along a chain, :func:`dnabraid.forces.wca_exclusions`) and, where the force carries the
  per-particle switch ``on``, between switched-on particles only;
* ``wall`` (``CustomExternalForce``, :func:`dnabraid.forces.wall_force`):
  U = k/2 (z_w - z)^2 for z < z_w, for the force's particles;
* ``pull`` (``CustomExternalForce``, :func:`dnabraid.forces.pull_force`):
  U = -F share_i z_i.
* ``frame``, ``twist`` and the bead's plane ``beadwall`` of torsionally constrained DNA
  (the plectoneme: frame springs, twist joints and clamps,
  :mod:`dnabraid.forces.twist_frames`): twins in :mod:`dnabraid.kernels.twist`.
* ``capsule`` (the segment contact between strands) and ``chiral`` (the Kornyshev term),
  both ``openmm.PythonForce`` s: twins in :mod:`dnabraid.kernels.segment_terms`, their
  parameters read from the evaluator the force carries.

A Force is recognised by its name and type and its energy expression is checked against
the expression its factory writes, so a changed factory fails loudly here instead of
silently differing. A System with any other Force (a changed factory, another Python
callable) is refused: :class:`LocalEnergy` would not know its energy.

Pairs within the WCA range are found with a spatial hash: a uniform grid of cells of
:data:`CELL_FACTOR` x r_c = 2 r_c, so that the ball of radius r_c about a point touches
2 x 2 x 2 cells (measured faster than 27 cells of r_c for tethers: fewer buckets to visit),
whose cells are hashed into a power-of-two table of singly linked buckets (Teschner et al.,
"Optimized spatial hashing for collision detection of deformable objects", VMV 2003). A
particle records its cell, and a bucket's members are matched against the queried cell, so
hash collisions cost time but never a wrong or doubled pair. The table is built once per
call (O(N)) and updated in place when an accepted move changes a particle's cell.

The energy change of a move touches only the moved particles: bonds and hinges with a
moved member, their wall and pull terms, WCA pairs of a moved with an unmoved particle
(from the hash) and, unless the move is rigid, pairs of two moved particles. A rigid move
(rotation of a whole set, as crankshaft and pivot moves are) keeps every distance, angle
and pair energy within the moved set, so those are skipped (they change by round-off
only). Inside the Monte Carlo loop (:func:`run_chain_moves`) three shortcuts leave every
decision unchanged: the old WCA pairs are not searched while no pair interacts (the loop
keeps the number of interacting pairs, counted afresh at every call); the Metropolis test is made against the threshold
-kT ln u drawn first, so a move is rejected as soon as the bonded, wall and pull change
plus the WCA energy found so far exceed it (WCA pair energies are >= 0); and a pivot that
moves more particles than it leaves searches the pairs from the unmoved side, the unmoved
particles turned back by R^T (the same distances).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numba
import numpy as np
import openmm
from openmm import unit as u

from ..forces import (
    bead_exclusion_force,
    bending_force,
    pull_force,
    trap_force,
    wall_force,
    wca_force,
)
from ..units import PN_NM_IN_KJ_MOL
from . import segment_terms as _sg
from . import twist as _tw

__all__ = ["LocalEnergy", "TERMS", "run_chain_moves"]

#: The terms a :class:`LocalEnergy` knows, in the order of its term arrays.
TERMS = ("stretch", "bend", "wca", "wall", "pull", "link", "trap", "beadwall", "frame",
         "twist", "capsule", "chiral")
#: Number of terms (length of every per-term array).
NTERMS = len(TERMS)

#: Cell coordinates are clamped to +-2^20 cells (5 mm at 5-nm cells) and packed in 21 bits
#: each; clamping is monotone and 1-Lipschitz, so neighbouring cells stay neighbours.
_CELL_OFF = 1 << 20
_CELL_MAX = (1 << 20) - 2

#: Hash-grid cell size / r_c (>= 1; a query scans the cells that the ball of radius r_c
#: touches).
CELL_FACTOR = 2.0

# Parameters of the terms, in numba-friendly arrays (a namedtuple is passed whole to the
# compiled functions). Index arrays int64, per-particle flags uint8, energies pN nm.
_Params = namedtuple("_Params", [
    "n",
    # bonds (i, j) of stretch, link and beadwall: k (pN/nm), r0 (nm), term index b_t,
    # one-sided flag b_one (beadwall: energy only for r < r0); per-particle CSR of the
    # bonds it is in
    "has_bond", "b_i", "b_j", "b_k", "b_r0", "b_t", "b_one", "b_ptr", "b_list",
    # bend: hinges (i, j, k) and kappa (pN nm); per-particle CSR of the hinges it is in
    "has_bend", "a_i", "a_j", "a_k", "kappa", "a_ptr", "a_list",
    # wca: switch per particle, eps (pN nm), sigma^2, r_c^2 (nm^2), cell size (nm),
    # sorted per-particle CSR of excluded partners
    "has_wca", "w_on", "eps", "sig2", "rc", "rc2", "cell", "e_ptr", "e_list",
    # wall: per-particle flag, k (pN/nm), z_w (nm)
    "has_wall", "wall_on", "wall_k", "wall_z",
    # pull: share per particle, F (pN)
    "has_pull", "share", "pull_f",
    # trap: particles (t_i, t_j), K (pN nm), cos and sin of the angle, tilt k (pN/nm)
    "has_trap", "t_i", "t_j", "trap_K", "trap_c", "trap_s", "trap_kt",
    # twist joints (dnabraid.kernels.twist): type (0 interior, 1 surface clamp, 2 bead
    # clamp), particles (padded with -1) and their number, g (pN nm), fixed vectors (clamp
    # tangent and material vector, or bead axis); per-particle CSR of the joints it is in
    "has_twist", "j_type", "j_p", "j_np", "j_g", "j_vec", "j_ptr", "j_list",
    # the bead's plane (beadwall of a plectoneme): attachment, per-particle bond count, k
    "has_plane", "pl_att", "pl_on", "pl_cnt", "pl_k",
    # capsule contact between chains and the chiral term (dnabraid.kernels.segment_terms):
    # segments (global particle numbers), chain of each, D_c (nm), k (pN/nm); the chiral
    # term's chain, position in chain, segments per chain, ring flag, exclusion along a
    # chain, sample points q, weight (D_c, range, r_s, r_c in nm), N(eta') coefficients and
    # alpha (pN)
    "has_cap", "cap_seg", "cap_cid", "cap_D", "cap_k",
    "has_chi", "chi_seg", "chi_cid", "chi_pic", "chi_nseg", "chi_ring", "chi_excl", "chi_q",
    "chi_delta", "chi_rho", "chi_rs", "chi_rc", "chi_ncoef", "chi_alpha",
])

_Hash = namedtuple("_Hash", ["head", "nxt", "key", "bucket", "inv_cell", "mask"])


# ----------------------------------------------------------------------------- spatial hash
@numba.njit(cache=True)
def _cells(x, y, z, inv_cell):
    cx = math.floor(x * inv_cell)
    cy = math.floor(y * inv_cell)
    cz = math.floor(z * inv_cell)
    cx = min(max(cx, -_CELL_MAX), _CELL_MAX)
    cy = min(max(cy, -_CELL_MAX), _CELL_MAX)
    cz = min(max(cz, -_CELL_MAX), _CELL_MAX)
    return np.int64(cx), np.int64(cy), np.int64(cz)


@numba.njit(cache=True)
def _key(cx, cy, cz):
    return ((cx + _CELL_OFF) << 42) | ((cy + _CELL_OFF) << 21) | (cz + _CELL_OFF)


@numba.njit(cache=True)
def _bucket(cx, cy, cz, mask):
    return ((cx * 73856093) ^ (cy * 19349663) ^ (cz * 83492791)) & mask


@numba.njit(cache=True)
def _hash_insert(H, p, x, y, z):
    cx, cy, cz = _cells(x, y, z, H.inv_cell)
    b = _bucket(cx, cy, cz, H.mask)
    H.key[p] = _key(cx, cy, cz)
    H.bucket[p] = b
    H.nxt[p] = H.head[b]
    H.head[b] = p


@numba.njit(cache=True)
def _hash_remove(H, p):
    b = H.bucket[p]
    q = H.head[b]
    if q == p:
        H.head[b] = H.nxt[p]
    else:
        while q >= 0:
            if H.nxt[q] == p:
                H.nxt[q] = H.nxt[p]
                break
            q = H.nxt[q]
    H.nxt[p] = -1
    H.bucket[p] = -1


@numba.njit(cache=True)
def hash_move(H, p, x, y, z):
    """Re-file particle p (already in the table) at (x, y, z) if its cell changed."""
    cx, cy, cz = _cells(x, y, z, H.inv_cell)
    if _key(cx, cy, cz) != H.key[p]:
        _hash_remove(H, p)
        _hash_insert(H, p, x, y, z)


@numba.njit(cache=True)
def hash_build(pos, on, cell_nm):
    n = pos.shape[0]
    nb = 64
    while nb < 2 * n:
        nb *= 2
    H = _Hash(np.full(nb, -1, np.int64), np.full(n, -1, np.int64), np.zeros(n, np.int64),
              np.full(n, -1, np.int64), 1.0 / cell_nm, np.int64(nb - 1))
    for p in range(n):
        if on[p]:
            _hash_insert(H, p, pos[p, 0], pos[p, 1], pos[p, 2])
    return H


# ------------------------------------------------------------------------------- pair terms
@numba.njit(cache=True)
def _excluded(P, p, q):
    for t in range(P.e_ptr[p], P.e_ptr[p + 1]):
        if P.e_list[t] == q:
            return True
    return False


@numba.njit(cache=True)
def _wca_pair(r2, P):
    if r2 > P.rc2:  # OpenMM: step(rc - r) is 1 at r = rc
        return 0.0
    s6 = (P.sig2 / r2) ** 3
    return 4.0 * P.eps * (s6 * s6 - s6) + P.eps


@numba.njit(cache=True)
def _wca_site(P, H, pos, moved, p, x, y, z, qmin, stop, of_moved=False):
    """WCA energy (pN nm) and number of pairs within r_c of particle p placed at
    (x, y, z) with every switched-on, non-excluded particle q > qmin in the table that is
    unmoved (``of_moved`` False) or moved (True); the sum stops early once it exceeds
    ``stop`` (pair energies are >= 0)."""
    rc = P.rc
    inv = H.inv_cell
    xlo, ylo, zlo = _cells(x - rc, y - rc, z - rc, inv)
    xhi, yhi, zhi = _cells(x + rc, y + rc, z + rc, inv)
    e = 0.0
    cnt = 0
    for cx in range(xlo, xhi + 1):
        for cy in range(ylo, yhi + 1):
            for cz in range(zlo, zhi + 1):
                k = _key(cx, cy, cz)
                q = H.head[_bucket(cx, cy, cz, H.mask)]
                while q >= 0:
                    if H.key[q] == k and q > qmin and q != p and (moved[q] > 0) == of_moved:
                        ddx = pos[q, 0] - x
                        ddy = pos[q, 1] - y
                        ddz = pos[q, 2] - z
                        r2 = ddx * ddx + ddy * ddy + ddz * ddz
                        if r2 <= P.rc2 and not _excluded(P, p, q):
                            e += _wca_pair(r2, P)
                            cnt += 1
                            if e > stop:
                                return e, cnt
                    q = H.nxt[q]
    return e, cnt


# ----------------------------------------------------------------------- bonded helpers
@numba.njit(cache=True)
def _at(pos, new, moved, p, c):
    """Coordinate c of particle p after the move (``moved[p]`` = slot + 1, 0 = unmoved)."""
    s = moved[p]
    if s > 0:
        return new[s - 1, c]
    return pos[p, c]


@numba.njit(cache=True)
def _bond_e(xi, yi, zi, xj, yj, zj, k, r0, one):
    dx = xj - xi
    dy = yj - yi
    dz = zj - zi
    d = math.sqrt(dx * dx + dy * dy + dz * dz) - r0
    if one and d >= 0.0:  # one-sided (beadwall): step(R - r)
        return 0.0
    return 0.5 * k * d * d


@numba.njit(cache=True)
def _trap_e(xi, yi, zi, xj, yj, zj, P):
    dx = xj - xi
    dy = yj - yi
    dz = zj - zi
    return -P.trap_K * (dx * P.trap_c + dy * P.trap_s) / math.sqrt(dx * dx + dy * dy) \
        + 0.5 * P.trap_kt * dz * dz


@numba.njit(cache=True)
def _trap_at(pos, new, moved, P):
    i = P.t_i
    j = P.t_j
    return _trap_e(_at(pos, new, moved, i, 0), _at(pos, new, moved, i, 1),
                   _at(pos, new, moved, i, 2), _at(pos, new, moved, j, 0),
                   _at(pos, new, moved, j, 1), _at(pos, new, moved, j, 2), P)


@numba.njit(cache=True)
def _bend_e(xi, yi, zi, xj, yj, zj, xk, yk, zk, kappa):
    ax = xj - xi
    ay = yj - yi
    az = zj - zi
    bx = xk - xj
    by = yk - yj
    bz = zk - zj
    c = (ax * bx + ay * by + az * bz) / math.sqrt(
        (ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz))
    return kappa * (1.0 - c)


@numba.njit(cache=True)
def _wall_e(z, P):
    d = P.wall_z - z
    if d > 0.0:
        return 0.5 * P.wall_k * d * d
    return 0.0


# --------------------------------------------------------------------------- energies
@numba.njit(cache=True)
def wca_all(pos, P, H):
    """WCA energy (pN nm) and number of interacting pairs (r <= r_c) of the whole model."""
    moved = np.zeros(P.n, np.int64)
    e = 0.0
    cnt = 0
    for p in range(P.n):
        if P.w_on[p]:
            de, dc = _wca_site(P, H, pos, moved, p, pos[p, 0], pos[p, 1], pos[p, 2], p,
                               np.inf)
            e += de
            cnt += dc
    return e, cnt


@numba.njit(cache=True)
def _total(pos, P, out):
    """Every term's energy (pN nm) at ``pos`` into ``out`` (order of :data:`TERMS`)."""
    for t in range(out.shape[0]):
        out[t] = 0.0
    if P.has_bond:
        for b in range(P.b_i.shape[0]):
            i = P.b_i[b]
            j = P.b_j[b]
            out[P.b_t[b]] += _bond_e(pos[i, 0], pos[i, 1], pos[i, 2], pos[j, 0], pos[j, 1],
                                     pos[j, 2], P.b_k[b], P.b_r0[b], P.b_one[b])
    if P.has_bend:
        for a in range(P.a_i.shape[0]):
            i = P.a_i[a]
            j = P.a_j[a]
            k = P.a_k[a]
            out[1] += _bend_e(pos[i, 0], pos[i, 1], pos[i, 2], pos[j, 0], pos[j, 1],
                              pos[j, 2], pos[k, 0], pos[k, 1], pos[k, 2], P.kappa)
    if P.has_wca:
        out[2] = wca_all(pos, P, hash_build(pos, P.w_on, P.cell))[0]
    for p in range(P.n):
        if P.has_wall and P.wall_on[p]:
            out[3] += _wall_e(pos[p, 2], P)
        if P.has_pull and P.share[p] != 0.0:
            out[4] -= P.pull_f * P.share[p] * pos[p, 2]
    if P.has_trap:
        i = P.t_i
        j = P.t_j
        out[6] = _trap_e(pos[i, 0], pos[i, 1], pos[i, 2], pos[j, 0], pos[j, 1], pos[j, 2], P)
    if P.has_plane:
        out[7] += _tw.plane_total(pos, P)
    if P.has_twist:
        out[9] = _tw.twist_total(pos, P)
    if P.has_cap:
        out[10] = _sg.capsule_total(pos, P)
    if P.has_chi:
        out[11] = _sg.chiral_total(pos, P)


#: Moves of more particles than this (rigid or not) take their WCA change from two
#: sweeps along z (:func:`_wca_sweep`).
_SWEEP_MIN = 24


@numba.njit(cache=True)
def _wca_sweep(P, pos, new, moved, after):
    """WCA energy (pN nm) and number of interacting pairs of all switched-on particles,
    before the move (``after`` False) or after it (moved particles at ``new``). Sort and
    sweep along z (Baraff 1992): particles sorted by z, each paired only with those above
    it within r_c in z. Exact for any configuration; O(n log n + pairs) for chains
    stretched along z, where searching the table from each moved particle of a collective
    move (83 of the long braid's 83) walks every neighbour cell's moved particles too."""
    n = P.n
    ids = np.empty(n, np.int64)
    k = 0
    for p in range(n):
        if P.w_on[p]:
            ids[k] = p
            k += 1
    xyz = np.empty((k, 3))
    for a in range(k):
        p = ids[a]
        s = moved[p] if after else 0
        for c in range(3):
            xyz[a, c] = new[s - 1, c] if s > 0 else pos[p, c]
    order = np.argsort(xyz[:, 2])
    e = 0.0
    cnt = 0
    for ai in range(k):
        a = order[ai]
        p = ids[a]
        for bi in range(ai + 1, k):
            c = order[bi]
            if xyz[c, 2] - xyz[a, 2] > P.rc:
                break
            q = ids[c]
            dx = xyz[c, 0] - xyz[a, 0]
            dy = xyz[c, 1] - xyz[a, 1]
            dz = xyz[c, 2] - xyz[a, 2]
            r2 = dx * dx + dy * dy + dz * dz
            if r2 <= P.rc2 and not _excluded(P, p, q):
                e += _wca_pair(r2, P)
                cnt += 1
    return e, cnt


@numba.njit(cache=True)
def _wca_cross(P, pos, new, moved, after):
    """WCA energy (pN nm) and number of interacting pairs between the moved and the
    unmoved switched-on particles, the moved ones at their old (``after`` False) or new
    positions. A rigid move keeps every moved-moved and unmoved-unmoved pair, so its WCA
    change is ``_wca_cross(after) - _wca_cross(before)``. Only particles inside the other
    set's bounding box grown by r_c can take part; those are sorted along z and swept
    (Baraff 1992) as in :func:`_wca_sweep`. For a pivot of a stretched tether (the two
    sets meet near the pivot) the band holds a few particles instead of all of them."""
    n = P.n
    rc = P.rc
    big = np.inf
    lo_m = np.full(3, big)
    hi_m = np.full(3, -big)
    lo_u = np.full(3, big)
    hi_u = np.full(3, -big)
    xyz = np.empty((n, 3))
    for p in range(n):
        if not P.w_on[p]:
            continue
        s = moved[p]
        if s > 0:
            for c in range(3):
                v = new[s - 1, c] if after else pos[p, c]
                xyz[p, c] = v
                lo_m[c] = min(lo_m[c], v)
                hi_m[c] = max(hi_m[c], v)
        else:
            for c in range(3):
                v = pos[p, c]
                xyz[p, c] = v
                lo_u[c] = min(lo_u[c], v)
                hi_u[c] = max(hi_u[c], v)
    ids = np.empty(n, np.int64)
    k = 0
    for p in range(n):
        if not P.w_on[p]:
            continue
        if moved[p] > 0:
            lo, hi = lo_u, hi_u
        else:
            lo, hi = lo_m, hi_m
        if (xyz[p, 0] >= lo[0] - rc and xyz[p, 0] <= hi[0] + rc
                and xyz[p, 1] >= lo[1] - rc and xyz[p, 1] <= hi[1] + rc
                and xyz[p, 2] >= lo[2] - rc and xyz[p, 2] <= hi[2] + rc):
            ids[k] = p
            k += 1
    zs = np.empty(k)
    for a in range(k):
        zs[a] = xyz[ids[a], 2]
    order = np.argsort(zs)
    e = 0.0
    cnt = 0
    for ai in range(k):
        p = ids[order[ai]]
        mp = moved[p] > 0
        for bi in range(ai + 1, k):
            q = ids[order[bi]]
            dz = xyz[q, 2] - xyz[p, 2]
            if dz > rc:
                break
            if (moved[q] > 0) == mp:
                continue
            dx = xyz[q, 0] - xyz[p, 0]
            dy = xyz[q, 1] - xyz[p, 1]
            r2 = dx * dx + dy * dy + dz * dz
            if r2 <= P.rc2 and not _excluded(P, p, q):
                e += _wca_pair(r2, P)
                cnt += 1
    return e, cnt


@numba.njit(cache=True)
def delta_kernel(pos, idx, new, moved, rigid, P, H, out, thr, ncon, dcon, flip, rinv, center,
                 bonded):
    """Energy change (pN nm) when particles ``idx`` move to ``new``; per term into ``out``.

    ``moved[p]`` must hold the slot + 1 of every moved particle (0 for the others) and
    ``H`` the table of the unmoved particles' positions (moved particles in it are
    skipped). ``rigid``: the move is a rigid motion of the moved set, whose internal terms
    are then left out. ``ncon``: interacting WCA pairs before the move (0: none, so the
    moved particles' old WCA energy is 0 and is not searched for). The change of that
    number goes to ``dcon[0]``. The WCA search of the new positions stops, and the
    function returns +inf, as soon as the change is known to exceed ``thr`` (a Metropolis
    test that will reject; WCA pair energies are >= 0, so partial sums only grow).

    ``flip`` (rigid moves only): the moved set was turned by R about ``center``, and the
    moved-unmoved pairs are searched from the unmoved side instead (cheaper when it is the
    smaller set): |R (p - c) - (q - c)| = |(p - c) - R^T (q - c)|, so the new pairs are the
    moved particles' old positions against the unmoved ones turned back by ``rinv`` = R^T.

    ``bonded``: the moved particles whose bonds, hinges and twist joints are searched
    (``idx`` itself in general; for a rigid move any subset holding every moved member of
    each term that also has an unmoved member, e.g. the few particles next to a pivot; a
    rigid move leaves the other terms unchanged). Per-particle terms (wall, pull) are
    taken over all of ``idx``.

    Moves of more than ``_SWEEP_MIN`` particles take the WCA change as the difference of
    the WCA energy after and before, without the early stop (``flip`` is then not used):
    of every pair (:func:`_wca_sweep`), or for a rigid move of the moved-unmoved pairs
    alone (:func:`_wca_cross`).
    """
    for t in range(out.shape[0]):
        out[t] = 0.0
    dcon[0] = 0
    m = idx.shape[0]
    for a in range(m):
        p = idx[a]
        if P.has_wall and P.wall_on[p]:
            out[3] += _wall_e(new[a, 2], P) - _wall_e(pos[p, 2], P)
        if P.has_pull and P.share[p] != 0.0:
            out[4] -= P.pull_f * P.share[p] * (new[a, 2] - pos[p, 2])
    for a in range(bonded.shape[0]):
        p = bonded[a]
        if P.has_bond:
            for t in range(P.b_ptr[p], P.b_ptr[p + 1]):
                b = P.b_list[t]
                i = P.b_i[b]
                j = P.b_j[b]
                q = j if i == p else i
                if moved[q] > 0 and (rigid or q < p):
                    continue
                e0 = _bond_e(pos[i, 0], pos[i, 1], pos[i, 2], pos[j, 0], pos[j, 1],
                             pos[j, 2], P.b_k[b], P.b_r0[b], P.b_one[b])
                # the new coordinates written out (through _at, 6 calls of ~20 ns each)
                si = moved[i] - 1
                sj = moved[j] - 1
                e1 = _bond_e(new[si, 0] if si >= 0 else pos[i, 0],
                             new[si, 1] if si >= 0 else pos[i, 1],
                             new[si, 2] if si >= 0 else pos[i, 2],
                             new[sj, 0] if sj >= 0 else pos[j, 0],
                             new[sj, 1] if sj >= 0 else pos[j, 1],
                             new[sj, 2] if sj >= 0 else pos[j, 2],
                             P.b_k[b], P.b_r0[b], P.b_one[b])
                out[P.b_t[b]] += e1 - e0
        if P.has_bend:
            for t in range(P.a_ptr[p], P.a_ptr[p + 1]):
                h = P.a_list[t]
                i = P.a_i[h]
                j = P.a_j[h]
                k = P.a_k[h]
                # count a hinge once, from its first moved member
                first = i if moved[i] > 0 else (j if moved[j] > 0 else k)
                if first != p:
                    continue
                if rigid and moved[i] > 0 and moved[j] > 0 and moved[k] > 0:
                    continue
                e0 = _bend_e(pos[i, 0], pos[i, 1], pos[i, 2], pos[j, 0], pos[j, 1],
                             pos[j, 2], pos[k, 0], pos[k, 1], pos[k, 2], P.kappa)
                si = moved[i] - 1
                sj = moved[j] - 1
                sk = moved[k] - 1
                e1 = _bend_e(new[si, 0] if si >= 0 else pos[i, 0],
                             new[si, 1] if si >= 0 else pos[i, 1],
                             new[si, 2] if si >= 0 else pos[i, 2],
                             new[sj, 0] if sj >= 0 else pos[j, 0],
                             new[sj, 1] if sj >= 0 else pos[j, 1],
                             new[sj, 2] if sj >= 0 else pos[j, 2],
                             new[sk, 0] if sk >= 0 else pos[k, 0],
                             new[sk, 1] if sk >= 0 else pos[k, 1],
                             new[sk, 2] if sk >= 0 else pos[k, 2], P.kappa)
                out[1] += e1 - e0
    if P.has_twist:
        out[9] += _tw.twist_delta(pos, bonded, new, moved, rigid, P)
    if P.has_plane:
        out[7] += _tw.plane_delta(pos, idx, new, moved, P)
    if P.has_trap and (moved[P.t_i] > 0 or moved[P.t_j] > 0):
        # (not skipped for rigid moves: a rotation about a tilted axis turns the chord)
        i = P.t_i
        j = P.t_j
        out[6] += _trap_at(pos, new, moved, P) - _trap_e(pos[i, 0], pos[i, 1], pos[i, 2],
                                                         pos[j, 0], pos[j, 1], pos[j, 2], P)
    # the segment terms before the WCA: its early stop needs the rest of the change known
    if P.has_cap:
        out[10] += _sg.capsule_delta(pos, new, moved, rigid, P)
    if P.has_chi:
        out[11] += _sg.chiral_delta(pos, new, moved, rigid, P)
    if P.has_wca:
        if m > _SWEEP_MIN:
            # a large moved set: the WCA energy before and after by sweeps along z, of the
            # moved-unmoved pairs only for a rigid move (the others are kept)
            if rigid:
                e1, c1 = _wca_cross(P, pos, new, moved, True)
                e0, c0 = _wca_cross(P, pos, new, moved, False)
            else:
                e1, c1 = _wca_sweep(P, pos, new, moved, True)
                e0, c0 = _wca_sweep(P, pos, new, moved, False)
            out[2] += e1 - e0
            dcon[0] += c1 - c0
            if _sum(out) > thr:
                return np.inf
            return _sum(out)
        # pairs of two moved particles (a rigid move keeps them)
        if not rigid:
            for a in range(m):
                p = idx[a]
                if not P.w_on[p]:
                    continue
                for c in range(a + 1, m):
                    q = idx[c]
                    if not P.w_on[q] or _excluded(P, p, q):
                        continue
                    dx = new[c, 0] - new[a, 0]
                    dy = new[c, 1] - new[a, 1]
                    dz = new[c, 2] - new[a, 2]
                    r2 = dx * dx + dy * dy + dz * dz
                    if r2 <= P.rc2:
                        out[2] += _wca_pair(r2, P)
                        dcon[0] += 1
                    dx = pos[q, 0] - pos[p, 0]
                    dy = pos[q, 1] - pos[p, 1]
                    dz = pos[q, 2] - pos[p, 2]
                    r2 = dx * dx + dy * dy + dz * dz
                    if r2 <= P.rc2:
                        out[2] -= _wca_pair(r2, P)
                        dcon[0] -= 1
        # moved against unmoved: the old pairs first (none when nothing interacts) ...
        if ncon > 0:
            if flip:
                for q in range(P.n):
                    if P.w_on[q] and moved[q] == 0:
                        e, c = _wca_site(P, H, pos, moved, q, pos[q, 0], pos[q, 1],
                                         pos[q, 2], -1, np.inf, True)
                        out[2] -= e
                        dcon[0] -= c
            else:
                for a in range(m):
                    p = idx[a]
                    if P.w_on[p]:
                        e, c = _wca_site(P, H, pos, moved, p, pos[p, 0], pos[p, 1],
                                         pos[p, 2], -1, np.inf)
                        out[2] -= e
                        dcon[0] -= c
        # ... then the new ones, stopping once the move is sure to be rejected
        rest = _sum(out)
        if rest > thr:
            return np.inf
        if flip:
            for q in range(P.n):
                if P.w_on[q] and moved[q] == 0:
                    x = pos[q, 0] - center[0]
                    y = pos[q, 1] - center[1]
                    z = pos[q, 2] - center[2]
                    e, c = _wca_site(P, H, pos, moved, q,
                                     rinv[0, 0] * x + rinv[0, 1] * y + rinv[0, 2] * z
                                     + center[0],
                                     rinv[1, 0] * x + rinv[1, 1] * y + rinv[1, 2] * z
                                     + center[1],
                                     rinv[2, 0] * x + rinv[2, 1] * y + rinv[2, 2] * z
                                     + center[2], -1, thr - rest, True)
                    out[2] += e
                    rest += e
                    dcon[0] += c
                    if rest > thr:
                        return np.inf
        else:
            for a in range(m):
                p = idx[a]
                if P.w_on[p]:
                    e, c = _wca_site(P, H, pos, moved, p, new[a, 0], new[a, 1], new[a, 2],
                                     -1, thr - rest)
                    out[2] += e
                    rest += e
                    dcon[0] += c
                    if rest > thr:
                        return np.inf
    elif _sum(out) > thr:
        return np.inf
    return _sum(out)


@numba.njit(cache=True)
def _sum(out):
    s = 0.0
    for t in range(out.shape[0]):
        s += out[t]
    return s


@numba.njit(cache=True)
def _delta_once(pos, idx, new, P, out):
    """:func:`delta_kernel` with a table built for this call and any move (not rigid)."""
    moved = np.zeros(P.n, np.int64)
    for a in range(idx.shape[0]):
        moved[idx[a]] = a + 1
    if P.has_wca:
        H = hash_build(pos, P.w_on, P.cell)
    else:
        H = hash_build(pos[:0], P.w_on[:0], 1.0)
    dcon = np.zeros(1, np.int64)
    return delta_kernel(pos, idx, new, moved, False, P, H, out, np.inf, 1, dcon, False,
                        np.eye(3), np.zeros(3), idx)


# ------------------------------------------------------------------------ Monte Carlo
@numba.njit(cache=True)
def rotation_matrix(ax, ay, az, theta):
    """Rotation matrix by ``theta`` about the unit vector (ax, ay, az) (Rodrigues)."""
    c = math.cos(theta)
    s = math.sin(theta)
    t = 1.0 - c
    R = np.empty((3, 3))
    R[0, 0] = c + ax * ax * t
    R[0, 1] = ax * ay * t - az * s
    R[0, 2] = ax * az * t + ay * s
    R[1, 0] = ay * ax * t + az * s
    R[1, 1] = c + ay * ay * t
    R[1, 2] = ay * az * t - ax * s
    R[2, 0] = az * ax * t - ay * s
    R[2, 1] = az * ay * t + ax * s
    R[2, 2] = c + az * az * t
    return R


@numba.njit(cache=True)
def apply_accepted(pos, new, idx, m, P, H, terms, dterm):
    """Move the ``m`` particles ``idx`` of an accepted move to ``new``, keep the spatial
    hash in step and add the move's per-term changes ``dterm`` to ``terms``."""
    for c in range(terms.shape[0]):
        terms[c] += dterm[c]
    for a in range(m):
        p = idx[a]
        pos[p, 0] = new[a, 0]
        pos[p, 1] = new[a, 1]
        pos[p, 2] = new[a, 2]
        if P.has_wca and P.w_on[p]:
            hash_move(H, p, new[a, 0], new[a, 1], new[a, 2])


@numba.njit(cache=True)
def ball_proposal(pos, mobile, nmob, bead_nm, gx, gy, gz, u_pick, u_rad, new):
    """A single-particle proposal: a mobile particle (from ``u_pick``) displaced uniformly in
    the ball of radius ``bead_nm`` (direction from the Gaussian (gx, gy, gz), radius
    bead_nm u^(1/3)): symmetric. Writes the new position into ``new[0]``; returns the
    particle, or -1 when there is none to move."""
    nrm = math.sqrt(gx * gx + gy * gy + gz * gz)
    if nmob == 0 or nrm == 0.0:
        return -1
    p = mobile[min(int(u_pick * nmob), nmob - 1)]
    rad = bead_nm * u_rad ** (1.0 / 3.0) / nrm
    new[0, 0] = pos[p, 0] + rad * gx
    new[0, 1] = pos[p, 1] + rad * gy
    new[0, 2] = pos[p, 2] + rad * gz
    return p


@numba.njit(cache=True)
def crank_proposal(pos, c_beads, c_fixed, s, nb, crank_max, crank_angle, u_pos, u_len, u_ang):
    """A crankshaft proposal on the strand whose beads are ``c_beads[s:s + nb]``: an arc
    i..j of 1 ... ``crank_max`` beads (never the strand's first or last bead) turned by an
    angle uniform in [-``crank_angle``, ``crank_angle``] about the line through beads i-1
    and j+1 (Vologodskii et al. 1992), from three uniforms in [0, 1).

    Returns (ok, i, j, pa, pb, R, nrm): ``ok`` False when the strand is too short, a fixed
    bead would move or the pivots coincide; ``pa``, ``pb`` the pivot particles, ``R`` the
    rotation, ``nrm`` the pivots' distance (nm).
    """
    R = np.eye(3)
    mmax = min(crank_max, nb - 2)
    if mmax < 1:
        return False, 0, 0, 0, 0, R, 0.0
    ln = 1 + min(int(u_len * mmax), mmax - 1)
    i = 1 + min(int(u_pos * (nb - 1 - ln)), nb - 2 - ln)
    j = i + ln - 1
    pa = c_beads[s + i - 1]
    pb = c_beads[s + j + 1]
    ax = pos[pb, 0] - pos[pa, 0]
    ay = pos[pb, 1] - pos[pa, 1]
    az = pos[pb, 2] - pos[pa, 2]
    nrm = math.sqrt(ax * ax + ay * ay + az * az)
    if c_fixed[s + j + 1] - c_fixed[s + i] > 0 or nrm < 1e-9:
        return False, i, j, pa, pb, R, nrm
    R = rotation_matrix(ax / nrm, ay / nrm, az / nrm, crank_angle * (2.0 * u_ang - 1.0))
    return True, i, j, pa, pb, R, nrm


@numba.njit(cache=True)
def rotate_into(pos, R, cx, cy, cz, p, new, a):
    x = pos[p, 0] - cx
    y = pos[p, 1] - cy
    z = pos[p, 2] - cz
    new[a, 0] = R[0, 0] * x + R[0, 1] * y + R[0, 2] * z + cx
    new[a, 1] = R[1, 0] * x + R[1, 1] * y + R[1, 2] * z + cy
    new[a, 2] = R[2, 0] * x + R[2, 1] * y + R[2, 2] * z + cz


@numba.njit(cache=True)
def loop_setup(pos, P, nterms):
    """The working state every compiled move loop starts from: the WCA hash of ``pos``,
    the number of interacting WCA pairs, the number of WCA particles, and scratch arrays
    (dcon, moved, idx, new, dterm) for :func:`delta_kernel` and :func:`apply_accepted`."""
    n = pos.shape[0]
    if P.has_wca:
        H = hash_build(pos, P.w_on, P.cell)
    else:
        H = hash_build(pos[:0], P.w_on[:0], 1.0)
    ncon = wca_all(pos, P, H)[1] if P.has_wca else 0
    n_on = 0
    if P.has_wca:
        for p in range(n):
            if P.w_on[p]:
                n_on += 1
    return (H, ncon, n_on, np.zeros(1, np.int64), np.zeros(n, np.int64),
            np.empty(n, np.int64), np.empty((n, 3)), np.zeros(nterms))


@numba.njit(cache=True)
def run_chain_moves(pos, P, c_ptr, c_beads, c_fixed, mobile, cum, crank_max, crank_angle,
                    pivot_angle, bead_nm, kT, uni, gau, stats, terms):
    """Metropolis crankshaft, pivot and bead moves on ``pos`` (modified in place).

    Parameters
    ----------
    pos : float64 (N, 3), nm
    P : _Params
    c_ptr, c_beads : int64
        Chains in CSR form: beads of chain c are ``c_beads[c_ptr[c]:c_ptr[c + 1]]``.
    c_fixed : int64 (len(c_beads) + 1,)
        Prefix counts of immobile beads along ``c_beads``.
    mobile : int64
        Mobile chain beads (for bead moves).
    cum : float64 (3,)
        Cumulative probabilities of crankshaft, pivot, bead moves.
    crank_max : int
        Most beads of a crankshaft arc.
    crank_angle, pivot_angle : float
        Largest rotation angles (rad).
    bead_nm : float
        Radius of the bead move's ball (nm).
    kT : float
        pN nm.
    uni : float64 (n, 6), gau : float64 (n, 3)
        Uniform [0, 1) and standard normal numbers, one row per proposal.
    stats : int64 (3, 3)
        Added to: rows crankshaft, pivot, bead; columns attempted, refused, accepted.
    terms : float64 (NTERMS,)
        Added to: the accepted energy change of each term (pN nm).

    Returns
    -------
    float
        Sum of |dE| over the accepted moves (pN nm), the scale of the round-off in
        ``terms``.
    """
    nch = c_ptr.shape[0] - 1
    nmob = mobile.shape[0]
    H, ncon, n_on, dcon, moved, idx, new, dterm = loop_setup(pos, P, terms.shape[0])
    rinv = np.eye(3)
    center = np.zeros(3)
    absum = 0.0
    for t in range(uni.shape[0]):
        r = uni[t, 0]
        kind = 0 if r < cum[0] else (1 if r < cum[1] else 2)
        stats[kind, 0] += 1
        flip = False
        ch = min(int(uni[t, 1] * nch), nch - 1)
        s = c_ptr[ch]
        nb = c_ptr[ch + 1] - s
        m = 0
        if kind == 0:
            # crankshaft: beads i..j turned about the line through beads i-1 and j+1
            ok, i, j, pa, pb, R, nrm = crank_proposal(pos, c_beads, c_fixed, s, nb, crank_max,
                                                      crank_angle, uni[t, 2], uni[t, 3],
                                                      uni[t, 4])
            if not ok:
                stats[kind, 1] += 1
                continue
            for k in range(i, j + 1):
                p = c_beads[s + k]
                rotate_into(pos, R, pos[pa, 0], pos[pa, 1], pos[pa, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
        elif kind == 1:
            # pivot: beads i..end turned about bead i-1 by a random rotation
            if nb < 2:
                stats[kind, 1] += 1
                continue
            i = 1 + min(int(uni[t, 2] * (nb - 1)), nb - 2)
            gx = gau[t, 0]
            gy = gau[t, 1]
            gz = gau[t, 2]
            nrm = math.sqrt(gx * gx + gy * gy + gz * gz)
            if c_fixed[s + nb] - c_fixed[s + i] > 0 or nrm == 0.0:
                stats[kind, 1] += 1
                continue
            theta = pivot_angle * (2.0 * uni[t, 4] - 1.0)
            R = rotation_matrix(gx / nrm, gy / nrm, gz / nrm, theta)
            pc = c_beads[s + i - 1]
            m_on = 0
            for k in range(i, nb):
                p = c_beads[s + k]
                rotate_into(pos, R, pos[pc, 0], pos[pc, 1], pos[pc, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
                if P.has_wca and P.w_on[p]:
                    m_on += 1
            if n_on - m_on < m_on:
                # fewer unmoved than moved particles: search the pairs from their side
                flip = True
                rinv = rotation_matrix(gx / nrm, gy / nrm, gz / nrm, -theta)  # R^T, bitwise
                for c in range(3):
                    center[c] = pos[pc, c]
        else:
            # one bead displaced uniformly in a ball
            p = ball_proposal(pos, mobile, nmob, bead_nm, gau[t, 0], gau[t, 1], gau[t, 2],
                              uni[t, 2], uni[t, 3], new)
            if p < 0:
                stats[kind, 1] += 1
                continue
            idx[0] = p
            m = 1
            moved[p] = 1
        # Metropolis: accept when dE <= 0 or u < exp(-dE / kT), i.e. dE < -kT ln u
        thr = -kT * math.log(uni[t, 5]) if uni[t, 5] > 0.0 else np.inf
        dE = delta_kernel(pos, idx[:m], new[:m], moved, kind < 2, P, H, dterm, thr, ncon, dcon,
                          flip, rinv, center, idx[:m])
        if math.isfinite(dE) and (dE <= 0.0 or dE < thr):
            ncon += dcon[0]
            stats[kind, 2] += 1
            absum += abs(dE)
            apply_accepted(pos, new, idx, m, P, H, terms, dterm)
        for a in range(m):
            moved[idx[a]] = 0
    return absum


# ------------------------------------------------------------------------------ Python API
def _csr(n: int, members: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-particle lists of the rows of ``members`` (rows x k) that contain it."""
    rows = np.repeat(np.arange(len(members)), members.shape[1]) if members.size else \
        np.zeros(0, np.int64)
    parts = members.ravel()
    order = np.argsort(parts, kind="stable")
    ptr = np.zeros(n + 1, np.int64)
    np.add.at(ptr, parts + 1, 1)
    return np.cumsum(ptr).astype(np.int64), rows[order].astype(np.int64)


def _global(force, name: str) -> float:
    for k in range(force.getNumGlobalParameters()):
        if force.getGlobalParameterName(k) == name:
            return float(force.getGlobalParameterDefaultValue(k))
    raise ValueError(f"LocalEnergy: force {force.getName()!r} has no global parameter {name!r}")


def _check_expr(force, expected: str) -> None:
    got = force.getEnergyFunction()
    if got != expected:
        raise ValueError(f"LocalEnergy: force {force.getName()!r} has the energy {got!r}; the "
                         f"kernel reproduces {expected!r} only")


class LocalEnergy:
    """The energy of a bead-chain model and its change under local moves, compiled.

    Parameters
    ----------
    model : dnabraid.chains.Model or openmm.System
        A built model (or its System) whose System holds only the terms of :data:`TERMS`
        (any subset, named as the chain kit names them). Parameters are the Forces'
        default values (a protocol that changes a global parameter in the Context is not
        seen).

    Attributes
    ----------
    terms : tuple of str
        The terms present, a subset of :data:`TERMS`.
    n : int
        Particles.
    n_constraints : int
        Rigid bonds of the System (moves that change a bond length would break them).

    Raises
    ------
    ValueError
        For a Force the kernels do not reproduce (another name, type or expression).
    """

    def __init__(self, model):
        system = model if isinstance(model, openmm.System) else model.system
        n = system.getNumParticles()
        self.n = n
        self.n_constraints = system.getNumConstraints()
        z = np.zeros(0, np.int64)
        fz = np.zeros(0)
        p = dict(n=n, has_bond=False, b_i=z, b_j=z, b_k=fz, b_r0=fz, b_t=z,
                 b_one=np.zeros(0, np.uint8), b_ptr=np.zeros(n + 1, np.int64), b_list=z,
                 has_bend=False, a_i=z, a_j=z, a_k=z, kappa=0.0,
                 a_ptr=np.zeros(n + 1, np.int64), a_list=z,
                 has_wca=False, w_on=np.zeros(n, np.uint8), eps=0.0, sig2=1.0, rc=0.0, rc2=0.0,
                 cell=1.0, e_ptr=np.zeros(n + 1, np.int64), e_list=z,
                 has_wall=False, wall_on=np.zeros(n, np.uint8), wall_k=0.0, wall_z=0.0,
                 has_pull=False, share=np.zeros(n), pull_f=0.0,
                 has_trap=False, t_i=0, t_j=0, trap_K=0.0, trap_c=1.0, trap_s=0.0,
                 trap_kt=0.0, has_twist=False, j_type=z, j_p=np.zeros((0, 5), np.int64),
                 j_np=z, j_g=fz, j_vec=np.zeros((0, 6)), j_ptr=np.zeros(n + 1, np.int64),
                 j_list=z, has_plane=False, pl_att=0, pl_on=np.zeros(n, np.uint8),
                 pl_cnt=np.zeros(n), pl_k=0.0, **_sg.segment_fields(n))
        present = []
        bonds = []  # (i, j, k, r0, term, one-sided) of stretch, link, beadwall, frame
        joints = []  # (type, particles, g, fixed vectors) of the twist forces
        self._trap_angle = None
        for f in system.getForces():
            name = f.getName()
            if name in ("stretch", "link", "frame") and isinstance(f,
                                                                  openmm.HarmonicBondForce):
                t = TERMS.index(name)
                for b in range(f.getNumBonds()):
                    i, j, r, kk = f.getBondParameters(b)
                    bonds.append((i, j, kk.value_in_unit(u.kilojoule_per_mole / u.nanometer**2)
                                  / PN_NM_IN_KJ_MOL, r.value_in_unit(u.nanometer), t, 0))
            elif name == "beadwall" and isinstance(f, openmm.CustomBondForce):
                _check_expr(f, bead_exclusion_force(0, [], 1.0, 1.0, name=name)
                            .getEnergyFunction())
                k = _global(f, f"{name}_k") / PN_NM_IN_KJ_MOL
                r0 = _global(f, f"{name}_R")
                for b in range(f.getNumBonds()):
                    i, j, _ = f.getBondParameters(b)
                    bonds.append((i, j, k, r0, TERMS.index(name), 1))
            elif name in _tw.TWIST_NAMES and isinstance(f, openmm.CustomCompoundBondForce):
                joints.extend(_tw.read_twist_force(f))
                name = "twist"
            elif name == "beadwall" and isinstance(f, openmm.CustomCompoundBondForce):
                p.update(_tw.read_plane_force(f, n))
            elif name == "trap" and isinstance(f, openmm.CustomCompoundBondForce):
                _check_expr(f, trap_force(0, 1, 1.0, name=name).getEnergyFunction())
                if f.getNumBonds() != 1:
                    raise ValueError(f"LocalEnergy: force {name!r} must hold one bond")
                (i, j), _ = f.getBondParameters(0)
                ang = _global(f, f"{name}_angle")
                p.update(has_trap=True, t_i=int(i), t_j=int(j),
                         trap_K=_global(f, f"{name}_K") / PN_NM_IN_KJ_MOL,
                         trap_c=math.cos(ang), trap_s=math.sin(ang),
                         trap_kt=_global(f, f"{name}_ktilt") / PN_NM_IN_KJ_MOL)
                self._trap_angle = ang
            elif name == "bend" and isinstance(f, openmm.CustomAngleForce):
                _check_expr(f, bending_force([], 1.0, name=name).getEnergyFunction())
                na = f.getNumAngles()
                ijk = np.array([f.getAngleParameters(a)[:3] for a in range(na)],
                               np.int64).reshape(-1, 3)
                ptr, lst = _csr(n, ijk)
                p.update(has_bend=na > 0, a_i=ijk[:, 0].copy(), a_j=ijk[:, 1].copy(),
                         a_k=ijk[:, 2].copy(), kappa=_global(f, f"{name}_kappa")
                         / PN_NM_IN_KJ_MOL, a_ptr=ptr, a_list=lst)
            elif name == "wca" and isinstance(f, openmm.CustomNonbondedForce):
                self._read_wca(f, n, p)
            elif name == "wall" and isinstance(f, openmm.CustomExternalForce):
                _check_expr(f, wall_force([], 0.0, 1.0, name=name).getEnergyFunction())
                on = np.zeros(n, np.uint8)
                for k in range(f.getNumParticles()):
                    on[f.getParticleParameters(k)[0]] = 1
                p.update(has_wall=bool(on.any()), wall_on=on,
                         wall_k=_global(f, f"{name}_k") / PN_NM_IN_KJ_MOL,
                         wall_z=_global(f, f"{name}_z"))
            elif name == "capsule" and isinstance(f, openmm.PythonForce):
                p.update(_sg.capsule_params(f))
            elif name == "chiral" and isinstance(f, openmm.PythonForce):
                p.update(_sg.chiral_params(f))
            elif name == "pull" and isinstance(f, openmm.CustomExternalForce):
                _check_expr(f, pull_force([], [], 1.0, name=name).getEnergyFunction())
                share = np.zeros(n)
                for k in range(f.getNumParticles()):
                    i, par = f.getParticleParameters(k)
                    share[i] += float(par[0])
                p.update(has_pull=bool(share.any()), share=share,
                         pull_f=_global(f, f"{name}_f") / PN_NM_IN_KJ_MOL)
            else:
                raise ValueError(f"LocalEnergy: no kernel for force {name!r} "
                                 f"({type(f).__name__}); it knows {', '.join(TERMS)}")
            present.append(name)
        if bonds:
            ij = np.array([b[:2] for b in bonds], np.int64).reshape(-1, 2)
            ptr, lst = _csr(n, ij)
            p.update(has_bond=True, b_i=ij[:, 0].copy(), b_j=ij[:, 1].copy(),
                     b_k=np.array([b[2] for b in bonds], float),
                     b_r0=np.array([b[3] for b in bonds], float),
                     b_t=np.array([b[4] for b in bonds], np.int64),
                     b_one=np.array([b[5] for b in bonds], np.uint8), b_ptr=ptr, b_list=lst)
        if joints:
            p.update(_tw.joint_params(n, joints))
        self.terms = tuple(t for t in TERMS if t in present)
        self.params = _Params(**p)
        self._out = np.zeros(NTERMS)

    def _read_wca(self, f, n: int, p: dict) -> None:
        name = f.getName()
        switched = f.getNumPerParticleParameters() > 0
        _check_expr(f, wca_force(0, 1.0, 1.0, particles=[] if switched else None,
                                 name=name).getEnergyFunction())
        if f.getNonbondedMethod() != openmm.CustomNonbondedForce.CutoffNonPeriodic \
                or f.getNumInteractionGroups() or f.getUseSwitchingFunction():
            raise ValueError(f"LocalEnergy: force {name!r} must be a plain non-periodic "
                             "cutoff without interaction groups or switching")
        sigma = _global(f, f"{name}_sigma")
        rc = min(_global(f, f"{name}_rc"), f.getCutoffDistance().value_in_unit(u.nanometer))
        on = np.ones(n, np.uint8)
        if switched:
            for k in range(n):
                on[k] = 1 if f.getParticleParameters(k)[0] != 0.0 else 0
        ne = f.getNumExclusions()
        ex = np.array([f.getExclusionParticles(k) for k in range(ne)], np.int64).reshape(-1, 2)
        both = np.concatenate([ex, ex[:, ::-1]])
        both = both[np.lexsort((both[:, 1], both[:, 0]))]
        ptr = np.zeros(n + 1, np.int64)
        np.add.at(ptr, both[:, 0] + 1, 1)
        p.update(has_wca=True, w_on=on, eps=_global(f, f"{name}_eps") / PN_NM_IN_KJ_MOL,
                 sig2=sigma * sigma, rc=rc, rc2=rc * rc, cell=CELL_FACTOR * rc, e_ptr=np.cumsum(ptr),
                 e_list=both[:, 1].copy())

    @property
    def trap_angle(self) -> float | None:
        """The trap's angle phi0 (rad) the kernels use; None without a trap."""
        return self._trap_angle

    def set_trap_angle(self, angle_rad: float) -> None:
        """Use the trap angle ``angle_rad`` (the protocol's ``trap_angle``, which the
        System's default value does not follow)."""
        if not self.params.has_trap:
            raise ValueError("LocalEnergy: no trap")
        a = float(angle_rad)
        if a != self._trap_angle:
            self._trap_angle = a
            self.params = self.params._replace(trap_c=math.cos(a), trap_s=math.sin(a))

    @property
    def pull_force(self) -> float | None:
        """The pulling force (pN) the kernels use; None without a pull term."""
        return float(self.params.pull_f) if self.params.has_pull else None

    def set_pull_force(self, force_pN: float) -> None:
        """Use the pulling force ``force_pN`` (pN; the ``pull`` term -F sum_i s_i z_i with
        the System's shares s_i) instead of the System's: the rungs of a force ladder
        (:class:`dnabraid.run.ladder.ForceLadder`)."""
        if not self.params.has_pull:
            raise ValueError("LocalEnergy: no pull term")
        self.params = self.params._replace(pull_f=float(force_pN))

    def _pos(self, pos) -> np.ndarray:
        pos = np.ascontiguousarray(pos, dtype=np.float64)
        if pos.shape != (self.n, 3):
            raise ValueError(f"positions must have shape ({self.n}, 3), got {pos.shape}")
        return pos

    def total_terms(self, pos) -> dict:
        """Energy of each present term at ``pos`` (nm), pN nm."""
        _total(self._pos(pos), self.params, self._out)
        return {t: float(self._out[TERMS.index(t)]) for t in self.terms}

    def total(self, pos) -> float:
        """Total energy at ``pos`` (nm), pN nm."""
        _total(self._pos(pos), self.params, self._out)
        return float(self._out.sum())

    def _delta(self, pos, idx, new_xyz):
        pos = self._pos(pos)
        idx = np.ascontiguousarray(np.atleast_1d(idx), dtype=np.int64)
        new = np.ascontiguousarray(new_xyz, dtype=np.float64).reshape(-1, 3)
        if len(idx) != len(new) or len(np.unique(idx)) != len(idx):
            raise ValueError("idx must be distinct particles, one row of new_xyz each")
        if len(idx) and (idx.min() < 0 or idx.max() >= self.n):
            raise ValueError(f"idx out of range [0, {self.n})")
        return float(_delta_once(pos, idx, new, self.params, self._out))

    def delta(self, pos, idx, new_xyz) -> float:
        """Energy change (pN nm) when particles ``idx`` move from ``pos`` to ``new_xyz``
        (shape (len(idx), 3), nm), from the moved particles alone."""
        return self._delta(pos, idx, new_xyz)

    def delta_terms(self, pos, idx, new_xyz) -> dict:
        """:meth:`delta` per present term (pN nm)."""
        self._delta(pos, idx, new_xyz)
        return {t: float(self._out[TERMS.index(t)]) for t in self.terms}
