"""Calibration statistics of reported error bars against an exact answer.

A study reports a mean, its standard error (sem) and a 95 % interval (half-width) from R
replicas; K independent studies of a quantity whose exact value is known test whether
the intervals cover it as often as they claim and whether the t-scores
t = (mean - exact) / sem scatter like Student t(R - 1). Used by workflows/calibration.py
(the tether against the exact discrete worm-like chain).

* :func:`calib_stats`: bias, coverage (with its Clopper-Pearson interval), <t^2>, <z^2>
  and the between-study scatter over the reported sem^2 of one case;
* :func:`pooled`: the same pooled over cases, with a KS test of the z-scores and a
  chi^2 test of the biases;
* :func:`untruncated`: study means and errors recomputed from the replicas' raw series;
* reference bands: :func:`clopper_pearson`, :func:`t2_band`, :func:`z2_band`, and
  :func:`t_to_z` (Student-t scores to normal scores).

Numbers are in the units of the measured quantity (nm for an extension).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import stats

__all__ = [
    "calib_stats",
    "clopper_pearson",
    "pooled",
    "t2_band",
    "t_to_z",
    "untruncated",
    "z2_band",
]


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper-Pearson) binomial interval of a proportion ``k`` / ``n``.

    Parameters
    ----------
    k, n : int
        Successes (e.g. intervals that covered the exact value) and trials.
    level : float
        Confidence level.

    Returns
    -------
    (float, float)
        Lower and upper bound of the proportion (0 and 1 at the edges).
    """
    a = 1.0 - level
    lo = 0.0 if k == 0 else stats.beta.ppf(a / 2, k, n - k + 1)
    hi = 1.0 if k == n else stats.beta.ppf(1 - a / 2, k + 1, n - k)
    return float(lo), float(hi)


@functools.lru_cache(None)
def t2_band(K: int, dof: int, level: float = 0.95, draws: int = 200_000) -> tuple:
    """Monte-Carlo band of the mean of K squared Student-t(dof) draws.

    Its variance is infinite for dof <= 4, so no normal error applies. Deterministic
    (seeded by ``K`` and ``dof``) and cached.

    Returns
    -------
    (float, float)
        The ``(1 - level) / 2`` and ``(1 + level) / 2`` quantiles of mean(t^2).
    """
    rng = np.random.default_rng(12345 + K * 100 + dof)
    m = np.empty(draws)
    for i in range(0, draws, 20_000):
        m[i:i + 20_000] = np.mean(rng.standard_t(dof, size=(20_000, K)) ** 2, axis=1)
    a = (1 - level) / 2
    return float(np.quantile(m, a)), float(np.quantile(m, 1 - a))


def z2_band(K: int, level: float = 0.95) -> tuple:
    """Band of the mean of K squared standard-normal scores (chi^2_K / K quantiles)."""
    a = (1 - level) / 2
    return float(stats.chi2.ppf(a, K) / K), float(stats.chi2.ppf(1 - a, K) / K)


def t_to_z(t: np.ndarray, dof: int) -> np.ndarray:
    """Student-t scores mapped to standard-normal scores (probability integral
    transform): N(0, 1) exactly when the t-scores follow Student t(dof)."""
    return stats.norm.isf(stats.t.sf(t, dof))


def calib_stats(means, sems, halfw, exact, R) -> dict:
    """Calibration of K studies of one case against the exact value.

    Parameters
    ----------
    means, sems, halfw : array_like
        Per study: the reported mean, its standard error and the 95 % half-width.
    exact : float
        The exact value.
    R : int
        Replicas per study (the t-scores have R - 1 degrees of freedom).

    Returns
    -------
    dict
        ``K``; ``bias`` (mean of the means - exact) and ``bias_err``; ``covered``,
        ``coverage`` and ``coverage_ci`` (Clopper-Pearson); ``t2`` and ``z2`` (mean
        squared t- and z-scores); ``scatter_over_sem2`` (between-study variance over the
        mean reported sem^2); ``mean_sem``; the scores ``t`` and ``z`` (lists).
    """
    m, s, h = (np.asarray(x, float) for x in (means, sems, halfw))
    K = m.size
    t = (m - exact) / s
    z = t_to_z(t, R - 1)
    cov = int(np.sum(np.abs(m - exact) <= h))
    return {"K": K, "bias": float(m.mean() - exact),
            "bias_err": float(m.std(ddof=1) / math.sqrt(K)) if K > 1 else float("nan"),
            "covered": cov, "coverage": cov / K, "coverage_ci": clopper_pearson(cov, K),
            "t2": float(np.mean(t**2)), "z2": float(np.mean(z**2)),
            "scatter_over_sem2": float(m.var(ddof=1) / np.mean(s**2)) if K > 1 else float("nan"),
            "mean_sem": float(np.mean(s)), "t": t.tolist(), "z": z.tolist()}


def untruncated(studies, R) -> tuple:
    """Study means, sems and 95 % half-widths with every sample kept (no cut).

    Parameters
    ----------
    studies : list of dict
        Each with ``series``: the R replicas' raw sample series.
    R : int
        Replicas per study.

    Returns
    -------
    (list, list, list)
        Means of the replica means, their standard errors, and the Student-t 95 %
        half-widths; the arguments :func:`calib_stats` takes.
    """
    tq = stats.t.ppf(0.975, R - 1)
    m, s = [], []
    for st in studies:
        rm = np.array([np.mean(x) for x in st["series"]])
        m.append(rm.mean())
        s.append(rm.std(ddof=1) / math.sqrt(R))
    return m, s, [tq * x for x in s]


def pooled(rows, R) -> dict:
    """The calibration pooled over cases.

    Parameters
    ----------
    rows : list of dict
        One per case, each holding :func:`calib_stats` results under ``reported`` and
        ``no_cut``.
    R : int
        Replicas per study (unused; kept with the other functions' signature).

    Returns
    -------
    dict
        For ``reported`` and ``no_cut``: ``n`` studies, ``covered``, ``coverage``,
        ``coverage_ci``, ``z2`` with ``z2_band``, ``ks_p`` (Kolmogorov-Smirnov test of
        the z-scores against N(0, 1)), and ``bias_chi2``, ``bias_dof``, ``bias_chi2_p``
        (the cases' biases in units of their errors, which should scatter as N(0, 1)).
        Empty without rows.
    """
    if not rows:
        return {}
    out = {}
    for key in ("reported", "no_cut"):
        z = np.concatenate([r[key]["z"] for r in rows])
        cov = sum(r[key]["covered"] for r in rows)
        n = sum(r[key]["K"] for r in rows)
        # bias in units of its error, per case: should scatter as N(0, 1)
        b = np.array([r[key]["bias"] / r[key]["bias_err"] for r in rows])
        out[key] = {"n": n, "covered": cov, "coverage": cov / n,
                    "coverage_ci": clopper_pearson(cov, n), "z2": float(np.mean(z**2)),
                    "z2_band": z2_band(n), "ks_p": float(stats.kstest(z, "norm").pvalue),
                    "bias_chi2": float(np.sum(b**2)), "bias_dof": len(rows),
                    "bias_chi2_p": float(stats.chi2.sf(np.sum(b**2), len(rows)))}
    return out
