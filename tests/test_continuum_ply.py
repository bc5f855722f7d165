"""Two-ply (seed slides 15-19): fixed points, lock-up, and the theta(s) problem with ends."""

from __future__ import annotations

import argparse
import math

import pytest

from dnabraid.continuum import ply
from dnabraid.continuum._result import ContinuumResult

#: Tolerances (named, fixed).
TOL_EXACT = 1e-12  # closed-form identities
TOL_ROOT = 1e-10  # root finder on theta, rad
TOL_BVP_THETA = 1e-6  # BVP interior against the fixed point, rad
TOL_BVP_REL = 1e-6  # BVP against exact uniform solutions (relative)
TOL_FD_TORQUE = 1e-4  # finite-difference torque (relative)

B = ply.DEFAULT_BENDING_PN_NM2
DELTA = 5.0


def test_lockup_angle_and_densest_packing_slide18():
    assert ply.LOCKUP_ANGLE_DEG == 45.0
    assert math.degrees(ply.LOCKUP_ANGLE_RAD) == pytest.approx(45.0, abs=TOL_EXACT)
    # p / r = 2 pi at lock-up (slide 18)
    assert ply.pitch_over_radius(ply.LOCKUP_ANGLE_RAD) == pytest.approx(2 * math.pi,
                                                                         rel=TOL_EXACT)
    assert ply.LOCKUP_PITCH_OVER_RADIUS == pytest.approx(6.283185307179586, rel=TOL_EXACT)
    # densest packing: volume fraction grows with theta up to lock-up, 1/sqrt(2) there
    fr = [ply.packing_fraction(math.radians(a)) for a in (10, 20, 30, 40, 45)]
    assert fr == sorted(fr)
    assert fr[-1] == pytest.approx(1 / math.sqrt(2), rel=TOL_EXACT)


def test_dna_pitch_over_radius_slide18():
    # DNA data on slide 18: r = 5.92 A, p = 35.7 A -> p/r = 6.03
    assert round(35.7 / 5.92, 2) == 6.03
    theta = ply.helix_angle_from_pitch(35.7, 5.92)
    assert round(ply.pitch_over_radius(theta), 2) == 6.03
    assert theta > ply.LOCKUP_ANGLE_RAD  # p/r < 2 pi: just past the two-ply lock-up


@pytest.mark.parametrize("deg, below", [(30.0, True), (44.5, True), (45.5, False), (60.0, False)])
def test_lockup_is_loss_of_closest_approach(deg, below):
    """Pitchfork at 45 deg (slide 18): beyond it the strands come closer than Delta."""
    dmin = ply.interstrand_distance_min(math.radians(deg), DELTA)
    if below:
        assert dmin == pytest.approx(DELTA, rel=1e-12)
    else:
        assert dmin < DELTA * (1 - 1e-4)


def test_free_ply_twist_moment_slide17_and_divergence():
    theta = math.radians(30.0)
    c_tau, v, t = ply.free_ply_twist_moment(theta, DELTA, B)
    # it is the fixed point of slide 17 with F = M = 0
    resid = ply.ply_potential_derivative(theta, 0.0, 0.0, DELTA, B, 0.0, c_tau)
    assert abs(resid) < 1e-12 * abs(c_tau)
    assert v == pytest.approx(c_tau / DELTA, rel=TOL_EXACT)
    assert t == pytest.approx(v * math.tan(theta), rel=TOL_EXACT)
    # all -> infinity at lock-up, like 1 / (45 deg - theta)
    eps = 1e-6
    c1 = ply.free_ply_twist_moment(ply.LOCKUP_ANGLE_RAD - eps, DELTA, B)[0]
    c2 = ply.free_ply_twist_moment(ply.LOCKUP_ANGLE_RAD - eps / 10, DELTA, B)[0]
    assert abs(c1) > 1e6
    assert c2 / c1 == pytest.approx(10.0, rel=1e-4)


@pytest.mark.parametrize("alpha", [0.0, 0.5, -0.5])
@pytest.mark.parametrize("theta", [-0.6, -0.2, 0.1, 0.5, 0.78])
def test_uniform_ply_inverts_fixed_point_torque(theta, alpha):
    F = 2.0
    M = float(ply.fixed_point_torque(theta, F, DELTA, B, alpha))
    res = ply.solve_uniform_ply(F, M, DELTA, bending_pN_nm2=B, alpha_pN=alpha,
                                initial=ContinuumResult(True, 0, "", {"theta_rad": theta}))
    assert res.success, res.message
    assert res["theta_rad"] == pytest.approx(theta, abs=TOL_ROOT)
    assert res["eta_rad"] == pytest.approx(-2 * theta, abs=2 * TOL_ROOT)


def test_contact_force_equals_kirchhoff_helix():
    """p = kappa (n_t + B tau^2) for a helix with zero twist moment (independent formula)."""
    F, theta = 3.0, 0.4
    r = DELTA / 2
    s, c = math.sin(theta), math.cos(theta)
    kappa, tau = s * s / r, s * c / r
    n_t = (F / 2 + B * kappa * tau * s) / c  # axial force balance of one strand
    expected = kappa * (n_t + B * tau * tau)
    assert ply.uniform_ply_contact_force(theta, F, DELTA, B) == pytest.approx(expected,
                                                                              rel=TOL_EXACT)


def test_uniform_ply_past_lockup_is_data():
    res = ply.solve_uniform_ply(2.0, 1e5, DELTA)
    assert not res.success and res.status == 3 and "lock-up" in res.message
    res = ply.solve_uniform_ply(2.0, -1e5, DELTA)
    assert not res.success and res.status == 3


def test_bvp_interior_equals_fixed_point():
    """Clamped ply (theta = 0 at the ends): the long interior is the uniform ply."""
    for alpha in (0.0, 1.0):
        theta_star = 0.5
        M = float(ply.fixed_point_torque(theta_star, 2.0, DELTA, B, alpha))
        res = ply.solve_ply_bvp(1000.0, 2.0, DELTA, torque_pN_nm=M, alpha_pN=alpha)
        assert res.success, res.message
        assert res["theta_mid_rad"] == pytest.approx(theta_star, abs=TOL_BVP_THETA)
        assert res["hamiltonian_spread_pN"] < 1e-6  # slide 15 first integral


def test_bvp_free_ends_prescribed_link_is_uniform():
    L, F, link = 400.0, 2.0, 10.0
    res = ply.solve_ply_bvp(L, F, DELTA, ply_link=link, bc="free")
    assert res.success, res.message
    theta = math.asin(2 * math.pi * link * DELTA / 2 / L)
    assert res["extension_nm"] == pytest.approx(L * math.cos(theta), rel=TOL_BVP_REL)
    assert res["torque_pN_nm"] == pytest.approx(float(ply.fixed_point_torque(theta, F, DELTA)),
                                                rel=TOL_BVP_REL)
    assert res["ply_link"] == pytest.approx(link, rel=TOL_BVP_REL)


def test_bvp_torque_is_derivative_of_energy():
    """M = d(E + F D)/dR at fixed F: Lagrange multiplier of the ply link (slide 16)."""
    L, F, link, h = 300.0, 2.0, 6.0, 1e-3
    kw = {"tol": 1e-8, "alpha_pN": 0.3}
    res = ply.solve_ply_bvp(L, F, DELTA, ply_link=link, **kw)

    def g(k):
        r = ply.solve_ply_bvp(L, F, DELTA, ply_link=k, initial=res, **kw)
        assert r.success
        return r["energy_pN_nm"] + F * r["end_shortening_nm"]

    fd = (g(link + h) - g(link - h)) / (2 * h * 2 * math.pi)
    assert res["torque_pN_nm"] == pytest.approx(fd, rel=TOL_FD_TORQUE)


def test_bvp_failures_are_data():
    res = ply.solve_ply_bvp(100.0, 2.0, DELTA, ply_link=10.0)  # needs theta > 45 deg
    assert not res.success and res.status == 3
    res = ply.solve_ply_bvp(500.0, 2.0, DELTA, torque_pN_nm=1e4, max_nodes=2000)
    assert not res.success and res.status == 3 and "lock-up" in res.message


@pytest.mark.parametrize("kwargs", [{"force_pN": -1.0}, {"delta_nm": 0.0},
                                    {"length_nm": -5.0}, {"bc": "glued"},
                                    {"ply_link": 1.0, "torque_pN_nm": 1.0}])
def test_invalid_input_raises(kwargs):
    base = {"length_nm": 100.0, "force_pN": 1.0, "delta_nm": DELTA, "ply_link": 1.0}
    base.update(kwargs)
    with pytest.raises(ValueError):
        ply.solve_ply_bvp(**base)


def test_continuation_matches_cold_solves():
    links = [2.0, 4.0, 6.0]
    path = ply.continuation(ply.solve_ply_bvp, "ply_link", links, length_nm=300.0,
                            force_pN=2.0, delta_nm=DELTA)
    assert [r.success for r in path] == [True] * 3
    cold = ply.solve_ply_bvp(300.0, 2.0, DELTA, ply_link=6.0)
    assert path[-1]["torque_pN_nm"] == pytest.approx(cold["torque_pN_nm"], rel=TOL_BVP_REL)
    assert path[-1]["continuation_parameter"] == 6.0


def test_convergence_table_error_decreases():
    rows = ply.convergence_table()
    bvp = [r for r in rows if r["problem"] == "ply_bvp_clamped"]
    assert all(r["success"] for r in rows)
    assert bvp[-1]["error"] < 1e-8 < bvp[0]["error"]
    assert bvp[-1]["mesh_nodes"] > bvp[0]["mesh_nodes"]


def test_cli_roundtrip():
    parser = argparse.ArgumentParser()
    ply.cli_add_arguments(parser)
    out = ply.cli_run(parser.parse_args(["--force-pN", "2", "--torque-pN-nm", "20"]))
    assert out["success"] and out["problem"] == "uniform_ply"
    out = ply.cli_run(parser.parse_args(["--length-nm", "300", "--ply-link", "4", "--bc",
                                         "free"]))
    assert out["success"] and out["ply_link"] == pytest.approx(4.0)
