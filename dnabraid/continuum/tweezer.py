"""Tweezer braid: two nicked rods between surface and bead, turned ``n`` times.

Model (zero temperature, no ``kT``)
-----------------------------------
Two identical inextensible rods of contour length ``L`` and bending stiffness ``B``; their lower
ends are tethered on the surface at ``(+-d/2, 0, 0)``, their upper ends on the bead at the same
separation ``d`` rotated by ``2 pi n`` about ``z`` (``n`` = catenation number = bead turns).
The bead is pulled with total force ``F`` along ``+z`` and does not tilt; tethers are free
hinges and the molecules are nicked (no twist moment, ``C tau = 0``).  The strands have a
hard-contact diameter ``Delta = 2 r``.

*Free branch* (strands not touching; possible for ``|n| <= n_c = arccos(Delta/d)/pi``):
two straight strands, ``z = sqrt(L^2 - d^2 sin^2(pi n))`` and
``Gamma = F d^2 sin(2 pi n) / (4 z)``.

*Braided branch*: a central uniform two-ply on the ``z`` axis (slides 15-17, see
:mod:`dnabraid.continuum.ply`): ply angle ``theta``, strand arclength ``L_p``, radius ``r``,
and four straight *tails* joining the tethers to the ply ends, symmetric under the two
rotations by ``pi`` (exchange of the strands; exchange of surface and bead).  A tail runs
from the tether ``(d/2, 0, 0)`` to the ply end ``(r cos psi0, r sin psi0, h)``; its horizontal
run is ``rho^2 = d^2/4 + r^2 - d r cos psi0`` and its length ``l_t = sqrt(h^2 + rho^2)``.
The tails may not cut into the other strand, which holds while ``cos psi0 >= Delta/d``.
Constraints and energy (``sigma = sign n``, ``theta`` and ``psi0`` carry the sign of ``n``):

* ``L = L_p + 2 l_t``                                   (inextensibility)
* ``2 pi n = 2 psi0 + L_p sin(theta) / r``              (catenation; ``psi' = sin theta / r``,
  slide 16: the tails turn the chord by ``psi0`` each)
* ``z = 2 h + L_p cos theta``                           (extension)
* ``G = L_p [B sin^4(theta)/r^2 + phi(theta)] - F z``   (slide 16 bending of the ply, tails
  straight; ``phi = alpha tan(eta/2) = -alpha tan theta``, ``eta = -2 theta``, slide 32)

``G`` is minimised over ``(theta, psi0)`` at fixed ``n`` and ``F``; the lower of the free and
braided branches is returned.  The torque on the bead is ``Gamma = dG/d(2 pi n)`` (envelope
theorem at an interior minimum):
``Gamma = sigma r / sin|theta| [B sin^4/r^2 + phi - F cos theta + F l_t / h]``.

**Handedness.**  ``n > 0`` is a right-handed braid (``theta > 0``, ``eta < 0``); ``alpha > 0``
favours it (slide 32; slide 35: positive ``n`` right-handed, more stable at high salt).
At ``alpha = 0`` the model is symmetric: ``z(-n) = z(n)``, ``Gamma(-n) = -Gamma(n)``.  The
chiral asymmetry is ``Delta z(n) = z(+n) - z(-n)``.

Where it is exact, and its error elsewhere
------------------------------------------
* *Tethers in contact* (``d = Delta``): ``psi0 = 0``, the tails are straight pieces of ply
  with ``theta = 0`` and the model is the ply with free ends of
  :func:`dnabraid.continuum.ply.solve_ply_bvp` (``bc="free"``), whose solution is the uniform
  ply filling the molecule, ``sin theta = 2 pi n r / L``, ``z = L cos theta``,
  ``Gamma = M(theta)`` of slide 17 (for a convex ``U``; a large ``alpha`` may split it into a
  tight ply and parallel strands, which the model also finds).
* *Free branch*: exact for rods with free-hinge ends (a straight rod under tension).
* Elsewhere the neglected terms are (i) the bending boundary layers at the four tail/ply
  junctions, where the tangent turns by ``gamma``: energy ``~ 8 sqrt(B T)(1 - cos(gamma/4))``
  each, with ``T`` the tail tension (reported as ``kink_energy_pN_nm`` and converted to an
  extension error ``E_kink / (2 F)`` as ``extension_error_estimate_nm``); (ii) the
  non-uniformity of ``theta`` near the ply ends (decay length ``sqrt(2B/U'')``, see
  :mod:`~dnabraid.continuum.ply`); (iii) thermal fluctuations (entropic repulsion makes real
  braids tighter and shorter at the same ``n``; this model has none).  At zero temperature the
  ply is long and loose (small ``theta``) when ``d << L``.
* The chiral potential is a contact-line potential with no ``Delta`` dependence: the
  reported ``contact_force_pN_per_nm`` may be negative for the favoured hand, in which case
  the contact holds only if the interaction is adhesive (see the ``message``).
"""

from __future__ import annotations

import argparse
import logging
import math
import time

import numpy as np
from scipy.optimize import minimize_scalar

from dnabraid.continuum._result import ContinuumResult
from dnabraid.continuum._validate import check_finite, check_positive
from dnabraid.continuum.ply import (
    DEFAULT_BENDING_PN_NM2,
    LOCKUP_ANGLE_RAD,
    chiral_potential,
    fixed_point_torque,
    uniform_ply_contact_force,
)

logger = logging.getLogger(__name__)

#: Grid points of the coarse scans that bracket the minima (inner ``theta``, outer ``psi0``).
N_SCAN_THETA = 24
N_SCAN_PSI = 16
#: Default tolerance on the minimising angles, rad.
DEFAULT_XATOL = 1e-10
#: Minimising ``theta`` closer than this to 45 deg counts as lock-up, rad.
LOCKUP_TOL_RAD = 1e-6


def _validate(turns, force_pN, length_nm, tether_separation_nm, delta_nm, bending_pN_nm2,
              alpha_pN):
    n, alpha = check_finite("turns", turns), check_finite("alpha_pN", alpha_pN)
    F, L, d, delta, B = (check_positive(name, v) for name, v in (
        ("force_pN", force_pN), ("length_nm", length_nm),
        ("tether_separation_nm", tether_separation_nm), ("delta_nm", delta_nm),
        ("bending_pN_nm2", bending_pN_nm2)))
    if d < delta:
        raise ValueError(f"tether_separation_nm ({d}) must be >= delta_nm ({delta}): the "
                         "tethered strands would overlap")
    if L <= d:
        raise ValueError(f"length_nm ({L}) must exceed tether_separation_nm ({d})")
    return n, F, L, d, delta, B, alpha


class _Model:
    """Energy of the braided branch for ``|n|`` with signed chirality ``alpha_eff``."""

    def __init__(self, n_abs, F, L, d, delta, B, alpha_eff):
        self.n, self.F, self.L, self.d, self.B, self.a = n_abs, F, L, d, B, alpha_eff
        self.r = 0.5 * delta
        self.psi_max = min(math.acos(min(1.0, delta / d)), math.pi * n_abs)

    def rho(self, psi0):
        r, d = self.r, self.d
        return math.sqrt(max(0.0, d * d / 4 + r * r - d * r * math.cos(psi0)))

    def ply_length(self, theta, psi0):
        return self.r * (2 * math.pi * self.n - 2 * psi0) / math.sin(theta)

    def theta_low(self, psi0):
        """Smallest ``theta`` with ``h >= 0`` (the ply may not need more than ``L - 2 rho``)."""
        room = self.L - 2 * self.rho(psi0)
        num = self.r * (2 * math.pi * self.n - 2 * psi0)
        if num <= 0.0:
            return 0.0
        if room <= 0.0:
            return math.inf
        x = num / room
        return math.asin(x) if x < 1.0 else math.inf

    def parts(self, theta, psi0):
        Lp = self.ply_length(theta, psi0) if self.n * 2 * math.pi - 2 * psi0 > 0 else 0.0
        lt = 0.5 * (self.L - Lp)
        rho = self.rho(psi0)
        h = math.sqrt(max(0.0, lt * lt - rho * rho))
        z = 2 * h + Lp * math.cos(theta)
        e_p = self.B * math.sin(theta) ** 4 / self.r**2 + float(chiral_potential(theta, self.a))
        G = Lp * e_p - self.F * z  # slide 16 (ply bending) + slide 32 (chiral) - F z
        return G, z, Lp, lt, h, rho

    def energy(self, theta, psi0):
        return self.parts(theta, psi0)[0]


def _bounded_min(f, lo, hi, n_scan, xatol):
    """Global-ish minimum of ``f`` on ``[lo, hi]``: coarse scan, then bounded Brent."""
    if hi - lo <= xatol:
        x = 0.5 * (lo + hi)
        return x, f(x), 1
    xs = np.linspace(lo, hi, n_scan)
    fs = [f(x) for x in xs]
    i = int(np.argmin(fs))
    a, b = xs[max(i - 1, 0)], xs[min(i + 1, n_scan - 1)]
    res = minimize_scalar(f, bounds=(a, b), method="bounded",
                          options={"xatol": xatol, "maxiter": 500})
    nfev = n_scan + int(res.nfev)
    if res.fun <= fs[i]:
        return float(res.x), float(res.fun), nfev
    return float(xs[i]), float(fs[i]), nfev


def _free_branch(n, F, L, d):
    s = math.sin(math.pi * n)
    z = math.sqrt(L * L - d * d * s * s)
    gamma = F * d * d * math.sin(2 * math.pi * n) / (4 * z)
    return {"branch": "free", "extension_nm": z, "torque_pN_nm": gamma,
            "free_energy_pN_nm": -F * z, "theta_rad": 0.0, "psi0_rad": math.pi * n,
            "ply_length_nm": 0.0, "ply_turns": 0.0, "tail_length_nm": L / 2,
            "tail_height_nm": z / 2, "tail_tilt_rad": math.atan2(d * abs(s), z),
            "contact_force_pN_per_nm": 0.0, "kink_energy_pN_nm": 0.0,
            "extension_error_estimate_nm": 0.0}


def solve_tweezer(turns: float, force_pN: float, length_nm: float, tether_separation_nm: float,
                  delta_nm: float, *, bending_pN_nm2: float = DEFAULT_BENDING_PN_NM2,
                  alpha_pN: float = 0.0, xatol: float = DEFAULT_XATOL,
                  initial: ContinuumResult | None = None) -> ContinuumResult:
    """Extension ``z(n)`` and bead torque ``Gamma(n)`` of a two-molecule tweezer braid.

    Minimises ``G = L_p [B sin^4 theta / r^2 + phi(theta)] - F z`` over the ply angle and the
    tail landing angle under the catenation and length constraints (module docstring;
    slides 16-17 for the ply, slide 32 for ``phi = -alpha tan theta``), and compares with the
    free (unbraided) branch.

    Parameters
    ----------
    turns : float
        Bead turns ``n`` (positive: right-handed braid).
    force_pN : float
        Total pulling force ``F > 0`` on the bead, pN.
    length_nm : float
        Contour length ``L`` of each molecule, nm.
    tether_separation_nm : float
        Separation ``d >= Delta`` of the tethers (surface and bead), nm.
    delta_nm : float
        Hard-contact diameter ``Delta``, nm.
    bending_pN_nm2 : float
        ``B = kT l_p``, pN nm^2 (default ``kT x 50 nm`` at 298.15 K).
    alpha_pN : float
        Chiral strength ``alpha`` (energy per contact length), pN.
    xatol : float
        Tolerance on the minimising angles, rad.
    initial : ContinuumResult, optional
        Previous solution (continuation): its ``(theta, psi0)`` are tried first and kept if
        no scan finds a lower energy; the free branch is always compared.

    Returns
    -------
    ContinuumResult
        ``values``: ``extension_nm``, ``torque_pN_nm``, ``free_energy_pN_nm`` (``G``),
        ``branch`` ("free" / "braid"), ``theta_rad``, ``theta_deg``, ``eta_rad``,
        ``psi0_rad``, ``ply_length_nm``, ``ply_turns``, ``tail_length_nm``,
        ``tail_height_nm``, ``tail_tilt_rad``, ``contact_force_pN_per_nm``,
        ``kink_energy_pN_nm``, ``extension_error_estimate_nm``; ``residual`` is the
        stationarity residual ``|dG/dtheta| / (F L)`` of an interior minimum; ``mesh_size``
        the number of energy evaluations.  ``success=False, status=3`` at lock-up or when
        ``n`` turns cannot fit in ``L``.
    """
    t0 = time.perf_counter()
    n, F, L, d, delta, B, alpha = _validate(turns, force_pN, length_nm, tether_separation_nm,
                                            delta_nm, bending_pN_nm2, alpha_pN)
    xatol = float(xatol)
    if not (xatol > 0):
        raise ValueError(f"xatol must be positive, got {xatol!r}")
    sigma = 1.0 if n >= 0 else -1.0
    n_abs = abs(n)
    n_c = math.acos(min(1.0, delta / d)) / math.pi
    if n_abs == 0.0:
        vals = _free_branch(0.0, F, L, d)
        return ContinuumResult(True, 0, "n = 0: straight strands", _finish(vals, sigma),
                               0.0, 1, time.perf_counter() - t0)
    try:
        model = _Model(n_abs, F, L, d, delta, B, sigma * alpha)
        best = _braid_minimum(model, xatol, initial, sigma)
    except (ValueError, ZeroDivisionError, OverflowError, FloatingPointError) as exc:
        return ContinuumResult(False, 4, f"minimisation failed: {exc}", {}, math.nan, 0,
                               time.perf_counter() - t0)
    free = _free_branch(n_abs, F, L, d) if n_abs <= n_c else None
    nfev = best["nfev"] if best else 0
    if best is None and free is None:
        wall = time.perf_counter() - t0
        return ContinuumResult(False, 3, f"{n} turns do not fit in L={L} nm below lock-up "
                               "(45 deg): the braid would have to buckle", {}, math.nan, nfev,
                               wall)
    if best is None or (free is not None and free["free_energy_pN_nm"] <= best["G"]):
        vals = free
        wall = time.perf_counter() - t0
        return ContinuumResult(True, 0, "converged (free branch: strands apart)",
                               _finish(vals, sigma), 0.0, nfev + 1, wall)
    *_, h, rho = model.parts(best["theta"], best["psi0"])
    if h <= 1e-12 * L and rho > 1e-9 * L:
        return ContinuumResult(False, 4, f"tails lie flat on the surface (h = {h:.3g} nm) at "
                               f"F={F} pN: the tension is too small to resolve the braid "
                               "geometry in floating point", {}, math.nan, nfev,
                               time.perf_counter() - t0)
    vals, residual, msg = _braid_values(model, best, sigma)
    wall = time.perf_counter() - t0
    if LOCKUP_ANGLE_RAD - best["theta"] < LOCKUP_TOL_RAD:
        return ContinuumResult(False, 3, "minimum at the lock-up angle (45 deg): the ply "
                               "cannot tighten further, the braid would buckle; outside the "
                               "model", _finish(vals, sigma), residual, nfev, wall)
    return ContinuumResult(True, 0, msg, _finish(vals, sigma), residual, nfev, wall)


def _finish(vals, sigma):
    """Give the angles (and the free-branch torque) the sign of ``n``."""
    out = dict(vals)
    for k in ("theta_rad", "psi0_rad", "ply_turns"):
        out[k] = sigma * abs(vals[k])
    if vals["branch"] == "free":
        out["torque_pN_nm"] = sigma * vals["torque_pN_nm"]
    out["theta_deg"] = math.degrees(out["theta_rad"])
    out["eta_rad"] = -2.0 * out["theta_rad"]  # slide 15
    return out


def _braid_minimum(model: _Model, xatol, initial, sigma):
    """Nested minimisation over ``psi0`` (outer) and ``theta`` (inner)."""
    lock = LOCKUP_ANGLE_RAD
    counter = {"nfev": 0}

    def inner(psi0):
        lo = model.theta_low(psi0)
        if not lo < lock:
            return None
        lo = max(lo, 1e-12)

        def f(t):
            return model.energy(t, psi0)

        # scan in log(tan theta) when the window spans decades
        if lock / lo > 50:
            def g(u):
                return f(math.atan(math.exp(u)))

            u, val, nf = _bounded_min(g, math.log(math.tan(lo)), 0.0, N_SCAN_THETA, xatol)
            counter["nfev"] += nf
            return math.atan(math.exp(u)), val
        t, val, nf = _bounded_min(f, lo, lock, N_SCAN_THETA, xatol)
        counter["nfev"] += nf
        return t, val

    def outer(psi0):
        res = inner(psi0)
        return math.inf if res is None else res[1]

    psi_hi = model.psi_max
    # exclude the no-ply end point psi0 = pi n (that is the free/touching configuration)
    if psi_hi >= math.pi * model.n:
        psi_hi = math.pi * model.n * (1 - 1e-9)
    if psi_hi <= 0.0:
        psi = 0.0
    else:
        psi, _, nf = _bounded_min(outer, 0.0, psi_hi, N_SCAN_PSI, xatol)
        counter["nfev"] += nf
        if not math.isfinite(outer(psi)):
            return None
    res = inner(psi)
    if res is None:
        return None
    theta, G = res
    if initial is not None and initial.success and initial.values.get("branch") == "braid":
        t_i = abs(initial.values["theta_rad"])
        p_i = min(abs(initial.values["psi0_rad"]), psi_hi)
        if model.theta_low(p_i) < t_i < lock:
            G_i = model.energy(t_i, p_i)
            if G_i < G:
                theta, psi, G = t_i, p_i, G_i
    return {"theta": theta, "psi0": psi, "G": G, "nfev": counter["nfev"]}


def _braid_values(model: _Model, best, sigma):
    theta, psi0 = best["theta"], best["psi0"]
    F, B, r, L = model.F, model.B, model.r, model.L
    G, z, Lp, lt, h, rho = model.parts(theta, psi0)
    s, c = math.sin(theta), math.cos(theta)
    e_p = B * s**4 / r**2 + float(chiral_potential(theta, model.a))
    fills = h < 1e-9 * L and rho < 1e-9 * L  # tethers in contact, ply fills the molecule
    if fills:
        # constrained minimum sin(theta) = 2 pi n r / L: Gamma = M(theta), slide 17
        gamma = float(fixed_point_torque(theta, F, 2 * r, B, model.a))
        residual = 0.0
    else:
        gamma = r / s * (e_p - F * c + F * lt / h)  # envelope theorem, dG/d(2 pi n)
        # stationarity residual |dG/dtheta| (analytic), pN nm per rad
        dLp = -Lp * c / s
        de_p = 4 * B * s**3 * c / r**2 - model.a / c**2  # slides 17, 32
        residual = abs(dLp * (e_p - F * c) + Lp * (de_p + F * s) + F * (lt / h) * dLp) / (F * L)
    contact = uniform_ply_contact_force(theta, F, 2 * r, B, model.a)
    # kink angle between tail (towards the ply) and ply tangent at a junction
    if not fills and lt > 0 and h > 0:
        q = np.array([model.d / 2, 0.0, 0.0])
        j = np.array([r * math.cos(psi0), r * math.sin(psi0), h])
        u = (j - q) / lt
        t = np.array([-s * math.sin(psi0), s * math.cos(psi0), c])
        gam = math.acos(max(-1.0, min(1.0, float(u @ t))))
        tension = 0.5 * F * lt / h
        kink = 4 * 8 * math.sqrt(B * tension) * (1 - math.cos(gam / 4))
        tilt = math.atan2(rho, h)
    else:
        kink, tilt = 0.0, 0.0
    vals = {"branch": "braid", "extension_nm": z, "torque_pN_nm": sigma * gamma,
            "free_energy_pN_nm": G, "theta_rad": theta, "psi0_rad": psi0,
            "ply_length_nm": Lp, "ply_turns": Lp * s / (2 * math.pi * r),
            "tail_length_nm": lt, "tail_height_nm": h, "tail_tilt_rad": tilt,
            "contact_force_pN_per_nm": contact, "kink_energy_pN_nm": kink,
            "extension_error_estimate_nm": kink / (2 * F)}
    msg = "converged (braid branch" + (", ply fills the molecule)" if fills else ")")
    if contact < 0:
        msg += ("; contact force < 0: the contact holds only if the chiral interaction is "
                "adhesive")
    return vals, residual, msg


def tweezer_curve(turns, force_pN, length_nm, tether_separation_nm, delta_nm,
                  **kwargs) -> list[ContinuumResult]:
    """Solve :func:`solve_tweezer` along ``turns`` (in order), reusing each solution
    as ``initial`` of the next (continuation in ``n``)."""
    out, last = [], None
    for n in turns:
        res = solve_tweezer(n, force_pN, length_nm, tether_separation_nm, delta_nm,
                            initial=last, **kwargs)
        out.append(res)
        last = res if res.success else None
    return out


def handedness_asymmetry(turns: float, force_pN: float, length_nm: float,
                         tether_separation_nm: float, delta_nm: float, **kwargs) -> dict:
    """``Delta z(n) = z(+n) - z(-n)`` and ``Gamma(+n) + Gamma(-n)`` (zero when ``alpha = 0``).

    Returns
    -------
    dict
        ``delta_z_nm``, ``torque_sum_pN_nm``, ``delta_G_pN_nm`` (``G(+n) - G(-n)``),
        ``success`` (both solves), ``message``, and the two results under ``plus``/``minus``.
    """
    n = abs(float(turns))
    rp = solve_tweezer(n, force_pN, length_nm, tether_separation_nm, delta_nm, **kwargs)
    rm = solve_tweezer(-n, force_pN, length_nm, tether_separation_nm, delta_nm, **kwargs)
    ok = rp.success and rm.success
    out = {"turns": n, "success": ok, "message": f"+n: {rp.message}; -n: {rm.message}",
           "plus": rp, "minus": rm, "wall_time_s": rp.wall_time_s + rm.wall_time_s}
    if ok:
        out["delta_z_nm"] = rp["extension_nm"] - rm["extension_nm"]
        out["torque_sum_pN_nm"] = rp["torque_pN_nm"] + rm["torque_pN_nm"]
        out["delta_G_pN_nm"] = rp["free_energy_pN_nm"] - rm["free_energy_pN_nm"]
    else:
        out["delta_z_nm"] = out["torque_sum_pN_nm"] = out["delta_G_pN_nm"] = math.nan
    return out


# --------------------------------------------------------------------------- CLI / workflow
def cli_add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of the tweezer-braid problem."""
    parser.add_argument("--turns", type=float, nargs="+", default=[2.0],
                        help="bead turns n (catenation number; positive = right-handed)")
    parser.add_argument("--force-pN", type=float, default=2.0, help="total force on bead, pN")
    parser.add_argument("--length-nm", type=float, default=1000.0,
                        help="contour length of each molecule, nm")
    parser.add_argument("--tether-separation-nm", type=float, default=50.0,
                        help="tether separation d on surface and bead, nm")
    parser.add_argument("--delta-nm", type=float, default=5.0,
                        help="hard-contact diameter Delta, nm")
    parser.add_argument("--alpha-pN", type=float, default=0.0,
                        help="chiral strength alpha (energy per contact length), pN")
    parser.add_argument("--bending-pN-nm2", type=float, default=DEFAULT_BENDING_PN_NM2,
                        help="bending stiffness B = kT lp, pN nm^2")
    parser.add_argument("--asymmetry", action="store_true",
                        help="also solve -n and report Delta z = z(+n) - z(-n)")


def cli_run(args) -> dict:
    """Solve the tweezer braid for each ``--turns``; JSON-serialisable summary."""
    t0 = time.perf_counter()
    kw = {"bending_pN_nm2": args.bending_pN_nm2, "alpha_pN": args.alpha_pN}
    geo = (args.force_pN, args.length_nm, args.tether_separation_nm, args.delta_nm)
    rows = []
    for res, n in zip(tweezer_curve(args.turns, *geo, **kw), args.turns):
        row = {"turns": float(n), **res.to_dict()}
        if args.asymmetry:
            asym = handedness_asymmetry(n, *geo, **kw)
            row["delta_z_nm"] = float(asym["delta_z_nm"])
            row["torque_sum_pN_nm"] = float(asym["torque_sum_pN_nm"])
        rows.append(row)
    return {"problem": "tweezer_braid", "success": all(r["success"] for r in rows),
            "rows": rows, "wall_time_s": time.perf_counter() - t0}


def convergence_table() -> list[dict]:
    """Error of ``z`` and ``Gamma`` against the minimiser tolerance, with wall time.

    Two cases: (a) ``d = Delta`` (tethers in contact), error against the exact uniform ply
    ``z = L cos theta``, ``Gamma = M(theta)`` with ``sin theta = 2 pi n r / L``; (b) ``d = 50 nm``,
    error against a reference at ``xatol = 1e-13``.  ``L = 1000 nm``, ``F = 2 pN``,
    ``Delta = 5 nm``, ``n = 5``.
    """
    rows = []
    L, F, delta, n = 1000.0, 2.0, 5.0, 5.0
    th = math.asin(2 * math.pi * n * 0.5 * delta / L)
    z_ex, g_ex = L * math.cos(th), float(fixed_point_torque(th, F, delta))
    for xatol in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10):
        res = solve_tweezer(n, F, L, delta, delta, xatol=xatol)
        err = max(abs(res["extension_nm"] - z_ex), abs(res["torque_pN_nm"] - g_ex))
        rows.append({"problem": "tweezer_d_eq_delta_vs_exact", "setting": f"xatol={xatol:g}",
                     "mesh_nodes": res.mesh_size, "error": err, "success": res.success,
                     "wall_time_s": res.wall_time_s})
    ref = solve_tweezer(n, F, L, 50.0, delta, xatol=1e-13)
    for xatol in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10):
        res = solve_tweezer(n, F, L, 50.0, delta, xatol=xatol)
        err = max(abs(res["extension_nm"] - ref["extension_nm"]),
                  abs(res["torque_pN_nm"] - ref["torque_pN_nm"]))
        rows.append({"problem": "tweezer_d50_vs_reference", "setting": f"xatol={xatol:g}",
                     "mesh_nodes": res.mesh_size, "error": err, "success": res.success,
                     "wall_time_s": res.wall_time_s})
    return rows
