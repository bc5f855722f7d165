"""The hat curve of torsionally constrained DNA against rod theory.

From a ``plectoneme`` run over a range of turns (its ``summary.json``):

* below buckling, the twist-torque slope gives an effective twist stiffness
  C_eff = (dGamma/dn) L / (2 pi kT), against Moroz & Nelson (PNAS 94, 14418 (1997), Eq. 12):
  C_eff(F) = C (1 - (C / 4A) sqrt(kT / (A F))) (A, C persistence lengths in nm);
* the buckling point (first turn value with a plectoneme in more than half the frames) and
  the torque plateau after it, against the classical buckling torque
  Gamma_b = sqrt(2 kT A F) (kT A the bending stiffness in pN nm^2; Marko, PRE 76, 021926
  (2007), explains why a finite chain's plateau lies above it).
"""

from __future__ import annotations

import math

import numpy as np

from ..units import KB_PN_NM, TWO_PI

__all__ = ["moroz_nelson_ceff", "buckling_torque", "hat_curve"]


def moroz_nelson_ceff(C: float, A: float, F: float, kT: float) -> float:
    """Effective twist persistence C_eff (nm) of a stretched rod (Moroz & Nelson 1997,
    Eq. 12): C (1 - (C / 4A) sqrt(kT / (A F))); C, A in nm, F in pN, kT in pN nm."""
    return C * (1.0 - C / (4.0 * A) * math.sqrt(kT / (A * F)))


def buckling_torque(A: float, F: float, kT: float) -> float:
    """The classical buckling torque sqrt(2 kT A F) (pN nm); A in nm, F in pN."""
    return math.sqrt(2.0 * kT * A * F)


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
        buckled points).
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
           "ceff_theory": moroz_nelson_ceff(C, A, F, kT), "n_buckle": nb, "C": C}
    if lin.sum() >= 2:
        w = 1.0 / np.maximum(tq_sem[lin], 1e-9) ** 2
        slope = float(np.sum(w * n[lin] * tq[lin]) / np.sum(w * n[lin] ** 2))  # through 0
        dslope = float(1.0 / math.sqrt(np.sum(w * n[lin] ** 2)))
        out["ceff_sim"] = slope * L / (TWO_PI * kT)
        out["ceff_sim_err"] = dslope * L / (TWO_PI * kT)
    if buckled.size:
        out["plateau_torque"] = float(np.mean(tq[buckled]))
        out["plateau_torque_err"] = float(np.sqrt(np.sum(tq_sem[buckled] ** 2)) / buckled.size)
    return pts, out
