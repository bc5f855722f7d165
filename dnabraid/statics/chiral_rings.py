"""Two linked elastic rings with twist and the Kornyshev chiral term, at zero temperature.

The seed's chiral linked rings (van der Heijden, "Equilibrium theory of elastic braids",
slides 31-32; Starostin & van der Heijden, JMPS 64, 83 (2014)): two DNA minicircles of
length ``L`` linked as a 2-crossing Hopf link (``Lk_12 = -1``, left-handed; the Villarceau
circles of slide 14 are the start), each with a closed material frame of linking number
``Lk_i``, in contact with each other at distance ``Delta``, and a chiral interaction of
energy ``phi = alpha tan(eta/2)`` per unit contact length (Kornyshev, Lee, Leikin &
Wynveen, Rev. Mod. Phys. 79, 943 (2007)); ``alpha > 0`` lowers the braid angle ``eta``
(favours right-handed contact).

Units
-----
Lengths in ``L`` (the length of each ring), energies in ``B/L`` (``B`` the bending
stiffness), forces in ``B/L^2``, stiffness (Hessian) in ``B/L^3``, ``alpha`` in ``B/L^2``
(as slide 32), torques in ``B/L``. The bead model of :mod:`dnabraid.statics.closed_braid`
is reused with its "nm" read as ``L`` and ``B = 1``.

Energy (:func:`energy_terms`)
-----------------------------
* ``stretch``, ``bend``: the periodic bead chains of :mod:`~dnabraid.statics.closed_braid`
  (stiff bonds, hinges ``(B/b)(1 - cos beta)``);
* ``hard``: the one-sided capsule contact of :mod:`dnabraid.forces.segment_contact` between
  all segment pairs (other ring, or far along the same ring), ``k/2 (Delta - d)^2``;
* ``bilateral`` (contact ``"bilateral"`` only): every bead is held at ``Delta`` from the
  other ring, ``(k/2) sum_i (d_i - Delta)^2`` with ``d_i`` the distance from bead ``i`` to
  the closest point of the other ring's polyline. The seed's braid theory works with
  constant-distance curves (slides 3-4, 13): the contact is bilateral along the whole
  length and its pressure sign is checked afterwards (:func:`measure` reports it);
* ``twist``: per ring ``E_tw = 2 pi^2 C (Lk_i - Wr_i)^2 / L`` (isotropic rod, closed
  material frame, uniform twist ``Tw_i = Lk_i - Wr_i`` by Calugareanu-White-Fuller
  ``Lk = Tw + Wr``; White 1969, Fuller 1978). ``Wr_i`` is the Gauss writhe of the bead
  polygon (:func:`dnabraid.geometry.curves.writhe`); its gradient is local
  (:func:`writhe_gradient`): the polygon's writhe and the holonomy of discrete parallel
  transport around it add to a constant (Fuller's theorem for polygons), so ``dWr =
  -(1/2 pi) sum_i dm_i`` with ``m_i`` the reference twist of vertex ``i`` (Bergou et al.
  2008, Discrete elastic rods: ``dm_i/de_{i-1} = kb_i/(2|e_{i-1}|)``, ``dm_i/de_i =
  kb_i/(2|e_i|)``, ``kb_i = 2 t_{i-1} x t_i / (1 + t_{i-1}.t_i)``). The twisting moment of
  ring ``i`` is ``T_i = 2 pi C (Lk_i - Wr_i) / L``;
* ``chiral``: ``E_ch = alpha sum_{i in ring 1, j in ring 2} b^2 (t_i.t_j) w(rho_ij) h(zeta_ij)
  tan(eta_ij / 2)``, symmetrised over which bead's tangent is the axis (half each), where
  for bead tangents ``t_i, t_j`` and chord ``r = x_j - x_i``: ``zeta = r.t_i`` (the offset
  along the strand; the factor ``t_i.t_j`` below turns bead j's length ``b`` into its
  projection on ``t_i``, so that the sum over ``j`` integrates ``d zeta``),
  ``rho = |r - zeta t_i|`` (the distance across it), ``eta_ij =
  atan2((t_i x t_j).r/rho, t_i.t_j)`` (docs/chirality.md's braid angle; positive
  left-handed), ``h`` a normalised Gaussian (standard deviation ``a/4``) tapered to zero at
  ``|zeta| = a`` (:func:`axial_kernel`) (``sum_j b h -> 1``: the double sum is an integral
  per unit contact length) and the contact weight ``w(rho) = 1`` for ``rho <= Delta``,
  ``1 - S((rho - Delta)/delta)`` for
  ``Delta < rho < Delta + delta`` (``S`` the C^2 smootherstep ``6u^5 - 15u^4 + 10u^3``), 0
  beyond. ``tan(eta/2) = y / (sqrt(x^2 + y^2) + x)`` with ``x = t_i.t_j``, ``y = (t_i x
  t_j).r/rho``. The product ``x tan(eta/2)`` is folded for apolar DNA
  (docs/chirality.md, Eq. C3) as ``x y / (sqrt(x^2 + y^2) + |x|)``: the same for
  ``|eta| < pi/2`` (the seed's contact), even under ``t_j -> -t_j`` and bounded where two
  strands meet antiparallel (a writhed pair touching itself). Once contact partners are
  tracked (:func:`update_partners`) only pairs within :func:`chiral_window` beads of each
  other's partner count: the seed's term acts along the contact curve, and the far side of
  a self-touching ply carries only the hard contact.

Relaxation (:func:`relax`)
--------------------------
A Levenberg-damped Newton method with a trust radius on the largest bead displacement
(doubled when a clipped step descends, halved on every refused trial step, clipped or not,
with the damping raised tenfold; a step that changes Lk_12 or a writhe by more than 1/2,
i.e. passes a strand through another, is refused) on the dense Hessian (the twist couples
every bead of a ring through ``Wr_i``): the stretch/bend/hard-contact parts are the exact
sparse Hessians of :mod:`~dnabraid.statics.closed_braid` and
:mod:`~dnabraid.forces.segment_contact`; the chiral, bilateral and local writhe parts by central differences of their analytic gradients
over a distance-2 colouring of their sparsity (a few tens of gradient calls); the twist's
rank-one part ``(4 pi^2 C / L) grad Wr grad Wr^T`` exactly. Six coordinates pin the rigid
modes (:func:`~dnabraid.statics.closed_braid.pinned_dofs`). Stability (:func:`lowest_modes`):
the lowest eigenvalues of the exact Hessian with the six rigid modes and each ring's
bead-lattice sliding mode (all beads of a ring moved along their tangents: a zero mode of
the continuum) projected out. The bilateral contact holds each bead to its partner: the
closest point of the other ring, searched within :data:`PARTNER_WINDOW` beads of the
previous partner after every accepted step (globally only at the start), so that a pair
touching itself keeps its own contact. :func:`continuation` steps ``Lk_i`` or ``alpha``.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import DnabraidError, UserError
from ..forces import segment_contact as sc
from ..geometry.curves import gauss_linking_number, writhe
from . import closed_braid as cb

CONTACT_MODELS = ("bilateral", "hard")

#: C/B used for DNA: C ~ 75 nm (twist persistence, Moroz & Nelson, PNAS 94, 14418 (1997);
#: Bryant et al., Nature 424, 338 (2003) find 90-110 nm) over B ~ 50 nm (bending
#: persistence, Bustamante et al. 1994): 75/50 = 1.5.
DNA_TWIST_OVER_BEND = 1.5


class ChiralRingsError(DnabraidError, RuntimeError):
    """The rings could not be relaxed or measured (says where and why)."""


@dataclasses.dataclass(frozen=True)
class ChiralRings:
    """Two linked rings with twist and the chiral term (lengths in L, B = 1).

    Attributes
    ----------
    lk_ring : float
        ``Lk_i`` of each ring's material frame (both rings; slide 32: 5).
    alpha_B_per_L2 : float
        Chiral amplitude ``alpha`` (B/L^2); ``alpha > 0`` favours ``eta < 0``.
    twist_over_bend : float
        ``C/B`` (:data:`DNA_TWIST_OVER_BEND`).
    diameter_over_length : float
        ``Delta/L`` (slide 32: 0.02).
    n : int
        Ply turns of the link: 1 the Hopf link (``Lk_12 = -+1``), ``n`` the (2, 2n) torus link.
    handedness : str
        ``"left"`` (``Lk_12 = -n``, the seed's start) or ``"right"``.
    contact : str
        ``"bilateral"`` (every bead held at Delta from the other ring, plus the hard
        contact) or ``"hard"`` (one-sided only, as closed_braid).
    spacing_over_diameter : float
        Bead spacing ``b/Delta`` (<= 0.5).
    decay_over_diameter : float
        ``delta/Delta``, the range over which the chiral weight decays beyond contact.
    window_over_diameter : float
        ``a/Delta``, the half-width of the axial kernel ``h``.
    overlap_target : float
        Expected contact penalty overlap / Delta (sets the contact stiffness, as closed_braid).
    start_noise : float
        Start perturbation (x Delta), as closed_braid.
    seed : int
        Seed of the start perturbation.
    """

    lk_ring: float = 5.0
    alpha_B_per_L2: float = 0.0
    twist_over_bend: float = DNA_TWIST_OVER_BEND
    diameter_over_length: float = 0.02
    n: int = 1
    handedness: str = "left"
    contact: str = "bilateral"
    spacing_over_diameter: float = 0.5
    decay_over_diameter: float = 0.5
    window_over_diameter: float = 2.0
    overlap_target: float = 1e-4
    start_noise: float = 0.02
    seed: int = 1

    def __post_init__(self):
        if self.contact not in CONTACT_MODELS:
            raise UserError(f"contact={self.contact!r}: must be one of {CONTACT_MODELS}")
        for name in ("lk_ring", "alpha_B_per_L2", "twist_over_bend"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise UserError(f"{name}={v!r}: must be a finite number")
        if self.twist_over_bend < 0:
            raise UserError(f"twist_over_bend={self.twist_over_bend!r}: must be >= 0 (C/B)")
        for name in ("diameter_over_length", "spacing_over_diameter", "decay_over_diameter",
                     "window_over_diameter", "overlap_target"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise UserError(f"{name}={v!r}: must be a finite number > 0")
        if self.spacing_over_diameter > 0.5:
            raise UserError(f"spacing_over_diameter={self.spacing_over_diameter:g}: must be "
                            "<= 0.5 (b <= Delta/2, as closed_braid)")
        if self.window_over_diameter < 4 * self.spacing_over_diameter:
            raise UserError(f"window_over_diameter={self.window_over_diameter:g}: the axial "
                            "kernel needs a half-width of at least four bead spacings "
                            f"(>= {4 * self.spacing_over_diameter:g} Delta)")
        try:
            _ = self.braid
        except ValueError as exc:
            raise UserError(str(exc)) from exc

    @property
    def braid(self) -> cb.ClosedBraid:
        """The closed_braid link with the same geometry ("nm" = L, B = 1)."""
        return cb.ClosedBraid(
            topology="link", n=int(self.n), handedness=self.handedness,
            diameter_nm=self.diameter_over_length,
            diameter_over_length=self.diameter_over_length, bending_stiffness_pN_nm2=1.0,
            spacing_over_radius=2 * self.spacing_over_diameter, contact="segments",
            overlap_target=self.overlap_target, start_noise=self.start_noise, seed=self.seed)

    @property
    def twist_stiffness(self) -> float:
        """C in B (B = 1)."""
        return float(self.twist_over_bend)


# -- problem structure -------------------------------------------------------------------------

@dataclasses.dataclass
class Problem:
    """Index structure and constants of a :class:`ChiralRings` bead model (L = B = 1)."""

    model: ChiralRings
    braid: cb.ClosedBraid
    cbp: cb.Problem
    nxt: np.ndarray
    prv: np.ndarray
    ring_of: np.ndarray
    b: float
    delta: float
    k_contact: float
    #: per bead, its partner bead on the other ring (global index), tracked by continuity
    #: (:func:`update_partners`); None until assigned
    partner: np.ndarray | None = None

    @property
    def n_beads(self) -> int:
        return int(self.cbp.chains.n_beads)

    def ring(self, k) -> slice:
        return self.cbp.chains.ring(k)

    def along(self, idx, offset):
        """Global index of the bead ``offset`` beads along its ring from bead ``idx``."""
        idx = np.asarray(idx, int)
        start = np.where(self.ring_of[idx] == 0, self.ring(0).start, self.ring(1).start)
        size = np.where(self.ring_of[idx] == 0, self.ring(0).stop - self.ring(0).start,
                        self.ring(1).stop - self.ring(1).start)
        return start + (idx - start + np.asarray(offset, int)) % size

    def ring_distance(self, a, b):
        """Number of beads between beads ``a`` and ``b`` of one ring, the short way round."""
        a, b = np.asarray(a, int), np.asarray(b, int)
        size = np.where(self.ring_of[a] == 0, self.ring(0).stop - self.ring(0).start,
                        self.ring(1).stop - self.ring(1).start)
        d = (a - b) % size
        return np.minimum(d, size - d)


def make_problem(model: ChiralRings) -> Problem:
    br = model.braid
    cbp = cb.make_problem(br)
    ch = cbp.chains
    nxt = ch.bonds[:, 1].copy()
    prv = ch.hinges[:, 0].copy()
    k = br.contact_stiffness_pN_nm
    return Problem(model, br, cbp, nxt, prv, ch.ring_of.copy(), br.bead_spacing_nm,
                   br.diameter_nm, k)


def initial_geometry(model: ChiralRings) -> np.ndarray:
    """Start (N, 3) in L: closed_braid's uniform closed ply (n = 1: the Villarceau pair)."""
    return np.vstack(cb.initial_geometry(model.braid))


# -- writhe and twist --------------------------------------------------------------------------

def writhe_gradient(ring) -> np.ndarray:
    """Gradient (M, 3) (1/L) of the Gauss writhe of a closed polygon ``ring`` (M, 3).

    ``dWr = -(1/2 pi) sum_i dm_i`` (module docstring): local, exact for the polygon.
    """
    x = np.asarray(ring, float)
    e = np.roll(x, -1, 0) - x
    le = np.linalg.norm(e, axis=1)
    t = e / le[:, None]
    tp, lp = np.roll(t, 1, 0), np.roll(le, 1)
    den = 1.0 + np.sum(tp * t, axis=1)
    if np.any(den < 1e-8):
        raise ChiralRingsError("writhe_gradient: a vertex folds back on itself (turning "
                               "angle pi)")
    kb = 2.0 * np.cross(tp, t) / den[:, None]
    a = kb / (2.0 * lp[:, None])
    c = kb / (2.0 * le[:, None])
    g = a - c + np.roll(-a, -1, 0) + np.roll(c, 1, 0)
    return -g / (2.0 * math.pi)


def ring_writhes(x, prob: Problem) -> list:
    return [float(writhe(x[prob.ring(k)])) for k in range(2)]


def twist_energy(x, prob: Problem, wr=None) -> float:
    """sum_i 2 pi^2 C (Lk_i - Wr_i)^2 / L (B/L)."""
    wr = ring_writhes(x, prob) if wr is None else wr
    C, lk = prob.model.twist_stiffness, prob.model.lk_ring
    return float(sum(2 * math.pi**2 * C * (lk - w) ** 2 for w in wr))


def _writhe_grads(x, prob: Problem) -> np.ndarray:
    g = np.zeros_like(x)
    for k in range(2):
        sl = prob.ring(k)
        g[sl] = writhe_gradient(x[sl])
    return g


def twist_gradient(x, prob: Problem, wr=None) -> np.ndarray:
    """Gradient (N, 3) of :func:`twist_energy` (B/L^2)."""
    wr = ring_writhes(x, prob) if wr is None else wr
    C, lk = prob.model.twist_stiffness, prob.model.lk_ring
    gw = _writhe_grads(x, prob)
    for k in range(2):
        sl = prob.ring(k)
        gw[sl] *= -4 * math.pi**2 * C * (lk - wr[k])
    return gw


# -- chiral term -------------------------------------------------------------------------------

def _smootherstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u**3 * (10 - 15 * u + 6 * u * u), 30 * u * u * (1 - u) ** 2


def contact_weight(rho, delta: float, decay: float):
    """w(rho) and dw/drho: 1 for rho <= delta, C^2 smootherstep decay to 0 at delta + decay."""
    S, dS = _smootherstep((np.asarray(rho, float) - delta) / decay)
    return 1.0 - S, -dS / decay


_KERNEL_NORM = None


def _kernel_norm() -> float:
    global _KERNEL_NORM
    if _KERNEL_NORM is None:
        u = np.linspace(-1.0, 1.0, 200001)
        k = np.exp(-8.0 * u * u) * (1 - u * u) ** 4
        _KERNEL_NORM = float(1.0 / (np.sum(k) * (u[1] - u[0])))
    return _KERNEL_NORM


def axial_kernel(zeta, a: float):
    """h(zeta) (1/L) and h'(zeta): a Gaussian of standard deviation a/4 tapered to zero at
    |zeta| = a by (1 - (zeta/a)^2)^4 (C^3), normalised to integral 1.

    Sampled at a spacing b <= a/4 its sum b sum_j h(zeta_j) is 1 within ~1e-4 whatever the
    offset (the Gaussian's Fourier transform at 2 pi/b is exp(-2 pi^2 (a/4b)^2)).
    """
    u = np.asarray(zeta, float) / a
    inside = np.abs(u) < 1
    q = np.where(inside, 1 - u * u, 0.0)
    g = np.exp(-8.0 * u * u)
    c = _kernel_norm() / a
    h = c * g * q**4
    dh = c * g * (-16.0 * u * q**4 - 8.0 * u * q**3) / a
    return np.where(inside, h, 0.0), np.where(inside, dh, 0.0)


def bead_tangents(x, prob: Problem):
    """Unit bead tangents (N, 3), ``(x_{i+1} - x_{i-1})`` normalised, and the norms (L)."""
    v = x[prob.nxt] - x[prob.prv]
    nv = np.linalg.norm(v, axis=1)
    return v / nv[:, None], nv


def chiral_cutoff(prob: Problem) -> float:
    m = prob.model
    a = m.window_over_diameter * prob.delta
    return math.hypot(a, prob.delta * (1 + m.decay_over_diameter))


def chiral_pairs(x, prob: Problem, margin: float = 0.0) -> np.ndarray:
    """Bead pairs (P, 2), ring 0 bead then ring 1 bead, closer than the chiral cutoff."""
    s0, s1 = prob.ring(0), prob.ring(1)
    t0, t1 = cKDTree(x[s0]), cKDTree(x[s1])
    lists = t0.query_ball_tree(t1, chiral_cutoff(prob) + margin)
    i = np.repeat(np.arange(len(lists)), [len(q) for q in lists])
    j = np.concatenate([np.asarray(q, int) for q in lists]) if len(i) else np.zeros(0, int)
    pairs = np.column_stack([i + s0.start, j + s1.start]).astype(int).reshape(-1, 2)
    if prob.partner is not None and len(pairs):
        # the seed's term acts along the contact curve: keep pairs near each other's partner
        w = chiral_window(prob)
        i, j = pairs[:, 0], pairs[:, 1]
        keep = ((prob.ring_distance(j, prob.partner[i]) <= w)
                | (prob.ring_distance(i, prob.partner[j]) <= w))
        pairs = pairs[keep]
    return pairs


def chiral_window(prob: Problem) -> int:
    """Half-width (beads) about a bead's partner within which pairs carry the chiral term
    once partners are tracked: the cutoff in beads plus two."""
    return int(math.ceil(chiral_cutoff(prob) / prob.b)) + 2


def _chiral_directed(x, T, nv, i, j, prob: Problem, alpha: float, want_grad: bool):
    """Half the chiral energy of the pairs (i, j) with bead i's tangent as the axis."""
    m = prob.model
    D = prob.delta
    a = m.window_over_diameter * D
    r = x[j] - x[i]
    Ti, Tj = T[i], T[j]
    zeta = np.sum(r * Ti, axis=1)
    rho2 = np.sum(r * r, axis=1) - zeta * zeta
    rho = np.sqrt(np.maximum(rho2, 1e-300))
    cr = np.cross(Ti, Tj)
    Y = np.sum(cr * r, axis=1)
    y = Y / rho
    xx = np.sum(Ti * Tj, axis=1)
    s = np.sqrt(xx * xx + y * y)
    if np.any(s < 1e-12):
        raise ChiralRingsError("chiral term: a pair's tangents are both along the chord "
                               "(no braid angle is defined)")
    ax = np.abs(xx)
    sx = s + ax
    # tan(eta/2) x the projected length factor x = t_i.t_j, eta = atan2(y, x), folded for
    # apolar DNA (docs/chirality.md, Eq. C3): x y / (s + |x|) equals x tan(eta/2) for
    # |eta| < pi/2, is even under t_j -> -t_j, bounded (|tau| < 0.31 s) and C1 through x = 0
    tau = y / sx * xx
    W, dW = contact_weight(rho, D, m.decay_over_diameter * D)
    H, dH = axial_kernel(zeta, a)
    c = 0.5 * alpha * prob.b * prob.b
    E = float(np.sum(c * W * H * tau))
    if not want_grad:
        return E, None
    f_tau = c * W * H
    dtau_dy = xx * ax / (s * sx)
    dtau_dx = y / sx - y * ax / (s * sx)
    g_rho = c * dW * H * tau + f_tau * dtau_dy * (-Y / (rho * rho))
    g_Y = f_tau * dtau_dy / rho
    g_x = f_tau * dtau_dx
    g_zeta = c * W * dH * tau
    rperp = r - zeta[:, None] * Ti
    d_r = (g_zeta[:, None] * Ti + (g_rho / rho)[:, None] * rperp + g_Y[:, None] * cr)
    d_Ti = (g_zeta[:, None] * r - (g_rho * zeta / rho)[:, None] * r
            + g_Y[:, None] * np.cross(Tj, r) + g_x[:, None] * Tj)
    d_Tj = g_Y[:, None] * np.cross(r, Ti) + g_x[:, None] * Ti
    N = len(x)
    g = np.zeros((N, 3))
    np.add.at(g, j, d_r)
    np.add.at(g, i, -d_r)
    for idx, dT in ((i, d_Ti), (j, d_Tj)):
        Tk = T[idx]
        dv = (dT - np.sum(dT * Tk, axis=1)[:, None] * Tk) / nv[idx][:, None]
        np.add.at(g, prob.nxt[idx], dv)
        np.add.at(g, prob.prv[idx], -dv)
    return E, g


def chiral_energy_gradient(x, prob: Problem, pairs=None, *, alpha=None, want_grad=True):
    """Chiral energy (B/L) and its gradient (N, 3) (B/L^2), or (E, None).

    ``pairs`` from :func:`chiral_pairs` (default: found at ``x``); ``alpha`` (B/L^2)
    defaults to the model's.
    """
    alpha = prob.model.alpha_B_per_L2 if alpha is None else float(alpha)
    x = np.asarray(x, float)
    if pairs is None:
        pairs = chiral_pairs(x, prob)
    if len(pairs) == 0 or alpha == 0.0:
        return 0.0, (np.zeros_like(x) if want_grad else None)
    T, nv = bead_tangents(x, prob)
    E1, g1 = _chiral_directed(x, T, nv, pairs[:, 0], pairs[:, 1], prob, alpha, want_grad)
    E2, g2 = _chiral_directed(x, T, nv, pairs[:, 1], pairs[:, 0], prob, alpha, want_grad)
    return E1 + E2, (g1 + g2 if want_grad else None)


# -- bilateral contact -------------------------------------------------------------------------

#: Half-width (beads) of the window about a bead's partner on the other ring in which the
#: bilateral contact looks for the closest point, once partners are tracked
#: (:func:`update_partners`). A writhed pair touches itself: near a bead lie two stretches of
#: the other ring (its partner, and the far side of the ply), both at about Delta; a global
#: search would jump between them.
PARTNER_WINDOW = 4


def bilateral_candidates(x, prob: Problem, k_max: int = 24) -> np.ndarray:
    """For every bead, up to ``k_max`` segment starts of the other ring near it ((N, k), -1 pad).

    With partners tracked (``prob.partner``): the ``2 PARTNER_WINDOW + 1`` segments about the
    partner. Otherwise the segments ``(s, nxt[s])`` whose start or end bead lies within
    ``1.5 Delta + 2 b``.
    """
    if prob.partner is not None:
        off = np.arange(-PARTNER_WINDOW, PARTNER_WINDOW + 1)
        return prob.along(prob.partner[:, None], off[None, :])
    N = prob.n_beads
    out = np.full((N, k_max), -1, int)
    used = 1
    rad = 1.5 * prob.delta + 2 * prob.b
    for k in range(2):
        me, other = prob.ring(k), prob.ring(1 - k)
        tree = cKDTree(x[other])
        lists = tree.query_ball_point(x[me], rad)
        for q, js in enumerate(lists):
            js = np.asarray(js, int) + other.start
            if not len(js):
                continue
            st = np.unique(np.concatenate([js, prob.prv[js]]))
            if len(st) > k_max:
                d = np.linalg.norm(x[st] - x[me.start + q], axis=1)
                st = st[np.argsort(d)[:k_max]]
            out[me.start + q, :len(st)] = st
            used = max(used, len(st))
    return out[:, :used]


def _cr_basis(u):
    """Uniform Catmull-Rom basis (k = -1, 0, 1, 2) and its first two derivatives in u."""
    u2, u3 = u * u, u * u * u
    B = 0.5 * np.stack([-u + 2 * u2 - u3, 2 - 5 * u2 + 3 * u3, u + 4 * u2 - 3 * u3,
                        -u2 + u3], axis=-1)
    dB = 0.5 * np.stack([-1 + 4 * u - 3 * u2, -10 * u + 9 * u2, 1 + 8 * u - 9 * u2,
                         -2 * u + 3 * u2], axis=-1)
    ddB = 0.5 * np.stack([4 - 6 * u, -10 + 18 * u, 8 - 18 * u, -2 + 6 * u], axis=-1)
    return B, dB, ddB


def _spline_points(x, prob: Problem, seg):
    """Control beads (..., 4) of the Catmull-Rom piece over segment (seg, nxt[seg])."""
    return np.stack([prob.prv[seg], seg, prob.nxt[seg], prob.nxt[prob.nxt[seg]]], axis=-1)


def closest_on_other_ring(x, prob: Problem, cand, newton_steps: int = 5):
    """Closest point of the other ring's Catmull-Rom curve (through its beads) to each bead.

    The polyline's sagitta (``b^2 kappa / 8``) would make a bead-to-polyline distance
    corrugate with the beads' register; the C^1 spline removes it to ``O(b^4 kappa^3)``.
    Returns (seg start (N,), u (N,), q (N, 3), d (N,), tangent (N, 3) unit); beads without
    candidates get seg = -1, d = inf.
    """
    N = len(x)
    valid = cand >= 0
    c = np.where(valid, cand, 0)
    a = x[c]
    bb = x[prob.nxt[c]]
    ab = bb - a
    u = np.clip(np.sum((x[:, None, :] - a) * ab, axis=2) / np.sum(ab * ab, axis=2), 0.0, 1.0)
    P = x[_spline_points(x, prob, c)]                      # (N, K, 4, 3)
    for _ in range(newton_steps):
        B, dB, ddB = _cr_basis(u)
        q = np.einsum("nkj,nkjc->nkc", B, P)
        q1 = np.einsum("nkj,nkjc->nkc", dB, P)
        q2 = np.einsum("nkj,nkjc->nkc", ddB, P)
        r = q - x[:, None, :]
        f1 = np.sum(r * q1, axis=2)
        f2 = np.sum(q1 * q1, axis=2) + np.sum(r * q2, axis=2)
        u = np.clip(u - f1 / np.where(f2 > 0, f2, np.sum(q1 * q1, axis=2)), 0.0, 1.0)
    B, dB, _ = _cr_basis(u)
    q = np.einsum("nkj,nkjc->nkc", B, P)
    d = np.linalg.norm(x[:, None, :] - q, axis=2)
    d = np.where(valid, d, np.inf)
    m = np.argmin(d, axis=1)
    rr = np.arange(N)
    seg = np.where(valid[rr, m], c[rr, m], -1)
    tq = np.einsum("nj,njc->nc", dB[rr, m], P[rr, m])
    tq /= np.linalg.norm(tq, axis=1)[:, None]
    return seg, u[rr, m], q[rr, m], d[rr, m], tq


#: Re-centred windowed searches :func:`update_partners` makes before it gives up on a partner
#: that keeps landing on its window's edge.
PARTNER_RECENTRES = 8


def fold_eta(eta):
    """The apolar braid angle: ``eta`` (rad) folded into (-pi/2, pi/2] (eta and eta +- pi
    describe one crossing of two apolar strands; the chiral term folds them alike)."""
    eta = np.asarray(eta, float)
    return np.pi / 2 - np.mod(np.pi / 2 - eta, np.pi)


def mirror_image(x, partner, prob):
    """The mirror image (z -> -z) of a state with ring 2 reversed, and its partners mapped
    bead by bead. Mirroring flips every writhe, twist and Lk_i and the link's hand;
    reversing ring 2 (DNA is apolar: no energy changes) flips the Gauss Lk_12 back to the
    solver's -1, so the image is a state of the same solver at -Lk_i with the opposite
    hand, equal in energy at alpha = 0 (partners mapped, not searched again: the bilateral
    energy depends on the assignment)."""
    sl = prob.ring(1)
    idx = np.arange(prob.n_beads)
    rev = idx.copy()
    rev[sl] = idx[sl][::-1]            # bead j of ring 2 -> its index after reversal
    y = np.asarray(x, float) * np.array([1.0, 1.0, -1.0])
    y = y[rev]
    partner = np.asarray(partner, int)
    new = np.empty_like(partner)
    new[rev] = rev[partner]            # both the bead and its partner renumbered
    return y, new


def update_partners(x, prob: Problem) -> np.ndarray:
    """Set ``prob.partner`` to each bead's closest bead of the other ring: found globally
    the first time, within :data:`PARTNER_WINDOW` of the previous partner afterwards.

    A closest point on the window's first or last end point may lie beyond it (a step that
    slid the rings by more than the window): the window is re-centred there and searched
    again, up to :data:`PARTNER_RECENTRES` times; a partner still on the edge after that is
    an error, never a silently clamped contact."""
    windowed = prob.partner is not None
    for _ in range(PARTNER_RECENTRES + 1):
        cand = bilateral_candidates(x, prob)
        seg, u, _, _, _ = closest_on_other_ring(x, prob, cand)
        if np.any(seg < 0):
            raise ChiralRingsError(f"partners: {int(np.sum(seg < 0))} beads have no point of "
                                   "the other ring within 1.5 Delta (contact lost)")
        prob.partner = np.where(u < 0.5, seg, prob.nxt[seg]).astype(int)
        if not windowed:
            return prob.partner
        edge = ((seg == cand[:, 0]) & (u <= 1e-12)) | ((seg == cand[:, -1]) & (u >= 1 - 1e-12))
        if not np.any(edge):
            return prob.partner
    raise ChiralRingsError(f"partners: {int(np.sum(edge))} beads' closest points stay on the "
                           f"edge of their {2 * PARTNER_WINDOW + 1}-segment window after "
                           f"{PARTNER_RECENTRES} re-centred searches")


def bilateral_energy_gradient(x, prob: Problem, cand=None, want_grad=True):
    """``(k/2) sum_i (d_i - Delta)^2`` (B/L) and its gradient (N, 3), or (E, None)."""
    x = np.asarray(x, float)
    cand = bilateral_candidates(x, prob) if cand is None else cand
    seg, u, q, d, _ = closest_on_other_ring(x, prob, cand)
    if np.any(seg < 0):
        raise ChiralRingsError(f"bilateral contact: {int(np.sum(seg < 0))} beads have no "
                               "point of the other ring within 1.5 Delta (contact lost)")
    k = prob.k_contact
    gap = d - prob.delta
    E = 0.5 * k * float(np.sum(gap * gap))
    if not want_grad:
        return E, None
    n = (x - q) / d[:, None]
    f = (k * gap)[:, None] * n
    g = f.copy()
    B, _, _ = _cr_basis(u)
    ctrl = _spline_points(x, prob, seg)
    for k in range(4):
        np.add.at(g, ctrl[:, k], -B[:, k][:, None] * f)
    return E, g


# -- total energy ------------------------------------------------------------------------------

#: In the bilateral model the one-sided contact between the two rings acts at
#: ``(1 - HARD_SLACK) Delta``: it only stops strands passing through each other away from the
#: held partner (a polyline's segment-segment distance is a little below its bead-to-segment
#: distance, and the two penalties would otherwise fight at the partner).
HARD_SLACK = 0.02


def _hard_groups(x, prob: Problem) -> list:
    """[(segment pairs, contact distance)]: same-ring pairs at Delta, other-ring pairs at
    Delta (hard model) or (1 - HARD_SLACK) Delta (bilateral model)."""
    p = cb.segment_pairs(x, prob.cbp)
    if not len(p):
        return []
    seg = prob.cbp.segments
    same = prob.ring_of[seg[p[:, 0], 0]] == prob.ring_of[seg[p[:, 1], 0]]
    d_other = prob.delta * (1 - HARD_SLACK if prob.model.contact == "bilateral" else 1.0)
    return [(p[same], prob.delta), (p[~same], d_other)]


def hard_energy(x, prob: Problem) -> float:
    """One-sided capsule contact energy (B/L)."""
    return float(sum(sc.contact_energy(x, prob.cbp.segments, p, D, prob.k_contact)
                     for p, D in _hard_groups(x, prob) if len(p)))


def _hard_gradient_hessian(x, prob: Problem, gauss_newton: bool):
    N = len(x)
    g = np.zeros(3 * N)
    H = sp.csr_matrix((3 * N, 3 * N))
    for p, D in _hard_groups(x, prob):
        if len(p):
            gc, Hc = sc.contact_gradient_hessian(x, prob.cbp.segments, p, D, prob.k_contact,
                                                 gauss_newton=gauss_newton)
            g += np.asarray(gc).ravel()
            H = H + sp.csr_matrix(Hc)
    return g, H


def energy_terms(x, prob: Problem) -> dict:
    """Energy of each term (B/L) at ``x`` (N, 3) (L)."""
    x = np.asarray(x, float)
    t = cb.energy_terms(x, prob.cbp)
    out = {"stretch": t["stretch"], "bend": t["bend"], "hard": hard_energy(x, prob)}
    out["bilateral"] = (bilateral_energy_gradient(x, prob, want_grad=False)[0]
                        if prob.model.contact == "bilateral" else 0.0)
    out["twist"] = twist_energy(x, prob)
    out["chiral"] = chiral_energy_gradient(x, prob, want_grad=False)[0]
    return out


def energy(x, prob: Problem) -> float:
    """Total energy (B/L)."""
    return float(sum(energy_terms(x, prob).values()))


class _Lists:
    """Neighbour lists frozen for one Newton iteration (with a margin)."""

    def __init__(self, x, prob: Problem):
        self.chiral = chiral_pairs(x, prob, margin=0.5 * prob.delta)
        self.cand = None
        if prob.model.contact == "bilateral":
            seg = closest_on_other_ring(x, prob, bilateral_candidates(x, prob))[0]
            if np.any(seg < 0):
                raise ChiralRingsError(f"bilateral contact: {int(np.sum(seg < 0))} beads have "
                                       "no point of the other ring within 1.5 Delta")
            # the closest piece and its two neighbours (enough for small displacements)
            self.cand = np.column_stack([prob.prv[seg], seg, prob.nxt[seg]])
            self.seg = seg


def _soft_gradient(x, prob: Problem, lists: _Lists, wr_coef) -> np.ndarray:
    """Chiral + bilateral gradient + the writhe gradient with frozen coefficients."""
    g = chiral_energy_gradient(x, prob, lists.chiral)[1]
    if lists.cand is not None:
        g = g + bilateral_energy_gradient(x, prob, lists.cand)[1]
    gw = _writhe_grads(x, prob)
    for k in range(2):
        sl = prob.ring(k)
        g[sl] += wr_coef[k] * gw[sl]
    return g


def gradient(x, prob: Problem, lists: _Lists | None = None) -> np.ndarray:
    """Gradient (3N,) of :func:`energy` (B/L^2)."""
    x = np.asarray(x, float)
    lists = _Lists(x, prob) if lists is None else lists
    g_cb, _ = cb.gradient_hessian(x, prob.cbp, gauss_newton=True, terms=("stretch", "bend"))
    g_cb = g_cb + _hard_gradient_hessian(x, prob, True)[0]
    wr = ring_writhes(x, prob)
    C, lk = prob.model.twist_stiffness, prob.model.lk_ring
    coef = [-4 * math.pi**2 * C * (lk - w) for w in wr]
    return g_cb + _soft_gradient(x, prob, lists, coef).ravel()


def _colouring(x, prob: Problem, lists: _Lists) -> np.ndarray:
    """Distance-2 colouring of the beads for the soft terms' Jacobian (colour per bead)."""
    N = prob.n_beads
    rows, cols = [], []

    def clique(groups):
        g = np.column_stack(groups)
        for p in range(g.shape[1]):
            for q in range(g.shape[1]):
                rows.append(g[:, p])
                cols.append(g[:, q])

    i = np.arange(N)
    clique([prob.prv[prob.prv[i]], prob.prv[i], i, prob.nxt[i], prob.nxt[prob.nxt[i]]])
    if len(lists.chiral) and prob.model.alpha_B_per_L2 != 0.0:
        a, b = lists.chiral[:, 0], lists.chiral[:, 1]
        clique([prob.prv[a], a, prob.nxt[a], prob.prv[b], b, prob.nxt[b]])
    if lists.cand is not None:
        # the current closest piece's four control beads (a step of 1e-6 Delta does not
        # move a bead's closest point onto another piece but at measure-zero places)
        s = lists.seg
        clique([i, prob.prv[s], s, prob.nxt[s], prob.nxt[prob.nxt[s]]])
    A = sp.csr_matrix((np.ones(sum(len(r) for r in rows)), (np.concatenate(rows),
                                                            np.concatenate(cols))),
                      shape=(N, N))
    A.data[:] = 1.0
    A2 = (A @ A).tocsr()
    colour = np.full(N, -1)
    for v in range(N):
        used = set(colour[A2.indices[A2.indptr[v]:A2.indptr[v + 1]]].tolist())
        c = 0
        while c in used:
            c += 1
        colour[v] = c
    return colour, A


def hessian(x, prob: Problem, lists: _Lists | None = None, *, fd_step: float | None = None
            ) -> np.ndarray:
    """Dense Hessian (3N, 3N) of :func:`energy` (B/L^3): exact sparse parts, coloured
    central differences of the soft gradients, the twist's exact rank-one part."""
    x = np.asarray(x, float)
    N = len(x)
    lists = _Lists(x, prob) if lists is None else lists
    _, Hs = cb.gradient_hessian(x, prob.cbp, gauss_newton=False, terms=("stretch", "bend"))
    H = (Hs + _hard_gradient_hessian(x, prob, False)[1]).toarray()
    wr = ring_writhes(x, prob)
    C, lk = prob.model.twist_stiffness, prob.model.lk_ring
    coef = [-4 * math.pi**2 * C * (lk - w) for w in wr]
    colour, A = _colouring(x, prob, lists)
    h = 1e-6 * prob.delta if fd_step is None else fd_step
    J = np.zeros((3 * N, 3 * N))
    Acoo = A.tocsc()
    for c in range(int(colour.max()) + 1):
        beads = np.flatnonzero(colour == c)
        for k in range(3):
            xp = x.copy()
            xm = x.copy()
            xp[beads, k] += h
            xm[beads, k] -= h
            dg = (_soft_gradient(xp, prob, lists, coef)
                  - _soft_gradient(xm, prob, lists, coef)).reshape(N, 3) / (2 * h)
            for p in beads:
                rws = Acoo.indices[Acoo.indptr[p]:Acoo.indptr[p + 1]]
                J[(3 * rws[:, None] + np.arange(3)).ravel(), 3 * p + k] = dg[rws].ravel()
    H += 0.5 * (J + J.T)
    gw = _writhe_grads(x, prob)
    for kk in range(2):
        v = np.zeros((N, 3))
        sl = prob.ring(kk)
        v[sl] = gw[sl]
        v = v.ravel()
        H += 4 * math.pi**2 * C * np.outer(v, v)
    return H


# -- relaxation and stability ------------------------------------------------------------------

def default_gtol(prob: Problem) -> float:
    """:func:`relax`'s gradient target (B/L^2): 1e-6 x the contact force per bead of
    closed_braid's pressure scale."""
    br = prob.braid
    return 1e-6 * br.pressure_scale_pN_per_nm * br.bead_spacing_nm


def relax(model: ChiralRings, x0, *, gtol: float | None = None, max_iter: int = 200,
          progress=None, prob: Problem | None = None) -> dict:
    """Levenberg-damped Newton minimisation of the energy from ``x0`` ((N, 3), L).

    Stops when the largest gradient component on the free coordinates is below ``gtol``
    (B/L^2; default 1e-6 x the contact force per bead of closed_braid's pressure scale),
    or when the energy stalls (10 steps in a row that no damping makes descend) with the
    gradient below ``100 gtol``. ``progress(iteration, max_gradient)`` is called each step.
    Returns dict(x, energy, iterations, max_gradient, converged, wall_time_s).
    """
    t0 = time.perf_counter()
    prob = make_problem(model) if prob is None else prob
    x = np.array(x0, float)
    N = len(x)
    if x.shape != (prob.n_beads, 3):
        raise UserError(f"x0 has shape {x.shape}, expected ({prob.n_beads}, 3)")
    gtol = default_gtol(prob) if gtol is None else float(gtol)
    pinned = cb.pinned_dofs(x)
    free = np.setdiff1d(np.arange(3 * N), pinned)
    # trust radius on the largest bead displacement: doubles when a clipped step descends
    # (a buckled ring travels many Delta to its writhed branch), halves on every refused
    # trial (clipped or not; 12 clipped successes bring it back from its floor)
    max_step = 0.25 * prob.delta
    step_range = (1e-3 * prob.delta, MAX_STEP_OVER_DIAMETER * prob.delta)
    slide_stiffness = SLIDE_STIFFNESS
    mu = 1e-3
    track = prob.model.contact == "bilateral"
    if track:
        update_partners(x, prob)
    E = energy(x, prob)
    topo = _topology(x, prob)
    it = 0
    stalls = 0
    converged = False
    gmax = np.inf
    for it in range(1, max_iter + 1):
        lists = _Lists(x, prob)
        g = gradient(x, prob, lists)
        gmax = float(np.max(np.abs(g[free])))
        if progress is not None:
            progress(it, gmax)
        if gmax < gtol:
            converged = True
            break
        H = hessian(x, prob, lists)
        # each ring's bead-lattice sliding (all beads along their tangents) is a near-zero
        # mode of a smooth ring: stiffen it in the step (not in the energy) so that steps do
        # not wander. Not where the sliding has a curvature of its own (a writhed,
        # self-touching ring: the added stiffness would then keep the sliding force from
        # relaxing, and Newton would converge linearly)
        T, _ = bead_tangents(x, prob)
        for kk in range(2):
            v = np.zeros((N, 3))
            v[prob.ring(kk)] = T[prob.ring(kk)]
            v = v.ravel() / math.sqrt(prob.ring(kk).stop - prob.ring(kk).start)
            if float(v @ H @ v) < SLIDE_CURVATURE:
                H += slide_stiffness * np.outer(v, v)
        H = H[np.ix_(free, free)]
        gf = g[free]
        accepted = False
        for _ in range(30):
            try:
                cf = sla.cho_factor(H + mu * np.eye(len(free)), check_finite=False)
            except (np.linalg.LinAlgError, sla.LinAlgError):
                mu = max(mu * 10, 1e-6)
                continue
            p = -sla.cho_solve(cf, gf, check_finite=False)
            pm = np.max(np.abs(p))
            clipped = pm > max_step
            if clipped:
                p *= max_step / pm
            xn = x.copy().ravel()
            xn[free] += p
            xn = xn.reshape(N, 3)
            try:
                En = energy(xn, prob)
                # a step must not pass a strand through another (the contact penalties are
                # finite): the link and each ring's writhe change continuously otherwise
                tn = _topology(xn, prob)
                if np.max(np.abs(tn - topo)) > 0.5:
                    En = np.inf
            except ChiralRingsError:
                En = np.inf
            if np.isfinite(En) and En < E:
                x, E, topo = xn, En, tn
                mu = max(mu / 3, 1e-10)
                accepted = True
                if clipped:
                    max_step = min(2 * max_step, step_range[1])
                if track:
                    update_partners(x, prob)
                    E = energy(x, prob)
                break
            mu *= 10
            max_step = max(0.5 * max_step, step_range[0])
        if not accepted:
            stalls += 1
            mu = 1e-3
            if stalls >= 10 or gmax < 100 * gtol:
                converged = gmax < 100 * gtol
                break
        else:
            stalls = 0
    if not np.all(np.isfinite(x)):
        raise ChiralRingsError("relaxation produced non-finite positions")
    return {"x": x, "energy_B_per_L": E, "iterations": it, "max_gradient_B_per_L2": gmax,
            "converged": bool(converged), "gtol_B_per_L2": gtol,
            "wall_time_s": time.perf_counter() - t0}


#: Stiffness (B/L^3) added along a ring's sliding mode in :func:`relax`'s step when the
#: energy's own curvature along it is below :data:`SLIDE_CURVATURE` (B/L^3).
SLIDE_STIFFNESS = 100.0
SLIDE_CURVATURE = 1.0

#: Largest trust radius of :func:`relax` (x Delta).
MAX_STEP_OVER_DIAMETER = 4.0


def _topology(x, prob: Problem) -> np.ndarray:
    """(Lk_12, Wr_1, Wr_2): a strand passage changes Lk_12 by 1 (between the rings) or a
    ring's writhe by 2 (within it)."""
    return np.array([gauss_linking_number(x[prob.ring(0)], x[prob.ring(1)]),
                     *ring_writhes(x, prob)])


def lowest_modes(x, prob: Problem, k: int = 3, H=None):
    """Lowest ``k`` eigenvalues (B/L^3) and vectors of the Hessian, with the rigid modes and
    each ring's bead-lattice sliding mode projected out (given a large eigenvalue)."""
    x = np.asarray(x, float)
    N = len(x)
    H = hessian(x, prob) if H is None else H
    V = [cb.rigid_modes(x)]
    T, _ = bead_tangents(x, prob)
    for kk in range(2):
        v = np.zeros((N, 3))
        sl = prob.ring(kk)
        v[sl] = T[sl]
        V.append(v.reshape(-1, 1))
    Q, _ = np.linalg.qr(np.hstack(V))
    HQ = H @ Q
    big = 10.0 * float(np.max(np.abs(np.diag(H))))
    Hp = H - HQ @ Q.T - Q @ HQ.T + Q @ (Q.T @ HQ) @ Q.T + big * (Q @ Q.T)
    Hp = 0.5 * (Hp + Hp.T)
    w, v = sla.eigh(Hp, subset_by_index=[0, k - 1])
    return w, v


# -- measurement -------------------------------------------------------------------------------

def measure(x, prob: Problem) -> dict:
    """Topology, twist, torque and the contact's braid angle of relaxed rings.

    Per bead of ring 1 (``eta`` rad, ``gap_over_diameter``) at its closest point on ring 2
    (the partner's tangent interpolated between its segment's bead tangents). Scalars:
    ``writhe_per_ring``, ``twist_per_ring`` (``Lk_i - Wr_i``, turns), ``torque_per_ring_B_per_L``
    (``T_i = 2 pi C Tw_i / L``), ``linking_number`` (Gauss), eta mean/min/max and the
    contact-length mean of ``tan(eta/2)``, the bilateral force's sign (``pulling_fraction``:
    beads held at ``d > Delta``, where a one-sided contact would open), energy terms.
    """
    x = np.asarray(x, float)
    m = prob.model
    wr = ring_writhes(x, prob)
    tw = [m.lk_ring - w for w in wr]
    C = m.twist_stiffness
    T, _ = bead_tangents(x, prob)
    cand = bilateral_candidates(x, prob)
    seg, u, q, d, tq = closest_on_other_ring(x, prob, cand)
    sl = prob.ring(0)
    seg0, q0, d0, t2 = seg[sl], q[sl], d[sl], tq[sl]
    ok = seg0 >= 0
    dv = np.where(ok[:, None], (q0 - x[sl]) / np.where(ok, d0, 1.0)[:, None], 0.0)
    t1 = T[sl]
    eta = np.arctan2(np.sum(np.cross(t1, t2) * dv, axis=1), np.sum(t1 * t2, axis=1))
    eta = np.where(ok, eta, np.nan)
    D = prob.delta
    in_contact = ok & (d0 < D * (1 + 0.05))
    terms = energy_terms(x, prob)
    out = {
        "writhe_per_ring": wr, "twist_per_ring": tw,
        "torque_per_ring_B_per_L": [2 * math.pi * C * t for t in tw],
        "linking_number": float(gauss_linking_number(x[prob.ring(0)], x[prob.ring(1)])),
        "eta": eta, "gap_over_diameter": d0 / D - 1.0,
        "contact_fraction": float(np.mean(in_contact)),
        "eta_mean_rad": float(np.nanmean(np.where(in_contact, eta, np.nan)))
        if np.any(in_contact) else float("nan"),
        "eta_min_rad": float(np.nanmin(eta)), "eta_max_rad": float(np.nanmax(eta)),
        # the apolar braid angle (eta and eta +- pi are one crossing of apolar strands, as
        # the chiral term folds them): in (-pi/2, pi/2], unchanged by reversing a ring
        "eta_folded_mean_rad": float(np.nanmean(np.where(in_contact, fold_eta(eta), np.nan)))
        if np.any(in_contact) else float("nan"),
        "tan_half_eta_contact_integral_L": float(np.sum(np.where(in_contact, np.tan(eta / 2), 0.0))
                                                 * prob.b),
        "energy_terms_B_per_L": {k: float(v) for k, v in terms.items()},
        "energy_B_per_L": float(sum(terms.values())),
        "pulling_fraction": float(np.mean(d0 > D)) if m.contact == "bilateral" else None,
        "max_overlap_over_diameter": float(max(0.0, np.max(D - d))) / D,
    }
    return out


def solve(model: ChiralRings, x0=None, *, progress=None, stability: bool = True,
          max_iter: int = 200, max_escapes: int = 3, escape_over_diameter: float = 0.5,
          partner=None) -> dict:
    """Relax from ``x0`` (default :func:`initial_geometry`), measure, and (``stability``)
    the lowest projected Hessian eigenvalues (B/L^3); a saddle is escaped along its negative
    mode (largest bead displacement ``escape_over_diameter`` x Delta, both signs tried, the
    lower energy kept), at most ``max_escapes`` times. ``partner``: the contact partners of
    ``x0`` (a previous result's ``"partner"``; default: found globally at ``x0``), carried
    along a continuation so that a self-touching pair keeps its own contact."""
    prob = make_problem(model)
    if partner is not None:
        partner = np.asarray(partner, int)
        if partner.shape != (prob.n_beads,):
            raise UserError(f"partner has shape {partner.shape}, expected ({prob.n_beads},)")
        prob.partner = partner.copy()
    x0 = initial_geometry(model) if x0 is None else np.asarray(x0, float)
    res = relax(model, x0, progress=progress, prob=prob, max_iter=max_iter)
    escapes = 0
    w = v = None
    if stability:
        w, v = lowest_modes(res["x"], prob)
        # a saddle (e.g. the twisted circles past Michell's threshold, an equilibrium for
        # every Lk_i) is left along its negative mode, both ways, keeping the lower
        while w[0] < -1e-6 * prob.braid.pressure_scale_pN_per_nm and escapes < max_escapes:
            escapes += 1
            mode = v[:, 0].reshape(-1, 3)
            mode = mode * (escape_over_diameter * prob.delta / np.max(np.abs(mode)))
            best = None
            start_partner = None if prob.partner is None else prob.partner.copy()
            for sgn in (1.0, -1.0):
                prob.partner = None if start_partner is None else start_partner.copy()
                r = relax(model, res["x"] + sgn * mode, prob=prob, max_iter=max_iter,
                          progress=progress)
                r["partner"] = None if prob.partner is None else prob.partner.copy()
                if best is None or r["energy_B_per_L"] < best["energy_B_per_L"]:
                    best = r
            res = best
            prob.partner = res["partner"]
            w, v = lowest_modes(res["x"], prob)
    out = {**res, **measure(res["x"], prob), "saddle_escapes": escapes,
           "partner": None if prob.partner is None else prob.partner.copy()}
    if stability:
        out["lowest_eigenvalues_B_per_L3"] = [float(t) for t in w]
        out["lowest_mode"] = v[:, 0]
    return out


# -- continuation ------------------------------------------------------------------------------

#: A step whose ring writhe (either ring) changes by more than this (turns) has left the
#: branch it came from (a buckling jump or a fold); it is kept and marked, not refined.
WRITHE_JUMP = 0.25


def continuation(model: ChiralRings, start: dict, parameter: str, target: float,
                 step: float, *, min_step: float | None = None, max_iter: int = 60,
                 stability: bool = True):
    """Natural-parameter continuation of ``model``'s ``parameter`` (``"lk_ring"`` or
    ``"alpha_B_per_L2"``) from a solved state ``start`` (a :func:`solve` result at ``model``)
    to ``target``, yielding each accepted :func:`solve` result with ``"parameter_value"``.

    Each step restarts Newton from the last accepted state and its contact partners. A
    step that does not converge is halved (down to ``min_step``, default ``|step|/4``); at
    the smallest step the result is accepted as it is, ``"converged"`` saying so. A step
    whose ring writhe changes by more than :data:`WRITHE_JUMP` (``"jump"``) has left its
    branch: the state it came from turned unstable (:func:`solve` escapes the saddle) and the
    solver fell onto another branch. Such a jump is kept, not refined: the instability point
    is bracketed by the two rows and located by the lowest eigenvalue's zero on the branch
    before it. No arc length: folds are crossed by jumps, not followed.
    """
    if parameter not in ("lk_ring", "alpha_B_per_L2"):
        raise UserError(f"parameter={parameter!r}: must be 'lk_ring' or 'alpha_B_per_L2'")
    if step == 0 or not math.isfinite(step):
        raise UserError(f"step={step!r}: must be a finite number != 0")
    value = float(getattr(model, parameter))
    direction = math.copysign(1.0, target - value)
    h = abs(step)
    h_min = h / 4 if min_step is None else float(min_step)
    if not 0 < h_min <= h:
        raise UserError(f"min_step={min_step!r}: must lie in (0, |step| = {h}]")
    cur = start
    while direction * (target - value) > 1e-12:
        nxt = value + direction * min(h, abs(target - value))
        m = dataclasses.replace(model, **{parameter: nxt})
        r = solve(m, cur["x"], partner=cur.get("partner"), stability=stability,
                  max_iter=max_iter)
        jump = max(abs(a - b) for a, b in zip(r["writhe_per_ring"], cur["writhe_per_ring"]))
        if not r["converged"] and h > h_min * (1 + 1e-9):
            h = max(h / 2, h_min)
            continue
        r["parameter"] = parameter
        r["parameter_value"] = nxt
        r["jump"] = float(jump)
        r["branch_left"] = bool(jump > WRITHE_JUMP or r.get("saddle_escapes", 0) > 0)
        r["step"] = float(h)
        yield r
        cur, value = r, nxt
        if r["converged"] and h < abs(step):
            h = min(2 * h, abs(step))
