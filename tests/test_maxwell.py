"""Torque from extension by the Maxwell relation dGamma/dF = -(1/2 pi) dz/dn.

Checked against the unbraided tweezer pair, whose z(n) and Gamma(n, F) are exact in closed
form (two straight inextensible rods with free hinges: z = sqrt(L^2 - d^2 sin^2(pi n)),
Gamma = F d^2 sin(2 pi n) / (4 z); dnabraid.continuum.tweezer, free branch), and the error
propagation against a Monte Carlo of the same linear map.
"""

import numpy as np
import pytest

from dnabraid.analysis.maxwell import torque_from_extension

L, D = 200.0, 40.0


def _free(n, F):
    z = np.sqrt(L**2 - D**2 * np.sin(np.pi * n) ** 2)
    return z, F * D**2 * np.sin(2 * np.pi * n) / (4 * z)


def test_free_pair_torque_follows_from_extension():
    F = np.array([0.5, 1.0, 2.0, 4.0])
    n = np.linspace(-0.4, 0.4, 65)
    z, g = _free(n[None, :], F[:, None])
    z = np.broadcast_to(z, g.shape)
    out = torque_from_extension(F, n, z, g[0])
    # the finite-difference error of dz/dn at h = 0.0125 (second order: |z'''| h^2 / 6
    # inside, ~|z'''| h^2 / 3 at the one-sided edges, |z'''| <= 2 pi^3 d^2 / L ~ 500 nm) is
    # < 0.026 nm per turn, times (F - F_ref) / 2 pi <= 3.5 / 2 pi: < 0.015 pN nm
    np.testing.assert_allclose(out["torque_pN_nm"], g, atol=0.02)
    assert np.max(np.abs(g)) > 5.0  # a test with torques to get right


def test_reference_force_in_the_middle():
    F = np.array([0.5, 1.0, 2.0, 4.0])
    n = np.linspace(-0.4, 0.4, 65)
    z, g = _free(n[None, :], F[:, None])
    z = np.broadcast_to(z, g.shape)
    out = torque_from_extension(F, n, z, g[2], ref_index=2)
    np.testing.assert_allclose(out["torque_pN_nm"], g, atol=0.02)


def test_force_integral_when_extension_depends_on_force():
    """A free energy whose extension depends on F, so that the force quadrature matters:
    G(n, F) = -F z0(n) - c sqrt(F) h(n) gives z = -dG/dF = z0 + c h / (2 sqrt F) and
    Gamma = (1/2 pi) dG/dn = -(F z0' + c sqrt(F) h') / (2 pi); the Maxwell relation holds by
    construction. Tolerance: trapezoid error (b - a) dF^2 max|f''| / 12 <= 0.003 pN nm plus
    the second-order difference error in n (h_n^2 |z^(3)| / 6 x 3 pN / 2 pi <= 0.002)."""
    c = 20.0
    F = np.linspace(1.0, 4.0, 31)
    n = np.linspace(-2.0, 2.0, 81)
    z = (100.0 - 5.0 * n[None, :] ** 2) + c * np.sin(n[None, :]) / (2 * np.sqrt(F[:, None]))
    g = -(F[:, None] * (-10.0 * n[None, :]) + c * np.sqrt(F[:, None]) * np.cos(n[None, :])) \
        / (2 * np.pi)
    out = torque_from_extension(F, n, z, g[0])
    np.testing.assert_allclose(out["torque_pN_nm"], g, atol=0.01)
    assert np.max(np.abs(g[-1] - g[0])) > 1.0  # torques that move with F


def test_error_propagation_matches_monte_carlo():
    from dnabraid.analysis.maxwell import _operator

    rng = np.random.default_rng(3)
    F = np.array([1.0, 2.0, 3.0])
    n = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    z = 150.0 - 3.0 * n[None, :] ** 2 + 0 * F[:, None]
    sz, sg = 0.5, 8.0
    out = torque_from_extension(F, n, z, np.zeros(5), extension_sem_nm=sz,
                                torque_ref_sem_pN_nm=np.full(5, sg))
    # the function is linear in (z, Gamma_ref): push 20000 draws through its operator
    A = _operator(F, n, 0)
    dz = sz * rng.standard_normal((20000, z.size))
    dg = sg * rng.standard_normal((20000, n.size))
    draws = dz @ A.T + np.tile(dg, F.size)
    # 20000 draws: the sample std is within 3 x 0.5 % (1/sqrt(2 x 20000)) of the truth
    np.testing.assert_allclose(draws.std(axis=0), out["sem_pN_nm"].ravel(), rtol=0.02)
    # and the function is that operator
    z1 = z + rng.standard_normal(z.shape)
    got = torque_from_extension(F, n, z1, np.zeros(5))["torque_pN_nm"].ravel()
    np.testing.assert_allclose(got, A @ z1.ravel(), atol=1e-9)


def test_bad_grids_are_refused():
    with pytest.raises(ValueError, match="shape"):
        torque_from_extension([1.0, 2.0], [0.0, 1.0], np.zeros((3, 2)), [0.0, 0.0])
    with pytest.raises(ValueError, match="increasing"):
        torque_from_extension([2.0, 1.0], [0.0, 1.0], np.zeros((2, 2)), [0.0, 0.0])
    with pytest.raises(ValueError, match="one value per turn"):
        torque_from_extension([1.0, 2.0], [0.0, 1.0], np.zeros((2, 2)), [0.0])
    with pytest.raises(ValueError, match="finite"):
        torque_from_extension([1.0, np.nan], [0.0, 1.0], np.zeros((2, 2)), [0.0, 0.0])
    with pytest.raises(ValueError, match="finite"):
        torque_from_extension([1.0, 2.0], [0.0, 1.0], np.full((2, 2), np.inf), [0.0, 0.0])
    with pytest.raises(ValueError, match=">= 0"):
        torque_from_extension([1.0, 2.0], [0.0, 1.0], np.zeros((2, 2)), [0.0, 0.0],
                              extension_sem_nm=-1.0)
    with pytest.raises(ValueError, match="torque_ref_sem"):
        torque_from_extension([1.0, 2.0], [0.0, 1.0], np.zeros((2, 2)), [0.0, 0.0],
                              extension_sem_nm=0.1, torque_ref_sem_pN_nm=[1.0])
