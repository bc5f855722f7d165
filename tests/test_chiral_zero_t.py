"""Zero-temperature chirality cross-check on the long braid with the capsule contact
(dnabraid.validation.chiral_zero_t; table in workflows/results/chiral_zero_t.md).

2 x 200 nm, 2 pN, tethers 40 nm, 150 mM, contact = capsules (D_c = 4.9 nm, the continuum's
Delta and the chiral weight's normalisation distance), n = +-2, formed quasi-statically.

Measured 2026-12-02 (n = 2; bead / continuum):

| alpha | torque sum (pN nm) | z(+2) - z(-2) (nm) | contact +2 / -2 (alpha = 0: 4.897 nm) |
| 0.5   | -3.07 / -2.56 (+20 %) | +2.04 / +0.068  | 4.897 / 6.020 |
| 1     | -4.78 / -4.72 (+1.3 %) | +3.08 / -0.172 | 4.897 / 6.514 |
| 2     | -8.00 / -9.20 (-13 %) | +3.97 / -1.119  | 4.897 / 7.156 |

The favoured (right-handed) braid stays at the alpha = 0 contact (0.0004 nm). The disfavoured
braid opens: its positive chiral energy alpha tan(|eta|/2) (~0.23 alpha pN per nm of braid)
falls beyond D_c with the weight's range rho = 0.446 nm, and the largest slope of that fall,
0.37 alpha tan(|eta|/2) / rho ~ 0.19 alpha pN/nm, beats the long braid's contact pressure
(~0.046 pN/nm) for alpha > ~0.25 pN; the strands settle where the slope equals the pressure,
x e^{-x/rho} / rho^2 = p / (alpha tan(|eta|/2)): predicted gaps 1.2, 1.6, 2.0 nm against the
measured 1.12, 1.62, 2.26 nm. The continuum braid has a hard contact and cannot open, so its
z(+n) - z(-n) and the bead model's differ in sign. Those comparisons are plain xfails quoting
the numbers (docs/chirality.md). At 20 pN (ten times the contact pressure) alpha = 0.5 pN
passes all three checks (torque sum -2.29 against -2.62, dz +0.038 against +0.009, contact
shift 0.001 nm): test_checks_pass_at_20_pN (slow).
"""

import inspect

import pytest

from dnabraid.scenes import make_scene
from dnabraid.validation import chiral_zero_t as cz

N = 2.0


@pytest.fixture(scope="module")
def contact0():
    return cz.baseline(N).contact_nm


@pytest.fixture(scope="module")
def row1(contact0):
    return cz.check_alpha(N, 1.0, contact0)


def test_alpha_zero_contact_is_the_capsule_distance(contact0):
    """Unloaded capsules touch at D_c; the braid's pressure compresses them by < 0.01 nm."""
    assert 4.9 - 0.01 < contact0 <= 4.9


def test_favoured_hand_keeps_the_contact_distance(row1, contact0):
    """(a) for the favoured hand: the chiral weight is flat at contact, so it does not pull the
    right-handed braid's strands together (the old weight did, by 0.6 nm)."""
    assert row1["contact_plus_nm"] == pytest.approx(contact0, abs=cz.CONTACT_TOL_NM)
    assert row1["catenation"][0] == pytest.approx(N, abs=1e-3)
    assert row1["catenation"][1] == pytest.approx(-N, abs=1e-3)


def test_torque_sum_matches_the_continuum(row1):
    """(c) at alpha = 1 pN: Gamma(+2) + Gamma(-2) within 15 % (measured -4.78 against -4.72)."""
    assert row1["continuum_success"]
    bead, cont = row1["bead_torque_sum_pN_nm"], row1["cont_torque_sum_pN_nm"]
    assert bead < 0 and cont < 0
    assert bead == pytest.approx(cont, rel=cz.TORQUE_RTOL)


@pytest.mark.xfail(reason="the disfavoured hand opens at T = 0: contact at -2 is 6.51 nm "
                          "against 4.90 at alpha = 0 (tolerance 0.02 nm), where the decay of "
                          "the chiral weight (range 0.446 nm) outweighs the contact pressure "
                          "(~0.046 pN/nm)", strict=False)
def test_disfavoured_hand_keeps_the_contact_distance(row1, contact0):
    assert row1["contact_minus_nm"] == pytest.approx(contact0, abs=cz.CONTACT_TOL_NM)


@pytest.mark.xfail(reason="z(+2) - z(-2) = +3.08 nm in the bead model against -0.172 nm in "
                          "the continuum at alpha = 1 pN (tolerance: same sign, 30 % + "
                          "0.05 nm): the disfavoured braid opens by 1.6 nm", strict=False)
def test_extension_asymmetry_matches_the_continuum(row1):
    assert row1["b_ok"], row1


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [
    pytest.param(0.5, marks=pytest.mark.xfail(
        reason="torque sum -3.07 against the continuum's -2.56 pN nm (+20 %, tolerance 15 %); "
               "the disfavoured hand is open by 1.1 nm", strict=False)),
    2.0,  # -8.00 against -9.20 (-13 %), the disfavoured hand open by 2.26 nm
])
def test_torque_sum_other_alphas(contact0, alpha):
    r = cz.check_alpha(N, alpha, contact0)
    assert r["contact_plus_nm"] == pytest.approx(contact0, abs=cz.CONTACT_TOL_NM)
    assert r["c_ok"], r


@pytest.mark.slow
def test_checks_pass_at_20_pN():
    """Ten times the force, ten times the contact pressure: at alpha = 0.5 pN both hands keep
    the alpha = 0 contact and (a), (b), (c) hold (measured: shift 0.001 nm, dz +0.038 against
    +0.009 nm, torque sum -2.29 against -2.62 pN nm). At alpha = 1 pN (b) misses by 0.008 nm
    (+0.076 against +0.014) and at 2 pN the disfavoured hand opens by 0.66 nm
    (workflows/results/chiral_zero_t.md)."""
    over = {"force_pN": 20.0}
    c0 = cz.baseline(N, overrides=over).contact_nm
    r = cz.check_alpha(N, 0.5, c0, overrides=over)
    assert r["a_ok"] and r["b_ok"] and r["c_ok"], r


# --- the scene key ---------------------------------------------------------------------------


def test_capsule_contact_builds_and_refuses_moves():
    """contact = 'capsules': a capsule term in the excluded-volume group, no bead WCA between
    the strands, the chiral weight flat to D_c; the Metropolis moves cannot evaluate it."""
    from dnabraid.scenes.base import SceneError

    s = make_scene("braid", {"contact": "capsules", "alpha": 1.0})
    m = s.build()
    assert "capsule" in m.forces and "capsule" in m.rebuild_forces
    names = {m.system.getForce(i).getName(): m.system.getForce(i)
             for i in range(m.system.getNumForces())}
    wca = names["wca"]
    excl = {tuple(sorted(wca.getExclusionParticles(k))) for k in range(wca.getNumExclusions())}
    c0, c1 = m.chains
    assert all((min(int(i), int(j)), max(int(i), int(j))) in excl for i in c0 for j in c1)
    make = m.rebuild_forces["chiral"].make  # the chiral weight is flat to the capsules' D_c
    assert inspect.signature(make).parameters["contact"].default == s.effective_diameter_nm
    assert make_scene("braid", {}).contact == "beads"
    with pytest.raises(SceneError, match="mc_moves"):
        make_scene("braid", {"contact": "capsules", "mc_moves": 10})
    with pytest.raises(SceneError, match="contact"):
        make_scene("braid", {"contact": "tubes"})
