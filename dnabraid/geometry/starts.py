"""Starting conformations."""

from __future__ import annotations

import numpy as np


def random_wlc(n_beads: int, b_nm: float, kappa_kT: float, rng: np.random.Generator,
               first=(0.0, 0.0, 1.0)) -> np.ndarray:
    """A conformation drawn from the discrete worm-like chain's own equilibrium.

    Hinge angles are independent with density exp(x cos beta) sin beta, x = kappa/kT
    (sampled exactly: cos beta = 1 + ln(1 - U (1 - e^{-2x})) / x), azimuths uniform. The
    first bond points along ``first``. Starting here instead of from a straight rod spares
    the equilibration of the slow long-wavelength bending modes (tau ~ L^4).

    Returns
    -------
    ndarray (n_beads, 3), nm, first bead at the origin.
    """
    x = float(kappa_kT)
    t = np.asarray(first, float)
    t = t / np.linalg.norm(t)
    pos = np.zeros((n_beads, 3))
    for i in range(1, n_beads):
        if i > 1:
            u = rng.uniform()
            c = 1.0 + np.log1p(-u * (-np.expm1(-2.0 * x))) / x
            c = min(1.0, max(-1.0, c))
            s = np.sqrt(max(0.0, 1.0 - c * c))
            a = rng.uniform(0, 2 * np.pi)
            helper = np.array([1.0, 0, 0]) if abs(t[0]) < 0.9 else np.array([0, 1.0, 0])
            e1 = np.cross(t, helper)
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(t, e1)
            t = c * t + s * (np.cos(a) * e1 + np.sin(a) * e2)
            t /= np.linalg.norm(t)
        pos[i] = pos[i - 1] + b_nm * t
    return pos


def random_tether(n_beads: int, b_nm: float, kappa_kT: float, seed: int, *,
                  z_min: float | None = None, tries: int = 2000) -> np.ndarray:
    """A random WLC tether from the origin, upwards; with ``z_min`` all beads after the
    first stay above it (rejection; falls back to a straight rod)."""
    rng = np.random.default_rng(seed)
    for _ in range(tries):
        p = random_wlc(n_beads, b_nm, kappa_kT, rng)
        if z_min is None or np.all(p[1:, 2] > z_min):
            return p
    return np.c_[np.zeros(n_beads), np.zeros(n_beads), b_nm * np.arange(n_beads)]
