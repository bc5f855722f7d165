"""Handedness asymmetry (issues 4 and 6): left- against right-handed braids, bead model
against the continuum tweezer braid.

Zero temperature (fast, deterministic): the bead braid is formed quasi-statically by
turning the trap in 40 increments with an energy minimisation after each
(dnabraid.crosscheck), for the default braid geometry (2 x 200 nm, tethers 40 nm apart,
F = 2 pN, 150 mM) at n = +-2 turns. The continuum uses the bead model's own contact
distance (5.48 nm, measured at alpha = 0) as Delta.

Measured (2026-11-22): alpha = 0: bead torque 5.02 pN nm, continuum 4.82 (4 %); extension
187.69 vs 186.90 nm (0.4 %). Torque sum Gamma(+2) + Gamma(-2): alpha = 0.5 pN: bead -3.06,
continuum -2.89 pN nm (6 %); alpha = 1 pN: -5.64 vs -5.32 (6 %); alpha = 2: -9.0 vs -10.4;
alpha = 4: -14.7 vs -22.0 (the disfavoured left-handed braid opens up: see
test_disfavoured_hand_opens). The bead torques move by ~3 % with the minimiser's path and
tolerance (alpha = 0.5: -3.06 to -3.18 over runs). Tolerances below: 15 % on the torques at
alpha <= 1 pN (model difference: tails, kinks, soft WCA contact, path), 1 % on the
extension.

The extension asymmetry z(+n) - z(-n) differs between the two models, and the test says so
rather than hiding it: the bead model's chiral weight decays with distance, so it also pushes
the strands of the disfavoured hand apart (and pulls the favoured ones together); the
continuum braid is in hard contact at a fixed Delta and has no such radial force.

Room temperature (slow): the sign and growth of the torque asymmetry with alpha.
"""

import math

import pytest

from dnabraid.crosscheck import compare_tweezer, zero_temperature_braid
from dnabraid.scene import make_scene

N = 2.0
TORQUE_RTOL = 0.15
EXT_RTOL = 0.01


@pytest.fixture(scope="module")
def contact():
    return zero_temperature_braid(N, {"alpha": 0.0}).contact_nm


@pytest.fixture(scope="module")
def achiral(contact):
    return compare_tweezer(N, 0.0, contact_nm=contact)


def test_zero_temperature_symmetric_at_alpha_zero(achiral):
    r = achiral
    assert r["plus"]["bead_catenation"] == pytest.approx(N, abs=1e-3)
    assert r["minus"]["bead_catenation"] == pytest.approx(-N, abs=1e-3)
    g = r["plus"]["bead_torque_pN_nm"]
    assert g > 0  # the trap holds a positive braid with a positive torque
    assert abs(r["bead_torque_sum_pN_nm"]) < 1e-3 * g
    assert abs(r["bead_delta_z_nm"]) < 1e-3


def test_zero_temperature_braid_matches_continuum(achiral):
    p = achiral["plus"]
    assert p["bead_extension_nm"] == pytest.approx(p["continuum_extension_nm"], rel=EXT_RTOL)
    assert p["bead_torque_pN_nm"] == pytest.approx(p["continuum_torque_pN_nm"], rel=TORQUE_RTOL)


@pytest.mark.parametrize("alpha", [pytest.param(0.5, marks=pytest.mark.slow), 1.0])
def test_torque_asymmetry_matches_continuum(contact, alpha):
    r = compare_tweezer(N, alpha, contact_nm=contact)
    # alpha > 0 favours right-handed (n > 0) braids: less torque is needed to hold +n
    assert r["bead_torque_sum_pN_nm"] < 0
    assert r["bead_torque_sum_pN_nm"] == pytest.approx(r["continuum_torque_sum_pN_nm"],
                                                       rel=TORQUE_RTOL)
    # continuum: Gamma_chiral ~ -r alpha / cos(theta) per hand (phi = -alpha tan theta
    # over a contact length 2 pi r n / sin theta): the sum is close to -2 r alpha
    r_half = 0.5 * contact
    assert r["continuum_torque_sum_pN_nm"] == pytest.approx(-2 * r_half * alpha, rel=0.10)


@pytest.mark.slow
def test_disfavoured_hand_opens(contact):
    """alpha = 2 pN: the left-handed braid's strands move apart, the right-handed ones stay."""
    plus = zero_temperature_braid(N, {"alpha": 2.0})
    minus = zero_temperature_braid(-N, {"alpha": 2.0})
    assert plus.contact_nm == pytest.approx(contact, abs=0.1)
    assert minus.contact_nm > contact + 1.0
    assert plus.extension_nm > minus.extension_nm  # so z(+n) - z(-n) > 0 in the bead model


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason=(
    "open (issue 4): too little sampling to resolve the signal. Measured 2026-11-22 with these "
    "settings: alpha = 0: +23.8 +- 10.5, alpha = 12 pN: -11.8 +- 10.0 pN nm. Twelve seeds of "
    "an n = 0 braid (150k steps) scatter by 15.6 pN nm around -0.5 +- 4.5 (no bias) while "
    "each run's autocorrelation SEM says ~9.5: the torque SEM is ~1.6x too small"))
def test_room_temperature_torque_asymmetry_sign(tmp_path):
    """Thermal braids at n = -2, 0, +2: Gamma(+n) + Gamma(-n) is zero within error at
    alpha = 0 and negative beyond 3 standard errors at alpha = 12 pN.

    The turn list must be symmetric about 0: the protocol then ramps +n and -n from the same
    n = 0 state. With turns [-2, 2] alone the +2 point is reached through -2, and with 400k
    sampling steps that history left Gamma(+2) + Gamma(-2) = 17.8 +- 7.8 pN nm at alpha = 0
    (measured 2026-11-22; then 3.2 +- 7.7 at alpha = 4 and -8.0 +- 7.6 at alpha = 8)."""
    from dnabraid.runner import run_scene

    sums = {}
    for alpha in (0.0, 12.0):
        s = make_scene("braid", {"length_nm": 150.0, "tether_separation_nm": 30.0,
                                 "turns": [-2.0, 0.0, 2.0], "steps": 300_000,
                                 "equilibration_steps": 100_000, "alpha": alpha, "seed": 3})
        pts = {p["turns"]: p["torque_pN_nm"]
               for p in run_scene(s, str(tmp_path / f"a{alpha}"))["points"]}
        sums[alpha] = (pts[2.0]["mean"] + pts[-2.0]["mean"],
                       math.hypot(pts[2.0]["sem"], pts[-2.0]["sem"]))
    print("torque sums (pN nm):", sums)
    z = 3.0
    assert abs(sums[0.0][0]) < z * sums[0.0][1], sums
    assert sums[12.0][0] < -z * sums[12.0][1], sums
