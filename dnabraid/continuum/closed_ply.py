"""Closed two-ply: torus links and torus knots in hard contact (van der Heijden, elastic braids, slides 19-23).

Everything here is scale free: lengths in units of the strand length ``L``, the pressure
(contact force per unit strand length) in ``B/L^3``, forces in ``B/L^2``, moments in ``B/L``,
energies in ``B/L`` (``B`` the bending stiffness of each strand).  Key suffixes say so
(``_over_L``, ``_B_per_L3`` ...).  Seed: van der Heijden, "Equilibrium theory of elastic
braids" (talk; Starostin & van der Heijden, J. Mech. Phys. Solids 64, 83 (2014)).

What is closed
--------------
Two strands of length ``L`` each, in hard contact at centre-line distance ``Delta = 2r``,
wind about a circular axis (the *ply axis*) of radius ``R``:

* ``topology="link"``: the ``(2, 2n)`` torus link; each strand is one ring (slide 20,
  ``Lk = -n``, ``n = 1..5``).
* ``topology="knot"``: the ``(n, 2)`` torus knot, ``n`` odd; the two strands are the two
  halves of one ring of length ``2L`` that close into each other (slide 22, ``Lk = -n/2``).

Both are left-handed as in the seed: Gauss linking number ``-n`` for the link, and braid
angle ``eta > 0`` (van der Heijden's sign, slide 5: ``eta`` is the angle from ``t1`` to
``t2`` about the chord ``d1``; for a left-handed ply ``eta = +2 theta``, see
:func:`dnabraid.geometry.curves.crossing_angles`; slide 21 shows ``eta ~ +0.509``).

Uniform closed ply (leading order)
----------------------------------
Let ``theta`` be each strand's helix angle to the ply axis and ``psi`` the azimuth of the
chord about the axis.  The cylindrical constraint of slide 16, ``psi' = sin(theta)/r`` per
unit strand arclength, integrated over one circuit of the axis (one strand length ``L``):

    ``Delta psi = L sin(theta) / r``.

*Link*: each strand must come back to itself after one circuit of the axis, and the two
strands of a ``(2, 2n)`` torus link cross ``2n`` times, i.e. the chord makes ``n`` full turns
(a full turn of a two-ply is two crossings, the braid word ``sigma^2``):
``Delta psi = 2 pi n``.  (Each strand makes ``n`` full turns about the axis, not ``n/2``: for
the Hopf link, ``n = 1``, the two rings are the ``(1, 1)`` Villarceau curves of the torus.)
The axis is a planar circle: its writhe is 0 and its in-plane normal is a parallel frame, so
the chord's turns are the twist of the ribbon (axis, chord) and ``|Lk| = n`` (White's
formula).  *Knot*: strand 1 must arrive at strand 2's start after one circuit, so the chord
turns by an odd multiple of ``pi``: ``Delta psi = pi n`` (``n`` crossings, ply link ``n/2``,
the seed's ``Lk = -n/2``).  With ``m`` the number of chord turns per circuit (``m = n`` for a
link, ``m = n/2`` for a knot):

    ``sin(theta) = 2 pi m r / L = pi m Delta / L``                           (1)

which is the brief's ``sin theta = pi n Delta / L`` for links, and ``pi (n/2) Delta / L`` for
knots.  The braid angle is ``eta = 2 theta`` (slide 15, ``theta = -eta/2`` up to the sign of
the hand); the axis has length ``L cos(theta)`` (strand arclength projected on the axis), so
``R = L cos(theta) / (2 pi)``; the pitch (axial rise per full turn of a strand) is
``2 pi r / tan(theta) = L cos(theta) / m``.  ``theta`` must stay below the two-ply lock-up
``45 deg`` (slides 17-18; past it the points at equal axial position are no longer closest
points) and the axis ring must leave room for the tube (``R >= 2 r``: the inner strands on
opposite sides of the hole would overlap), so ``n`` that do not fit are refused.

What holds a free closed ply (``F = M_ext = 0``, no twist)
----------------------------------------------------------
Isotropic strands whose material frames are not closed (or nicked DNA) carry no twisting
moment (``C tau = 0``).  A straight uniform two-ply without twist unwinds unless a ply
moment holds it (slide 17: ``U'(theta) != 0`` at ``F = M = C tau = 0``).  In the closed ply
the topology holds it: the total chord rotation ``L sin(theta)/r = 2 pi m`` and the strand
length are fixed, so ``theta`` is fixed by (1); the end shortening is free, so the axial force
vanishes (``F = 0``), and the ply moment is the Lagrange multiplier of the link constraint,
:func:`dnabraid.continuum.ply.fixed_point_torque` at ``F = 0``:

    ``M = 4 B sin^3(theta) / r``      (both strands, about the axis)

Each strand is a helix with curvature ``kappa = sin^2/r`` and torsion ``tau = sin cos / r``;
with the bending moment ``B kappa b`` only, Kirchhoff's moment balance gives the binormal
shear ``-B kappa tau``, zero axial force gives the tension ``T = B kappa tau tan(theta) =
B sin^4/r^2``, and the normal balance gives the contact pressure (slide 14's ``p``; the same
as :func:`dnabraid.continuum.ply.uniform_ply_contact_force` at ``F = alpha = 0``)

    ``p0 = kappa (T + B tau^2) = B sin^4(theta) / r^3 = 8 pi^4 m^4 (Delta/L) B / L^3``.   (2)

It is also the virtual work of the bending energy ``E = B L sin^4/r^2`` of both strands at
fixed ``L`` and ``m``: ``p0 = (1/L) dE/dDelta``.  On the ring, the ply moment about the local
axis tangent is balanced (as in Michell's twisted ring) by a constant shear force
``M / R`` along the ring's symmetry axis (``M' = -(M/R) e_R`` needs ``e_u x F = (M/R) e_R``).

Curvature of the axis (torus helix)
-----------------------------------
The strands of the uniform closed ply lie on a torus of radii ``R`` and ``r``: strand ``j``
is ``x(u) = ((R + r cos phi) cos u, (R + r cos phi) sin u, r sin phi)`` with ``phi = m u +
j pi`` (``u`` the angle about the ring's symmetry axis; for the knot, one ring with
``u in [0, 4 pi)``).  Points at equal ``u`` are exact closest-approach points at distance
``Delta`` (the chord is ``r e_r(phi)``, normal to both tangents).  Write ``eps = r/R``
(``= pi (Delta/L)/cos(theta)`` to leading order; 0.065 for the seed's 4-link) and
``tan(theta_R) = r m / R``.  The strands feel the axis curvature ``1/R`` besides the helix
curvature ``sin^2/r``; their ratio is ``eps / sin^2(theta) = 1/(m sin cos)``, about 1 for the
seed's cases, so the corrections below carry large coefficients ``1/m^2 = eps^2/tan^2``.

* **Length.**  ``L = 2 pi <sqrt((R + r cos phi)^2 + r^2 m^2)>_phi`` exactly;
  ``L = 2 pi A (1 + eps^2 cos^2 sin^2 / 4 + ...)`` with ``A = sqrt(R^2 + r^2 m^2)``, so
  ``theta_R = theta + eps^2 sin^3 cos / 4`` (second order) and ``R = L cos(theta)/(2 pi)``
  to first order.
* **Braid angle** (exact on the torus): ``eta(phi) = atan(k/(1 + eps cos phi)) +
  atan(k/(1 - eps cos phi))``, ``k = tan(theta_R)``.  Exchanging the strands (``phi -> phi +
  pi``) leaves it unchanged, so there is no first-order term:

      ``eta = 2 theta_R + 2 sin cos^3 eps^2 cos^2(phi) + O(eps^4)``              (3)

  of period ``pi`` in ``phi``: ``2n`` periods along a link's ring (slide 21: "eta is
  period-2n"), mean ``2 theta + eps^2 (sin cos^3 + sin^3 cos / 2)``.
* **Pressure, mean** (virtual work on the torus family at fixed ``L``, ``m``): the bending
  energy of both strands is ``E = (2 pi B / R) [sin^4/(eps^2 cos) + g(theta) + O(eps^2)]``
  with ``g/cos = h(S) = 1 - 3 S^2/2 + 13 S^4/2 - 15 S^6/4`` (``S = sin theta``; the ``g``
  term is the ring bending ``B (2 pi)^2 cos^2 / L`` plus the cross terms of helix and axis
  curvature averaged over ``phi``), hence ``p_mean = (1/L) dE/dDelta``:

      ``p_mean = p0 [1 + (-3/2 + 13 S^2 - 9 S^4) / m^2 + O(1/m^4)]``.                  (4)

  (``-9 S^4 = -45 S^4/4`` from ``g`` ``+ 9 S^4/4`` from the length relation: the helix term
  is ``B L S^4/r^2 (1 + 3 eps^2 cos^2 S^2/4)`` with the exact ``A``, and ``eps^2 = tan^2/m^2``.)
  This is second order in ``eps`` (``1/m^2 = eps^2 cos^2 / sin^2``), with a large
  coefficient (-4.5 % at the seed's 4-link, -19 % for its pentafoil); the next terms, from the
  ``O(eps^2)`` energy, are relative ``O(1/m^4)``, which ruins Eq. 4 for the Hopf link
  (``m = 1``).  :func:`mean_pressure_virtual_work` evaluates the exact torus
  family, which :func:`closed_ply` reports as the corrected mean.
* **Pressure, modulation.**  The contact force per unit *axis* angle ``u`` is unchanged by
  the strand exchange (rotation by ``pi/m`` about the symmetry axis), so it has period ``pi``
  in ``phi``; per unit length of strand 1 it is divided by ``ds1/du = A (1 + eps cos^2 cos
  phi + ...)``, which has period ``2 pi``: ``p(s)`` along a strand is allowed the harmonics
  ``n, 2n, ...`` on a link's ring (slide 21: "p is period-n") while ``eta`` only has ``2n, 4n,
  ...`` ("eta is period-2n").  The amplitude is *not* given by the torus helix: it is not a
  first-order equilibrium.  The local Kirchhoff balance on it
  (:func:`torus_helix_local_balance`) needs an out-of-contact-plane load of relative size
  ``~ eps / sin^2`` (O(1) for the seed's cases) and breaks ``p1 ds1 = p2 ds2``: the strands
  leave the torus at first order in ``eps / sin^2``.  That is what the relaxed ply computes.
* **Contact curve.**  The midpoints of the contact chords of the torus helix are exactly the
  axis circle, so the contact curve's curvature is ``1/R`` (``2 pi / cos(theta)`` in 1/L);
  slide 23's 6.2-6.8 modulation of the pentafoil is beyond the torus helix.
* **Writhe** (Fuller 1978: ``Wr = (1/2 pi) oint t_z d lambda`` modulo an integer, with
  ``lambda`` the longitude of the tangent about the symmetry axis; see :func:`writhe_fuller`):
  per ring of a left-handed link ``Wr = -[m (1 - cos theta) - eps sin cos^2 / 2] + O(eps^2)``
  (the helical term ``1 - cos theta`` per turn, as for a solenoid, less the first-order
  correction from the modulated speed ``R + r cos phi``); for the knot's single ring
  ``Wr = -[n (2 - cos theta) - eps sin cos^2] + O(eps^2)``, the integer ``n`` being the
  ``n`` crossings of the two strands (the thin-tube limit of a closed two-braid), fixed here
  and checked against the Gauss double integral.

Relaxed closed ply (:func:`relax_closed_ply`)
---------------------------------------------
Any pair ``x_1,2 = X(u) +- r e(u)`` with a unit ``e`` normal to ``X'`` is a constant-distance
pair (slide 4) whose points at equal ``u`` are closest points at distance exactly ``Delta``.
Writing the contact curve ``X`` and the chord angle ``psi`` as the torus helix plus the
harmonics ``2 m j`` allowed by the seed's symmetry (D_2n links, D_n knots; slides 20, 22),
fixing ``R`` by the strand length and minimising the bending energy (no twist) gives the
equilibrium without any small-``eps`` expansion; the pressure follows from each strand's
Kirchhoff balance, and the two residuals that vanish only at equilibrium (the
out-of-contact-plane load and Newton's third law ``p1 ds1 = p2 ds2``) are reported.  For the
seed's 4-link this reproduces slide 21: ``eta`` in ``[0.509093, 0.509358]`` against the plot's
``[0.50910, 0.50935]`` and ``p`` in ``[3163, 3926]`` against ``3200-3900`` (2 harmonics,
converged to 0.3 B/L^3 with 3).  For the pentafoil it gives ``p`` in ``[365, 558]``
(mean 472) and ``kappa_c`` in ``[5.98, 6.74]`` against the plots' ``400-550`` and
``6.2-6.8``: the upper ends agree, the lower ends do not (the seed notes ``L2 != L`` for its
pentafoil, which this strand-exchange-symmetric ansatz excludes; not resolved here).  The
Hopf link (``n = 1``) relaxes to two round circles (energy ``4 pi^2 B/L``) touching without
pressure.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.optimize import brentq

from dnabraid.continuum import ply as _ply
from dnabraid.continuum._result import ContinuumResult
from dnabraid.continuum._validate import InputError, check_n, check_positive

__all__ = [
    "SEED",
    "TOPOLOGIES",
    "axis_radius_exact",
    "braid_angle_expansion",
    "braid_angle_torus",
    "closed_ply",
    "closed_ply_angle",
    "convergence_table",
    "energy_formula",
    "mean_pressure_formula",
    "mean_pressure_virtual_work",
    "ply_turns",
    "relax_closed_ply",
    "seed_comparison_table",
    "torus_helix_energy",
    "torus_helix_local_balance",
    "torus_ply_curves",
    "uniform_pressure",
    "writhe_formula",
    "writhe_fuller",
]

TOPOLOGIES = ("link", "knot")
LINK, KNOT = TOPOLOGIES

#: Seed numbers (van der Heijden, slides 21 and 23), read off the plots' axes.
SEED = {
    "link4": {"slide": 21, "n": 4, "topology": "link", "diameter_over_length": 0.02,
              "eta_min": 0.50910, "eta_max": 0.50935, "pressure_min": 3200.0,
              "pressure_max": 3900.0},
    "pentafoil": {"slide": 23, "n": 5, "topology": "knot", "diameter_over_length": 0.02,
                  "pressure_min": 400.0, "pressure_max": 550.0,
                  "contact_curvature_min": 6.2, "contact_curvature_max": 6.8},
}

#: Points of the phi grid for the exact torus-family averages (periodic trapezoid rule,
#: spectrally accurate: the integrands' harmonics fall like eps^k).
_N_PHI = 256


# --------------------------------------------------------------------------- validation
def _check(n, diameter_over_length, topology) -> tuple[int, float, str, float]:
    """Validate ``(n, Delta/L, topology)``; return them with ``m`` (chord turns per circuit)."""
    if topology not in TOPOLOGIES:
        raise InputError(f"topology must be one of {TOPOLOGIES}, got {topology!r}")
    n = check_n(n, minimum=1, name="n",
                what="the link's |Lk|" if topology == LINK else "the knot's odd n")
    d = check_positive("diameter_over_length", diameter_over_length)
    if topology == KNOT and n % 2 == 0:
        raise InputError(f"n must be odd for the (n, 2) torus knot, got n={n}: an even n "
                         f"closes the two strands into two rings, the (2, {n}) torus link "
                         f"(use topology='link' with n={n // 2})")
    m = float(n) if topology == LINK else 0.5 * n
    s = math.pi * m * d
    if s >= 1.0:
        raise InputError(f"n={n} does not fit: sin(theta) = pi m Delta/L = pi*{m:g}*{d:g} = "
                         f"{s:.4g} >= 1 (m = {m:g} chord turns per circuit of the axis); the "
                         f"strands are too short for {m:g} turns at this diameter")
    theta = math.asin(s)
    if theta >= _ply.LOCKUP_ANGLE_RAD:
        raise InputError(f"n={n} does not fit: helix angle theta = {math.degrees(theta):.2f} "
                         f"deg >= 45 deg, the two-ply lock-up (slides 17-18; sin(theta) = "
                         f"pi m Delta/L = {s:.4g} >= 1/sqrt(2)): the strands would interpenetrate")
    radius = math.cos(theta) / (2.0 * math.pi)
    if radius < d:
        raise InputError(f"n={n} does not fit: the ply axis ring R = L cos(theta)/(2 pi) = "
                         f"{radius:.4g} L is smaller than Delta = {d:g} L, so the strands on "
                         f"opposite sides of the ring's hole would overlap (R >= Delta needed)")
    return n, d, topology, m


def ply_turns(n, topology: str = "link") -> float:
    """Chord turns per circuit of the axis, ``m``: ``n`` for a link, ``n/2`` for a knot."""
    if topology not in TOPOLOGIES:
        raise InputError(f"topology must be one of {TOPOLOGIES}, got {topology!r}")
    n = check_n(n, minimum=1, name="n")
    if topology == KNOT and n % 2 == 0:
        raise InputError(f"n must be odd for the (n, 2) torus knot, got n={n}")
    return float(n) if topology == LINK else 0.5 * n


# --------------------------------------------------------------------------- leading order
def closed_ply_angle(n, diameter_over_length: float, topology: str = "link") -> float:
    """Helix angle of the uniform closed ply, ``theta = asin(pi m Delta/L)``, rad (Eq. 1)."""
    _, d, _, m = _check(n, diameter_over_length, topology)
    return math.asin(math.pi * m * d)


def uniform_pressure(n, diameter_over_length: float, topology: str = "link") -> float:
    """Contact pressure of the uniform closed ply, ``B sin^4/r^3 = 8 pi^4 m^4 Delta/L``, B/L^3.

    Eq. (2) of the module docstring (torque-free straight ply with ``F = 0``; slide 17's
    fixed point with the ply moment as the link's Lagrange multiplier).
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    s = math.pi * m * d
    return s**4 / (0.5 * d) ** 3


# --------------------------------------------------------------------------- torus family
def _mean_length(R: float, r: float, m: float, n_phi: int = _N_PHI) -> float:
    phi = 2.0 * math.pi * np.arange(n_phi) / n_phi
    return 2.0 * math.pi * float(np.mean(np.sqrt((R + r * np.cos(phi)) ** 2 + (r * m) ** 2)))


def _axis_radius(r: float, m: float) -> float:
    """Exact ``R`` (units of L) of the torus helix of tube radius ``r`` with strand length 1."""
    hi = 1.0 / (2.0 * math.pi)
    return brentq(lambda R: _mean_length(R, r, m) - 1.0, 1e-9, hi, xtol=1e-16, rtol=1e-15)


def axis_radius_exact(n, diameter_over_length: float, topology: str = "link") -> float:
    """Axis radius ``R/L`` of the torus helix whose strands have length exactly ``L``.

    Solves ``L = 2 pi <sqrt((R + r cos phi)^2 + r^2 m^2)>_phi`` (module docstring, "Length";
    each strand covers whole periods of ``phi``, or for the knot a half-integer number whose
    average equals the full-period average by the symmetry ``phi -> pi - phi``).
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    return _axis_radius(0.5 * d, m)


def torus_ply_curves(n, diameter_over_length: float, topology: str = "link",
                     n_points: int = 1000, length: float = 1.0) -> list[np.ndarray]:
    """Discretised uniform closed ply on its torus (left-handed, the seed's ``Lk = -n``).

    Parameters
    ----------
    n, diameter_over_length, topology
        As in :func:`closed_ply`.
    n_points : int
        Points per strand (a knot's ring gets ``2 n_points``), equally spaced in ``u``.
    length : float
        Strand length ``L`` in the caller's unit (positions scale with it).

    Returns
    -------
    list of ndarray
        Link: two rings, shape ``(n_points, 3)`` each; knot: one ring ``(2 n_points, 3)``
        whose first half is strand 1 and second half strand 2 (point ``i`` of strand 1 is in
        contact with point ``i`` of strand 2).
    """
    _, d, topology, m = _check(n, diameter_over_length, topology)
    n_points = check_n(n_points, minimum=8, name="n_points")
    length = check_positive("length", length)
    r = 0.5 * d
    R = _axis_radius(r, m)
    if topology == LINK:
        u = 2.0 * math.pi * np.arange(n_points) / n_points
        phases = (0.0, math.pi)
    else:
        u = 4.0 * math.pi * np.arange(2 * n_points) / (2 * n_points)
        phases = (0.0,)
    out = []
    for ph in phases:
        phi = m * u + ph  # + m u: left-handed (Gauss Lk = -n)
        rho = R + r * np.cos(phi)
        out.append(length * np.stack([rho * np.cos(u), rho * np.sin(u), r * np.sin(phi)], 1))
    return out


def braid_angle_torus(phi, n, diameter_over_length: float, topology: str = "link"):
    """Exact braid angle of the torus helix at chord azimuth ``phi``, rad (module Eq. 3 exact).

    ``eta = atan(k/(1 + eps cos phi)) + atan(k/(1 - eps cos phi))`` with ``eps = r/R`` and
    ``k = r m / R`` (``phi = 0``: strand 1 on the outside of the torus).
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    r = 0.5 * d
    R = _axis_radius(r, m)
    eps, k = r / R, r * m / R
    c = np.cos(np.asarray(phi, dtype=float))
    return np.arctan(k / (1.0 + eps * c)) + np.arctan(k / (1.0 - eps * c))


def braid_angle_expansion(n, diameter_over_length: float, topology: str = "link") -> dict:
    """Braid angle to second order in ``eps = r/R`` (module Eq. 3), rad.

    Returns
    -------
    dict
        ``eta_uniform`` (``2 theta``), ``eta_mean``, ``eta_min``, ``eta_max`` (the torus
        helix's range), ``eta_correction_mean`` (``eta_mean - 2 theta``),
        ``eta_modulation_amplitude`` (half the range, ``eps^2 sin cos^3``) and ``epsilon``
        (``pi (Delta/L)/cos theta``).
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    s = math.pi * m * d
    theta = math.asin(s)
    c = math.cos(theta)
    eps = math.pi * d / c
    shift = eps**2 * s**3 * c / 4.0  # theta_R - theta
    amp = eps**2 * s * c**3  # half range of eta
    eta_min = 2.0 * (theta + shift)
    return {"eta_uniform": 2.0 * theta, "eta_mean": eta_min + amp, "eta_min": eta_min,
            "eta_max": eta_min + 2.0 * amp, "eta_correction_mean": eta_min + amp - 2 * theta,
            "eta_modulation_amplitude": amp, "epsilon": eps}


def _energy_density(phi, eps: float, k: float):
    """The integrand ``f = (kappa R)^2 |x_u| / R`` of ``E = (2 pi B/R) <f>`` (E of both strands).

    ``kappa^2 R^2 = [Q X - a^2 k^2 sin^2] / Q^3`` with ``a = 1 + eps cos phi``,
    ``Q = a^2 + k^2``, ``X = k^4/eps^2 + 2 k^2 a cos/eps + a^2 + 4 k^2 sin^2``, times the
    speed ``R sqrt(Q)``: ``f = [Q X - a^2 k^2 sin^2] / Q^(5/2)`` (exact for the torus helix).
    """
    c, s = np.cos(phi), np.sin(phi)
    a = 1.0 + eps * c
    Q = a * a + k * k
    X = k**4 / eps**2 + 2.0 * k * k * a * c / eps + a * a + 4.0 * k * k * s * s
    return (Q * X - a * a * k * k * s * s) / Q**2.5


def _torus_energy(r: float, m: float, n_phi: int = _N_PHI) -> float:
    R = _axis_radius(r, m)
    phi = 2.0 * math.pi * np.arange(n_phi) / n_phi
    return 2.0 * math.pi / R * float(np.mean(_energy_density(phi, r / R, r * m / R)))


def torus_helix_energy(n, diameter_over_length: float, topology: str = "link") -> float:
    """Bending energy of both strands of the torus helix, ``B/L`` (exact quadrature).

    ``E = sum_strands (B/2) oint kappa^2 ds = (2 pi B/R) <f(phi)>`` (see ``_energy_density``);
    the same for a link's two rings and a knot's one ring of length ``2L``.
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    return _torus_energy(0.5 * d, m)


def energy_formula(n, diameter_over_length: float, topology: str = "link") -> float:
    """Bending energy of both strands to ``O(1)`` in ``eps``, B/L.

    ``S^4/r^2 (1 + 3 eps^2 cos^2 S^2/4) + 4 pi^2 h(S)``, ``h(S) = 1 - 3 S^2/2 + 13 S^4/2 -
    15 S^6/4`` (module docstring, "Pressure, mean"): the helix term ``B L sin^4/r^2`` of the
    straight ply (with the exact length relation) plus the ring and cross terms; the
    neglected terms are ``(2 pi B/R) O(eps^2)``.
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    s = math.pi * m * d
    c2 = 1.0 - s * s
    eps2 = (math.pi * d) ** 2 / c2
    h = 1.0 - 1.5 * s**2 + 6.5 * s**4 - 3.75 * s**6
    return s**4 / (0.5 * d) ** 2 * (1.0 + 0.75 * eps2 * c2 * s * s) + 4.0 * math.pi**2 * h


def mean_pressure_virtual_work(n, diameter_over_length: float, topology: str = "link",
                               rel_step: float = 1e-4) -> float:
    """Mean contact pressure of the torus-helix family, ``(1/L) dE/dDelta``, B/L^3.

    Virtual work at fixed strand length and chord turns: ``int p ds = dE/dDelta`` over the
    contact (strand 1's length ``L``).  Central difference in ``Delta`` with relative step
    ``rel_step`` (truncation ``~ rel_step^2``).
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    h = rel_step * d
    e_plus = _torus_energy(0.5 * (d + h), m)
    e_minus = _torus_energy(0.5 * (d - h), m)
    return (e_plus - e_minus) / (2.0 * h)


def mean_pressure_formula(n, diameter_over_length: float, topology: str = "link") -> float:
    """Mean pressure with the axis-curvature correction, module Eq. (4), B/L^3.

    ``p0 [1 + (-3/2 + 13 S^2 - 9 S^4)/m^2]``, ``S = sin theta``; the neglected terms are
    relative ``O(1/m^4)`` (useless for the Hopf link, ``m = 1``).
    """
    _, d, _, m = _check(n, diameter_over_length, topology)
    s = math.pi * m * d
    p0 = s**4 / (0.5 * d) ** 3
    return p0 * (1.0 + (-1.5 + 13.0 * s**2 - 9.0 * s**4) / m**2)  # Eq. (4)


# --------------------------------------------------------------------------- writhe
def writhe_formula(n, diameter_over_length: float, topology: str = "link") -> float:
    """Writhe to first order in ``eps``: per ring of a link, or of the knot's ring.

    Link: ``-[m (1 - cos theta) - eps sin cos^2 / 2]``; knot:
    ``-[n (2 - cos theta) - eps sin cos^2]`` (module docstring, "Writhe"; left-handed).
    """
    n, d, topology, m = _check(n, diameter_over_length, topology)
    s = math.pi * m * d
    c = math.sqrt(1.0 - s * s)
    eps = math.pi * d / c
    if topology == LINK:
        return -(m * (1.0 - c) - 0.5 * eps * s * c * c)
    return -(n * (2.0 - c) - eps * s * c * c)


def writhe_fuller(n, diameter_over_length: float, topology: str = "link",
                  n_points: int = 4096) -> float:
    """Writhe of a ring of the torus helix by Fuller's one-dimensional formula.

    ``Wr = W0 - (1/2 pi) oint t_z d lambda`` (Fuller, PNAS 75, 3557 (1978): ``1 + Wr`` equals
    the area enclosed by the tangent indicatrix over ``2 pi``, mod 2), with the exact tangent
    ``t ~ (-k sin phi, 1 + eps cos phi, k cos phi)`` in the frame ``(e_R, e_u, e_z)`` of the
    left-handed ply (``phi = m u``), its height ``t_z`` and its longitude
    ``lambda = u + pi/2 + atan2(k sin phi, 1 + eps cos phi)``.  The integer ``W0`` is 0 for a link's
    ring and ``-n`` for the knot (the thin-tube limit, module docstring).  Periodic trapezoid
    rule on ``n_points`` per circuit (spectrally accurate).
    """
    n, d, topology, m = _check(n, diameter_over_length, topology)
    n_points = check_n(n_points, minimum=16, name="n_points")
    r = 0.5 * d
    R = _axis_radius(r, m)
    eps, k = r / R, r * m / R
    circuits = 1 if topology == LINK else 2
    u = 2.0 * math.pi * circuits * np.arange(circuits * n_points) / (circuits * n_points)
    phi = m * u
    a = 1.0 + eps * np.cos(phi)
    q = a * a + k * k
    tz = k * np.cos(phi) / np.sqrt(q)
    # the horizontal part a e_u - k sin e_R points at u + pi/2 + atan2(k sin, a), so
    # d lambda/du = 1 + k m (a cos + eps sin^2) / (a^2 + k^2 sin^2)
    dlam = 1.0 + k * m * (a * np.cos(phi) + eps * np.sin(phi) ** 2) / (
        a * a + (k * np.sin(phi)) ** 2)
    area_term = float(np.mean(tz * dlam)) * circuits  # (1/2pi) oint t_z dlambda
    w0 = 0.0 if topology == LINK else -float(n)
    return w0 - area_term


# --------------------------------------------------------------------------- local balance
def _spectral_derivative(f: np.ndarray, period: float) -> np.ndarray:
    N = f.shape[0]
    w = 2.0 * math.pi * np.fft.fftfreq(N, d=period / N)
    if N % 2 == 0:
        w[N // 2] = 0.0
    return np.real(np.fft.ifft(1j * w[:, None] * np.fft.fft(f, axis=0), axis=0))


def torus_helix_local_balance(n, diameter_over_length: float, topology: str = "link",
                              n_points: int = 2048) -> dict:
    """Kirchhoff balance of each strand of the torus helix, with the virtual-work mean pressure.

    For a rod with bending moment ``B t x t'`` only, ``m' + t x F = 0`` gives
    ``F = -B t'' + lambda t`` and ``F' + q = 0`` along ``t`` gives
    ``lambda = lambda0 - 3 B kappa^2 / 2``; the load needed to hold the prescribed curve is
    ``q = B t''' - lambda t' `` (normal to ``t``).  Frictionless hard contact allows only
    ``q = -p d`` (``d`` the chord towards the other strand) with ``p1 ds1 = p2 ds2`` at each
    contact.  ``lambda0`` is set so that the mean of ``p`` equals
    :func:`mean_pressure_virtual_work`.  On the straight ply (``eps -> 0``) everything closes;
    on the torus the out-of-plane load ``q . (t x d)`` measures how far the torus helix is
    from equilibrium.  Derivatives are spectral (periodic, exact curve).

    Returns
    -------
    dict
        ``pressure_mean``, ``pressure_min``, ``pressure_max`` (strand 1, B/L^3),
        ``out_of_plane_rel`` (max ``|q . (t x d)|`` over ``pressure_mean``),
        ``newton3_rel`` (max ``|p1 ds1 - p2 ds2|`` over the mean of ``p1 ds1``), ``epsilon``.
    """
    n, d, topology, m = _check(n, diameter_over_length, topology)
    n_points = check_n(n_points, minimum=64, name="n_points")
    rings = torus_ply_curves(n, d, topology, n_points=n_points)
    period = 2.0 * math.pi * (1 if topology == LINK else 2)

    def frames(x):
        xu = _spectral_derivative(x, period)
        speed = np.linalg.norm(xu, axis=1)
        t = xu / speed[:, None]
        der = [t]
        for _ in range(3):
            der.append(_spectral_derivative(der[-1], period) / speed[:, None])
        return x, der, speed

    if topology == LINK:
        (xa, da, sa), (xb, db, sb) = frames(rings[0]), frames(rings[1])
    else:
        x, der, sp = frames(rings[0])
        half = slice(0, n_points), slice(n_points, 2 * n_points)
        xa, da, sa = x[half[0]], [v[half[0]] for v in der], sp[half[0]]
        xb, db, sb = x[half[1]], [v[half[1]] for v in der], sp[half[1]]
    chord = xb - xa
    chord /= np.linalg.norm(chord, axis=1)[:, None]

    def load(dr, lam0):
        t, t1, _, t3 = dr
        lam = lam0 - 1.5 * np.sum(t1 * t1, axis=1)
        return t3 - lam[:, None] * t1

    p_mean = mean_pressure_virtual_work(n, d, topology)
    w = sa / np.sum(sa)
    q0, q1 = load(da, 0.0), load(da, 1.0) - load(da, 0.0)
    pa0, pa1 = -np.sum(q0 * chord, 1), -np.sum(q1 * chord, 1)
    lam0 = (p_mean - np.sum(pa0 * w)) / np.sum(pa1 * w)
    qa = load(da, lam0)
    pa = -np.sum(qa * chord, 1)
    out_a = np.sum(qa * np.cross(da[0], chord), 1)
    qb = load(db, lam0)
    pb = np.sum(qb * chord, 1)  # strand 2 is pushed along +d
    fa, fb = pa * sa, pb * sb
    return {"pressure_mean": float(np.sum(pa * w)), "pressure_min": float(pa.min()),
            "pressure_max": float(pa.max()),
            "out_of_plane_rel": float(np.max(np.abs(out_a)) / p_mean),
            "newton3_rel": float(np.max(np.abs(fa - fb)) / np.mean(fa)),
            "epsilon": 0.5 * d / _axis_radius(0.5 * d, m)}


# --------------------------------------------------------------------------- relaxed ply
class _RitzPly:
    """Constant-distance pair ``x_1,2 = X(u) +- r e(u)`` with symmetric Fourier modes.

    ``X = (R + r xi) e_R + r zeta e_z``, ``e = cos(psi) a1 + sin(psi) a2`` with ``(a1, a2)``
    the orthonormal frame normal to ``X'`` obtained from ``(e_R, e_z)``, ``psi = m u + chi``;
    ``xi = sum a_j cos(2 m j u)``, ``zeta = sum b_j sin(2 m j u)``, ``chi = sum c_j sin(2 m j u)``.
    """

    def __init__(self, n, d, topology, harmonics, n_points):
        self.m = ply_turns(n, topology)
        self.r = 0.5 * d
        self.circuits = 1 if topology == LINK else 2
        self.topology = topology
        self.period = 2.0 * math.pi * self.circuits
        self.u = self.period * np.arange(n_points * self.circuits) / (n_points * self.circuits)
        ku = 2.0 * self.m * np.arange(1, harmonics + 1)[None, :] * self.u[:, None]
        self.cos, self.sin = np.cos(ku), np.sin(ku)
        self.e_R = np.stack([np.cos(self.u), np.sin(self.u), 0.0 * self.u], 1)
        self.J = harmonics
        self.R = self.R0 = _axis_radius(self.r, self.m)
        self.slope = 2.0 * math.pi * math.cos(math.asin(math.pi * self.m * d))

    def curves(self, R, c):
        a, b, cc_ = c.reshape(3, self.J)
        X = (R + self.r * (self.cos @ a))[:, None] * self.e_R
        X[:, 2] += self.r * (self.sin @ b)
        T = _spectral_derivative(X, self.period)
        T /= np.linalg.norm(T, axis=1)[:, None]
        a1 = self.e_R - np.sum(self.e_R * T, 1)[:, None] * T
        a1 /= np.linalg.norm(a1, axis=1)[:, None]
        a2 = np.cross(a1, T)  # = e_z on the torus: psi = m u is left-handed, as above
        psi = self.m * self.u + self.sin @ cc_
        e = np.cos(psi)[:, None] * a1 + np.sin(psi)[:, None] * a2
        return X + self.r * e, X - self.r * e, X

    def length(self, R, c) -> float:
        x1 = self.curves(R, c)[0]
        speed = np.linalg.norm(_spectral_derivative(x1, self.period), axis=1)
        return float(np.mean(speed)) * self.period / self.circuits

    def radius(self, c) -> float:
        """``R`` at which strand 1 has length exactly 1 (Newton, slope ``2 pi cos theta``,
        from the torus value); nan where no such ``R`` is found (a degenerate shape)."""
        R = self.R0
        for _ in range(60):
            gap = self.length(R, c) - 1.0
            if abs(gap) < 1e-14:
                return R
            R -= gap / self.slope
            if not (0.5 * self.R0 < R < 2.0 * self.R0):
                return math.nan
        return R if abs(self.length(R, c) - 1.0) < 1e-12 else math.nan

    def energy(self, c) -> float:
        R = self.radius(c)
        if not math.isfinite(R):
            return 1e3 * self.e_torus  # outside the admissible shapes: a wall for L-BFGS-B
        x1, x2, _ = self.curves(R, c)
        total = 0.0
        for x in ((x1, x2) if self.topology == LINK else (x1,)):
            xp = _spectral_derivative(x, self.period)
            xpp = _spectral_derivative(xp, self.period)
            speed = np.linalg.norm(xp, axis=1)
            k2s = np.sum(np.cross(xp, xpp) ** 2, axis=1) / speed**5  # kappa^2 |x'|
            total += 0.5 * float(np.mean(k2s)) * self.period
        return total


def _strand_frames(x, period):
    xp = _spectral_derivative(x, period)
    speed = np.linalg.norm(xp, axis=1)
    der = [xp / speed[:, None]]
    for _ in range(3):
        der.append(_spectral_derivative(der[-1], period) / speed[:, None])
    return der, speed


def _harmonic(y) -> int:
    spec = np.abs(np.fft.rfft(np.asarray(y) - np.mean(y)))
    return int(np.argmax(spec[1:]) + 1)


def relax_closed_ply(n, diameter_over_length: float, topology: str = "link", *,
                     harmonics: int = 2, n_points: int | None = None,
                     ftol: float = 1e-15) -> ContinuumResult:
    """Equilibrium closed ply beyond the torus helix: a symmetric Ritz minimisation.

    The two strands are written as a constant-distance pair (slide 4):
    ``x_1,2(u) = X(u) +- r e(u)`` with ``e`` a unit vector normal to ``X'``; then points at equal
    ``u`` are closest-approach points at distance exactly ``Delta`` for *any* contact curve
    ``X`` and chord angle ``psi`` (``(x2 - x1) . x1' = 2 r e . (X' + r e') = 0``).  The ansatz
    (class ``_RitzPly``) keeps the D_2n (link) or D_n (knot) symmetry of the seed's solutions
    (slides 20, 22) -- rotation by ``pi/m`` about the symmetry axis exchanging the strands, and
    the in-plane half turns -- so only harmonics ``2 m j`` of ``u`` appear:
    ``X = (R + r sum a_j cos 2mju) e_R + r sum b_j sin(2mju) e_z``,
    ``psi = m u + sum c_j sin(2mju)``, ``j = 1..harmonics``.  ``R`` is fixed by the strand
    length ``L = 1``; the bending energy of both strands (``C tau = 0``) is minimised over
    ``(a, b, c)`` with L-BFGS-B.  The symmetry is imposed here (the bead model must find it).

    The contact pressure is then read from each strand's Kirchhoff balance
    (:func:`torus_helix_local_balance`): ``q = B t''' - lambda t'``, ``lambda = lambda0 - 3 B
    kappa^2/2``, with ``lambda0`` fitted to make the out-of-contact-plane load vanish
    (least squares over both strands).  At an equilibrium that load is zero and
    ``p1 ds1 = p2 ds2`` (Newton's third law); both residuals are returned and fall with
    ``harmonics`` (the check that the Ritz shape is the equilibrium).

    Parameters
    ----------
    n, diameter_over_length, topology
        As in :func:`closed_ply`.
    harmonics : int
        Number ``J`` of symmetric harmonics per field (``J = 2`` converges p to ~1e-4).
    n_points : int, optional
        Grid points per circuit (default ``max(256, 16 * 2 m J)``, a power of two).
    ftol : float
        L-BFGS-B ``ftol``.

    Returns
    -------
    ContinuumResult
        ``values`` (B/L^3, rad, 1/L, B/L): ``energy_B_per_L``, ``energy_torus_B_per_L``,
        ``axis_radius_over_L``, ``pressure_mean/min/max_B_per_L3`` (per unit length of strand
        1, over one circuit: a link's ring, a knot's strand; both strands for the knot),
        ``eta_mean/min/max_rad``, ``contact_curvature_mean/min/max_per_L`` (the curve ``X`` of
        chord midpoints), ``pressure_harmonic``, ``eta_harmonic``,
        ``contact_curvature_harmonic`` (dominant periods per ring),
        ``out_of_plane_rel``, ``newton3_rel``, ``coefficients`` (``a, b, c``).
        ``solution``: dict of arrays ``s`` (strand-1 arclength, units of L), ``pressure``,
        ``eta``, ``contact_curvature`` along the ring (link) or along the whole ring (knot).
    """
    from scipy.optimize import minimize

    t0 = time.perf_counter()
    n, d, topology, m = _check(n, diameter_over_length, topology)
    harmonics = check_n(harmonics, minimum=1, name="harmonics")
    if n_points is None:
        n_points = 1 << max(8, math.ceil(math.log2(16 * 2 * m * harmonics)))
    n_points = check_n(n_points, minimum=64, name="n_points")
    model = _RitzPly(n, d, topology, harmonics, n_points)
    model.e_torus = math.inf
    e_torus = model.e_torus = model.energy(np.zeros(3 * harmonics))
    # bounds: contact-curve displacements up to 0.3 r, chord-angle harmonics up to 0.05 rad
    # (the relaxed values are ~0.04 r and ~0.003 rad for the seed's cases)
    bounds = [(-0.3, 0.3)] * (2 * harmonics) + [(-0.05, 0.05)] * harmonics
    opt = minimize(model.energy, np.zeros(3 * harmonics), method="L-BFGS-B", bounds=bounds,
                   options={"ftol": ftol, "gtol": 1e-10, "maxiter": 2000})
    coef = np.asarray(opt.x)
    R = model.radius(coef)
    if not math.isfinite(R) or np.any(np.isclose(np.abs(coef), [b[1] for b in bounds])):
        return ContinuumResult(False, 4, f"relaxation left the admissible shapes or hit a bound "
                               f"(coefficients {coef.tolist()}): {opt.message}",
                               {"energy_torus_B_per_L": float(e_torus)}, math.nan, len(model.u),
                               time.perf_counter() - t0)
    x1, x2, X = model.curves(R, coef)
    P = model.period
    if topology == LINK:
        (da, sa), (db, sb) = _strand_frames(x1, P), _strand_frames(x2, P)
        xa, xb = x1, x2
    else:  # x1 covers the whole ring; strand 2 is its second circuit
        der, sp = _strand_frames(x1, P)
        half = len(x1) // 2
        da, sa = [v[:half] for v in der], sp[:half]
        db, sb = [v[half:] for v in der], sp[half:]
        xa, xb = x1[:half], x1[half:]
    chord = xb - xa
    chord /= np.linalg.norm(chord, axis=1)[:, None]

    def load(dr, lam0):
        t, t1, _, t3 = dr
        lam = lam0 - 1.5 * np.sum(t1 * t1, axis=1)
        return t3 - lam[:, None] * t1

    ea, eb = np.cross(da[0], chord), np.cross(db[0], chord)
    r0 = np.concatenate([np.sum(load(da, 0.0) * ea, 1), np.sum(load(db, 0.0) * eb, 1)])
    r1 = np.concatenate([np.sum((load(da, 1.0) - load(da, 0.0)) * ea, 1),
                         np.sum((load(db, 1.0) - load(db, 0.0)) * eb, 1)])
    lam0 = -float(np.dot(r0, r1) / np.dot(r1, r1))
    qa, qb = load(da, lam0), load(db, lam0)
    pa = -np.sum(qa * chord, 1)  # pushed away from strand 2
    pb = np.sum(qb * chord, 1)
    out_plane = max(np.max(np.abs(np.sum(qa * ea, 1))), np.max(np.abs(np.sum(qb * eb, 1))))
    t1, t2 = da[0], db[0]
    eta = np.arctan2(np.sum(chord * np.cross(t1, t2), 1), np.sum(t1 * t2, 1))
    Xp = _spectral_derivative(X, P)
    Xpp = _spectral_derivative(Xp, P)
    kc = np.linalg.norm(np.cross(Xp, Xpp), axis=1) / np.linalg.norm(Xp, axis=1) ** 3
    du = P / len(x1)
    if topology == LINK:
        p_ring, s_ring, eta_ring = pa, np.concatenate([[0.0], np.cumsum(sa[:-1])]) * du, eta
        w = sa
    else:  # along the whole ring: strand 1 then strand 2 (eta is a pair quantity)
        p_ring = np.concatenate([pa, pb])
        sp_ring = np.concatenate([sa, sb])
        s_ring = np.concatenate([[0.0], np.cumsum(sp_ring[:-1])]) * du
        eta_ring = np.concatenate([eta, eta])
        w = sp_ring
        kc = kc[: len(kc) // 2]
    p_mean = float(np.sum(p_ring * w) / np.sum(w))
    values = {
        "energy_B_per_L": float(opt.fun),
        "energy_torus_B_per_L": float(e_torus),
        "axis_radius_over_L": float(R),
        "pressure_mean_B_per_L3": p_mean,
        "pressure_min_B_per_L3": float(p_ring.min()),
        "pressure_max_B_per_L3": float(p_ring.max()),
        "eta_mean_rad": float(np.mean(eta)),
        "eta_min_rad": float(eta.min()),
        "eta_max_rad": float(eta.max()),
        "contact_curvature_mean_per_L": float(np.mean(kc)),
        "contact_curvature_min_per_L": float(kc.min()),
        "contact_curvature_max_per_L": float(kc.max()),
        "pressure_harmonic": _harmonic(p_ring),
        "eta_harmonic": _harmonic(eta_ring),
        "contact_curvature_harmonic": _harmonic(kc),
        "out_of_plane_rel": float(out_plane / max(abs(p_mean), 1e-300)),
        "newton3_rel": float(np.max(np.abs(pa * sa - pb * sb))
                             / max(abs(float(np.mean(pa * sa))), 1e-300)),
        "harmonics": harmonics,
        "coefficients": [float(v) for v in coef],
    }
    profiles = {"s": s_ring, "pressure": p_ring, "eta": eta_ring,
                "contact_curvature": kc, "strands": (x1, x2)}
    ok = bool(opt.success) and values["energy_B_per_L"] <= e_torus
    msg = f"L-BFGS-B: {opt.message}" if ok else f"not converged: {opt.message}"
    return ContinuumResult(ok, 0 if ok else 1, msg, values, values["out_of_plane_rel"],
                           len(x1), time.perf_counter() - t0, profiles)


# --------------------------------------------------------------------------- result
_RELAXED_KEYS = ("energy_B_per_L", "pressure_mean_B_per_L3", "pressure_min_B_per_L3",
                 "pressure_max_B_per_L3", "eta_mean_rad", "eta_min_rad", "eta_max_rad",
                 "contact_curvature_mean_per_L", "contact_curvature_min_per_L",
                 "contact_curvature_max_per_L", "pressure_harmonic", "eta_harmonic",
                 "contact_curvature_harmonic", "out_of_plane_rel", "newton3_rel", "harmonics")


def closed_ply(n, diameter_over_length: float, topology: str = "link", *, relax: bool = True,
               harmonics: int = 2) -> ContinuumResult:
    """Uniform closed two-ply, its axis-curvature correction and the relaxed ply.

    Parameters
    ----------
    n : int
        ``|Lk|`` of the ``(2, 2n)`` torus link, or the odd ``n`` of the ``(n, 2)`` torus knot.
    diameter_over_length : float
        ``Delta / L`` (``L`` each strand's length: a ring for a link, half the ring for a knot).
    topology : {"link", "knot"}
    relax : bool
        Also run :func:`relax_closed_ply` (about 2 s) and add its values as ``relaxed_*``.
    harmonics : int
        Harmonics of the relaxed ply's Ritz ansatz.

    Returns
    -------
    ContinuumResult
        ``values`` (lengths in L, pressure in B/L^3, forces B/L^2, moments B/L, energy B/L):
        ``theta_rad``, ``theta_deg``, ``eta_rad`` (``2 theta``), ``linking_number`` (``-n``
        for the link; the ply link ``-n/2`` for the knot), ``ply_turns`` (``m``),
        ``pitch_over_L``, ``pitch_over_radius``, ``axis_radius_over_L`` (``cos/2pi``),
        ``axis_radius_exact_over_L``, ``epsilon`` (``r/R``), ``helix_curvature_per_L``,
        ``axis_curvature_per_L``, ``contact_curvature_per_L`` (``L/R``),
        ``pressure_uniform_B_per_L3`` (Eq. 2), ``pressure_mean_B_per_L3`` (exact torus
        family, virtual work), ``pressure_mean_formula_B_per_L3`` (Eq. 4),
        ``tension_B_per_L2``, ``ply_moment_B_per_L``, ``ring_shear_force_B_per_L2``,
        ``energy_formula_B_per_L``, ``energy_torus_B_per_L``, ``eta_mean_rad``,
        ``eta_min_rad``, ``eta_max_rad`` (Eq. 3, torus helix), ``writhe_per_ring`` (formula),
        ``writhe_per_ring_fuller`` (exact 1-D quadrature), ``pressure_periods``,
        ``eta_periods`` (the symmetry's periods along a ring's contact loop), and with
        ``relax`` the ``relaxed_*`` values of :func:`relax_closed_ply`.  ``success`` is the
        relaxation's (True without it).
    """
    t0 = time.perf_counter()
    n, d, topology, m = _check(n, diameter_over_length, topology)
    s = math.pi * m * d
    theta = math.asin(s)
    c = math.cos(theta)
    r = 0.5 * d
    R0 = c / (2.0 * math.pi)
    R = _axis_radius(r, m)
    eta = braid_angle_expansion(n, d, topology)
    p0 = s**4 / r**3  # Eq. (2)
    p_torus = mean_pressure_virtual_work(n, d, topology)
    p_formula = mean_pressure_formula(n, d, topology)
    M = float(_ply.fixed_point_torque(theta, 0.0, d, 1.0))  # = 4 sin^3 / r
    values = {
        "topology": topology,
        "n": n,
        "diameter_over_length": d,
        "ply_turns": m,
        "linking_number": -float(n) if topology == LINK else -0.5 * n,
        "theta_rad": theta,
        "theta_deg": math.degrees(theta),
        "eta_rad": 2.0 * theta,
        "pitch_over_L": c / m,
        "pitch_over_radius": _ply.pitch_over_radius(theta),
        "axis_radius_over_L": R0,
        "axis_radius_exact_over_L": R,
        "epsilon": r / R,
        "helix_curvature_per_L": s * s / r,
        "axis_curvature_per_L": 1.0 / R,
        "contact_curvature_per_L": 1.0 / R,
        "pressure_uniform_B_per_L3": p0,
        "pressure_mean_B_per_L3": p_torus,
        "pressure_mean_formula_B_per_L3": p_formula,
        "tension_B_per_L2": s**4 / r**2,
        "ply_moment_B_per_L": M,
        "ring_shear_force_B_per_L2": M / R,
        "energy_formula_B_per_L": energy_formula(n, d, topology),
        "energy_torus_B_per_L": _torus_energy(r, m),
        "eta_mean_rad": eta["eta_mean"],
        "eta_min_rad": eta["eta_min"],
        "eta_max_rad": eta["eta_max"],
        "writhe_per_ring": writhe_formula(n, d, topology),
        "writhe_per_ring_fuller": writhe_fuller(n, d, topology),
        "pressure_periods": n,
        "eta_periods": 2 * n,
    }
    msg = ("uniform closed ply (exact at leading order); eta and mean pressure of the torus "
           "helix to O(eps^2)")
    ok, status = True, 0
    if relax:
        rel = relax_closed_ply(n, d, topology, harmonics=harmonics)
        values.update({f"relaxed_{k}": rel.values[k] for k in _RELAXED_KEYS})
        ok, status = rel.success, rel.status
        msg += f"; relaxed ply ({harmonics} harmonics): {rel.message}"
    return ContinuumResult(ok, status, msg, values, abs(p_formula - p_torus) / p0, _N_PHI,
                           time.perf_counter() - t0)


# --------------------------------------------------------------------------- seed table
def seed_comparison_table(harmonics: int = 2) -> list[dict]:
    """Rows: continuum (uniform, torus-corrected, relaxed) against slides 21 and 23.

    Each row: ``case``, ``quantity``, ``unit``, ``uniform`` (leading order),
    ``corrected`` (torus helix to O(eps^2); None where it has no value), ``relaxed``
    (:func:`relax_closed_ply`), ``seed`` (the value read off the slide's plot: the ends of
    the plotted curve's range, taken as the axis limits), ``slide``.
    """
    rows: list[dict] = []
    a = SEED["link4"]
    v = closed_ply(a["n"], a["diameter_over_length"], a["topology"], harmonics=harmonics).values
    case = "4-link, Delta/L=0.02"
    for q, uni, cor, rel, seed in (
            ("eta min", v["eta_rad"], v["eta_min_rad"], v["relaxed_eta_min_rad"], a["eta_min"]),
            ("eta max", v["eta_rad"], v["eta_max_rad"], v["relaxed_eta_max_rad"], a["eta_max"]),
            ("eta mean", v["eta_rad"], v["eta_mean_rad"], v["relaxed_eta_mean_rad"],
             0.5 * (a["eta_min"] + a["eta_max"]))):
        rows.append({"case": case, "quantity": q, "unit": "rad", "uniform": uni,
                     "corrected": cor, "relaxed": rel, "seed": seed, "slide": 21})
    for q, cor, key, seed in (("pressure min", None, "min", a["pressure_min"]),
                              ("pressure max", None, "max", a["pressure_max"]),
                              ("pressure mean", v["pressure_mean_B_per_L3"], "mean", None)):
        rows.append({"case": case, "quantity": q, "unit": "B/L^3",
                     "uniform": v["pressure_uniform_B_per_L3"], "corrected": cor,
                     "relaxed": v[f"relaxed_pressure_{key}_B_per_L3"], "seed": seed,
                     "slide": 21})
    b = SEED["pentafoil"]
    v = closed_ply(b["n"], b["diameter_over_length"], b["topology"], harmonics=harmonics).values
    case = "pentafoil (5,2), Delta/L=0.02"
    for q, cor, key, seed in (("pressure min", None, "min", b["pressure_min"]),
                              ("pressure max", None, "max", b["pressure_max"]),
                              ("pressure mean", v["pressure_mean_B_per_L3"], "mean", None)):
        rows.append({"case": case, "quantity": q, "unit": "B/L^3",
                     "uniform": v["pressure_uniform_B_per_L3"], "corrected": cor,
                     "relaxed": v[f"relaxed_pressure_{key}_B_per_L3"], "seed": seed,
                     "slide": 23})
    for q, key, seed in (("contact curvature min", "min", b["contact_curvature_min"]),
                         ("contact curvature max", "max", b["contact_curvature_max"]),
                         ("contact curvature mean", "mean", None)):
        rows.append({"case": case, "quantity": q, "unit": "1/L",
                     "uniform": 2 * math.pi / math.cos(v["theta_rad"]),
                     "corrected": v["contact_curvature_per_L"],
                     "relaxed": v[f"relaxed_contact_curvature_{key}_per_L"], "seed": seed,
                     "slide": 23})
    return rows


def convergence_table() -> list[dict]:
    """Error against mesh/harmonics and wall time (``workflows/continuum_convergence.py``).

    (a) Relaxed 4-link at Delta/L = 0.02: pressure min/max and eta max against harmonics
    ``J = 1..3``, error against ``J = 4`` (B/L^3; eta's error in rad is in its own column).
    (b) Writhe of the 4-link's ring: polygon Gauss integral against the spectral Fuller
    quadrature, for 100..800 points (the polygon's ``h^2`` error).
    (c) Mean pressure of the torus family: the central difference's relative step.
    """
    from dnabraid.geometry.curves import writhe

    rows: list[dict] = []
    ref = relax_closed_ply(4, 0.02, "link", harmonics=4)
    for J in (1, 2, 3):
        res = relax_closed_ply(4, 0.02, "link", harmonics=J)
        err = max(abs(res.values[k] - ref.values[k]) for k in
                  ("pressure_min_B_per_L3", "pressure_max_B_per_L3", "pressure_mean_B_per_L3"))
        rows.append({"problem": "relaxed_4_link", "setting": f"harmonics={J}",
                     "mesh_nodes": res.mesh_size, "error": err,
                     "eta_error_rad": abs(res.values["eta_max_rad"] - ref.values["eta_max_rad"]),
                     "out_of_plane_rel": res.values["out_of_plane_rel"],
                     "success": res.success, "wall_time_s": res.wall_time_s})
    exact = writhe_fuller(4, 0.02, "link")
    for N in (100, 200, 400, 800):
        t0 = time.perf_counter()
        w = writhe(torus_ply_curves(4, 0.02, "link", n_points=N)[0])
        rows.append({"problem": "writhe_polygon", "setting": f"n_points={N}", "mesh_nodes": N,
                     "error": abs(w - exact), "success": True,
                     "wall_time_s": time.perf_counter() - t0})
    p_ref = mean_pressure_virtual_work(4, 0.02, "link", rel_step=1e-4)
    for step in (1e-1, 1e-2, 1e-3):
        t0 = time.perf_counter()
        p = mean_pressure_virtual_work(4, 0.02, "link", rel_step=step)
        rows.append({"problem": "torus_virtual_work", "setting": f"rel_step={step:g}",
                     "mesh_nodes": _N_PHI, "error": abs(p - p_ref), "success": True,
                     "wall_time_s": time.perf_counter() - t0})
    return rows


# --------------------------------------------------------------------------- CLI
def cli_add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``dnabraid continuum closed``."""
    parser.add_argument("--n", type=int, default=4,
                        help="|Lk| of the (2,2n) torus link, or the odd n of the (n,2) knot")
    parser.add_argument("--diameter-over-length", type=float, default=0.02,
                        help="Delta/L (L: each strand's length)")
    parser.add_argument("--topology", choices=list(TOPOLOGIES), default="link",
                        help="link (two rings) or knot (one ring of length 2L)")
    parser.add_argument("--harmonics", type=int, default=2,
                        help="harmonics of the relaxed ply (0: uniform and torus only)")


def _fmt(x) -> str:
    if x is None or x == "":
        return ""
    return f"{x:.6g}" if isinstance(x, float) else str(x)


def _table(v: dict) -> str:
    rel = "relaxed_pressure_mean_B_per_L3" in v
    rows = [("helix angle theta", "rad", v["theta_rad"], "", ""),
            ("braid angle eta mean", "rad", v["eta_rad"], v["eta_mean_rad"],
             v.get("relaxed_eta_mean_rad")),
            ("eta min", "rad", v["eta_rad"], v["eta_min_rad"], v.get("relaxed_eta_min_rad")),
            ("eta max", "rad", v["eta_rad"], v["eta_max_rad"], v.get("relaxed_eta_max_rad")),
            ("pressure p mean", "B/L^3", v["pressure_uniform_B_per_L3"],
             v["pressure_mean_B_per_L3"], v.get("relaxed_pressure_mean_B_per_L3")),
            ("pressure p min", "B/L^3", v["pressure_uniform_B_per_L3"], "",
             v.get("relaxed_pressure_min_B_per_L3")),
            ("pressure p max", "B/L^3", v["pressure_uniform_B_per_L3"], "",
             v.get("relaxed_pressure_max_B_per_L3")),
            ("contact curvature", "1/L", 2 * math.pi / math.cos(v["theta_rad"]),
             v["contact_curvature_per_L"], v.get("relaxed_contact_curvature_mean_per_L")),
            ("axis radius R", "L", v["axis_radius_over_L"], v["axis_radius_exact_over_L"], ""),
            ("pitch", "L", v["pitch_over_L"], "", ""),
            ("writhe per ring", "1", v["writhe_per_ring"], v["writhe_per_ring_fuller"], ""),
            ("linking number", "1", v["linking_number"], "", "")]
    head = f"{'quantity':<22} {'unit':<6} {'uniform':>12} {'torus O(eps^2)':>15}"
    head += f" {'relaxed':>12}" if rel else ""
    lines = [head]
    for name, unit, a, b, c in rows:
        line = f"{name:<22} {unit:<6} {_fmt(a):>12} {_fmt(b):>15}"
        line += f" {_fmt(c):>12}" if rel else ""
        lines.append(line)
    return "\n" + "\n".join(lines)


def cli_run(args) -> dict:
    """Solve the closed ply chosen by ``args``; JSON-serialisable summary."""
    harmonics = int(getattr(args, "harmonics", 2))
    if harmonics < 0:
        raise InputError(f"--harmonics must be >= 0 (0: no relaxation), got {harmonics}")
    res = closed_ply(args.n, args.diameter_over_length, args.topology, relax=harmonics > 0,
                     harmonics=max(harmonics, 1))
    out = {"problem": "closed_ply", **res.to_dict()}
    if not getattr(args, "json", False):
        out["table"] = _table(res.values)
    return out
