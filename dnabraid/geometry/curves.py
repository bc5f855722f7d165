"""Pure-numpy geometry of bead chains: linking, writhe, catenation, braid angle, bending.

All functions take plain arrays of positions in nm (``float64`` after conversion) and
return plain floats or arrays; nothing here knows about OpenMM or MDAnalysis.

Gauss linking integral of two polygons
--------------------------------------
For two curves :math:`x_1(s), x_2(t)` the Gauss integral is

.. math::

    G = \\frac{1}{4\\pi} \\int\\int
        \\frac{(x_1 - x_2) \\cdot (\\dot x_1 \\times \\dot x_2)}{|x_1 - x_2|^3}\\, ds\\, dt .

For one straight segment of each curve the double integral equals, exactly, the signed
solid angle :math:`\\Omega` swept by the unit vector :math:`(x_2 - x_1)/|x_2 - x_1|` over the
parameter square divided by :math:`4\\pi` (Klenin & Langowski, Biopolymers 54, 307 (2000),
Eq. 14-16; Banchoff, Indiana Univ. Math. J. 25, 1171 (1976)). That image is a spherical
quadrilateral bounded by great-circle arcs with corners ``c-a, c-b, d-b, d-a`` (segment
``a->b`` on curve 1, ``c->d`` on curve 2); we compute its signed area as the sum of two
spherical triangles with the Van Oosterom & Strackee formula (IEEE Trans. Biomed. Eng. 30,
125 (1983))

.. math::

    \\tan\\frac{\\Omega_\\triangle}{2} = \\frac{v_1 \\cdot (v_2 \\times v_3)}
        {|v_1||v_2||v_3| + (v_1\\cdot v_2)|v_3| + (v_1\\cdot v_3)|v_2| + (v_2\\cdot v_3)|v_1|},

evaluated with ``arctan2``. This is algebraically the same as Klenin & Langowski's
four-arcsine sum but stays accurate for the very elongated quadrilaterals that appear
when strands are extended by long rays (:func:`catenation_number`). Sums over segment
pairs are vectorised and processed in chunks of at most :data:`_PAIR_CHUNK` pairs.

Sign conventions
----------------
* ``gauss_linking_number`` follows the standard Gauss convention: a right-handed
  (positive) crossing counts +1/2, so the two strands of a right-handed double helix
  closed into rings have Lk > 0.
* ``catenation_number`` is positive for a right-handed braid (the top chord rotated
  counter-clockwise about +z relative to the bottom chord when z increases).
* ``crossing_angles`` uses van der Heijden's braid frame: eta is the signed angle from
  the tangent t1 of strand 1 to the tangent t2 of strand 2, measured about the unit chord
  d1 that points from strand 1 to strand 2 (right-hand rule). For an ideal right-handed
  two-strand ply with helix angle theta (to the axis), eta = -2 theta; for a
  left-handed ply eta = +2 theta (compare theta = -eta / 2 in van der Heijden, Starostin
  & Korte, J. Mech. Phys. Solids 64, 83 (2014)).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "bending_cosines",
    "bond_lengths",
    "catenation_number",
    "chord_angle",
    "crossing_angles",
    "extension",
    "gauss_linking_number",
    "persistence_length_from_cosines",
    "segment_distances",
    "unwrap_angle",
    "writhe",
]

#: Largest number of segment pairs evaluated at once (bounds memory to ~ 100 MB).
_PAIR_CHUNK = 400_000


# ----------------------------------------------------------------------------- helpers
def as_points(x, name: str, *, min_points: int = 2) -> np.ndarray:
    """Validate an ``(n, 3)`` array of positions and return it as float64."""
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3); got shape {arr.shape}")
    if arr.shape[0] < min_points:
        raise ValueError(f"{name} needs at least {min_points} points; got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains non-finite coordinates")
    return arr


def _closed_segments(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end points of the segments of a closed polygon (last -> first included)."""
    return c, np.roll(c, -1, axis=0)


def triangle_solid_angle(v1, v2, v3):
    """Signed solid angle of the spherical triangle with corner vectors ``v1, v2, v3``.

    Van Oosterom & Strackee (1983). Shapes ``(..., 3)`` -> ``(...)``. Degenerate
    triangles (a zero vector) give 0.
    """
    n1 = np.linalg.norm(v1, axis=-1)
    n2 = np.linalg.norm(v2, axis=-1)
    n3 = np.linalg.norm(v3, axis=-1)
    num = np.einsum("...i,...i->...", v1, np.cross(v2, v3))
    den = (
        n1 * n2 * n3
        + np.einsum("...i,...i->...", v1, v2) * n3
        + np.einsum("...i,...i->...", v1, v3) * n2
        + np.einsum("...i,...i->...", v2, v3) * n1
    )
    omega = 2.0 * np.arctan2(num, den)
    degenerate = (n1 == 0.0) | (n2 == 0.0) | (n3 == 0.0)
    return np.where(degenerate, 0.0, omega)


def pair_solid_angles(a, b, c, d):
    """Signed solid angle Omega_ij for segments ``a->b`` (curve 1) and ``c->d`` (curve 2).

    Broadcasting shapes ``(..., 3)``; returns ``(...)``. The Gauss integral of the pair is
    ``Omega / (4 pi)``.
    """
    v1 = c - a  # (s, t) = (0, 0)
    v2 = c - b  # (1, 0)
    v3 = d - b  # (1, 1)
    v4 = d - a  # (0, 1)
    return triangle_solid_angle(v1, v2, v3) + triangle_solid_angle(v1, v3, v4)


def gauss_sum(a, b, c, d, mask_fn=None) -> float:
    """Sum of Omega_ij / (4 pi) over all pairs (segment i of curve 1, segment j of curve 2).

    Parameters
    ----------
    a, b : ndarray, shape (n, 3)
        Start and end points of the segments of curve 1.
    c, d : ndarray, shape (m, 3)
        Start and end points of the segments of curve 2.
    mask_fn : callable, optional
        ``mask_fn(i, j)`` with index arrays of shape ``(k, 1)`` and ``(1, m)`` returning a
        boolean array of pairs to include (used for the writhe).
    """
    n, m = a.shape[0], c.shape[0]
    rows = max(1, _PAIR_CHUNK // max(m, 1))
    total = 0.0
    j = np.arange(m)[None, :]
    for start in range(0, n, rows):
        stop = min(n, start + rows)
        omega = pair_solid_angles(
            a[start:stop, None, :], b[start:stop, None, :], c[None, :, :], d[None, :, :]
        )
        if mask_fn is not None:
            i = np.arange(start, stop)[:, None]
            omega = np.where(mask_fn(i, j), omega, 0.0)
        total += float(np.sum(omega))
    return total / (4.0 * math.pi)


# ----------------------------------------------------------------------------- linking
def gauss_linking_number(c1, c2) -> float:
    """Gauss linking integral of two closed polygons.

    Parameters
    ----------
    c1 : array_like, shape (n, 3)
        Vertices of the first closed polygon in nm (the last vertex joins the first).
    c2 : array_like, shape (m, 3)
        Vertices of the second closed polygon in nm.

    Returns
    -------
    float
        The linking number; an integer (to round-off) for disjoint closed curves.
        Positive for right-handed links (e.g. the two strands of a right-handed double
        helix closed into rings).
    """
    p = as_points(c1, "c1", min_points=3)
    q = as_points(c2, "c2", min_points=3)
    a, b = _closed_segments(p)
    c, d = _closed_segments(q)
    return gauss_sum(a, b, c, d)


def writhe(c) -> float:
    """Writhe of a closed polygon.

    ``Wr = (1/4pi) sum_{i != j, non-adjacent} Omega_ij = (1/2pi) sum_{i<j} Omega_ij``,
    with the same exact segment-pair solid angle as :func:`gauss_linking_number`
    (Klenin & Langowski 2000, Eq. 13). Adjacent segments (sharing a vertex, including the
    closing segment) contribute nothing.

    Parameters
    ----------
    c : array_like, shape (n, 3)
        Vertices of the closed polygon in nm, ``n >= 4``.

    Returns
    -------
    float
        Writhe (dimensionless). Zero for planar curves; changes sign under reflection.
    """
    p = as_points(c, "c", min_points=4)
    n = p.shape[0]
    a, b = _closed_segments(p)

    def upper_nonadjacent(i, j):
        # pairs i < j that do not share a vertex; (0, n-1) share vertex 0
        return (j > i + 1) & ~((i == 0) & (j == n - 1))

    return 2.0 * gauss_sum(a, b, a, b, mask_fn=upper_nonadjacent)


def catenation_number(strand1, strand2, ray_length: float | None = None) -> float:
    """Catenation (braid linking) number of two open strands tethered surface-to-bead.

    Each strand is extended at its first vertex by a vertical ray straight down (-z) and
    at its last vertex by a vertical ray straight up (+z), of length ``ray_length``; the
    result is the Gauss integral of the two extended open polylines, summed exactly over
    all segment pairs. Vertical rays are mutually parallel, so ray-ray pairs contribute
    nothing and the result is insensitive to ``ray_length`` (error ~ extent / ray_length).

    The value is continuous in the coordinates: with ``phi`` the counter-clockwise angle
    (about +z) from the bottom chord ``strand2[0] - strand1[0]`` to the top chord
    ``strand2[-1] - strand1[-1]`` (both projected on xy), it equals ``phi / (2 pi)`` plus
    an integer that changes only when the strands pass through each other. A right-handed
    braid (strand 2 winding counter-clockwise about strand 1 as z increases) gives a
    positive number; an ideal two-strand helix with ``n`` turns gives ``n``.

    Parameters
    ----------
    strand1, strand2 : array_like, shape (n, 3) and (m, 3)
        Bead positions in nm, from the surface attachment (index 0, z ~ 0) to the magnetic
        bead attachment (index -1).
    ray_length : float, optional
        Length of the vertical extensions in nm. Default: ``1e4`` times the larger extent
        (largest bounding-box side) of the two strands.

    Returns
    -------
    float
        Catenation number (turns, dimensionless).
    """
    p = as_points(strand1, "strand1")
    q = as_points(strand2, "strand2")
    if ray_length is None:
        extent = max(np.ptp(p, axis=0).max(), np.ptp(q, axis=0).max(), 1e-12)
        ray_length = 1e4 * float(extent)
    ray_length = float(ray_length)
    if not ray_length > 0.0:
        raise ValueError(f"ray_length must be positive; got {ray_length}")
    up = np.array([0.0, 0.0, ray_length])
    pe = np.vstack([p[0] - up, p, p[-1] + up])
    qe = np.vstack([q[0] - up, q, q[-1] + up])
    return gauss_sum(pe[:-1], pe[1:], qe[:-1], qe[1:])


# ----------------------------------------------------------------------------- angles
def unwrap_angle(phi_sequence) -> np.ndarray:
    """Continuous unwrapping of a sequence of angles (rad); thin wrapper of ``np.unwrap``.

    Parameters
    ----------
    phi_sequence : array_like, shape (n,)
        Angles in rad, e.g. :func:`chord_angle` per frame.

    Returns
    -------
    ndarray, shape (n,)
        Angles in rad with jumps larger than pi removed by adding multiples of 2 pi.
    """
    phi = np.asarray(phi_sequence, dtype=np.float64)
    if phi.ndim != 1:
        raise ValueError(f"phi_sequence must be one-dimensional; got shape {phi.shape}")
    return np.unwrap(phi)


def chord_angle(p1, p2):
    """Azimuth of the chord from ``p1`` to ``p2`` projected on the xy plane.

    Parameters
    ----------
    p1, p2 : array_like, shape (..., 3)
        Points in nm (broadcast against each other).

    Returns
    -------
    float or ndarray, shape (...)
        ``atan2(dy, dx)`` in rad, in (-pi, pi], counter-clockwise about +z.
    """
    d = np.asarray(p2, dtype=np.float64) - np.asarray(p1, dtype=np.float64)
    if d.shape[-1] != 3:
        raise ValueError(f"points must have a last axis of length 3; got shape {d.shape}")
    out = np.arctan2(d[..., 1], d[..., 0])
    return float(out) if out.ndim == 0 else out


def segment_distances(a, b, c, d):
    """Closest points between segments ``a->b`` and ``c->d`` (broadcasting).

    Ericson, *Real-Time Collision Detection* (2005), Sec. 5.1.9.

    Parameters
    ----------
    a, b, c, d : ndarray, shape (..., 3)
        Segment end points in nm.

    Returns
    -------
    dist : ndarray, shape (...)
        Closest distance in nm.
    s, t : ndarray, shape (...)
        Parameters in [0, 1] of the closest points ``a + s (b - a)`` and ``c + t (d - c)``.
    """
    u = b - a
    v = d - c
    r = a - c
    aa = np.einsum("...i,...i->...", u, u)
    ee = np.einsum("...i,...i->...", v, v)
    ff = np.einsum("...i,...i->...", v, r)
    cc = np.einsum("...i,...i->...", u, r)
    bb = np.einsum("...i,...i->...", u, v)
    denom = aa * ee - bb * bb
    tiny = 1e-12 * np.maximum(aa * ee, 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > tiny, np.clip((bb * ff - cc * ee) / denom, 0.0, 1.0), 0.0)
        t = (bb * s + ff) / ee
        s_lo = np.clip(-cc / aa, 0.0, 1.0)
        s_hi = np.clip((bb - cc) / aa, 0.0, 1.0)
    s = np.where(t < 0.0, s_lo, np.where(t > 1.0, s_hi, s))
    t = np.clip(t, 0.0, 1.0)
    p = a + s[..., None] * u
    q = c + t[..., None] * v
    dist = np.linalg.norm(q - p, axis=-1)
    return dist, s, t


def crossing_angles(strand1, strand2, cutoff: float):
    """Signed braid (crossing) angles between two strands at their closest approaches.

    For every segment i of strand 1 the closest segment j of strand 2 is found (closest
    distance between the two segments). If that distance is below ``cutoff``, the braid
    angle eta is the signed angle from the unit tangent t1 of segment i to the unit
    tangent t2 of segment j, measured about the unit chord d1 that joins the closest
    point on segment i to the closest point on segment j (pointing from strand 1 to
    strand 2), right-hand rule, with both tangents projected on the plane normal to d1
    (van der Heijden's first braid frame {t1, d1, u1}):

    ``eta = atan2(d1 . (t1 x t2), t1 . t2 - (t1 . d1)(t2 . d1))``.

    DNA is apolar, so eta is folded modulo pi into (-pi/2, pi/2]. An ideal right-handed
    two-strand ply with helix angle theta to its axis gives eta = -2 theta; its mirror
    image gives +2 theta (valid while 2 theta < pi/2).

    Parameters
    ----------
    strand1 : array_like, shape (n, 3)
        Bead positions of strand 1 in nm.
    strand2 : array_like, shape (m, 3)
        Bead positions of strand 2 in nm.
    cutoff : float
        Largest closest-approach distance in nm for a segment pair to count.

    Returns
    -------
    eta : ndarray, shape (k,)
        Braid angles in rad, one per strand-1 segment that has a partner within cutoff
        (in strand-1 segment order).
    distance : ndarray, shape (k,)
        The corresponding closest distances in nm.
    """
    p = as_points(strand1, "strand1")
    q = as_points(strand2, "strand2")
    cutoff = float(cutoff)
    if not cutoff > 0.0:
        raise ValueError(f"cutoff must be positive (nm); got {cutoff}")
    a, b = p[:-1], p[1:]
    c, d = q[:-1], q[1:]
    n, m = a.shape[0], c.shape[0]
    best_j = np.empty(n, dtype=np.intp)
    best_dist = np.empty(n)
    best_s = np.empty(n)
    best_t = np.empty(n)
    rows = max(1, _PAIR_CHUNK // max(m, 1))
    for start in range(0, n, rows):
        stop = min(n, start + rows)
        dist, s, t = segment_distances(
            a[start:stop, None, :], b[start:stop, None, :], c[None, :, :], d[None, :, :]
        )
        j = np.argmin(dist, axis=1)
        k = np.arange(stop - start)
        best_j[start:stop] = j
        best_dist[start:stop] = dist[k, j]
        best_s[start:stop] = s[k, j]
        best_t[start:stop] = t[k, j]
    keep = best_dist < cutoff
    if not np.any(keep):
        return np.empty(0), np.empty(0)
    i = np.nonzero(keep)[0]
    j = best_j[keep]
    u = b[i] - a[i]
    v = d[j] - c[j]
    x1 = a[i] + best_s[keep, None] * u
    x2 = c[j] + best_t[keep, None] * v
    t1 = u / np.linalg.norm(u, axis=1, keepdims=True)
    t2 = v / np.linalg.norm(v, axis=1, keepdims=True)
    chord = x2 - x1
    dist = np.linalg.norm(chord, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        d1 = chord / dist[:, None]
    # Touching/intersecting segments have no chord direction: drop them.
    ok = dist > 0.0
    t1, t2, d1, dist = t1[ok], t2[ok], d1[ok], dist[ok]
    sin_part = np.einsum("ij,ij->i", d1, np.cross(t1, t2))
    cos_part = np.einsum("ij,ij->i", t1, t2) - np.einsum("ij,ij->i", t1, d1) * np.einsum(
        "ij,ij->i", t2, d1
    )
    eta = np.arctan2(sin_part, cos_part)
    eta = 0.5 * np.pi - np.mod(0.5 * np.pi - eta, np.pi)  # fold into (-pi/2, pi/2]
    return eta, dist


# ----------------------------------------------------------------------------- chains
def extension(positions_z) -> float:
    """End-to-end extension along z.

    Parameters
    ----------
    positions_z : array_like, shape (n,)
        z coordinates in nm of a strand, from surface (index 0) to bead (index -1).

    Returns
    -------
    float
        ``z[-1] - z[0]`` in nm.
    """
    z = np.asarray(positions_z, dtype=np.float64).reshape(-1)
    if z.size == 0:
        raise ValueError("positions_z is empty")
    return float(z[-1] - z[0])


def bond_lengths(strand) -> np.ndarray:
    """Lengths of consecutive bonds.

    Parameters
    ----------
    strand : array_like, shape (n, 3)
        Bead positions in nm.

    Returns
    -------
    ndarray, shape (n-1,)
        Bond lengths in nm.
    """
    p = as_points(strand, "strand")
    return np.linalg.norm(np.diff(p, axis=0), axis=1)


def bending_cosines(strand) -> np.ndarray:
    """Cosines of the angles between consecutive bond vectors.

    Parameters
    ----------
    strand : array_like, shape (n, 3)
        Bead positions in nm, ``n >= 3``.

    Returns
    -------
    ndarray, shape (n-2,)
        ``cos(angle)`` between bond i and bond i+1 (1 for a straight chain).
    """
    p = as_points(strand, "strand", min_points=3)
    bonds = np.diff(p, axis=0)
    lengths = np.linalg.norm(bonds, axis=1)
    if np.any(lengths == 0.0):
        raise ValueError("strand has coincident consecutive beads (zero bond length)")
    t = bonds / lengths[:, None]
    return np.clip(np.einsum("ij,ij->i", t[:-1], t[1:]), -1.0, 1.0)


def persistence_length_from_cosines(mean_cos, b):
    """Persistence length of a worm-like chain from the mean bond-bond cosine.

    ``<cos> = exp(-b / Lp)``, hence ``Lp = -b / ln <cos>``.

    Parameters
    ----------
    mean_cos : float or array_like
        Mean cosine between consecutive bonds, in (0, 1].
    b : float or array_like
        Bond length in nm.

    Returns
    -------
    float or ndarray
        Persistence length in nm (``inf`` for ``mean_cos == 1``).
    """
    mc = np.asarray(mean_cos, dtype=np.float64)
    if np.any((mc <= 0.0) | (mc > 1.0)):
        raise ValueError(f"mean_cos must lie in (0, 1]; got {mean_cos}")
    bb = np.asarray(b, dtype=np.float64)
    with np.errstate(divide="ignore"):
        lp = np.where(mc == 1.0, np.inf, -bb / np.log(np.where(mc == 1.0, 0.5, mc)))
    return float(lp) if lp.ndim == 0 else lp
