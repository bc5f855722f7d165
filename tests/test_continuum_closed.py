"""Closed two-ply (van der Heijden, elastic braids, slides 19-23): uniform torus links/knots and the axis correction.

Every number asserted comes from an independent computation (the discretised torus curves
through :mod:`dnabraid.geometry.curves`, the open-ply module, an exact quadrature of the torus
family) or from the seed's slides 21 and 23; tolerances are named and justified where set.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from dnabraid.cli import main
from dnabraid.continuum import closed_ply as cc
from dnabraid.continuum import ply
from dnabraid.geometry.curves import crossing_angles, gauss_linking_number, writhe

D = 0.02  # the seed's Delta/L (slides 20-23)
#: Closed-form identities evaluated two ways.
TOL_EXACT = 1e-12
#: Richardson-extrapolated polygon (h^2 error removed) against spectral quadrature: the
#: remaining h^4 term at 150/300 points per strand is ~1e-7 (measured h^2 error 2e-4 at 300).
TOL_RICHARDSON = 1e-5
#: A linking number of two disjoint closed polygons is an integer up to round-off.
TOL_INTEGER = 1e-8


def _richardson(f, n_points):
    """``(4 f(2N) - f(N)) / 3``: removes the polygon's h^2 error."""
    return (4.0 * f(2 * n_points) - f(n_points)) / 3.0


# --------------------------------------------------------------------------- geometry
@pytest.mark.parametrize("n, topology", [(1, "link"), (4, "link"), (5, "knot")])
def test_angle_formula_from_the_discretised_torus(n, topology):
    """Eq. (1): the torus curve with strands of length L has sin(theta) = pi m Delta/L.

    Measured on the curve: its polygon length is L and the mean angle between its tangent and
    the axis direction e_u is theta_R; theta_R - theta = eps^2 sin^3 cos/4 (second order).
    """
    rings = cc.torus_ply_curves(n, D, topology, n_points=2000)
    x = rings[0]
    seg = np.roll(x, -1, axis=0) - x
    n_strands = 1 if topology == "link" else 2
    assert np.sum(np.linalg.norm(seg, axis=1)) / n_strands == pytest.approx(1.0, rel=1e-5)
    mid = 0.5 * (x + np.roll(x, -1, axis=0))
    e_u = np.stack([-mid[:, 1], mid[:, 0], 0 * mid[:, 0]], 1)
    e_u /= np.linalg.norm(e_u, axis=1)[:, None]
    t = seg / np.linalg.norm(seg, axis=1)[:, None]
    # angle of t to e_u, measured at the points where cos(phi) = 0 (strands level with
    # the axis), where the exact torus value is tan(theta_R) = r m / R
    m = cc.ply_turns(n, topology)
    R = cc.axis_radius_exact(n, D, topology)
    theta_R = math.atan(0.5 * D * m / R)
    theta = cc.closed_ply_angle(n, D, topology)
    eps = 0.5 * D / R
    assert theta_R - theta == pytest.approx(eps**2 * math.sin(theta) ** 3 * math.cos(theta) / 4,
                                            rel=0.05, abs=1e-9)
    ang = np.arccos(np.clip(np.sum(t * e_u, axis=1), -1, 1))
    z = mid[:, 2] / (0.5 * D)
    level = np.abs(z) > 0.999  # sin(phi) = +-1 -> cos(phi) = 0
    assert np.mean(ang[level]) == pytest.approx(theta_R, abs=2e-5)  # polygon, h = L/2000
    assert math.sin(theta) == pytest.approx(math.pi * m * D, rel=TOL_EXACT)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
def test_link_has_gauss_linking_number_minus_n(n):
    """Slide 20: the left-handed (2, 2n) torus links have Lk = -n."""
    a, b = cc.torus_ply_curves(n, D, "link", n_points=400)
    lk = gauss_linking_number(a, b)
    assert lk == pytest.approx(-n, abs=TOL_INTEGER)
    assert cc.closed_ply(n, D, "link", relax=False).values["linking_number"] == -n


@pytest.mark.parametrize("n, topology", [(4, "link"), (5, "knot")])
def test_writhe_gauss_integral_against_fuller_and_formula(n, topology):
    """Writhe per ring: Gauss double integral on the polygon (Richardson) = Fuller quadrature;
    the first-order formula differs by O(eps^2) (tolerance eps^2, eps = r/R ~ 0.065)."""
    fuller = cc.writhe_fuller(n, D, topology)
    gauss = _richardson(lambda N: writhe(cc.torus_ply_curves(n, D, topology, n_points=N)[0]),
                        120)
    assert gauss == pytest.approx(fuller, abs=TOL_RICHARDSON)
    eps = cc.closed_ply(n, D, topology, relax=False).values["epsilon"]
    assert cc.writhe_formula(n, D, topology) == pytest.approx(fuller, abs=eps**2)
    assert fuller < 0  # left-handed


def test_braid_angle_on_the_polygon_period_2n_and_expansion():
    """eta along the 4-link's contact from curves.crossing_angles on the discretised torus:
    mean = the exact torus value = Eq. (3) to O(eps^4); dominant harmonic 2n (slide 21)."""
    n = 4
    exact = cc.braid_angle_torus(np.linspace(0, 2 * np.pi, 4096, endpoint=False), n, D)

    def mean_eta(N):
        a, b = cc.torus_ply_curves(n, D, "link", n_points=N)
        eta, dist = crossing_angles(np.vstack([a, a[:1]]), np.vstack([b, b[:1]]), cutoff=1.5 * D)
        assert len(eta) == N and np.allclose(dist, D, rtol=1e-2)  # polygon sagitta
        mean_eta.last = eta
        return float(np.mean(eta))

    assert _richardson(mean_eta, 250) == pytest.approx(float(np.mean(exact)),
                                                       abs=TOL_RICHARDSON)
    spec = np.abs(np.fft.rfft(mean_eta.last - mean_eta.last.mean()))
    assert int(np.argmax(spec)) == 2 * n
    e = cc.braid_angle_expansion(n, D)
    eps4 = e["epsilon"] ** 4
    assert float(np.mean(exact)) == pytest.approx(e["eta_mean"], abs=eps4)
    assert float(exact.min()) == pytest.approx(e["eta_min"], abs=eps4)
    assert float(exact.max()) == pytest.approx(e["eta_max"], abs=eps4)


# --------------------------------------------------------------------------- forces
@pytest.mark.parametrize("n, topology", [(4, "link"), (5, "knot"), (2, "link")])
def test_uniform_pressure_and_moment_from_the_open_ply(n, topology):
    """Eq. (2) = ply.uniform_ply_contact_force at F = alpha = 0; M = ply.fixed_point_torque."""
    v = cc.closed_ply(n, D, topology, relax=False).values
    theta = v["theta_rad"]
    assert v["pressure_uniform_B_per_L3"] == pytest.approx(
        ply.uniform_ply_contact_force(theta, 0.0, D, 1.0), rel=TOL_EXACT)
    m = cc.ply_turns(n, topology)
    assert v["pressure_uniform_B_per_L3"] == pytest.approx(8 * math.pi**4 * m**4 * D,
                                                           rel=TOL_EXACT)
    assert v["ply_moment_B_per_L"] == pytest.approx(4 * math.sin(theta) ** 3 / (D / 2),
                                                    rel=TOL_EXACT)


@pytest.mark.parametrize("n, topology, d", [(4, "link", D), (5, "knot", D), (8, "link", D / 2)])
def test_mean_pressure_formula_against_exact_torus_virtual_work(n, topology, d):
    """Eq. (4) against the exact torus-family virtual work; neglected: relative O(1/m^4)."""
    v = cc.closed_ply(n, d, topology, relax=False).values
    m = cc.ply_turns(n, topology)
    p0, eps = v["pressure_uniform_B_per_L3"], v["epsilon"]
    assert v["pressure_mean_formula_B_per_L3"] == pytest.approx(
        v["pressure_mean_B_per_L3"], rel=m**-4)
    assert abs(v["pressure_mean_B_per_L3"] - p0) > 5 * m**-4 * p0  # it is a correction
    assert v["energy_formula_B_per_L"] == pytest.approx(v["energy_torus_B_per_L"], rel=eps**2)


def test_virtual_work_reproduces_the_straight_ply_pressure():
    """Straight limit at fixed theta (m -> inf, eps -> 0): (p_mean - p0)/p0 * m^2 tends to the
    coefficient of Eq. (4), -3/2 + 13 S^2 - 9 S^4 (difference O(1/m^2), coefficient < 1)."""
    S = math.pi * 4 * D
    coef = -1.5 + 13 * S**2 - 9 * S**4
    for m in (16, 32):
        d = S / (math.pi * m)
        p0 = cc.uniform_pressure(m, d)
        pm = cc.mean_pressure_virtual_work(m, d)
        assert (pm - p0) / p0 * m**2 == pytest.approx(coef, abs=1.0 / m**2)


def test_torus_helix_is_not_a_first_order_equilibrium():
    """Local Kirchhoff balance on the torus helix: the out-of-contact-plane load is first order
    in eps at fixed theta (halving eps halves it, to O(eps^2)); it vanishes in the straight
    limit, where the local pressure is uniform and equals p0."""
    S = math.pi * 4 * D
    out = {}
    for m in (100, 200):
        out[m] = cc.torus_helix_local_balance(m, S / (math.pi * m), "link", n_points=8192)
    ratio = out[100]["out_of_plane_rel"] / out[200]["out_of_plane_rel"]
    eps_ratio = out[100]["epsilon"] / out[200]["epsilon"]
    assert ratio == pytest.approx(eps_ratio, rel=0.05)
    spread = (out[200]["pressure_max"] - out[200]["pressure_min"]) / out[200]["pressure_mean"]
    assert spread < 20 * out[200]["epsilon"]
    assert out[200]["newton3_rel"] < 20 * out[200]["epsilon"]
    # the seed's 4-link: the out-of-plane load is O(1), not small
    seed4 = cc.torus_helix_local_balance(4, D, "link", n_points=1024)
    assert seed4["out_of_plane_rel"] > 0.1


# --------------------------------------------------------------------------- seed numbers
def test_eta_of_the_4_link_against_slide_21():
    """Slide 21: eta in [0.50910, 0.50935] (mean 0.509225 +- 0.000125 read off the axis).

    Uniform ply: 2 asin(4 pi 0.02) = 0.508103 (not 0.5091: the seed's value includes the axis
    curvature).  It must agree within the size of what it neglects: the second-order mean
    shift eps^2 (sin cos^3 + sin^3 cos/2) = 0.00099 plus the torus helix's modulation
    amplitude eps^2 sin cos^3 = 0.00096 (which the relaxed braid changes), plus the plot
    reading.  The corrected mean must agree within the last two.
    """
    seed = cc.SEED["link4"]
    mean = 0.5 * (seed["eta_min"] + seed["eta_max"])
    half = 0.5 * (seed["eta_max"] - seed["eta_min"])
    e = cc.braid_angle_expansion(4, D)
    assert e["eta_uniform"] == pytest.approx(2 * math.asin(4 * math.pi * D), rel=TOL_EXACT)
    assert e["eta_uniform"] == pytest.approx(0.508103, abs=1e-6)
    tol_uniform = abs(e["eta_correction_mean"]) + e["eta_modulation_amplitude"] + half
    assert abs(e["eta_uniform"] - mean) < tol_uniform
    assert abs(e["eta_mean"] - mean) < e["eta_modulation_amplitude"] + half
    assert abs(e["eta_mean"] - mean) < abs(e["eta_uniform"] - mean)  # the correction helps


def test_torus_corrected_pressures_against_slides_21_and_23():
    """Mean pressures of the torus helix with the axis correction fall inside the seed's
    plotted ranges (the uniform ply's do not: 3990 > 3900 and 609 > 550); the pentafoil's
    contact curve has the axis curvature L/R = 6.36, inside slide 23's 6.2-6.8."""
    for key, name in (("link4", "pressure_"), ("pentafoil", "pressure_")):
        seed = cc.SEED[key]
        v = cc.closed_ply(seed["n"], D, seed["topology"], relax=False).values
        assert seed[name + "min"] <= v["pressure_mean_B_per_L3"] <= seed[name + "max"]
        assert v["pressure_uniform_B_per_L3"] > seed[name + "max"]
    seed = cc.SEED["pentafoil"]
    v = cc.closed_ply(5, D, "knot", relax=False).values
    assert seed["contact_curvature_min"] <= v["contact_curvature_per_L"] \
        <= seed["contact_curvature_max"]


# --------------------------------------------------------------------------- relaxed ply
#: Slide 21's axis ticks: 0.00005 (eta) and 100 B/L^3 (p); the plotted curves' ends are read
#: to half a tick.
TOL_SLIDE21_ETA = 0.000025
TOL_SLIDE21_P = 50.0


@pytest.fixture(scope="module")
def relaxed_link4():
    return cc.relax_closed_ply(4, D, "link", harmonics=2)


def test_relaxed_4_link_is_an_equilibrium(relaxed_link4):
    """The Ritz shape is the equilibrium: the two loads that vanish only there (the
    out-of-contact-plane load and p1 ds1 - p2 ds2) are < 1e-3 of p (they are 0.7 and 0.04 on
    the torus helix, which the relaxation lowers in energy)."""
    v = relaxed_link4.values
    assert relaxed_link4.success
    assert v["out_of_plane_rel"] < 1e-3 and v["newton3_rel"] < 1e-3
    assert v["energy_B_per_L"] < v["energy_torus_B_per_L"]
    torus = cc.torus_helix_local_balance(4, D, "link", n_points=1024)
    assert torus["out_of_plane_rel"] > 100 * v["out_of_plane_rel"]


@pytest.mark.slow
def test_relaxed_4_link_pressure_is_the_virtual_work(relaxed_link4):
    """The local (Kirchhoff) mean pressure equals (1/L) dE/dDelta of the re-relaxed energy
    (envelope theorem), within the central difference's O(h^2) and the Ritz truncation
    (1e-3 relative). ~3 s."""
    v = relaxed_link4.values
    h = 2e-4
    e_p = cc.relax_closed_ply(4, D + h, "link", harmonics=2).values["energy_B_per_L"]
    e_m = cc.relax_closed_ply(4, D - h, "link", harmonics=2).values["energy_B_per_L"]
    assert (e_p - e_m) / (2 * h) == pytest.approx(v["pressure_mean_B_per_L3"], rel=1e-3)


def test_relaxed_4_link_against_slide_21(relaxed_link4):
    """Slide 21: eta between 0.50910 and 0.50935, p between 3200 and 3900, p of period n and
    eta of period 2n (dominant harmonics along the ring)."""
    v = relaxed_link4.values
    seed = cc.SEED["link4"]
    assert v["eta_min_rad"] == pytest.approx(seed["eta_min"], abs=TOL_SLIDE21_ETA)
    assert v["eta_max_rad"] == pytest.approx(seed["eta_max"], abs=TOL_SLIDE21_ETA)
    assert v["pressure_min_B_per_L3"] == pytest.approx(seed["pressure_min"], abs=TOL_SLIDE21_P)
    assert v["pressure_max_B_per_L3"] == pytest.approx(seed["pressure_max"], abs=TOL_SLIDE21_P)
    assert v["pressure_harmonic"] == 4 and v["eta_harmonic"] == 8
    assert v["pressure_min_B_per_L3"] > 0  # hard contact holds everywhere


@pytest.mark.slow
def test_relaxed_ply_converges_in_harmonics(relaxed_link4):
    """J = 1 -> 2 changes p_min by 51 B/L^3; J = 2 -> 3 by < 1 (measured 0.3): J = 2 is the
    default. Tolerance: 2 B/L^3, 4 % of the seed's tick. ~5 s."""
    v3 = cc.relax_closed_ply(4, D, "link", harmonics=3).values
    v2 = relaxed_link4.values
    for key in ("pressure_min_B_per_L3", "pressure_max_B_per_L3", "pressure_mean_B_per_L3"):
        assert v3[key] == pytest.approx(v2[key], abs=2.0)
    assert v3["eta_max_rad"] == pytest.approx(v2["eta_max_rad"], abs=2e-6)


def test_relaxed_hopf_link_is_two_round_circles():
    """n = 1: the two rings relax to round circles of length L (energy 2 x (B/2) (2 pi)^2 / L)
    that touch without pressing (p = 0 to 2e-2 of the uniform ply's 15.6 B/L^3)."""
    res = cc.relax_closed_ply(1, D, "link", harmonics=1)
    v = res.values
    assert v["energy_B_per_L"] == pytest.approx(4 * math.pi**2, rel=1e-8)
    p0 = cc.uniform_pressure(1, D)
    # measured |p| <= 0.0103 p0 (the Kirchhoff pressure of a contact that carries nothing is
    # the residual of the one-harmonic fit); a pressing contact would give p ~ p0
    assert abs(v["pressure_min_B_per_L3"]) < 0.02 * p0 and abs(v["pressure_max_B_per_L3"]) \
        < 0.02 * p0
    x1, x2 = res.solution["strands"]
    assert gauss_linking_number(x1, x2) == pytest.approx(-1, abs=TOL_INTEGER)


def test_relaxed_pentafoil_against_slide_23():
    """Slide 23: p 400-550, kappa_c 6.2-6.8. The relaxed pentafoil's means (472, 6.37) lie
    inside; its maxima (558, 6.74) agree to half a tick (25 B/L^3, 0.1/L); its minima (365,
    5.98) lie below the plotted ranges by 35 and 0.22 -- a real difference, reported (the seed's
    pentafoil has L2 != L, which this symmetric ansatz excludes). p > 0 everywhere."""
    v = cc.relax_closed_ply(5, D, "knot", harmonics=2).values
    seed = cc.SEED["pentafoil"]
    assert v["out_of_plane_rel"] < 1e-3
    assert seed["pressure_min"] < v["pressure_mean_B_per_L3"] < seed["pressure_max"]
    assert seed["contact_curvature_min"] < v["contact_curvature_mean_per_L"] \
        < seed["contact_curvature_max"]
    assert v["pressure_max_B_per_L3"] == pytest.approx(seed["pressure_max"], abs=25.0)
    assert v["contact_curvature_max_per_L"] == pytest.approx(seed["contact_curvature_max"],
                                                             abs=0.1)
    assert 0 < v["pressure_min_B_per_L3"] < seed["pressure_min"]
    assert v["contact_curvature_harmonic"] == 5  # kappa_c period n on [0, L] (slide 23)


def test_seed_table_rows():
    rows = cc.seed_comparison_table(harmonics=1)
    assert {r["slide"] for r in rows} == {21, 23}
    for r in rows:
        assert r["unit"] in ("rad", "B/L^3", "1/L") and math.isfinite(r["relaxed"])


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, match", [
    ({"n": 4, "diameter_over_length": D, "topology": "knot"}, r"n must be odd for the \(n, 2\)"),
    ({"n": 20, "diameter_over_length": D}, r"n=20 does not fit: sin\(theta\) = pi m Delta/L"),
    ({"n": 12, "diameter_over_length": D}, r"45 deg, the two-ply lock-up"),
    ({"n": 1, "diameter_over_length": 0.16}, r"smaller than Delta"),
    ({"n": 0, "diameter_over_length": D}, r"^n must be an integer >= 1"),
    ({"n": 2, "diameter_over_length": -0.1}, r"^diameter_over_length must be a positive"),
    ({"n": 2, "diameter_over_length": D, "topology": "braid"}, r"^topology must be one of"),
])
def test_bad_input_is_refused_clearly(kwargs, match):
    with pytest.raises(ValueError, match=match):
        cc.closed_ply(**kwargs)


# --------------------------------------------------------------------------- CLI
@pytest.mark.parametrize("argv, n, topology", [
    (["--harmonics", "0"], 4, "link"), (["--n", "5", "--topology", "knot", "--harmonics", "1"],
                                        5, "knot")])
def test_cli_json_round_trip(capsys, argv, n, topology):
    rc = main(["continuum", "closed", "--diameter-over-length", "0.02", *argv, "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["success"] is True and out["problem"] == "closed_ply"
    assert "table" not in out
    harmonics = int(argv[argv.index("--harmonics") + 1])
    ref = cc.closed_ply(n, D, topology, relax=harmonics > 0, harmonics=max(harmonics, 1)).to_dict()
    for key in ("theta_rad", "eta_rad", "eta_mean_rad", "pressure_uniform_B_per_L3",
                "pressure_mean_B_per_L3", "writhe_per_ring_fuller", "linking_number"):
        assert out[key] == pytest.approx(ref[key], rel=1e-12), key
    assert out["topology"] == topology
    assert ("relaxed_pressure_min_B_per_L3" in out) == (harmonics > 0)
    if harmonics:
        assert out["relaxed_pressure_min_B_per_L3"] == pytest.approx(
            ref["relaxed_pressure_min_B_per_L3"], rel=1e-9)


def test_cli_table_has_units(capsys):
    assert main(["continuum", "closed", "--n", "4", "--harmonics", "1"]) == 0
    text = capsys.readouterr().out
    assert "B/L^3" in text and "unit" in text and "rad" in text and "relaxed" in text


def test_cli_refuses_even_knot(capsys):
    assert main(["continuum", "closed", "--n", "4", "--topology", "knot"]) == 2
    assert "odd" in capsys.readouterr().err


@pytest.mark.slow
def test_convergence_table_errors_fall():
    """workflows/continuum_convergence.py's rows: the Ritz error falls with the harmonics, the
    polygon writhe error falls as h^2 (ratio 4 +- 10 % per doubling), the central difference
    as step^2. ~20 s."""
    rows = cc.convergence_table()
    ritz = [r["error"] for r in rows if r["problem"] == "relaxed_4_link"]
    assert ritz == sorted(ritz, reverse=True) and ritz[-1] < 1.0
    wr = [r["error"] for r in rows if r["problem"] == "writhe_polygon"]
    for a, b in zip(wr, wr[1:]):
        assert a / b == pytest.approx(4.0, rel=0.1)
    fd = [r["error"] for r in rows if r["problem"] == "torus_virtual_work"]
    for a, b in zip(fd, fd[1:]):
        assert a / b == pytest.approx(100.0, rel=0.1)
