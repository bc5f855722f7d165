"""The hat curve of torsionally constrained DNA against rod theory.

From a ``plectoneme`` run over a range of turns (its ``summary.json``):

* below buckling, the twist-torque slope gives an effective twist stiffness
  C_eff = (dGamma/dn) L / (2 pi kT), against Moroz & Nelson (PNAS 94, 14418 (1997), Eq. 12):
  C_eff(F) = C (1 - (C / 4A) sqrt(kT / (A F))) (A, C persistence lengths in nm);
* the buckling point (first turn value with a plectoneme in more than half the frames) and
  the torque plateau after it, against the classical buckling torque
  Gamma_b = sqrt(2 kT A F) (kT A the bending stiffness in pN nm^2; Marko, PRE 76, 021926
  (2007), explains why a finite chain's plateau lies above it);
* after buckling, the two-phase coexistence of Marko (PRE 76, 021926 (2007)): a stretched
  phase of free energy per length -g + c_s w^2 / 2 (g = F - sqrt(kT F / A), c_s = kT C_eff
  of Moroz & Nelson) and a plectoneme phase (kT P / 2) w^2 of no extension exchange length
  at equal torque tau and equal free energy at fixed torque, which gives
  tau^2 = 2 g kT P c_s / (c_s - kT P) and, eliminating the unknown plectoneme stiffness P,
  the parameter-free slope of the extension against turns
  dz/dn = -2 pi x / (w_p - w_s) = -pi x tau / g, with x = 1 - sqrt(kT / (A F)) / 2 the
  stretched phase's extension per length (:func:`marko_two_phase`,
  :func:`coexistence_slope`, :func:`implied_plectoneme_stiffness`).
"""

from __future__ import annotations

import math

import numpy as np

from ..units import KB_PN_NM, TWO_PI

__all__ = ["moroz_nelson_ceff", "buckling_torque", "marko_two_phase", "coexistence_slope",
           "implied_plectoneme_stiffness", "hat_curve"]


def moroz_nelson_ceff(C: float, A: float, F: float, kT: float) -> float:
    """Effective twist persistence C_eff (nm) of a stretched rod (Moroz & Nelson 1997,
    Eq. 12): C (1 - (C / 4A) sqrt(kT / (A F))); C, A in nm, F in pN, kT in pN nm."""
    return C * (1.0 - C / (4.0 * A) * math.sqrt(kT / (A * F)))


def buckling_torque(A: float, F: float, kT: float) -> float:
    """The classical buckling torque sqrt(2 kT A F) (pN nm); A in nm, F in pN."""
    return math.sqrt(2.0 * kT * A * F)


def _stretched(A: float, F: float, kT: float) -> tuple[float, float]:
    """g (pN) and x of the stretched phase (high-force WLC; Marko 2007)."""
    if not (A > 0 and F > 0 and kT > 0):
        raise ValueError("A, F and kT must be > 0")
    g = F - math.sqrt(kT * F / A)
    if g <= 0:
        raise ValueError(f"F = {F} pN is below kT / A = {kT / A:.3g} pN: the high-force "
                         "stretched phase of the two-phase model does not apply")
    return g, 1.0 - 0.5 * math.sqrt(kT / (A * F))


def marko_two_phase(C: float, A: float, F: float, kT: float, P: float) -> dict:
    """Marko's (2007) two-phase coexistence for a plectoneme twist stiffness P (nm).

    Returns ``torque`` (pN nm, the coexistence torque), ``omega_s``, ``omega_p`` (twist
    rates of the two phases, rad/nm), ``slope_nm_per_turn`` (dz/dn after buckling), ``x``
    and ``g`` (pN) of the stretched phase and ``C_s`` (nm). P must lie below C_s."""
    g, x = _stretched(A, F, kT)
    cs = moroz_nelson_ceff(C, A, F, kT)
    if not 0 < P < cs:
        raise ValueError(f"P = {P} nm must lie in (0, C_s = {cs:.3g} nm)")
    tau = kT * math.sqrt(2.0 * (g / kT) * P * cs / (cs - P))
    ws, wp = tau / (kT * cs), tau / (kT * P)
    return {"torque": tau, "omega_s": ws, "omega_p": wp, "C_s": cs, "g": g, "x": x,
            "slope_nm_per_turn": -TWO_PI * x / (wp - ws)}


def coexistence_slope(torque: float, A: float, F: float, kT: float) -> float:
    """The two-phase slope dz/dn = -pi x tau / g (nm per turn) at coexistence torque tau
    (pN nm), whatever the plectoneme's stiffness (module docstring)."""
    g, x = _stretched(A, F, kT)
    return -math.pi * x * torque / g


def implied_plectoneme_stiffness(torque: float, C: float, A: float, F: float,
                                 kT: float) -> float:
    """The plectoneme twist stiffness P (nm) for which Marko's coexistence torque equals
    ``torque``: 1 / P = 1 / C_s + 2 g kT / tau^2."""
    g, _ = _stretched(A, F, kT)
    return 1.0 / (1.0 / moroz_nelson_ceff(C, A, F, kT) + 2.0 * g * kT / torque ** 2)


def hat_curve(summary: dict) -> tuple[list, dict]:
    """The points of a plectoneme run sorted by turns, and its comparison with theory.

    Returns
    -------
    points : list of dict
    result : dict
        ``kT``, ``C``, ``ceff_theory``, ``gamma_b_theory``, ``n_buckle`` (NaN without
        buckling) and, where the run allows, ``ceff_sim`` +- ``ceff_sim_err`` (nm; a
        weighted fit through 0 of the twist torque at the unbuckled points) and
        ``plateau_torque`` +- ``plateau_torque_err`` (pN nm; the mean twist torque of the
        buckled points) and, with two or more buckled points, ``slope_sim`` +-
        ``slope_sim_err`` (nm per turn; a weighted straight line through their extensions)
        beside ``slope_two_phase`` +- ``slope_two_phase_err`` (:func:`coexistence_slope` at
        the plateau torque), ``P_implied`` (nm; :func:`implied_plectoneme_stiffness`) and
        ``n_onset_two_phase`` (turns at which the stretched phase's torque, C_eff of
        Moroz-Nelson, reaches the plateau: where the two-phase model starts coexistence).
    """
    sc = summary["scene"]
    kT = KB_PN_NM * float(sc.get("temperature_K", 298.15))
    L, C = float(sc["length_nm"]), float(sc["twist_persistence_nm"])
    A, F = float(sc["persistence_nm"]), float(sc["force_pN"])
    pts = sorted(summary["points"], key=lambda p: p["turns"])
    n = np.array([p["turns"] for p in pts])
    tq = np.array([p["twist_torque_pN_nm"]["mean"] for p in pts])
    tq_sem = np.array([p["twist_torque_pN_nm"]["sem"] for p in pts])
    frac = np.array([np.nan if p["plectoneme_fraction"] is None else p["plectoneme_fraction"]
                     for p in pts])  # None: no frame sampled
    buckled = np.nonzero(frac > 0.5)[0]
    nb = n[buckled[0]] if buckled.size else math.nan
    # below buckling: points before the first buckled one with no plectoneme in any frame
    lin = (frac == 0) & (n < nb if buckled.size else np.ones(n.size, bool))
    out = {"kT": kT, "gamma_b_theory": buckling_torque(A, F, kT),
           "ceff_theory": moroz_nelson_ceff(C, A, F, kT), "n_buckle": nb, "C": C, "L": L}
    if lin.sum() >= 2:
        w = 1.0 / np.maximum(tq_sem[lin], 1e-9) ** 2
        slope = float(np.sum(w * n[lin] * tq[lin]) / np.sum(w * n[lin] ** 2))  # through 0
        dslope = float(1.0 / math.sqrt(np.sum(w * n[lin] ** 2)))
        out["ceff_sim"] = slope * L / (TWO_PI * kT)
        out["ceff_sim_err"] = dslope * L / (TWO_PI * kT)
    if buckled.size:
        out["plateau_torque"] = float(np.mean(tq[buckled]))
        out["plateau_torque_err"] = float(np.sqrt(np.sum(tq_sem[buckled] ** 2)) / buckled.size)
        tau, dtau = out["plateau_torque"], out["plateau_torque_err"]
        if F * A > kT and tau > 0:  # the two-phase model's high-force stretched phase
            s1 = coexistence_slope(1.0, A, F, kT)
            out["slope_two_phase"], out["slope_two_phase_err"] = s1 * tau, abs(s1) * dtau
            out["P_implied"] = implied_plectoneme_stiffness(tau, C, A, F, kT)
            # where the stretched phase reaches the plateau torque: the two-phase onset
            out["n_onset_two_phase"] = tau * L / (TWO_PI * kT * out["ceff_theory"])
    if buckled.size >= 2:
        z = np.array([p["extension_nm"]["mean"] for p in pts])[buckled]
        zs = np.array([p["extension_nm"]["sem"] for p in pts])[buckled]
        w = 1.0 / np.maximum(zs, 1e-9) ** 2
        nb_ = n[buckled]
        nm_ = np.sum(w * nb_) / np.sum(w)
        sxx = np.sum(w * (nb_ - nm_) ** 2)
        out["slope_sim"] = float(np.sum(w * (nb_ - nm_) * z) / sxx)
        out["slope_sim_err"] = float(1.0 / math.sqrt(sxx))
    return pts, out
