"""Worm-like chain under tension: the force-extension references of the ``tether`` scene.

* :func:`marko_siggia_extension`: the continuous WLC interpolation formula
  F lp / kT = 1/(4 (1 - z/L)^2) - 1/4 + z/L  [Marko & Siggia, Macromolecules 28, 8759 (1995)].
* :func:`discrete_wlc_extension`: the exact mean extension of the bead model's own chain
  (N bonds of length b, hinge energy kappa (1 - cos beta), force F on the end, free first
  bond) by a transfer matrix over the polar cosine u = t_z, the azimuths integrated
  analytically: K(u, u') = exp[x (u u' + s s')] I0-scaled(x s s'), s = sqrt(1 - u^2),
  x = kappa / kT; site weight exp(F b u / kT). Gauss-Legendre quadrature in u.
  Stretchable bonds (k = S/b) are added to first order: <l> = b (1 + 2 kT / (k b^2)) and
  F <u^2> / k per bond.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, special


def marko_siggia_extension(force_pN: float, length_nm: float, persistence_nm: float,
                           kT: float) -> float:
    """Mean extension (nm) of a continuous WLC by the Marko-Siggia interpolation."""
    if force_pN <= 0:
        return 0.0
    a = force_pN * persistence_nm / kT

    def g(x):
        return 0.25 / (1 - x) ** 2 - 0.25 + x - a

    x = optimize.brentq(g, 0.0, 1 - 1e-12)
    return x * length_nm


def discrete_wlc_extension(force_pN: float, n_bonds: int, b_nm: float, kappa_kT: float,
                           kT: float, *, stretch_k_pN_per_nm: float | None = None,
                           nodes: int = 400) -> dict:
    """Exact mean extension of the discrete WLC bead chain under end force F.

    Parameters
    ----------
    force_pN : float
    n_bonds : int
        Number of bonds (beads - 1); the first bond's direction is free (a free hinge at
        the tether), the force acts on the last bead.
    b_nm : float
    kappa_kT : float
        Hinge stiffness x = kappa / kT.
    kT : float
        pN nm.
    stretch_k_pN_per_nm : float, optional
        Bond spring constant; None for inextensible bonds.
    nodes : int
        Gauss-Legendre nodes in u = cos(theta).

    Returns
    -------
    dict
        ``extension_nm``, ``mean_u`` (per bond), ``inextensible_nm``.
    """
    if n_bonds < 1:
        raise ValueError("n_bonds must be >= 1")
    u, w = np.polynomial.legendre.leggauss(int(nodes))
    s = np.sqrt(np.clip(1 - u * u, 0, None))
    x = float(kappa_kT)
    f = force_pN * b_nm / kT
    uu = np.outer(u, u)
    ss = np.outer(s, s)
    K = np.exp(x * (uu + ss - 1.0)) * special.i0e(x * ss)  # scaled by exp(-x)
    g = np.exp(f * (u - 1.0)) * w  # site weight x quadrature weight, scaled
    # forward a_i(u_i): weight of bonds 1..i with bond i at u_i (includes g_i)
    fwd = np.empty((n_bonds, len(u)))
    a = g.copy()
    a /= a.sum()
    fwd[0] = a
    for i in range(1, n_bonds):
        a = (K.T @ a) * g
        a /= a.sum()
        fwd[i] = a
    bwd = np.empty_like(fwd)
    bb = np.ones(len(u))
    bwd[-1] = bb
    for i in range(n_bonds - 2, -1, -1):
        bb = K @ (g * bb)
        bb /= bb.sum()
        bwd[i] = bb
    p = fwd * bwd
    p /= p.sum(axis=1, keepdims=True)
    mean_u = p @ u
    mean_u2 = p @ (u * u)
    z_inext = b_nm * float(mean_u.sum())
    z = z_inext
    if stretch_k_pN_per_nm:
        k = stretch_k_pN_per_nm
        z = z_inext * (1.0 + 2.0 * kT / (k * b_nm**2)) + force_pN * float(mean_u2.sum()) / k
    return {"extension_nm": z, "inextensible_nm": z_inext, "mean_u": mean_u}


def persistence_from_mean_cos(mean_cos: float, b_nm: float) -> float:
    """lp = -b / ln <cos beta> (the discrete WLC definition)."""
    return -b_nm / math.log(mean_cos)
