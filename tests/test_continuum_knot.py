"""Knot braid difference problem (Audoly et al. 2007, Audoly et al. PRL 2007, Eqs. 1, 5-9)."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

from dnabraid.continuum import knot_braid

# Tolerances: a single solve at the default spacing dw = 0.005 carries an O(dw) error
# (smooth trend + node-phase oscillation, see knot_braid.solve_knot_averaged): measured spread
# of w_c over grid phases +-5e-4, trend -3e-4 (w_c), -2e-4 (sigma).  The converged values
# (Richardson of nested meshes dw = 0.005/0.0025 | of phase means at 0.01/0.005) are
# w_c = 3.5056|3.5059, contact 0.3497|0.3483, gap 0.0214|0.0215 at 1.8223|1.8228,
# isolated contact 2.6813|2.6814, sigma 0.4925|0.4923.


@pytest.fixture(scope="module")
def trefoil():
    return knot_braid.solve_knot(1)


@pytest.fixture(scope="module")
def trefoil_coarse():
    return knot_braid.solve_knot(1, n_grid=500)  # dw ~ 0.01, W default


def test_trefoil_converges(trefoil):
    assert trefoil.success, trefoil.message
    assert trefoil.status == 0
    assert trefoil.residual < 1e-2  # KKT: free gradient per dw (round-off floor ~1e-4)
    assert trefoil.mesh_size > 900
    sol = trefoil.solution
    # parities: u even (u'(0) = 0 discretely: u_1 = u_0 on contact), v odd (v(0) = 0)
    assert sol["v"][0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(sol["rho"] >= 1.0 - 1e-9)  # Eq. 5
    # 1.5 turns: psi passed pi (the crossing w_c) and tends to 3 pi / 2 as W -> infinity
    # (u is linear and v ~ -w^2/2 in the tail, so at W = 5 psi is still ~4.04)
    assert math.pi < sol["psi"][-1] < 1.5 * math.pi


def test_trefoil_crossing(trefoil):
    # Audoly et al. 2007: w_c = 3.506 (Eq. 7); here 3.5057 converged, 3.506 +- 0.0006 at dw = 0.005
    assert trefoil["w_c"] == pytest.approx(3.506, abs=1e-3)


def test_trefoil_contact_region(trefoil):
    # seed: continuous contact |w| < 0.348.  Ours: 0.348-0.350 converged (two estimates),
    # 0.346-0.350 at the default mesh depending on node phase.
    assert trefoil["contact_half_width"] == pytest.approx(0.348, abs=3e-3)


def test_trefoil_gap(trefoil):
    # seed: largest gap 0.021 at w = +-1.823; converged 0.0214 at 1.8223 (0.0216 at dw=0.005)
    assert trefoil["max_gap"] == pytest.approx(0.021, abs=1e-3)
    assert trefoil["max_gap_at"] == pytest.approx(1.823, abs=1.5e-3)


def test_trefoil_isolated_contact(trefoil):
    # seed: isolated contact at +-2.681; converged 2.6813
    assert trefoil["isolated_contact_at"] == pytest.approx(2.681, abs=1e-3)
    assert len(trefoil["isolated_contacts"]) == 1


def test_trefoil_sigma(trefoil):
    # seed: sigma = 0.492 (P = sigma EI R^-3/2 h^-1/2); converged 0.4925
    assert trefoil["sigma"] == pytest.approx(0.492, abs=1e-3)
    # sigma = int f dw / (2 sqrt 2): the force budget splits into the central density,
    # the point forces at its ends and the isolated contacts
    v = trefoil.values
    assert v["contact_force_integral"] / (2 * math.sqrt(2)) == pytest.approx(v["sigma"])
    assert v["edge_force"] + v["isolated_contact_force"] < v["contact_force_integral"]


def test_trefoil_mesh_trend(trefoil, trefoil_coarse):
    # first-order convergence from above for w_c (trend ~ +0.06 dw), from below for sigma
    assert trefoil_coarse.success
    assert abs(trefoil_coarse["w_c"] - trefoil["w_c"]) < 2e-3
    assert abs(trefoil_coarse["sigma"] - trefoil["sigma"]) < 1e-3


def test_independent_of_W():
    # same spacing 0.01 and node positions, different domain: identical solution
    a = knot_braid.solve_knot(1, n_grid=450, half_width_W=4.5)
    b = knot_braid.solve_knot(1, n_grid=600, half_width_W=6.0)
    assert a.success and b.success
    for key in ("w_c", "sigma", "contact_half_width", "max_gap", "isolated_contact_at"):
        assert a[key] == pytest.approx(b[key], abs=1e-6), key
    # the energies differ only by the end work v'(W), a constant shift for the fixed tail
    np.testing.assert_allclose(a.solution["rho"][:400], b.solution["rho"][:400], atol=1e-7)


def test_continuation_refines_mesh():
    coarse = knot_braid.solve_knot(1, n_grid=225, half_width_W=4.5)
    fine = knot_braid.solve_knot(1, n_grid=450, half_width_W=4.5, initial=coarse)
    direct = knot_braid.solve_knot(1, n_grid=450, half_width_W=4.5)
    assert fine.success
    assert fine["w_c"] == pytest.approx(direct["w_c"], abs=1e-6)
    assert fine["sigma"] == pytest.approx(direct["sigma"], abs=1e-6)


def test_cinquefoil_crossing():
    # Audoly et al. 2007: 7.640; Jawed et al. (2015) quotes 7.60.  Converged: 7.640 +- 0.001
    # (nested meshes 7.6388, 7.6407, 7.6398, 7.6402 at dw = 0.02 ... 0.0025; phase means
    # 7.6402 and 7.6407 at dw = 0.02, 0.01): Audoly et al. 2007 is right, 7.60 is 0.04 too small.
    res = knot_braid.solve_knot(2, n_grid=int(round(knot_braid.default_half_width(2) / 0.01)))
    assert res.success, res.message
    assert res["w_c"] == pytest.approx(knot_braid.W_C_CINQUEFOIL, abs=3e-3)
    assert abs(res["w_c"] - knot_braid.W_C_CINQUEFOIL_SEED001) > 0.03
    # same contact topology, wider central contact (seed text)
    assert res["contact_half_width"] > 4.0
    assert res["max_gap"] == pytest.approx(0.021, abs=1e-3)
    assert len(res["isolated_contacts"]) == 1


def test_barrier_fallback_agrees(monkeypatch):
    # when the active-set iteration cycles the interior-point point is kept: same numbers
    exact = knot_braid.solve_knot(1, n_grid=450, half_width_W=4.5)
    orig = knot_braid._active_set
    monkeypatch.setattr(knot_braid, "_active_set",
                        lambda grid, y, a, f, x, max_outer=60: orig(grid, y, a, f, x, 0))
    fallback = knot_braid.solve_knot(1, n_grid=450, half_width_W=4.5)
    assert exact.values["final_stage"] == "active_set"
    assert fallback.success and fallback.values["final_stage"] == "barrier"
    for key, tol in (("w_c", 1e-5), ("sigma", 1e-4), ("max_gap", 1e-5),
                     ("isolated_contact_at", 1e-3), ("contact_half_width", 1e-3)):
        assert fallback[key] == pytest.approx(exact[key], abs=tol), key


def test_large_n_returns_result():
    res = knot_braid.solve_knot(3, n_grid=int(round(knot_braid.default_half_width(3) / 0.02)))
    assert isinstance(res, knot_braid.ContinuumResult)
    assert res.success and res.status == 0, res.message
    # w_c(n) = 3.506 + 4.135 (n - 1) (11.775 at dw = 0.005)
    assert res["w_c"] == pytest.approx(3.506 + 2 * 4.135, abs=0.01)
    assert res["sigma"] == pytest.approx(0.492 + 2 * 0.975, abs=0.01)


@pytest.mark.parametrize("kwargs", [{"n": 0}, {"n": -1}, {"n": 1.5}, {"n": True},
                                    {"n": 1, "half_width_W": 3.0},
                                    {"n": 2, "half_width_W": 6.0},
                                    {"n": 1, "half_width_W": -1.0},
                                    {"n": 1, "n_grid": 10},
                                    {"n": 1, "n_grid": 100000},
                                    {"n": 1, "initial": "previous"}])
def test_bad_input(kwargs):
    n = kwargs.pop("n")
    with pytest.raises(ValueError):
        knot_braid.solve_knot(n, **kwargs)


# ----------------------------------------------------------------------- tension law
def test_frictionless_tension_is_eq1():
    EI, h = 4.1 * 50.0, 1.0
    for R in (10.0, 100.0, 1234.5):
        T = knot_braid.tension_from_radius(R, thickness=h, bending_stiffness=EI)
        assert T == pytest.approx(EI / (2 * R**2), rel=1e-14)  # Eq. 1
        assert knot_braid.radius_from_tension(T, thickness=h, bending_stiffness=EI) == \
            pytest.approx(R, rel=1e-10)


def test_tension_law_branches_and_inverse():
    EI, h, mu = 2.0, 0.5, 0.07
    R = 40.0
    eps = math.sqrt(h / R)
    up = knot_braid.tension_from_radius(R, thickness=h, bending_stiffness=EI, mu=mu)
    down = knot_braid.tension_from_radius(R, thickness=h, bending_stiffness=EI, mu=mu,
                                    tightening=False)
    assert up * h**2 / EI == pytest.approx(eps**4 / 2 + mu * 0.492 * eps**3)  # Eq. 8
    assert down * h**2 / EI == pytest.approx(eps**4 / 2 - mu * 0.492 * eps**3)
    for T, tight in ((up, True), (down, False)):
        assert knot_braid.radius_from_tension(T, thickness=h, bending_stiffness=EI, mu=mu,
                                        tightening=tight) == pytest.approx(R, rel=1e-9)


def test_friction_lock():
    sigma = knot_braid.SIGMA_TREFOIL
    assert 1 / (2 * sigma) == pytest.approx(1.02, abs=5e-3)  # Eq. 9's 1.02
    assert knot_braid.friction_from_lock(1.0) == pytest.approx(1 / (2 * sigma))
    mu = 0.07
    eps0 = knot_braid.lock_epsilon(mu)
    assert eps0 == pytest.approx(2 * mu * sigma)
    assert knot_braid.friction_from_lock(eps0) == pytest.approx(mu)
    # loosening tension vanishes at the lock (Eq. 8 -> Eq. 9)
    assert knot_braid.scaled_tension(eps0, mu, tightening=False) == pytest.approx(0.0, abs=1e-15)
    assert knot_braid.epsilon_from_scaled_tension(0.0, mu, tightening=False) == pytest.approx(eps0)
    with pytest.raises(ValueError):
        knot_braid.epsilon_from_scaled_tension(-1.0, mu, tightening=False)
    with pytest.raises(ValueError):
        knot_braid.epsilon_from_scaled_tension(0.0, mu, tightening=True)


def test_braid_length_eq7():
    assert knot_braid.braid_length(100.0, 1.0) == pytest.approx(2 * 3.506 * math.sqrt(200.0))
    assert knot_braid.braid_length(100.0, 1.0, w_c=knot_braid.W_C_CINQUEFOIL) == \
        pytest.approx(2 * 7.640 * math.sqrt(200.0))
    with pytest.raises(ValueError):
        knot_braid.braid_length(-1.0, 1.0)


# ----------------------------------------------------------------------- CLI
def test_cli_roundtrip():
    parser = argparse.ArgumentParser()
    knot_braid.cli_add_arguments(parser)
    args = parser.parse_args(["--n", "1", "--n-grid", "250"])
    out = knot_braid.cli_run(args)
    json.dumps(out)
    for key in ("w_c", "sigma", "contact_half_width", "max_gap", "max_gap_at",
                "isolated_contact_at", "success", "wall_time_s"):
        assert key in out
    assert out["success"] is True
    assert out["w_c"] == pytest.approx(3.506, abs=5e-3)
    assert parser.parse_args([]).n == 1


@pytest.mark.slow
def test_convergence_table():
    rows = knot_braid.convergence_table()
    assert len(rows) == 5 and all(r["success"] for r in rows)
    errs = [r["error_w_c"] for r in rows[:-1]]
    assert all(a > b for a, b in zip(errs, errs[1:]))  # monotone first-order convergence
    ref = rows[-1]
    assert ref["w_c"] == pytest.approx(3.506, abs=6e-4)
    assert ref["sigma"] == pytest.approx(0.492, abs=6e-4)
    assert ref["max_gap"] == pytest.approx(0.021, abs=5e-4)
    assert ref["max_gap_at"] == pytest.approx(1.823, abs=1e-3)
    assert ref["isolated_contact_at"] == pytest.approx(2.681, abs=5e-4)
    assert ref["contact_half_width"] == pytest.approx(0.348, abs=2.5e-3)  # 0.3497


@pytest.mark.slow
def test_phase_averaged_cinquefoil():
    # phase means at dw = 0.01, 0.005 (10 shifts each), extrapolated: 7.640 +- 0.002
    res = knot_braid.solve_knot_averaged(2, spacings=(0.01, 0.005), n_shifts=10)
    assert res.success
    assert res["w_c"] == pytest.approx(7.640, abs=2.5e-3)
    assert abs(res["w_c"] - 7.60) > 0.035
    assert res["w_c_std_1"] < 1e-3
