"""Linearised bead-spring model of the tweezer scenes: relaxation times of their slow modes.

The model behind the default braid (docs/slow_modes.md, workflows/slow_modes.py): the
discrete chain under tension with bending, linearised about the straight state, one
transverse coordinate per bead, with the exact bead frictions (for the braid: two strands
whose ends are held by the bead centre on its tilt spring F/h and the rotational trap). Its
overdamped dynamics zeta du/dt = -H u + noise decomposes into independent modes of rate
lambda_k (the generalised eigenproblem H v = lambda Z v, Z the friction matrix).

* :class:`Lin1D`, :func:`chain`, :func:`longitudinal_chain`, :func:`twist_model`: the
  quadratic energies and frictions;
* :func:`linear_model`: the predicted autocorrelation times of a scene's observables
  (extension, bead x/y, tilt, trap torque) at given sampling intervals;
* closed forms: :func:`string_tau1` (slowest mode tau_1 = zeta_l L^2 / (f q^2),
  q tan q = zeta_l L / zeta_end), :func:`extension_formula`, :func:`libration_tau`,
  :func:`e_time_spectrum`;
* estimators of the same times from a measured series: :func:`tau_of`, :func:`e_time`,
  :func:`e_time_err`, :func:`block_means`.

Conventions: tau = g Delta / 2, with g = 1 + 2 sum rho the statistical inefficiency
(:func:`dnabraid.analysis.stats.integrated_autocorrelation_time`, Sokal's window) and
Delta the sampling interval; tau equals the relaxation time of a single exponential and the
integral of the autocorrelation function. Units: nm, pN, ns; frictions in pN ns / nm
(rotational: pN ns nm), stiffnesses in pN / nm (angles: pN nm / rad^2), kT in pN nm,
rates in 1 / ns.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "TORQUE_BLOCK",
    "Lin1D",
    "block_means",
    "chain",
    "e_time",
    "e_time_err",
    "e_time_spectrum",
    "extension_formula",
    "libration_tau",
    "linear_model",
    "longitudinal_chain",
    "string_tau1",
    "tau_of",
    "twist_model",
]

#: Default block length (samples) of the slow part of the torque: 10 samples x 100 steps
#: x 71 ps = 71 ns, far beyond the trap's libration (~2 ns) and the sampling interval.
TORQUE_BLOCK = 10


class Lin1D:
    """Linear overdamped model: one coordinate u_i per particle, quadratic energy.

    The energy is a sum of terms k_t / 2 (sum_i c_ti u_i)^2 (:meth:`term`), so
    U = u^T H u / 2; the dynamics is zeta du/dt = -H u + noise. The generalised
    eigenproblem H v = lambda Z v (Z = diag(zeta), V^T Z V = 1; :meth:`modes`) gives
    independent modal amplitudes a_k with rate lambda_k (1/ns) and variance kT / lambda_k.

    Attributes
    ----------
    zeta : list of float
        Friction of each particle (pN ns / nm; pN ns nm for an angle).
    terms : list of (dict, float)
        The energy terms: coefficients {particle index: c_i} and stiffness k.
    """

    def __init__(self):
        self.zeta: list[float] = []
        self.terms: list[tuple[dict, float]] = []

    def particle(self, zeta: float) -> int:
        """Add a particle of friction ``zeta``; returns its index."""
        self.zeta.append(float(zeta))
        return len(self.zeta) - 1

    def term(self, coeffs: dict, k: float) -> None:
        """Add the energy k/2 (sum_i c_i u_i)^2.

        Parameters
        ----------
        coeffs : dict
            Particle index -> coefficient c_i; an index None is a fixed particle (u = 0).
        k : float
            Stiffness of the term (pN / nm for lengths, pN nm for angles).
        """
        self.terms.append(({i: c for i, c in coeffs.items() if i is not None}, float(k)))

    def matrix(self, terms=None) -> np.ndarray:
        """The Hessian H of the energy (or of the given ``terms``, same form as
        :attr:`terms`), shape (n, n)."""
        n = len(self.zeta)
        H = np.zeros((n, n))
        for c, k in (self.terms if terms is None else terms):
            g = np.zeros(n)
            for i, ci in c.items():
                if i is not None:  # a fixed particle
                    g[i] += ci
            H += k * np.outer(g, g)
        return H

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Rates lambda_k (1/ns, ascending) and Z-orthonormal mode vectors V (columns)."""
        from scipy.linalg import eigh

        lam, V = eigh(self.matrix(), np.diag(self.zeta))
        return lam, V


def chain(m: Lin1D, n_bonds: int, b: float, tension: float, kappa: float, zeta: float,
          zeta_end: float) -> tuple[list, list]:
    """Add a strand under tension, fixed at the surface, to ``m`` (one transverse direction).

    Bead 0 is fixed; beads 1 .. n_bonds - 1 have friction ``zeta``, the last one
    ``zeta_end``. Energies: tension f / (2 b) (Delta u)^2 per bond, bending
    kappa / (2 b^2) (u_{i-1} - 2 u_i + u_{i+1})^2 per joint.

    Parameters
    ----------
    m : Lin1D
        The model to add to.
    n_bonds : int
        Bonds of the strand.
    b : float
        Bond length (nm).
    tension : float
        Tension f (pN).
    kappa : float
        Hinge bending stiffness (pN nm; U = kappa (1 - cos theta)).
    zeta, zeta_end : float
        Friction of the inner beads and of the last bead (pN ns / nm).

    Returns
    -------
    idx : list of int
        The mobile beads' particle indices, surface to end.
    ext : list of (dict, float)
        Energy-form terms whose sum is the extension's quadratic part,
        sum over bonds of (Delta u)^2 / (2 b) (for :meth:`Lin1D.matrix`).
    """
    idx = [None] + [m.particle(zeta) for _ in range(n_bonds - 1)] + [m.particle(zeta_end)]
    for i in range(n_bonds):  # tension: f/(2b) (Delta u)^2
        m.term({idx[i]: -1.0, idx[i + 1]: 1.0}, tension / b)
    for i in range(1, n_bonds):  # bending: kappa/(2 b^2) (u_{i-1} - 2 u_i + u_{i+1})^2
        c: dict = {}
        for j, cj in ((idx[i - 1], 1.0), (idx[i], -2.0), (idx[i + 1], 1.0)):
            if j is not None:
                c[j] = c.get(j, 0.0) + cj
        m.term(c, kappa / b**2)
    ext = [({idx[i]: -1.0, idx[i + 1]: 1.0}, 0.5 / b) for i in range(n_bonds)]
    return idx[1:], ext


def _g_linear(lam, V, Z, g, dt):
    """Statistical inefficiency g and tau = g dt / 2 (ns) of the linear observable g.u
    sampled every dt (ns); also the continuous-time tau and the modes' variance weights
    (summing to 1)."""
    c = V.T @ g  # amplitude of mode k in g.u is c_k a_k
    w = c**2 / lam  # variance weights (x kT)
    w = w / w.sum()
    gi = float(np.sum(w / np.tanh(lam * dt / 2)))
    return {"g": gi, "tau_ns": gi * dt / 2, "tau_cont_ns": float(np.sum(w / lam)),
            "weights": w}


def _parts_linear(lam, V, g, kT, dt):
    """(variance, variance x g) of the linear observable g.u sampled every dt."""
    c = V.T @ g
    w = kT * c**2 / lam
    return float(np.sum(w)), float(np.sum(w / np.tanh(lam * dt / 2))), (w, lam)


def _parts_quadratic(lam, V, D, kT, dt):
    """(variance, variance x g) of u^T D u (Gaussian modes of variance kT / lambda)."""
    M = V.T @ D @ V
    W = 2 * kT**2 * M**2 / np.outer(lam, lam)
    rate = lam[:, None] + lam[None, :]
    return (float(np.sum(W)), float(np.sum(W / np.tanh(rate * dt / 2))),
            (W.ravel(), rate.ravel()))


def longitudinal_chain(m: Lin1D, n_bonds: int, k_bond: float, zeta: float,
                       zeta_end: float) -> list:
    """Add a strand's bond stretching along the force to ``m``: springs ``k_bond`` (S / b,
    pN / nm) between consecutive beads, bead 0 fixed, frictions ``zeta`` and (last bead)
    ``zeta_end`` (pN ns / nm). Returns the mobile beads' particle indices."""
    idx = [None] + [m.particle(zeta) for _ in range(n_bonds - 1)] + [m.particle(zeta_end)]
    for i in range(n_bonds):
        m.term({idx[i]: -1.0, idx[i + 1]: 1.0}, k_bond)
    return idx[1:]


def _block_linear(lam, w, dt, B):
    """Block means over B samples (spacing dt) of a sum of exponentials (rates lam,
    variance weights w, summing to 1): tau (ns) of the block series and the fraction of
    the variance that survives the averaging."""
    r = np.exp(-lam * dt)[:, None]
    d = np.arange(1, B)[None, :]
    c0 = (B + 2 * np.sum((B - d) * r**d, axis=1)) / B**2
    S = np.sum(r ** np.arange(B)[None, :], axis=1)
    rB = r[:, 0] ** B
    csum = r[:, 0] * S**2 / B**2 / np.maximum(1 - rB, 1e-300)
    v = w * c0
    g = float(np.sum(w * (c0 + 2 * csum)) / np.sum(v))
    return {"tau_ns": g * B * dt / 2, "slow_fraction": float(np.sum(v))}


def twist_model(scene, d) -> Lin1D:
    """Rotation about the axis of a torsionally constrained tether (plectoneme scene, n = 0).

    One frame angle per bond (side particle of friction zeta_f at the arm a_f), joints of
    stiffness C kT / b, clamps 2 C kT / b at the surface and at the bead, the bead's
    orientation particle (friction zeta at 20 nm) in the rotational trap K.

    Parameters
    ----------
    scene : dnabraid.scenes.plectoneme.Plectoneme
        The scene (bead spacing, beads, twist persistence C, trap stiffness).
    d : mechanics
        ``scene.dna()`` (kT, bead friction).

    Returns
    -------
    model : Lin1D
        Coordinates are angles (rad), frictions in pN ns nm.
    bead : int
        The bead's orientation particle.
    """
    from ..scenes.plectoneme import (
        BEAD_ARM_NM,
        FRAME_ARM_FRACTION,
        FRAME_FRICTION_FRACTION,
    )

    b, N = scene.bead_spacing_nm, scene.n_beads - 1
    g = scene.twist_persistence_nm * d.kT / b
    zf = FRAME_FRICTION_FRACTION * d.zeta_bead * (FRAME_ARM_FRACTION * b) ** 2
    m = Lin1D()
    th = [m.particle(zf) for _ in range(N)]
    bead = m.particle(d.zeta_bead * BEAD_ARM_NM**2)
    m.term({th[0]: 1.0}, 2 * g)
    for i in range(N - 1):
        m.term({th[i]: -1.0, th[i + 1]: 1.0}, g)
    m.term({th[-1]: -1.0, bead: 1.0}, 2 * g)
    m.term({bead: 1.0}, scene.trap_stiffness_pN_nm)
    return m, bead


def linear_model(scene, sample_dt_ns: float, frame_dt_ns: float, *,
                 torque_block: int = TORQUE_BLOCK) -> dict:
    """Predicted autocorrelation times of a tweezer scene's observables.

    From the scene's linearised transverse dynamics about the straight state (n = 0; for
    n != 0 the same numbers are the reference): tether and plectoneme one strand ending
    at the bead (plectoneme: plus :func:`twist_model`); braid two strands of tension F/2
    whose ends are rigidly linked to the bead centre C at height h above their chord.

    Parameters
    ----------
    scene : dnabraid.scenes.base.Scene
        A ``tether``, ``plectoneme`` or ``braid`` scene.
    sample_dt_ns : float
        Sampling interval of the observables (extension, torque), ns.
    frame_dt_ns : float
        Sampling interval of the frames (bead x, y, tilt), ns.
    torque_block : int
        Samples per block of the torque's slow part.

    Returns
    -------
    dict
        tau = g dt / 2 (ns) at its sampling interval of ``extension``, ``bead_xy``,
        ``tilt``, ``torque``, ``torque_slow`` (block means) where the scene has them
        (braid also ``bead_x``, ``bead_y``; plectoneme ``twist_torque``); ``tau1_ns``
        (slowest mode) and ``tau1_formula_ns`` (:func:`string_tau1`); the closed forms
        ``*_formula_ns``; ``extension_std_nm``, ``extension_stretch_fraction``,
        ``torque_slow_fraction``, ``zeta_end`` (pN ns / nm); and ``_spectra``: per
        observable the (variance weights, rates) of its modes, for
        :func:`e_time_spectrum`.
    """
    from .. import units

    d = scene.dna()
    b, N, F = scene.bead_spacing_nm, scene.n_beads - 1, scene.force_pN
    kappa, zeta = d.kappa, d.zeta_bead
    zl = zeta / b
    L = scene.length_nm
    zeta_phys = units.stokes_friction(scene.bead_radius_nm)
    out: dict = {}
    twisted = scene.torsionally_constrained
    if scene.strands == 1:
        zeta_end = max(zeta, scene.bead_friction_factor * zeta_phys)
        if twisted:
            zeta_end += zeta  # the orientation particle m moves with the attachment
        m = Lin1D()
        idx, ext = chain(m, N, b, F, kappa, zeta, zeta_end)
        lam, V = m.modes()
        Z = np.diag(m.zeta)
        g = np.zeros(len(m.zeta))
        g[idx[-1]] = 1.0
        rb = _g_linear(lam, V, Z, g, frame_dt_ns)
        out["bead_xy"] = rb["tau_ns"]
        spec = {"bead_x": (rb["weights"], lam), "bead_y": (rb["weights"], lam)}
        out["_spectra"] = spec
        vq, gq, sq = _parts_quadratic(lam, V, m.matrix(ext), d.kT, sample_dt_ns)
        ml = Lin1D()
        il = longitudinal_chain(ml, N, d.k_bond, zeta, zeta_end)
        gl = np.zeros(len(ml.zeta))
        gl[il[-1]] = 1.0
        vl, gll, sl = _parts_linear(*ml.modes(), gl, d.kT, sample_dt_ns)
        spec["extension"] = (np.r_[2 * sq[0], sl[0]], np.r_[sq[1], sl[1]])
        # two transverse directions (x, y) plus the bonds' stretch along z
        out["extension"] = (2 * gq + gll) / (2 * vq + vl) * sample_dt_ns / 2
        out["extension_std_nm"] = math.sqrt(2 * vq + vl)
        out["extension_stretch_fraction"] = vl / (2 * vq + vl)
        out["tau1_ns"] = float(1 / lam[0])
        out["tau1_formula_ns"] = string_tau1(zl, L, F, zeta_end)
        out["bead_xy_formula_ns"] = L * (zl * L / 3 + zeta_end) / F
        out["extension_formula_ns"] = extension_formula(zl, L, F, d.kT, scene.persistence_nm,
                                                        scene.stretch_modulus_pN, 0.5)
        out["zeta_end"] = zeta_end
        if twisted:
            tm, bead = twist_model(scene, d)
            lam, V = tm.modes()
            gt = np.zeros(len(tm.zeta))
            gt[bead] = scene.trap_stiffness_pN_nm
            r = _g_linear(lam, V, np.diag(tm.zeta), gt, sample_dt_ns)
            out["torque"] = r["tau_ns"]
            spec["torque"] = (r["weights"], lam)
            blk = _block_linear(lam, r["weights"], sample_dt_ns, torque_block)
            out["torque_slow"] = blk["tau_ns"]
            out["torque_slow_fraction"] = blk["slow_fraction"]
            out["tau_twist_ns"] = float(1 / lam[0])
            # the twist torque 2 pi Tw C kT / L: total twist = bead angle (Lk) - ...; the
            # twist's slowest mode
            tw = np.zeros(len(tm.zeta))
            tw[bead] = 1.0
            out["twist_torque"] = _g_linear(lam, V, np.diag(tm.zeta), tw, sample_dt_ns)["tau_ns"]
            a = 20.0
            out["tilt"] = libration_tau(zeta, scene.trap_stiffness_pN_nm / a**2, frame_dt_ns)
        return out
    # braid: two strands (tension F/2 each) ending at attachments rigidly linked to the
    # bead centre C (friction zeta_C) at height h above the chord's midpoint
    s = scene.tether_separation_nm
    R = scene.bead_radius_nm
    h = math.sqrt(R * R - s * s / 4)
    zc = scene.bead_friction_factor * zeta_phys
    K = scene.trap_stiffness_pN_nm
    k_tilt = K / (s / 2) ** 2
    res = {}
    for axis in ("y", "x"):
        m = Lin1D()
        ia, ea = chain(m, N, b, F / 2, kappa, zeta, zeta)
        ib, eb = chain(m, N, b, F / 2, kappa, zeta, zeta)
        c = m.particle(zc)
        A, B = ia[-1], ib[-1]
        if axis == "y":  # perpendicular to the chord: trap holds the chord angle; C on F/h
            m.term({A: -1.0 / s, B: 1.0 / s}, K)
            m.term({c: 1.0, A: -0.5, B: -0.5}, F / h)
        else:  # along the chord: rigid link; C's swing tilts the chord (trap tilt term)
            m.term({A: -1.0, B: 1.0}, d.k_bond)
            m.term({c: 1.0, A: -0.5, B: -0.5}, F / h + k_tilt * s * s / h**2)
        lam, V = m.modes()
        Z = np.diag(m.zeta)
        e = np.eye(len(m.zeta))  # e[i]: the unit vector of particle i
        r = {"lam": lam, "V": V, "Z": Z,
             "ext": m.matrix([(cc, 0.5 * k) for cc, k in ea + eb]),
             "C": _g_linear(lam, V, Z, e[c], frame_dt_ns),
             "tilt": _g_linear(lam, V, Z, (e[c] - 0.5 * e[A] - 0.5 * e[B]) / h, frame_dt_ns)}
        if axis == "y":
            gt = K * (e[B] - e[A]) / s
            r["torque"] = _g_linear(lam, V, Z, gt, sample_dt_ns)
            blk = _block_linear(lam, r["torque"]["weights"], sample_dt_ns, torque_block)
            r["torque_slow_cont"] = blk["tau_ns"]
            r["torque_slow_fraction"] = blk["slow_fraction"]
        res[axis] = r
    # extension: x and y transverse directions and the stretch along z (variances add)
    num = den = 0.0
    ws, rs = [], []
    for r in res.values():
        v, vg, sq = _parts_quadratic(r["lam"], r["V"], r["ext"], d.kT, sample_dt_ns)
        num += vg
        den += v
        ws.append(sq[0])
        rs.append(sq[1])
    ml = Lin1D()
    ia = longitudinal_chain(ml, N, d.k_bond, zeta, zeta)
    ib = longitudinal_chain(ml, N, d.k_bond, zeta, zeta)
    c = ml.particle(zc)
    ml.term({ia[-1]: -1.0, c: 1.0}, d.k_bond)  # the links to the bead centre
    ml.term({ib[-1]: -1.0, c: 1.0}, d.k_bond)
    ml.term({ia[-1]: -1.0, ib[-1]: 1.0}, k_tilt)  # the trap keeps the chord level
    gl = np.zeros(len(ml.zeta))
    gl[ia[-1]] = gl[ib[-1]] = 0.5
    vl, vgl, sl = _parts_linear(*ml.modes(), gl, d.kT, sample_dt_ns)
    out["_spectra"] = {
        "extension": (np.concatenate(ws + [sl[0]]), np.concatenate(rs + [sl[1]])),
        "bead_x": (res["x"]["C"]["weights"], res["x"]["lam"]),
        "bead_y": (res["y"]["C"]["weights"], res["y"]["lam"]),
        "tilt": (res["y"]["tilt"]["weights"], res["y"]["lam"]),
        "torque": (res["y"]["torque"]["weights"], res["y"]["lam"])}
    out["extension"] = (num + vgl) / (den + vl) * sample_dt_ns / 2
    out["extension_std_nm"] = math.sqrt(den + vl)
    out["extension_stretch_fraction"] = vl / (den + vl)
    out["bead_xy"] = max(res["x"]["C"]["tau_ns"], res["y"]["C"]["tau_ns"])
    out["bead_x"] = res["x"]["C"]["tau_ns"]
    out["bead_y"] = res["y"]["C"]["tau_ns"]
    out["tilt"] = res["y"]["tilt"]["tau_ns"]
    out["torque"] = res["y"]["torque"]["tau_ns"]
    out["torque_slow"] = res["y"]["torque_slow_cont"]
    out["torque_slow_fraction"] = res["y"]["torque_slow_fraction"]
    out["tau1_ns"] = float(1 / min(res["x"]["lam"][0], res["y"]["lam"][0]))
    out["tau1_formula_ns"] = string_tau1(2 * zl, L, F, 2 * zeta + zc)
    # C across the chord: pendulum and tilt spring in series; along the chord: pendulum
    out["bead_y_formula_ns"] = ((2 * zl * L**3 / 3 + 2 * zeta * L**2 + zc * (L + h) ** 2)
                                / (F * (L + h)))
    out["bead_x_formula_ns"] = L * (2 * zl * L / 3 + 2 * zeta + zc) / F
    out["bead_xy_formula_ns"] = max(out["bead_x_formula_ns"], out["bead_y_formula_ns"])
    out["extension_formula_ns"] = extension_formula(zl, L, F / 2, d.kT, scene.persistence_nm,
                                                    scene.stretch_modulus_pN, 1.0 / 3.0)
    out["tau_tilt_formula_ns"] = zc * h / F
    out["tau_libration_formula_ns"] = 2 * zeta * (s / 2) ** 2 / K
    out["tau_antisym_formula_ns"] = zl * L**2 / (math.pi**2 * F / 2)
    out["zeta_end"] = 2 * zeta + zc
    return out


def extension_formula(zl, L, f, kT, lp, S, mode_sum):
    """Closed-form tau (ns) of the extension of a strand under tension, L >> l_f.

    tau = (1 - phi_s) zl L l_f / f x 2 mode_sum with l_f = sqrt(kT lp / f); mode_sum =
    sum_k 1 / q_k^2 = 1/2 for a free end (tether), 1/3 averaged over the braid's free
    (1/2) and held (1/6) mode families; phi_s = 1 / (1 + S kT / (4 f^2 l_f)) is the
    variance share of the (fast) bond stretch.

    Parameters
    ----------
    zl : float
        Friction per length (pN ns / nm^2).
    L : float
        Contour length (nm).
    f : float
        Tension (pN).
    kT : float
        Thermal energy (pN nm).
    lp : float
        Persistence length (nm).
    S : float
        Stretch modulus (pN).
    mode_sum : float
        sum_k 1 / q_k^2 of the strand's mode family.
    """
    lf = math.sqrt(kT * lp / f)
    phi = 1.0 / (1.0 + S * kT / (4 * f * f * lf))
    return (1 - phi) * zl * L * lf / f * 2 * mode_sum


def string_tau1(zl: float, L: float, f: float, zeta_end: float) -> float:
    """Relaxation time (ns) of the slowest transverse mode of a string ending at a bead.

    The string (friction ``zl`` per length, tension ``f``, length ``L``) is fixed at the
    surface and free at a bead of friction ``zeta_end``: tau_1 = zl L^2 / (f q^2) with
    q tan q = zl L / zeta_end. Limits: q -> pi/2 for a frictionless end
    (tau_1 -> 4 zl L^2 / (pi^2 f)); q^2 -> zl L / zeta_end for a heavy bead
    (tau_1 -> zeta_end L / f).

    Parameters
    ----------
    zl : float
        Friction per length (pN ns / nm^2).
    L : float
        Length (nm).
    f : float
        Tension (pN).
    zeta_end : float
        Friction of the end bead (pN ns / nm), > 0.
    """
    from scipy.optimize import brentq

    a = zl * L / zeta_end
    q = brentq(lambda q: q * math.tan(q) - a, 1e-12, math.pi / 2 - 1e-12)
    return zl * L * L / (f * q * q)


def libration_tau(zeta_rot: float, stiffness: float, dt: float) -> float:
    """tau = g dt / 2 (ns) of a single exponential sampled every ``dt`` (ns).

    The exponential's time is t = zeta_rot / stiffness (a particle on a spring; for
    dt << t, tau -> t). ``zeta_rot`` and ``stiffness`` in matching units (pN ns nm and
    pN nm for a rotation, pN ns / nm and pN / nm for a translation).
    """
    t = zeta_rot / stiffness
    return dt / 2 / math.tanh(dt / (2 * t))


def e_time_spectrum(spec) -> float:
    """Lag (ns) at which rho(t) = sum w e^{-r t} / sum w first falls to 1/e.

    ``spec`` is (variance weights w, rates r in 1/ns), as in ``linear_model``'s
    ``_spectra``. A single exponential gives 1 / r.
    """
    from scipy.optimize import brentq

    w, r = (np.asarray(a, float) for a in spec)
    w = w / w.sum()

    def f(t):
        return float(np.sum(w * np.exp(-r * t))) - math.exp(-1.0)

    hi = 1.0 / r[w > 1e-12 * w.max()].min()
    if f(0.0) <= 0:
        return 0.0
    while f(hi) > 0:
        hi *= 2
    return brentq(f, 0.0, hi)


def e_time(x, dt_ns: float) -> float | None:
    """First lag (ns) at which the measured autocorrelation falls below 1/e.

    Linear interpolation between the samples (spacing ``dt_ns``). None for fewer than
    20 finite samples, a constant series, or one that never decorrelates to 1/e.
    """
    from .stats import autocorrelation

    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if x.size < 20 or np.ptp(x) == 0:
        return None
    rho = autocorrelation(x)
    k = np.nonzero(rho < math.exp(-1.0))[0]
    if k.size == 0:
        return None
    k = int(k[0])
    t = (k - 1) + (rho[k - 1] - math.exp(-1.0)) / (rho[k - 1] - rho[k])
    return float(t * dt_ns)


def e_time_err(x, dt_ns: float, parts: int = 4) -> tuple[float | None, float | None]:
    """1/e time (ns, :func:`e_time`) of the whole series and its error from the scatter
    over ``parts`` consecutive segments (std / sqrt(parts)); None where undefined."""
    whole = e_time(x, dt_ns)
    x = np.asarray(x, float)
    seg = [e_time(c, dt_ns) for c in np.array_split(x, parts)]
    seg = [v for v in seg if v is not None]
    err = float(np.std(seg, ddof=1) / math.sqrt(len(seg))) if len(seg) > 1 else None
    return whole, err


def tau_of(x, dt_ns: float, *, cut: bool = True) -> dict:
    """tau = g dt / 2 (ns) of one series, with Sokal's error and the run in units of tau.

    Parameters
    ----------
    x : array_like
        The series (non-finite values dropped), spacing ``dt_ns`` (ns).
    cut : bool
        Drop the initial transient first (Chodera's rule,
        :func:`dnabraid.analysis.convergence.detect_equilibration`).

    Returns
    -------
    dict
        ``tau_ns`` (None for fewer than 20 samples or a constant series), ``g``,
        ``window`` (Sokal's M), ``n``, ``cut``, ``rel_err`` (sqrt(2 (2M + 1) / n)),
        ``run_over_tau``, ``mean``, ``std``.
    """
    from .convergence import detect_equilibration
    from .stats import integrated_autocorrelation_time

    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if x.size < 20 or np.ptp(x) == 0:
        return {"tau_ns": None}
    t0 = detect_equilibration(x)[0] if cut else 0
    y = x[t0:]
    g, M = integrated_autocorrelation_time(y)
    g = max(g, 1.0)
    n = y.size
    T = n * dt_ns
    tau = g * dt_ns / 2
    return {"tau_ns": tau, "g": g, "window": int(M), "n": int(n), "cut": int(t0),
            "rel_err": math.sqrt(2 * (2 * M + 1) / n), "run_over_tau": T / tau,
            "mean": float(y.mean()), "std": float(y.std())}


def block_means(x, k: int) -> np.ndarray:
    """Means of consecutive blocks of ``k`` samples (a last partial block is dropped)."""
    x = np.asarray(x, float)
    n = x.size // k
    return x[: n * k].reshape(n, k).mean(axis=1)
