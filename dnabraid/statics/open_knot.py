"""Open elastic knots in a bead rod at zero temperature, against the continuum theory.

What is built
-------------
An elastic rod of radius ``h`` and bending stiffness ``B = EI`` (pN nm^2), discretised into
beads ``b`` apart (harmonic bonds of stretch modulus ``S``, hinges ``U = (B/b)(1 - cos beta)``,
self-contact ``U = k/2 (2h - r)^2`` for ``r < 2h``, with ``r`` the distance between beads
(:mod:`dnabraid.forces.contact`, ``contact="beads"``) or the closest distance between the
straight segments joining them (:mod:`dnabraid.forces.segment_contact`,
``contact="segments"``: a smooth tube; beads make a corrugated surface whose slope acts as
static friction, ~ b / (4h), and pins the loop), tied
into an open ``(2, 2n+1)`` torus knot (``n = 1`` trefoil, ``n = 2`` cinquefoil; ``n`` is the
unknotting number of Jawed et al. 2015) and pulled by a tension ``T`` at both ends. There is no
tweezer bead, no surface, no electrostatics and no temperature: the scene leaves them out.
The ends are held on the pulling axis (their two last beads are restrained sideways), a
stand-in for the infinitely long straight tails of the theory; the tails are
``tail_factor`` x ``sqrt(B/T)`` long (the decay length of their deflection, Audoly et al. 2007).

The start is the asymptotic shape itself: straight tails along z, a braid of length
``l0`` in which the two strands wind around each other (their half-difference turning by
``(2n+1) pi``), and a planar loop of radius ``R0`` in the y-z plane. It is then relaxed to a
minimum of the energy. Plain L-BFGS (OpenMM's ``LocalEnergyMinimizer``, scipy's) does
*not* get there: the slow mode is the rod sliding through the braid, which in Cartesian
coordinates is a curved valley (measured: 18000 L-BFGS iterations moved the loop by
< 1 % for a 737-bead trefoil). :func:`relax` runs the damped Newton method of
:mod:`dnabraid.statics.newton` on the exact sparse Hessian (bonds and contacts
Gauss-Newton, hinges exact), which converges in tens of iterations; the forces at its end
are checked against OpenMM's (the same System the scene would integrate) and the largest
OpenMM force left is reported.

What is measured (:func:`measure`) and against which theory
------------------------------------------------------------
* loop radius: ``R_dL = Delta L / (2 pi)``, the shortening over 2 pi as in the experiments
  of Audoly et al. 2007 (below Eq. 9), ``R_apex`` = half the loop's largest distance from the
  axis (sensitive to the tails' length: the knot's base sits O(h) off the axis), and
  ``R_curv`` = 1 / curvature at that apex; against ``T = EI / (2 R^2)`` (Audoly et al. 2007, Eq. 1,
  no friction). With frictionless contact ``H = B kappa^2 / 2 + N . t`` is conserved
  along the rod and equals ``T``, so ``R_curv`` differs from Eq. 1 by the loop's internal
  force ``N`` (zero only as eps -> 0);
* braid length ``l``: the distance between the outermost apparent crossings of the two
  strands seen along the loop's normal (Audoly et al. 2007: ``v(w_c) = 0``); against
  ``l = 2 w_c sqrt(2 h R)`` (Audoly et al. 2007, Eq. 7; ``w_c`` from :mod:`dnabraid.continuum.knot_braid`);
* helical wave number ``k = |d phi / dz|`` of the strands' half-difference in the middle
  half of the braid; against ``k = (sqrt(12) h R)^(-1/2)`` (Jawed et al. 2015, Eq. 3);
* the winding of the half-difference between the outermost crossings: ``2 pi n`` for
  the ``(2, 2n+1)`` knot (a topology check).

The theory is the leading order in ``eps = sqrt(h/R)``; the bead model has the
corrections (the braid is ``l/R = 2 sqrt2 w_c eps`` of the loop radius: ~1 at eps = 0.1
for a trefoil), so the comparison is a trend: the relative differences must fall as eps
does. ``workflows/knot_crosscheck.py`` tabulates them.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from scipy.spatial import cKDTree

from ..errors import DnabraidError
from ..forces import segment_contact as segc
from ..forces.contact import contact_exclusion_range
from . import newton

#: Self-contact models of the rod: between beads (spheres of radius h) or between the
#: segments joining them (a tube of radius h round the polyline).
CONTACT_MODELS = ("beads", "segments")


class KnotError(DnabraidError, RuntimeError):
    """The knot could not be relaxed or measured (says where and why)."""


@dataclasses.dataclass(frozen=True)
class KnotRod:
    """An open (2, 2n+1) knot in an elastic rod under tension (nm, pN, pN nm^2)."""

    n: int = 1
    thickness_nm: float = 1.0             #: rod radius h
    bending_stiffness_pN_nm2: float = 1000.0  #: B = EI
    tension_pN: float = 0.8               #: T
    bead_spacing_nm: float = 0.5          #: b
    stretch_modulus_pN: float = 1000.0    #: S (bond stiffness S / b)
    contact_stiffness_pN_nm: float = 2000.0  #: k of the contact penalty
    tail_factor: float = 1.5              #: tail length / sqrt(B / T)
    contact: str = "segments"             #: "segments" or "beads" (CONTACT_MODELS)

    def __post_init__(self):
        if self.contact not in CONTACT_MODELS:
            raise ValueError(f"KnotRod.contact must be one of {CONTACT_MODELS}, got "
                             f"{self.contact!r}")

    @property
    def radius_theory_nm(self) -> float:
        """R of T = EI / (2 R^2) (Audoly et al. 2007, Eq. 1)."""
        return math.sqrt(self.bending_stiffness_pN_nm2 / (2.0 * self.tension_pN))

    @property
    def eps(self) -> float:
        return math.sqrt(self.thickness_nm / self.radius_theory_nm)

    @property
    def decay_length_nm(self) -> float:
        return math.sqrt(self.bending_stiffness_pN_nm2 / self.tension_pN)

    @property
    def exclusion_range(self) -> int:
        return contact_exclusion_range(self.thickness_nm, self.bead_spacing_nm)


def w_c(n: int) -> float:
    """Apparent-crossing abscissa w_c of the difference problem (Audoly et al. 2007; computed)."""
    from ..continuum import knot_braid as ck

    if n == 1:
        return ck.W_C_TREFOIL
    if n == 2:
        return ck.W_C_CINQUEFOIL
    return float(_W_C_CACHE.setdefault(n, ck.solve_knot(n).values["w_c"]))


_W_C_CACHE: dict = {}


def wave_number_theory(thickness_nm: float, radius_nm: float) -> float:
    """Helical wave number of a long knot's braid, k = (sqrt(12) h R)^(-1/2) (Jawed et al. 2015, Eq. 3)."""
    return (math.sqrt(12.0) * thickness_nm * radius_nm) ** -0.5


def braid_length_theory(n: int, thickness_nm: float, radius_nm: float) -> float:
    """l = 2 w_c sqrt(2 h R) (Audoly et al. 2007, Eq. 7)."""
    return 2.0 * w_c(n) * math.sqrt(2.0 * thickness_nm * radius_nm)


# -- geometry -------------------------------------------------------------------------------

def initial_geometry(rod: KnotRod, *, radius_factor: float = 1.0,
                     braid_factor: float = 1.0) -> np.ndarray:
    """Beads of the asymptotic knot shape (tails, braid, loop), ``b`` apart along the curve.

    Tails along z through (0, -+h), a braid |z| < l0/2 whose strands a, b sit at
    -+h (cos psi, sin psi), psi = s (2n+1) pi z / l0, and a loop in the plane x = 0,
    y = h + R0 (1 - cos t), z = R0 sin t + (l0/2) cos(t/2), joining the top of strand a
    to the bottom of strand b (z shifted by (l0/2) cos(t/2)). ``R0, l0`` are the theory's values times the factors.
    """
    n, h = rod.n, rod.thickness_nm
    R0 = rod.radius_theory_nm * radius_factor
    l0 = braid_length_theory(n, h, rod.radius_theory_nm) * braid_factor
    m = 4000
    sgn = 1.0 if n % 2 == 1 else -1.0
    zb = np.linspace(-l0 / 2, l0 / 2, m)
    psi = sgn * (2 * n + 1) * math.pi * zb / l0
    d = h * np.column_stack([np.cos(psi), np.sin(psi)])
    a = np.column_stack([-d, zb])
    bb = np.column_stack([d, zb])
    # loop: from the top of strand a (heading +z) round to the bottom of strand b (heading
    # +z); the shift (l0/2) cos(t/2) moves it down by l0 with zero slope at both ends
    th = np.linspace(0.0, 2 * math.pi, 4 * m)
    loop = np.column_stack([np.zeros_like(th), h + R0 * (1 - np.cos(th)),
                            R0 * np.sin(th) + (l0 / 2) * np.cos(th / 2)])
    tail = rod.tail_factor * rod.decay_length_nm
    t1 = np.column_stack([np.zeros(m), np.full(m, a[0, 1]), np.linspace(-l0 / 2 - tail, -l0 / 2, m)])
    t2 = np.column_stack([np.zeros(m), np.full(m, bb[-1, 1]), np.linspace(l0 / 2, l0 / 2 + tail, m)])
    curve = np.vstack([t1[:-1], a[:-1], loop[:-1], bb[:-1], t2])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])
    nb = int(round(s[-1] / rod.bead_spacing_nm))
    si = np.linspace(0.0, s[-1], nb + 1)
    return np.column_stack([np.interp(si, s, curve[:, k]) for k in range(3)])


# -- energy, gradient, Hessian (numpy; the OpenMM System is built in build_system) -----------

@dataclasses.dataclass
class _Problem:
    rod: KnotRod
    n_beads: int
    anchors: np.ndarray        # (4, 2) x, y of the clamped beads 0, 1, N-2, N-1
    k_side: float              # sideways restraint stiffness (pN/nm)

    @property
    def clamped(self):
        N = self.n_beads
        return np.array([0, 1, N - 2, N - 1])


def _segment_pairs(x, rod: KnotRod):
    """Segment pairs (indices of the segments (i, i+1)) closer than 2h, neighbours along
    the rod excluded: segments s, s+m with m <= exclusion_range (their nearest beads are
    then at least exclusion_range * b >= 2.5 h apart along the rod, as for the beads)."""
    return segc.segment_pairs(x, segc.chain_segments(len(x)), 2.0 * rod.thickness_nm,
                              min_separation=rod.exclusion_range)


def _contact_energy(x, rod: KnotRod) -> float:
    if rod.contact == "segments":
        return segc.contact_energy(x, segc.chain_segments(len(x)), _segment_pairs(x, rod),
                                   2.0 * rod.thickness_nm, rod.contact_stiffness_pN_nm)
    p = _pairs(x, rod)
    if not len(p):
        return 0.0
    rr = np.linalg.norm(x[p[:, 1]] - x[p[:, 0]], axis=1)
    return float(0.5 * rod.contact_stiffness_pN_nm * np.sum((2 * rod.thickness_nm - rr) ** 2))


def _pairs(x, rod: KnotRod):
    d0 = 2.0 * rod.thickness_nm
    p = np.array(sorted(cKDTree(x).query_pairs(d0)), dtype=int).reshape(-1, 2)
    return p[np.abs(p[:, 1] - p[:, 0]) > rod.exclusion_range]


def energy_terms(x, prob: _Problem) -> dict:
    """Energy of each term (pN nm) at bead positions ``x`` (N, 3)."""
    rod = prob.rod
    b = rod.bead_spacing_nm
    d = np.diff(x, axis=0)
    r = np.linalg.norm(d, axis=1)
    out = {"stretch": 0.5 * rod.stretch_modulus_pN / b * np.sum((r - b) ** 2)}
    # 1 - cos(beta) = |u/|u| - v/|v||^2 / 2: no cancellation when beta is small (the sliding
    # mode's energy changes are ~1e-11 pN nm, below the rounding of sum(1 - u.v/|u||v|))
    t = d / r[:, None]
    out["bend"] = rod.bending_stiffness_pN_nm2 / b * 0.5 * np.sum((t[1:] - t[:-1]) ** 2)
    out["contact"] = _contact_energy(x, rod)
    out["pull"] = -rod.tension_pN * (x[-1, 2] - x[0, 2])
    out["ends"] = 0.5 * prob.k_side * np.sum((x[prob.clamped, :2] - prob.anchors) ** 2)
    return out


def energy(x, prob: _Problem) -> float:
    return float(sum(energy_terms(x, prob).values()))


def gradient_hessian(x, prob: _Problem, *, gauss_newton: bool = True):
    """Gradient (3N,) and sparse Hessian (3N x 3N, CSR) of :func:`energy`.

    With ``gauss_newton`` the negative (compression) part of the bond and contact
    Hessians is dropped, which keeps the matrix closer to positive definite.
    """
    rod = prob.rod
    N = len(x)
    b = rod.bead_spacing_nm
    asm = newton.HessianAssembler(N)
    # bonds
    i = np.arange(N - 1)
    d = x[1:] - x[:-1]
    r = np.linalg.norm(d, axis=1)
    gd, Hd = newton.pair_blocks(d, r, rod.stretch_modulus_pN / b, b, gauss_newton)
    asm.pair(i, i + 1, gd, Hd)
    # contacts
    p = _pairs(x, rod) if rod.contact == "beads" else ()
    if len(p):
        dc = x[p[:, 1]] - x[p[:, 0]]
        rc = np.linalg.norm(dc, axis=1)
        gd, Hd = newton.pair_blocks(dc, rc, rod.contact_stiffness_pN_nm, 2 * rod.thickness_nm,
                                    gauss_newton)
        asm.pair(p[:, 0], p[:, 1], gd, Hd)
    # hinges: U = kappa (1 - c), c = u.v / (|u||v|), u = x1 - x0, v = x2 - x1
    j0 = np.arange(N - 2)
    asm.hinges(x, np.column_stack([j0, j0 + 1, j0 + 2]), rod.bending_stiffness_pN_nm2 / b)
    # pull and sideways restraints
    g = asm.g
    g[0, 2] += rod.tension_pN
    g[-1, 2] -= rod.tension_pN
    cl = prob.clamped
    g[cl, :2] += prob.k_side * (x[cl, :2] - prob.anchors)
    for ax in range(2):
        asm.diagonal(3 * cl + ax, np.full(len(cl), prob.k_side))
    H = asm.matrix()
    if rod.contact == "segments":
        gc, Hc = segc.contact_gradient_hessian(
            x, segc.chain_segments(N), _segment_pairs(x, rod), 2.0 * rod.thickness_nm,
            rod.contact_stiffness_pN_nm, gauss_newton=gauss_newton)
        g += gc
        H = H + Hc
    return g.ravel(), H


def make_problem(rod: KnotRod, x0) -> _Problem:
    N = len(x0)
    cl = np.array([0, 1, N - 2, N - 1])
    return _Problem(rod, N, np.asarray(x0)[cl, :2].copy(),
                    k_side=100.0 * rod.stretch_modulus_pN / rod.bead_spacing_nm)


def relax(rod: KnotRod, x0, *, gtol_pN: float | None = None, max_iter: int = 2000,
          max_escapes: int = 200, progress=None) -> dict:
    """Damped Newton minimisation of the knot energy from ``x0``, by
    :func:`dnabraid.statics.newton.minimize`.

    Stops when the largest force component is below ``gtol_pN`` (default 1e-6 T) and the
    exact Hessian has no negative curvature (the z-translation, a zero mode of the pulled
    rod, left out); saddles are escaped along their lowest mode by h/2.
    Returns dict(x, iterations, max_force_pN, energy_pN_nm, wall_time_s, converged,
    saddle_escapes, lowest_curvature_pN_per_nm, terms_pN_nm).
    Raises KnotError on non-finite values (naming the iteration) or when the strands
    passed through each other (the contact overlap exceeded h).
    """
    t0 = time.perf_counter()
    prob = make_problem(rod, x0)
    S, b = rod.stretch_modulus_pN, rod.bead_spacing_nm
    settings = newton.NewtonSettings(
        gtol=1e-6 * rod.tension_pN if gtol_pN is None else float(gtol_pN),
        max_step=0.5 * rod.thickness_nm, escape_step=0.5 * rod.thickness_nm,
        mu_start=1e-8 * S / b, mu_min=1e-12, saddle_tol=1e-9 * S / b,
        max_iter=max_iter, max_escapes=max_escapes, max_damping_tries=30, max_halvings=20)
    try:
        res = newton.minimize(
            x0, lambda x: energy(x, prob),
            lambda x, gn: gradient_hessian(x, prob, gauss_newton=gn), settings,
            lowest_mode=lambda x: _lowest_mode(x, prob), progress=progress)
    except newton.NewtonError as exc:
        raise KnotError(str(exc)) from exc
    x = res["x"]
    overlap = max_overlap(x, rod)
    if overlap > rod.thickness_nm:
        raise KnotError(f"strands passed through each other during relaxation (overlap "
                        f"{overlap:.3g} nm > h = {rod.thickness_nm} nm): lower bead_spacing_nm "
                        "or raise contact stiffness")
    return {**res, "wall_time_s": time.perf_counter() - t0,
            "terms_pN_nm": energy_terms(x, prob)}


def _lowest_mode(x, prob: _Problem):
    """Lowest eigenvalue (pN/nm) and eigenvector of the exact Hessian, the z-translation
    (a zero mode of the pulled rod) projected out."""
    _, H = gradient_hessian(x, prob, gauss_newton=False)
    n3 = H.shape[0]
    t = np.zeros(n3)
    t[2::3] = 1.0 / math.sqrt(n3 / 3)
    shift = 1e-6 * prob.rod.stretch_modulus_pN / prob.rod.bead_spacing_nm
    return newton.lowest_mode(H, shift=shift, k=4, exclude=(t,))


def max_overlap(x, rod: KnotRod) -> float:
    """Largest overlap 2h - d (nm) of the contact model (0 if nothing touches)."""
    if rod.contact == "segments":
        seg = segc.chain_segments(len(x))
        p = _segment_pairs(x, rod)
        if not len(p):
            return 0.0
        d = segc.segment_distance(x[seg[p[:, 0], 0]], x[seg[p[:, 0], 1]],
                                  x[seg[p[:, 1], 0]], x[seg[p[:, 1], 1]])[0]
        return float(2 * rod.thickness_nm - d.min())
    p = _pairs(x, rod)
    if not len(p):
        return 0.0
    return float(np.max(2 * rod.thickness_nm - np.linalg.norm(x[p[:, 1]] - x[p[:, 0]], axis=1)))


# -- OpenMM twin -------------------------------------------------------------------------------

def build_system(rod: KnotRod, x0, x_contacts=None, *, contact_cutoff_nm: float | None = None):
    """The OpenMM System of the knot scene (same energy as :func:`energy`).

    ``x0`` sets the end anchors. With ``rod.contact == "segments"`` the contact is a
    fixed list of segment pairs (:func:`dnabraid.forces.segment_contact.segment_contact_force`):
    without ``contact_cutoff_nm``, the pairs closer than 2h at ``x_contacts`` (default
    ``x0``) with their clamping cases frozen there (exact at ``x_contacts``: a check of a
    relaxed state); with it, every pair closer than the cutoff, in the general (slow to
    build) expression, for a System that moves.
    """
    import openmm

    from ..forces import bending_force, contact_force, stretch_force
    from ..units import PN_NM_IN_KJ_MOL as C

    prob = make_problem(rod, x0)
    N = len(x0)
    b = rod.bead_spacing_nm
    system = openmm.System()
    for _ in range(N):
        system.addParticle(1.0)
    system.addForce(stretch_force([(i, i + 1) for i in range(N - 1)], rod.stretch_modulus_pN / b, b))
    system.addForce(bending_force([(i, i + 1, i + 2) for i in range(N - 2)],
                                  rod.bending_stiffness_pN_nm2 / b))
    if rod.contact == "segments":
        xc = np.asarray(x0 if x_contacts is None else x_contacts, float)
        seg = segc.chain_segments(N)
        cut = 2.0 * rod.thickness_nm if contact_cutoff_nm is None else float(contact_cutoff_nm)
        p = segc.segment_pairs(xc, seg, cut, min_separation=rod.exclusion_range)
        # a static check (no cutoff given) freezes each pair's clamping case at xc: exact
        # there, and fast to build (the general Lepton expression takes ~10 s or more)
        system.addForce(segc.segment_contact_force(
            np.column_stack([seg[p[:, 0]], seg[p[:, 1]]]).reshape(-1, 4),
            2.0 * rod.thickness_nm, rod.contact_stiffness_pN_nm, name="contact",
            frozen_at=xc if contact_cutoff_nm is None else None))
    else:
        system.addForce(contact_force(N, rod.thickness_nm, rod.contact_stiffness_pN_nm,
                                      exclusion_range=rod.exclusion_range))
    ends = openmm.CustomExternalForce("-ends_f*z + 0.5*ends_k*((x-x0)^2+(y-y0)^2)")
    ends.setName("ends")
    ends.addGlobalParameter("ends_k", prob.k_side * C)
    for k in ("ends_f", "x0", "y0"):
        ends.addPerParticleParameter(k)
    for idx, (cx, cy) in zip(prob.clamped, prob.anchors):
        f = -rod.tension_pN if idx == 0 else (rod.tension_pN if idx == N - 1 else 0.0)
        ends.addParticle(int(idx), [f * C, float(cx), float(cy)])
    system.addForce(ends)
    return system


def openmm_forces(rod: KnotRod, x, x0=None, platform: str = "Reference"):
    """(energy pN nm, forces pN (N, 3)) of the OpenMM System at ``x``."""
    import openmm
    from openmm import unit

    from ..units import PN_NM_IN_KJ_MOL as C

    system = build_system(rod, x if x0 is None else x0, x_contacts=x)
    ctx = openmm.Context(system, openmm.VerletIntegrator(1e-3),
                         openmm.Platform.getPlatformByName(platform))
    ctx.setPositions(np.asarray(x) * unit.nanometer)
    st = ctx.getState(getEnergy=True, getForces=True)
    e = st.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole) / C
    f = st.getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole / unit.nanometer) / C
    del ctx
    return e, np.asarray(f)


# -- measurement -------------------------------------------------------------------------------

def measure(x, rod: KnotRod) -> dict:
    """Loop radius, braid length, wave number and winding of a relaxed knot (see module doc)."""
    x = np.asarray(x, float)
    h = rod.thickness_nm
    L = float(np.linalg.norm(np.diff(x, axis=0), axis=1).sum())
    ez = x[-1] - x[0]
    D = float(np.linalg.norm(ez))
    ez = ez / D
    rel = x - x[0]
    perp = rel - np.outer(rel @ ez, ez)
    rho = np.linalg.norm(perp, axis=1)
    apex = int(np.argmax(rho))
    ey = perp[apex] / rho[apex]
    ex = np.cross(ey, ez)
    X, Y, Z = rel @ ex, rel @ ey, rel @ ez
    # strand a: start .. loop top (largest z before the apex); strand b: loop bottom .. end
    ta = int(np.argmax(Z[:apex + 1]))
    tb = apex + int(np.argmin(Z[apex:]))
    za, zb = Z[:ta + 1], Z[tb:]
    if np.any(np.diff(za) <= 0) or np.any(np.diff(zb) <= 0):
        raise KnotError("the strands do not run monotonically along the axis: not a relaxed "
                        "open knot (measure after relax())")
    lo, hi = max(za[0], zb[0]), min(za[-1], zb[-1])
    zz = np.linspace(lo, hi, 20001)
    xa, ya = np.interp(zz, za, X[:ta + 1]), np.interp(zz, za, Y[:ta + 1])
    xb, yb = np.interp(zz, zb, X[tb:]), np.interp(zz, zb, Y[tb:])
    ub, vb = (xb - xa) / 2, (yb - ya) / 2
    sc = np.where(np.sign(vb[1:]) * np.sign(vb[:-1]) < 0)[0]
    if len(sc) < 2:
        raise KnotError("fewer than two apparent crossings: no braid found")
    zc = zz[sc] - vb[sc] * (zz[sc + 1] - zz[sc]) / (vb[sc + 1] - vb[sc])
    z_lo, z_hi = float(zc[0]), float(zc[-1])
    ell = z_hi - z_lo
    phi = np.unwrap(np.arctan2(vb, ub))
    inb = (zz >= z_lo) & (zz <= z_hi)
    winding = float(abs(phi[inb][-1] - phi[inb][0]))
    mid = (zz >= z_lo + ell / 4) & (zz <= z_hi - ell / 4)
    k = float(abs(np.polyfit(zz[mid], phi[mid], 1)[0]))
    sep = np.hypot(ub, vb)
    R_dL = (L - D) / (2 * math.pi)
    R_apex = float(rho[apex]) / 2.0
    # radius of curvature at the apex: 1 / rms of |dt/ds| over the 5 hinges round it
    seg = np.diff(x, axis=0)
    sl = np.linalg.norm(seg, axis=1)
    tan = seg / sl[:, None]
    kap = np.linalg.norm(np.diff(tan, axis=0), axis=1) / (0.5 * (sl[1:] + sl[:-1]))
    hinge = min(max(apex - 1, 2), len(kap) - 3)  # hinge index of bead `apex`
    R_curv = float(1.0 / math.sqrt(np.mean(kap[hinge - 2:hinge + 3] ** 2)))
    return {"contour_nm": L, "end_to_end_nm": D, "shortening_nm": L - D,
            "radius_dL_nm": R_dL, "radius_apex_nm": R_apex, "radius_curvature_nm": R_curv,
            "braid_length_nm": ell, "crossings": len(zc), "winding_turns": winding / (2 * math.pi),
            "wave_number_per_nm": k,
            "min_half_separation_over_h": float(sep[inb].min() / h),
            "max_overlap_nm": max_overlap(x, rod)}


def compare(rod: KnotRod, *, radius_factor: float = 1.0, braid_factor: float = 1.0,
            check_openmm: bool = True, progress=None) -> dict:
    """Relax the knot from the asymptotic shape and compare with the continuum theory."""
    x0 = initial_geometry(rod, radius_factor=radius_factor, braid_factor=braid_factor)
    res = relax(rod, x0, progress=progress)
    m = measure(res["x"], rod)
    h, B, T = rod.thickness_nm, rod.bending_stiffness_pN_nm2, rod.tension_pN
    R_th = rod.radius_theory_nm
    out = {"n": rod.n, "eps": rod.eps, "beads": len(x0), "radius_theory_nm": R_th,
           "tension_pN": T, **m,
           "tension_ratio_dL": 2 * T * m["radius_dL_nm"] ** 2 / B,
           "tension_ratio_apex": 2 * T * m["radius_apex_nm"] ** 2 / B,
           "tension_ratio_curvature": 2 * T * m["radius_curvature_nm"] ** 2 / B,
           "braid_length_theory_nm": braid_length_theory(rod.n, h, R_th),
           "wave_number_theory_per_nm": wave_number_theory(h, R_th),
           "iterations": res["iterations"], "max_force_pN": res["max_force_pN"],
           "converged": res["converged"], "wall_time_s": res["wall_time_s"],
           "energy_pN_nm": res["energy_pN_nm"], "x": res["x"]}
    out["braid_ratio"] = m["braid_length_nm"] / out["braid_length_theory_nm"]
    out["wave_number_ratio"] = m["wave_number_per_nm"] / out["wave_number_theory_per_nm"]
    if check_openmm:
        _, f = openmm_forces(rod, res["x"], x0)
        out["openmm_max_force_pN"] = float(np.abs(f).max())
    return out
