"""The linearised bead-spring model (dnabraid.analysis.slow_modes) against analytic limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.analysis import slow_modes as sm


def _string(n_bonds, length, tension, zeta_per_length, zeta_end):
    """A tensioned string (no bending) of n_bonds beads fixed at the surface; its rates."""
    m = sm.Lin1D()
    b = length / n_bonds
    idx, ext = sm.chain(m, n_bonds, b, tension, 0.0, zeta_per_length * b, zeta_end)
    return m, idx, ext


def test_single_bead_on_a_spring_relaxes_at_k_over_zeta():
    m = sm.Lin1D()
    i = m.particle(2.5)  # pN ns / nm
    m.term({i: 1.0, None: -1.0}, 4.0)  # a spring of 4 pN / nm to a fixed point
    lam, V = m.modes()
    assert lam == pytest.approx([4.0 / 2.5])
    assert V[0, 0] ** 2 * 2.5 == pytest.approx(1.0)  # V^T Z V = 1
    # sampled every dt: g = (1 + rho) / (1 - rho), rho = exp(-dt / t); tau -> t for dt -> 0
    t, dt = 2.5 / 4.0, 0.1
    rho = math.exp(-dt / t)
    assert sm.libration_tau(2.5, 4.0, dt) == pytest.approx(dt / 2 * (1 + rho) / (1 - rho))
    assert sm.libration_tau(2.5, 4.0, 1e-6) == pytest.approx(t, rel=1e-9)
    assert sm.e_time_spectrum(([1.0], [1 / t])) == pytest.approx(t)


def test_string_fixed_at_both_ends():
    """Slowest transverse mode of a string under tension f, both ends fixed: exactly
    lambda_1 = (f / b) / zeta 4 sin^2(pi / 2N) for N bonds, and zeta_l L^2 / (pi^2 f) in
    the string limit."""
    f, L, zl, N = 5.0, 100.0, 0.02, 200
    b = L / N
    m = sm.Lin1D()
    idx = [None] + [m.particle(zl * b) for _ in range(N - 1)] + [None]  # None: fixed
    for i in range(N):
        m.term({idx[i]: -1.0, idx[i + 1]: 1.0}, f / b)
    lam = m.modes()[0]
    exact = (f / b) / (zl * b) * 4 * np.sin(np.arange(1, 4) * math.pi / (2 * N)) ** 2
    assert lam[:3] == pytest.approx(exact, rel=1e-6)
    assert 1 / lam[0] == pytest.approx(zl * L**2 / (math.pi**2 * f), rel=1e-4)


@pytest.mark.parametrize("ratio", [0.01, 1.0, 30.0])
def test_string_with_a_bead_at_its_end(ratio):
    """A string fixed at the surface and ending at a bead of friction zeta_end: the slowest
    mode of the discrete chain tends to tau_1 = zl L^2 / (f q^2), q tan q = zl L / zeta_end."""
    f, L, zl, N = 2.0, 200.0, 0.01, 400
    zeta_end = ratio * zl * L
    m, _, _ = _string(N, L, f, zl, zeta_end)
    tau1 = 1 / m.modes()[0][0]
    assert tau1 == pytest.approx(sm.string_tau1(zl, L, f, zeta_end), rel=5e-3)


def test_string_tau1_limits():
    f, L, zl = 2.0, 200.0, 0.01
    # a frictionless end: q = pi / 2, the quarter wave
    assert sm.string_tau1(zl, L, f, 1e-9 * zl * L) == pytest.approx(
        4 * zl * L**2 / (math.pi**2 * f), rel=1e-6)
    # a heavy bead: tau_1 -> zeta_end L / f + zl L^2 / (3 f) (the string's own friction)
    zeta_end = 1e4 * zl * L
    assert sm.string_tau1(zl, L, f, zeta_end) == pytest.approx(
        zeta_end * L / f + zl * L**2 / (3 * f), rel=1e-6)


def test_extension_variance_of_a_string_mode():
    """Equipartition: the end of a one-bond string (tension f, bond b) has <u^2> = kT b / f
    (rate f / (b zeta_end)), so the extension's term u^2 / (2 b) averages kT / (2 f)."""
    m = sm.Lin1D()
    idx, ext = sm.chain(m, 1, 10.0, 4.0, 0.0, 1.0, 3.0)
    lam, V = m.modes()
    kT = 4.1
    var_u = kT * V[0, 0] ** 2 / lam[0]
    D = m.matrix(ext)
    assert lam[0] == pytest.approx(4.0 / 10.0 / 3.0)
    assert var_u * D[0, 0] == pytest.approx(kT / (2 * 4.0))


def test_estimators_on_an_exponential_series():
    """An AR(1) series of correlation time t: tau_of gives (dt / 2) coth(dt / 2t) within
    Sokal's error; the 1/e time is t."""
    rng = np.random.default_rng(7)
    dt, t, n = 1.0, 10.0, 200_000
    rho = math.exp(-dt / t)
    x = np.empty(n)
    x[0] = rng.normal()
    noise = rng.normal(size=n) * math.sqrt(1 - rho**2)
    for i in range(1, n):
        x[i] = rho * x[i - 1] + noise[i]
    r = sm.tau_of(x, dt, cut=False)
    expect = dt / 2 * (1 + rho) / (1 - rho)
    assert r["tau_ns"] == pytest.approx(expect, rel=4 * r["rel_err"])
    assert r["run_over_tau"] == pytest.approx(n * dt / r["tau_ns"])
    e, err = sm.e_time_err(x, dt)
    assert e == pytest.approx(t, rel=0.1) and err is not None and err > 0
    assert sm.tau_of(np.ones(100), dt) == {"tau_ns": None}
    assert sm.block_means(np.arange(7.0), 3).tolist() == [1.0, 4.0]


def test_linear_model_of_the_default_tether_meets_its_closed_forms():
    """For the long default tether (300 nm, 1 pN) the bead-spring model's slowest mode and
    bead x, y time are those of the string (bending and discreteness: a few %)."""
    from dnabraid.scenes import make_scene

    s = make_scene("tether")
    p = sm.linear_model(s, 10.0, 100.0)
    assert p["tau1_ns"] == pytest.approx(p["tau1_formula_ns"], rel=0.05)
    assert p["bead_xy"] == pytest.approx(p["bead_xy_formula_ns"], rel=0.05)
    assert p["extension"] == pytest.approx(p["extension_formula_ns"], rel=0.15)
    w, r = p["_spectra"]["bead_x"]
    assert sum(w) == pytest.approx(1.0) and min(r) > 0
