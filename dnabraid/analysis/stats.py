"""Statistics of correlated time series: means with honest error bars.

Two estimators of the standard error of the mean (SEM) of a stationary, correlated
series ``x_0 .. x_{n-1}``:

* :func:`integrated_autocorrelation_time` / ``mean_sem(method="sokal")``: the normalised
  autocorrelation function ``rho(t)`` is computed by FFT, and the integrated
  autocorrelation time

  .. math:: \\tau_{int}(M) = 1 + 2 \\sum_{t=1}^{M} \\rho(t)

  is summed up to Sokal's automatic window, the smallest ``M`` with ``M >= c tau_int(M)``
  (``c = 5``; A. D. Sokal, *Monte Carlo Methods in Statistical Mechanics: Foundations and
  New Algorithms*, Cargese lectures 1996, Eq. 3.19 and Sec. 3.3). Then
  ``sem = sqrt(var * tau_int / n)`` and ``n_eff = n / tau_int``. With this convention an
  AR(1) process with lag-one correlation ``rho`` has ``tau_int = (1 + rho) / (1 - rho)``;
  ``tau_int`` counts samples and equals 1 for uncorrelated data.
* :func:`blocking_sem` (``method="blocking"``): the Flyvbjerg-Petersen blocking
  transformation (J. Chem. Phys. 91, 461 (1989)), pairwise averaging until the estimate
  reaches its plateau; the plateau is chosen automatically with Jonsson's chi-squared test
  on the lag-one autocovariances of the blocked series (M. Jonsson, Phys. Rev. E 98,
  043304 (2018), Eq. 19-21, 99 % quantile).

Both give the asymptotic SEM for long series (n >> tau_int); for fewer than
:data:`MIN_SAMPLES` samples they fall back on the naive ``std / sqrt(n)`` and say so.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats as _sps

__all__ = [
    "MIN_SAMPLES",
    "bimodality",
    "autocorrelation",
    "blocking_sem",
    "integrated_autocorrelation_time",
    "mean_sem",
]

#: Below this many samples the autocorrelation is not estimated (naive SEM, flagged).
MIN_SAMPLES = 10


def as_series(x) -> np.ndarray:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 2 and arr.shape[1] == 1:  # a column vector is accepted
        arr = arr[:, 0]
    if arr.ndim != 1:
        raise ValueError(f"x must be a one-dimensional series; got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError("x is empty")
    if not np.all(np.isfinite(arr)):
        raise ValueError("x contains NaN or infinite values; remove or impute them first")
    return arr


def autocorrelation(x) -> np.ndarray:
    """Normalised autocorrelation function via FFT.

    Parameters
    ----------
    x : array_like, shape (n,)
        Time series (any unit), finite.

    Returns
    -------
    ndarray, shape (n,)
        ``rho(t) = C(t) / C(0)`` with ``C(t) = (1/n) sum_i (x_i - m)(x_{i+t} - m)``
        (biased estimator, as in Sokal), ``rho(0) = 1``. All zeros after ``rho(0)`` for a
        constant series.
    """
    arr = as_series(x)
    n = arr.size
    dx = arr - arr.mean()
    nfft = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(dx, nfft)
    acov = np.fft.irfft(f * np.conj(f), nfft)[:n] / n
    if acov[0] <= 0.0:
        out = np.zeros(n)
        out[0] = 1.0
        return out
    return acov / acov[0]


def integrated_autocorrelation_time(x, *, c: float = 5.0) -> tuple[float, int]:
    """Integrated autocorrelation time with Sokal's automatic window.

    Parameters
    ----------
    x : array_like, shape (n,)
        Time series, finite.
    c : float, optional
        Window constant; the window is the smallest ``M`` with ``M >= c * tau_int(M)``.

    Returns
    -------
    tau_int : float
        ``1 + 2 sum_{t=1}^{M} rho(t)`` in samples (>= 1 is not enforced; clipped below at
        a small positive number only to keep ``n_eff`` finite).
    window : int
        The window ``M`` used (``n - 1`` if no window satisfied the criterion).
    """
    rho = autocorrelation(x)
    n = rho.size
    if n < 2:
        return 1.0, 0
    taus = 1.0 + 2.0 * np.cumsum(rho[1:])  # taus[M-1] = tau_int(M)
    m = np.arange(1, n)
    ok = m >= c * taus
    window = int(m[np.argmax(ok)]) if np.any(ok) else n - 1
    tau = float(taus[window - 1])
    return max(tau, 1e-12), window


def blocking_sem(x) -> dict:
    """Standard error of the mean by Flyvbjerg-Petersen blocking with automatic plateau.

    The series is repeatedly halved by averaging neighbouring pairs (an odd last sample is
    dropped). At level ``k`` with ``n_k`` blocks, ``sem_k = sqrt(s_k^2 / (n_k - 1))`` with
    ``s_k^2`` the (biased) variance of the blocked series. Jonsson's statistic
    ``M_j = sum_{k>=j} n_k (gamma_k / s_k^2)^2`` (``gamma_k`` the lag-one autocovariance)
    is compared with the 99 % quantile of chi-squared with as many degrees of freedom as
    levels summed; the first level that passes is the plateau.

    Parameters
    ----------
    x : array_like, shape (n,)
        Time series, finite.

    Returns
    -------
    dict
        ``mean``; ``sem``; ``level`` (blocking level chosen, 0 = raw data);
        ``n_blocks`` at that level; ``sems`` (ndarray of the estimate at every level);
        ``converged`` (False if no level passed the test, i.e. the series is too short
        compared with its correlation time; then the last level with at least 2 blocks is
        used); ``naive`` (True for fewer than :data:`MIN_SAMPLES` samples).
    """
    arr = as_series(x)
    n = arr.size
    mean = float(arr.mean())
    if n < MIN_SAMPLES:
        sem = float(arr.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
        return {"mean": mean, "sem": sem, "level": 0, "n_blocks": n,
                "sems": np.array([sem]), "converged": False, "naive": True}
    sems, nks, stat = [], [], []
    y = arr.copy()
    while y.size >= 2:
        nk = y.size
        var = float(np.var(y))
        gamma = float(np.mean((y[:-1] - mean) * (y[1:] - mean))) * (nk - 1) / nk
        sems.append(math.sqrt(var / (nk - 1)))
        nks.append(nk)
        stat.append(nk * (gamma / var) ** 2 if var > 0.0 else 0.0)
        if nk % 2:
            y = y[:-1]
        y = 0.5 * (y[0::2] + y[1::2])
    sems_a = np.array(sems)
    if sems_a[0] == 0.0:  # constant series
        return {"mean": mean, "sem": 0.0, "level": 0, "n_blocks": n,
                "sems": sems_a, "converged": True, "naive": False}
    d = len(sems)
    m_stat = np.cumsum(np.array(stat)[::-1])[::-1]  # M_j = sum_{k >= j}
    q = _sps.chi2.ppf(0.99, df=np.arange(d, 0, -1))
    passed = np.nonzero(m_stat < q)[0]
    converged = passed.size > 0
    level = int(passed[0]) if converged else d - 1
    return {"mean": mean, "sem": float(sems_a[level]), "level": level,
            "n_blocks": int(nks[level]), "sems": sems_a, "converged": bool(converged),
            "naive": False}


def mean_sem(x, *, method: str = "sokal") -> dict:
    """Mean and standard error of the mean of a correlated series.

    Parameters
    ----------
    x : array_like, shape (n,)
        Time series (any unit), finite. NaN or inf raise ``ValueError``.
    method : {"sokal", "blocking"}
        ``"sokal"``: integrated autocorrelation time with Sokal's automatic window
        (``c = 5``); ``"blocking"``: :func:`blocking_sem`, with ``tau_int`` inferred as
        ``n sem^2 / var``.

    Returns
    -------
    dict
        ``mean`` (unit of x); ``sem`` (unit of x); ``tau_int`` (samples, 1 for
        uncorrelated data); ``n_eff = n / tau_int``; ``n``; ``naive`` (True when
        ``n < MIN_SAMPLES`` and the naive ``std(ddof=1)/sqrt(n)`` was used, with
        ``tau_int = 1``; ``sem`` is NaN for ``n == 1``); ``method``.
        A constant series gives ``sem = 0``, ``tau_int = 1``.
    """
    if method not in ("sokal", "blocking"):
        raise ValueError(f"method must be 'sokal' or 'blocking'; got {method!r}")
    arr = as_series(x)
    n = int(arr.size)
    mean = float(arr.mean())
    out = {"mean": mean, "n": n, "method": method, "naive": False}
    if n < MIN_SAMPLES:
        sem = float(arr.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan
        out.update(sem=sem, tau_int=1.0, n_eff=float(n), naive=True)
        return out
    var = float(np.var(arr))
    if var == 0.0 or np.ptp(arr) == 0.0:
        out.update(sem=0.0, tau_int=1.0, n_eff=float(n))
        return out
    if method == "sokal":
        tau, _ = integrated_autocorrelation_time(arr)
        sem = math.sqrt(var * tau / n)
    else:
        sem = blocking_sem(arr)["sem"]
        tau = n * sem * sem / var
    out.update(sem=float(sem), tau_int=float(tau), n_eff=float(n / tau))
    return out


def bimodality(x) -> dict:
    """Mean, standard deviation, skewness and Sarle's bimodality coefficient of samples.

    BC = (skew^2 + 1) / kurtosis (the plain, not excess, kurtosis; SAS Institute 1990;
    Pfister et al., Front. Psychol. 4, 700 (2013)): 1/3 for a Gaussian, 1 for two equal
    delta peaks, 5/9 for the uniform distribution; above 5/9 hints at two modes (a buckled and
    an unbuckled ring's writhe). Population moments, no small-sample correction.
    """
    x = np.asarray(x, float)
    if x.size < 3 or not np.all(np.isfinite(x)):
        raise ValueError("need >= 3 finite samples")
    d = x - x.mean()
    m2 = float(np.mean(d * d))
    if m2 == 0.0:
        return {"mean": float(x.mean()), "sd": 0.0, "skew": float("nan"), "bc": float("nan")}
    skew = float(np.mean(d**3) / m2**1.5)
    kurt = float(np.mean(d**4) / m2**2)
    return {"mean": float(x.mean()), "sd": math.sqrt(m2), "skew": skew,
            "bc": (skew * skew + 1.0) / kurt}
