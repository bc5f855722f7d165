"""Worm-like chain under tension: the force-extension references of the ``tether`` scene.

* :func:`marko_siggia_extension`: the continuous WLC interpolation formula
  F lp / kT = 1/(4 (1 - z/L)^2) - 1/4 + z/L  [Marko & Siggia, Macromolecules 28, 8759 (1995)].
* :func:`discrete_wlc_extension`: the mean extension of the bead model's own chain
  (N bonds of length b, hinge energy kappa (1 - cos beta), force F on the end, free first
  bond) by a transfer matrix over the polar cosine u = t_z, the azimuths integrated
  analytically: K(u, u') = exp[x (u u' + s s')] I0-scaled(x s s'), s = sqrt(1 - u^2),
  x = kappa / kT; site weight exp(F b u / kT). Gauss-Legendre quadrature in u
  [transfer matrix of the discrete WLC under force: Rosa, Hoang, Marenduzzo & Maritan,
  Macromolecules 36, 10095 (2003); Kierfeld, Niamploy, Sa-yakanit & Lipowsky,
  Eur. Phys. J. E 14, 17 (2004)]. Stretchable bonds (k = S/b) exactly (default,
  :func:`discrete_wlc_exact`) or by the earlier correction (``stretch="first_order"``:
  <l> = b (1 + 2 kT / (k b^2)) and F <u^2> / k per bond, orientations of the inextensible
  chain; it omits an O(1/k) orientational term, ~2e-4 of z for the default tether).
* :func:`discrete_wlc_exact`: exact mean and variance of the end height z_N with harmonic
  bonds, the bond length integrated per bond in closed form (:func:`bond_site_weight`).
* :func:`sample_discrete_wlc`: independent draws of whole chains from the exact Boltzmann
  distribution (backward messages + von Mises-Fisher proposals + exact rejection).

The model (what the OpenMM ``tether`` scene builds with surface and excluded volume off):
beads r_0 = 0, r_1 .. r_N, bonds q_i = r_i - r_{i-1} = l_i t_i,

    U = sum_i (k/2) (l_i - b)^2 + kappa sum_{i=1}^{N-1} (1 - t_i . t_{i+1}) - F z_N,

z_N = sum_i l_i u_i, u_i = t_i . z. Configurations carry the 3D measure
d^3 q_i = l_i^2 dl_i d^2 t_i, so the bond-length distribution is the one Brownian dynamics
samples.
"""

from __future__ import annotations

import math
import operator

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


# --------------------------------------------------------------------------------------
# input checks
# --------------------------------------------------------------------------------------

def _as_int(name, value, minimum):
    """``value`` as an int >= ``minimum`` (bools and non-integral numbers rejected)."""
    try:
        v = operator.index(value)
    except TypeError:
        v = None
    if v is None or isinstance(value, bool) or v < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(v)


def _check(force_pN, n_bonds, b_nm, kappa_kT, kT, stretch_k_pN_per_nm, nodes=None):
    """Validate the common arguments; return them as (float, int, float, float, float, k)."""
    n = _as_int("n_bonds", n_bonds, 1)
    vals = {"force_pN": force_pN, "b_nm": b_nm, "kappa_kT": kappa_kT, "kT": kT}
    for name, v in vals.items():
        if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v)):
            raise ValueError(f"{name} must be a finite number, got {v!r}")
    if force_pN < 0:
        raise ValueError(f"force_pN must be >= 0 (pulling force), got {force_pN!r}")
    if b_nm <= 0:
        raise ValueError(f"b_nm must be > 0, got {b_nm!r}")
    if kappa_kT < 0:
        raise ValueError(f"kappa_kT must be >= 0, got {kappa_kT!r}")
    if kT <= 0:
        raise ValueError(f"kT must be > 0, got {kT!r}")
    k = stretch_k_pN_per_nm
    if k is not None:
        if not (isinstance(k, (int, float, np.floating, np.integer)) and math.isfinite(k)
                and k > 0):
            raise ValueError(f"stretch_k_pN_per_nm must be a positive finite number or None, "
                             f"got {k!r}")
        k = float(k)
    if nodes is not None:
        _as_int("nodes", nodes, 2)
    return float(force_pN), n, float(b_nm), float(kappa_kT), float(kT), k


# --------------------------------------------------------------------------------------
# one bond: the radial integral
# --------------------------------------------------------------------------------------

def _radial_moments(mu):
    """P_n(mu) / d^n for n = 2, 3, 4 and d = max(mu, 1), with
    P_n(mu) = int_{-mu}^inf (t + mu)^n exp(-t^2/2) dt (closed form, valid for mu >= 0).

    g_0 = sqrt(pi/2) erfc(-mu/sqrt 2), g_1 = exp(-mu^2/2),
    g_j = (-mu)^(j-1) exp(-mu^2/2) + (j-1) g_(j-2)  (integration by parts),
    P_n = sum_j C(n, j) mu^(n-j) g_j; every term is >= 0 for mu >= 0 (no cancellation).
    """
    d = np.maximum(mu, 1.0)
    e = np.exp(-0.5 * mu * mu)
    g0 = math.sqrt(math.pi / 2) * special.erfc(-mu / math.sqrt(2.0))
    g1 = e
    g2 = -mu * e + g0
    g3 = mu * mu * e + 2.0 * g1
    g4 = -mu**3 * e + 3.0 * g2
    r = mu / d  # mu / d <= 1
    gd = [g0, g1 / d, g2 / d**2, g3 / d**3, g4 / d**4]  # g_j / d^j
    out = []
    for n in (2, 3, 4):
        s = sum(math.comb(n, j) * r ** (n - j) * gd[j] for j in range(n + 1))
        out.append(s)
    return d, out


def _radial_moments_quad(m, sig, nq=240):
    """log J_n and J_3/J_2, J_4/J_2 for m < 0 by Gauss-Legendre quadrature.

    J_n = int_0^inf l^n exp(-(l - m)^2 / (2 sig^2)) dl; for m < 0 the integrand decays
    from l = 0 on the scale h = sig^2 / (|m| + sig): l = h t, t in [0, 80].
    Returns log J_2 (with the factor exp(-m^2 / 2 sig^2) included), <l>, <l^2>.
    """
    t, wt = np.polynomial.legendre.leggauss(nq)
    t = 40.0 * (t + 1.0)
    wt = 40.0 * wt
    h = sig * sig / (np.abs(m) + sig)
    lv = h[:, None] * t[None, :]
    # exponent -(l - m)^2 / 2 sig^2 = -m^2/2sig^2 - l^2/2sig^2 + l m / sig^2
    ex = -0.5 * (lv / sig) ** 2 + lv * (m[:, None] / sig**2)
    base = np.exp(ex) * wt[None, :]
    j2 = (base * lv**2).sum(axis=1)
    j3 = (base * lv**3).sum(axis=1)
    j4 = (base * lv**4).sum(axis=1)
    log_j2 = np.log(j2) + np.log(h) - 0.5 * (m / sig) ** 2
    return log_j2, j3 / j2, j4 / j2


def bond_site_weight(u, force_pN: float, b_nm: float, kT: float,
                     stretch_k_pN_per_nm: float | None = None) -> dict:
    """Radial integral of one bond at fixed direction cosine u = t . z.

    .. math::

        w(u) = \\int_0^\\infty l^2 \\exp\\left[-\\frac{k (l - b)^2}{2 k_B T}
               + \\frac{F l u}{k_B T}\\right] dl
             = e^{c b + c^2 \\sigma^2 / 2} J_2(m),\\qquad
        J_n(m) = \\int_0^\\infty l^n e^{-(l - m)^2 / 2\\sigma^2} dl,

    with c = F u / kT (1/nm), sigma^2 = kT / k (nm^2) and m = b + F u / k (nm). J_n is
    evaluated in closed form (erfc and Gaussians, :func:`_radial_moments`) for m >= 0 and
    by Gauss-Legendre quadrature for m < 0 (only when F > k b, far outside the model's use).
    The conditional moments of the bond length are <l | u> = J_3 / J_2 and
    <l^2 | u> = J_4 / J_2, and d ln w / d(F/kT) = u <l | u>.

    With ``stretch_k_pN_per_nm=None`` (inextensible bonds) l = b: ln w = F b u / kT
    (the constant b^2 dropped).

    Parameters
    ----------
    u : array_like
        Direction cosines in [-1, 1], any shape.
    force_pN : float
        F (pN); any sign is accepted here.
    b_nm : float
        Rest length b (nm).
    kT : float
        Thermal energy (pN nm).
    stretch_k_pN_per_nm : float, optional
        Bond spring constant k (pN/nm); None for inextensible bonds.

    Returns
    -------
    dict
        ``log_w`` (same shape as u; ln of w in nm^3, up to the u-independent constant
        stated above), ``mean_l_nm`` (<l | u>), ``mean_l2_nm2`` (<l^2 | u>).
    """
    u = np.asarray(u, dtype=float)
    c = force_pN * u / kT
    if stretch_k_pN_per_nm is None:
        return {"log_w": c * b_nm, "mean_l_nm": np.full_like(u, b_nm),
                "mean_l2_nm2": np.full_like(u, b_nm * b_nm)}
    k = float(stretch_k_pN_per_nm)
    sig = math.sqrt(kT / k)
    m = b_nm + force_pN * u / k
    flat = np.atleast_1d(m).ravel()
    log_j2 = np.empty_like(flat)
    ml = np.empty_like(flat)
    ml2 = np.empty_like(flat)
    pos = flat >= 0
    if pos.any():
        mu = flat[pos] / sig
        d, (p2, p3, p4) = _radial_moments(mu)
        log_j2[pos] = 3.0 * math.log(sig) + 2.0 * np.log(d) + np.log(p2)
        ml[pos] = sig * d * p3 / p2
        ml2[pos] = sig * sig * d * d * p4 / p2
    if (~pos).any():
        log_j2[~pos], ml[~pos], ml2[~pos] = _radial_moments_quad(flat[~pos], sig)
    shape = u.shape
    log_w = c * b_nm + 0.5 * (c * sig) ** 2 + log_j2.reshape(shape)
    return {"log_w": log_w, "mean_l_nm": ml.reshape(shape), "mean_l2_nm2": ml2.reshape(shape)}


# --------------------------------------------------------------------------------------
# transfer matrix
# --------------------------------------------------------------------------------------

def _kernel(ua, sa, ub, sb, x):
    """Azimuth-integrated hinge kernel / (2 pi e^x):
    exp[x (u u' + s s' - 1)] I0e(x s s') = int dphi/2pi exp[x (t . t' - 1)].  Shape (a, b)."""
    ss = np.outer(sa, sb)
    return np.exp(x * (np.outer(ua, ub) + ss - 1.0)) * special.i0e(x * ss)


def _grid(nodes):
    u, wq = np.polynomial.legendre.leggauss(int(nodes))
    s = np.sqrt(np.clip(1 - u * u, 0, None))
    return u, s, wq


def _site(u, wq, force_pN, b_nm, kT, k):
    """Site weights on the grid, scaled by a constant: g, g' = dg/dphi, g'' (phi = F/kT)."""
    site = bond_site_weight(u, force_pN, b_nm, kT, k)
    lw = site["log_w"]
    g = np.exp(lw - lw.max()) * wq
    d1 = u * site["mean_l_nm"]
    d2 = u * u * site["mean_l2_nm2"]
    return g, d1, d2, site


def _exact_core(force_pN, n_bonds, b_nm, x, kT, k, nodes):
    """Mean and variance of z_N (forward-mode derivatives of ln Z in phi = F/kT) and the
    per-bond marginals (forward-backward)."""
    u, s, wq = _grid(nodes)
    K = _kernel(u, s, u, s, x)  # symmetric
    g, d1, d2, site = _site(u, wq, force_pN, b_nm, kT, k)
    g1 = g * d1
    g2 = g * d2
    # A = (Z, dZ/dphi, d2Z/dphi2) restricted to bond i at u, re-centred after every bond:
    # A <- A e^{-phi c} (c = current mean) so that the variance comes without cancellation.
    A0, A1, A2 = g.copy(), g1.copy(), g2.copy()
    shift = 0.0
    fwd = np.empty((n_bonds, len(u)))
    for i in range(n_bonds):
        if i > 0:
            P = K.T @ np.stack([A0, A1, A2], axis=1)
            P0, P1, P2 = P[:, 0], P[:, 1], P[:, 2]
            A0, A1, A2 = P0 * g, P1 * g + P0 * g1, P2 * g + 2.0 * P1 * g1 + P0 * g2
        z0 = A0.sum()
        c = A1.sum() / z0
        A2 = (A2 - 2.0 * c * A1 + c * c * A0) / z0
        A1 = (A1 - c * A0) / z0
        A0 = A0 / z0
        shift += c
        fwd[i] = A0
    mean_z = float(shift + A1.sum())
    var_z = float(A2.sum()) - float(A1.sum()) ** 2
    bwd = np.empty_like(fwd)
    bb = np.ones(len(u))
    bwd[-1] = bb
    for i in range(n_bonds - 2, -1, -1):
        bb = K @ (g * bb)
        bb /= bb.sum()
        bwd[i] = bb
    p = fwd * bwd
    p /= p.sum(axis=1, keepdims=True)
    return {"extension_nm": mean_z, "extension_var_nm2": var_z, "mean_u": p @ u,
            "mean_length_nm": p @ site["mean_l_nm"], "mean_lu_nm": p @ d1,
            "mean_u2": p @ (u * u)}


def discrete_wlc_exact(force_pN: float, n_bonds: int, b_nm: float, kappa_kT: float,
                       kT: float, stretch_k_pN_per_nm: float | None = None,
                       nodes: int = 400) -> dict:
    """Exact mean and variance of the end height of the discrete WLC with harmonic bonds.

    Transfer matrix over u = cos(theta) of each bond [Rosa et al., Macromolecules 36, 10095
    (2003); Kierfeld et al., Eur. Phys. J. E 14, 17 (2004)], with the bond length
    integrated exactly per bond. The partition function is

    .. math::

        Z(\\phi) = \\int \\prod_i du_i\\, w(u_1) \\prod_{i=1}^{N-1}
                   K(u_i, u_{i+1})\\, w(u_{i+1}),\\qquad \\phi = F / k_B T,

    K(u, u') = 2 pi exp(x u u') I0(x s s') (the hinge Boltzmann factor exp(x t . t'),
    x = kappa/kT, integrated over the relative azimuth) and w(u) the radial integral of
    :func:`bond_site_weight`. Then <z_N> = d ln Z / d phi and Var z_N = d^2 ln Z / d phi^2
    = kT d<z_N>/dF. Both derivatives are propagated through the recursion exactly
    (forward-mode differentiation: dw/dphi = u <l|u> w, d^2 w / dphi^2 = u^2 <l^2|u> w),
    so the only approximation is the Gauss-Legendre quadrature in u (spectrally
    convergent; the kernel is analytic in u, u').

    Parameters
    ----------
    force_pN : float
        End force F >= 0 (pN), along +z.
    n_bonds : int
        Number of bonds N >= 1. The first bond's direction is free (no hinge at r_0).
    b_nm : float
        Bond rest length b (nm).
    kappa_kT : float
        Hinge stiffness x = kappa / kT >= 0 (dimensionless).
    kT : float
        Thermal energy (pN nm).
    stretch_k_pN_per_nm : float, optional
        Bond spring constant k = S / b (pN/nm); None for inextensible bonds (l = b).
    nodes : int
        Gauss-Legendre nodes in u.

    Returns
    -------
    dict
        ``extension_nm`` (<z_N>, nm), ``extension_var_nm2`` (Var z_N, nm^2),
        ``mean_u`` (shape (N,), <u_i>), ``mean_length_nm`` (shape (N,), <l_i>, nm) and
        ``mean_lu_nm`` (shape (N,), <l_i u_i>, nm; sums to ``extension_nm``).
    """
    f, n, b, x, kT, k = _check(force_pN, n_bonds, b_nm, kappa_kT, kT, stretch_k_pN_per_nm,
                               nodes)
    return _exact_core(f, n, b, x, kT, k, int(nodes))


def discrete_wlc_extension(force_pN: float, n_bonds: int, b_nm: float, kappa_kT: float,
                           kT: float, *, stretch_k_pN_per_nm: float | None = None,
                           nodes: int = 400, stretch: str = "exact") -> dict:
    """Mean extension of the discrete WLC bead chain under end force F.

    Parameters
    ----------
    force_pN : float
        End force F >= 0 (pN).
    n_bonds : int
        Number of bonds (beads - 1); the first bond's direction is free (a free hinge at
        the tether), the force acts on the last bead.
    b_nm : float
        Bond (rest) length (nm).
    kappa_kT : float
        Hinge stiffness x = kappa / kT.
    kT : float
        pN nm.
    stretch_k_pN_per_nm : float, optional
        Bond spring constant; None for inextensible bonds.
    nodes : int
        Gauss-Legendre nodes in u = cos(theta).
    stretch : {"exact", "first_order"}
        Treatment of stretchable bonds (ignored when ``stretch_k_pN_per_nm`` is None):
        ``"exact"`` integrates the bond length exactly (:func:`discrete_wlc_exact`);
        ``"first_order"`` corrects the inextensible result by
        <l> = b (1 + 2 kT / (k b^2)) and F <u^2> / k per bond, keeping the inextensible
        orientation distribution. It misses a term of the same order: the force couples
        to l u, so the longer bonds feel a larger torque,
        dz = 2 F Var z / (k b^2) + F^2 / (2 k) d(sum <u_i^2>)/dF to first order in 1/k
        (2e-4 of z at F = 1 pN, N = 60, b = 5 nm, S = 1100 pN; up to ~1e-3 at 0.1 pN).

    Returns
    -------
    dict
        ``extension_nm`` (nm), ``mean_u`` (shape (N,), per bond), ``inextensible_nm``
        (b sum <u_i> of the same chain with inextensible bonds, nm) and
        ``extension_var_nm2`` (Var z_N, nm^2; of the inextensible chain with
        ``stretch="first_order"``).
    """
    f, n, b, x, kT, k = _check(force_pN, n_bonds, b_nm, kappa_kT, kT, stretch_k_pN_per_nm,
                               nodes)
    if stretch not in ("exact", "first_order"):
        raise ValueError(f"stretch must be 'exact' or 'first_order', got {stretch!r}")
    inext = _exact_core(f, n, b, x, kT, None, int(nodes))
    z_inext = b * float(inext["mean_u"].sum())
    out = {"extension_nm": z_inext, "inextensible_nm": z_inext, "mean_u": inext["mean_u"],
           "extension_var_nm2": inext["extension_var_nm2"]}
    if k is None:
        return out
    if stretch == "exact":
        ex = _exact_core(f, n, b, x, kT, k, int(nodes))
        out.update(extension_nm=ex["extension_nm"], mean_u=ex["mean_u"],
                   extension_var_nm2=ex["extension_var_nm2"])
    else:
        out["extension_nm"] = (z_inext * (1.0 + 2.0 * kT / (k * b**2))
                               + f * float(inext["mean_u2"].sum()) / k)
    return out


# --------------------------------------------------------------------------------------
# exact sampler
# --------------------------------------------------------------------------------------

def _sampler_tables(f, n, b, x, kT, k, nodes, table_points, u_eval=None):
    """Backward messages and the rejection tables of :func:`sample_discrete_wlc`.

    Row i of ``log_h`` (i = 0 .. N-1 for bond i+1) is ln[w(u) beta_{i+1}(u)] on
    ``u_table`` (uniform in theta = arccos u, so denser near u = +-1), where
    beta_N = 1 and beta_i(u) = int du' K(u, u') w(u') beta_{i+1}(u') is evaluated at any u
    by the Nystroem extension of the Gauss-Legendre sum. Each row carries its own constant.
    ``lam`` is the tilt of the vMF proposal (weighted least-squares slope of ln h against u
    under the marginal of u_i) and ``log_max`` = max_u [ln h(u) - lam u] over the table nodes,
    which is the exact maximum of the piecewise-linear interpolant. With ``u_eval`` the
    same ln h is evaluated there directly (for the interpolation-error check).
    """
    u, s, wq = _grid(nodes)
    K = _kernel(u, s, u, s, x)
    g, _, _, site = _site(u, wq, f, b, kT, k)
    th = np.linspace(math.pi, 0.0, int(table_points))
    uf = np.cos(th)
    uf[0], uf[-1] = -1.0, 1.0
    sf = np.sin(th).clip(0.0, None)
    Kf = _kernel(uf, sf, u, s, x)
    lwf = bond_site_weight(uf, f, b, kT, k)["log_w"]
    if u_eval is not None:
        ue = np.asarray(u_eval, dtype=float)
        Ke = _kernel(ue, np.sqrt(np.clip(1 - ue * ue, 0, None)), u, s, x)
        lwe = bond_site_weight(ue, f, b, kT, k)["log_w"]
        H_eval = np.empty((n, len(ue)))
        H_eval[-1] = lwe
    tiny = np.finfo(float).tiny
    # forward messages (for the marginals that set the proposal tilt)
    fwd = np.empty((n, len(u)))
    a = g / g.sum()
    fwd[0] = a
    for i in range(1, n):
        a = (K.T @ a) * g
        a /= a.sum()
        fwd[i] = a
    H = np.empty((n, len(uf)))
    bwd = np.empty_like(fwd)
    bb = np.ones(len(u))
    bwd[-1] = bb
    H[-1] = lwf
    for i in range(n - 2, -1, -1):
        v = g * bb
        bb = K @ v
        norm = bb.sum()
        bb /= norm
        bwd[i] = bb
        H[i] = lwf + np.log(np.maximum(Kf @ v / norm, tiny))
        if u_eval is not None:
            H_eval[i] = lwe + np.log(np.maximum(Ke @ v / norm, tiny))
    H = np.maximum(H, H.max(axis=1, keepdims=True) - 1000.0)  # below e^-1000: probability 0
    p = fwd * bwd
    p /= p.sum(axis=1, keepdims=True)
    lh = site["log_w"][None, :] + np.log(np.maximum(bwd, tiny))
    ubar = p @ u
    du = u[None, :] - ubar[:, None]
    varu = (p * du * du).sum(axis=1)
    cov = (p * du * (lh - (p * lh).sum(axis=1, keepdims=True))).sum(axis=1)
    lam = np.where(varu > 1e-300, cov / np.maximum(varu, 1e-300), 0.0)
    log_max = (H - lam[:, None] * uf[None, :]).max(axis=1)
    out = {"u_table": uf, "log_h": H, "lam": lam, "log_max": log_max, "mean_u": ubar}
    if u_eval is not None:
        out["log_h_eval"] = H_eval
    return out


def _vmf_directions(mean_vec, rng):
    """Unit vectors from the von Mises-Fisher density on S^2, p(t) ∝ exp(m . t).

    ``mean_vec`` (n, 3) gives the mean direction and concentration kappa = |m|. The cosine
    w = t . m/|m| has density ∝ exp(kappa w) on [-1, 1], inverted in closed form
    w = 1 + ln[1 + xi (e^{-2 kappa} - 1)] / kappa, xi ~ U[0, 1) [Wood, Commun. Stat. Simul.
    Comput. 23, 157 (1994), exact in three dimensions]; the azimuth about m is uniform.
    """
    n = mean_vec.shape[0]
    kap = np.linalg.norm(mean_vec, axis=1)
    mu = np.zeros_like(mean_vec)
    mu[:, 2] = 1.0
    nz = kap > 0
    mu[nz] = mean_vec[nz] / kap[nz, None]
    xi = rng.random(n)
    big = kap > 1e-8
    w = 1.0 - 2.0 * xi  # uniform limit kappa -> 0
    kb = kap[big]
    w[big] = 1.0 + np.log1p(xi[big] * np.expm1(-2.0 * kb)) / kb
    w = np.clip(w, -1.0, 1.0)
    psi = 2.0 * math.pi * rng.random(n)
    # orthonormal frame (e1, e2) perpendicular to mu
    ref = np.zeros_like(mu)
    use_x = np.abs(mu[:, 2]) > 0.9
    ref[use_x, 0] = 1.0
    ref[~use_x, 2] = 1.0
    e1 = np.cross(ref, mu)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(mu, e1)
    sw = np.sqrt(np.clip(1.0 - w * w, 0.0, None))
    return (w[:, None] * mu
            + (sw * np.cos(psi))[:, None] * e1 + (sw * np.sin(psi))[:, None] * e2)


def _bond_lengths(uz, f, b, kT, k, rng):
    """Bond lengths drawn exactly from p(l | u) ∝ l^2 exp(-(l - m)^2 / (2 sigma^2)), l > 0.

    ln p is concave with (ln p)'' <= -1/sigma^2, so the Gaussian N(l*, sigma^2) centred at the
    mode l* = (m + sqrt(m^2 + 8 sigma^2)) / 2 bounds it from above (Taylor with remainder);
    the acceptance probability reduces to rho^2 exp(2 - 2 rho), rho = l / l*.
    """
    sig = math.sqrt(kT / k)
    m = b + f * uz / k
    lstar = 0.5 * (m + np.sqrt(m * m + 8.0 * sig * sig))
    out = np.empty_like(uz)
    pending = np.arange(uz.size)
    while pending.size:
        ls = lstar[pending]
        lv = ls + sig * rng.standard_normal(pending.size)
        rho = lv / ls
        with np.errstate(divide="ignore", invalid="ignore"):
            log_acc = np.where(rho > 0, 2.0 * np.log(np.where(rho > 0, rho, 1.0))
                               + 2.0 - 2.0 * rho, -np.inf)
        acc = np.log1p(-rng.random(pending.size)) < log_acc
        out[pending[acc]] = lv[acc]
        pending = pending[~acc]
    return out


def _sample_chains(f, n, b, x, kT, k, n_samples, rng, nodes, table_points):
    tab = _sampler_tables(f, n, b, x, kT, k, nodes, table_points)
    uf, H, lam, M = tab["u_table"], tab["log_h"], tab["lam"], tab["log_max"]
    T = np.empty((n_samples, n, 3))
    proposals = 0
    zhat = np.array([0.0, 0.0, 1.0])
    for i in range(n):
        base = np.zeros((n_samples, 3)) if i == 0 else x * T[:, i - 1]
        mvec = base + lam[i] * zhat
        pending = np.arange(n_samples)
        while pending.size:
            proposals += pending.size
            t = _vmf_directions(mvec[pending], rng)
            uz = t[:, 2]
            log_acc = np.interp(uz, uf, H[i]) - lam[i] * uz - M[i]
            acc = np.log1p(-rng.random(pending.size)) < log_acc
            T[pending[acc], i] = t[acc]
            pending = pending[~acc]
    if k is None:
        lengths = np.full((n_samples, n), b)
    else:
        lengths = _bond_lengths(T[:, :, 2].ravel(), f, b, kT, k, rng).reshape(n_samples, n)
    pos = np.zeros((n_samples, n + 1, 3))
    pos[:, 1:] = np.cumsum(lengths[:, :, None] * T, axis=1)
    return pos, {"acceptance": n_samples * n / proposals}


def sample_discrete_wlc(force_pN: float, n_bonds: int, b_nm: float, kappa_kT: float,
                        kT: float, *, stretch_k_pN_per_nm: float | None = None,
                        n_samples: int = 1, rng=None, nodes: int = 200,
                        table_points: int = 4097) -> np.ndarray:
    """Independent chains drawn from the exact Boltzmann distribution of the tether.

    The distribution is p ∝ exp(-U / kT) prod_i l_i^2 dl_i d^2 t_i with U as in the module
    docstring (harmonic bonds k, hinges kappa, end force F along z, free first bond).
    Chains are drawn bond by bond from the exact conditionals (sequential / backward-
    message sampling of a Markov chain):

    1. Backward messages on the Gauss-Legendre grid in u (as in :func:`discrete_wlc_exact`):
       beta_N = 1, beta_i(u) = int du' K(u, u') w(u') beta_{i+1}(u'), with w the radial
       integral of :func:`bond_site_weight`. Then

       .. math::

           p(t_1) \\propto h_1(u_1),\\qquad
           p(t_{i+1} | t_1..t_i) \\propto e^{x\\, t_i \\cdot t_{i+1}}\\, h_{i+1}(u_{i+1}),
           \\qquad h_i = w\\, \\beta_i .

       ln h_i is tabulated on ``table_points`` values of u (Nystroem extension of the
       quadrature sum, no spline) and interpolated linearly; the interpolation error of
       ln h is below 1e-6 for the model's parameters (checked in the tests).
    2. Direction t_{i+1}: proposal from the von Mises-Fisher density
       ∝ exp[(x t_i + lam_i z) . t] (exact inverse-CDF sampling of the cosine, Wood 1994),
       accepted with probability h(u) e^{-lam_i u} / max_u[h(u) e^{-lam_i u}]. The tilt
       lam_i (slope of ln h_i) only sets the efficiency; the maximum is exact because the
       interpolant is piecewise linear. The first bond uses x = 0 (no hinge at r_0).
    3. Bond lengths given the directions are independent:
       p(l | u) ∝ l^2 exp[-k (l - b)^2 / (2 kT) + F l u / kT], drawn by exact rejection
       from a Gaussian at its mode (the log-density is concave with curvature
       <= -k/kT). Inextensible bonds (k None) have l = b.

    Parameters
    ----------
    force_pN : float
        End force F >= 0 (pN).
    n_bonds : int
        Number of bonds N >= 1.
    b_nm : float
        Bond rest length b (nm).
    kappa_kT : float
        Hinge stiffness x = kappa / kT >= 0.
    kT : float
        Thermal energy (pN nm).
    stretch_k_pN_per_nm : float, optional
        Bond spring constant k (pN/nm); None for inextensible bonds.
    n_samples : int
        Number of independent chains.
    rng : None, int or numpy.random.Generator
        Seed or generator (``numpy.random.default_rng(rng)``).
    nodes : int
        Gauss-Legendre nodes in u for the backward messages.
    table_points : int
        Points of the ln h tables in u (uniform in arccos u).

    Returns
    -------
    numpy.ndarray
        Shape (n_samples, n_bonds + 1, 3): bead positions (nm), bead 0 at the origin.
    """
    f, n, b, x, kT, k = _check(force_pN, n_bonds, b_nm, kappa_kT, kT, stretch_k_pN_per_nm,
                               nodes)
    n_samples = _as_int("n_samples", n_samples, 1)
    table_points = _as_int("table_points", table_points, 3)
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    pos, _ = _sample_chains(f, n, b, x, kT, k, int(n_samples), gen, int(nodes),
                            int(table_points))
    return pos


def persistence_from_mean_cos(mean_cos: float, b_nm: float) -> float:
    """lp = -b / ln <cos beta> (the discrete WLC definition)."""
    return -b_nm / math.log(mean_cos)


class StartDrawError(ValueError):
    """No draw of a tether start met the conditions within the allowed number of tries."""


def sample_tether_start(force_pN: float, n_bonds: int, b_nm: float, kappa_kT: float,
                        kT: float, rng, *, stretch_k_pN_per_nm: float | None = None,
                        wall_z_nm: float | None = None, min_separation_nm: float = 0.0,
                        min_chemical_gap: int = 1, accept=None, tries: int = 64
                        ) -> np.ndarray:
    """A tether start drawn from the exact discrete-WLC equilibrium under force
    (:func:`sample_discrete_wlc`), conditioned by rejection on the scene's constraints.

    A draw is rejected when a bead after the first lies at or below ``wall_z_nm`` (the
    wall), when two beads at least ``min_chemical_gap`` bonds apart are closer than
    ``min_separation_nm`` (excluded volume), or when ``accept(x)`` is False (e.g. a writhe
    the bead clamp cannot take). Accepted draws are exact for the model without those
    terms, conditioned on being allowed with them (for wall and excluded volume the
    rejection is the model's own hard-core limit, so the start is close to equilibrium).

    Parameters
    ----------
    force_pN, n_bonds, b_nm, kappa_kT, kT, stretch_k_pN_per_nm
        As for :func:`sample_discrete_wlc`.
    rng : numpy.random.Generator
        The replica's own stream (each replica draws its own start).
    wall_z_nm, min_separation_nm, min_chemical_gap, accept
        The conditions (see above); None / 0 leaves a condition out.
    tries : int
        Draws before giving up.

    Returns
    -------
    ndarray (n_bonds + 1, 3), nm

    Raises
    ------
    StartDrawError
        When no draw of ``tries`` is accepted (never a silent fallback to a shared start).
    """
    from scipy.spatial import cKDTree

    reasons: dict = {}
    batch = 8
    for _ in range(max(1, tries // batch)):
        for x in sample_discrete_wlc(force_pN, n_bonds, b_nm, kappa_kT, kT,
                                     stretch_k_pN_per_nm=stretch_k_pN_per_nm,
                                     n_samples=batch, rng=rng):
            if wall_z_nm is not None and np.any(x[1:, 2] <= wall_z_nm):
                reasons["below the wall"] = reasons.get("below the wall", 0) + 1
                continue
            if min_separation_nm > 0 and n_bonds > min_chemical_gap:
                pairs = cKDTree(x).query_pairs(min_separation_nm, output_type="ndarray")
                if np.any(np.abs(pairs[:, 1] - pairs[:, 0]) >= min_chemical_gap):
                    reasons["beads overlapping"] = reasons.get("beads overlapping", 0) + 1
                    continue
            if accept is not None and not accept(x):
                reasons["refused by the scene"] = reasons.get("refused by the scene", 0) + 1
                continue
            return x
    why = ", ".join(f"{k} {v}" for k, v in reasons.items())
    raise StartDrawError(f"no exact tether start in {max(1, tries // batch) * batch} draws "
                         f"({why}) at F = {force_pN} pN, {n_bonds} bonds of {b_nm} nm")
