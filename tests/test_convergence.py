"""Tests for dnabraid.analysis.convergence: equilibration detection, split R-hat / bulk ESS
against ArviZ and pymbar, and calibration of replica error bars (fixed seeds throughout).

Synthetic data are Gaussian AR(1) processes x_t = rho x_{t-1} + e_t, e ~ N(0, 1), started
in the stationary distribution: variance 1 / (1 - rho^2), statistical inefficiency
g = (1 + rho) / (1 - rho), and the exact variance of the mean of n samples
var / n * (1 + 2 sum_{k<n} (1 - k/n) rho^k).
"""

import logging
import math

import numpy as np
import pytest
from scipy import stats as sps
from scipy.signal import lfilter

from dnabraid.analysis import convergence as cv
from dnabraid.analysis import stats

#: Nominal two-sided confidence of the replica intervals.
CONF = 0.95
#: Accepted coverage band for 400 studies: binomial sd sqrt(.95 * .05 / 400) = 0.011, so
#: +-0.03 is +-2.75 sd.
COVERAGE_BAND = (0.92, 0.98)
#: p-value below which a Kolmogorov-Smirnov comparison with Student t fails.
KS_ALPHA = 0.01
#: Relative agreement with ArviZ: same algorithm, only FFT padding / summation order differ.
ARVIZ_RTOL = 1e-9
#: pymbar comparison: start within 2 transient decay times (5 % of T) of pymbar's, g within
#: 20 %, and pymbar's own N_eff criterion at our t0 within 5 % of its maximum.
T0_TOL = 1000
G_RTOL = 0.20
NEFF_EFFICIENCY = 0.95


def ar1(rho, shape, rng):
    """Stationary AR(1) along the last axis, unit innovations."""
    e = rng.normal(size=shape)
    e[..., 0] /= math.sqrt(1.0 - rho**2)
    return lfilter([1.0], [1.0, -rho], e, axis=-1)


def var_mean_ar1(rho, n):
    """Exact variance of the mean of n consecutive stationary AR(1) samples."""
    k = np.arange(1, n)
    return (1.0 / (1.0 - rho**2)) / n * (1.0 + 2.0 * np.sum((1.0 - k / n) * rho**k))


# --------------------------------------------------------------------------------------
# detect_equilibration / mser
# --------------------------------------------------------------------------------------


def test_suffix_inefficiency_is_exactly_the_stats_estimator():
    rng = np.random.default_rng(1)
    T = 5000
    x = ar1(0.9, T, rng) + 8.0 * np.exp(-np.arange(T) / 300.0)
    t0, g, n_eff = cv.detect_equilibration(x)
    tau, _ = stats.integrated_autocorrelation_time(x[t0:])
    assert g == pytest.approx(max(tau, 1.0), rel=1e-10)
    assert n_eff == pytest.approx((T - t0) / g, rel=1e-12)
    assert 0 < t0 < T // 2


@pytest.mark.parametrize("direct", [True, False])
def test_chodera_grid_equals_brute_force(direct, monkeypatch):
    """One level (n_candidates > T/2): the vectorised search is the exhaustive one, with
    the lagged products formed directly or by the segmented FFT."""
    if not direct:
        monkeypatch.setattr(cv, "_MAX_DIRECT", 0)
    rng = np.random.default_rng(2)
    T = 600
    x = ar1(0.8, T, rng) + 6.0 * np.exp(-np.arange(T) / 40.0)
    t0, g, n_eff = cv.detect_equilibration(x, n_candidates=1000)
    brute = []
    for t in range(0, T // 2 + 1):
        gt = max(stats.integrated_autocorrelation_time(x[t:])[0], 1.0)
        brute.append(((T - t) / gt, t, gt))
    nb, tb, gb = max(brute)
    assert t0 == tb
    assert g == pytest.approx(gb, rel=1e-10)
    assert n_eff == pytest.approx(nb, rel=1e-10)


@pytest.mark.parametrize("seed", [0, 3, 5])
def test_detect_equilibration_vs_pymbar(seed):
    ts = pytest.importorskip("pymbar.timeseries")
    logging.getLogger("pymbar").setLevel(logging.ERROR)
    rho, T, tau_eq = 0.8, 20000, 500.0
    rng = np.random.default_rng(seed)
    x = ar1(rho, T, rng) + 10.0 * np.exp(-np.arange(T) / tau_eq)
    # pymbar's exact (fast=False) inefficiency; its fast mode overestimates g by ~20 %
    t_p, g_p, neff_p = ts.detect_equilibration(x, fast=False, nskip=200)
    t0, g, n_eff = cv.detect_equilibration(x)
    assert abs(t0 - t_p) <= T0_TOL
    assert g == pytest.approx(float(g_p), rel=G_RTOL)
    assert g == pytest.approx((1 + rho) / (1 - rho), rel=G_RTOL)  # theory: 9
    g_p_at_ours = ts.statistical_inefficiency(x[t0:], fast=False)
    assert (T - t0 + 1) / g_p_at_ours >= NEFF_EFFICIENCY * float(neff_p)


def test_detect_equilibration_on_long_series():
    """A long AR(1) series (rho = 0.9, g = 19) with a slow transient (its speed is a
    benchmark, workflows/, not a test)."""
    rng = np.random.default_rng(4)
    T = 100_000
    x = ar1(0.9, T, rng) + 8.0 * np.exp(-np.arange(T) / 5000.0)
    t0, g, _ = cv.detect_equilibration(x)
    # the bias the remaining transient leaves in the kept mean,
    # 8 * 5000 e^{-t0/5000} / (T - t0), must be below the mean's SEM sqrt(var g / n)
    n = T - t0
    bias = 8.0 * 5000.0 * math.exp(-t0 / 5000.0) / n
    assert bias < 2.0 * math.sqrt(19.0 / (1 - 0.81) / n)
    assert g == pytest.approx(19.0, rel=G_RTOL)


def test_detect_equilibration_degenerate():
    assert cv.detect_equilibration(np.full(100, 3.0)) == (0, 1.0, 1.0)  # pymbar's convention
    assert cv.detect_equilibration(np.arange(5.0)) == (0, 1.0, 5.0)
    with pytest.raises(ValueError):
        cv.detect_equilibration(np.arange(50.0), nskip=0)
    with pytest.raises(ValueError):
        cv.detect_equilibration([1.0, np.nan] * 20)
    # nskip sets the resolution of t0
    rng = np.random.default_rng(6)
    x = ar1(0.5, 3000, rng) + 5.0 * np.exp(-np.arange(3000) / 100.0)
    assert cv.detect_equilibration(x, nskip=7)[0] % 7 == 0


@pytest.mark.parametrize("seed", range(5))
def test_mser_finds_step_transient(seed):
    """A 5-sigma offset on the first L samples: MSER-5 cuts at L (theory: any earlier cut
    keeps a batch biased by 5 sigma); and finds (almost) nothing in a stationary series."""
    rng = np.random.default_rng(seed)
    L, T, rho = 500, 5000, 0.5
    x = ar1(rho, T, rng)
    y = x.copy()
    y[:L] += 5.0 / math.sqrt(1 - rho**2)
    assert L <= cv.mser(y) <= L + 100
    assert cv.mser(x) <= 0.05 * T
    assert cv.mser(x[:12]) == 0  # fewer than 4 batches: nothing to decide


# --------------------------------------------------------------------------------------
# split R-hat and bulk ESS vs ArviZ
# --------------------------------------------------------------------------------------


def _rhat_cases():
    rng = np.random.default_rng(7)
    return {
        "iid": rng.normal(size=(4, 1000)),
        "ar1_0.9": ar1(0.9, (4, 1001), rng),  # odd length: middle draw dropped
        "shifted_means": rng.normal(size=(4, 500)) + np.array([0.0, 0.0, 0.0, 0.5])[:, None],
        "ar1_shifted": ar1(0.9, (3, 800), rng) + np.array([0.0, 2.0, -1.0])[:, None],
        "ties": rng.integers(0, 5, size=(3, 300)).astype(float),
        "antithetic": ar1(-0.5, (4, 200), rng),
        "minimal": rng.normal(size=(2, 4)),
    }


@pytest.mark.parametrize("case", list(_rhat_cases()))
def test_rhat_ess_match_arviz(case):
    az = pytest.importorskip("arviz")
    x = _rhat_cases()[case]
    assert cv.split_rhat(x) == pytest.approx(float(az.rhat(x, method="rank")), rel=ARVIZ_RTOL)
    assert cv.ess(x) == pytest.approx(float(az.ess(x, method="bulk")), rel=ARVIZ_RTOL)


def test_batched_autocovariance_is_the_stats_one():
    rng = np.random.default_rng(10)
    x = ar1(0.7, (3, 257), rng)
    ref = np.stack([stats.autocorrelation(r) * r.var() for r in x])
    np.testing.assert_allclose(cv._autocov_rows(x), ref, rtol=0, atol=1e-12 * ref[:, :1].max())


def test_rhat_ess_known_values():
    """Theory: R-hat ~ 1 and ESS ~ R T for i.i.d. draws; ESS ~ R T / g for AR(1)."""
    rng = np.random.default_rng(8)
    x = rng.normal(size=(4, 2000))
    assert abs(cv.split_rhat(x) - 1.0) < 0.005
    assert cv.ess(x) == pytest.approx(8000, rel=0.1)
    y = ar1(0.9, (4, 20000), rng)
    assert cv.ess(y) == pytest.approx(80000 / 19.0, rel=0.15)
    # one chain displaced by 3 (1.3 sd): classic R-hat^2 - 1 -> var(split-chain means) / W
    # = (3^2 * 2 * 6 / 8 / 7) (1 - 0.81) = 0.366 for 8 half-chains, 2 of them displaced
    z = y + np.array([0.0, 0.0, 0.0, 3.0])[:, None]
    assert cv.split_rhat(z) == pytest.approx(math.sqrt(1 + 9 * 12 / 56 * 0.19), rel=0.03)


def test_rhat_ess_degenerate_input():
    with pytest.raises(ValueError, match="at least"):
        cv.split_rhat(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="at least"):
        cv.ess(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="NaN"):
        cv.split_rhat([[0.0, 1.0, np.nan, 2.0, 3.0]] * 2)
    with pytest.raises(ValueError, match="shape"):
        cv.ess(np.zeros((2, 3, 4)))
    const = np.ones((4, 100))
    assert math.isnan(cv.split_rhat(const))
    assert cv.ess(const) == 400.0  # as ArviZ: the mean is exact
    stuck = np.repeat(np.arange(4.0)[:, None], 100, axis=1)
    assert cv.split_rhat(stuck) == math.inf
    # a single chain is split in halves
    assert cv.split_rhat(np.random.default_rng(9).normal(size=400)) < 1.05


# --------------------------------------------------------------------------------------
# replica_summary: calibration on AR(1) replicas
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("R, equilibration, seed", [(4, "chodera", 11), (8, "mser", 12)])
def test_replica_summary_calibration(R, equilibration, seed):
    """400 studies of R stationary AR(1) replicas (rho = 0.8, g = 9, 500 samples = 55 g).

    Theory: replica means are i.i.d. normal with mean 0, so mean / sem is Student t with
    R - 1 dof (variance (R - 1) / (R - 3)) and the t interval covers 0 with probability
    0.95; for converged, positively correlated chains of N draws split R-hat obeys
    R-hat^2 = (N - 1) / N + m / ESS with m = 2 R split chains of N = n / 2 draws, to leading
    order (Vats & Knudson, Stat. Sci. 36, 518 (2021)).
    """
    rho, T, n_studies = 0.8, 500, 400
    rng = np.random.default_rng(seed)
    res = [cv.replica_summary(ar1(rho, (R, T), rng), confidence=CONF,
                              equilibration=equilibration) for _ in range(n_studies)]
    means = np.array([r["mean"] for r in res])
    sems = np.array([r["sem"] for r in res])
    hw = np.array([r["ci_halfwidth"] for r in res])
    cov = cv.coverage(means, hw, 0.0)
    assert COVERAGE_BAND[0] <= cov <= COVERAGE_BAND[1], cov
    tscore = means / sems
    assert sps.kstest(tscore, sps.t(R - 1).cdf).pvalue > KS_ALPHA
    if R > 5:  # the sample variance of t_3 has infinite variance; t_7's is finite
        nu = R - 1
        var_t = nu / (nu - 2)
        kurt = 3 + 6 / (nu - 4)
        sd = math.sqrt((kurt - 1) * var_t**2 / n_studies)
        assert abs(tscore.var() - var_t) < 3 * sd
    # sem^2 is unbiased for the variance of the grand mean (sd of the ratio ~ 0.1 here)
    assert np.mean(sems**2) / np.mean(means**2) == pytest.approx(1.0, abs=0.3)
    # the discarded transient costs little: variance of the mean vs exact no-discard value
    assert np.mean(means**2) / (var_mean_ar1(rho, T) / R) < 1.5
    # Vats-Knudson relation between R-hat and ESS (leading order; 15 % named tolerance)
    rh = np.array([r["rhat"] for r in res])
    es = np.array([r["ess"] for r in res])
    n_half = np.array([min(r["n_samples"]) // 2 for r in res])
    assert np.mean((rh**2 - (n_half - 1) / n_half) * es / (2 * R)) == pytest.approx(1, abs=0.15)
    # the verdict is exactly the two thresholds here (stationary: no equilibration flag)
    verdict = (rh <= cv.RHAT_MAX) & (es >= cv.MIN_ESS)
    assert np.array_equal(verdict, [r["converged"] for r in res])


def test_slow_mode_seen_across_replicas_not_within():
    """Each replica sits at its own offset ~ N(0, 1) (a slow mode no replica samples) plus
    fast AR(1) noise (rho = 0.5, g = 3). The within-replica SEM sees only the noise;
    the across-replica SEM sees the offsets; R-hat flags the disagreement."""
    R, T, rho, s_slow = 4, 2000, 0.5, 1.0
    rng = np.random.default_rng(21)
    x = ar1(rho, (R, T), rng) + s_slow * rng.normal(size=(R, 1))
    out = cv.replica_summary(x)
    sem_fast = math.sqrt(var_mean_ar1(rho, T) / R)  # theory: 0.022
    assert out["sem_within"] == pytest.approx(sem_fast, rel=0.25)
    assert out["sem"] > 5 * out["sem_within"]
    assert out["rhat"] > 1.1
    assert not out["converged"]
    assert "R-hat" in out["reason"]

    # calibration over 400 studies of 500 samples: the t interval covers 0 at the nominal
    # rate; an interval from the within-replica SEM covers with 2 Phi(1.96 s_w / s_tot) - 1
    n_studies, T = 400, 500
    covered_t, covered_w = [], []
    for _ in range(n_studies):
        x = ar1(rho, (R, T), rng) + s_slow * rng.normal(size=(R, 1))
        o = cv.replica_summary(x, equilibration="mser")
        covered_t.append(abs(o["mean"]) <= o["ci_halfwidth"])
        covered_w.append(abs(o["mean"]) <= 1.96 * o["sem_within"])
    s_w = math.sqrt(var_mean_ar1(rho, T))
    p_w = 2 * sps.norm.cdf(1.96 * s_w / math.sqrt(s_slow**2 + s_w**2)) - 1  # 0.14
    assert COVERAGE_BAND[0] <= np.mean(covered_t) <= COVERAGE_BAND[1]
    assert np.mean(covered_w) == pytest.approx(p_w, abs=4 * math.sqrt(p_w / n_studies))


# --------------------------------------------------------------------------------------
# replica_summary: verdicts, bookkeeping, errors
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("equilibration", ["chodera", "mser"])
def test_replica_summary_flags_slow_equilibration(equilibration):
    rng = np.random.default_rng(31)
    T = 4000
    x = [ar1(0.5, T, rng) for _ in range(4)]
    x[2] = x[2] + 20.0 * np.clip(1.0 - np.arange(T) / (0.8 * T), 0.0, None)  # ramp: 80 %
    out = cv.replica_summary(x, equilibration=equilibration)
    assert not out["converged"]
    assert "replica 2" in out["reason"]
    assert "equilibration" in out["reason"]
    assert out["equilibration_samples"][2] > 0.4 * T


def test_replica_summary_transient_removed_and_converged():
    """Long, well-mixed replicas with a strong initial transient: the transient is cut,
    the interval covers the truth and the strict default verdict passes."""
    rng = np.random.default_rng(41)
    R, T, rho = 4, 20000, 0.5
    x = ar1(rho, (R, T), rng) + 10.0 * np.exp(-np.arange(T) / 100.0)
    out = cv.replica_summary(list(x))
    assert all(100 < t0 < 2000 for t0 in out["equilibration_samples"])
    assert abs(out["mean"]) <= out["ci_halfwidth"]
    assert out["converged"], out["reason"]
    assert out["reason"].startswith("ok")
    assert out["rhat"] < cv.RHAT_MAX and out["ess"] > cv.MIN_ESS
    raw = cv.replica_summary(list(x), equilibration=None)
    assert raw["mean"] > out["mean"] + 3 * out["sem"]  # the transient biases the raw mean


def test_replica_summary_bookkeeping():
    rng = np.random.default_rng(51)
    series = [ar1(0.5, n, rng) + 1.0 for n in (900, 1200, 1500)]
    out = cv.replica_summary(series, equilibration=100, confidence=0.9)
    assert out["n_replicas"] == 3
    assert out["equilibration_samples"] == [100, 100, 100]
    assert out["n_samples"] == [800, 1100, 1400]
    m = np.array([s[100:].mean() for s in series])
    assert out["mean"] == pytest.approx(m.mean())
    assert out["sem"] == pytest.approx(m.std(ddof=1) / math.sqrt(3))
    assert out["ci_halfwidth"] == pytest.approx(sps.t.ppf(0.95, 2) * out["sem"])
    sw = [stats.mean_sem(s[100:])["sem"] for s in series]
    assert out["sem_within"] == pytest.approx(math.sqrt(sum(v * v for v in sw)) / 3)
    block = np.stack([s[-800:] for s in series])
    assert out["rhat"] == pytest.approx(cv.split_rhat(block))
    assert out["ess"] == pytest.approx(cv.ess(block))
    # the thresholds are arguments; the reason names the failed ones
    strict = cv.replica_summary(series, equilibration=None, min_ess=1e9, rhat_max=0.5)
    assert not strict["converged"]
    assert "R-hat" in strict["reason"] and "ESS" in strict["reason"]
    relaxed = cv.replica_summary(series, equilibration=None, min_ess=cv.MIN_ESS_RELAXED,
                                 rhat_max=cv.RHAT_MAX_RELAXED)
    assert relaxed["converged"], relaxed["reason"]


def test_replica_summary_constant_and_errors():
    out = cv.replica_summary([np.full(50, 2.0), np.full(80, 2.0)])
    assert out["converged"] and out["sem"] == 0.0 and out["mean"] == 2.0
    with pytest.raises(ValueError, match="2 replicas"):
        cv.replica_summary([np.arange(100.0)])
    with pytest.raises(ValueError, match="equilibration"):
        cv.replica_summary([np.arange(100.0)] * 2, equilibration="bogus")
    with pytest.raises(ValueError, match="no samples"):
        cv.replica_summary([np.arange(100.0)] * 2, equilibration=100)
    with pytest.raises(ValueError, match="confidence"):
        cv.replica_summary([np.arange(100.0)] * 2, confidence=1.5)
    short = cv.replica_summary([np.arange(3.0), np.arange(3.0) + 1], equilibration=None)
    assert math.isnan(short["rhat"]) and not short["converged"]


# --------------------------------------------------------------------------------------
# reduced_chi2 / coverage
# --------------------------------------------------------------------------------------


def test_reduced_chi2_and_coverage_exact():
    means, sems = [1.0, 2.0, 3.0], [1.0, 1.0, 2.0]
    # weighted mean (1 + 2 + 3/4) / 2.25 = 5/3; chi2 = 4/9 + 1/9 + (4/3)^2 / 4 = 1
    assert cv.reduced_chi2(means, sems) == pytest.approx(1.0 / 2)
    assert cv.reduced_chi2(means, sems, truth=2.0) == pytest.approx((1 + 0 + 0.25) / 3)
    assert cv.coverage(means, [0.5, 0.5, 1.0], 2.0) == pytest.approx(2 / 3)
    with pytest.raises(ValueError):
        cv.reduced_chi2([1.0, 2.0], [1.0, 0.0])
    with pytest.raises(ValueError):
        cv.reduced_chi2([1.0], [1.0])
    with pytest.raises(ValueError):
        cv.coverage([1.0], [-1.0], 0.0)


def test_reduced_chi2_honest_errors():
    """chi2 / dof of honest Gaussian errors is 1 with sd sqrt(2 / dof)."""
    rng = np.random.default_rng(61)
    n = 2000
    sems = rng.uniform(0.5, 2.0, size=n)
    means = 3.0 + sems * rng.normal(size=n)
    tol = 3 * math.sqrt(2 / n)
    assert cv.reduced_chi2(means, sems) == pytest.approx(1.0, abs=tol)
    assert cv.reduced_chi2(means, sems, truth=3.0) == pytest.approx(1.0, abs=tol)
    assert cv.reduced_chi2(means, sems / 2, truth=3.0) == pytest.approx(4.0, abs=4 * tol)
    assert cv.coverage(means, 1.96 * sems, 3.0) == pytest.approx(0.95, abs=0.015)
