"""Two-ply: two elastic rods wound about a straight axis in hard contact (seed slides 15-19).

Geometry and conventions
------------------------
Two identical isotropic rods (bending stiffness ``B``, pN nm^2) of centre-line distance
``Delta = 2 r`` (nm) wind about a common straight axis (``z``).  Each strand is a curve on
the cylinder of radius ``r`` about the axis; ``theta(s)`` is the angle between a strand's
tangent and the axis (slide 16).  With ``psi`` the azimuth of the strand about the axis,

* ``psi' = sin(theta) / r``                       (cylindrical constraint, slide 16)
* ``kappa^2 = theta'^2 + sin(theta)^4 / r^2``     (geodesic + normal curvature, slide 16)
* ``D = int (1 - cos theta) ds``                  (end shortening, slide 16)
* ``R = int psi' ds``                             (end rotation, "ply link" ``R / 2 pi``)

**Handedness.**  ``theta > 0`` means ``psi`` increases along ``+z``: a *right-handed* ply;
``theta < 0`` is left-handed.  The braid angle of slides 4-5 is ``eta = -2 theta``
(slide 15), so a right-handed ply has ``eta < 0``.

**Chiral interaction** (slide 32, Kornyshev et al. 2007): ``phi = alpha tan(eta / 2)``
per unit contact length (pN), i.e. ``phi(theta) = -alpha tan(theta)``.  ``alpha > 0``
lowers ``eta`` (slide 32), i.e. favours right-handed plies (``theta > 0``).

Energy of the pair
------------------
Per unit strand arclength and for *both* strands together (twice slide 16's ``V`` per
strand, with ``phi`` added as on slide 15),

``e = B theta'^2 + U(theta)``, with
``U(theta) = B sin^4(theta)/r^2 + 2 C tau sin(theta) cos(theta)/r + phi(theta)
             + F (1 - cos theta) - M sin(theta)/r``                        (slides 15-16)

where ``F`` (pN) is the axial ply force, ``M`` (pN nm) the ply moment about the axis and
``C tau`` (pN nm) the (constant) twist moment of each strand (zero for nicked DNA).  Its
Euler-Lagrange equation is slide 17's equilibrium equation with the chiral term added:

``B theta'' = 2B/r^2 sin^3 cos + C tau/r cos 2theta + F/2 sin - M/(2r) cos + phi'/2``

and ``B theta'^2 - U(theta)`` is constant along a solution (slide 15's first integral,
multiplied by ``1/r^2``).  Fixed points ``U'(theta) = 0`` are uniform helical plies.

Lock-up
-------
The points of the two strands at equal height are closest-approach points (slide 5,
``|eta| < pi/2``) only while ``|theta| < pi/4``; beyond 45 degrees the strands would
interpenetrate (pitchfork at 45 degrees, slide 18).  At 45 degrees ``p / r = 2 pi`` (pitch
``p = 2 pi r / tan theta``), the densest packing (slide 18).  Solutions reaching
``|theta| >= pi/4`` are returned with ``success=False``, ``status=3``.
"""

from __future__ import annotations

import argparse
import logging
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import replace

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq

from dnabraid import forcefield
from dnabraid.continuum._result import ContinuumResult
from dnabraid.continuum._validate import check_finite, check_nonnegative, check_positive
from dnabraid.units import kT

logger = logging.getLogger(__name__)

#: Lock-up angle of the two-ply (slides 17-18), rad.
LOCKUP_ANGLE_RAD = math.pi / 4.0
#: Lock-up angle in degrees.
LOCKUP_ANGLE_DEG = 45.0
#: Pitch over radius at lock-up: the densest packing (slide 18).
LOCKUP_PITCH_OVER_RADIUS = 2.0 * math.pi
#: Persistence length used for the default bending stiffness, nm: ``persistence_nm`` of
#: ``forcefields/dna.toml`` (50 nm).
DEFAULT_PERSISTENCE_NM = forcefield.mechanics_parameters().persistence_nm
#: Default bending stiffness ``kT * DEFAULT_PERSISTENCE_NM`` at 298.15 K, pN nm^2.
DEFAULT_BENDING_PN_NM2 = kT(298.15) * DEFAULT_PERSISTENCE_NM
#: Angles closer than this to lock-up count as "at lock-up", rad.
LOCKUP_MARGIN_RAD = 1e-9

_BVP_STATUS = {0: 0, 1: 1, 2: 2, 3: 4}


# --------------------------------------------------------------------------- geometry
def chiral_potential(theta, alpha_pN: float):
    """Chiral interaction per unit contact length, ``phi = alpha tan(eta/2)``, pN (slide 32).

    Parameters
    ----------
    theta : float or ndarray
        Ply angle, rad (``eta = -2 theta``, slide 15).
    alpha_pN : float
        Chiral strength, pN (energy per unit length).

    Returns
    -------
    float or ndarray
        ``-alpha tan(theta)``, pN.
    """
    eta = -2.0 * np.asarray(theta)  # slide 15
    return alpha_pN * np.tan(eta / 2.0)  # slide 32


def chiral_potential_derivative(theta, alpha_pN: float):
    """``d phi / d theta = -alpha / cos^2 theta``, pN."""
    return -alpha_pN / np.cos(theta) ** 2


def pitch_over_radius(theta) -> float:
    """Pitch (axial rise per full turn of one strand) over ply radius, ``2 pi / tan|theta|``.

    Equals ``2 pi`` at lock-up (slide 18).
    """
    return 2.0 * math.pi / math.tan(abs(theta))


def helix_angle_from_pitch(pitch_nm: float, radius_nm: float) -> float:
    """Ply angle ``theta = atan(2 pi r / p)`` (rad) of a helix of pitch ``p`` and radius ``r``."""
    return math.atan2(2.0 * math.pi * radius_nm, pitch_nm)


def packing_fraction(theta) -> float:
    """Volume fraction of two tubes of radius ``r`` inside the enclosing cylinder ``2 r``.

    ``2 pi r^2 (1/cos theta) / (pi (2r)^2) = 1 / (2 cos theta)``: grows with ``|theta|``, so the
    densest admissible ply is the lock-up ply, ``1/sqrt(2)`` at 45 degrees (slide 18).
    """
    return 1.0 / (2.0 * math.cos(theta))


def interstrand_distance_min(theta: float, delta_nm: float, n_samples: int = 4001) -> float:
    """Least distance between the two helices of a uniform ply (numerical), nm.

    Strand 1 at ``(r, 0, 0)``, strand 2 at ``(-r, 0, 0)``; the helices have angle
    ``theta``.  For ``|theta| < 45 deg`` the points at equal height are the closest
    (distance ``Delta``); beyond lock-up the strands come closer than ``Delta`` (slide 18's
    pitchfork), which this function lets a test see without using the formula.
    """
    r = 0.5 * delta_nm
    if abs(theta) < 1e-12:
        return delta_nm
    c = r / math.tan(abs(theta))  # axial rise per radian
    phi = np.linspace(-math.pi, math.pi, n_samples)
    d2 = 2.0 * r * r * (1.0 + np.cos(phi)) + (c * phi) ** 2
    return float(np.sqrt(d2.min()))


def free_ply_twist_moment(theta, delta_nm: float, bending_pN_nm2: float = DEFAULT_BENDING_PN_NM2):
    """Uniform ply held by strand twist alone (``F = M = 0``), slide 17.

    Returns
    -------
    tuple of float
        ``(C tau, V, T)``: the twist moment ``C tau = -2B sin^3 cos / (r cos 2 theta)``
        (pN nm), ``V = C tau / (2 r)`` and ``T = V tan theta`` (pN), as printed on slide 17.
        All diverge as ``theta -> 45 deg`` (lock-up).
    """
    r = 0.5 * delta_nm
    s, c = math.sin(theta), math.cos(theta)
    c_tau = -2.0 * bending_pN_nm2 * s**3 * c / (r * math.cos(2.0 * theta))  # slide 17
    v = c_tau / (2.0 * r)  # slide 17
    return c_tau, v, v * math.tan(theta)  # slide 17


# --------------------------------------------------------------------------- energy density
def ply_potential(theta, force_pN, torque_pN_nm, delta_nm, bending_pN_nm2=DEFAULT_BENDING_PN_NM2,
                  alpha_pN=0.0, twist_moment_pN_nm=0.0):
    """``U(theta)`` of the pair per unit strand length, pN (slides 15-16, module docstring)."""
    r = 0.5 * delta_nm
    th = np.asarray(theta, dtype=float)
    s, c = np.sin(th), np.cos(th)
    return (bending_pN_nm2 * s**4 / r**2  # slide 16: B kappa^2 (normal curvature)
            + 2.0 * twist_moment_pN_nm * s * c / r  # slide 15: C r tau sin 2 theta
            + chiral_potential(th, alpha_pN)  # slide 32
            + force_pN * (1.0 - c)  # slide 16: F D
            - torque_pN_nm * s / r)  # slide 16: -M R


def ply_potential_derivative(theta, force_pN, torque_pN_nm, delta_nm,
                             bending_pN_nm2=DEFAULT_BENDING_PN_NM2, alpha_pN=0.0,
                             twist_moment_pN_nm=0.0):
    """``U'(theta)``, pN; ``2 B theta'' = U'(theta)`` is twice slide 17's equation."""
    r = 0.5 * delta_nm
    th = np.asarray(theta, dtype=float)
    s, c = np.sin(th), np.cos(th)
    return (4.0 * bending_pN_nm2 * s**3 * c / r**2  # slide 17: 2B/r^2 sin^3 cos (x2)
            + 2.0 * twist_moment_pN_nm * np.cos(2.0 * th) / r  # slide 17: C tau/r cos 2theta
            + chiral_potential_derivative(th, alpha_pN)  # slide 32
            + force_pN * s  # slide 17: F/2 sin (x2)
            - torque_pN_nm * c / r)  # slide 17: -M/(2r) cos (x2)


def _ply_potential_second(theta, force_pN, torque_pN_nm, delta_nm, bending_pN_nm2, alpha_pN,
                          twist_moment_pN_nm):
    r = 0.5 * delta_nm
    s, c = math.sin(theta), math.cos(theta)
    return (4.0 * bending_pN_nm2 * (3.0 * s**2 * c**2 - s**4) / r**2
            - 4.0 * twist_moment_pN_nm * math.sin(2.0 * theta) / r
            - 2.0 * alpha_pN * s / c**3
            + force_pN * c + torque_pN_nm * s / r)


def fixed_point_torque(theta, force_pN, delta_nm, bending_pN_nm2=DEFAULT_BENDING_PN_NM2,
                       alpha_pN=0.0, twist_moment_pN_nm=0.0):
    """Ply moment ``M`` (pN nm) that makes ``theta`` a uniform helical ply (slide 17).

    Solves ``U'(theta) = 0`` for ``M``:
    ``M = 4B sin^3/r + 2 C tau cos 2theta / cos + F r tan - alpha r / cos^3``.
    """
    r = 0.5 * delta_nm
    th = np.asarray(theta, dtype=float)
    s, c = np.sin(th), np.cos(th)
    return (4.0 * bending_pN_nm2 * s**3 * c / r**2 + 2.0 * twist_moment_pN_nm * np.cos(2 * th) / r
            + chiral_potential_derivative(th, alpha_pN) + force_pN * s) * r / c  # slide 17


def uniform_ply_contact_force(theta, force_pN, delta_nm, bending_pN_nm2=DEFAULT_BENDING_PN_NM2,
                              alpha_pN=0.0):
    """Interstrand contact force per unit strand length of a uniform ply (``C tau = 0``), pN/nm.

    ``p = -dg/dDelta`` at fixed axial length, ply rotation and fixed ``phi`` (virtual work),
    ``p = sin(theta)/(2 r^2) [2 B sin^3/r + F r tan - alpha r / cos^3]``; for ``alpha = 0``
    this equals Kirchhoff's ``kappa (n_t + B tau^2)`` for a helix.  ``p >= 0`` is the
    hard-contact condition of slide 14; ``p < 0`` (only possible with ``alpha`` favouring
    the ply's hand) means the contact holds only if the chiral interaction is adhesive.
    """
    r = 0.5 * delta_nm
    s, c = math.sin(theta), math.cos(theta)
    return s / (2 * r * r) * (2 * bending_pN_nm2 * s**3 / r + force_pN * r * s / c
                              - alpha_pN * r / c**3)


# --------------------------------------------------------------------------- uniform ply
def solve_uniform_ply(force_pN: float, torque_pN_nm: float, delta_nm: float, *,
                      bending_pN_nm2: float = DEFAULT_BENDING_PN_NM2, alpha_pN: float = 0.0,
                      twist_moment_pN_nm: float = 0.0, n_grid: int = 2001,
                      xtol: float = 1e-14,
                      initial: ContinuumResult | None = None) -> ContinuumResult:
    """Uniform helical ply under ply force ``F`` and moment ``M`` (fixed points, slide 17).

    Finds all roots of ``U'(theta) = 0`` in ``(-45, 45)`` degrees (module docstring) and
    returns the stable one (``U'' > 0``) of lowest ``U``.  With ``initial`` (a previous
    result) the root nearest its ``theta`` is preferred when it is still stable
    (continuation along a branch).

    Parameters
    ----------
    force_pN : float
        Axial ply force ``F >= 0``, pN.
    torque_pN_nm : float
        Ply moment ``M`` about the axis, pN nm (positive winds right-handed).
    delta_nm : float
        Centre-line distance in contact ``Delta = 2 r``, nm.
    bending_pN_nm2, alpha_pN, twist_moment_pN_nm : float
        ``B`` (pN nm^2), chiral strength ``alpha`` (pN), strand twist moment ``C tau`` (pN nm).
    n_grid : int
        Grid points used to bracket roots (the "mesh size").
    xtol : float
        Root tolerance in ``theta``, rad.
    initial : ContinuumResult, optional
        Previous solution for continuation.

    Returns
    -------
    ContinuumResult
        ``values``: ``theta_rad``, ``theta_deg``, ``eta_rad``, ``pitch_nm``,
        ``pitch_over_radius``, ``extension_per_length`` (``cos theta``),
        ``ply_turns_per_nm`` (per strand arclength), ``potential_pN`` (``U``),
        ``stiffness_pN`` (``U''``), ``contact_force_pN_per_nm`` (``C tau = 0`` only, else nan),
        ``packing_fraction``.  ``status=3`` when no stable ply exists below lock-up.
    """
    t0 = time.perf_counter()
    force_pN = check_nonnegative("force_pN", force_pN)
    torque_pN_nm = check_finite("torque_pN_nm", torque_pN_nm)
    delta_nm = check_positive("delta_nm", delta_nm)
    bending_pN_nm2 = check_positive("bending_pN_nm2", bending_pN_nm2)
    alpha_pN = check_finite("alpha_pN", alpha_pN)
    twist_moment_pN_nm = check_finite("twist_moment_pN_nm", twist_moment_pN_nm)
    if int(n_grid) < 3:
        raise ValueError(f"n_grid must be >= 3, got {n_grid!r}")
    args = (force_pN, torque_pN_nm, delta_nm, bending_pN_nm2, alpha_pN, twist_moment_pN_nm)

    def dU(t):
        return float(ply_potential_derivative(t, *args))

    lim = LOCKUP_ANGLE_RAD - LOCKUP_MARGIN_RAD
    grid = np.linspace(-lim, lim, int(n_grid))
    vals = ply_potential_derivative(grid, *args)
    roots = []
    for i in range(len(grid) - 1):
        if vals[i] == 0.0:
            roots.append(float(grid[i]))
        elif vals[i] * vals[i + 1] < 0.0:
            roots.append(brentq(dU, grid[i], grid[i + 1], xtol=xtol, rtol=4 * np.finfo(float).eps))
    stable = [t for t in roots if _ply_potential_second(t, *args) > 0.0]
    wall = time.perf_counter() - t0
    if not stable:
        edge = "right" if vals[-1] < 0 else "left"
        msg = (f"no stable uniform ply below lock-up (45 deg): U' keeps one sign towards the "
               f"{edge}-handed lock-up for F={force_pN} pN, M={torque_pN_nm} pN nm, "
               f"alpha={alpha_pN} pN")
        return ContinuumResult(False, 3, msg, {}, math.nan, int(n_grid), wall)
    if initial is not None and "theta_rad" in initial.values:
        theta = min(stable, key=lambda t: abs(t - initial.values["theta_rad"]))
    else:
        theta = min(stable, key=lambda t: float(ply_potential(t, *args)))
    r = 0.5 * delta_nm
    contact = (uniform_ply_contact_force(theta, force_pN, delta_nm, bending_pN_nm2, alpha_pN)
               if twist_moment_pN_nm == 0.0 else math.nan)
    values = {
        "theta_rad": theta,
        "theta_deg": math.degrees(theta),
        "eta_rad": -2.0 * theta,
        "pitch_nm": 2 * math.pi * r / abs(math.tan(theta)) if theta != 0 else math.inf,
        "pitch_over_radius": pitch_over_radius(theta) if theta != 0 else math.inf,
        "extension_per_length": math.cos(theta),
        "ply_turns_per_nm": math.sin(theta) / (2 * math.pi * r),
        "potential_pN": float(ply_potential(theta, *args)),
        "stiffness_pN": _ply_potential_second(theta, *args),
        "contact_force_pN_per_nm": contact,
        "packing_fraction": packing_fraction(theta),
        "n_stable_roots": len(stable),
    }
    msg = "converged"
    if contact < 0:
        msg += ("; contact force < 0: contact holds only if the chiral interaction is "
                "adhesive (vanishes on separation)")
    return ContinuumResult(True, 0, msg, values, abs(dU(theta)), int(n_grid), wall)


# --------------------------------------------------------------------------- ply with ends
def solve_ply_bvp(length_nm: float, force_pN: float, delta_nm: float, *,
                  torque_pN_nm: float | None = None, ply_link: float | None = None,
                  bc: str = "clamped", theta_end_rad: float = 0.0,
                  bending_pN_nm2: float = DEFAULT_BENDING_PN_NM2, alpha_pN: float = 0.0,
                  twist_moment_pN_nm: float = 0.0, tol: float = 1e-6, max_nodes: int = 100000,
                  n_initial: int | None = None,
                  initial: ContinuumResult | None = None) -> ContinuumResult:
    """Ply with ends: the ``theta(s)`` boundary-value problem on ``0 <= s <= L`` (slides 16-17).

    Solves ``2 B theta'' = U'(theta)`` (slide 17's equation times two, chiral term of slide 32
    included; see the module docstring) together with ``R' = sin(theta)/r``,
    ``D' = 1 - cos theta`` (slide 16) and the energy
    ``E' = B theta'^2 + B sin^4/r^2 + 2 C tau sin cos / r + phi``.

    Exactly one of ``torque_pN_nm`` (ply moment ``M`` given) and ``ply_link`` (``R(L) / 2 pi``
    given; ``M`` becomes an unknown parameter, the Lagrange multiplier of the link) must be
    set.  Boundary conditions: ``bc="clamped"``: ``theta(0) = theta(L) = theta_end_rad``
    (strands enter along the axis for 0); ``bc="free"``: ``theta'(0) = theta'(L) = 0``
    (natural conditions for ends free to pivot, e.g. nicked tethers in contact).

    Parameters
    ----------
    length_nm : float
        Strand arclength ``L`` of the ply, nm.
    force_pN : float
        Axial ply force ``F >= 0``, pN.
    delta_nm : float
        Contact distance ``Delta = 2 r``, nm.
    tol, max_nodes : float, int
        Passed to :func:`scipy.integrate.solve_bvp`.
    n_initial : int, optional
        Nodes of the initial mesh (default from the boundary-layer width).
    initial : ContinuumResult, optional
        Previous solution (continuation): its ``solution`` (a ``BVPResult``) seeds the mesh,
        ``theta(s)`` and, for prescribed link, ``M``.

    Returns
    -------
    ContinuumResult
        ``values``: ``torque_pN_nm``, ``ply_link``, ``end_shortening_nm``, ``extension_nm``
        (``L - D``), ``energy_pN_nm`` (elastic + chiral, no load terms), ``theta_mid_rad``,
        ``theta_max_rad``, ``hamiltonian_spread_pN`` (variation of ``B theta'^2 - U``, zero
        for an exact solution).  ``status=3`` if ``|theta|`` reaches lock-up.
    """
    t0 = time.perf_counter()
    L = check_positive("length_nm", length_nm)
    F = check_nonnegative("force_pN", force_pN)
    delta_nm = check_positive("delta_nm", delta_nm)
    B = check_positive("bending_pN_nm2", bending_pN_nm2)
    alpha = check_finite("alpha_pN", alpha_pN)
    c_tau = check_finite("twist_moment_pN_nm", twist_moment_pN_nm)
    theta_end = check_finite("theta_end_rad", theta_end_rad)
    if (torque_pN_nm is None) == (ply_link is None):
        raise ValueError("give exactly one of torque_pN_nm and ply_link")
    if bc not in ("clamped", "free"):
        raise ValueError(f"bc must be 'clamped' or 'free', got {bc!r}")
    if abs(theta_end) >= LOCKUP_ANGLE_RAD:
        raise ValueError(f"|theta_end_rad| must be below lock-up (pi/4), got {theta_end}")
    tol = check_positive("tol", tol)
    r = 0.5 * delta_nm
    prescribed = ply_link is not None
    link = check_finite("ply_link", ply_link) if prescribed else None
    if prescribed and abs(2 * math.pi * link * r) >= L * math.sin(LOCKUP_ANGLE_RAD):
        wall = time.perf_counter() - t0
        return ContinuumResult(False, 3, f"ply link {link} needs |theta| >= 45 deg over "
                               f"L={L} nm: past lock-up", {}, math.nan, 0, wall)

    def dU(theta, M):
        return ply_potential_derivative(theta, F, M, delta_nm, B, alpha, c_tau)

    def fun(x, y, p=()):
        M = p[0] if prescribed else torque_pN_nm
        th = y[0]
        s, c = np.sin(th), np.cos(th)
        w = y[1] / L  # theta' in 1/nm
        return np.vstack([
            y[1],
            L * L * dU(th, M) / (2.0 * B),  # slide 17 (x2): 2 B theta'' = U'
            L * s / r,  # slide 16: psi' = sin(theta)/r
            L * (1.0 - c),  # slide 16: D
            L * (B * w * w + B * s**4 / r**2 + 2 * c_tau * s * c / r
                 + chiral_potential(th, alpha)),  # slides 15-16, 32
        ])

    def bcfun(ya, yb, p=()):
        if bc == "clamped":
            res = [ya[0] - theta_end, yb[0] - theta_end]
        else:
            res = [ya[1], yb[1]]
        res += [ya[2], ya[3], ya[4]]
        if prescribed:
            res.append(yb[2] - 2 * math.pi * link)
        return np.array(res)

    # ---- initial guess
    p0 = None
    if prescribed:
        theta_s = math.asin(2 * math.pi * link * r / L)
        M0 = float(fixed_point_torque(theta_s, F, delta_nm, B, alpha, c_tau))
        p0 = np.array([M0])
    else:
        M0 = float(torque_pN_nm)
        uni = solve_uniform_ply(F, M0, delta_nm, bending_pN_nm2=B, alpha_pN=alpha,
                                twist_moment_pN_nm=c_tau, n_grid=401)
        theta_s = uni.values["theta_rad"] if uni.success else math.copysign(
            0.9 * LOCKUP_ANGLE_RAD, M0)
    curv = abs(_ply_potential_second(theta_s, F, M0, delta_nm, B, alpha, c_tau))
    lam = math.sqrt(2 * B / max(curv, 1e-12))  # boundary-layer width, nm
    lam = min(lam, L / 4)
    n0 = int(n_initial) if n_initial else int(min(max(60, 12 * L / lam), 5000))
    if n0 < 3:
        raise ValueError(f"n_initial must be >= 3, got {n_initial!r}")
    x0 = np.linspace(0.0, 1.0, n0)
    prev = getattr(initial, "solution", None) if initial is not None else None
    if prev is not None and getattr(prev, "sol", None) is not None:
        # continuation: previous solution resampled on a fresh, coarse mesh (solve_bvp only
        # ever adds nodes, so reusing the old mesh would make it grow along a branch)
        if not n_initial:
            x0 = np.linspace(0.0, 1.0, 100)
        y0 = np.asarray(prev.sol(x0))
        if prescribed and "torque_pN_nm" in initial.values:
            p0 = np.array([initial.values["torque_pN_nm"]])
            old = initial.values.get("ply_link", 0.0)
            if old:  # rescale the previous rotation to the new link (secant predictor)
                y0[2] *= link / old
    else:
        if bc == "clamped":
            prof = (1 - np.exp(-x0 * L / lam)) * (1 - np.exp(-(1 - x0) * L / lam))
            th0 = theta_end + (theta_s - theta_end) * prof
        else:
            th0 = np.full_like(x0, theta_s)
        y0 = np.zeros((5, n0))
        y0[0] = th0
        y0[1] = np.gradient(th0, x0)
        y0[2] = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(th0[1:]) + np.sin(th0[:-1]))
                                                 * np.diff(x0))]) * L / r
        y0[3] = np.concatenate([[0.0], np.cumsum(0.5 * (2 - np.cos(th0[1:]) - np.cos(th0[:-1]))
                                                 * np.diff(x0))]) * L
    try:
        sol = solve_bvp(fun, bcfun, x0, y0, p=p0, tol=tol, max_nodes=int(max_nodes))
    except (ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:
        wall = time.perf_counter() - t0
        return ContinuumResult(False, 4, f"solve_bvp raised: {exc}", {}, math.nan, len(x0), wall)
    wall = time.perf_counter() - t0
    M = float(sol.p[0]) if prescribed else float(torque_pN_nm)
    y = sol.y
    theta_max = float(np.max(np.abs(y[0])))
    xs = np.linspace(0, 1, 2001)
    ys = sol.sol(xs)
    ham = B * (ys[1] / L) ** 2 - ply_potential(ys[0], F, M, delta_nm, B, alpha, c_tau)
    values = {
        "torque_pN_nm": M,
        "ply_link": float(y[2, -1] / (2 * math.pi)),
        "end_shortening_nm": float(y[3, -1]),
        "extension_nm": float(L - y[3, -1]),
        "energy_pN_nm": float(y[4, -1]),
        "theta_mid_rad": float(sol.sol(0.5)[0]),
        "theta_max_rad": theta_max,
        "hamiltonian_spread_pN": float(np.ptp(ham)),
        "length_nm": L,
    }
    residual = float(np.max(sol.rms_residuals)) if sol.rms_residuals is not None else math.nan
    residual = max(residual, float(np.max(np.abs(bcfun(y[:, 0], y[:, -1], sol.p if prescribed
                                                        else ())))))
    if theta_max >= LOCKUP_ANGLE_RAD:
        return ContinuumResult(False, 3, f"|theta| reaches {math.degrees(theta_max):.3f} deg "
                               f">= 45 deg (lock-up): outside the hard-contact ply model",
                               values, residual, sol.x.size, wall, sol)
    if not sol.success:
        return ContinuumResult(False, _BVP_STATUS.get(sol.status, 4), f"solve_bvp: {sol.message}",
                               values, residual, sol.x.size, wall, sol)
    return ContinuumResult(True, 0, f"converged ({sol.message})", values, residual, sol.x.size,
                           wall, sol)


# --------------------------------------------------------------------------- continuation
def continuation(solve: Callable[..., ContinuumResult], parameter: str, values: Iterable[float],
                 stop_on_failure: bool = True, **kwargs) -> list[ContinuumResult]:
    """Natural-parameter continuation: step ``parameter`` through ``values``, reusing the last
    converged solution as ``initial`` of the next solve.

    Parameters
    ----------
    solve : callable
        A solver of this package accepting ``initial=`` (e.g. :func:`solve_ply_bvp`).
    parameter : str
        Keyword argument stepped (e.g. ``"ply_link"``, ``"alpha_pN"``).
    values : iterable of float
        Parameter values in order.
    stop_on_failure : bool
        Stop after the first failed step (its result is included).
    **kwargs
        Other fixed arguments of ``solve``.

    Returns
    -------
    list of ContinuumResult
        One per attempted value; ``values["continuation_parameter"]`` records the value.
    """
    out: list[ContinuumResult] = []
    last = kwargs.pop("initial", None)
    for v in values:
        res = solve(**{**kwargs, parameter: v}, initial=last)
        res = replace(res, values={**res.values, "continuation_parameter": float(v)})
        out.append(res)
        if res.success:
            last = res
        elif stop_on_failure:
            logger.debug("continuation stopped at %s=%s: %s", parameter, v, res.message)
            break
    return out


# --------------------------------------------------------------------------- CLI / workflow
def cli_add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of the two-ply problem (uniform ply, or ply with ends when ``--length-nm``)."""
    parser.add_argument("--force-pN", type=float, default=1.0, help="axial ply force F, pN")
    parser.add_argument("--torque-pN-nm", type=float, default=None,
                        help="ply moment M, pN nm (uniform ply, or BVP with given torque)")
    parser.add_argument("--ply-link", type=float, default=None,
                        help="prescribed ply link R/2pi (BVP; M becomes unknown)")
    parser.add_argument("--delta-nm", type=float, default=5.0, help="contact distance 2r, nm")
    parser.add_argument("--alpha-pN", type=float, default=0.0, help="chiral strength alpha, pN")
    parser.add_argument("--bending-pN-nm2", type=float, default=DEFAULT_BENDING_PN_NM2,
                        help="bending stiffness B, pN nm^2 (default kT x persistence_nm "
                             "of forcefields/dna.toml)")
    parser.add_argument("--twist-moment-pN-nm", type=float, default=0.0,
                        help="strand twist moment C tau, pN nm (0 for nicked DNA)")
    parser.add_argument("--length-nm", type=float, default=None,
                        help="strand length L, nm: solve the ply with ends theta(s)")
    parser.add_argument("--bc", choices=["clamped", "free"], default="clamped",
                        help="end conditions of the ply with ends")
    parser.add_argument("--tol", type=float, default=1e-6, help="solve_bvp tolerance")


def cli_run(args) -> dict:
    """Run the ply problem chosen by ``args``; JSON-serialisable summary."""
    common = {"bending_pN_nm2": args.bending_pN_nm2, "alpha_pN": args.alpha_pN,
                  "twist_moment_pN_nm": args.twist_moment_pN_nm}
    if args.length_nm is None:
        torque = 0.0 if args.torque_pN_nm is None else args.torque_pN_nm
        res = solve_uniform_ply(args.force_pN, torque, args.delta_nm, **common)
        out = {"problem": "uniform_ply", **res.to_dict()}
    else:
        torque = args.torque_pN_nm
        if torque is None and args.ply_link is None:
            torque = 0.0
        res = solve_ply_bvp(args.length_nm, args.force_pN, args.delta_nm, torque_pN_nm=torque,
                            ply_link=args.ply_link, bc=args.bc, tol=args.tol, **common)
        out = {"problem": "ply_bvp", **res.to_dict()}
    return out


def convergence_table() -> list[dict]:
    """Error of the ply-with-ends BVP against tolerance (and mesh), with wall time.

    Problem: clamped ply (``theta = 0`` at both ends), ``L = 400 nm``, ``Delta = 5 nm``,
    ``F = 2 pN``, prescribed ply link 10, ``B = kT x 50 nm``.  Error: largest of the
    differences in torque (pN nm) and extension (nm) from a reference at ``tol = 1e-8``
    (initial mesh 40 nodes, so the mesh grows with the tolerance),
    and the first-integral spread ``max - min (B theta'^2 - U)`` (exact: 0).  Also the
    uniform-ply root finder against the exact inverse ``M(theta)`` of slide 17.
    """
    rows: list[dict] = []
    kw = {"ply_link": 10.0, "bc": "clamped", "max_nodes": 200000, "n_initial": 40}
    ref = solve_ply_bvp(400.0, 2.0, 5.0, tol=1e-8, **kw)
    for tol in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6):
        res = solve_ply_bvp(400.0, 2.0, 5.0, tol=tol, **kw)
        err = max(abs(res.values["torque_pN_nm"] - ref.values["torque_pN_nm"]),
                  abs(res.values["extension_nm"] - ref.values["extension_nm"]))
        rows.append({"problem": "ply_bvp_clamped", "setting": f"tol={tol:g}",
                     "mesh_nodes": res.mesh_size, "error": err,
                     "first_integral_spread_pN": res.values["hamiltonian_spread_pN"],
                     "success": res.success, "wall_time_s": res.wall_time_s})
    theta_exact = 0.5
    M = float(fixed_point_torque(theta_exact, 2.0, 5.0))
    for n_grid in (11, 101, 1001):
        for xtol in (1e-4, 1e-8, 1e-14):
            res = solve_uniform_ply(2.0, M, 5.0, n_grid=n_grid, xtol=xtol)
            rows.append({"problem": "uniform_ply", "setting": f"n_grid={n_grid},xtol={xtol:g}",
                         "mesh_nodes": n_grid, "error": abs(res.values["theta_rad"] - theta_exact),
                         "success": res.success, "wall_time_s": res.wall_time_s})
    return rows
