"""Known-answer tests for dnabraid.analysis.stats (AR(1) processes, fixed seeds)."""

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from dnabraid.analysis import stats

#: Relative tolerance on SEM / tau_int estimates for 2^16-sample AR(1) series.
TOL_SEM = 0.15


def ar1(rho, n, seed):
    """Stationary AR(1): x_t = rho x_{t-1} + e_t, e ~ N(0, 1); var = 1 / (1 - rho^2)."""
    rng = np.random.default_rng(seed)
    e = rng.normal(size=n)
    e[0] /= math.sqrt(1 - rho**2)  # start in the stationary distribution
    return lfilter([1.0], [1.0, -rho], e)


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_ar1_sem_matches_exact_asymptotic(rho):
    n = 2**16
    x = ar1(rho, n, seed=12345)
    tau_exact = (1 + rho) / (1 - rho)
    sem_exact = math.sqrt(tau_exact / (1 - rho**2) / n)
    sok = stats.mean_sem(x)
    blk = stats.mean_sem(x, method="blocking")
    assert set(sok) >= {"mean", "sem", "tau_int", "n_eff", "n"}
    assert sok["n"] == n and not sok["naive"]
    assert sok["sem"] == pytest.approx(sem_exact, rel=TOL_SEM)
    assert sok["tau_int"] == pytest.approx(tau_exact, rel=TOL_SEM)
    assert sok["n_eff"] == pytest.approx(n / sok["tau_int"])
    assert blk["sem"] == pytest.approx(sem_exact, rel=TOL_SEM)
    assert blk["sem"] == pytest.approx(sok["sem"], rel=TOL_SEM)  # the two methods agree
    assert stats.blocking_sem(x)["converged"]


def test_autocorrelation_of_ar1():
    x = ar1(0.8, 2**16, seed=1)
    rho = stats.autocorrelation(x)
    assert rho[0] == 1.0
    np.testing.assert_allclose(rho[1:4], 0.8 ** np.arange(1, 4), atol=0.02)


def test_constant_series_has_zero_sem():
    for method in ("sokal", "blocking"):
        r = stats.mean_sem(np.full(100, 3.25), method=method)
        assert r["mean"] == 3.25 and r["sem"] == 0.0 and r["tau_int"] == 1.0
    assert stats.blocking_sem(np.full(64, -1.0))["sem"] == 0.0


def test_short_series_falls_back_to_naive_and_flags_it():
    x = [1.0, 2.0, 4.0, 3.0]
    r = stats.mean_sem(x)
    assert r["naive"] and r["n"] == 4 and r["tau_int"] == 1.0
    assert r["sem"] == pytest.approx(np.std(x, ddof=1) / 2.0)
    assert stats.blocking_sem(x)["naive"]
    assert math.isnan(stats.mean_sem([5.0])["sem"])


def test_invalid_input_raises():
    with pytest.raises(ValueError, match="NaN"):
        stats.mean_sem([1.0, np.nan] * 20)
    with pytest.raises(ValueError):
        stats.mean_sem([])
    with pytest.raises(ValueError):
        stats.mean_sem(np.ones((5, 5)))
    with pytest.raises(ValueError):
        stats.mean_sem(np.arange(20.0), method="jackknife")


def test_bimodality_coefficient_of_known_distributions():
    """Sarle's BC: 1/3 for a Gaussian, 5/9 for the uniform, 1 for two equal delta peaks
    (exact population values; 4e5 samples, tolerance 1 %)."""
    from dnabraid.analysis.stats import bimodality

    rng = np.random.default_rng(7)
    assert bimodality(rng.normal(size=400000))["bc"] == pytest.approx(1 / 3, rel=0.01)
    assert bimodality(rng.uniform(size=400000))["bc"] == pytest.approx(5 / 9, rel=0.01)
    assert bimodality(np.r_[np.zeros(100), np.ones(100)])["bc"] == pytest.approx(1.0)
    with pytest.raises(ValueError):
        bimodality([1.0, 2.0])
