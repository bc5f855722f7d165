"""Tweezer braid z(n), Gamma(n): symmetry, exact limits, torque = dG/d(2 pi n), chirality."""

from __future__ import annotations

import argparse
import math

import pytest

from dnabraid.continuum import ply, tweezer

#: Tolerances (named, fixed).
TOL_EXACT_REL = 1e-9  # closed-form branches
TOL_PLY_LIMIT_REL = 1e-6  # tethers in contact vs the ply BVP
TOL_FD_TORQUE_REL = 1e-4  # finite-difference torque
TOL_PERTURB_REL = 1e-3  # first order in alpha
FD_STEP_TURNS = 1e-4

L, F, DELTA = 1000.0, 2.0, 5.0


@pytest.mark.parametrize("d", [5.0, 20.0, 50.0])
@pytest.mark.parametrize("n", [0.2, 0.7, 3.0, 15.0])
def test_alpha_zero_is_mirror_symmetric(n, d):
    rp = tweezer.solve_tweezer(n, F, L, d, DELTA)
    rm = tweezer.solve_tweezer(-n, F, L, d, DELTA)
    assert rp.success and rm.success
    assert rp["extension_nm"] == rm["extension_nm"]
    assert rp["torque_pN_nm"] == -rm["torque_pN_nm"]
    assert rp["torque_pN_nm"] > 0 and rp["theta_rad"] >= 0 and rp["eta_rad"] <= 0
    asym = tweezer.handedness_asymmetry(n, F, L, d, DELTA)
    assert asym["delta_z_nm"] == 0.0


def test_free_branch_is_exact():
    d, n = 50.0, 0.2  # below contact, n_c = arccos(Delta/d)/pi = 0.468
    res = tweezer.solve_tweezer(n, F, L, d, DELTA)
    assert res.success and res["branch"] == "free"
    z = math.sqrt(L * L - d * d * math.sin(math.pi * n) ** 2)
    assert res["extension_nm"] == pytest.approx(z, rel=TOL_EXACT_REL)
    assert res["torque_pN_nm"] == pytest.approx(F * d * d * math.sin(2 * math.pi * n) / (4 * z),
                                                rel=TOL_EXACT_REL)


@pytest.mark.parametrize("d, n, alpha", [(50.0, 0.2, 0.0), (20.0, 3.0, 0.0), (50.0, 8.0, 0.0),
                                         (20.0, 3.0, 0.05), (20.0, -3.0, 0.05),
                                         (5.0, 4.0, 0.3)])
def test_torque_is_derivative_of_free_energy(d, n, alpha):
    res = tweezer.solve_tweezer(n, F, L, d, DELTA, alpha_pN=alpha)
    assert res.success, res.message

    def g(m):
        return tweezer.solve_tweezer(m, F, L, d, DELTA, alpha_pN=alpha)["free_energy_pN_nm"]

    h = FD_STEP_TURNS
    fd = (g(n + h) - g(n - h)) / (2 * h * 2 * math.pi)
    assert res["torque_pN_nm"] == pytest.approx(fd, rel=TOL_FD_TORQUE_REL)


@pytest.mark.parametrize("n, alpha", [(5.0, 0.0), (-8.0, 0.0), (8.0, 0.5), (8.0, -0.5)])
def test_tethers_in_contact_is_ply_with_free_ends(n, alpha):
    tw = tweezer.solve_tweezer(n, F, L, DELTA, DELTA, alpha_pN=alpha)
    bvp = ply.solve_ply_bvp(L, F, DELTA, ply_link=n, bc="free", alpha_pN=alpha)
    assert tw.success and bvp.success
    assert tw["extension_nm"] == pytest.approx(bvp["extension_nm"], rel=TOL_PLY_LIMIT_REL)
    assert tw["torque_pN_nm"] == pytest.approx(bvp["torque_pN_nm"], rel=TOL_PLY_LIMIT_REL)


def test_chiral_energy_first_order_and_mirror():
    """dG/dalpha at alpha = 0 is -sigma L_p tan|theta| (Hellmann-Feynman, slide 32)."""
    d, n, a = 20.0, 4.0, 1e-3
    base = tweezer.solve_tweezer(n, F, L, d, DELTA)
    expected = -base["ply_length_nm"] * math.tan(base["theta_rad"])
    gp = tweezer.solve_tweezer(n, F, L, d, DELTA, alpha_pN=a)["free_energy_pN_nm"]
    gm = tweezer.solve_tweezer(n, F, L, d, DELTA, alpha_pN=-a)["free_energy_pN_nm"]
    assert (gp - gm) / (2 * a) == pytest.approx(expected, rel=TOL_PERTURB_REL)
    # alpha > 0 favours the right-handed braid (positive n), slides 32 and 35
    asym = tweezer.handedness_asymmetry(n, F, L, d, DELTA, alpha_pN=0.2)
    assert asym["delta_G_pN_nm"] < 0
    # mirror: (n, alpha) -> (-n, -alpha) leaves z unchanged, so Delta z is odd in alpha
    asym_m = tweezer.handedness_asymmetry(n, F, L, d, DELTA, alpha_pN=-0.2)
    assert asym["delta_z_nm"] == pytest.approx(-asym_m["delta_z_nm"], rel=1e-9, abs=1e-9)
    assert asym["delta_z_nm"] != 0.0


@pytest.mark.parametrize("kwargs, status, says", [
    ({"turns": 44.9}, 3, "lock-up"), ({"turns": 200.0}, 3, "lock-up"),  # too many turns
    ({"alpha_pN": 100.0}, 3, "lock-up"), ({"alpha_pN": 1e4}, 3, "lock-up"),  # chiral drive
    ({"force_pN": 1e-8}, 4, "flat"),  # tension too small for floating point
    ({"force_pN": 1e-4}, 0, "converged"), ({"force_pN": 1e6}, 0, "converged"),
    ({"turns": 44.0}, 0, "converged"), ({"turns": -44.0, "alpha_pN": 100.0}, 0, "converged"),
])
def test_stability_returns_data(kwargs, status, says):
    """Extreme inputs give a determined outcome: status 3 beyond lock-up (45 deg), 4 when
    the tails lie flat, else a converged braid below lock-up."""
    base = {"turns": 5.0, "force_pN": F, "length_nm": L, "tether_separation_nm": 20.0,
            "delta_nm": DELTA}
    base.update(kwargs)
    res = tweezer.solve_tweezer(**base)
    assert res.status == status and res.success == (status == 0), res.message
    assert says in res.message
    if res.success:
        assert 0.0 < res["extension_nm"] <= L
        assert abs(res["theta_rad"]) < ply.LOCKUP_ANGLE_RAD
        assert math.isfinite(res["torque_pN_nm"])


def test_lockup_and_too_many_turns_are_status_3():
    assert tweezer.solve_tweezer(60.0, F, L, 20.0, DELTA).status == 3
    res = tweezer.solve_tweezer(5.0, F, L, 20.0, DELTA, alpha_pN=100.0)
    assert not res.success and res.status == 3 and "lock-up" in res.message


@pytest.mark.parametrize("kwargs", [{"force_pN": -1.0}, {"force_pN": 0.0}, {"delta_nm": 0.0},
                                    {"tether_separation_nm": 3.0}, {"turns": math.nan},
                                    {"length_nm": 10.0}])
def test_invalid_input_raises(kwargs):
    base = {"turns": 2.0, "force_pN": F, "length_nm": L, "tether_separation_nm": 20.0,
            "delta_nm": DELTA}
    base.update(kwargs)
    with pytest.raises(ValueError):
        tweezer.solve_tweezer(**base)


def test_curve_continuation_matches_cold():
    turns = [0.3, 0.6, 1.0, 2.0, 4.0]
    curve = tweezer.tweezer_curve(turns, F, L, 50.0, DELTA, alpha_pN=0.05)
    for n, res in zip(turns, curve):
        cold = tweezer.solve_tweezer(n, F, L, 50.0, DELTA, alpha_pN=0.05)
        assert res.success
        assert res["extension_nm"] == pytest.approx(cold["extension_nm"], rel=1e-9)
    z = [r["extension_nm"] for r in curve]
    assert z == sorted(z, reverse=True)  # extension falls with turns


def test_convergence_table():
    rows = tweezer.convergence_table()
    assert all(r["success"] for r in rows)
    exact = [r for r in rows if r["problem"] == "tweezer_d_eq_delta_vs_exact"]
    ref = [r for r in rows if r["problem"] == "tweezer_d50_vs_reference"]
    assert max(r["error"] for r in exact) < 1e-9
    assert ref[-1]["error"] < 1e-5 < ref[0]["error"]


def test_cli_roundtrip():
    parser = argparse.ArgumentParser()
    tweezer.cli_add_arguments(parser)
    out = tweezer.cli_run(parser.parse_args(["--turns", "1", "3", "--alpha-pN", "0.1",
                                             "--asymmetry"]))
    assert out["success"] and len(out["rows"]) == 2
    assert out["rows"][1]["delta_z_nm"] != 0.0
