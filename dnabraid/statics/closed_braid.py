"""Closed elastic braids at zero temperature: torus links and torus knots with hard contact.

What is built
-------------
Two elastic rings of length ``L`` linked as the ``(2, 2n)`` torus link (linking number
``Lk = -+n``), or one ring of length ``2L`` tied as the ``(n, 2)`` torus knot (``n`` odd: 3
trefoil, 5 pentafoil, ...), as in van der Heijden's closed braids ("Equilibrium
theory of elastic braids", Starostin & van der Heijden, JMPS 64, 83 (2014); slides 19-23).
``L`` is the length of each of the braid's two strands (a knot's two strands close into each
other, so its ring is ``2L``); ``Delta`` is the contact diameter (the strands' centre lines
stay at least ``Delta`` apart). Each ring is a periodic chain of beads ``b`` apart: stiff
harmonic bonds (the strands are inextensible; strain < 1e-5), hinges
``U = (B/b)(1 - cos beta)`` (bending stiffness ``B``) and a one-sided contact penalty
``U = k/2 (Delta - r)^2`` for ``r < Delta`` whose stiffness is set from the expected
contact force so that the overlap is ``overlap_target`` x Delta (checked < 1 % after
relaxation). The contact is either between beads (``contact = "beads"``, as in
:mod:`dnabraid.statics.open_knot`) or between the chain's segments (``contact =
"segments"``, the smooth capsule contact of :mod:`dnabraid.forces.segment_contact`).

No twist: at zero temperature an isotropic rod whose material frame is not closed (or
whose ``Lk_i`` equals its writhe) carries no twisting moment, and the centre lines are
those of rods with bending only. This is what the seed's closed braids of slides 19-23
need: the uniform torque-free helical ply has the contact pressure
``p = B sin^4(theta) / r^3`` (r = Delta/2; derived in :func:`uniform_ply_pressure`), 3990 B/L^3
for the 4-link at Delta/L = 0.02, and the relaxed torque-free bead model gives a mean 3636 and
a range 3121-3979 (b = h/8; workflows/results/closed.md) against the seed's ~3200-3900,
whereas a ply held by a twisting moment (slide 17, ``C tau = -2B sin^3 cos / (r cos 2 theta)``)
would carry 4570 B/L^3. The twisted rings of slide 32 (``Lk_i = 5``) belong to the
chiral-buckling problem (the ``catenane`` scene), not here.

How it is relaxed
-----------------
From the uniform closed ply (strands on a torus of tube radius ``Delta/2``; ``sin theta =
pi n_ply Delta / L`` with ``n_ply = n`` for a link and ``n/2`` for a knot), with a small random
perturbation (``start_noise``, fixed seed) that breaks every symmetry of the start, so that
the symmetry of the relaxed braid is found, not imposed. :func:`relax` is the damped Newton
method of :mod:`dnabraid.statics.newton` (L-BFGS does not converge on the curved sliding
valleys; see that module's docstring) on the sparse Hessian (Gauss-Newton far from the
minimum, exact near it), for periodic chains: six coordinates are held to pin the rigid-body modes
(translations and rotations; the rotation about the torus axis is the "ply phase" of the
uniform start), and at a stationary point the lowest eigenvalue of the exact pinned
Hessian is checked (saddles are escaped along their negative mode).

What is measured (:func:`measure`)
----------------------------------
Along strand 1 (for a knot: along the whole ring), for every bead: its contact partner (the
closest point of the other strand), the chord ``d`` (from the bead to the partner), the braid
angle ``eta = atan2((t1 x t2) . d, t1 . t2)`` (the angle between the strands' tangents about
the chord; ``eta = 2 theta`` for a uniform ply; positive for a left-handed braid, as the
seed's slide 21 reports eta ~ +0.509 for Lk = -4), the contact pressure ``p`` = the normal
contact force on the bead per unit length (in B/L^3), the contact curve ``c = x + (Delta/2) d``
and, for knots, its curvature (in 1/L). The dominant Fourier harmonics of p, eta and kappa_c
(number of periods along the strand or ring) give the symmetry (slide 21: p of period n, eta
of period 2n). Gauss linking number and writhe per ring come from
:mod:`dnabraid.geometry.curves`.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import scipy.sparse as sp
from scipy.optimize import brentq
from scipy.spatial import cKDTree

from ..continuum.closed_ply import LINK, TOPOLOGIES
from ..errors import DnabraidError
from ..forces.contact import contact_exclusion_range
from . import newton

CONTACT_MODELS = ("beads", "segments")


class ClosedError(DnabraidError, RuntimeError):
    """A closed braid could not be built, relaxed or measured (says where and why)."""


# -- the uniform closed ply (start and scales) -----------------------------------------------

def ply_turns(topology: str, n: int) -> float:
    """Turns of the strands about each other per strand length L: n (link), n/2 (knot)
    (:func:`dnabraid.continuum.closed_ply.ply_turns`, which also checks n)."""
    from ..continuum.closed_ply import ply_turns as _ply_turns

    return _ply_turns(n, topology)


def uniform_sin_theta(topology: str, n: int, diameter_over_length: float) -> float:
    """sin(theta) = pi n_ply Delta / L of the uniform closed ply (theta = eta / 2).

    A strand of length L winding ``n_ply`` times at radius Delta/2 about an axis of length
    ``L cos(theta)``: tan(theta) = (Delta/2)(2 pi n_ply) / (L cos theta).
    """
    return math.pi * ply_turns(topology, n) * diameter_over_length


def uniform_ply_pressure(sin_theta: float, radius: float, bending_stiffness: float = 1.0) -> float:
    """Contact pressure of the torque-free uniform straight ply, ``p = B sin^4(theta) / r^3``.

    Kirchhoff equations for a helix (radius r, helical angle theta, curvature
    kappa = sin^2/r, torsion tau = sin cos / r) with bending moment ``B kappa b`` only:
    m' + t x n = 0 gives the binormal shear ``n_b = -B kappa tau``; zero net axial force
    (a closed ply carries none) gives the tension ``n_t = B kappa tau tan(theta)``; the
    normal balance gives ``p = n_t kappa + B kappa tau^2 = B sin^4 / r^3``. The leading
    order in Delta/L of the closed ply's pressure (the axis' curvature modulates it).
    """
    return bending_stiffness * sin_theta**4 / radius**3


@dataclasses.dataclass(frozen=True)
class ClosedBraid:
    """A closed two-strand braid (link or knot) of rods in hard contact (nm, pN, pN nm^2)."""

    topology: str = "link"                 #: "link" (2, 2n) or "knot" (n, 2)
    n: int = 4                             #: |Lk| of the link, or the knot's odd n
    handedness: str = "left"               #: "left" (Lk = -n, the seed's) or "right"
    diameter_nm: float = 2.0               #: contact diameter Delta
    diameter_over_length: float = 0.02     #: Delta / L (L: each strand's length)
    bending_stiffness_pN_nm2: float = 1000.0  #: B
    spacing_over_radius: float = 0.5       #: b / h with h = Delta / 2
    contact: str = "segments"              #: "segments" or "beads"
    overlap_target: float = 1e-4           #: expected penalty overlap / Delta
    start_noise: float = 0.02              #: start perturbation (x Delta, per bead, smooth)
    seed: int = 1

    def __post_init__(self):
        check(self)

    # geometry
    @property
    def is_link(self) -> bool:
        """Two rings, the (2, 2n) torus link (else one ring, the (n, 2) torus knot)."""
        return self.topology == LINK

    @property
    def length_nm(self) -> float:
        """L, each strand's length."""
        return self.diameter_nm / self.diameter_over_length

    @property
    def radius_nm(self) -> float:
        return 0.5 * self.diameter_nm

    @property
    def beads_per_strand(self) -> int:
        return int(round(self.length_nm / (self.spacing_over_radius * self.radius_nm)))

    @property
    def ring_beads(self) -> tuple:
        M = self.beads_per_strand
        return (M, M) if self.is_link else (2 * M,)

    @property
    def bead_spacing_nm(self) -> float:
        return self.length_nm / self.beads_per_strand

    @property
    def chirality(self) -> float:
        return 1.0 if self.handedness == "left" else -1.0

    @property
    def sin_theta(self) -> float:
        return uniform_sin_theta(self.topology, self.n, self.diameter_over_length)

    @property
    def pressure_unit(self) -> float:
        """B / L^3 in pN/nm."""
        return self.bending_stiffness_pN_nm2 / self.length_nm**3

    @property
    def pressure_scale_pN_per_nm(self) -> float:
        """Expected contact pressure: uniform ply plus the axis' curvature scale B (2 pi/L)^3."""
        B, L = self.bending_stiffness_pN_nm2, self.length_nm
        return (uniform_ply_pressure(self.sin_theta, self.radius_nm, B)
                + B * (2 * math.pi / L) ** 3)

    @property
    def contact_stiffness_pN_nm(self) -> float:
        """k such that the contact force per bead p b overlaps by overlap_target x Delta."""
        return (self.pressure_scale_pN_per_nm * self.bead_spacing_nm
                / (self.overlap_target * self.diameter_nm))

    @property
    def bond_stiffness_pN_nm(self) -> float:
        """Bond spring S/b, stiff enough that the strain under the ply tension is < 1e-5."""
        tension = self.pressure_scale_pN_per_nm * self.length_nm  # generous upper bound
        return max(tension, 1.0) / (1e-5 * self.bead_spacing_nm)

    @property
    def exclusion_range(self) -> int:
        """Beads this close along a ring do not interact (:func:`contact_exclusion_range`)."""
        return contact_exclusion_range(self.radius_nm, self.bead_spacing_nm)


def check(braid: ClosedBraid) -> None:
    """Refuse braids that cannot be built, saying which value and why (ValueError)."""
    if braid.topology not in TOPOLOGIES:
        raise ValueError(f"topology={braid.topology!r}: must be one of {TOPOLOGIES}")
    if braid.contact not in CONTACT_MODELS:
        raise ValueError(f"contact={braid.contact!r}: must be one of {CONTACT_MODELS}")
    if braid.handedness not in ("left", "right"):
        raise ValueError(f"handedness={braid.handedness!r}: must be 'left' or 'right'")
    if not isinstance(braid.n, (int, np.integer)) or braid.n < 1:
        raise ValueError(f"n={braid.n!r}: must be an integer >= 1")
    if not braid.is_link and (braid.n % 2 == 0 or braid.n < 3):
        raise ValueError(f"n={braid.n}: a (n, 2) torus knot needs an odd n >= 3 (3 trefoil, "
                         "5 pentafoil, ...): an even n gives a two-component link, n = 1 the "
                         "unknot")
    for name in ("diameter_nm", "diameter_over_length", "bending_stiffness_pN_nm2",
                 "spacing_over_radius", "overlap_target"):
        v = getattr(braid, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name}={v!r}: must be a finite number > 0")
    s = braid.sin_theta
    npl = ply_turns(braid.topology, braid.n)
    if s >= 1.0:
        raise ValueError(f"n={braid.n}: does not fit: sin(theta) = pi n_ply Delta/L = "
                         f"pi x {npl:g} x {braid.diameter_over_length:g} = {s:.3f} >= 1 (a strand "
                         f"of length L cannot wind {npl:g} times about the other at diameter "
                         "Delta); lower n or diameter_over_length")
    if s >= math.sqrt(0.5):
        raise ValueError(f"n={braid.n}: does not fit: sin(theta) = pi n_ply Delta/L = {s:.3f} "
                         ">= sin(pi/4): the ply is past lock-up (theta = 45 deg, where its "
                         "forces diverge: van der Heijden, elastic braids, slide 17; eta = 2 theta must stay below "
                         "pi/2 for closest approach, slide 5); lower n or diameter_over_length")
    R0 = braid.length_nm * math.sqrt(1 - s * s) / (2 * math.pi)
    if R0 < braid.diameter_nm:
        raise ValueError(f"diameter_over_length={braid.diameter_over_length:g}: the ply's axis "
                         f"(radius ~ L cos(theta)/2pi = {R0 / braid.length_nm:.3f} L) is too "
                         f"tight for its thickness: the strands across the ring's hole would "
                         "overlap (axis radius must be >= Delta)")
    if braid.spacing_over_radius > 1.0:
        raise ValueError(f"spacing_over_radius={braid.spacing_over_radius:g}: must be <= 1 "
                         "(b <= h = Delta/2; coarser beads let the strands slip through each "
                         "other)")
    if not (0 <= braid.start_noise <= 0.2):
        raise ValueError(f"start_noise={braid.start_noise!r}: must be in [0, 0.2] (x Delta)")


# -- start geometry ----------------------------------------------------------------------------

def _torus_curve(R0, r, turns, windings, chi, phase, m=40000):
    """Points of the curve phi in [0, 2 pi windings), psi = chi turns phi + phase on a torus."""
    phi = np.linspace(0.0, 2 * math.pi * windings, m, endpoint=False)
    psi = chi * turns * phi + phase
    rho = R0 + r * np.cos(psi)
    return np.column_stack([rho * np.cos(phi), rho * np.sin(phi), r * np.sin(psi)])


def _closed_length(c):
    return float(np.linalg.norm(np.diff(np.vstack([c, c[:1]]), axis=0), axis=1).sum())


def _resample_closed(c, nb):
    cc = np.vstack([c, c[:1]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(cc, axis=0), axis=1))])
    si = np.linspace(0.0, s[-1], nb, endpoint=False)
    return np.column_stack([np.interp(si, s, cc[:, k]) for k in range(3)])


def initial_geometry(braid: ClosedBraid) -> list:
    """Bead rings (list of (M, 3) arrays, nm) of the uniform closed ply, perturbed.

    Link: rings ``k = 0, 1`` are ``phi in [0, 2 pi)``, ``psi = chi n phi + k pi``; knot: one ring
    ``phi in [0, 4 pi)``, ``psi = chi (n/2) phi`` (its two passes lie on opposite sides of the
    tube); both on a torus of tube radius Delta/2 whose major radius R0 makes each strand
    exactly L long. ``chi = -1`` is the left-handed (Lk = -n) braid. The perturbation is a
    smooth random displacement (a few long-wavelength Fourier modes, amplitude
    ``start_noise`` x Delta, seed ``seed``) that breaks the start's symmetry.
    """
    L, r, n = braid.length_nm, braid.radius_nm, braid.n
    chi = braid.chirality
    if braid.is_link:
        specs = [(n, 1, 0.0), (n, 1, math.pi)]
        target = L
    else:
        specs = [(0.5 * n, 2, 0.0)]
        target = 2 * L

    def length_of(R0):
        t, w, ph = specs[0]
        return _closed_length(_torus_curve(R0, r, t, w, chi, ph)) - target

    R0 = brentq(length_of, 1.5 * r, L)
    rng = np.random.default_rng(braid.seed)
    rings = []
    for (t, w, ph), nb in zip(specs, braid.ring_beads):
        x = _resample_closed(_torus_curve(R0, r, t, w, chi, ph), nb)
        if braid.start_noise > 0:
            u = np.linspace(0, 2 * math.pi, nb, endpoint=False)
            pert = np.zeros_like(x)
            for k in range(1, 6):
                a = rng.normal(size=(2, 3))
                pert += np.outer(np.cos(k * u), a[0]) + np.outer(np.sin(k * u), a[1])
            pert *= braid.start_noise * braid.diameter_nm / np.abs(pert).max()
            x = x + pert
        rings.append(x)
    return rings


# -- chain topology ------------------------------------------------------------------------------

@dataclasses.dataclass
class Chains:
    """Index structure of the periodic chains (concatenated rings)."""

    sizes: tuple
    offsets: np.ndarray
    ring_of: np.ndarray      # (N,) ring index of each bead
    pos_in: np.ndarray       # (N,) index within its ring
    bonds: np.ndarray        # (N, 2) periodic bonds
    hinges: np.ndarray       # (N, 3) periodic hinges
    exclusion: int

    @property
    def n_beads(self) -> int:
        return int(sum(self.sizes))

    def ring(self, k) -> slice:
        return slice(int(self.offsets[k]), int(self.offsets[k] + self.sizes[k]))

    def allowed(self, i, j) -> np.ndarray:
        """True for bead pairs that may be in contact (other ring, or far along the ring)."""
        i, j = np.asarray(i), np.asarray(j)
        same = self.ring_of[i] == self.ring_of[j]
        m = np.asarray(self.sizes)[self.ring_of[i]]
        dk = np.abs(self.pos_in[i] - self.pos_in[j])
        dk = np.minimum(dk, m - dk)
        return ~same | (dk > self.exclusion)


def make_chains(sizes, exclusion: int) -> Chains:
    sizes = tuple(int(s) for s in sizes)
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int)
    ring_of = np.concatenate([np.full(s, k) for k, s in enumerate(sizes)])
    pos_in = np.concatenate([np.arange(s) for s in sizes])
    bonds, hinges = [], []
    for o, s in zip(offsets, sizes):
        i = np.arange(s)
        bonds.append(np.column_stack([o + i, o + (i + 1) % s]))
        hinges.append(np.column_stack([o + (i - 1) % s, o + i, o + (i + 1) % s]))
    return Chains(sizes, offsets, ring_of, pos_in, np.vstack(bonds), np.vstack(hinges),
                  int(exclusion))


def _segment_module():
    try:
        from ..forces import segment_contact
    except ImportError as exc:
        raise ClosedError("contact='segments' needs dnabraid.forces.segment_contact, which "
                          "this installation lacks; use contact='beads'") from exc
    return segment_contact


# -- energy, gradient, Hessian -----------------------------------------------------------------

@dataclasses.dataclass
class Problem:
    braid: ClosedBraid
    chains: Chains

    @property
    def segments(self) -> np.ndarray:
        return self.chains.bonds


def make_problem(braid: ClosedBraid) -> Problem:
    return Problem(braid, make_chains(braid.ring_beads, braid.exclusion_range))


def bead_pairs(x, prob: Problem) -> np.ndarray:
    """Bead pairs closer than Delta that may touch (k-d tree, then the chain exclusion)."""
    p = np.array(sorted(cKDTree(x).query_pairs(prob.braid.diameter_nm)), dtype=int).reshape(-1, 2)
    if not len(p):
        return p
    return p[prob.chains.allowed(p[:, 0], p[:, 1])]


def segment_pairs(x, prob: Problem) -> np.ndarray:
    """Segment pairs (indices into ``prob.segments``, the rings' bonds) closer than Delta,
    segments at most ``exclusion_range`` apart along a ring excluded."""
    sc = _segment_module()
    ch = prob.chains
    excl = sc.chain_exclusion([(m, True) for m in ch.sizes], ch.exclusion)
    return np.asarray(sc.segment_pairs(x, prob.segments, prob.braid.diameter_nm,
                                       exclude=excl), dtype=int).reshape(-1, 2)


def energy_terms(x, prob: Problem) -> dict:
    """Energy of each term (pN nm) at bead positions ``x`` (N, 3)."""
    br, ch = prob.braid, prob.chains
    b = br.bead_spacing_nm
    d = x[ch.bonds[:, 1]] - x[ch.bonds[:, 0]]
    r = np.linalg.norm(d, axis=1)
    out = {"stretch": 0.5 * br.bond_stiffness_pN_nm * float(np.sum((r - b) ** 2))}
    u = x[ch.hinges[:, 1]] - x[ch.hinges[:, 0]]
    v = x[ch.hinges[:, 2]] - x[ch.hinges[:, 1]]
    c = np.sum(u * v, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
    out["bend"] = br.bending_stiffness_pN_nm2 / b * float(np.sum(1.0 - c))
    out["contact"] = contact_energy(x, prob)
    return out


def energy(x, prob: Problem) -> float:
    return float(sum(energy_terms(x, prob).values()))


def contact_energy(x, prob: Problem) -> float:
    br = prob.braid
    if br.contact == "segments":
        sc = _segment_module()
        p = segment_pairs(x, prob)
        return float(sc.contact_energy(x, prob.segments, p, br.diameter_nm,
                                       br.contact_stiffness_pN_nm)) if len(p) else 0.0
    p = bead_pairs(x, prob)
    if not len(p):
        return 0.0
    rr = np.linalg.norm(x[p[:, 1]] - x[p[:, 0]], axis=1)
    return 0.5 * br.contact_stiffness_pN_nm * float(np.sum((br.diameter_nm - rr) ** 2))


def gradient_hessian(x, prob: Problem, *, gauss_newton: bool = True, terms=None):
    """Gradient (3N,) and sparse Hessian (3N x 3N, CSR) of :func:`energy`.

    ``terms`` (default all) restricts to a subset of ("stretch", "bend", "contact").
    With ``gauss_newton`` the compression part of the bond and contact Hessians is dropped.
    """
    br, ch = prob.braid, prob.chains
    terms = ("stretch", "bend", "contact") if terms is None else terms
    N = len(x)
    asm = newton.HessianAssembler(N)
    if "stretch" in terms:
        i, j = ch.bonds[:, 0], ch.bonds[:, 1]
        d = x[j] - x[i]
        r = np.linalg.norm(d, axis=1)
        gd, Hd = newton.pair_blocks(d, r, br.bond_stiffness_pN_nm, br.bead_spacing_nm,
                                    gauss_newton)
        asm.pair(i, j, gd, Hd)
    if "bend" in terms:
        asm.hinges(x, ch.hinges, br.bending_stiffness_pN_nm2 / br.bead_spacing_nm)
    H_extra = None
    if "contact" in terms:
        if br.contact == "segments":
            sc = _segment_module()
            p = segment_pairs(x, prob)
            if len(p):
                gc, H_extra = sc.contact_gradient_hessian(
                    x, prob.segments, p, br.diameter_nm, br.contact_stiffness_pN_nm,
                    gauss_newton=gauss_newton)
                asm.g += np.asarray(gc).reshape(N, 3)
        else:
            p = bead_pairs(x, prob)
            if len(p):
                dc = x[p[:, 1]] - x[p[:, 0]]
                rc = np.linalg.norm(dc, axis=1)
                gd, Hd = newton.pair_blocks(dc, rc, br.contact_stiffness_pN_nm, br.diameter_nm,
                                            gauss_newton)
                asm.pair(p[:, 0], p[:, 1], gd, Hd)
    H = asm.matrix()
    if H_extra is not None:
        H = (H + sp.csr_matrix(H_extra)).tocsr()
    return asm.g.ravel(), H


def contact_forces(x, prob: Problem) -> np.ndarray:
    """Contact force on every bead (pN, (N, 3)): minus the contact energy's gradient."""
    g, _ = gradient_hessian(x, prob, terms=("contact",))
    return -g.reshape(-1, 3)


def rigid_modes(x) -> np.ndarray:
    """Orthonormal basis (3N, 6) of the rigid-body motions (translations, rotations) at x."""
    x = np.asarray(x, float)
    N = len(x)
    c = x - x.mean(axis=0)
    V = np.zeros((3 * N, 6))
    for k in range(3):
        V[k::3, k] = 1.0
        e = np.zeros(3)
        e[k] = 1.0
        V[:, 3 + k] = np.cross(e, c).ravel()
    q, _ = np.linalg.qr(V)
    return q


# -- relaxation --------------------------------------------------------------------------------

def pinned_dofs(x) -> np.ndarray:
    """Six coordinates whose fixing removes the rigid-body modes (flat indices into x).

    Bead a = 0 (all three), the bead b farthest from it (the two coordinates across a-b),
    the bead c farthest from the line a-b (the coordinate along the plane's normal).
    """
    x = np.asarray(x, float)
    a = 0
    b = int(np.argmax(np.linalg.norm(x - x[a], axis=1)))
    e = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
    rel = x - x[a]
    perp = rel - np.outer(rel @ e, e)
    c = int(np.argmax(np.linalg.norm(perp, axis=1)))
    nrm = np.cross(e, perp[c])
    kb = [k for k in np.argsort(np.abs(e))[:2]]
    kc = int(np.argmax(np.abs(nrm)))
    return np.array([3 * a, 3 * a + 1, 3 * a + 2, 3 * b + kb[0], 3 * b + kb[1], 3 * c + kc])


def relax(braid: ClosedBraid, x0, *, gtol_pN: float | None = None, max_iter: int = 400,
          max_escapes: int = 50, check_saddle: bool = True, progress=None) -> dict:
    """Damped Newton minimisation of the closed braid's energy from ``x0`` ((N, 3), nm),
    by :func:`dnabraid.statics.newton.minimize`.

    Stops when the largest force component is below ``gtol_pN`` (default 1e-6 x the
    contact force per bead, p_scale b). The rigid-body modes are pinned: six coordinates
    (:func:`pinned_dofs`) are held, which leaves the energy's minima unchanged (any
    configuration can be moved rigidly onto that slice). The Hessian is Gauss-Newton
    (compressed bonds' and contacts' negative transverse stiffness dropped) while the
    force is large and exact (Levenberg-damped) once it is below 1e-3 p_scale b: the
    dropped term is the contact's sliding softness, without which the last, soft sliding
    modes converge only linearly. The rotation about the torus axis (the uniform start's
    "ply phase") is one of the pinned rigid modes; what remains soft is each ring's bead
    lattice sliding along the ring (a zero mode of the continuum, weakly corrugated by the
    discretisation), which the exact-Hessian phase resolves in a few tens of iterations.
    At a stationary point the lowest eigenvalue of the exact pinned Hessian is checked
    (``check_saddle``); a negative one is escaped along its mode.
    Returns dict(x, iterations, max_force_pN, energy_pN_nm, converged, saddle_escapes,
    lowest_curvature_pN_per_nm, wall_time_s, terms_pN_nm).
    Raises ClosedError on non-finite values or when the strands passed through each other.
    """
    t0 = time.perf_counter()
    prob = make_problem(braid)
    f_scale = braid.pressure_scale_pN_per_nm * braid.bead_spacing_nm
    soft = braid.bending_stiffness_pN_nm2 / braid.bead_spacing_nm**3
    settings = newton.NewtonSettings(
        gtol=1e-6 * f_scale if gtol_pN is None else float(gtol_pN),
        max_step=0.25 * braid.radius_nm, escape_step=0.1 * braid.radius_nm,
        mu_start=1e-6 * soft, mu_min=1e-12 * soft, saddle_tol=1e-9 * soft,
        max_iter=max_iter, max_escapes=max_escapes, max_damping_tries=40, max_halvings=12,
        exact_below=1e-3 * f_scale, adaptive_damping=True, stall_limit=3)
    pinned = pinned_dofs(x0)
    free = np.setdiff1d(np.arange(np.size(x0)), pinned)
    try:
        res = newton.minimize(
            x0, lambda x: energy(x, prob),
            lambda x, gn: gradient_hessian(x, prob, gauss_newton=gn), settings, pinned=pinned,
            lowest_mode=(lambda x: lowest_mode(x, prob, free=free)) if check_saddle else None,
            progress=progress)
    except newton.NewtonError as exc:
        raise ClosedError(str(exc)) from exc
    x = res["x"]
    terms = energy_terms(x, prob)
    overlap = max_overlap(x, prob)
    if overlap > 0.5 * braid.diameter_nm:
        raise ClosedError(f"strands passed through each other during relaxation (overlap "
                          f"{overlap:.3g} nm > Delta/2): lower spacing_over_radius")
    return {**res, "gtol_pN": settings.gtol, "wall_time_s": time.perf_counter() - t0,
            "terms_pN_nm": terms}


def lowest_mode(x, prob: Problem, free=None):
    """Lowest eigenvalue (pN/nm) and eigenvector (3N,) of the exact Hessian with the rigid
    modes pinned (``free``: the unpinned flat coordinates; default :func:`pinned_dofs`)."""
    _, H = gradient_hessian(x, prob, gauss_newton=False)
    if free is None:
        free = np.setdiff1d(np.arange(H.shape[0]), pinned_dofs(x))
    shift = 1e-3 * prob.braid.bending_stiffness_pN_nm2 / prob.braid.bead_spacing_nm**3
    try:
        return newton.lowest_mode(H, shift=shift, free=free)
    except newton.NewtonError as exc:
        raise ClosedError(str(exc)) from exc


def max_overlap(x, prob: Problem) -> float:
    """Largest penetration Delta - (closest distance) of contacting beads/segments (nm)."""
    br = prob.braid
    if br.contact == "segments":
        sc = _segment_module()
        p = segment_pairs(x, prob)
        if not len(p):
            return 0.0
        seg = prob.segments
        a, b = seg[p[:, 0]], seg[p[:, 1]]
        dist, _, _ = sc.segment_distance(x[a[:, 0]], x[a[:, 1]], x[b[:, 0]], x[b[:, 1]])
        return float(max(0.0, np.max(br.diameter_nm - dist)))
    p = bead_pairs(x, prob)
    if not len(p):
        return 0.0
    return float(np.max(br.diameter_nm - np.linalg.norm(x[p[:, 1]] - x[p[:, 0]], axis=1)))


# -- measurement -------------------------------------------------------------------------------

def _tangents(x, chains: Chains) -> np.ndarray:
    """Unit tangent at every bead (central difference on its ring)."""
    d = x[chains.hinges[:, 2]] - x[chains.hinges[:, 0]]
    return d / np.linalg.norm(d, axis=1)[:, None]


def _bead_lengths(x, chains: Chains) -> np.ndarray:
    """Length of ring carried by each bead (half its two bonds)."""
    a = np.linalg.norm(x[chains.hinges[:, 1]] - x[chains.hinges[:, 0]], axis=1)
    b = np.linalg.norm(x[chains.hinges[:, 2]] - x[chains.hinges[:, 1]], axis=1)
    return 0.5 * (a + b)


def partners(x, chains: Chains, min_ring_distance: int, search_radius: float):
    """Closest point of the other strand to every bead.

    Candidates are the segments (j, j+1) of beads j within ``search_radius`` on another ring,
    or more than ``min_ring_distance`` beads away along the same ring. Returns
    (seg_start (N,), u (N,), q (N, 3) nm, dist (N,) nm, next_bead (N,)): the partner is
    ``q = x[s] + u (x[next[s]] - x[s])`` on segment ``s = seg_start``; seg_start = -1 where
    none was found.
    """
    N = len(x)
    tree = cKDTree(x)
    nbr = tree.query_ball_point(x, search_radius)
    nxt = np.empty(N, dtype=int)
    for k in range(len(chains.sizes)):
        sl = chains.ring(k)
        idx = np.arange(sl.start, sl.stop)
        nxt[idx] = np.roll(idx, -1)
    prv = np.empty(N, dtype=int)
    prv[nxt] = np.arange(N)
    seg_start = np.full(N, -1)
    u_best = np.zeros(N)
    q_best = np.full((N, 3), np.nan)
    d_best = np.full(N, np.inf)
    sizes = np.asarray(chains.sizes)
    for i in range(N):
        js = np.asarray(nbr[i], dtype=int)
        if not len(js):
            continue
        same = chains.ring_of[js] == chains.ring_of[i]
        dk = np.abs(chains.pos_in[js] - chains.pos_in[i])
        dk = np.minimum(dk, sizes[chains.ring_of[i]] - dk)
        js = js[~same | (dk > min_ring_distance)]
        if not len(js):
            continue
        starts = np.unique(np.concatenate([js, prv[js]]))
        a, b = x[starts], x[nxt[starts]]
        ab = b - a
        u = np.clip(np.sum((x[i] - a) * ab, axis=1) / np.sum(ab * ab, axis=1), 0.0, 1.0)
        q = a + u[:, None] * ab
        dd = np.linalg.norm(q - x[i], axis=1)
        m = int(np.argmin(dd))
        seg_start[i], u_best[i], q_best[i], d_best[i] = starts[m], u[m], q[m], dd[m]
    return seg_start, u_best, q_best, d_best, nxt


def harmonics(y, top: int = 3) -> list:
    """Dominant Fourier harmonics of a periodic sample ``y``: [(k, |c_k| / |c_0|), ...].

    ``k`` is the number of periods along the sample (k >= 1), sorted by amplitude.
    """
    y = np.asarray(y, float)
    c = np.fft.rfft(y) / len(y)
    amp = np.abs(c[1:])
    order = np.argsort(amp)[::-1][:top]
    c0 = abs(c[0]) if abs(c[0]) > 0 else 1.0
    return [(int(k + 1), float(2 * amp[k] / c0)) for k in order]


def _smooth_periodic(y, window: int):
    """Moving average over ``window`` samples on a periodic sample."""
    if window <= 1:
        return np.asarray(y, float)
    k = np.ones(window) / window
    yy = np.concatenate([y[-window:], y, y[:window]])
    return np.convolve(yy, k, mode="same")[window:-window]


def _curvature_periodic(c, ds, kmax):
    """Curvature of a closed sampled curve c (M, 3), spectral derivatives up to harmonic kmax."""
    M = len(c)
    C = np.fft.rfft(c, axis=0)
    C[kmax + 1:] = 0.0
    k = np.arange(C.shape[0])[:, None]
    w = 2 * math.pi * k / (M * ds)
    c1 = np.fft.irfft(1j * w * C, n=M, axis=0)
    c2 = np.fft.irfft(-(w**2) * C, n=M, axis=0)
    return np.linalg.norm(np.cross(c1, c2), axis=1) / np.linalg.norm(c1, axis=1) ** 3


def measure(x, braid: ClosedBraid, *, smooth_over_diameter: float = 1.0) -> dict:
    """Contact map, braid angle, pressure, contact curve and topology of a relaxed braid.

    Arrays (per bead of strand 1 for a link, of the whole ring for a knot): ``s_over_L``,
    ``eta`` (rad) and ``pressure`` (B/L^3) per bead, ``eta_smooth`` and ``pressure_smooth``
    (moving averages over ``smooth_over_diameter`` x Delta of ring, which remove the
    bead-scale corrugation), ``gap_over_diameter`` (closest distance / Delta - 1), and for
    knots ``contact_curvature`` (1/L). Scalars: means (of the per-bead values), min/max (of
    the smoothed ones; ``*_raw_*`` per bead), dominant harmonics, the power fraction in
    multiples of the expected period counts (:func:`symmetry`), Gauss linking number, writhe
    per ring, overlap and contact-loss measures.

    Notes
    -----
    eta(s) is parametrised by strand 1's arclength: the strand exchange (rotation by pi/n),
    which makes eta of period 2n on the contact itself, maps s to the partner's sigma(s),
    and sigma' - 1 has period n, so a small harmonic n remains in eta(s) (about 1/6 of the
    2n one for the 4-link, independent of b). The contact curve's curvature is computed
    from the contact points' Fourier series over the ring truncated at max(8, 6n)
    harmonics (a low-pass against the bead-scale roughness, well above the 2n of the
    physical modulation).
    """
    x = np.asarray(x, float)
    prob = make_problem(braid)
    ch = prob.chains
    L, D = braid.length_nm, braid.diameter_nm
    t = _tangents(x, ch)
    ell = _bead_lengths(x, ch)
    min_rd = max(ch.exclusion, int(0.25 * braid.beads_per_strand))
    seg, u, q, dist, nxt = partners(x, ch, min_rd, 1.5 * D + 2 * braid.bead_spacing_nm)
    lost = seg < 0                 # no partner within 1.5 Delta: the strands are apart here
    if np.all(lost):
        raise ClosedError("no bead has a contact partner within 1.5 Delta: the strands "
                          "separated (not a braid)")
    seg = np.where(lost, 0, seg)
    t2 = (1 - u)[:, None] * t[seg] + u[:, None] * t[nxt[seg]]
    t2 /= np.linalg.norm(t2, axis=1)[:, None]
    q = np.where(lost[:, None], x, q)
    dist = np.where(lost, np.inf, dist)
    dvec = np.where(lost[:, None], 0.0, (q - x) / np.where(lost, 1.0, dist)[:, None])
    eta = np.arctan2(np.sum(np.cross(t, t2) * dvec, axis=1), np.sum(t * t2, axis=1))
    eta = np.where(lost, np.nan, eta)
    fc = contact_forces(x, prob)
    pn = -np.sum(fc * dvec, axis=1) / ell          # normal push away from the partner, pN/nm
    p = pn / braid.pressure_unit
    if braid.is_link:
        sl = ch.ring(0)
    else:
        sl = slice(0, ch.n_beads)
    s = np.concatenate([[0.0], np.cumsum(ell[sl][:-1])]) / L
    win = max(1, int(round(smooth_over_diameter * D / braid.bead_spacing_nm)))
    ps = _smooth_periodic(p[sl], win)
    if np.any(np.isnan(eta[sl])):
        raise ClosedError(f"{int(np.sum(np.isnan(eta[sl])))} beads of strand 1 have no "
                          "contact partner within 1.5 Delta: the strands separated")
    es = _smooth_periodic(eta[sl], win)
    out = {
        "s_over_L": s, "eta": eta[sl], "eta_smooth": es, "pressure": p[sl],
        "pressure_smooth": ps, "gap_over_diameter": dist[sl] / D - 1.0,
        "eta_mean": float(np.mean(eta[sl])), "eta_min": float(np.min(es)),
        "eta_max": float(np.max(es)),
        "eta_raw_min": float(np.min(eta[sl])), "eta_raw_max": float(np.max(eta[sl])),
        "pressure_mean": float(np.mean(p[sl])),
        "pressure_min": float(np.min(ps)), "pressure_max": float(np.max(ps)),
        "pressure_raw_min": float(np.min(p[sl])), "pressure_raw_max": float(np.max(p[sl])),
        "pressure_smoothing_window_beads": win,
        # no contact force within a window of ~Delta: the strands touch without pressing or
        # are apart there (the threshold: 1e-3 of the uniform ply's pressure)
        "contact_lost_fraction": float(np.mean(
            ps <= 1e-3 * uniform_ply_pressure(braid.sin_theta, 0.5 * braid.diameter_over_length))),
        "contact_lost_fraction_per_bead": float(np.mean(p[sl] <= 0.0)),
        "pressure_harmonics": harmonics(p[sl]),
        "eta_harmonics": harmonics(eta[sl]),
        "contact_distance_over_diameter_mean": float(np.mean(dist[sl]) / D),
        "contact_distance_over_diameter_min": float(np.min(dist[sl]) / D),
        "contact_distance_over_diameter_max": float(np.max(dist[sl]) / D),
        "max_overlap_over_diameter": max_overlap(x, prob) / D,
        "strand_lengths_over_L": [float(np.sum(np.linalg.norm(
            x[ch.bonds[ch.ring(k), 1]] - x[ch.bonds[ch.ring(k), 0]], axis=1)) / L)
            for k in range(len(ch.sizes))],
    }
    out["pressure_smooth_harmonics"] = harmonics(ps)
    out["eta_smooth_harmonics"] = harmonics(es)
    # slide 21: p of period n, eta of period 2n along a link's ring; slide 23: p of period n
    # on a knot's whole ring (its contact, covered twice by the ring, has eta of period n)
    npk = braid.n
    nek = 2 * braid.n if braid.is_link else braid.n
    out["pressure_symmetry"] = symmetry(ps, npk)
    out["eta_symmetry"] = symmetry(es, nek)
    out["eta_symmetry_half"] = symmetry(es, npk) if braid.is_link else None
    from ..geometry.curves import gauss_linking_number, writhe

    rings = [x[ch.ring(k)] for k in range(len(ch.sizes))]
    out["writhe_per_ring"] = [float(writhe(r)) for r in rings]
    if braid.is_link:
        out["linking_number"] = float(gauss_linking_number(rings[0], rings[1]))
    else:
        out["linking_number"] = None
        c = 0.5 * (x + q)                           # contact curve over the whole ring
        ds = float(np.mean(ell))
        kappa = _curvature_periodic(c, ds, kmax=max(8, 6 * braid.n)) * L
        # the contact curve is covered twice by the ring: its length is about L, so the
        # curvature wrt the ring parameter is rescaled by |dc/ds_ring| (spectral, as above)
        C = np.fft.rfft(c, axis=0)
        C[max(8, 6 * braid.n) + 1:] = 0.0
        kk = np.arange(C.shape[0])[:, None]
        c1 = np.fft.irfft(1j * (2 * math.pi * kk / (len(c) * ds)) * C, n=len(c), axis=0)
        out["contact_curve_length_over_L"] = float(np.mean(np.linalg.norm(c1, axis=1))
                                                   * len(c) * ds / L / 2.0)
        out["contact_curvature"] = kappa
        out["contact_curvature_mean"] = float(np.mean(kappa))
        out["contact_curvature_min"] = float(np.min(kappa))
        out["contact_curvature_max"] = float(np.max(kappa))
        out["contact_curvature_harmonics_per_ring"] = harmonics(kappa)
    return out


def continuum_reference(braid: ClosedBraid) -> dict:
    """The closed ply's continuum numbers (lengths in L, pressure in B/L^3, energy in B/L).

    ``eta_uniform`` and ``pressure_uniform_torque_free`` (:func:`uniform_ply_pressure`)
    always; under ``continuum`` the closed-form functions of
    :mod:`dnabraid.continuum.closed_ply` (the axis-curvature corrections): ``eta_rad``,
    ``eta_mean_rad``/``eta_min_rad``/``eta_max_rad`` (O(eps^2) expansion),
    ``pressure_uniform_B_per_L3``, ``pressure_mean_B_per_L3`` (Eq. 4),
    ``pressure_mean_torus_B_per_L3`` (virtual work on the torus family),
    ``writhe_per_ring`` (formula), ``writhe_per_ring_fuller``, ``energy_torus_B_per_L`` (the
    torus helix, an upper bound of the relaxed energy), ``contact_curvature_per_L`` (1/R).
    Each is taken only if that function exists and succeeds (``continuum_error`` lists the
    others); the full :func:`~dnabraid.continuum.closed_ply.closed_ply` result is not called,
    to keep the scene fast.
    """
    s = braid.sin_theta
    out = {"eta_uniform": 2 * math.asin(s),
           "pressure_uniform_torque_free": uniform_ply_pressure(s, 0.5 * braid.diameter_over_length),
           "source": "sin theta = pi n_ply Delta/L, p = B sin^4 theta / r^3 "
                     "(dnabraid.statics.closed_braid)"}
    try:
        from ..continuum import closed_ply as cc
    except ImportError as exc:
        out["continuum_error"] = f"dnabraid.continuum.closed_ply unavailable: {exc}"
        return out
    args = (braid.n, braid.diameter_over_length, braid.topology)
    calls = {
        "eta_rad": lambda: 2 * cc.closed_ply_angle(*args),
        "eta_expansion": lambda: cc.braid_angle_expansion(*args),
        "pressure_uniform_B_per_L3": lambda: cc.uniform_pressure(*args),
        "pressure_mean_B_per_L3": lambda: cc.mean_pressure_formula(*args),
        "pressure_mean_torus_B_per_L3": lambda: cc.mean_pressure_virtual_work(*args),
        "writhe_per_ring": lambda: cc.writhe_formula(*args),
        "writhe_per_ring_fuller": lambda: cc.writhe_fuller(*args),
        "energy_torus_B_per_L": lambda: cc.torus_helix_energy(*args),
        "contact_curvature_per_L": lambda: 1.0 / cc.axis_radius_exact(*args),
    }
    vals, errors = {}, []
    for k, f in calls.items():
        try:
            vals[k] = f()
        except Exception as exc:  # noqa: BLE001 - a comparison column is optional
            errors.append(f"{k}: {type(exc).__name__}: {exc}")
    eta = vals.pop("eta_expansion", None)
    if isinstance(eta, dict):
        for k in ("mean", "min", "max"):
            if f"eta_{k}" in eta:
                vals[f"eta_{k}_rad"] = float(eta[f"eta_{k}"])
    out["continuum"] = {k: float(v) for k, v in vals.items()}
    out["source"] += "; dnabraid.continuum.closed_ply"
    if errors:
        out["continuum_error"] = "; ".join(errors)
    return out


def symmetry(y, period_count: int) -> dict:
    """How much of a periodic sample's variation lies in harmonics that are multiples of
    ``period_count`` (1 for a signal with exactly that many periods), and the amplitude
    (|c_k| / |c_0|, as :func:`harmonics`) at k = period_count."""
    y = np.asarray(y, float)
    c = np.fft.rfft(y - y.mean())
    pw = np.abs(c[1:]) ** 2
    k = np.arange(1, len(c))
    tot = float(pw.sum())
    frac = float(pw[k % period_count == 0].sum() / tot) if tot > 0 else 1.0
    c0 = abs(np.mean(y)) or 1.0
    amp = float(2 * np.abs(c[period_count]) / len(y) / c0) if period_count < len(c) else 0.0
    return {"periods": int(period_count), "power_fraction": frac, "amplitude": amp}


def solve(braid: ClosedBraid, *, progress=None, check_saddle: bool = True) -> dict:
    """Build the start, relax, measure: everything the scene and the workflow report."""
    rings = initial_geometry(braid)
    x0 = np.vstack(rings)
    res = relax(braid, x0, progress=progress, check_saddle=check_saddle)
    m = measure(res["x"], braid)
    prob = make_problem(braid)
    B, L = braid.bending_stiffness_pN_nm2, braid.length_nm
    out = {"beads": len(x0), "bead_spacing_nm": braid.bead_spacing_nm,
           "contact_stiffness_pN_nm": braid.contact_stiffness_pN_nm,
           "sin_theta_uniform": braid.sin_theta, **m,
           "energy_over_B_per_L": res["energy_pN_nm"] / (B / L),
           "bending_energy_over_B_per_L": res["terms_pN_nm"]["bend"] / (B / L),
           "iterations": res["iterations"], "max_force_pN": res["max_force_pN"],
           "converged": res["converged"], "saddle_escapes": res["saddle_escapes"],
           "lowest_curvature_pN_per_nm": res["lowest_curvature_pN_per_nm"],
           "wall_time_s": res["wall_time_s"], "x": res["x"], "x0": x0,
           "reference": continuum_reference(braid),
           "n_contact_pairs": int(len(bead_pairs(res["x"], prob))) if braid.contact == "beads"
           else int(len(segment_pairs(res["x"], prob)))}
    return out
