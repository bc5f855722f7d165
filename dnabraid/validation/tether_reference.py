"""An independent reference for a tether with a wall and excluded volume.

The tether's energy is U = U_WLC + U_wall + U_wca: the discrete worm-like chain under the
end force (stretch, bend, pull), whose exact Boltzmann distribution
:func:`dnabraid.continuum.wlc.sample_discrete_wlc` draws from directly, plus the wall and
the WCA excluded volume. Draws x_k of the free chain weighted by
w_k = exp(-(U_wall + U_wca)(x_k) / kT) are therefore an exact importance sample of the full
model (Hammersley & Handscomb 1964; the same identity as exact reweighting): <A> =
sum w_k A(x_k) / sum w_k, with no dynamics, no Monte Carlo moves and no OpenMM involved.
The wall and WCA energies are those of the scene's own Forces, evaluated by their numba
twins (:class:`dnabraid.kernels.LocalEnergy`, tested against OpenMM to round-off).

The error comes from independent batches of draws (the ratio estimator's batch means),
and the weights' Kish effective sample size says how much of the sample carries the
answer (Kish 1965): the reference is trusted when it is a sizeable fraction of the draws.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["tether_reference"]


def tether_reference(scene, *, n_draws: int = 20000, batches: int = 20, seed: int = 12345
                     ) -> dict:
    """Mean extension (nm) of a ``tether`` scene with its wall and excluded volume, from
    weighted exact draws of the free discrete WLC.

    Parameters
    ----------
    scene : dnabraid.scenes.tether.Tether
        Its force, length, spacing, stiffnesses, wall and self-avoidance are used.
    n_draws : int
        Free-chain draws in all (split into ``batches`` independent batches).
    seed : int

    Returns
    -------
    dict
        ``extension_nm`` and ``extension_sem_nm`` (batch means of the ratio estimator),
        ``free_extension_nm`` (the unweighted mean: the chain without wall and excluded
        volume), ``kish_ess`` and ``kish_fraction`` of the weights, ``n_draws``.
    """
    from ..continuum.wlc import sample_discrete_wlc
    from ..kernels import LocalEnergy

    model = scene.build()
    energy = LocalEnergy(model)
    d = model.dna
    n = scene.n_beads - 1
    k = scene.stretch_modulus_pN / scene.bead_spacing_nm if scene.stretch == "bonds" else None
    rng = np.random.default_rng(seed)
    per = int(math.ceil(n_draws / batches))
    ext, logw = [], []
    pos = np.array(model.positions, float)
    chain = np.asarray(model.chains[0], int)
    for _ in range(batches):
        xs = sample_discrete_wlc(scene.force_pN, n, scene.bead_spacing_nm, d.kappa_kT, d.kT,
                                 stretch_k_pN_per_nm=k, n_samples=per, rng=rng)
        for x in xs:
            pos[chain] = x
            terms = energy.total_terms(pos)
            u = terms.get("wall", 0.0) + terms.get("wca", 0.0)
            logw.append(-u / d.kT)
            ext.append(float(x[-1, 2]))
    ext = np.asarray(ext)
    logw = np.asarray(logw)
    w = np.exp(logw - logw.max())
    est = []
    for b in range(batches):
        sl = slice(b * per, (b + 1) * per)
        if w[sl].sum() > 0:
            est.append(float(np.sum(w[sl] * ext[sl]) / np.sum(w[sl])))
    est = np.asarray(est)
    kish = float(w.sum() ** 2 / np.sum(w * w))
    return {"extension_nm": float(np.sum(w * ext) / np.sum(w)),
            "extension_sem_nm": float(np.std(est, ddof=1) / math.sqrt(len(est))),
            "free_extension_nm": float(ext.mean()), "kish_ess": kish,
            "kish_fraction": kish / ext.size, "n_draws": int(ext.size)}
