"""Compiled Metropolis moves of the braid (two strands, their attachments and the magnetic
bead's centre), on the local energies of :mod:`dnabraid.kernels.chain` (which reproduce
the braid's ``link``, ``trap``, ``beadwall`` and ``pull`` terms as well as the chains').

Kinds (rows of the statistics, in this order):

0. ``crankshaft``: an arc i..j of one strand (1 ... ``crank_max`` beads, no immobile bead),
   turned about the line through beads i-1 and j+1 (the arc ends at most one bead below
   the attachment, which is never in it);
1. ``bead``: one mobile particle (strand beads, attachments, bead centre) displaced
   uniformly in a ball;
2. ``shear``: the top (bead centre and both attachments) translated by d, d uniform in
   the cylinder |d_xy| <= ``shear_nm``, |d_z| <= ``shear_z_nm``, and strand bead k by
   w_k d, w_k = k / (beads - 1) (0 at the surface, 1 at the attachment): the pendulum of
   the whole top. A fixed linear map of the positions (Jacobian 1, d and -d equally
   likely), so plain Metropolis is exact;
3. ``twist``: every particle turned about the vertical axis through the bead centre by
   w_k theta (centre and attachments by theta), theta uniform in [-``twist_rad``,
   ``twist_rad``]: the top's rotation in the trap with the strands following. Each
   particle's map is a rotation about an axis the move does not change (the centre's
   position), so Jacobian 1 and the reverse move is -theta.
4. ``sway``: each strand turned rigidly by the same rotation R (a horizontal axis of
   uniform direction, angle uniform in [-``sway_rad``, ``sway_rad``]) about its own
   anchor (its first bead), the bead centre translated by the mean displacement of the two
   attachments: the pendulum of the top with the strands' bond lengths, bends and stored
   length kept (the four-bar linkage of two strands and a rigid top). The shear's affine
   map stretches every bond of a strand that is not straight (a 10 nm shear of the long
   braid costs about 17 kT of stretch), the sway only the links at the top. The map is a
   rotation of each strand and a translation of the centre by a function of the strands
   (block triangular, Jacobian 1); the reverse move is R^-1, as likely, so plain
   Metropolis is exact.
5. ``pivot``: bead k (uniform in 1 ... shorter strand - 1) of both strands: beads k ...
   of both strands turned rigidly by theta (uniform in [-``pivot_rad``, ``pivot_rad``])
   about the line through bead k - 1 of strand 1 and bead k - 1 of strand 2, the bead
   centre translated by the attachments' mean displacement (as in the sway: turning the
   centre with them would swing the 0.5-1 um bead about the attachments). Every strand
   bond keeps its length, and each strand's end-to-end
   distance changes at first order in theta wherever it is bent at bead k - 1: the
   stored length, hence the extension, which crankshafts (they keep the chord of their
   arc), the sway and the twist cannot change and which bead moves change only by
   diffusion along the strand. The axis is made of beads the move does not move, so the
   reverse move is -theta (Jacobian 1, as the sway's).
6. ``tilt``: the bead centre alone turned by theta (uniform in [-``tilt_rad``,
   ``tilt_rad``]) about the line through the two attachments: the bead's tilt about its
   attachments, resisted only by the force on the centre (the link bonds keep their
   lengths; std sqrt(kT / (F R)), 0.064 rad for R = 0.5 um at 2 pN), which the sway and
   the pivot leave alone. The axis is made of particles the move does not move (reverse
   -theta, Jacobian 1).
7. ``stretch``: the extension with the strands' slack. With the top fixed no move but the
   top's changes the extension, and the shear's vertical part stretches every bond (its
   steps are ~0.5 nm on the long braid, the extension's spread ~4 nm). Here, for each
   strand with anchor A and attachment T, positions relative to A are mapped
   z -> lambda z and the horizontal deviation from the line A-T, h = d_xy - d_xy(T) z /
   z(T), -> mu h (the attachment's horizontal offset kept): the strand rises and
   straightens together, bond lengths kept on average for mu = lambda^-a with
   a = <b_z^2> / <b_xy^2> (``stretch_ratio``). log lambda is uniform in
   [-``stretch_eps``, ``stretch_eps``]; the centre follows the attachments' mean
   displacement. The map is triangular with the constant Jacobian lambda^N mu^(2(N-1)) per
   strand of N mobile beads; the reverse move (1/lambda, 1/mu) is as likely, so the
   acceptance is min(1, J exp(-dE / kT)) (Metropolis-Hastings).
8. ``breathe``: the braid's radius with its extension. The stretch move keeps the strands'
   deviations from their own anchor-attachment lines in shape; a braid's radius, the
   distance between its two strands, is a slower mode (the extension follows it with
   correlation -0.57 on the long braid at n = 2) that crankshafts open only in many small
   steps. A window of pairs k0 ... k0 + w (the two strands' beads of the same index; 2
   <= w <= ``breathe_max``, k0 >= 1, k0 + w below the attachments) is opened about each
   pair's midpoint: the horizontal half-difference of pair k is scaled by mu^t_k, t_k a
   tent (0 at k0 and k0 + w, 1 in the middle), log mu uniform in [-``breathe_eps``,
   ``breathe_eps``]. Every bond of the window keeps its length: its height u is replaced
   by sign(u) sqrt(u^2 + h - h'), h and h' its squared horizontal extents before and after;
   everything above the window (strand beads and attachments) shifts vertically by its
   strand's change in height, the bead centre by the attachments' mean. The map is block
   triangular (horizontal first, then heights given them) with Jacobian prod_k mu^(2 t_k)
   prod_bonds |u / u'|, and the reverse move (1/mu, same window) undoes it exactly, so the
   acceptance is min(1, J exp(-dE / kT)) (Metropolis-Hastings). A bond that would have to
   lie flatter than horizontal refuses the move (its reverse never needs it).

Topology: a move may pass one strand through the other, which the Brownian dynamics
cannot (excluded volume). Every proposal that the Metropolis test would accept is checked,
first by :func:`no_passage`: if no segment of one ray-extended strand can meet a segment
of the other while every vertex moves on the straight line between its two places (a
bound from the segments' closest distances before and after and their relative
displacement), no crossing changed and the move is allowed without a Gauss sum (20 us on
the long braid against 120 us for the sum). Otherwise the catenation (Gauss integral of
the two strands closed by vertical rays, :func:`dnabraid.geometry.curves.catenation_number`,
twinned here) may not change by more than 0.5 turn, or the move is refused (statistics
column 1): the pre-test decides only moves whose Gauss answer it knows, so the chain of
states is the same with or without it. Crankshafts and bead moves only test the changed
segments against the other strand, and only when the other strand (rays included) comes
within the ball that the moved segments sweep (a rotation keeps every distance to a point
of its axis, so a crankshaft sweeps inside the ball about the axis' midpoint through its
farthest bead). The catenation itself is recomputed only when a Gauss test needs it and
at the end of the loop.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .chain import (
    apply_accepted,
    ball_proposal,
    crank_proposal,
    delta_kernel,
    loop_setup,
    rotate_into,
    rotation_matrix,
)

__all__ = ["BRAID_KINDS", "catenation", "no_passage", "run_braid_moves"]

#: Move kinds, in the order of :func:`run_braid_moves`' statistics rows.
BRAID_KINDS = ("crankshaft", "bead", "shear", "twist", "sway", "pivot", "tilt",
               "stretch", "breathe")


# ------------------------------------------------------------------------------- catenation
@numba.njit(cache=True)
def _tri(v1x, v1y, v1z, v2x, v2y, v2z, v3x, v3y, v3z):
    n1 = math.sqrt(v1x * v1x + v1y * v1y + v1z * v1z)
    n2 = math.sqrt(v2x * v2x + v2y * v2y + v2z * v2z)
    n3 = math.sqrt(v3x * v3x + v3y * v3y + v3z * v3z)
    if n1 == 0.0 or n2 == 0.0 or n3 == 0.0:
        return 0.0
    num = v1x * (v2y * v3z - v2z * v3y) + v1y * (v2z * v3x - v2x * v3z) \
        + v1z * (v2x * v3y - v2y * v3x)
    den = n1 * n2 * n3 + (v1x * v2x + v1y * v2y + v1z * v2z) * n3 \
        + (v1x * v3x + v1y * v3y + v1z * v3z) * n2 + (v2x * v3x + v2y * v3y + v2z * v3z) * n1
    return 2.0 * math.atan2(num, den)


@numba.njit(cache=True)
def _omega(a, b, c, d):
    """Signed solid angle of segment a->b against c->d (curves.pair_solid_angles)."""
    v1x = c[0] - a[0]
    v1y = c[1] - a[1]
    v1z = c[2] - a[2]
    v2x = c[0] - b[0]
    v2y = c[1] - b[1]
    v2z = c[2] - b[2]
    v3x = d[0] - b[0]
    v3y = d[1] - b[1]
    v3z = d[2] - b[2]
    v4x = d[0] - a[0]
    v4y = d[1] - a[1]
    v4z = d[2] - a[2]
    return _tri(v1x, v1y, v1z, v2x, v2y, v2z, v3x, v3y, v3z) + _tri(
        v1x, v1y, v1z, v3x, v3y, v3z, v4x, v4y, v4z)


@numba.njit(cache=True)
def _fill(pos, new, moved, use_new, beads, ray, out):
    """The vertices of a strand extended by vertical rays into ``out`` (n + 2, 3): 0 below
    bead 0, 1 ... n the beads, n + 1 above the last bead; at the positions before
    (``use_new`` False) or after the move (``new`` at the moved particles)."""
    n = beads.shape[0]
    for e in range(n + 2):
        k = min(max(e - 1, 0), n - 1)
        p = beads[k]
        s = moved[p] if use_new else 0
        for c in range(3):
            out[e, c] = new[s - 1, c] if s > 0 else pos[p, c]
    out[0, 2] -= ray
    out[n + 1, 2] += ray


@numba.njit(cache=True)
def _gauss(V1, lo1, hi1, V2, lo2, hi2):
    """Gauss sum / 4 pi over segments lo1..hi1 of the extended strand 1 (vertices ``V1``)
    and lo2..hi2 of strand 2 (segment e joins vertices e and e + 1)."""
    tot = 0.0
    for e in range(lo1, hi1 + 1):
        for f in range(lo2, hi2 + 1):
            tot += _omega(V1[e], V1[e + 1], V2[f], V2[f + 1])
    return tot / (4.0 * math.pi)


@numba.njit(cache=True)
def _seg_dist(p0, p1, q0, q1):
    """Closest distance of segments [p0, p1] and [q0, q1] (Ericson 2005, Sec. 5.1.9, as
    :func:`dnabraid.forces.segment_contact.segment_distance`)."""
    ux = p1[0] - p0[0]
    uy = p1[1] - p0[1]
    uz = p1[2] - p0[2]
    vx = q1[0] - q0[0]
    vy = q1[1] - q0[1]
    vz = q1[2] - q0[2]
    wx = p0[0] - q0[0]
    wy = p0[1] - q0[1]
    wz = p0[2] - q0[2]
    a = ux * ux + uy * uy + uz * uz
    e = vx * vx + vy * vy + vz * vz
    b = ux * vx + uy * vy + uz * vz
    c = ux * wx + uy * wy + uz * wz
    f = vx * wx + vy * wy + vz * wz
    den = a * e - b * b
    s = 0.0
    if den > 1e-14 * a * e:
        s = min(max((b * f - c * e) / den, 0.0), 1.0)
    t = 0.0
    if e > 1e-300:
        t = min(max((b * s + f) / e, 0.0), 1.0)
    s = 0.0
    if a > 1e-300:
        s = min(max((b * t - c) / a, 0.0), 1.0)
    rx = wx + s * ux - t * vx
    ry = wy + s * uy - t * vy
    rz = wz + s * uz - t * vz
    return math.sqrt(rx * rx + ry * ry + rz * rz)


@numba.njit(cache=True)
def _spheres(V, out):
    """Bounding sphere (midpoint, half length) of every segment of an extended strand:
    ``out[e] = (mx, my, mz, r)``."""
    for e in range(V.shape[0] - 1):
        dx = V[e + 1, 0] - V[e, 0]
        dy = V[e + 1, 1] - V[e, 1]
        dz = V[e + 1, 2] - V[e, 2]
        out[e, 0] = 0.5 * (V[e + 1, 0] + V[e, 0])
        out[e, 1] = 0.5 * (V[e + 1, 1] + V[e, 1])
        out[e, 2] = 0.5 * (V[e + 1, 2] + V[e, 2])
        out[e, 3] = 0.5 * math.sqrt(dx * dx + dy * dy + dz * dz)


@numba.njit(cache=True)
def _sphere_gap(S1, e, S2, f):
    dx = S1[e, 0] - S2[f, 0]
    dy = S1[e, 1] - S2[f, 1]
    dz = S1[e, 2] - S2[f, 2]
    return math.sqrt(dx * dx + dy * dy + dz * dz) - S1[e, 3] - S2[f, 3]


@numba.njit(cache=True)
def no_passage(V1, W1, V2, W2, lo1, hi1, lo2, hi2, S):
    """True when no segment lo1..hi1 of strand 1 can meet a segment lo2..hi2 of strand 2
    while every vertex moves on the straight line from its place before (``V1``, ``V2``)
    to its place after the move (``W1``, ``W2``); then the move changed no crossing and
    the catenation only continuously. A sufficient test, exact in the sense that it never
    says True for a path on which two segments meet.

    For points a(s), b(u) of the two segments, a - b moves from r0(s, u) to r1(s, u) along
    r0 + t D(s, u), and D is bilinear in (s, u), so |D| <= delta, the largest relative
    displacement of the four pairs of end vertices. |a - b| >= d0 - t delta and >= d1 -
    (1 - t) delta at every t, with d0, d1 the segments' closest distances before and after:
    the segments cannot meet when d0 + d1 > delta. Lower bounds of d0 and d1 from the
    segments' bounding spheres are tried first; the exact closest distances only where
    they do not decide. ``S`` is scratch of shape (4, max n + 1, 4). The test and its
    reverse are the same (delta and d0 + d1 are symmetric), so a Metropolis rule that uses
    it keeps detailed balance.
    """
    _spheres(V1, S[0])
    _spheres(W1, S[1])
    _spheres(V2, S[2])
    _spheres(W2, S[3])
    for e in range(lo1, hi1 + 1):
        for f in range(lo2, hi2 + 1):
            d2 = 0.0
            for i in range(e, e + 2):
                for j in range(f, f + 2):
                    dx = W1[i, 0] - V1[i, 0] - W2[j, 0] + V2[j, 0]
                    dy = W1[i, 1] - V1[i, 1] - W2[j, 1] + V2[j, 1]
                    dz = W1[i, 2] - V1[i, 2] - W2[j, 2] + V2[j, 2]
                    d2 = max(d2, dx * dx + dy * dy + dz * dz)
            delta = math.sqrt(d2) * (1.0 + 1e-9) + 1e-9
            g0 = _sphere_gap(S[0], e, S[2], f)
            g1 = _sphere_gap(S[1], e, S[3], f)
            if g0 + g1 > delta:
                continue
            d0 = _seg_dist(V1[e], V1[e + 1], V2[f], V2[f + 1])
            d1 = _seg_dist(W1[e], W1[e + 1], W2[f], W2[f + 1])
            if d0 + d1 > delta:
                continue
            return False
    return True


@numba.njit(cache=True)
def _extent(pos, b1, b2):
    best = 1e-12
    for beads in (b1, b2):
        for c in range(3):
            lo = np.inf
            hi = -np.inf
            for k in range(beads.shape[0]):
                v = pos[beads[k], c]
                lo = min(lo, v)
                hi = max(hi, v)
            best = max(best, hi - lo)
    return best


@numba.njit(cache=True)
def _catenation(pos, b1, b2, ray):
    moved = np.zeros(1, np.int64)
    V1 = np.empty((b1.shape[0] + 2, 3))
    V2 = np.empty((b2.shape[0] + 2, 3))
    _fill(pos, pos[:0], moved, False, b1, ray, V1)
    _fill(pos, pos[:0], moved, False, b2, ray, V2)
    return _gauss(V1, 0, b1.shape[0], V2, 0, b2.shape[0])


def catenation(pos, strand1, strand2, ray_length: float | None = None) -> float:
    """Compiled twin of :func:`dnabraid.geometry.curves.catenation_number` (strands given
    as bead indices into ``pos``)."""
    pos = np.ascontiguousarray(pos, np.float64)
    b1 = np.ascontiguousarray(strand1, np.int64)
    b2 = np.ascontiguousarray(strand2, np.int64)
    ray = 1e4 * _extent(pos, b1, b2) if ray_length is None else float(ray_length)
    return float(_catenation(pos, b1, b2, ray))


@numba.njit(cache=True)
def _seg_point_d2(ax, ay, az, bx, by, bz, px, py, pz):
    """Squared distance from point p to segment a-b."""
    ux = bx - ax
    uy = by - ay
    uz = bz - az
    wx = px - ax
    wy = py - ay
    wz = pz - az
    uu = ux * ux + uy * uy + uz * uz
    t = 0.0
    if uu > 0.0:
        t = min(max((wx * ux + wy * uy + wz * uz) / uu, 0.0), 1.0)
    dx = wx - t * ux
    dy = wy - t * uy
    dz = wz - t * uz
    return dx * dx + dy * dy + dz * dz


@numba.njit(cache=True)
def _near(V, cx, cy, cz, r2):
    """Whether a segment of the ray-extended strand with vertices ``V`` comes within
    sqrt(r2) of c."""
    for e in range(V.shape[0] - 1):
        if _seg_point_d2(V[e, 0], V[e, 1], V[e, 2], V[e + 1, 0], V[e + 1, 1], V[e + 1, 2],
                         cx, cy, cz) <= r2:
            return True
    return False


# ------------------------------------------------------------------------------- the loop
@numba.njit(cache=True)
def _breathe_proposal(pos, b1, b2, c_ptr, c_fixed, wmax_beads, eps, u_w, u_k, new, idx,
                      moved, logjac):
    """The breathe move (module docstring, kind 8) into ``new``/``idx``/``moved``: returns
    the number of moved particles and puts log J in ``logjac[0]``, or -(count + 1) when
    the move is refused (the caller clears ``moved`` of the first count entries)."""
    nmin = min(b1.shape[0], b2.shape[0])
    wmax = min(wmax_beads, nmin - 3)
    if wmax < 2:
        return -1
    w = 2 + int(u_w * (wmax - 1))
    k0 = 1 + int(u_k * (nmin - 2 - w))
    for c in range(2):
        g0 = c_ptr[c]
        if c_fixed[c_ptr[c + 1]] - c_fixed[g0 + k0] > 0:
            return -1  # an immobile bead at or above the window
    m = 0
    lj = 0.0
    # horizontal: the half-difference of pair k scaled by mu^t_k about the pair's midpoint
    for k in range(k0 + 1, k0 + w):
        tk = 1.0 - abs(2.0 * (k - k0) / w - 1.0)
        f = math.exp(eps * tk)
        p1 = b1[k]
        p2 = b2[k]
        for d in range(2):
            c = 0.5 * (pos[p1, d] + pos[p2, d])
            h = 0.5 * (pos[p1, d] - pos[p2, d])
            new[m, d] = c + f * h
            new[m + 1, d] = c - f * h
        idx[m] = p1
        idx[m + 1] = p2
        moved[p1] = m + 1
        moved[p2] = m + 2
        m += 2
        lj += 2.0 * eps * tk
    # vertical: each bond of the window keeps its length (its height from the new
    # horizontal extent, same sign); everything above shifts by the strand's change
    for c in range(2):
        bs = b1 if c == 0 else b2
        nb = bs.shape[0]
        zprev_old = pos[bs[k0], 2]
        zprev_new = zprev_old
        for j in range(k0, k0 + w):
            pa = bs[j]
            pb = bs[j + 1]
            u = pos[pb, 2] - pos[pa, 2]
            qa = moved[pa] - 1
            qb = moved[pb] - 1
            hx0 = pos[pb, 0] - pos[pa, 0]
            hy0 = pos[pb, 1] - pos[pa, 1]
            hx1 = (new[qb, 0] if qb >= 0 else pos[pb, 0]) - (new[qa, 0] if qa >= 0 else pos[pa, 0])
            hy1 = (new[qb, 1] if qb >= 0 else pos[pb, 1]) - (new[qa, 1] if qa >= 0 else pos[pa, 1])
            u2 = u * u + hx0 * hx0 + hy0 * hy0 - hx1 * hx1 - hy1 * hy1
            if u == 0.0 or u2 <= 0.0:
                return -(m + 1)
            un = math.copysign(math.sqrt(u2), u)
            lj += math.log(abs(u / un))
            zprev_new += un
            zprev_old += u
            if qb < 0:  # bead k0 + w: horizontal position kept
                new[m, 0] = pos[pb, 0]
                new[m, 1] = pos[pb, 1]
                idx[m] = pb
                m += 1
                moved[pb] = m
                qb = m - 1
            new[qb, 2] = zprev_new
        shift = zprev_new - zprev_old
        for k in range(k0 + w + 1, nb):
            p = bs[k]
            new[m, 0] = pos[p, 0]
            new[m, 1] = pos[p, 1]
            new[m, 2] = pos[p, 2] + shift
            idx[m] = p
            m += 1
            moved[p] = m
    logjac[0] = lj
    return m



@numba.njit(cache=True)
def _line_rotation(pos, pa, pb, theta):
    """(ok, R): the rotation by ``theta`` about the line from particle pa to pb (not ok for
    coincident particles)."""
    ax = pos[pb, 0] - pos[pa, 0]
    ay = pos[pb, 1] - pos[pa, 1]
    az = pos[pb, 2] - pos[pa, 2]
    nrm = math.sqrt(ax * ax + ay * ay + az * az)
    if nrm < 1e-9:
        return False, np.eye(3)
    return True, rotation_matrix(ax / nrm, ay / nrm, az / nrm, theta)


@numba.njit(cache=True)
def _centre_follows(pos, new, idx, moved, m, center, att1, att2):
    """Appends the bead centre, translated by the mean displacement of the two (moved)
    attachments, to the moved set; returns the new count."""
    if moved[center] != 0:
        return m
    q1 = moved[att1] - 1
    q2 = moved[att2] - 1
    for d in range(3):
        new[m, d] = pos[center, d] + 0.5 * (new[q1, d] - pos[att1, d] + new[q2, d]
                                            - pos[att2, d])
    idx[m] = center
    moved[center] = m + 1
    return m + 1


@numba.njit(cache=True)
def run_braid_moves(pos, P, c_ptr, c_beads, c_fixed, mobile, wgt, center, cum, crank_max,
                    crank_angle, bead_nm, shear_nm, shear_z_nm, twist_rad, sway_rad, pivot_rad,
                    tilt_rad, stretch_eps, stretch_ratio, breathe_eps, breathe_max, kT, uni,
                    gau, stats, terms, passage_test=True):
    """Metropolis crankshaft, bead, shear and twist moves of a braid on ``pos`` (modified
    in place; module docstring).

    Parameters
    ----------
    pos : float64 (N, 3), nm
    P : chain._Params
    c_ptr, c_beads, c_fixed : int64
        The two strands (CSR, surface -> attachment) and prefix counts of immobile beads.
    mobile : int64
        Particles of bead moves.
    wgt : float64 (N,)
        Weights of shear and twist (0: not moved by them).
    center : int
        The bead centre (axis of the twist).
    cum : float64 (9,)
        Cumulative probabilities of the kinds (:data:`BRAID_KINDS`).
    breathe_eps : float
        Largest |log mu| of a breathe move.
    breathe_max : int
        Most pairs (window width) of a breathe move.
    kT : float
    uni : float64 (n, 6), gau : float64 (n, 3)
    stats : int64 (9, 3)
        Added to: attempted, refused (topology or degenerate), accepted per kind.
    terms : float64 (NTERMS,)
        Added to: the accepted energy change per term (pN nm).
    passage_test : bool
        Try :func:`no_passage` before the Gauss sums (False: the Gauss sums alone, as
        before 2026-12-03; for benchmarks).

    Returns
    -------
    (float, float)
        Sum of |dE| over accepted moves (pN nm) and the final catenation (turns).
    """
    n = pos.shape[0]
    b1 = c_beads[c_ptr[0]:c_ptr[1]]
    b2 = c_beads[c_ptr[1]:c_ptr[2]]
    n1 = b1.shape[0]
    n2 = b2.shape[0]
    ray = 1e4 * _extent(pos, b1, b2)
    # vertices of the ray-extended strands now (V) and after a proposal (W)
    V1 = np.empty((n1 + 2, 3))
    V2 = np.empty((n2 + 2, 3))
    W1 = np.empty((n1 + 2, 3))
    W2 = np.empty((n2 + 2, 3))
    S = np.empty((4, max(n1, n2) + 1, 4))
    moved0 = np.zeros(1, np.int64)
    _fill(pos, pos[:0], moved0, False, b1, ray, V1)
    _fill(pos, pos[:0], moved0, False, b2, ray, V2)
    cat = _gauss(V1, 0, n1, V2, 0, n2)
    cat_ok = True  # False: a move was allowed by no_passage and ``cat`` is behind
    H, ncon, _, dcon, moved, idx, new, dterm = loop_setup(pos, P, terms.shape[0])
    logjac = np.zeros(1)
    logj = 0.0
    rinv = np.eye(3)
    cen = np.zeros(3)
    nmob = mobile.shape[0]
    absum = 0.0
    for t in range(uni.shape[0]):
        r = uni[t, 0]
        kind = cum.shape[0] - 1
        for q in range(cum.shape[0] - 1):
            if r < cum[q]:
                kind = q
                break
        stats[kind, 0] += 1
        m = 0
        ch = 0 if uni[t, 1] < 0.5 else 1
        s = c_ptr[ch]
        nb = c_ptr[ch + 1] - s
        lo = 0
        hi = 0
        rigid = kind == 0
        # ball that the moved segments sweep (crankshaft, bead): centre, radius^2
        bx = 0.0
        by = 0.0
        bz = 0.0
        br2 = 0.0
        if kind == 0:
            ok, i, j, pa, pb, R, nrm = crank_proposal(pos, c_beads, c_fixed, s, nb, crank_max,
                                                      crank_angle, uni[t, 2], uni[t, 3],
                                                      uni[t, 4])
            if not ok:
                stats[kind, 1] += 1
                continue
            bx = 0.5 * (pos[pa, 0] + pos[pb, 0])
            by = 0.5 * (pos[pa, 1] + pos[pb, 1])
            bz = 0.5 * (pos[pa, 2] + pos[pb, 2])
            br2 = 0.25 * nrm * nrm
            for k in range(i, j + 1):
                p = c_beads[s + k]
                rotate_into(pos, R, pos[pa, 0], pos[pa, 1], pos[pa, 2], p, new, m)
                dx = pos[p, 0] - bx
                dy = pos[p, 1] - by
                dz = pos[p, 2] - bz
                br2 = max(br2, dx * dx + dy * dy + dz * dz)
                idx[m] = p
                m += 1
                moved[p] = m
            lo = i  # changed segments of the extended strand: i .. j + 1
            hi = j + 1
        elif kind == 1:
            p = ball_proposal(pos, mobile, nmob, bead_nm, gau[t, 0], gau[t, 1], gau[t, 2],
                              uni[t, 2], uni[t, 3], new)
            if p < 0:
                stats[kind, 1] += 1
                continue
            idx[0] = p
            m = 1
            moved[p] = 1
            # which strand, and where (the centre is in none: no topology to check)
            ch = -1
            for c in range(2):
                for k in range(c_ptr[c + 1] - c_ptr[c]):
                    if c_beads[c_ptr[c] + k] == p:
                        ch = c
                        lo = k
                        hi = k + 1
            if ch >= 0:
                # the two segments at p sweep inside the ball about p through its
                # neighbours, widened by the displacement
                s = c_ptr[ch]
                nb = c_ptr[ch + 1] - s
                rr = 0.0
                for k in (lo - 1, lo + 1):
                    if 0 <= k < nb:
                        q = c_beads[s + k]
                        dx = pos[q, 0] - pos[p, 0]
                        dy = pos[q, 1] - pos[p, 1]
                        dz = pos[q, 2] - pos[p, 2]
                        rr = max(rr, math.sqrt(dx * dx + dy * dy + dz * dz))
                if lo == nb - 1:
                    rr = np.inf  # the attachment moves its ray
                bx = pos[p, 0]
                by = pos[p, 1]
                bz = pos[p, 2]
                br2 = (rr + bead_nm) ** 2
        else:
            if kind == 2:
                rho = shear_nm * math.sqrt(uni[t, 2])
                ang = 2.0 * math.pi * uni[t, 3]
                dx = rho * math.cos(ang)
                dy = rho * math.sin(ang)
                dz = shear_z_nm * (2.0 * uni[t, 4] - 1.0)
                for p in range(n):
                    w = wgt[p]
                    if w > 0.0:
                        new[m, 0] = pos[p, 0] + w * dx
                        new[m, 1] = pos[p, 1] + w * dy
                        new[m, 2] = pos[p, 2] + w * dz
                        idx[m] = p
                        m += 1
                        moved[p] = m
            elif kind == 4:
                th = sway_rad * (2.0 * uni[t, 2] - 1.0)
                ang = 2.0 * math.pi * uni[t, 3]
                R = rotation_matrix(math.cos(ang), math.sin(ang), 0.0, th)
                for c in range(2):
                    a = c_beads[c_ptr[c]]
                    for k in range(1, c_ptr[c + 1] - c_ptr[c]):
                        p = c_beads[c_ptr[c] + k]
                        g = c_ptr[c] + k
                        if c_fixed[g + 1] - c_fixed[g] > 0:
                            continue
                        rotate_into(pos, R, pos[a, 0], pos[a, 1], pos[a, 2], p, new, m)
                        idx[m] = p
                        m += 1
                        moved[p] = m
                m = _centre_follows(pos, new, idx, moved, m, center, b1[n1 - 1], b2[n2 - 1])
            elif kind == 5:
                k = 1 + int(uni[t, 3] * (min(n1, n2) - 1))
                pa = b1[k - 1]
                ok, R = _line_rotation(pos, pa, b2[k - 1], pivot_rad * (2.0 * uni[t, 2] - 1.0))
                if not ok:
                    stats[kind, 1] += 1
                    continue
                for c in range(2):
                    for kk in range(k, c_ptr[c + 1] - c_ptr[c]):
                        g = c_ptr[c] + kk
                        if c_fixed[g + 1] - c_fixed[g] > 0:
                            continue
                        p = c_beads[g]
                        rotate_into(pos, R, pos[pa, 0], pos[pa, 1], pos[pa, 2], p, new, m)
                        idx[m] = p
                        m += 1
                        moved[p] = m
                m = _centre_follows(pos, new, idx, moved, m, center, b1[n1 - 1], b2[n2 - 1])
            elif kind == 6:
                pa = b1[n1 - 1]
                ok, R = _line_rotation(pos, pa, b2[n2 - 1], tilt_rad * (2.0 * uni[t, 2] - 1.0))
                if not ok:
                    stats[kind, 1] += 1
                    continue
                rotate_into(pos, R, pos[pa, 0], pos[pa, 1], pos[pa, 2], center, new, 0)
                idx[0] = center
                m = 1
                moved[center] = 1
            elif kind == 7:
                eps = stretch_eps * (2.0 * uni[t, 2] - 1.0)
                lam = math.exp(eps)
                mu = math.exp(-stretch_ratio * eps)
                if abs(pos[b1[n1 - 1], 2] - pos[b1[0], 2]) < 1e-9 or \
                        abs(pos[b2[n2 - 1], 2] - pos[b2[0], 2]) < 1e-9:
                    stats[kind, 1] += 1  # an attachment at its anchor's height
                    continue
                logj = 0.0
                for c in range(2):
                    a = c_beads[c_ptr[c]]
                    nbc = c_ptr[c + 1] - c_ptr[c]
                    tt = c_beads[c_ptr[c] + nbc - 1]
                    tx = pos[tt, 0] - pos[a, 0]
                    ty = pos[tt, 1] - pos[a, 1]
                    tz = pos[tt, 2] - pos[a, 2]
                    nm = 0
                    for k in range(1, nbc):
                        g = c_ptr[c] + k
                        if c_fixed[g + 1] - c_fixed[g] > 0:
                            continue
                        p = c_beads[g]
                        dz = pos[p, 2] - pos[a, 2]
                        f = dz / tz
                        new[m, 0] = pos[a, 0] + mu * (pos[p, 0] - pos[a, 0] - tx * f) + tx * f
                        new[m, 1] = pos[a, 1] + mu * (pos[p, 1] - pos[a, 1] - ty * f) + ty * f
                        new[m, 2] = pos[a, 2] + lam * dz
                        idx[m] = p
                        m += 1
                        moved[p] = m
                        nm += 1
                    # z of N beads scaled; the attachment's xy kept, N - 1 deviations scaled
                    logj += nm * eps + 2.0 * (nm - 1) * (-stretch_ratio * eps)
                m = _centre_follows(pos, new, idx, moved, m, center, b1[n1 - 1], b2[n2 - 1])
            elif kind == 8:
                m = _breathe_proposal(pos, b1, b2, c_ptr, c_fixed, breathe_max,
                                      breathe_eps * (2.0 * uni[t, 2] - 1.0), uni[t, 3],
                                      uni[t, 4], new, idx, moved, logjac)
                if m < 0:
                    for a in range(-m - 1):
                        moved[idx[a]] = 0
                    stats[kind, 1] += 1
                    continue
                logj = logjac[0]
                m = _centre_follows(pos, new, idx, moved, m, center, b1[n1 - 1], b2[n2 - 1])
            else:
                th = twist_rad * (2.0 * uni[t, 2] - 1.0)
                cx = pos[center, 0]
                cy = pos[center, 1]
                for p in range(n):
                    w = wgt[p]
                    if w > 0.0:
                        c = math.cos(w * th)
                        sn = math.sin(w * th)
                        x = pos[p, 0] - cx
                        y = pos[p, 1] - cy
                        new[m, 0] = cx + c * x - sn * y
                        new[m, 1] = cy + sn * x + c * y
                        new[m, 2] = pos[p, 2]
                        idx[m] = p
                        m += 1
                        moved[p] = m
        thr = -kT * math.log(uni[t, 5]) if uni[t, 5] > 0.0 else np.inf
        hastings = kind == 7 or kind == 8
        if hastings:
            thr += kT * logj  # accept when dE < kT (log J - log u)
        dE = delta_kernel(pos, idx[:m], new[:m], moved, rigid, P, H, dterm, thr, ncon, dcon, False,
                          rinv, cen, idx[:m])
        ok = math.isfinite(dE) and ((dE <= 0.0 and not hastings) or dE < thr)
        strands = kind != 6 and not (kind == 1 and ch < 0)
        if ok and strands:
            # topology: no strand may pass the other (the catenation may not jump)
            _fill(pos, new, moved, True, b1, ray, W1)
            _fill(pos, new, moved, True, b2, ray, W2)
            allowed = True
            if kind >= 2:
                if not (passage_test and no_passage(V1, W1, V2, W2, 0, n1, 0, n2, S)):
                    if not cat_ok:
                        cat = _gauss(V1, 0, n1, V2, 0, n2)
                        cat_ok = True
                    newcat = _gauss(W1, 0, n1, W2, 0, n2)
                    allowed = abs(newcat - cat) <= 0.5
                    if allowed:
                        cat = newcat
                else:
                    cat_ok = False
            else:
                other = V2 if ch == 0 else V1
                if _near(other, bx, by, bz, br2):
                    if ch == 0:
                        safe = passage_test and no_passage(V1, W1, V2, W2, lo, hi, 0, n2, S)
                    else:
                        safe = passage_test and no_passage(V1, W1, V2, W2, 0, n1, lo, hi, S)
                    if safe:
                        cat_ok = False
                    else:
                        if ch == 0:
                            d = _gauss(W1, lo, hi, W2, 0, n2) - _gauss(V1, lo, hi, V2, 0, n2)
                        else:
                            d = _gauss(W1, 0, n1, W2, lo, hi) - _gauss(V1, 0, n1, V2, lo, hi)
                        allowed = abs(d) <= 0.5
                        if allowed:
                            cat += d
                else:
                    cat_ok = False
            if not allowed:
                ok = False
                stats[kind, 1] += 1
            else:
                V1[:, :] = W1
                V2[:, :] = W2
        if ok:
            ncon += dcon[0]
            stats[kind, 2] += 1
            absum += abs(dE)
            apply_accepted(pos, new, idx, m, P, H, terms, dterm)
        for a in range(m):
            moved[idx[a]] = 0
    if not cat_ok:
        cat = _gauss(V1, 0, n1, V2, 0, n2)
    return absum, cat
