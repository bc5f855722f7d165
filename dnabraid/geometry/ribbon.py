"""A framed bead chain as a ribbon: twist, writhe, linking, and plectonemes (pure numpy).

Frames. Bond i (beads r_i -> r_{i+1}) has unit tangent t_i and material vector u_i, the
part of ``s_i - r_i`` perpendicular to t_i (s_i its side particle,
:mod:`dnabraid.forces.twist_frames`).

Twist. The twist angle of a joint is the rotation about t_{i+1} that takes the parallel
transport of u_i (minimal rotation t_i -> t_{i+1}, Rodrigues' formula) onto u_{i+1};
Tw = sum of the angles / 2 pi. The tether's twist includes the two clamps: the surface
frame (+z, +x) against bond 0, and bond N-1 against the bead frame (+z, horizontal part
of the bead's orientation vector).

Writhe of an open tether. The chain is closed in a documented way: a vertical ray goes
down from its first bead and another up from its last bead, each of length ``1e4`` x the
chain's extent, and the rays are joined far away (their far closure lies, to O(extent /
ray length), in a plane with them and adds nothing). Wr is the exact Gauss self-integral
of the extended polygon (segment-pair solid angles, :func:`geometry.writhe` without the
closing segment). With this closure and frames parallel-transported along the rays,
Lk = Tw + Wr equals the bead's angle / 2 pi (unwrapped) as long as the chain does not
pass through itself or through a ray (the surface and the bead keep it from the rays).

Rings. A closed chain of n beads has n bonds (bond n-1 joins r_{n-1} -> r_0) and n joints
(the seam joint takes bond n-1 to bond 0); :func:`ring_twist` sums all n joint angles and
:func:`~dnabraid.geometry.curves.writhe` is the exact Gauss self-integral of the closed
polygon, so Tw + Wr is the ribbon's integer linking number (White 1969; Fuller 1978;
the discrete form: the holonomy of discrete parallel transport around a closed polygon is
2 pi Wr mod 2 pi). :func:`ring_side_positions` builds frames that close with a chosen
linking number.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..units import TWO_PI
from .curves import as_points, gauss_sum, writhe

__all__ = [
    "Plectoneme",
    "bond_frames",
    "find_plectonemes",
    "linking_number",
    "parallel_transport",
    "plectoneme_summary",
    "ring_bond_frames",
    "ring_side_positions",
    "ring_twist",
    "tether_twist",
    "twist_angles",
    "writhe_open",
]

Z = np.array([0.0, 0.0, 1.0])
X = np.array([1.0, 0.0, 0.0])


def parallel_transport(v, t1, t2):
    """Rotate ``v`` by the minimal rotation taking unit vector ``t1`` onto ``t2``.

    Rodrigues: ``R v = c v + k x v + (k . v) k / (1 + c)`` with ``k = t1 x t2``,
    ``c = t1 . t2`` (undefined for antiparallel tangents). Shapes ``(..., 3)``.
    """
    v = np.asarray(v, float)
    t1 = np.asarray(t1, float)
    t2 = np.asarray(t2, float)
    k = np.cross(t1, t2)
    c = np.sum(t1 * t2, axis=-1)[..., None]
    return c * v + np.cross(k, v) + np.sum(k * v, axis=-1)[..., None] * k / (1.0 + c)


def twist_angles(t1, u1, t2, u2) -> np.ndarray:
    """Twist angle (rad) from frame (t1, u1) to (t2, u2), shapes ``(..., 3)`` -> ``(...)``.

    Tangents must be unit vectors; u's are projected on the normal planes (any length).
    The angle is measured about t2, right-handed, in (-pi, pi].
    """
    t1 = np.asarray(t1, float)
    t2 = np.asarray(t2, float)
    u1 = np.asarray(u1, float)
    u2 = np.asarray(u2, float)
    u1 = u1 - np.sum(u1 * t1, axis=-1)[..., None] * t1
    u2 = u2 - np.sum(u2 * t2, axis=-1)[..., None] * t2
    p = parallel_transport(u1, t1, t2)
    return np.arctan2(np.sum(t2 * np.cross(p, u2), axis=-1), np.sum(p * u2, axis=-1))


def bond_frames(chain, sides):
    """Unit tangents and unit material vectors of the bonds of a framed chain.

    Parameters
    ----------
    chain : array_like, shape (n, 3)
        Bead positions (nm).
    sides : array_like, shape (n - 1, 3)
        Side particle of each bond (attached at the bond's first bead).

    Returns
    -------
    t, u : ndarray, shape (n - 1, 3)
    """
    p = as_points(chain, "chain")
    s = np.asarray(sides, float)
    if s.shape != (p.shape[0] - 1, 3):
        raise ValueError(f"sides must have shape ({p.shape[0] - 1}, 3); got {s.shape}")
    t = np.diff(p, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    w = s - p[:-1]
    u = w - np.sum(w * t, axis=1)[:, None] * t
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return t, u


def tether_twist(chain, sides, bead_vector=None, *, base=(Z, X), axis=Z, per_joint=False):
    """Twist Tw (turns) of a framed tether, clamps included.

    Parameters
    ----------
    chain : array_like, shape (n, 3)
    sides : array_like, shape (n - 1, 3)
    bead_vector : array_like, shape (3,), optional
        The bead's orientation vector ``m - r_att``; its part normal to ``axis`` is the
        bead frame's material vector. None: no bead clamp (free end).
    base : (tangent, material), optional
        The surface frame; None: no surface clamp.
    axis : array_like, shape (3,)
        Tangent of the bead frame.
    per_joint : bool
        Return the joint angles (rad, surface clamp first, bead clamp last) instead.
    """
    t, u = bond_frames(chain, sides)
    om = [twist_angles(t[:-1], u[:-1], t[1:], u[1:])]
    if base is not None:
        om.insert(0, np.atleast_1d(twist_angles(np.asarray(base[0], float),
                                                np.asarray(base[1], float), t[0], u[0])))
    if bead_vector is not None:
        om.append(np.atleast_1d(twist_angles(t[-1], u[-1], np.asarray(axis, float),
                                             np.asarray(bead_vector, float))))
    om = np.concatenate(om)
    return om if per_joint else float(np.sum(om) / TWO_PI)


def writhe_open(chain, ray_length: float | None = None) -> float:
    """Writhe of an open tether closed by vertical rays (see module docstring).

    Parameters
    ----------
    chain : array_like, shape (n, 3)
        Bead positions (nm), surface end first.
    ray_length : float, optional
        Default ``1e4`` x the largest bounding-box side of the chain.

    Returns
    -------
    float
        Wr (dimensionless); 0 for a planar chain whose end rays lie in its plane.
    """
    p = as_points(chain, "chain")
    if ray_length is None:
        ray_length = 1e4 * max(float(np.ptp(p, axis=0).max()), 1e-12)
    up = np.array([0.0, 0.0, float(ray_length)])
    q = np.vstack([p[0] - up, p, p[-1] + up])
    a, b = q[:-1], q[1:]
    return 2.0 * gauss_sum(a, b, a, b, mask_fn=lambda i, j: j > i + 1)


def linking_number(chain, sides, bead_vector, **kw) -> float:
    """Lk = Tw + Wr of a framed tether (turns): equals the bead's turns (unwrapped)."""
    return tether_twist(chain, sides, bead_vector, **kw) + writhe_open(chain)


# ----------------------------------------------------------------------------- rings
def ring_bond_frames(ring, sides):
    """Unit tangents and unit material vectors of the n bonds of a framed ring.

    Parameters
    ----------
    ring : array_like, shape (n, 3)
        Bead positions (nm); bond i joins bead i -> bead (i + 1) mod n.
    sides : array_like, shape (n, 3)
        Side particle of each bond (attached at the bond's first bead).

    Returns
    -------
    t, u : ndarray, shape (n, 3)
    """
    p = as_points(ring, "ring", min_points=3)
    s = np.asarray(sides, float)
    if s.shape != p.shape:
        raise ValueError(f"a ring of {p.shape[0]} beads has {p.shape[0]} bonds: sides must "
                         f"have shape {p.shape}; got {s.shape}")
    return bond_frames(np.vstack([p, p[:1]]), s)


def ring_twist(ring, sides, *, per_joint=False):
    """Twist Tw (turns) of a framed ring: the n joint angles, seam included, / 2 pi.

    Parameters
    ----------
    ring : array_like, shape (n, 3)
    sides : array_like, shape (n, 3)
    per_joint : bool
        Return the n joint angles (rad; joint i takes bond i to bond i + 1 mod n).
    """
    t, u = ring_bond_frames(ring, sides)
    om = twist_angles(t, u, np.roll(t, -1, axis=0), np.roll(u, -1, axis=0))
    return om if per_joint else float(np.sum(om) / TWO_PI)


def ring_side_positions(ring_pos, arm_nm: float, delta_lk: int = 0, first=None) -> np.ndarray:
    """Side-particle positions of a ring's frames closed with linking number ``delta_lk``.

    The material vector of bond 0 is ``first`` (projected on its normal plane; default the
    normal of the bond closest to the ring's mean plane); each next one is the parallel
    transport of the previous, turned about its tangent by the same angle
    ``2 pi (delta_lk - Wr) / n``, so the twist is spread evenly, Tw = delta_lk - Wr and
    Lk = Tw + Wr = delta_lk exactly (the seam joint closes with the same angle because a
    ribbon's Lk is an integer).

    Parameters
    ----------
    ring_pos : array_like, shape (n, 3)
        Bead positions (nm) of the closed ring.
    arm_nm : float
        Distance of a side particle from its bead.
    delta_lk : int
        Linking number of the closed ribbon (turns); a ribbon's Lk is an integer.
    first : array_like, shape (3,), optional

    Returns
    -------
    ndarray, shape (n, 3)
    """
    if int(delta_lk) != delta_lk:
        raise ValueError(f"delta_lk must be an integer (a closed ribbon's linking number); "
                         f"got {delta_lk!r}")
    p = as_points(ring_pos, "ring_pos", min_points=4)
    n = p.shape[0]
    t = np.roll(p, -1, axis=0) - p
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    wr = writhe(p)
    step = TWO_PI * (float(delta_lk) - wr) / n
    if abs(step) >= math.pi / 2:
        raise ValueError(f"delta_lk={delta_lk} over {n} bonds turns each joint by "
                         f"{math.degrees(step):.0f} deg (>= 90 deg): use more beads")
    if first is None:
        c = p - p.mean(axis=0)
        normal = np.linalg.svd(c)[2][-1]  # normal of the best-fit plane
        first = np.cross(t[0], normal)
        if np.linalg.norm(first) < 1e-8:
            first = np.cross(t[0], [1.0, 0.0, 0.0] if abs(t[0, 0]) < 0.9 else [0.0, 1.0, 0.0])
    cur = np.asarray(first, float) - np.dot(first, t[0]) * t[0]
    cur /= np.linalg.norm(cur)
    u = np.empty_like(t)
    u[0] = cur
    for i in range(1, n):
        v = parallel_transport(u[i - 1], t[i - 1], t[i])
        v = v - np.dot(v, t[i]) * t[i]
        v /= np.linalg.norm(v)
        # turn by `step` about t_i (right-handed)
        u[i] = math.cos(step) * v + math.sin(step) * np.cross(t[i], v)
    return p + float(arm_nm) * u


# ----------------------------------------------------------------------------- plectonemes
@dataclasses.dataclass(frozen=True)
class Plectoneme:
    """One plectoneme of a chain (contour positions in nm from the first bead).

    Attributes
    ----------
    start_nm, end_nm : float
        Contour positions where the plectoneme leaves and rejoins the tail.
    tip_nm : float
        Contour position of its end loop (the middle of the paired branches).
    length_nm : float
        DNA in the plectoneme, ``end_nm - start_nm``.
    n_contacts : int
        Bead pairs (one per branch) found in contact.
    """

    start_nm: float
    end_nm: float
    tip_nm: float
    length_nm: float
    n_contacts: int


def find_plectonemes(chain, *, contact_nm: float = 12.0, min_separation_nm: float = 25.0,
                     tip_tolerance_nm: float = 15.0, min_length_nm: float = 30.0):
    """Plectonemes of a chain from its self-contacts.

    A self-contact is a bead pair (i, j) at least ``min_separation_nm`` apart along the
    contour and less than ``contact_nm`` apart in space. In a plectoneme the two branches
    are paired around the end loop, so its contacts share their contour midpoint
    (s_i + s_j)/2, the tip; contacts are sorted by midpoint and split where consecutive
    midpoints differ by more than ``tip_tolerance_nm``. Each group spanning at least
    ``min_length_nm`` of contour is a plectoneme from min s_i to max s_j. Its ends are
    found to about ``contact_nm`` on each side (tail beads near the base touch the far
    branch), its tip to a few bead spacings.

    Parameters
    ----------
    chain : array_like, shape (n, 3)
        Bead positions (nm).
    contact_nm : float
        Largest distance of paired branches (about twice the superhelix radius plus the
        diameter; 12 nm suits 150 mM salt).
    min_separation_nm : float
        Smallest contour separation for a contact (excludes the bending of the tail).
    tip_tolerance_nm : float
        Largest gap between contact midpoints within one plectoneme.
    min_length_nm : float

    Returns
    -------
    list of Plectoneme, sorted by tip position.
    """
    p = as_points(chain, "chain")
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=-1)
    i, j = np.nonzero(np.triu((d < contact_nm) & (s[None, :] - s[:, None] >= min_separation_nm)))
    if i.size == 0:
        return []
    mid = 0.5 * (s[i] + s[j])
    order = np.argsort(mid)
    i, j, mid = i[order], j[order], mid[order]
    breaks = np.nonzero(np.diff(mid) > tip_tolerance_nm)[0] + 1
    out = []
    for grp in np.split(np.arange(mid.size), breaks):
        a, b = s[i[grp]].min(), s[j[grp]].max()
        if b - a >= min_length_nm:
            out.append(Plectoneme(float(a), float(b), float(np.median(mid[grp])), float(b - a),
                                  int(grp.size)))
    return out


def plectoneme_summary(chain, **kw) -> dict:
    """Number of plectonemes, DNA in them (nm) and the tip of the longest (nm, NaN if none)."""
    pl = find_plectonemes(chain, **kw)
    if not pl:
        return {"count": 0, "length_nm": 0.0, "tip_nm": math.nan}
    big = max(pl, key=lambda q: q.length_nm)
    return {"count": len(pl), "length_nm": float(sum(q.length_nm for q in pl)),
            "tip_nm": big.tip_nm}
