"""Torque from extension by the Maxwell relation of the tweezer ensemble.

At constant force ``F`` and bead angle ``2 pi n`` the free energy ``G(n, F)`` has
``dG = -z dF + Gamma d(2 pi n)``, so its mixed second derivatives give

    dGamma/dF = -(1 / 2 pi) dz/dn

(the Maxwell relation used for magnetic tweezers by Mosconi, Allemand, Bensimon & Croquette,
PRL 102, 078301 (2009), Eq. 2). The extension is measured far more precisely than the trap
torque (whose trap libration has a standard deviation sqrt(K kT), ~290 pN nm for the braid),
so where a force sweep exists the torque at force ``F`` follows from the torque at one
reference force and the extensions between:

    Gamma(n, F) = Gamma(n, F_ref) - (1 / 2 pi) int_{F_ref}^{F} dz/dn(n, F') dF'

with ``dz/dn`` by second-order finite differences on the turn grid (``numpy.gradient``) and
the force integral by the trapezoid rule. Errors are propagated exactly through this linear
map from independent extension errors and the reference torques' errors.
"""

from __future__ import annotations

import numpy as np

from ..units import TWO_PI


def _operator(forces, turns, ref_index: int) -> np.ndarray:
    """The linear map A (n_F*n_n x n_F*n_n) with Gamma - Gamma_ref = A vec(z)."""
    nF, nn = len(forces), len(turns)
    eye = np.eye(nF * nn)
    A = np.empty((nF * nn, nF * nn))
    for k in range(nF * nn):
        z = eye[k].reshape(nF, nn)
        dzdn = np.gradient(z, turns, axis=1, edge_order=2) if nn > 2 else np.gradient(z, turns, axis=1)
        # cumulative trapezoid along F, zero at the reference force
        seg = 0.5 * (dzdn[1:] + dzdn[:-1]) * np.diff(forces)[:, None]
        cum = np.vstack([np.zeros((1, nn)), np.cumsum(seg, axis=0)])
        A[:, k] = (-(cum - cum[ref_index]) / TWO_PI).ravel()
    return A


def torque_from_extension(forces_pN, turns, extension_nm, torque_ref_pN_nm, *,
                          extension_sem_nm=None, torque_ref_sem_pN_nm=None,
                          ref_index: int = 0) -> dict:
    """Torque on the bead (pN nm) on a (force x turns) grid from its extensions.

    Parameters
    ----------
    forces_pN : (nF,) increasing forces (pN).
    turns : (nn,) increasing turn values (at least 2).
    extension_nm : (nF, nn) mean extensions (nm).
    torque_ref_pN_nm : (nn,) torques measured at ``forces_pN[ref_index]``.
    extension_sem_nm, torque_ref_sem_pN_nm : standard errors (independent), optional.

    Returns
    -------
    dict with ``torque_pN_nm`` (nF, nn) and, when errors are given, ``sem_pN_nm`` (nF, nn).
    """
    F = np.asarray(forces_pN, float)
    n = np.asarray(turns, float)
    z = np.asarray(extension_nm, float)
    g0 = np.asarray(torque_ref_pN_nm, float)
    if F.ndim != 1 or n.ndim != 1 or z.shape != (F.size, n.size):
        raise ValueError(f"extension_nm must have shape (len(forces), len(turns)) = "
                         f"({F.size}, {n.size}), got {z.shape}")
    for name, v in (("forces_pN", F), ("turns", n), ("extension_nm", z),
                    ("torque_ref_pN_nm", g0)):
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{name} must be finite")
    if n.size < 2 or np.any(np.diff(n) <= 0) or np.any(np.diff(F) <= 0):
        raise ValueError("forces and turns must be strictly increasing, with >= 2 turn values")
    if g0.shape != (n.size,):
        raise ValueError(f"torque_ref_pN_nm must have one value per turn ({n.size})")
    if not 0 <= ref_index < F.size:
        raise ValueError(f"ref_index {ref_index} outside the {F.size} forces")
    A = _operator(F, n, ref_index)
    torque = (A @ z.ravel()).reshape(F.size, n.size) + g0[None, :]
    out = {"forces_pN": F, "turns": n, "torque_pN_nm": torque, "ref_force_pN": F[ref_index]}
    if extension_sem_nm is not None:
        s = np.broadcast_to(np.asarray(extension_sem_nm, float), z.shape).ravel()
        if not np.all(np.isfinite(s)) or np.any(s < 0):
            raise ValueError("extension_sem_nm must be finite and >= 0")
        var = (A * A) @ (s * s)
        if torque_ref_sem_pN_nm is not None:
            sg = np.asarray(torque_ref_sem_pN_nm, float)
            if sg.shape != (n.size,) or not np.all(np.isfinite(sg)) or np.any(sg < 0):
                raise ValueError(f"torque_ref_sem_pN_nm must be {n.size} finite values >= 0")
            var = var + np.tile(sg**2, F.size)
        out["sem_pN_nm"] = np.sqrt(var).reshape(F.size, n.size)
    return out
