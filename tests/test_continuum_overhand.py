"""Long overhand knots (Jawed et al. 2015, Jawed et al. PRL 2015): helical braid, loop elastica, Eq. (5)."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

from dnabraid.continuum import overhand as oh
from dnabraid.continuum._result import ContinuumResult

#: Tolerances (named, fixed).
TOL_EXACT = 1e-12  # closed-form identities
TOL_BVP_G = 1e-9  # solve_bvp (tol 1e-8) against the elliptic closed form, relative
TOL_TABLE_G = 1e-5  # spline of the default table against the closed form, relative
TOL_ROOT = 1e-9  # master-curve F by two methods, relative
TOL_FIRST_INTEGRAL = 1e-8  # spread of theta'^2/2 - T cos(theta) along the BVP solution

H = oh.NITINOL_RADIUS_M
B = oh.NITINOL_BENDING_N_M2
MU = oh.NITINOL_MU


# --------------------------------------------------------------------------- helical braid
def test_kbar_is_minimiser_of_ebar_eq3():
    """kbar = 12^(-1/4) minimises Ebar = kbar^3 + 1/(4 kbar) (seed, Eq. (3))."""
    assert oh.K_BAR == pytest.approx(12 ** -0.25, rel=TOL_EXACT)
    assert round(oh.K_BAR, 4) == 0.5373
    kb = np.linspace(0.2, 1.2, 100001)
    assert kb[np.argmin(oh.braid_energy_bar(kb))] == pytest.approx(oh.K_BAR, abs=2e-5)
    # Ebar(kbar*) = 4 kbar^3 = 4/12^(3/4) (seed, text for P)
    assert float(oh.braid_energy_bar(oh.K_BAR)) == pytest.approx(4 / 12 ** 0.75, rel=TOL_EXACT)
    assert oh.E_BAR_OPT == pytest.approx(4 * oh.K_BAR**3, rel=TOL_EXACT)


def test_wave_number_and_wavelength_eq3():
    R = 0.02
    k = oh.wave_number(H, R)
    assert k == pytest.approx((math.sqrt(12) * H * R) ** -0.5, rel=TOL_EXACT)
    br = oh.helical_braid(3, H, R, B, MU)
    # wavelength 2 pi/k = ell/n = 2 pi 12^(1/4) sqrt(hR) (seed, Fig. 2(c))
    assert br["wavelength"] == pytest.approx(2 * math.pi * 12 ** 0.25 * math.sqrt(H * R),
                                             rel=TOL_EXACT)
    assert br["ell"] / 3 == pytest.approx(br["wavelength"], rel=TOL_EXACT)
    assert br["kbar"] == pytest.approx(oh.K_BAR, rel=TOL_EXACT)


def test_w_c_printed_values():
    """w_c(1) = 4.13, w_c(2) = 8.27 (seed), w_c = pi n/(sqrt 2 kbar) = 3^(1/4) pi n."""
    assert round(oh.w_c_helical(1), 2) == 4.13
    assert round(oh.w_c_helical(2), 2) == 8.27
    for n in (1, 2, 7):
        assert oh.w_c_helical(n) == pytest.approx(3 ** 0.25 * math.pi * n, rel=TOL_EXACT)
        # ell = 2 w_c sqrt(2 h R) with ell = 2 n pi/k
        br = oh.helical_braid(n, H, 0.03, B)
        assert br["w_c"] == pytest.approx(oh.w_c_helical(n), rel=TOL_EXACT)


@pytest.mark.parametrize("exact", [oh.W_C_EXACT_SEED_QUOTED, oh.W_C_EXACT_ACN2007])
def test_helical_w_c_within_20_and_10_percent(exact):
    """Seed: within 20 % (n = 1) and 10 % (n = 2) of the exact w_c, closing in with n."""
    err = {n: (oh.w_c_helical(n) - exact[n]) / exact[n] for n in (1, 2)}
    assert 0 < err[1] < 0.20
    assert 0 < err[2] < 0.10
    assert err[2] < err[1]
    # the offset is a boundary-layer constant ~0.63, so the relative error falls like 1/n
    assert oh.w_c_helical(2) - exact[2] == pytest.approx(oh.w_c_helical(1) - exact[1], abs=0.05)


def test_contact_and_friction_force_eq4():
    n, R = 4, 0.015
    br = oh.helical_braid(n, H, R, B, MU)
    k = br["k"]
    assert br["P"] == pytest.approx(2 * n * math.pi * B * H * k**3, rel=TOL_EXACT)
    # P = Ebar B n pi / sqrt(4 h R^3) (seed, variational derivation)
    assert br["P"] == pytest.approx(oh.E_BAR_OPT * B * n * math.pi / math.sqrt(4 * H * R**3),
                                    rel=1e-12)
    # Eq. (4): F/(B k^2) = mu 2 pi n h k
    assert br["F_over_Bk2"] == pytest.approx(MU * br["two_pi_n_h_k"], rel=TOL_EXACT)


def test_contact_force_is_dE_dh():
    """P = dE_braid/dh at fixed k (envelope theorem), E from Eq. (1) on the ansatz Eq. (2)."""
    n, R, L = 50, 0.02, 1.0
    k = oh.wave_number(H, R)
    dh = H * 1e-6
    dE = (oh.braid_energy_ansatz(k, n, H + dh, R, B, L)
          - oh.braid_energy_ansatz(k, n, H - dh, R, B, L)) / (2 * dh)
    # exact derivative includes the O(1/n) term -B k/R; the seed's P drops it
    P = oh.helical_braid(n, H, R, B)["P"]
    assert dE == pytest.approx(P - B * k / R, rel=1e-6)
    assert abs(B * k / R) / P < 2.0 / n


def test_braid_energy_ansatz_matches_rescaled_form():
    """Eq. (1) on Eq. (2) = -BL/4R^2 + (eps^3/h) B n pi Ebar(kbar) + O(1/n) (seed)."""
    n, R, L = 5, 0.02, 2.0
    eps = math.sqrt(H / R)
    for kbar in (0.3, oh.K_BAR, 0.9):
        k = kbar / math.sqrt(H * R)
        E = oh.braid_energy_ansatz(k, n, H, R, B, L)
        lead = -B * L / (4 * R * R) + eps**3 / H * B * n * math.pi * oh.braid_energy_bar(kbar)
        assert E - lead == pytest.approx(-B * k * H / R, rel=1e-9)


def test_optimal_kbar_tends_to_12_quarter_as_n_grows():
    errs = [abs(oh.optimal_kbar_ansatz(n) - oh.K_BAR) for n in (1, 2, 10, 100, 1000)]
    assert errs == sorted(errs, reverse=True)
    assert errs[-1] < 1e-4


# --------------------------------------------------------------------------- loop elastica
@pytest.mark.parametrize("x", [0.0, 1e-3, 0.5, 3.0, 20.0, 100.0])
def test_loop_bvp_against_elliptic_closed_form(x):
    """solve_bvp on the Kirchhoff equations vs the independent elliptic-integral solution."""
    r = oh.solve_loop_elastica(x, tol=1e-8)
    assert isinstance(r, ContinuumResult) and r.success, r.message
    cf = oh.loop_closed_form_at(x)
    if x == 0.0:
        assert r.values["g"] == 0.0
    else:
        assert r.values["g"] == pytest.approx(cf["g"], rel=TOL_BVP_G)
    assert r.values["lambda_over_R"] == pytest.approx(cf["lambda_over_R"], rel=TOL_BVP_G)
    assert r.values["tension_R2_over_B"] == pytest.approx(cf["tension_R2_over_B"], abs=1e-8)
    assert r.values["aspect_ratio"] == pytest.approx(cf["aspect_ratio"], rel=1e-7)
    assert r.values["height_over_R"] == pytest.approx(cf["height_over_R"], rel=1e-7)
    assert r.values["first_integral_spread"] < TOL_FIRST_INTEGRAL


def test_loop_small_x_limit_is_circle():
    """x -> 0: circle of perimeter 2 pi R, g ~ x^2/(2 pi) (1 - 3x/(2pi)), a = W/H -> 1."""
    r0 = oh.solve_loop_elastica(0.0)
    assert r0.values["lambda_over_R"] == pytest.approx(2 * math.pi, rel=1e-9)
    assert r0.values["aspect_ratio"] == pytest.approx(1.0, rel=1e-9)
    assert r0.values["tension_R2_over_B"] == pytest.approx(0.0, abs=1e-9)
    for x in (1e-3, 1e-2):
        g = oh.solve_loop_elastica(x).values["g"]
        assert g == pytest.approx(x * x / (2 * math.pi), rel=2 * x)
        assert g == pytest.approx(float(oh.g_asymptotic_small(x)), rel=2 * x * x)


def test_loop_large_x_limit_is_soliton():
    """x -> inf: T R^2/B -> 1/4, lambda - ell -> 8R, g -> x/2 - 2, H -> 4R."""
    r = oh.solve_loop_elastica(100.0)
    v = r.values
    assert v["tension_R2_over_B"] == pytest.approx(0.25, abs=1e-9)
    assert v["lambda_over_R"] - 100.0 == pytest.approx(oh.LOOP_EXCESS_LARGE_X, rel=1e-8)
    assert v["g"] == pytest.approx(float(oh.g_asymptotic_large(100.0)), rel=1e-8)
    assert v["height_over_R"] == pytest.approx(4.0, rel=1e-8)


def test_closed_form_series_and_elliptic_branches_agree():
    from scipy.special import ellipe, ellipk
    for m in (0.1, 0.3, 0.5, 0.7):
        K, E = ellipk(m), ellipe(m)
        assert oh._x_series(m) == pytest.approx(4 * (2 * (K - E) / m - K), rel=1e-13)


def test_g_table_interpolant_and_monotonic():
    tab = oh.default_g_table()
    assert tab.success, tab.message
    assert np.all(np.diff(tab.g) > 0)
    xs = np.geomspace(0.01, 180.0, 60)
    ge = np.array([oh.g_closed_form(x) for x in xs])
    assert np.max(np.abs(tab(xs) - ge) / ge) < TOL_TABLE_G
    with pytest.raises(ValueError, match="tabulated range"):
        tab(tab.x_max * 2)


# --------------------------------------------------------------------------- master curve
def test_eq5_prefactors_from_components():
    """Eq. (5) = (ell = 2 n pi/k, Eq. (3), Eq. (4), ell^2 = e R g) recombined."""
    assert oh.C5_SHORTENING == pytest.approx(4 * math.pi**2 * math.sqrt(12), rel=TOL_EXACT)
    assert oh.C5_FORCE == pytest.approx(4 * math.pi**2 * 12 ** 1.5, rel=TOL_EXACT)


@pytest.mark.parametrize("n", [1, 3, 10])
def test_master_curve_consistency(n):
    e = 0.25
    r = oh.solve_overhand(e, n, H, B, MU)
    assert r.success, r.message
    v = r.values
    # Eq. (5) both sides
    assert n * n * H / e == pytest.approx(oh.default_g_table()(v["x_ell_over_R"])
                                          / oh.C5_SHORTENING, rel=1e-10)
    # the braid geometry of Eq. (3) at the solved R reproduces ell, and Eq. (4) F
    assert v["braid_length_residual"] < 1e-10
    assert v["eq4_residual"] < 1e-10
    assert v["ell"] ** 2 / (e * v["R"]) == pytest.approx(v["g"], rel=1e-10)
    assert v["lambda"] + v["ell"] == pytest.approx(e, rel=1e-5)  # e = lambda + ell (table)


@pytest.mark.parametrize("n, e", [(2, 0.15), (5, 0.4)])
def test_master_curve_three_methods_agree(n, e):
    F = [oh.solve_overhand(e, n, H, B, MU, method=m).values["F"]
         for m in ("elliptic", "direct", "table")]
    assert F[1] == pytest.approx(F[0], rel=TOL_ROOT)
    assert F[2] == pytest.approx(F[0], rel=1e-5)


def test_mu_zero_gives_zero_friction_force():
    """mu = 0: F = mu P = 0 (Eq. (4)); geometry unchanged; frictionless B/(2R^2) reported."""
    r0 = oh.solve_overhand(0.3, 3, H, B, 0.0)
    r1 = oh.solve_overhand(0.3, 3, H, B, MU)
    assert r0.success and r0.values["F"] == 0.0
    assert "mu = 0" in r0.message
    assert r0.values["x_ell_over_R"] == r1.values["x_ell_over_R"]
    assert r0.values["F_frictionless"] * r0.values["R"] ** 2 / B == pytest.approx(0.5)


def test_force_linear_in_mu_and_large_mu():
    F = [oh.solve_overhand(0.3, 4, H, B, mu).values["F"] for mu in (0.1, 0.2, 50.0)]
    assert F[1] == pytest.approx(2 * F[0], rel=1e-12)
    assert F[2] == pytest.approx(500 * F[0], rel=1e-12)


def test_large_e_limit_circle():
    """e -> inf: loop -> circle, R -> e/(2 pi), x -> 0, F ~ e^(-3/2) (from g ~ x^2/2pi)."""
    rs = [oh.solve_overhand(e, 1, H, B, MU) for e in (1e3, 1e4)]
    for e, r in zip((1e3, 1e4), rs):
        assert r.success
        assert r.values["R"] == pytest.approx(e / (2 * math.pi), rel=1e-2)
    assert rs[1].values["F"] / rs[0].values["F"] == pytest.approx(10 ** -1.5, rel=1e-2)


def test_inverse_round_trip():
    r = oh.solve_overhand(0.2, 4, H, B, MU, method="elliptic")
    e = oh.shortening_from_force(r.values["F"], 4, H, B, MU, method="elliptic")
    assert e == pytest.approx(0.2, rel=1e-10)
    with pytest.raises(ValueError, match="mu"):
        oh.shortening_from_force(1.0, 4, H, B, 0.0)
    # very small and very large tension: e -> inf and e -> O(n^2 h)
    assert oh.shortening_from_force(1e-12, 3, H, B, MU) > 1e6
    assert 0 < oh.shortening_from_force(1e6, 3, H, B, MU) < 9 * H
    with pytest.raises(ValueError, match="^F"):
        oh.shortening_from_force(1e12, 3, H, B, MU)


def test_curve_with_continuation_is_monotonic():
    es = np.linspace(0.12, 0.53, 12)
    res = oh.overhand_curve(es, 5, H, B, MU)
    assert all(r.success for r in res)
    F = [r.values["F"] for r in res]
    assert all(a > b for a, b in zip(F, F[1:]))  # tightening (smaller e) needs more force
    res_d = oh.overhand_curve(es[:4], 5, H, B, MU, method="direct")
    assert [r.values["F"] for r in res_d] == pytest.approx(F[:4], rel=1e-5)


def test_aspect_ratio_curve_fig3():
    a = oh.aspect_ratio_curve([1e-9, 1e-3, 1e-2, 0.1])
    assert a[0] == pytest.approx(1.0, abs=1e-3)
    assert np.all(np.diff(a) > 0)


# --------------------------------------------------------------------------- stability
def test_very_small_e_outside_model_or_table():
    # tighter than the table: status 3 with a reason
    r = oh.solve_overhand(0.5 * H, 3, H, B, MU)
    assert not r.success and r.status == 3 and "exceeds" in r.message
    # the closed form reaches further: at e = 2h, n = 1 it solves Eq. (5), but the loop
    # radius R = g e/x^2 comes out ~0.007 h <= h: outside the model (status 3)
    r = oh.solve_overhand(2 * H, 1, H, B, MU, method="elliptic")
    assert not r.success and r.status == 3 and "outside the model" in r.message
    v = r.values
    G = 8 * math.sqrt(3) * math.pi**2 * H / (2 * H)  # Eq. (5): g = 8 sqrt(3) pi^2 n^2 h/e
    assert v["g"] == pytest.approx(G, rel=TOL_EXACT)
    assert oh.g_closed_form(v["x_ell_over_R"]) == pytest.approx(G, rel=TOL_ROOT)
    assert v["R"] == pytest.approx(G * 2 * H / v["x_ell_over_R"] ** 2, rel=TOL_EXACT)
    assert v["R"] < H and v["eps"] == pytest.approx(math.sqrt(H / v["R"]), rel=TOL_EXACT)
    r = oh.solve_overhand(1e-4 * H, 10, H, B, MU, method="elliptic")
    assert not r.success and r.status == 3


def test_large_n():
    # n = 40 at e = 0.5 m: g = 8 sqrt(3) pi^2 n^2 h/e = 55.6 lies inside the table, and
    # R = 2.1 mm > h (eps = 0.25): converged, with the closed form's F
    r = oh.solve_overhand(0.5, 40, H, B, MU)
    assert isinstance(r, ContinuumResult)
    assert r.success and r.status == 0, r.message
    assert r.values["g"] == pytest.approx(8 * math.sqrt(3) * math.pi**2 * 1600 * H / 0.5,
                                          rel=TOL_EXACT)
    assert r.values["eps"] < 1.0
    ref = oh.solve_overhand(0.5, 40, H, B, MU, method="elliptic")
    assert ref.success
    assert r.values["F"] == pytest.approx(ref.values["F"], rel=TOL_TABLE_G)
    r = oh.solve_overhand(1e5, 1000, H, B, MU)
    assert r.success, r.message
    r = oh.solve_overhand(0.5, 1000, H, B, MU)
    assert not r.success and r.message


def test_direct_far_outside_returns_failure_not_exception():
    r = oh.solve_overhand(1e-3 * H, 10, H, B, MU, method="direct")
    assert isinstance(r, ContinuumResult)
    assert not r.success and r.message


@pytest.mark.parametrize("kwargs, name", [
    ({"n": 0}, "n"), ({"n": -2}, "n"), ({"n": 1.5}, "n"), ({"h": -1e-3}, "h"),
    ({"h": 0.0}, "h"), ({"B": -1.0}, "B"), ({"B": float("nan")}, "B"), ({"mu": -0.1}, "mu"),
    ({"e": 0.0}, "e"), ({"e": -1.0}, "e"),
])
def test_bad_input_raises_naming_argument(kwargs, name):
    args = {"e": 0.3, "n": 3, "h": H, "B": B, "mu": MU, **kwargs}
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        oh.solve_overhand(**args)


def test_bad_input_other_entry_points():
    with pytest.raises(ValueError, match="^n"):
        oh.w_c_helical(0)
    with pytest.raises(ValueError, match="^h"):
        oh.helical_braid(2, -1.0, 1.0)
    with pytest.raises(ValueError, match="^x"):
        oh.solve_loop_elastica(-1.0)
    with pytest.raises(ValueError, match="method"):
        oh.solve_overhand(0.3, 3, H, B, MU, method="nope")


# --------------------------------------------------------------------------- CLI / table
def test_cli_round_trip_json():
    p = argparse.ArgumentParser()
    oh.cli_add_arguments(p)
    out = oh.cli_run(p.parse_args(["--n", "4", "--e", "0.2"]))
    json.dumps(out)
    for key in ("k", "wavelength", "w_c_helical", "g", "F", "success", "wall_time_s"):
        assert key in out
    assert out["success"]
    out = oh.cli_run(p.parse_args(["--n", "2", "--e-range", "0.15", "0.5", "3"]))
    json.dumps(out)
    assert len(out["points"]) == 3 and out["success"]


@pytest.mark.slow
def test_convergence_table():
    rows = oh.convergence_table()
    json.dumps(rows)
    bvp = [r for r in rows if r["problem"] == "loop_bvp" and r["setting"].startswith("x=10")]
    assert bvp[-1]["error"] < 1e-12 and bvp[0]["error"] > bvp[-1]["error"]
    tab = [r["error"] for r in rows if r["problem"] == "g_table"]
    assert tab == sorted(tab, reverse=True) and tab[-1] < 1e-6
