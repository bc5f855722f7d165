"""Slow modes of the tweezer scenes: integrated autocorrelation times, measured and predicted.

For tether, braid and plectoneme, at several sizes and forces, one long trajectory per case
(one replica, run serially in this process) gives the integrated autocorrelation time of

* the extension (every sample),
* the trap torque (every sample) and its slow part (the torque averaged over blocks longer
  than the trap's fast libration),
* the bead position x, y (the bead centre C for the braid, the attachment for tether and
  plectoneme; from the trajectory frames),
* the bead tilt (braid: the bead centre's offset from the attachment chord's midpoint,
  perpendicular to the chord, over the height h of C above the chord; plectoneme: the
  orientation arm's z-difference over its length),
* the catenation crossings (braid, n != 0: the mean height of the apparent crossings of the
  two strands seen along y, per frame),
* the writhe (plectoneme, per frame).

Every measured time is set beside the prediction of a linearised bead-spring model of the
same scene (the discrete chain under tension with bending, the exact bead frictions, the
bead's centre on its tilt spring F/h and the trap; :func:`linear_model`), whose slowest
mode has the closed form tau_1 = zeta_l L^2 / (f q^2), q tan q = zeta_l L / zeta_end
(docs/slow_modes.md). The predictions for the default scenes, too slow to measure here, come
from the same model.

Conventions: tau = g Delta / 2, with g = 1 + 2 sum rho (the statistical inefficiency of
dnabraid.analysis.stats.integrated_autocorrelation_time, Sokal's window) and Delta the
sampling interval; tau equals the relaxation time of a single exponential and the integral
of the autocorrelation function. A run of length T holds T / (2 tau) independent samples.
The relative error of tau from one run is about sqrt(2 (2 M + 1) / N) (Sokal 1996, M the
window, N the samples): a run needs T >~ 50 tau for a usable estimate.

Beside tau, the first lag at which the autocorrelation falls below 1/e is given, measured
(error from four segments of the run) and predicted: it is far less noisy than tau in runs
of a few tens of tau, and tests the model's time scale directly.

The runs use timestep_safety = 0.9 (dt ~ 71 ps instead of the default 23.6 ps): relaxation
times in ns do not depend on the time step to first order in rate x dt (< 1e-3 for the slow
modes, 0.04 for the trap's libration), and the steps are reported at the default time step
(tau_ns / dt_default).

Usage: taskset -c 0 python workflows/slow_modes.py [--quick] [--cases id1,id2] [--scale s]
       [--keep DIR] [--reanalyse DIR] [--predict-only]
Writes workflows/results/slow_modes.md and .json after every case (about 16 min on one
free core for all cases). Results and formulas: docs/slow_modes.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import pathlib
import tempfile
import time
import warnings

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
RESULTS = HERE / "results"
#: Time-step safety of the runs (the scenes' default is 0.3).
RUN_SAFETY = 0.9
#: Block length (samples) for the slow part of the torque: 10 samples x 100 steps x 71 ps
#: = 71 ns, far beyond the trap's libration (~2 ns) and the sampling interval (7 ns).
TORQUE_BLOCK = 10


# ----------------------------------------------------------------------------- cases
@dataclasses.dataclass
class Case:
    id: str
    scene: str
    keys: dict
    steps: int               # sampling steps (at RUN_SAFETY)
    equilibration: int       # equilibration steps (at RUN_SAFETY)
    note: str = ""


CASES = [
    Case("tether-25nm-5pN", "tether", {"length_nm": 25.0, "force_pN": 5.0}, 1_000_000, 20_000),
    Case("tether-50nm-5pN", "tether", {"length_nm": 50.0, "force_pN": 5.0}, 1_000_000, 20_000),
    Case("tether-50nm-20pN", "tether", {"length_nm": 50.0, "force_pN": 20.0}, 400_000, 10_000),
    Case("braid-2x60nm-10pN-n0", "braid", {"length_nm": 60.0, "force_pN": 10.0,
                                           "turns": [0.0]}, 800_000, 100_000),
    Case("braid-2x60nm-10pN-n1", "braid", {"length_nm": 60.0, "force_pN": 10.0,
                                           "turns": [1.0]}, 800_000, 100_000),
    Case("plectoneme-50nm-5pN-n0", "plectoneme", {"length_nm": 50.0, "force_pN": 5.0,
                                                  "turns": [0.0]}, 400_000, 50_000),
    Case("plectoneme-100nm-1pN-n2", "plectoneme", {"length_nm": 100.0, "force_pN": 1.0,
                                                   "turns": [2.0]}, 400_000, 60_000,
         "the brief's size: its pivot mode (~40 us) is longer than this run (26 us)"),
    Case("tether-100nm-10pN", "tether", {"length_nm": 100.0, "force_pN": 10.0}, 800_000,
         20_000),
    Case("braid-2x60nm-20pN-n0", "braid", {"length_nm": 60.0, "force_pN": 20.0,
                                           "turns": [0.0]}, 800_000, 100_000),
]

#: Default scenes (and the brief's larger sizes), predicted only.
PREDICT_ONLY = [
    ("tether default (300 nm, 1 pN)", "tether", {}),
    ("tether 100 nm, 1 pN", "tether", {"length_nm": 100.0, "force_pN": 1.0}),
    ("tether 100 nm, 5 pN", "tether", {"length_nm": 100.0, "force_pN": 5.0}),
    ("tether 50 nm, 1 pN", "tether", {"length_nm": 50.0, "force_pN": 1.0}),
    ("braid old default (2 x 200 nm, 2 pN), n = 0", "braid",
     {"length_nm": 200.0, "force_pN": 2.0, "timestep_safety": 0.3, "turns": [0.0]}),
    ("braid 2 x 100 nm, 2 pN, n = 0", "braid", {"length_nm": 100.0, "force_pN": 2.0,
                                                "timestep_safety": 0.3, "turns": [0.0]}),
    ("braid 2 x 60 nm, 2 pN, n = 0", "braid", {"length_nm": 60.0, "force_pN": 2.0,
                                               "timestep_safety": 0.3, "turns": [0.0]}),
    ("braid default (2 x 60 nm, 20 pN), n = 0", "braid", {"turns": [0.0]}),
    ("plectoneme default (300 nm, 1 pN), n = 0", "plectoneme", {"turns": [0.0]}),
    ("plectoneme 100 nm, 1 pN, n = 0", "plectoneme", {"length_nm": 100.0, "turns": [0.0]}),
]


# ------------------------------------------------------------------------ linear model
class Lin1D:
    """One transverse coordinate per particle; energy sum_t k_t/2 (sum_i c_ti u_i)^2.

    Relaxation: zeta du/dt = -H u + noise. The generalised eigenproblem H v = lambda Z v
    (Z = diag(zeta), V^T Z V = 1) gives independent modal amplitudes a_k with rate
    lambda_k (1/ns) and variance kT / lambda_k.
    """

    def __init__(self):
        self.zeta: list[float] = []
        self.terms: list[tuple[dict, float]] = []

    def particle(self, zeta: float) -> int:
        self.zeta.append(float(zeta))
        return len(self.zeta) - 1

    def term(self, coeffs: dict, k: float) -> None:
        """Energy k/2 (sum_i c_i u_i)^2; an index None is a fixed particle (u = 0)."""
        self.terms.append(({i: c for i, c in coeffs.items() if i is not None}, float(k)))

    def matrix(self, terms=None) -> np.ndarray:
        n = len(self.zeta)
        H = np.zeros((n, n))
        for c, k in (self.terms if terms is None else terms):
            g = np.zeros(n)
            for i, ci in c.items():
                if i is not None:  # a fixed particle
                    g[i] += ci
            H += k * np.outer(g, g)
        return H

    def modes(self):
        from scipy.linalg import eigh

        lam, V = eigh(self.matrix(), np.diag(self.zeta))
        return lam, V


def chain(m: Lin1D, n_bonds: int, b: float, tension: float, kappa: float, zeta: float,
          zeta_end: float) -> tuple[list, list]:
    """A strand fixed at the surface (bead 0) with ``n_bonds`` bonds; returns its mobile
    bead indices and the extension's quadratic terms (sum of bond Delta u^2 / (2 b))."""
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
    """Statistical inefficiency, sampled every dt, and tau (ns) of the linear observable
    g.u; also the continuum tau and the slowest rate that carries weight."""
    c = V.T @ g  # amplitude of mode k in g.u is c_k a_k
    w = c**2 / lam  # variance weights (x kT)
    w = w / w.sum()
    gi = float(np.sum(w / np.tanh(lam * dt / 2)))
    return {"g": gi, "tau_ns": gi * dt / 2, "tau_cont_ns": float(np.sum(w / lam)),
            "weights": w}


def _g_quadratic(lam, V, D, dt):
    """Same for the quadratic observable u^T D u (Gaussian modes)."""
    M = V.T @ D @ V
    W = M**2 / np.outer(lam, lam)
    rate = lam[:, None] + lam[None, :]
    W = W / W.sum()
    gi = float(np.sum(W / np.tanh(rate * dt / 2)))
    return {"g": gi, "tau_ns": gi * dt / 2, "tau_cont_ns": float(np.sum(W / rate))}


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
    """Bond stretching along the force: springs S/b, bead 0 fixed; mobile indices."""
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
    """Rotation about the axis of a torsionally constrained tether at n = 0: one frame
    angle per bond (side particle of friction zeta_f at the arm a_f), joints of stiffness
    C kT / b, clamps 2 C kT / b at the surface and at the bead, the bead's orientation
    particle (friction zeta at 20 nm) in the trap K. Returns (model, bead index)."""
    from dnabraid.scenes.plectoneme import (
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


def linear_model(scene, sample_dt_ns: float, frame_dt_ns: float) -> dict:
    """Predicted tau (ns) of the scene's observables from its linearised transverse
    dynamics about the straight state (n = 0; for n != 0 the same numbers are the
    reference). Keys: tau1_ns (slowest mode), tau1_formula_ns (closed form), extension,
    bead_xy, tilt, torque, torque_slow (each a tau in ns at its sampling interval)."""
    from dnabraid import units

    d = scene.dna()
    b, N, F = scene.bead_spacing_nm, scene.n_beads - 1, scene.force_pN
    kappa, zeta = d.kappa, d.zeta_bead
    zl = zeta / b
    L = scene.length_nm
    zeta_phys = units.stokes_friction(scene.bead_radius_nm)
    out: dict = {}
    name = scene.name
    if name in ("tether", "plectoneme"):
        zeta_end = max(zeta, scene.bead_friction_factor * zeta_phys)
        if name == "plectoneme":
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
        if name == "plectoneme":
            tm, bead = twist_model(scene, d)
            lam, V = tm.modes()
            gt = np.zeros(len(tm.zeta))
            gt[bead] = scene.trap_stiffness_pN_nm
            r = _g_linear(lam, V, np.diag(tm.zeta), gt, sample_dt_ns)
            out["torque"] = r["tau_ns"]
            spec["torque"] = (r["weights"], lam)
            blk = _block_linear(lam, r["weights"], sample_dt_ns, TORQUE_BLOCK)
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
            blk = _block_linear(lam, r["torque"]["weights"], sample_dt_ns, TORQUE_BLOCK)
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
    """tau of the extension of a strand under tension f, L >> l_f = sqrt(kT lp / f):
    (1 - phi_s) zl L l_f / f x 2 mode_sum, mode_sum = sum_k 1/q_k^2 = 1/2 for a free end
    (tether), 1/3 averaged over the braid's free (1/2) and held (1/6) mode families;
    phi_s = 1 / (1 + S kT / (4 f^2 l_f)) is the variance share of the (fast) bond stretch."""
    lf = math.sqrt(kT * lp / f)
    phi = 1.0 / (1.0 + S * kT / (4 * f * f * lf))
    return (1 - phi) * zl * L * lf / f * 2 * mode_sum


def string_tau1(zl: float, L: float, f: float, zeta_end: float) -> float:
    """Slowest mode of a string (friction zl per length, tension f) fixed at the surface
    and free at a bead of friction zeta_end: tau_1 = zl L^2 / (f q^2), q tan q = zl L /
    zeta_end (q -> pi/2 for a free end, q^2 -> zl L / zeta_end: tau -> zeta_end L / f)."""
    from scipy.optimize import brentq

    a = zl * L / zeta_end
    q = brentq(lambda q: q * math.tan(q) - a, 1e-12, math.pi / 2 - 1e-12)
    return zl * L * L / (f * q * q)


def libration_tau(zeta_rot: float, stiffness: float, dt: float) -> float:
    """tau = g dt / 2 of a single exponential of time zeta_rot / stiffness sampled every dt."""
    t = zeta_rot / stiffness
    return dt / 2 / math.tanh(dt / (2 * t))


def e_time_spectrum(spec) -> float:
    """Lag (ns) at which rho(t) = sum w e^{-r t} / sum w first falls to 1/e."""
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


# --------------------------------------------------------------------------- measuring
def e_time(x, dt_ns: float) -> float | None:
    """First lag (ns) at which the measured autocorrelation falls below 1/e (linear
    interpolation between samples; 0 if already at the first lag's... lag 1 below)."""
    from dnabraid.analysis.stats import autocorrelation

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
    """1/e time of the whole series and its error from the scatter over ``parts``
    consecutive segments (std / sqrt(parts))."""
    whole = e_time(x, dt_ns)
    x = np.asarray(x, float)
    seg = [e_time(c, dt_ns) for c in np.array_split(x, parts)]
    seg = [v for v in seg if v is not None]
    err = float(np.std(seg, ddof=1) / math.sqrt(len(seg))) if len(seg) > 1 else None
    return whole, err


def tau_of(x, dt_ns: float, *, cut: bool = True) -> dict:
    """tau = g dt / 2 (ns) of one series, with Sokal's error and the run in units of tau."""
    from dnabraid.analysis.convergence import detect_equilibration
    from dnabraid.analysis.stats import integrated_autocorrelation_time

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
    x = np.asarray(x, float)
    n = x.size // k
    return x[: n * k].reshape(n, k).mean(axis=1)


def crossing_heights(pa: np.ndarray, pb: np.ndarray) -> tuple[float, int]:
    """Apparent crossings of two strands seen along y: heights where x_A - x_B changes sign
    (strands sampled at common heights). Returns (mean height of the crossings, count)."""
    z = np.linspace(max(pa[1, 2], pb[1, 2]), min(pa[-2, 2], pb[-2, 2]), 200)
    ia, ib = np.argsort(pa[:, 2]), np.argsort(pb[:, 2])
    dx = np.interp(z, pa[ia, 2], pa[ia, 0]) - np.interp(z, pb[ib, 2], pb[ib, 0])
    k = np.nonzero(np.sign(dx[:-1]) * np.sign(dx[1:]) < 0)[0]
    if k.size == 0:
        return math.nan, 0
    zc = z[k] - dx[k] * (z[k + 1] - z[k]) / (dx[k + 1] - dx[k])
    return float(np.mean(zc)), int(k.size)


def read_frames(out: str, model) -> dict:
    """Per-frame series from the trajectory: bead x, y; tilt; crossing heights."""
    import MDAnalysis as mda

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        u = mda.Universe(str(pathlib.Path(out) / "topology.pdb"),
                         str(pathlib.Path(out) / "trajectory.dcd"))
        att = model.attachments
        center = model.extra.get("bead_center")
        m = getattr(model, "bead_orientation", None)
        ser: dict = {k: [] for k in ("bead_x", "bead_y", "tilt", "crossing_z", "n_crossings")}
        for ts in u.trajectory:
            p = ts.positions.astype(float) / 10.0
            if center is not None:  # braid: the bead centre; tilt about the chord
                mid = p[att].mean(axis=0)
                chord = p[att[1]] - p[att[0]]
                perp = np.array([-chord[1], chord[0], 0.0])
                perp /= np.linalg.norm(perp)
                h = p[center, 2] - mid[2]
                ser["bead_x"].append(p[center, 0])
                ser["bead_y"].append(p[center, 1])
                ser["tilt"].append(float(np.dot(p[center] - mid, perp) / h))
                zc, nc = crossing_heights(p[model.chains[0]], p[model.chains[1]])
                ser["crossing_z"].append(zc)
                ser["n_crossings"].append(nc)
            else:
                ser["bead_x"].append(p[att[0], 0])
                ser["bead_y"].append(p[att[0], 1])
                if m is not None:
                    arm = p[m] - p[att[0]]
                    ser["tilt"].append(float(arm[2] / np.linalg.norm(arm)))
    return {k: np.asarray(v, float) for k, v in ser.items() if len(v)}


def read_csv(path) -> dict:
    from dnabraid.reporters import read_csv as _read

    return _read(path)


def case_scene(case: Case, quick: bool, scale: float):
    """The scene of a case (run keys) and its sampling settings."""
    from dnabraid.scenes import make_scene

    steps = case.steps if not quick else max(20_000, case.steps // 25)
    steps = int(round(steps * scale / 1000)) * 1000 if not quick else steps
    eq = case.equilibration if not quick else case.equilibration // 10
    fi = max(100, int(round(steps / 4000 / 100)) * 100)
    keys = dict(case.keys, steps=steps, equilibration_steps=eq, report_interval=100,
                frame_interval=fi, replicas=1, workers=1, protocol="ramp",
                timestep_safety=RUN_SAFETY, seed=3)
    return make_scene(case.scene, keys)


def run_case(case: Case, quick: bool, scale: float, keep: str = "") -> dict:
    from tqdm import tqdm

    scene = case_scene(case, quick, scale)
    model = scene.build()
    dt = model.timestep.time_step_ns
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()

        def bar(total):
            return tqdm(total=total, unit="step", unit_scale=True, desc=case.id,
                        mininterval=15.0)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene.run(tmp, threads=1, progress_factory=bar)
        wall = time.perf_counter() - t0
        obs = read_csv(pathlib.Path(tmp) / "observables.csv")
        frames = read_frames(tmp, model)
        fr = read_csv(pathlib.Path(tmp) / "frames.csv")
    if keep:  # the raw series, for re-analysis without rerunning
        pathlib.Path(keep).mkdir(parents=True, exist_ok=True)
        np.savez_compressed(pathlib.Path(keep) / f"{case.id}.npz", wall_s=wall,
                            sample_dt_ns=100 * dt, frame_dt_ns=scene.frame_interval * dt,
                            **{f"obs_{k}": v for k, v in obs.items()},
                            **{f"frame_{k}": v for k, v in frames.items()},
                            **{f"fr_{k}": v for k, v in fr.items()})
    return analyse(case, scene, dt, obs, frames, fr, wall)


def reanalyse(case: Case, path, quick: bool, scale: float) -> dict:
    """The row of a case from its saved series (``--keep``)."""
    z = np.load(path)
    pick = {p: {k[len(p):]: z[k] for k in z.files if k.startswith(p)}
            for p in ("obs_", "frame_", "fr_")}
    scene = case_scene(case, quick, scale)
    dt = float(z["sample_dt_ns"]) / 100
    return analyse(case, scene, dt, pick["obs_"], pick["frame_"], pick["fr_"],
                   float(z["wall_s"]) if "wall_s" in z.files else float("nan"))


def analyse(case: Case, scene, dt, obs, frames, fr, wall) -> dict:
    from dnabraid.scenes import make_scene

    default_dt_ns = make_scene(case.scene, dict(case.keys)).build().timestep.time_step_ns
    steps, fi = scene.steps, scene.frame_interval
    sdt = 100 * dt
    fdt = fi * dt
    pred = linear_model(scene, sdt, fdt)
    # a tether starts from an exact equilibrium draw: nothing to cut; the others are cut
    # where Chodera's rule says
    cut = scene.name != "tether"
    meas: dict = {"extension": tau_of(obs["extension_nm"], sdt, cut=cut)}
    if "torque_pN_nm" in obs:
        meas["torque"] = tau_of(obs["torque_pN_nm"], sdt, cut=cut)
        tb = block_means(obs["torque_pN_nm"], TORQUE_BLOCK)
        r = tau_of(tb, TORQUE_BLOCK * sdt, cut=False)
        if r["tau_ns"] is not None:
            r["slow_fraction"] = float(np.var(tb) / np.var(obs["torque_pN_nm"]))
        meas["torque_slow"] = r
    if "twist_torque_pN_nm" in obs:
        meas["twist_torque"] = tau_of(obs["twist_torque_pN_nm"], sdt, cut=cut)
    for k in ("bead_x", "bead_y", "tilt", "crossing_z"):
        if k in frames and np.isfinite(frames[k]).mean() > 0.9:
            meas[k] = tau_of(frames[k], fdt, cut=cut)
    if "writhe" in fr:
        meas["writhe"] = tau_of(fr["writhe"], fdt, cut=cut)
    spectra = pred.pop("_spectra", {})
    columns = {"extension": obs.get("extension_nm"), "torque": obs.get("torque_pN_nm"),
               "twist_torque": obs.get("twist_torque_pN_nm"), "writhe": fr.get("writhe")}
    columns.update({k: frames[k] for k in ("bead_x", "bead_y", "tilt", "crossing_z")
                    if k in frames})
    for k, m in meas.items():
        src = columns.get(k)
        if m.get("tau_ns") is None or src is None:
            continue
        src = np.asarray(src, float)
        src = src[np.isfinite(src)]
        step = sdt if k in ("extension", "torque", "twist_torque") else fdt
        m["e_time_ns"], m["e_time_err_ns"] = e_time_err(src[m["cut"]:], step)
        if k in spectra:
            m["e_time_pred_ns"] = e_time_spectrum(spectra[k])
    row = {"id": case.id, "scene": case.scene, "keys": case.keys, "steps": steps,
           "equilibration_steps": scene.equilibration_steps, "frame_interval": fi,
           "dt_ns": dt, "default_dt_ns": default_dt_ns, "wall_s": wall,
           "run_ns": steps * dt, "predicted": pred, "measured": meas, "note": case.note}
    if "n_crossings" in frames:
        row["mean_crossings"] = float(np.mean(frames["n_crossings"]))
    return row


# ----------------------------------------------------------------------------- output
OBS = [("extension", "extension", "extension"), ("torque", "trap torque", "torque"),
       ("torque_slow", "torque, 71 ns blocks", "torque_slow"),
       ("twist_torque", "twist torque", None),  # Tw = Lk - Wr: follows the writhe
       ("bead_x", "bead x", "bead_x"), ("bead_y", "bead y", "bead_y"),
       ("tilt", "bead tilt", "tilt"), ("crossing_z", "crossing height", None),
       ("writhe", "writhe", None)]


def _pred_for(row, key):
    p = row["predicted"]
    if key is None:
        return None
    if key in ("bead_x", "bead_y") and key not in p:
        return p.get("bead_xy")
    return p.get(key)


def fmt(x, nd=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{nd}g}"


def _pm(v, e):
    if v is None:
        return "-"
    return f"{v:.3g} +- {e:.2g}" if e is not None else f"{v:.3g}"


def table(rows) -> str:
    out = ["| case | observable | tau (ns) | +- | tau (steps at default dt) | run / tau | "
           "predicted tau (ns) | run / predicted tau | measured / predicted | "
           "1/e time (ns) | predicted 1/e time (ns) |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        for key, label, pkey in OBS:
            m = row["measured"].get(key)
            if not m or m.get("tau_ns") is None:
                continue
            tp = _pred_for(row, pkey)
            tau = m["tau_ns"]
            ratio = tau / tp if tp else None
            run_pred = f"{m['run_over_tau'] * tau / tp:.0f}" if tp else "-"
            extra = ""
            if key == "torque_slow" and "slow_fraction" in m:
                extra = (f" (var. kept {m['slow_fraction']:.2g}, predicted "
                         f"{fmt(row['predicted'].get('torque_slow_fraction'), 2)})")
            out.append(f"| {row['id']} | {label}{extra} | {fmt(tau)} | {m['rel_err'] * tau:.2g} | "
                       f"{tau / row['default_dt_ns']:.3g} | {m['run_over_tau']:.0f} | {fmt(tp)} | "
                       f"{run_pred} | "
                       f"{fmt(ratio, 2)} | {_pm(m.get('e_time_ns'), m.get('e_time_err_ns'))} | "
                       f"{fmt(m.get('e_time_pred_ns'))} |")
    return "\n".join(out)


def case_lines(rows) -> str:
    out = ["| case | steps (dt) | run (us) | wall (s) | tau_1 model (ns) | tau_1 formula (ns) "
           "| notes |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        p = r["predicted"]
        note = r.get("note", "")
        if "mean_crossings" in r:
            note = (note + "; " if note else "") + f"{r['mean_crossings']:.2f} crossings/frame"
        out.append(f"| {r['id']} | {r['steps']:,} ({r['dt_ns'] * 1e3:.1f} ps) | "
                   f"{r['run_ns'] / 1e3:.1f} | {r['wall_s']:.0f} | {fmt(p['tau1_ns'])} | "
                   f"{fmt(p['tau1_formula_ns'])} | {note} |")
    return "\n".join(out)


def predictions() -> list[dict]:
    from dnabraid.scenes import make_scene

    rows = []
    for label, name, keys in PREDICT_ONLY:
        s = make_scene(name, keys)
        dt = s.build().timestep.time_step_ns
        p = linear_model(s, 100 * dt, s.frame_interval * dt)
        p.pop("_spectra", None)
        worst = max(p["extension"], p.get("bead_xy", 0.0))
        rows.append({"label": label, "dt_ns": dt, "steps_default": s.steps,
                     "equilibration_default": s.equilibration_steps, "predicted": p,
                     "tau_worst_ns": worst,
                     "steps_needed": int(50 * p["extension"] / dt + 5 * p["tau1_ns"] / dt)})
    return rows


def prediction_table(prow) -> str:
    out = ["| scene | dt (ps) | tau_1 model (formula) (ns) | tau extension model (formula) (ns) | "
           "tau bead x,y model (formula) (ns) | tau tilt (ns) | steps/replica needed "
           "(50 tau_ext + 5 tau_1) | default steps (+ eq.) |", "|---|---|---|---|---|---|---|---|"]
    for r in prow:
        p = r["predicted"]
        out.append(f"| {r['label']} | {r['dt_ns'] * 1e3:.1f} | {fmt(p['tau1_ns'])} "
                   f"({fmt(p['tau1_formula_ns'])}) | {fmt(p['extension'])} "
                   f"({fmt(p['extension_formula_ns'])}) | {fmt(p.get('bead_xy'))} "
                   f"({fmt(p['bead_xy_formula_ns'])}) | {fmt(p.get('tilt'))} | "
                   f"{r['steps_needed']:.3g} | {r['steps_default']:,} (+{r['equilibration_default']:,}) |")
    return "\n".join(out)


def write(rows, prow, total_wall, quick):
    RESULTS.mkdir(exist_ok=True)
    stem = "slow_modes_quick" if quick else "slow_modes"
    md = [f"# slow modes, {time.strftime('%Y-%m-%d %H:%M')}"
          + (" (QUICK: runs too short to trust)" if quick else ""), "",
          "tau = g Delta / 2 (g = 1 + 2 sum rho, Sokal window; Delta the sampling interval); "
          "+- = Sokal's error sqrt(2 (2M+1)/N) tau; run / tau = sampled time over tau (>= 50 "
          "for a usable estimate); steps at the scene's default time step (safety 0.3); runs "
          f"at timestep_safety {RUN_SAFETY}. Predicted: the linearised bead-spring model "
          "(workflows/slow_modes.py: linear_model), about the straight n = 0 state.", "",
          "## measured", "", table(rows), "", "## cases", "", case_lines(rows), "",
          "## predicted for the default scenes", "", prediction_table(prow), "",
          f"total wall time {total_wall:.0f} s (one core, serial)", ""]
    (RESULTS / f"{stem}.md").write_text("\n".join(md))

    def clean(o):
        if isinstance(o, dict):
            return {k: clean(v) for k, v in o.items()}
        if isinstance(o, (list, tuple)):
            return [clean(v) for v in o]
        if isinstance(o, (np.floating, np.integer)):
            return o.item()
        if isinstance(o, np.ndarray):
            return None
        if isinstance(o, float) and not math.isfinite(o):
            return None
        return o

    (RESULTS / f"{stem}.json").write_text(json.dumps(
        {"cases": clean(rows), "predictions": clean(prow), "total_wall_s": total_wall,
         "run_safety": RUN_SAFETY}, indent=1))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short runs (a smoke test)")
    ap.add_argument("--cases", default="", help="comma-separated case ids (default: all)")
    ap.add_argument("--scale", type=float, default=1.0, help="multiply every run's steps")
    ap.add_argument("--keep", default="", help="directory to save each case's raw series "
                    "(npz)")
    ap.add_argument("--reanalyse", default="", help="rebuild the rows of the cases saved "
                    "in this directory (--keep) without running them; other rows are kept")
    ap.add_argument("--predict-only", action="store_true",
                    help="only print the model predictions for the default scenes")
    ap.add_argument("--append", action="store_true",
                    help="keep the cases already in the results JSON (rerun the named ones)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    prow = predictions()
    print(prediction_table(prow), flush=True)
    stem = "slow_modes_quick" if args.quick else "slow_modes"
    rows: list = []
    prev_wall = 0.0
    if (args.append or args.reanalyse) and (RESULTS / f"{stem}.json").exists():
        old = json.loads((RESULTS / f"{stem}.json").read_text())
        rows = old["cases"]
        prev_wall = old.get("total_wall_s", 0.0)
    if args.predict_only:  # printed above; the results files are left as they are
        return
    if args.reanalyse:
        for case in CASES:
            f = pathlib.Path(args.reanalyse) / f"{case.id}.npz"
            if f.exists():
                row = reanalyse(case, f, args.quick, args.scale)
                old = [r for r in rows if r["id"] == case.id]
                if old and not math.isfinite(row["wall_s"]):
                    row["wall_s"] = old[0]["wall_s"]
                rows = [r for r in rows if r["id"] != case.id] + [row]
        rows.sort(key=lambda r: [c.id for c in CASES].index(r["id"]))
        write(rows, prow, prev_wall, args.quick)
        print(table(rows))
        return
    want = [c for c in args.cases.split(",") if c]
    todo = [c for c in CASES if not want or c.id in want]
    for case in todo:
        row = run_case(case, args.quick, args.scale, args.keep)
        rows = [r for r in rows if r["id"] != case.id] + [row]
        rows.sort(key=lambda r: [c.id for c in CASES].index(r["id"]))
        write(rows, prow, prev_wall + time.perf_counter() - t0, args.quick)
        print(f"\n{case.id}: {row['wall_s']:.0f} s", flush=True)
        print(table([row]), flush=True)
    print(f"total wall {prev_wall + time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
