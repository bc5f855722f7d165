"""Exact reweighting in a parameter the energy is linear in, with replica jackknife errors.

When U(x; a) = U_0(x) + a W(x) (the chiral term: U_chiral = alpha W with W the contact
integral of tan(eta/2); van der Heijden's phi = alpha tan(eta/2)), samples of one ensemble
a_0 give every other a by the exponential reweighting identity (Zwanzig 1954):

    <A>_a = sum_k A_k w_k / sum_k w_k,   w_k = exp(-(a - a_0) W_k / kT).

It is exact for any a; its precision falls with the overlap of the two ensembles, which the
weights' effective sample size ESS = (sum w)^2 / sum w^2 measures (Kish 1965; for Gaussian W
of standard deviation s, ESS / N = exp(-((a - a_0) s / kT)^2)). Ratios of averages (a
contact-averaged angle <eta c> / <c>) and roots of a reweighted curve are smooth functions
of such means; their errors here come from the jackknife over independent replicas (each
replica an independent run from its own start: Efron 1982), which also sees the
autocorrelation within each replica.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["log_weights", "weights_ess", "reweighted_ratio", "jackknife", "first_root",
           "ReplicaReweighting"]


def log_weights(W, delta_a: float, kT: float) -> np.ndarray:
    """log w_k = -delta_a W_k / kT, shifted so that the largest is 0 (no overflow)."""
    lw = -float(delta_a) * np.asarray(W, float) / float(kT)
    return lw - np.max(lw)


def weights_ess(W, delta_a: float, kT: float) -> float:
    """Kish's effective sample size (sum w)^2 / sum w^2 of the reweighting weights."""
    w = np.exp(log_weights(W, delta_a, kT))
    return float(w.sum() ** 2 / np.sum(w * w))


def reweighted_ratio(num, den, W, delta_a: float, kT: float) -> float:
    """sum(num w) / sum(den w): <num>_a / <den>_a (den = 1 for a plain mean); NaN when the
    reweighted denominator vanishes."""
    w = np.exp(log_weights(W, delta_a, kT))
    d = float(np.sum(np.asarray(den, float) * w))
    return float(np.sum(np.asarray(num, float) * w) / d) if d != 0.0 else math.nan


def jackknife(estimate, groups: list) -> tuple[float, float]:
    """(estimate from all groups, jackknife standard error) of ``estimate(list_of_groups)``.

    The error is sqrt((G - 1) / G sum_g (theta_(g) - mean theta_(.))^2) over the G
    leave-one-group-out estimates (NaN ones make the error NaN).
    """
    G = len(groups)
    if G < 2:
        raise ValueError("the jackknife needs at least 2 groups")
    full = float(estimate(groups))
    loo = np.array([estimate(groups[:g] + groups[g + 1:]) for g in range(G)], float)
    se = float(math.sqrt((G - 1) / G * np.sum((loo - loo.mean()) ** 2)))
    return full, se


def first_root(x, y) -> float:
    """The first x where the piecewise-linear y(x) crosses zero (NaN when it does not)."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    for i in range(len(x) - 1):
        if not (np.isfinite(y[i]) and np.isfinite(y[i + 1])):
            continue
        if y[i] == 0.0:
            return float(x[i])
        if y[i] * y[i + 1] < 0.0:
            return float(x[i] - y[i] * (x[i + 1] - x[i]) / (y[i + 1] - y[i]))
    return float(x[-1]) if len(y) and y[-1] == 0.0 else math.nan


class ReplicaReweighting:
    """Frames of independent replicas at a_0, reweighted to other a.

    Parameters
    ----------
    replicas : list of dict
        Per replica, column -> 1-d array over its frames; must hold ``W``.
    a0 : float
        The parameter the frames were sampled at.
    kT : float
        In the units of a W.
    """

    def __init__(self, replicas: list, a0: float, kT: float):
        if len(replicas) < 2:
            raise ValueError("need at least 2 replicas (errors come from their scatter)")
        self.replicas = [{k: np.asarray(v, float) for k, v in r.items()} for r in replicas]
        self.a0 = float(a0)
        self.kT = float(kT)

    @staticmethod
    def _pool(groups, col):
        return np.concatenate([g[col] for g in groups])

    def ratio(self, a: float, num: str, den: str | None = None, groups=None) -> float:
        """<num>_a / <den>_a pooled over ``groups`` (default all replicas); ``num`` may be a
        product ``"x*y"`` of two columns."""
        groups = self.replicas if groups is None else groups

        def col(name):
            if "*" in name:
                p, q = name.split("*")
                return self._pool(groups, p) * self._pool(groups, q)
            return self._pool(groups, name)

        W = self._pool(groups, "W")
        d = col(den) if den else np.ones_like(W)
        return reweighted_ratio(col(num), d, W, a - self.a0, self.kT)

    def mean(self, a: float, num: str, den: str | None = None) -> tuple[float, float]:
        """(estimate, jackknife SE over replicas) of <num>_a / <den>_a."""
        return jackknife(lambda g: self.ratio(a, num, den, g), self.replicas)

    def ess(self, a: float) -> float:
        """Weights' effective sample size (frames) at a, all replicas pooled."""
        return weights_ess(self._pool(self.replicas, "W"), a - self.a0, self.kT)

    def root(self, grid, num: str, den: str | None = None) -> tuple[float, float]:
        """(a where <num>_a / <den>_a first crosses 0 on ``grid``, jackknife SE)."""
        grid = np.asarray(grid, float)

        def est(groups):
            return first_root(grid, [self.ratio(a, num, den, groups) for a in grid])

        return jackknife(est, self.replicas)
