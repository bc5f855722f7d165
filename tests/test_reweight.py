"""Reweighting in a linear parameter (dnabraid.analysis.reweight) against exact answers.

For W ~ N(mu, s^2) sampled at a_0, the ensemble at a is N(mu - (a - a_0) s^2 / kT, s^2)
exactly, and Kish's ESS / N of the weights tends to exp(-((a - a_0) s / kT)^2). Tolerances
are 4 jackknife (or analytic) standard errors; seeds fixed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.analysis.reweight import (
    ReplicaReweighting,
    first_root,
    jackknife,
    weights_ess,
)

KT = 4.1


def _replicas(n_rep=8, n=20000, mu=0.5, s=2.0, seed=11):
    rng = np.random.default_rng(seed)
    reps = []
    for _ in range(n_rep):
        W = rng.normal(mu, s, n)
        c = (rng.uniform(size=n) < 0.3).astype(float)  # a "contact" indicator, independent
        reps.append({"W": W, "c": c, "eta": -0.1 * W})
    return reps


def test_reweighted_mean_of_a_gaussian_is_exact():
    mu, s = 0.5, 2.0
    rw = ReplicaReweighting(_replicas(mu=mu, s=s), a0=0.0, kT=KT)
    for a in (-2.0, -0.5, 1.0, 3.0):
        m, se = rw.mean(a, "W")
        exact = mu - a * s * s / KT
        assert abs(m - exact) < 4 * se, (a, m, exact, se)
        assert se < 0.05


def test_reweighted_ratio_and_its_root():
    """<eta c>/<c> with eta = -0.1 W and c independent of W: exact -0.1 (mu - a s^2/kT),
    zero at a* = mu kT / s^2."""
    mu, s = 0.5, 2.0
    rw = ReplicaReweighting(_replicas(mu=mu, s=s), a0=0.0, kT=KT)
    m, se = rw.mean(1.0, "eta*c", "c")
    assert abs(m - (-0.1 * (mu - s * s / KT))) < 4 * se
    a_star, se_star = rw.root(np.linspace(-2, 2, 41), "eta*c", "c")
    exact = mu * KT / s**2
    assert abs(a_star - exact) < 4 * se_star, (a_star, exact, se_star)
    assert se_star < 0.05


def test_weights_ess_matches_the_lognormal_limit():
    rng = np.random.default_rng(2)
    s = 2.0
    W = rng.normal(0.0, s, 400000)
    for da in (0.5, 1.0, 2.0):
        frac = weights_ess(W, da, KT) / W.size
        exact = math.exp(-((da * s / KT) ** 2))
        assert abs(frac - exact) < 0.03 * exact + 0.002, (da, frac, exact)
    assert weights_ess(W, 0.0, KT) == pytest.approx(W.size)


def test_jackknife_of_a_mean_is_the_standard_error():
    rng = np.random.default_rng(3)
    groups = [rng.normal(size=50) for _ in range(10)]
    means = np.array([g.mean() for g in groups])
    est, se = jackknife(lambda gs: np.mean([g.mean() for g in gs]), groups)
    assert est == pytest.approx(means.mean())
    assert se == pytest.approx(means.std(ddof=1) / math.sqrt(10), rel=1e-12)


def test_first_root():
    assert first_root([0, 1, 2], [-1.0, 1.0, 3.0]) == pytest.approx(0.5)
    assert math.isnan(first_root([0, 1], [1.0, 2.0]))
    with pytest.raises(ValueError):
        ReplicaReweighting([{"W": np.zeros(3)}], 0.0, KT)
