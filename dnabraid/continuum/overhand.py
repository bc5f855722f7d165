"""Long overhand knots in elastic rods: helical braid, loop elastica and master curve (Jawed et al. 2015).

Source: Jawed, Dieleman, Audoly & Reis, "Untangling the mechanics and topology in the
frictional response of long overhand elastic knots", PRL 115, 118302 (2015) -- the *seed*,
equations (1)-(5).  Context: Audoly, Clauvelin & Neukirch, PRL 99, 164301 (2007) (ref. [21] of
the seed), whose exact braid lengths ``w_c`` are quoted below as literature constants.

Geometry and notation
---------------------
An overhand knot of unknotting number ``n = (chi - 1)/2`` (``n = 1`` trefoil, ``2``
cinquefoil, ...) in a rod of radius ``h`` and bending stiffness ``B`` is pulled by a traction
force ``F`` on its two tails.  It consists of a *braid* of length ``ell`` (two strands in
contact, both running along ``+z``) and a *loop* of arclength ``lambda`` joining the two
ends of the braid.  ``R`` is the radius of curvature of the loop where it leaves the braid,
``eps = sqrt(h/R)`` the small parameter, and ``e = lambda + ell`` the end-to-end shortening
(``e = 0`` for the straight, unknotted rod).  Any consistent unit system may be used (e.g. m,
N m^2 -> N; or nm, pN nm^2 -> pN); the rescaled quantities are dimensionless.

1. **Helical braid** (seed Eqs. (1)-(3)).  The difference braid is a helix of radius ``h``
   patched to a parabola (Eq. (2)); its energy (Eq. (1)) is
   ``E_braid = -B L/(4R^2) + (eps^3/h) B n pi Ebar(kbar)``, ``Ebar = kbar^3 + 1/(4 kbar)``,
   ``kbar = k sqrt(hR)``, minimal at ``kbar = 12^(-1/4)``, i.e. ``k = (sqrt(12) h R)^(-1/2)``
   (Eq. (3)).  Wavelength ``ell/n = 2 pi / k = 2 pi 12^(1/4) sqrt(hR)``, braid length
   ``ell = 2 n pi/k = 2 w_c sqrt(2hR)`` with ``w_c(n) = pi n / (sqrt(2) kbar) = 3^(1/4) pi n``.
   (The seed prints ``w_c = sqrt[4](3 pi n)``; its own numbers 4.13 and 8.27 are those of
   ``3^(1/4) pi n``, which is what ``pi n/(sqrt 2 kbar)`` equals -- the fourth root covers the
   3 only.)  Contact force ``P = dE_braid/dh = 2 n pi B h k^3`` and, by Coulomb's law with the
   loop force neglected, ``F = mu P``, i.e. ``F/(B k^2) = mu 2 pi n h k`` (Eq. (4)).
2. **Loop elastica** (seed text before Eq. (5); "planar Elastica problem of the loop").  The
   loop is a planar inextensible elastica in the ``(z, y)`` plane, leaving the braid end
   ``(z, y) = (ell/2, 0)`` tangent to the braid axis (the seed's ``theta(0) = pi`` condition,
   here written ``theta(0) = 0`` with ``theta`` the tangent angle from ``+z``), with curvature
   ``1/R`` there (definition of ``R``), and re-entering the braid at ``(-ell/2, 0)`` after
   turning by ``2 pi``.  The loop is mirror-symmetric about ``z = 0``; we solve the half-loop
   ``0 <= s <= lambda/2`` with apex conditions ``theta = pi``, ``z = 0``.  The Kirchhoff
   equations reduce to ``B theta'' = -T sin(theta)`` with ``T`` the (unknown, constant)
   tension of the loop along ``z``; first integral ``theta'^2 = R^-2 - (4T/B) sin^2(theta/2)``.
   Scale invariance gives ``ell^2/(e R) = g(ell/R)`` (seed).  Solved here with
   :func:`scipy.integrate.solve_bvp` (unknowns: half-length and ``T``), and independently in
   closed form with complete elliptic integrals (``m = 4 T R^2/B``):
   ``lambda/R = 4 K(m)``, ``ell/R = 4 [2 (K - E)/m - K]``, ``H/R = 4 (1 - sqrt(1-m))/m``.
   Limits: ``g(x) = x^2/(2 pi) (1 - 3x/(2 pi) + O(x^2))`` for ``x -> 0`` (circle of
   perimeter ``2 pi R``; first correction ``lambda/R = 2 pi + 2x``), and ``g(x) = x/2 - 2 +
   o(1)`` for ``x -> inf`` (``m -> 1``, ``lambda - ell -> 8R``, loop soliton).
3. **Master curve** (seed Eq. (5)):
   ``n^2 h / e = g(x) / (8 sqrt(3) pi^2)``, ``x = ell/R = [96 sqrt(3) pi^2 n^2 F h^2/(mu B)]^(1/3)``.
   Given ``e`` it is solved for ``x`` (root of the monotonic ``g``), then
   ``F = mu B x^3/(96 sqrt(3) pi^2 n^2 h^2)``, ``R = G e/x^2``, ``ell = x R``
   (``G = g(x)``).  ``mu = 0`` gives ``F = 0`` (friction-only model); the frictionless tension
   ``B/(2R^2)`` that the seed neglects (``F R^2/B = 1/2``, seed text) is reported alongside.

Where the model is exact, and its error elsewhere
-------------------------------------------------
Eq. (3)-(5) are the leading order for ``n >> 1`` and ``eps -> 0``: the boundary layers at
the braid ends (``O(1/n)`` in ``Ebar``) and the loop force ``~ B/R^2`` next to ``F`` are
neglected.  For ``n = 1, 2`` the helical ``w_c`` overshoots the exact value by a nearly
constant ``~0.63`` (17.9 % and 8.2 %).  Each point reports ``eps`` and ``F R^2/B`` so a user
can see how far from the asymptotic regime it lies; ``R <= h`` (``eps >= 1``) is outside the
model (``status = 3``).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import logging
import math
import time
from collections.abc import Callable, Iterable, Sequence

import numpy as np
from scipy.integrate import quad, solve_bvp
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq, minimize_scalar
from scipy.special import ellipe, ellipkm1

from dnabraid.continuum._result import ContinuumResult
from dnabraid.continuum._validate import check_n, check_nonnegative, check_positive

logger = logging.getLogger(__name__)

# --------------------------------------------------------------------------- constants
#: Optimal rescaled wave number of the helical braid, ``12^(-1/4)`` (seed, before Eq. (3)).
K_BAR = 12.0 ** -0.25
#: Rescaled braid energy at the optimum, ``Ebar = 4 kbar^3 = 4/12^(3/4)`` (seed, text for P).
E_BAR_OPT = 4.0 * K_BAR**3
#: Prefactor of Eq. (5): ``n^2 h/e = g(x) / C5``, ``C5 = 8 sqrt(3) pi^2``.
C5_SHORTENING = 8.0 * math.sqrt(3.0) * math.pi**2
#: Prefactor of Eq. (5): ``x^3 = C5F n^2 F h^2/(mu B)``, ``C5F = 96 sqrt(3) pi^2``.
C5_FORCE = 96.0 * math.sqrt(3.0) * math.pi**2
#: Frictionless balance ``F R^2/B = 1/2`` of the braid (seed, discussion of Fig. 1(f)).
FRICTIONLESS_FR2_OVER_B = 0.5
#: Exact braid lengths ``w_c`` of the difference problem, Audoly, Clauvelin & Neukirch, PRL 99,
#: 164301 (2007), Eq. after (5) (Audoly et al. 2007): trefoil (n = 1) and cinquefoil (n = 2).
W_C_EXACT_ACN2007 = {1: 3.506, 2: 7.640}
#: The same as quoted (rounded) in the seed (Jawed et al. 2015): "3.51" and "7.60".  The 7.60
#: differs from ACN2007's 7.640; both are kept so tests can check the seed's claim as printed.
W_C_EXACT_SEED_QUOTED = {1: 3.51, 2: 7.60}
#: Nitinol rods of the seed's experiments: radius (m), Young's modulus (Pa), friction.
NITINOL_RADIUS_M = 0.127e-3
NITINOL_YOUNG_PA = 67.50e9
NITINOL_BENDING_N_M2 = NITINOL_YOUNG_PA * math.pi * NITINOL_RADIUS_M**4 / 4.0  # B = E pi h^4/4
NITINOL_MU = 0.119
#: ``lambda/R - ell/R`` tends to this as ``ell/R -> inf`` (loop soliton, ``8 E(1) = 8``).
LOOP_EXCESS_LARGE_X = 8.0
#: Default largest ``x = ell/R`` of the tabulated ``g`` (``g ~ 98``, ``e ~ 1.4 n^2 h``).
DEFAULT_X_MAX = 200.0

_BVP_STATUS = {0: 0, 1: 1, 2: 2, 3: 4}
#: What ``n`` counts, for the messages of :func:`~dnabraid.continuum._validate.check_n`.
_N_MEANS = "unknotting number, n = (chi - 1)/2"


# --------------------------------------------------------------------------- helical braid
def braid_energy_bar(kbar):
    """Rescaled braid energy ``Ebar(kbar) = kbar^3 + 1/(4 kbar)`` (seed, text after Eq. (2)).

    Parameters
    ----------
    kbar : float or ndarray
        Rescaled wave number ``k sqrt(hR)`` (> 0).
    """
    kbar = np.asarray(kbar, dtype=float)
    return kbar**3 + 1.0 / (4.0 * kbar)  # seed: Ebar = kbar^3 + 1/(4 kbar)


def braid_energy_ansatz(k: float, n: int, h: float, R: float, B: float, L: float) -> float:
    """Eq. (1) evaluated exactly on the helix + parabola ansatz of Eq. (2) (no 1/n dropped).

    ``E = 2 [B/2 int_0^L |delta''|^2 dz - B/(2R) delta'(L).e_y]`` with the helix on
    ``0 <= z <= ell/2 = n pi/k`` (``|delta''|^2 = h^2 k^4``) and the parabola beyond
    (``|delta''|^2 = 1/(4R^2)``, ``delta_y'(L) = kh + (L - ell/2)/(2R)``):
    ``E = -B L/(4R^2) + B n pi (h^2 k^3 + 1/(4 k R^2)) - B k h/R``.
    The last term is the ``O(1/n)`` correction the seed neglects in ``Ebar``.

    Parameters
    ----------
    k : float
        Helical wave number, 1/length.
    n : int
        Unknotting number.
    h, R, B, L : float
        Rod radius, loop radius of curvature, bending stiffness, half-domain length
        (``L > ell/2``).

    Returns
    -------
    float
        Braid energy (energy units of ``B``/length).
    """
    half = n * math.pi / k  # ell/2 = n pi/k  (seed: ell = 2 n pi/k)
    if L < half:
        raise ValueError(f"L must exceed ell/2 = {half!r}, got {L!r}")
    u = L - half
    helix = 0.5 * B * (h * k * k) ** 2 * half  # Eq. (1) on the helix of Eq. (2)
    parabola = 0.5 * B * u / (4.0 * R * R)  # Eq. (1): delta_y'' = 1/(2R) on the parabola
    moment = -B / (2.0 * R) * (k * h + u / (2.0 * R))  # Eq. (1): -B/(2R) delta'(L).e_y
    return 2.0 * (helix + parabola + moment)  # Eq. (1): doubled half-braid


def optimal_kbar_ansatz(n: int) -> float:
    """Minimiser of :func:`braid_energy_ansatz` over ``kbar`` (keeps the ``O(1/n)`` term).

    With ``k h/R = kbar h^(1/2)/R^(3/2)`` the ansatz energy is
    ``-B L/(4R^2) + B n pi (h^(1/2)/R^(3/2)) [Ebar(kbar) - kbar/(n pi)]``, so the optimum
    depends on ``n`` only and tends to ``12^(-1/4)`` (Eq. (3)) as ``n -> inf``.
    """
    n = check_n(n, what=_N_MEANS)
    res = minimize_scalar(lambda kb: float(braid_energy_bar(kb)) - kb / (n * math.pi),
                          bounds=(1e-3, 5.0), method="bounded",
                          options={"xatol": 1e-12})
    return float(res.x)


def w_c_helical(n) -> float:
    """Rescaled braid length of the helical approximation, ``w_c = pi n/(sqrt(2) kbar)``.

    Defined by ``ell = 2 w_c sqrt(2 h R)`` (seed, after Eq. (3)); equals ``3^(1/4) pi n``:
    4.13 for ``n = 1``, 8.27 for ``n = 2`` (seed).
    """
    n = check_n(n, what=_N_MEANS)
    return math.pi * n / (math.sqrt(2.0) * K_BAR)  # seed: w_c = pi n/(sqrt 2 kbar)


def wave_number(h: float, R: float) -> float:
    """Helical wave number ``k = (sqrt(12) h R)^(-1/2)`` (seed Eq. (3)), 1/length."""
    h = check_positive("h", h)
    R = check_positive("R", R)
    return (math.sqrt(12.0) * h * R) ** -0.5  # Eq. (3)


def helical_braid(n, h: float, R: float, B: float = 1.0, mu: float = 0.0) -> dict:
    """Helical approximation of the braid for given loop radius ``R`` (seed Eqs. (2)-(4)).

    Parameters
    ----------
    n : int
        Unknotting number (>= 1).
    h : float
        Rod radius (length).
    R : float
        Radius of curvature of the loop at the braid exit (length).
    B : float
        Bending stiffness (force x length^2).
    mu : float
        Friction coefficient (>= 0).

    Returns
    -------
    dict
        ``k`` (Eq. (3)), ``kbar``, ``wavelength`` (``2 pi/k = ell/n``), ``ell``
        (``2 n pi/k``), ``w_c`` (``ell/(2 sqrt(2hR))``), ``eps``, ``E_bar``, ``P``
        (``2 n pi B h k^3``), ``F`` (``mu P``, Eq. (4)), ``F_over_Bk2``, ``two_pi_n_h_k``
        (the abscissa of the seed's Fig. 2(d)).
    """
    n = check_n(n, what=_N_MEANS)
    h = check_positive("h", h)
    R = check_positive("R", R)
    B = check_positive("B", B)
    mu = check_nonnegative("mu", mu)
    k = wave_number(h, R)  # Eq. (3)
    ell = 2.0 * n * math.pi / k  # seed: ell = 2 n pi/k
    P = 2.0 * n * math.pi * B * h * k**3  # seed: P = 2 n pi B h k^3
    F = mu * P  # seed: F = mu P  -> Eq. (4)
    return {
        "k": k, "kbar": k * math.sqrt(h * R), "wavelength": 2.0 * math.pi / k, "ell": ell,
        "w_c": ell / (2.0 * math.sqrt(2.0 * h * R)), "eps": math.sqrt(h / R),
        "E_bar": float(braid_energy_bar(k * math.sqrt(h * R))), "P": P, "F": F,
        "F_over_Bk2": F / (B * k * k),  # Eq. (4): = mu 2 pi n h k
        "two_pi_n_h_k": 2.0 * math.pi * n * h * k,
    }


# --------------------------------------------------------------------------- loop elastica
def _x_series(m: float) -> float:
    """``x(m) = 2 pi sum_{j>=1} c_j^2 j/(j+1) m^j`` (``c_j = (2j)!/(4^j j!^2)``), no cancellation.

    Obtained from the power series of ``K`` and ``E``; used for ``m < 1/2``.
    """
    c2, total, term_m = 1.0, 0.0, 1.0
    for j in range(1, 200):
        c2 *= ((2.0 * j - 1.0) / (2.0 * j)) ** 2
        term_m *= m
        term = c2 * j / (j + 1.0) * term_m
        total += term
        if term < 1e-17 * total:
            break
    return 2.0 * math.pi * total


def _elliptic_KE(p: float) -> tuple[float, float]:
    """``K(m), E(m)`` with ``m = 1 - p`` (accurate as ``p -> 0``)."""
    return float(ellipkm1(p)), float(ellipe(1.0 - p))


def loop_closed_form_x(m: float, *, p: float | None = None) -> float:
    """``x = ell/R = 4 [2 (K - E)/m - K]`` for modulus ``m`` (or its complement ``p = 1 - m``)."""
    if p is None:
        p = 1.0 - m
    m = 1.0 - p
    if m < 0.5:
        return _x_series(m)
    K, E = _elliptic_KE(p)
    return 4.0 * (2.0 * (K - E) / m - K)


def loop_closed_form(m: float, *, p: float | None = None) -> dict:
    """Loop elastica in closed form for the modulus ``m = 4 T R^2/B`` in ``[0, 1)``.

    From the first integral ``theta'^2 = 1 - m sin^2(theta/2)`` (``R = 1``), with
    ``phi = theta/2`` over the half-loop ``0 <= theta <= pi``:
    ``lambda/2 = 2 K(m)``, ``-ell/2 = int cos(theta)/theta' dtheta = 2 [K - 2 (K - E)/m]``,
    ``H = int sin(theta)/theta' dtheta = 4 (1 - sqrt(1 - m))/m = 4/(1 + sqrt(1 - m))``, and
    the half-width ``W/2 = ell/2 + int_0^{pi/2} cos(theta)/theta' dtheta`` (quadrature).

    Parameters
    ----------
    m : float
        Elliptic parameter in ``[0, 1)``.
    p : float, optional
        ``1 - m`` given directly (for ``m`` within rounding of 1).

    Returns
    -------
    dict
        ``x`` (``ell/R``), ``lambda_over_R``, ``g``, ``tension_R2_over_B`` (``m/4``),
        ``width_over_R``, ``height_over_R``, ``aspect_ratio`` (``W/H``).
    """
    if p is None:
        m = float(m)
        if not (0.0 <= m < 1.0):
            raise ValueError(f"m must lie in [0, 1), got {m!r}")
        p = 1.0 - m
    p = float(p)
    if not (0.0 < p <= 1.0):
        raise ValueError(f"p = 1 - m must lie in (0, 1], got {p!r}")
    m = 1.0 - p
    K, _ = _elliptic_KE(p)
    x = loop_closed_form_x(m, p=p)
    lam = 4.0 * K
    height = 4.0 / (1.0 + math.sqrt(p))
    quarter, _ = quad(lambda t: math.cos(t) / math.sqrt(1.0 - m * math.sin(0.5 * t) ** 2),
                      0.0, 0.5 * math.pi, epsabs=1e-13, epsrel=1e-13)
    width = x + 2.0 * quarter
    return {"x": x, "lambda_over_R": lam, "g": x * x / (lam + x), "tension_R2_over_B": m / 4.0,
            "width_over_R": width, "height_over_R": height, "aspect_ratio": width / height}


#: Largest ``x`` the closed form reaches (``1 - m`` down to ``exp(-700)``).
X_MAX_CLOSED_FORM = 1000.0


def g_closed_form(x: float, *, xtol: float = 1e-14) -> float:
    """``g(x)`` from the elliptic-integral solution (independent of the BVP)."""
    return loop_closed_form_at(x, xtol=xtol)["g"]


def loop_closed_form_at(x: float, *, xtol: float = 1e-14) -> dict:
    """:func:`loop_closed_form` at a given ``x = ell/R`` (root of ``x(m)`` by ``brentq``)."""
    x = check_nonnegative("x", x)
    if x == 0.0:
        return loop_closed_form(0.0)
    if x > X_MAX_CLOSED_FORM:
        raise ValueError(f"x must be <= {X_MAX_CLOSED_FORM:g} for the closed form, got {x!r}")

    # x(m) increases from 0 (m = 0) to inf (m -> 1); solve in q = -log(1 - m).
    def f(q):
        return loop_closed_form_x(0.0, p=math.exp(-q)) - x

    hi = 1.0
    while f(hi) < 0.0:
        hi *= 2.0
    q = brentq(f, 0.0, hi, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=300)
    return loop_closed_form(0.0, p=math.exp(-q))


def _loop_rhs(t, y, p):
    # y = (theta, kappa, z, y); t in [0, 1] is s/(lambda/2); p = (Lh, T[, x]) with R = B = 1.
    Lh, T = p[0], p[1]
    th, ka = y[0], y[1]
    s = np.sin(th)
    return Lh * np.vstack([ka,  # theta' = kappa
                           -T * s,  # Kirchhoff, planar: B theta'' = -T sin(theta)
                           np.cos(th),  # z' = cos(theta)
                           s])  # y' = sin(theta)


def _loop_guess(x: float, n_nodes: int):
    t = np.linspace(0.0, 1.0, n_nodes)
    th = math.pi * t  # circle of radius R
    y = np.vstack([th, np.ones_like(t), 0.5 * x * (1.0 - t) + np.sin(th), 1.0 - np.cos(th)])
    return t, y, np.array([math.pi + 0.5 * x, 0.0])


def _loop_values(sol, x: float, Lh: float, T: float) -> dict:
    tt = np.linspace(0.0, 1.0, 2001)
    yy = sol.sol(tt)
    lam = 2.0 * Lh
    hamiltonian = 0.5 * yy[1] ** 2 - T * np.cos(yy[0])  # first integral (const)
    # widest point: theta = pi/2 (theta increases monotonically on a convex loop)
    i = int(np.searchsorted(yy[0], 0.5 * math.pi))
    i = min(max(i, 1), tt.size - 1)
    try:
        t_w = brentq(lambda t: float(sol.sol(t)[0]) - 0.5 * math.pi, tt[i - 1], tt[i],
                     xtol=1e-15)
    except ValueError:
        t_w = tt[int(np.argmax(yy[2]))]
    width = 2.0 * float(sol.sol(t_w)[2])
    height = float(yy[3][-1])
    return {
        "x": x, "lambda_over_R": lam, "e_over_R": lam + x, "g": x * x / (lam + x),
        "tension_R2_over_B": T,
        "width_over_R": width, "height_over_R": height, "aspect_ratio": width / height,
        "first_integral_spread": float(np.ptp(hamiltonian)),
    }


def solve_loop_elastica(x: float, *, tol: float = 1e-8, n_nodes: int = 41,
                        max_nodes: int = 100000,
                        initial: ContinuumResult | None = None) -> ContinuumResult:
    """Solve the planar loop elastica for ``x = ell/R`` with :func:`scipy.integrate.solve_bvp`.

    Half-loop, ``R = B = 1``, ``t = s/(lambda/2)`` in ``[0, 1]``; unknown parameters the
    half-length ``lambda/2`` and the loop tension ``T`` (``T R^2/B``).  ODEs:
    ``theta' = kappa``, ``kappa' = -T sin theta``, ``z' = cos theta``, ``y' = sin theta``
    (times ``lambda/2``).  Boundary conditions: ``theta(0) = 0`` (tangent to the braid,
    seed's ``theta(0) = pi``), ``kappa(0) = 1`` (curvature ``1/R`` at the exit),
    ``z(0) = x/2``, ``y(0) = 0``; apex ``theta(1) = pi``, ``z(1) = 0`` (mirror symmetry).

    Parameters
    ----------
    x : float
        ``ell/R >= 0``.
    tol : float
        ``solve_bvp`` relative residual tolerance.
    n_nodes : int
        Initial mesh nodes (when no ``initial``).
    max_nodes : int
        Largest mesh allowed.
    initial : ContinuumResult, optional
        A previous solution (continuation in ``x``).

    Returns
    -------
    ContinuumResult
        ``values``: ``x``, ``lambda_over_R``, ``e_over_R`` (``(lambda + ell)/R``), ``g``
        (``ell^2/(e R)``), ``tension_R2_over_B``, ``width_over_R``, ``height_over_R``,
        ``aspect_ratio`` (``W/H``), ``first_integral_spread`` (exact: 0).
        ``solution`` is the ``BVPResult``.
    """
    t0 = time.perf_counter()
    x = check_nonnegative("x", x)
    tol = check_positive("tol", tol)
    if int(n_nodes) < 3:
        raise ValueError(f"n_nodes must be >= 3, got {n_nodes!r}")
    if initial is not None and initial.solution is not None and initial.success:
        s0 = initial.solution
        # resample on a modest mesh: carrying a refined mesh along a continuation path
        # makes every later solve pay for it
        t = np.linspace(0.0, 1.0, int(n_nodes) if int(n_nodes) > 101 else 101)
        y, p = s0.sol(t), s0.p.copy()
        x_old = float(initial.values["x"])
        y[2] = y[2] + 0.5 * (x - x_old) * (1.0 - t)  # shift the guess to the new ends
        p[0] = p[0] + 0.5 * (x - x_old)
    else:
        t, y, p = _loop_guess(x, int(n_nodes))

    def bc(ya, yb, p):
        return np.array([ya[0], ya[1] - 1.0, ya[2] - 0.5 * x, ya[3], yb[0] - math.pi, yb[2]])

    try:
        sol = solve_bvp(_loop_rhs, bc, t, y, p, tol=tol, max_nodes=int(max_nodes))
        if not sol.success and initial is None and x > 2.0:
            # continuation from the circle through intermediate x, then the target
            prev = None
            for xi in np.geomspace(2.0, x, int(math.ceil(math.log(x / 2.0) / math.log(1.5))) + 1):
                prev = solve_loop_elastica(float(xi), tol=max(tol, 1e-6), max_nodes=max_nodes,
                                           initial=prev)
                if not prev.success:
                    break
            if prev is not None and prev.success:
                s0 = prev.solution
                sol = solve_bvp(_loop_rhs, bc, s0.x, s0.y, s0.p, tol=tol,
                                max_nodes=int(max_nodes))
    except (ValueError, np.linalg.LinAlgError, FloatingPointError) as exc:
        return ContinuumResult(False, 2, f"solve_bvp failed: {exc}", {"x": x},
                               wall_time_s=time.perf_counter() - t0)
    Lh, T = float(sol.p[0]), float(sol.p[1])
    values = _loop_values(sol, x, Lh, T) if sol.success else {"x": x}
    ok = bool(sol.success)
    status, message = _BVP_STATUS.get(sol.status, 4), sol.message
    if ok:
        kap = sol.y[1]
        slack = max(1e-6, 10.0 * tol)  # loose tolerances: tiny apex curvature may dip below 0
        if Lh <= 0.0 or np.any(kap < -slack) or not (-slack <= T <= 0.25 + slack):
            ok, status = False, 4
            message = ("converged to a non-physical branch (loop not convex / T outside "
                       f"[0, 1/4]): lambda/2 = {Lh:.4g}, T R^2/B = {T:.4g}")
    res_max = float(np.max(sol.rms_residuals)) if sol.rms_residuals is not None else math.nan
    return ContinuumResult(ok, 0 if ok else status, message, values, res_max,
                           int(sol.x.size), time.perf_counter() - t0, sol)


def _default_x_grid(x_max: float, n_points: int) -> np.ndarray:
    n_lin = max(4, n_points // 4)
    lin = np.linspace(0.0, min(2.0, x_max), n_lin)
    if x_max <= 2.0:
        return lin
    geo = np.geomspace(2.0, x_max, n_points - n_lin + 1)[1:]
    return np.concatenate([lin, geo])


@dataclasses.dataclass
class GTable:
    """Tabulated ``g(x)`` of the solved loop elastica, with a cubic-spline interpolant.

    The spline is built on the smooth excess ``q(x) = lambda/R - x`` (from ``2 pi`` at
    ``x = 0`` to ``8`` as ``x -> inf``); ``g = x^2/(q + 2x)`` then keeps the exact
    ``x^2/(2 pi)`` behaviour at small ``x``.  Calling the table evaluates ``g``.

    Attributes
    ----------
    x, g, lambda_over_R, aspect_ratio, tension_R2_over_B : ndarray
        Grid values, shape ``(n,)``.
    success : bool
        All grid points converged.
    message : str
        Failure reason(s), or "ok".
    wall_time_s : float
        Time to build the table.
    mesh_nodes : int
        Largest BVP mesh used on the grid.
    """

    x: np.ndarray
    g: np.ndarray
    lambda_over_R: np.ndarray
    aspect_ratio: np.ndarray
    tension_R2_over_B: np.ndarray
    success: bool
    message: str
    wall_time_s: float
    mesh_nodes: int

    def __post_init__(self):
        self._q = CubicSpline(self.x, self.lambda_over_R - self.x)
        self._a = CubicSpline(self.x, self.aspect_ratio)

    @property
    def x_max(self) -> float:
        return float(self.x[-1])

    def __call__(self, x):
        """``g(x)`` (interpolated), ``0 <= x <= x_max``; raises ValueError outside."""
        xa = np.asarray(x, dtype=float)
        if np.any(xa < 0.0) or np.any(xa > self.x_max * (1.0 + 1e-12)):
            raise ValueError(f"x must lie in [0, {self.x_max:g}] (tabulated range), got {x!r}")
        out = xa * xa / (self._q(xa) + 2.0 * xa)
        return float(out) if out.ndim == 0 else out

    def lambda_over_R_at(self, x):
        """Interpolated loop length ``lambda/R``."""
        return self._q(x) + np.asarray(x, dtype=float)

    def aspect_ratio_at(self, x):
        """Interpolated loop aspect ratio ``W/H``."""
        return self._a(x)


def g_table(x_values: Sequence[float] | None = None, *, x_max: float = DEFAULT_X_MAX,
            n_points: int = 96, tol: float = 1e-6, max_nodes: int = 100000) -> GTable:
    """Solve the loop elastica on a grid of ``x = ell/R`` by continuation from the circle.

    Parameters
    ----------
    x_values : sequence of float, optional
        Increasing grid starting at 0 (default: ``n_points`` points, linear on ``[0, 2]``
        then geometric to ``x_max``).
    x_max, n_points : float, int
        Default grid.
    tol, max_nodes :
        Passed to :func:`solve_loop_elastica`.

    Returns
    -------
    GTable
    """
    t0 = time.perf_counter()
    if x_values is None:
        xs = _default_x_grid(check_positive("x_max", x_max), int(n_points))
    else:
        xs = np.asarray(x_values, dtype=float)
        if xs.ndim != 1 or xs.size < 4 or xs[0] != 0.0 or np.any(np.diff(xs) <= 0):
            raise ValueError("x_values must be an increasing 1-D grid of >= 4 points from 0")
    # continuation path: the grid plus steps of at most 20 % beyond x = 2 (not stored)
    path = sorted(set(float(v) for v in xs) | set(
        float(v) for v in np.geomspace(2.0, max(2.0, xs[-1]),
                                       int(math.ceil(math.log(max(xs[-1], 2.0) / 2.0)
                                                     / math.log(1.2))) + 1)
        if v < xs[-1]))
    wanted = set(float(v) for v in xs)
    rows, prev, msgs = [], None, []
    for x in path:
        res = solve_loop_elastica(x, tol=tol, max_nodes=max_nodes, initial=prev)
        if not res.success:  # retry from the circle
            res = solve_loop_elastica(x, tol=tol, max_nodes=max_nodes)
        if not res.success:
            msgs.append(f"x={x:g}: {res.message}")
            break
        if x in wanted:
            rows.append(res)
        prev = res
    ok = not msgs
    xs = xs[: len(rows)]
    val = {k: np.array([r.values[k] for r in rows]) for k in
           ("g", "lambda_over_R", "aspect_ratio", "tension_R2_over_B")}
    return GTable(xs, val["g"], val["lambda_over_R"], val["aspect_ratio"],
                  val["tension_R2_over_B"], ok, "ok" if ok else "; ".join(msgs),
                  time.perf_counter() - t0, max(r.mesh_size for r in rows) if rows else 0)


@functools.lru_cache(maxsize=4)
def default_g_table(tol: float = 1e-6) -> GTable:
    """The module's cached ``g`` table (built on first use, ~1 s; relative error ~1e-6).

    ``tol = 1e-6`` already gives ``g`` to ~1e-10 at the nodes (see :func:`convergence_table`),
    so the spline, not the BVP, sets the error.
    """
    return g_table(tol=tol)


def g_asymptotic_small(x):
    """``g(x) ~ x^2/(2 pi + 3x)`` as ``x -> 0`` (circle plus the first correction)."""
    x = np.asarray(x, dtype=float)
    return x * x / (2.0 * math.pi + 3.0 * x)


def g_asymptotic_large(x):
    """``g(x) ~ x^2/(2x + 8)`` as ``x -> inf`` (``lambda - ell -> 8R``, loop soliton)."""
    x = np.asarray(x, dtype=float)
    return x * x / (2.0 * x + LOOP_EXCESS_LARGE_X)


# --------------------------------------------------------------------------- master curve
def _check_inputs(e, n, h, B, mu):
    return (check_positive("e", e), check_n(n, what=_N_MEANS), check_positive("h", h),
            check_positive("B", B), check_nonnegative("mu", mu))


def _g_callable(method: str, table: GTable | None) -> tuple[Callable[[float], float], float]:
    if method == "table":
        tab = table if table is not None else default_g_table()
        return tab, tab.x_max
    if method == "elliptic":
        return g_closed_form, X_MAX_CLOSED_FORM
    raise ValueError(f"method must be 'table', 'direct' or 'elliptic', got {method!r}")


def _master_values(x, G, e, n, h, B, mu, lam_over_R, aspect):
    R = G * e / (x * x)  # ell^2 = e R g, ell = x R  ->  R = g e/x^2
    ell = x * R
    braid = helical_braid(n, h, R, B, mu)
    F_eq5 = mu * B * x**3 / (C5_FORCE * n * n * h * h)  # Eq. (5) solved for F
    return {
        "e": e, "n": n, "h": h, "B": B, "mu": mu,
        "x_ell_over_R": x, "g": G, "n2h_over_e": n * n * h / e,
        "F": F_eq5, "R": R, "ell": ell, "lambda": lam_over_R * R,
        "k": braid["k"], "kbar": braid["kbar"], "wavelength": braid["wavelength"],
        "w_c_helical": braid["w_c"], "P": braid["P"], "eps": braid["eps"],
        "F_over_Bk2": braid["F_over_Bk2"], "two_pi_n_h_k": braid["two_pi_n_h_k"],
        "F_R2_over_B": F_eq5 * R * R / B,
        "F_frictionless": FRICTIONLESS_FR2_OVER_B * B / (R * R),
        "aspect_ratio": aspect,
        "eq4_residual": abs(braid["F"] - F_eq5) / max(F_eq5, 1e-300) if mu > 0 else 0.0,
        "braid_length_residual": abs(braid["ell"] - ell) / ell,
    }


def _domain_message(v: dict) -> tuple[bool, int, str]:
    notes = []
    if v["eps"] >= 1.0:
        return False, 3, (f"outside the model: R = {v['R']:.3g} <= h (eps = {v['eps']:.3g} >= 1); "
                          "the slender-braid asymptotics (h << ell/n << R) do not hold")
    if v["eps"] > 0.3:
        notes.append(f"eps = sqrt(h/R) = {v['eps']:.3g} is not small")
    if v["mu"] == 0.0:
        notes.append("mu = 0: friction force F = mu P = 0; the frictionless tension B/(2R^2) "
                     "(F_frictionless, neglected by Eq. (5)) is the leading term")
    elif v["F_R2_over_B"] < 10.0 * FRICTIONLESS_FR2_OVER_B:
        notes.append(f"F R^2/B = {v['F_R2_over_B']:.3g} is not >> 1/2: the neglected loop force "
                     "B/(2R^2) matters")
    return True, 0, "converged" + ("; " + "; ".join(notes) if notes else "")


def solve_overhand(e: float, n, h: float, B: float, mu: float, *, method: str = "table",
                   table: GTable | None = None, xtol: float = 1e-13,
                   tol: float = 1e-8, initial: ContinuumResult | None = None) -> ContinuumResult:
    """Traction force of a long overhand knot at end-to-end shortening ``e`` (seed Eq. (5)).

    Solves ``g(x) = 8 sqrt(3) pi^2 n^2 h/e`` for ``x = ell/R`` (Eq. (5)), then
    ``F = mu B x^3/(96 sqrt(3) pi^2 n^2 h^2)``, ``R = g e/x^2``, ``ell = x R``, and the braid
    of Eqs. (3)-(4) at that ``R``.

    Parameters
    ----------
    e : float
        End-to-end shortening (length, > 0).
    n : int
        Unknotting number (>= 1).
    h, B : float
        Rod radius (length) and bending stiffness (force length^2), > 0.
    mu : float
        Friction coefficient (>= 0).
    method : {"table", "direct", "elliptic"}
        ``"table"``: root of the spline of the BVP-solved ``g`` (:func:`default_g_table` or
        ``table``); ``"direct"``: one BVP with ``x`` as an extra unknown and the extra
        condition ``x^2 = G (lambda/R + x)`` (continuation through ``initial``);
        ``"elliptic"``: root of the closed-form ``g`` (independent check).
    table : GTable, optional
        Table for ``method="table"``.
    xtol : float
        ``brentq`` tolerance on ``x``.
    tol : float
        BVP tolerance (``"direct"``).
    initial : ContinuumResult, optional
        A previous point (bracket / initial guess for continuation).

    Returns
    -------
    ContinuumResult
        ``values``: inputs, ``x_ell_over_R``, ``g``, ``F``, ``R``, ``ell``, ``lambda``,
        ``k``, ``kbar``, ``wavelength``, ``w_c_helical``, ``P``, ``eps``, ``F_over_Bk2``,
        ``two_pi_n_h_k``, ``F_R2_over_B``, ``F_frictionless`` (``B/(2R^2)``),
        ``aspect_ratio`` (loop ``W/H``), residuals.  ``status = 3`` outside the model
        (``R <= h``) or beyond the tabulated ``g``.
    """
    t0 = time.perf_counter()
    e, n, h, B, mu = _check_inputs(e, n, h, B, mu)
    G = C5_SHORTENING * n * n * h / e  # Eq. (5): g(x) = 8 sqrt(3) pi^2 n^2 h/e
    if method == "direct":
        return _solve_overhand_direct(e, n, h, B, mu, G, tol, initial, t0)
    g, x_hi = _g_callable(method, table)
    if method == "table" and not g.success:
        logger.warning("g table incomplete: %s", g.message)
    g_hi = float(g(x_hi))
    if not G < g_hi:
        return ContinuumResult(
            False, 3, f"g(x) = {G:.4g} (n^2 h/e = {n * n * h / e:.4g}) exceeds the range of g "
            f"solved ({g_hi:.4g} at x = {x_hi:g}): the knot is tighter than the tabulated loop; "
            "use method='elliptic' or a larger table", {"e": e, "n": n, "g": G},
            wall_time_s=time.perf_counter() - t0)
    lo, hi = 0.0, x_hi
    if initial is not None and initial.success:  # continuation: narrow the bracket
        x0 = float(initial.values["x_ell_over_R"])
        a, b = 0.5 * x0, min(2.0 * x0 + 1.0, x_hi)
        if float(g(a)) <= G <= float(g(b)):
            lo, hi = a, b
    try:
        x = brentq(lambda xx: float(g(xx)) - G, lo, hi, xtol=xtol,
                   rtol=8 * np.finfo(float).eps, maxiter=300)
    except (ValueError, RuntimeError) as exc:
        return ContinuumResult(False, 4, f"root finding on g failed: {exc}", {"e": e, "g": G},
                               wall_time_s=time.perf_counter() - t0)
    if method == "table":
        lam = float(g.lambda_over_R_at(x))
        aspect = float(g.aspect_ratio_at(x))
    else:
        cf = loop_closed_form_at(x)
        lam, aspect = cf["lambda_over_R"], cf["aspect_ratio"]
    values = _master_values(x, G, e, n, h, B, mu, lam, aspect)
    ok, status, message = _domain_message(values)
    resid = abs(float(g(x)) - G) / G
    return ContinuumResult(ok, status, message, values, resid,
                           g.x.size if method == "table" else 0, time.perf_counter() - t0, None)


def _solve_overhand_direct(e, n, h, B, mu, G, tol, initial, t0) -> ContinuumResult:
    """Eq. (5) as one BVP: unknowns ``(lambda/2, T, x)``, extra condition ``x^2 = G (2 Lh + x)``."""
    g_lim = float(g_asymptotic_large(X_MAX_CLOSED_FORM))
    if not G < g_lim:
        return ContinuumResult(
            False, 3, f"g(x) = {G:.4g} (n^2 h/e = {n * n * h / e:.4g}) needs ell/R > "
            f"{X_MAX_CLOSED_FORM:g}: the loop is a soliton far smaller than the braid, and "
            f"R ~ e/(4g) = {e / (4 * G):.3g} vs h = {h:.3g}; outside the model",
            {"e": e, "n": n, "g": G}, wall_time_s=time.perf_counter() - t0)
    if (initial is not None and initial.success
            and getattr(initial.solution, "p", None) is not None
            and len(initial.solution.p) == 3):
        s0 = initial.solution
        t, y, p = s0.x, s0.y, s0.p.copy()
    else:  # guess from the closed-form-free table
        tab = default_g_table()
        if not G < float(tab(tab.x_max)):
            x0 = 2.0 * G + 4.0  # large-x asymptote g ~ x/2 - 2
        else:
            x0 = brentq(lambda xx: float(tab(xx)) - G, 0.0, tab.x_max)
        r0 = solve_loop_elastica(x0, tol=1e-4)
        if r0.success:
            t, y = r0.solution.x, r0.solution.y
            p = np.array([r0.solution.p[0], r0.solution.p[1], x0])
        else:
            t, y, p2 = _loop_guess(x0, 41)
            p = np.array([p2[0], p2[1], x0])

    def bc(ya, yb, p):
        Lh, _, x = p
        return np.array([ya[0], ya[1] - 1.0, ya[2] - 0.5 * x, ya[3], yb[0] - math.pi, yb[2],
                         x * x - G * (2.0 * Lh + x)])  # Eq. (5): g(x) = x^2/(lambda/R + x) = G

    try:
        sol = solve_bvp(_loop_rhs, bc, t, y, p, tol=tol, max_nodes=200000)
    except (ValueError, np.linalg.LinAlgError, FloatingPointError) as exc:
        return ContinuumResult(False, 2, f"solve_bvp failed: {exc}", {"e": e, "g": G},
                               wall_time_s=time.perf_counter() - t0)
    if not sol.success:
        return ContinuumResult(False, _BVP_STATUS.get(sol.status, 4), sol.message,
                               {"e": e, "g": G}, mesh_size=int(sol.x.size),
                               wall_time_s=time.perf_counter() - t0, solution=sol)
    Lh, T, x = (float(v) for v in sol.p)
    slack = max(1e-6, 10.0 * tol)
    if x <= 0.0 or Lh <= 0.0 or not (-slack <= T <= 0.25 + slack) or np.any(sol.y[1] < -slack):
        return ContinuumResult(False, 4, f"non-physical loop branch (x = {x:.4g}, T = {T:.4g})",
                               {"e": e, "g": G}, mesh_size=int(sol.x.size),
                               wall_time_s=time.perf_counter() - t0, solution=sol)
    lv = _loop_values(sol, x, Lh, T)
    values = _master_values(x, G, e, n, h, B, mu, lv["lambda_over_R"], lv["aspect_ratio"])
    values["first_integral_spread"] = lv["first_integral_spread"]
    ok, status, message = _domain_message(values)
    resid = float(np.max(sol.rms_residuals))
    return ContinuumResult(ok, status, message, values, resid, int(sol.x.size),
                           time.perf_counter() - t0, sol)


def overhand_curve(e_values: Iterable[float], n, h: float, B: float, mu: float, *,
                   method: str = "table", **kwargs) -> list[ContinuumResult]:
    """Master curve ``F(e)`` (seed Eq. (5)) along ``e_values``, with continuation.

    Points are solved in the order given; each successful point seeds the next (bracket for
    ``"table"``/``"elliptic"``, initial mesh and parameters for ``"direct"``).  A failed
    point does not stop the sweep; the next one restarts without a seed.
    """
    out, prev = [], None
    for e in e_values:
        res = solve_overhand(e, n, h, B, mu, method=method, initial=prev, **kwargs)
        out.append(res)
        prev = res if res.success else None
    return out


def shortening_from_force(F: float, n, h: float, B: float, mu: float, *,
                          table: GTable | None = None, method: str = "table") -> float:
    """Inverse of Eq. (5): ``e = 8 sqrt(3) pi^2 n^2 h/g(x)`` with ``x`` from ``F`` (explicit).

    Raises ValueError for ``mu = 0`` (``x`` is undetermined: ``F = 0`` for every ``e``).
    """
    F = check_positive("F", F)
    n = check_n(n, what=_N_MEANS)
    h, B = check_positive("h", h), check_positive("B", B)
    mu = check_positive("mu", mu)
    x = (C5_FORCE * n * n * F * h * h / (mu * B)) ** (1.0 / 3.0)  # Eq. (5), argument of g
    g, x_hi = _g_callable(method, table)
    if x > x_hi:  # beyond the table: the closed form reaches further
        if x > X_MAX_CLOSED_FORM:
            raise ValueError(f"F = {F!r} too large: ell/R = {x:.4g} > {X_MAX_CLOSED_FORM:g}")
        g = g_closed_form
    return C5_SHORTENING * n * n * h / float(g(x))  # Eq. (5)


def aspect_ratio_curve(n2h_over_e: Sequence[float], *, table: GTable | None = None) -> np.ndarray:
    """Loop aspect ratio ``a = W/H`` as a function of ``n^2 h/e`` (seed Fig. 3, theory line)."""
    tab = table if table is not None else default_g_table()
    out = []
    for q in np.atleast_1d(np.asarray(n2h_over_e, dtype=float)):
        G = C5_SHORTENING * q  # Eq. (5)
        if not (0.0 < G < float(tab(tab.x_max))):
            out.append(math.nan)
            continue
        x = brentq(lambda xx, G=G: float(tab(xx)) - G, 0.0, tab.x_max, xtol=1e-13)
        out.append(float(tab.aspect_ratio_at(x)))
    return np.array(out)


# --------------------------------------------------------------------------- CLI / workflow
def cli_add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of the long-overhand-knot problem (SI defaults: the seed's Nitinol rods)."""
    parser.add_argument("--n", type=int, default=3, help="unknotting number n >= 1")
    parser.add_argument("--h", type=float, default=NITINOL_RADIUS_M,
                        help="rod radius h (default 0.127e-3, m)")
    parser.add_argument("--B", type=float, default=NITINOL_BENDING_N_M2,
                        help="bending stiffness B (default Nitinol E pi h^4/4, N m^2)")
    parser.add_argument("--mu", type=float, default=NITINOL_MU,
                        help="friction coefficient mu (default 0.119, seed)")
    parser.add_argument("--e", type=float, default=0.3,
                        help="end-to-end shortening e (same length unit as h; default 0.3)")
    parser.add_argument("--e-range", type=float, nargs=3, default=None,
                        metavar=("START", "STOP", "NUM"),
                        help="sweep e over numpy.linspace(START, STOP, NUM) with continuation")
    parser.add_argument("--method", choices=["table", "direct", "elliptic"], default="table",
                        help="how g is evaluated (BVP table, direct BVP, closed form)")


def cli_run(args) -> dict:
    """Solve the overhand-knot master curve for ``args``; JSON-serialisable summary."""
    t0 = time.perf_counter()
    n = check_n(args.n, what=_N_MEANS)
    out = {"problem": "overhand", "n": n, "h": float(args.h), "B": float(args.B),
           "mu": float(args.mu), "method": args.method, "k_bar": K_BAR,
           "w_c_helical": w_c_helical(n)}
    if args.e_range is not None:
        start, stop, num = args.e_range
        es = np.linspace(start, stop, int(num))
        res = overhand_curve(es, n, args.h, args.B, args.mu, method=args.method)
        out["points"] = [r.to_dict() for r in res]
        out["success"] = all(r.success for r in res)
    else:
        r = solve_overhand(args.e, n, args.h, args.B, args.mu, method=args.method)
        d = r.to_dict()
        out.update({k: d[k] for k in ("k", "wavelength", "g", "F", "R", "ell", "eps",
                                      "x_ell_over_R", "F_R2_over_B", "aspect_ratio")
                    if k in d})
        out["e"] = float(args.e)
        out["result"] = d
        out["success"] = bool(r.success)
        out["message"] = r.message
    out["wall_time_s"] = time.perf_counter() - t0
    return out


def convergence_table() -> list[dict]:
    """Error of ``g`` and of the master-curve ``F`` against tolerance / grid, with wall time.

    * ``loop_bvp``: :func:`solve_loop_elastica` at ``x = 1, 10, 50`` for ``tol`` from
      ``1e-2`` to ``1e-9`` (below ~1e-10 ``solve_bvp``'s mesh refinement stalls at x = 50); error ``|g - g_exact|/g_exact`` with ``g_exact`` the
      elliptic-integral closed form.
    * ``g_table``: spline of the BVP table (``tol = 1e-6``, nodes exact to ~1e-10; at
      ``tol = 1e-9`` the tables take ~1 min because ``solve_bvp`` stalls refining near
      ``x ~ 200``, for no gain) with 16 to 128 grid points;
      error = max relative error of ``g`` on 200 points in ``[0.05, 150]``.
    * ``master_F``: ``F`` at the seed's Nitinol parameters, ``n = 4``, ``e = 0.2 m``, by the
      table of each size and by the direct BVP, against the closed-form root.
    """
    rows: list[dict] = []
    for x in (1.0, 10.0, 50.0):
        g_ex = g_closed_form(x)
        for tol in (1e-2, 1e-4, 1e-6, 1e-8, 1e-9):
            r = solve_loop_elastica(x, tol=tol, n_nodes=11)
            err = abs(r.values["g"] - g_ex) / g_ex if r.success else math.nan
            rows.append({"problem": "loop_bvp", "setting": f"x={x:g},tol={tol:g}",
                         "mesh_nodes": r.mesh_size, "error": err, "success": r.success,
                         "wall_time_s": r.wall_time_s})
    xs_chk = np.geomspace(0.05, 150.0, 200)
    g_ex = np.array([g_closed_form(x) for x in xs_chk])
    e, n, h, B, mu = 0.2, 4, NITINOL_RADIUS_M, NITINOL_BENDING_N_M2, NITINOL_MU
    F_ex = solve_overhand(e, n, h, B, mu, method="elliptic").values["F"]
    for npts in (16, 32, 64, 128):
        tab = g_table(n_points=npts, tol=1e-6)
        err = float(np.max(np.abs(tab(xs_chk) - g_ex) / g_ex))
        rows.append({"problem": "g_table", "setting": f"n_points={npts}",
                     "mesh_nodes": tab.mesh_nodes, "error": err, "success": tab.success,
                     "wall_time_s": tab.wall_time_s})
        r = solve_overhand(e, n, h, B, mu, table=tab)
        rows.append({"problem": "master_F", "setting": f"table n_points={npts}",
                     "mesh_nodes": npts, "error": abs(r.values["F"] - F_ex) / F_ex,
                     "success": r.success, "wall_time_s": tab.wall_time_s + r.wall_time_s})
    for tol in (1e-3, 1e-5, 1e-7, 1e-9):
        r = solve_overhand(e, n, h, B, mu, method="direct", tol=tol)
        rows.append({"problem": "master_F", "setting": f"direct tol={tol:g}",
                     "mesh_nodes": r.mesh_size,
                     "error": abs(r.values["F"] - F_ex) / F_ex if r.success else math.nan,
                     "success": r.success, "wall_time_s": r.wall_time_s})
    return rows
