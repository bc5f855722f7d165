"""Mirror-coupled replica pairs: handedness asymmetries with the noise they share removed.

A braid at turn value ``n`` and its mirror image (y -> -y: catenation, bead angle and trap
torque change sign, the extension does not) are sampled by two runs with one seed:
``mirror = "original"`` at turns ``[n, ...]`` and ``mirror = "image"`` at ``[-n, ...]``
(:class:`dnabraid.scenes.braid.Braid`). The image starts from the mirror of the original's
start and is driven by the mirror of its noise (a signed-noise Euler-Maruyama
``CustomIntegrator``, :func:`dnabraid.run.engine.euler_maruyama_integrator`). Without a chiral
term the energy is mirror-symmetric, so the image *is* the mirror of the original,
sample by sample: ``z(+n) - z(-n)`` and ``Gamma(+n) + Gamma(-n)`` vanish replica by replica
(to round-off), as they must at alpha = 0. With ``alpha != 0`` only the chiral force breaks
the symmetry; the pair's common noise cancels in the difference, and the asymmetry is
estimated from the per-replica differences (a paired estimator: the standard error of the
mean of R differences, Student t with R - 1 degrees of freedom).

The variance reduction against the plain (unpaired) estimator is ``sem_unpaired^2 /
sem_paired^2``, with ``sem_unpaired = sqrt(sem_+^2 + sem_-^2)`` from the two runs' own
across-replica errors.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

#: Observables even under the mirror (the asymmetry is a difference) and odd (a sum).
EVEN = ("extension_nm",)
ODD = ("torque_pN_nm", "catenation", "bead_angle_turns")


def _replica_means(point: dict, column: str) -> np.ndarray:
    entry = point.get(column) or {}
    m = entry.get("replica_means")
    if not m:
        raise ValueError(f"point turns={point.get('turns')} has no replica means for {column!r} "
                         "(a mirror pair needs at least 2 replicas)")
    return np.asarray(m, float)


def paired_asymmetry(original: dict, image: dict, column: str = "extension_nm",
                     confidence: float = 0.95) -> list[dict]:
    """Asymmetry of ``column`` per turn value from a mirror-coupled pair of runs.

    Parameters
    ----------
    original, image : dict
        The two runs' ``summary.json`` contents (``mirror = "original"`` at turns ``n``,
        ``mirror = "image"`` at ``-n``; same seed and replicas).
    column : str
        An observable: even ones (extension) give ``X(+n) - X(-n)``, odd ones (torque,
        catenation, bead angle) ``X(+n) + X(-n)``.

    Returns
    -------
    list of dict, one per turn value of ``original``: ``turns``, ``asymmetry`` (mean over
    replica pairs), ``sem`` (paired: std of the differences / sqrt R), ``ci_halfwidth``
    (Student t), ``sem_unpaired`` (the runs' own errors added in quadrature),
    ``variance_reduction`` (sem_unpaired^2 / sem^2; inf when the differences vanish), ``n_pairs``.
    """
    if column in EVEN:
        sign = -1.0
    elif column in ODD:
        sign = 1.0
    else:
        raise ValueError(f"unknown parity of {column!r}; even: {EVEN}, odd: {ODD}")
    for s, want in ((original, "original"), (image, "image")):
        got = (s.get("scene") or {}).get("mirror")
        if got is not None and got != want:
            raise ValueError(f"expected a run with mirror = {want!r}, got {got!r}")
    by_turns = {round(float(p["turns"]), 9): p for p in image["points"]}
    out = []
    for p in original["points"]:
        n = float(p["turns"])
        q = by_turns.get(round(-n, 9))
        if q is None:
            raise ValueError(f"the image run has no point at turns = {-n:g} "
                             f"(mirror of {n:g}); run it with the negated turn list")
        a, b = _replica_means(p, column), _replica_means(q, column)
        if a.size != b.size:
            raise ValueError(f"turns={n:g}: {a.size} original and {b.size} image replicas")
        d = a + sign * b
        R = d.size
        if R < 2:
            raise ValueError(f"turns={n:g}: a paired error needs at least 2 replica pairs, "
                             f"got {R}")
        sem = float(np.std(d, ddof=1) / math.sqrt(R))
        t = float(stats.t.ppf(0.5 + confidence / 2, R - 1))
        su = math.hypot(float(p[column]["sem"]), float(q[column]["sem"]))
        out.append({"turns": n, "column": column, "asymmetry": float(np.mean(d)), "sem": sem,
                    "ci_halfwidth": t * sem, "confidence": confidence,
                    "sem_unpaired": su,
                    "variance_reduction": (su / sem) ** 2 if sem > 0 else float("inf"),
                    "n_pairs": R})
    return out
