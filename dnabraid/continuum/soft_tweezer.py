"""Tweezer braid whose chiral term has the bead model's range: the strands may open.

:func:`dnabraid.continuum.tweezer.solve_tweezer` keeps the two strands in hard contact at a
fixed axis distance ``Delta`` and gives them the chiral energy ``alpha tan(eta/2)`` per unit
contact length (van der Heijden, *Equilibrium theory of elastic braids*, slide 32, after
Kornyshev et al., Rev. Mod. Phys. 79, 943 (2007)). The bead model's chiral weight decays
beyond the contact distance ``D_c`` with the range ``rho`` of the first helical harmonic of
the charge pattern (:mod:`dnabraid.forces.reference_chiral`, Eqs. C2 and C6):

    w(d) = 1 (d <= D_c),   w(d) = (1 + x/rho) exp(-x/rho) S(d),   x = d - D_c,

``S`` the C2 switch to zero between ``D_c + 4 rho`` and ``D_c + 6 rho``; ``w = 1`` at ``D_c``
is the normalisation of alpha in both models. Here the axis distance ``d = D_c + x``,
``x >= 0``, is a free variable of the continuum braid (no strand may come closer than
``D_c``): the total energy at fixed bead turns ``n`` and force ``F``

    E(x; shape) = L_p [B sin^4(theta)/r^2 + alpha w(D_c + x) tan(eta/2)] - F z,   r = d/2,

(elastic + chiral + the force's work ``-F z``; ``eta = -2 theta``) is minimised over the shape
``(theta, psi0)`` AND ``x``. For each ``x`` the minimum over the shape is
:func:`solve_tweezer` at ``Delta = D_c + x`` with ``alpha_eff = alpha w(D_c + x)``; its
``free_energy_pN_nm`` is exactly ``E`` (``-F z`` included, on both branches), so

    E*(x) = solve_tweezer(n, F, L, d_t, D_c + x, alpha_pN=alpha w(D_c + x))["free_energy_pN_nm"]

and the braid's equilibrium is the minimum of ``E*(x)`` on ``0 <= x <= 6 rho`` (beyond the
cutoff ``w = 0`` and ``E*`` rises with ``x`` while the braid presses, p > 0). ``E*(x)`` may
have two local minima: in contact (``x = 0``; ``w'(D_c) = 0``, so the contact is a minimum
whenever the hard-contact pressure is positive) and open, where the chiral term's radial
force ``-alpha w'(d) tan(eta/2)`` (positive, opening, for the disfavoured hand) balances the
pressure of the braid: for a uniform ply ``p(theta, d) = alpha |w'(d)| tan(|eta|/2)``
(``p`` of :func:`dnabraid.continuum.ply.uniform_ply_contact_force`), in closed form
``(x/rho^2) exp(-x/rho) = p / (alpha tan(|eta|/2))`` below the switch. So ``E*`` is scanned
on a grid first and every local minimum refined (bounded Brent).

Envelope theorem: at a minimum over ``x`` (interior or at ``x = 0``), the bead torque
``Gamma = dE/d(2 pi n)`` is the torque of the shape solve at ``(D_c + x*, alpha w(D_c + x*))``
(tested against a finite difference of the re-minimised ``E`` in ``n``).

Branches. ``branch="global"`` returns the lowest minimum. ``branch="path"`` returns the one
a quasi-static experiment reaches, as the bead model's
:func:`dnabraid.validation.crosscheck.zero_temperature_braid` does: the turns go from 0 to
``n`` in ``increments`` steps and at each the gap descends into the minimum whose basin holds
the previous gap, starting apart (``x = 6 rho``: the strands come together from outside).

Neglected (besides what :mod:`~dnabraid.continuum.tweezer` neglects): the chiral energy of the
tails, which leave the ply within a few ``rho`` of contact; the weight's ``sqrt(D_c/d)``
factor (as the bead model).
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.optimize import minimize_scalar

from dnabraid.continuum._result import ContinuumResult
from dnabraid.continuum._validate import check_finite, check_positive
from dnabraid.continuum.ply import DEFAULT_BENDING_PN_NM2
from dnabraid.continuum.tweezer import DEFAULT_XATOL, solve_tweezer

#: Grid points of the scan of E*(x) on [0, x_max] (x_max = 6 rho: 0.056 nm apart at 150 mM).
N_SCAN_GAP = 49
#: Tolerance on the refined gap, nm.
DEFAULT_GAP_XATOL_NM = 1e-7
#: Trap increments of the quasi-static path (``branch="path"``): the bead model's default.
DEFAULT_INCREMENTS = 40


def chiral_weight(contact_nm: float, debye_nm: float, range_nm: float | None = None):
    """The bead model's distance weight as a function ``d -> (w, dw/dd)`` (d in nm, dw/dd in
    1/nm): :meth:`dnabraid.forces.reference_chiral.ChiralKernel.weight` with D_c =
    ``contact_nm`` and rho = ``range_nm`` (default ``chiral_range_nm(debye_nm)``, Eq. C6).
    Returns the function and the kernel (for its ``range``, ``r_s``, ``r_c``)."""
    from dnabraid.forces.reference_chiral import ChiralKernel

    kernel = ChiralKernel(contact_nm, debye_nm, range_nm=range_nm)

    def weight(d):
        w, dw = kernel.weight(float(d))
        return float(w), float(dw)

    return weight, kernel


class _GapProblem:
    """E*(x) at fixed n: one :func:`solve_tweezer` per gap, memoised."""

    def __init__(self, n, F, L, d_t, D_c, B, alpha, weight, x_max, xatol):
        self.args = (n, F, L, d_t)
        self.D_c, self.B, self.alpha, self.weight = D_c, B, alpha, weight
        self.x_max, self.xatol = x_max, xatol
        self.cache: dict[float, ContinuumResult] = {}

    def solve(self, x):
        x = float(x)
        if x not in self.cache:
            w, _ = self.weight(self.D_c + x)
            self.cache[x] = solve_tweezer(*self.args, self.D_c + x, bending_pN_nm2=self.B,
                                          alpha_pN=self.alpha * w, xatol=self.xatol)
        return self.cache[x]

    def energy(self, x):
        r = self.solve(x)
        return r["free_energy_pN_nm"] if r.success else math.inf

    def scan(self, n_scan):
        xs = np.linspace(0.0, self.x_max, n_scan)
        return xs, np.array([self.energy(x) for x in xs])

    def refine(self, xs, fs, i, gap_xatol):
        """The local minimum of the scan at grid index ``i``, refined (x, E)."""
        x0, f0 = float(xs[i]), float(fs[i])
        lo, hi = xs[max(i - 1, 0)], xs[min(i + 1, len(xs) - 1)]
        res = minimize_scalar(self.energy, bounds=(float(lo), float(hi)), method="bounded",
                              options={"xatol": gap_xatol, "maxiter": 200})
        # bounded Brent never evaluates the bounds: keep a grid point (x = 0) that is lower
        if res.fun < f0:
            return float(res.x), float(res.fun)
        return x0, f0


def _local_minima(fs):
    """Indices of the scan's local minima (end points included), by energy."""
    n = len(fs)
    idx = [i for i in range(n) if math.isfinite(fs[i])
           and (i == 0 or fs[i] <= fs[i - 1]) and (i == n - 1 or fs[i] <= fs[i + 1])]
    return sorted(idx, key=lambda i: fs[i])


def _descend(fs, i):
    """From grid index ``i``, walk downhill on the scan to a local minimum."""
    n = len(fs)
    while True:
        nb = [j for j in (i - 1, i + 1) if 0 <= j < n and fs[j] < fs[i]]
        if not nb:
            return i
        i = min(nb, key=lambda j: fs[j])


def solve_soft_tweezer(turns: float, force_pN: float, length_nm: float,
                       tether_separation_nm: float, contact_nm: float, *, debye_nm: float,
                       range_nm: float | None = None,
                       bending_pN_nm2: float = DEFAULT_BENDING_PN_NM2, alpha_pN: float = 0.0,
                       branch: str = "global", increments: int = DEFAULT_INCREMENTS,
                       n_scan: int = N_SCAN_GAP, gap_xatol_nm: float = DEFAULT_GAP_XATOL_NM,
                       xatol: float = DEFAULT_XATOL) -> ContinuumResult:
    """Tweezer braid with the bead model's chiral weight: minimum over shape and gap.

    Parameters
    ----------
    turns, force_pN, length_nm, tether_separation_nm, bending_pN_nm2, alpha_pN, xatol
        As :func:`~dnabraid.continuum.tweezer.solve_tweezer` (turns; pN; nm; nm; pN nm^2;
        pN; rad).
    contact_nm : float
        Contact distance D_c, nm: the closest axis distance and where ``w = 1``.
    debye_nm : float
        Debye length, nm (sets rho = ``chiral_range_nm(debye_nm)`` unless ``range_nm``).
    range_nm : float, optional
        Range rho of the weight, nm.
    branch : {"global", "path"}
        The lowest minimum over the gap, or the one a quasi-static turning reaches (module
        docstring).
    increments : int
        Steps of the quasi-static path (``branch="path"``).
    n_scan : int
        Grid points of the scan of E*(x) on ``[0, 6 rho]``.
    gap_xatol_nm : float
        Tolerance on the gap, nm.

    Returns
    -------
    ContinuumResult
        ``values``: those of :func:`solve_tweezer` at the optimum (``extension_nm``,
        ``torque_pN_nm``, ``free_energy_pN_nm`` = E*, ``theta_rad``, ``eta_rad``,
        ``contact_force_pN_per_nm`` = p of the uniform ply at the optimum with the hard
        constraint, ...), and ``gap_nm`` (x*, nm), ``axis_distance_nm`` (D_c + x*, nm),
        ``contact_nm`` (D_c), ``range_nm`` (rho), ``chiral_weight`` (w*),
        ``chiral_weight_slope_per_nm`` (w'*), ``alpha_eff_pN`` (alpha w*),
        ``chiral_radial_force_pN_per_nm`` (``-alpha w'(d*) tan(eta*/2)``, > 0 opens),
        ``energy_at_contact_pN_nm`` (E*(0)), ``local_minima`` (list of ``{"gap_nm",
        "energy_pN_nm"}`` at the final turns, lowest first), ``branch_rule``.
        ``success=False`` when the shape solve fails at the optimum (e.g. lock-up).
    """
    t0 = time.perf_counter()
    n, alpha = check_finite("turns", turns), check_finite("alpha_pN", alpha_pN)
    F, L, d_t, D_c, B, lam = (check_positive(k, v) for k, v in (
        ("force_pN", force_pN), ("length_nm", length_nm),
        ("tether_separation_nm", tether_separation_nm), ("contact_nm", contact_nm),
        ("bending_pN_nm2", bending_pN_nm2), ("debye_nm", debye_nm)))
    if branch not in ("global", "path"):
        raise ValueError(f"branch must be 'global' or 'path', got {branch!r}")
    if int(n_scan) < 3 or int(increments) < 1:
        raise ValueError(f"need n_scan >= 3 and increments >= 1, got {n_scan!r}, "
                         f"{increments!r}")
    weight, kernel = chiral_weight(D_c, lam, range_nm)
    x_max = min(kernel.r_c, d_t) - D_c
    if not x_max > 0:
        raise ValueError(f"tether_separation_nm ({d_t}) must exceed contact_nm ({D_c})")

    def problem(turns_k):
        return _GapProblem(turns_k, F, L, d_t, D_c, B, alpha, weight, x_max, xatol)

    prob = problem(n)
    xs, fs = prob.scan(int(n_scan))
    minima = _local_minima(fs)
    nfev = 0
    if branch == "global" or len(minima) <= 1:
        # with one minimum at the final turns every quasi-static path ends in it
        rule = "global minimum over the gap" + (
            "" if branch == "global" else " (the only one: every path ends there)")
        pick = minima[0] if minima else None
    else:
        x_prev = x_max  # strands apart before they first meet
        for k in range(1, int(increments)):
            pk = problem(n * k / int(increments))
            xk, fk = pk.scan(int(n_scan))
            nfev += len(pk.cache)
            ok = np.isfinite(fk)
            if not ok.any() or np.ptp(fk[ok]) <= 1e-12 * max(1.0, abs(fk[ok][0])):
                continue  # free branch: E* does not depend on the gap, no contact yet
            i = _descend(fk, int(np.argmin(np.abs(xk - x_prev))))
            x_prev, _ = pk.refine(xk, fk, i, gap_xatol_nm)
        pick = _descend(fs, int(np.argmin(np.abs(xs - x_prev))))
        rule = f"quasi-static path in {int(increments)} increments from apart"
    if pick is None:
        return ContinuumResult(False, 4, "no finite energy on the gap scan", {}, math.nan,
                               nfev + len(prob.cache), time.perf_counter() - t0)
    local = [dict(zip(("gap_nm", "energy_pN_nm"), prob.refine(xs, fs, i, gap_xatol_nm)))
             for i in minima]
    x_star, _ = prob.refine(xs, fs, pick, gap_xatol_nm)
    res = prob.solve(x_star)
    nfev += len(prob.cache)
    wall = time.perf_counter() - t0
    if not res.success:
        return ContinuumResult(False, res.status, f"shape solve at the optimum gap "
                               f"{x_star:.4g} nm: {res.message}", dict(res.values),
                               res.residual, nfev, wall)
    w, dw = weight(D_c + x_star)
    vals = dict(res.values)
    vals.update({
        "gap_nm": x_star, "axis_distance_nm": D_c + x_star, "contact_nm": D_c,
        "range_nm": kernel.range, "chiral_weight": w, "chiral_weight_slope_per_nm": dw,
        "alpha_eff_pN": alpha * w,
        "chiral_radial_force_pN_per_nm": -alpha * dw * math.tan(0.5 * vals["eta_rad"]),
        "energy_at_contact_pN_nm": prob.energy(0.0), "local_minima": local,
        "branch_rule": rule})
    where = "in contact" if x_star == 0.0 else f"open by {x_star:.3f} nm"
    if x_star >= x_max * (1 - 1e-9):
        where += " (at the weight's cutoff: the scan's end, the strands would separate)"
    msg = f"{res.message}; {where}; {len(local)} local minimum/minima over the gap"
    return ContinuumResult(True, 0, msg, vals, res.residual, nfev, wall)


def soft_handedness_asymmetry(turns: float, force_pN: float, length_nm: float,
                              tether_separation_nm: float, contact_nm: float,
                              **kwargs) -> dict:
    """``z(+n) - z(-n)`` (nm), ``Gamma(+n) + Gamma(-n)`` (pN nm) and the axis distances at
    +-n (nm) of :func:`solve_soft_tweezer` (same keyword arguments)."""
    n = abs(float(turns))
    rp = solve_soft_tweezer(n, force_pN, length_nm, tether_separation_nm, contact_nm, **kwargs)
    rm = solve_soft_tweezer(-n, force_pN, length_nm, tether_separation_nm, contact_nm,
                            **kwargs)
    ok = rp.success and rm.success
    out = {"turns": n, "success": ok, "plus": rp, "minus": rm,
           "message": f"+n: {rp.message}; -n: {rm.message}"}
    if ok:
        out["delta_z_nm"] = rp["extension_nm"] - rm["extension_nm"]
        out["torque_sum_pN_nm"] = rp["torque_pN_nm"] + rm["torque_pN_nm"]
        out["axis_distance_plus_nm"] = rp["axis_distance_nm"]
        out["axis_distance_minus_nm"] = rm["axis_distance_nm"]
    else:
        for k in ("delta_z_nm", "torque_sum_pN_nm", "axis_distance_plus_nm",
                  "axis_distance_minus_nm"):
            out[k] = math.nan
    return out
