"""The tweezer braid with the bead model's chiral range (dnabraid.continuum.soft_tweezer).

Long braid of the chirality cross-check: 2 x 200 nm, tethers 40 nm, D_c = 4.9 nm,
B = kT x 50 nm at 298.15 K, 150 mM (lambda_D = 0.785 nm, rho = 0.446 nm), n = +-2.
"""

import math

import pytest
from scipy.optimize import brentq

from dnabraid.continuum import tweezer
from dnabraid.continuum.soft_tweezer import (chiral_weight, soft_handedness_asymmetry,
                                             solve_soft_tweezer)
from dnabraid.continuum.tweezer import solve_tweezer
from dnabraid.forces.reference_chiral import chiral_range_nm

F, L, D_T, D_C, N = 2.0, 200.0, 40.0, 4.9, 2.0
B = 4.1164049935 * 50.0  # kT (298.15 K) x 50 nm, pN nm^2
DEBYE = 0.7849246248313698  # 150 mM, nm
RHO = chiral_range_nm(DEBYE)
KW = {"debye_nm": DEBYE, "bending_pN_nm2": B}
#: |dE/dx| at a refined interior optimum, relative to the pressure scale L_p p of the braid
#: (~6 pN): the gap is refined to 1e-7 nm and E''(x) ~ 10 pN/nm, so |dE/dx| ~ 1e-6 pN.
STATIONARY_RTOL = 1e-4
#: The uniform-ply force balance p = alpha |w'(d)| tan(|eta|/2) at the open optimum: the
#: tails' share of dE/dd (their landing points move with r) is not in p; a few per cent.
BALANCE_RTOL = 0.05
#: Closed-form gap (x/rho^2) e^{-x/rho} = p / (alpha tan(|eta|/2)) with p and eta of the
#: optimum: a BALANCE_RTOL error of the balance moves x by BALANCE_RTOL / (1/rho - 1/x)
#: (= 0.036 nm at x = 1.2 nm); 0.05 nm.
GAP_CLOSED_FORM_TOL_NM = 0.05
#: Finite difference of the re-minimised energy in the turns against the reported torque.
TORQUE_FD_RTOL = 1e-5


def soft(n, alpha, **kw):
    r = solve_soft_tweezer(n, F, L, D_T, D_C, alpha_pN=alpha, **KW, **kw)
    assert r.success, r.message
    return r


def hard(n, alpha, delta=D_C, force=F):
    r = solve_tweezer(n, force, L, D_T, delta, bending_pN_nm2=B, alpha_pN=alpha)
    assert r.success, r.message
    return r


def energy_at_gap(n, alpha, x, force=F):
    w, _ = chiral_weight(D_C, DEBYE)[0](D_C + x)
    return solve_tweezer(n, force, L, D_T, D_C + x, bending_pN_nm2=B,
                         alpha_pN=alpha * w)["free_energy_pN_nm"]


def test_weight_is_the_bead_models():
    """The continuum uses the bead kernel's w(d): 1 up to D_c, (1 + u) e^{-u} beyond."""
    w = chiral_weight(D_C, DEBYE)[0]
    assert w(D_C - 1.0) == (1.0, 0.0) and w(D_C) == (1.0, 0.0)
    u = 1.3
    assert w(D_C + u * RHO)[0] == pytest.approx((1 + u) * math.exp(-u), rel=1e-12)
    assert w(D_C + 6 * RHO + 1e-9)[0] == 0.0


@pytest.mark.parametrize("n", [N, -N])
def test_alpha_zero_is_the_hard_braid_at_contact(n):
    """(i) Without the chiral term nothing pushes the strands apart: x* = 0 and every
    observable is solve_tweezer's at D_c, exactly (the same call)."""
    r, h = soft(n, 0.0), hard(n, 0.0)
    assert r["gap_nm"] == 0.0 and len(r["local_minima"]) == 1
    for k in ("extension_nm", "torque_pN_nm", "free_energy_pN_nm", "theta_rad"):
        assert r[k] == h[k]


def test_favoured_hand_in_contact_where_the_hard_pressure_is_positive():
    """(ii) alpha = 0.5 pN, n = +2: the hard braid presses (dE/dDelta > 0) and w is flat at
    D_c (w' = 0), so the contact is the minimum: x* = 0 and the soft braid is the hard one."""
    h = hard(N, 0.5)
    assert (energy_at_gap(N, 0.5, 1e-3) - h["free_energy_pN_nm"]) > 0
    r = soft(N, 0.5)
    assert r["gap_nm"] == 0.0
    assert r["extension_nm"] == h["extension_nm"] and r["torque_pN_nm"] == h["torque_pN_nm"]


def test_favoured_hand_held_by_the_weight_where_the_hard_contact_pulls():
    """(ii') alpha = 2 pN, n = +2: the hard braid's energy falls as Delta grows
    (dE/dDelta = -6.4 pN: it needs an adhesive contact, its message says so). The soft weight
    is that adhesion: near D_c, w = 1 - x^2 / (2 rho^2) + O(x^3), so the favoured chiral energy
    -alpha w tan|theta| L_p rises as alpha tan|theta| L_p x^2 / (2 rho^2) and the strands sit
    at x* = -E'(0) rho^2 / (alpha tan|theta| L_p). Tolerance 15 %: the O(x^3 / rho^3) term
    of w (x*/rho ~ 0.05: 5 %) and the change of theta and L_p with x."""
    h = hard(N, 2.0)
    assert "adhesive" in h.message
    dE = (energy_at_gap(N, 2.0, 1e-4) - h["free_energy_pN_nm"]) / 1e-4
    assert dE < 0
    x_lin = -dE * RHO**2 / (2.0 * math.tan(abs(h["theta_rad"])) * h["ply_length_nm"])
    r = soft(N, 2.0)
    assert r["gap_nm"] == pytest.approx(x_lin, rel=0.15)
    assert 0 < r["gap_nm"] < 0.1 * RHO


@pytest.mark.parametrize("alpha", [0.5, 1.0])
def test_disfavoured_hand_opens_to_the_force_balance(alpha):
    """(iii) n = -2: the open minimum is stationary (central difference of E*(x), h = 1e-3 nm),
    lower than the contact, balances the chiral push against the uniform ply's pressure, and
    its gap matches the closed form (x/rho^2) e^{-x/rho} = p / (alpha tan(|eta|/2)) (below the
    switch at 4 rho = 1.78 nm)."""
    r = soft(-N, alpha)
    x = r["gap_nm"]
    assert RHO < x < 4 * RHO
    assert r["free_energy_pN_nm"] < r["energy_at_contact_pN_nm"]
    assert len(r["local_minima"]) == 2 and r["local_minima"][1]["gap_nm"] == 0.0
    h = 1e-3
    dEdx = (energy_at_gap(-N, alpha, x + h) - energy_at_gap(-N, alpha, x - h)) / (2 * h)
    scale = r["ply_length_nm"] * r["contact_force_pN_per_nm"]
    assert abs(dEdx) < STATIONARY_RTOL * scale
    # the slope either side has the sign of a minimum
    assert energy_at_gap(-N, alpha, x + 0.05) > r["free_energy_pN_nm"]
    assert energy_at_gap(-N, alpha, x - 0.05) > r["free_energy_pN_nm"]
    p, push = r["contact_force_pN_per_nm"], r["chiral_radial_force_pN_per_nm"]
    assert push > 0 and push == pytest.approx(p, rel=BALANCE_RTOL)
    ratio = p / (alpha * math.tan(0.5 * abs(r["eta_rad"])))
    x_cf = brentq(lambda y: y / RHO**2 * math.exp(-y / RHO) - ratio, RHO, 4 * RHO)
    assert x == pytest.approx(x_cf, abs=GAP_CLOSED_FORM_TOL_NM)


@pytest.mark.parametrize("n,alpha", [(-N, 1.0), (N, 1.0)])
def test_torque_is_the_derivative_of_the_minimised_energy(n, alpha):
    """(iv) Envelope theorem: Gamma = dE*/d(2 pi n) with E* minimised over shape AND gap
    (central difference in n, dn = 1e-4, each side re-minimised)."""
    r = soft(n, alpha)
    dn = 1e-4
    ep = soft(n + dn, alpha)["free_energy_pN_nm"]
    em = soft(n - dn, alpha)["free_energy_pN_nm"]
    fd = (ep - em) / (2 * dn) / (2 * math.pi)
    assert r["torque_pN_nm"] == pytest.approx(fd, rel=TORQUE_FD_RTOL)


def test_quasi_static_path_stays_open_where_the_contact_is_lower():
    """At 20 pN and alpha = 2 pN the disfavoured hand has two minima: contact (lowest) and
    open by ~0.67 nm, 5.9 pN nm higher. Turning from apart, the strands meet the open one
    first and stay there (branch="path"); the global minimum is the contact."""
    kw = {"alpha_pN": 2.0, **KW}
    g = solve_soft_tweezer(-N, 20.0, L, D_T, D_C, **kw)
    p = solve_soft_tweezer(-N, 20.0, L, D_T, D_C, branch="path", **kw)
    assert g.success and p.success
    assert g["gap_nm"] == 0.0 and len(g["local_minima"]) == 2
    assert p["gap_nm"] == pytest.approx(g["local_minima"][1]["gap_nm"], abs=1e-6)
    assert p["free_energy_pN_nm"] > g["free_energy_pN_nm"]
    assert p["chiral_radial_force_pN_per_nm"] == pytest.approx(p["contact_force_pN_per_nm"],
                                                               rel=BALANCE_RTOL)


def test_asymmetry_sign_differs_from_the_hard_braid():
    """alpha = 1 pN: the hard braid gives z(+2) - z(-2) = -0.17 nm (the disfavoured hand, held
    in contact, is pushed to a smaller |eta| and is longer); the soft braid lets it open by
    ~1.7 nm, which shortens it, and dz turns positive (+2.85 nm) as in the bead model."""
    a = soft_handedness_asymmetry(N, F, L, D_T, D_C, alpha_pN=1.0, **KW)
    assert a["success"]
    assert tweezer.handedness_asymmetry(N, F, L, D_T, D_C, bending_pN_nm2=B,
                                        alpha_pN=1.0)["delta_z_nm"] < 0
    assert a["delta_z_nm"] > 0
    assert a["axis_distance_minus_nm"] - D_C > RHO
    assert a["axis_distance_plus_nm"] - D_C < 0.01


def test_rejects_bad_input():
    with pytest.raises(ValueError, match="branch"):
        solve_soft_tweezer(N, F, L, D_T, D_C, branch="lowest", **KW)
    with pytest.raises(ValueError, match="debye_nm"):
        solve_soft_tweezer(N, F, L, D_T, D_C, debye_nm=0.0, bending_pN_nm2=B)
