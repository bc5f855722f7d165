"""Zero-temperature chirality cross-check on the long braid with the capsule contact
(dnabraid.validation.chiral_zero_t; table in workflows/results/chiral_zero_t.md).

2 x 200 nm, 2 pN, tethers 40 nm, 150 mM, contact = capsules (D_c = 4.9 nm, the continuum's
Delta and the chiral weight's normalisation distance), n = +-2, formed quasi-statically.
The reference is the soft-range continuum (dnabraid.continuum.soft_tweezer: the bead model's
weight w(d), the axis distance free); the hard-contact continuum (solve_tweezer at D_c) cannot
open and is kept for comparison.

Measured 2026-12-03 (n = 2; bead / hard / soft):

| alpha | torque sum (pN nm)     | z(+2) - z(-2) (nm)     | contact -2 bead / soft (nm) |
| 0.5   | -3.07 / -2.56 / -3.07  | +2.04 / +0.07 / +2.18  | 6.020 / 6.073               |
| 1     | -4.78 / -4.72 / -4.55  | +3.08 / -0.17 / +2.85  | 6.514 / 6.565               |
| 2     | -8.00 / -9.20 / -7.03  | +3.96 / -1.12 / +3.10  | 7.156 / 7.214               |

The favoured hand stays in contact (4.897 nm, the alpha = 0 value); the disfavoured hand opens
by the gap the soft continuum predicts (bead 0.05-0.06 nm below it: the chords' offset,
tolerance 0.16-0.20 nm), so the issue's check (a) cannot hold for it (the flat weight itself
predicts the opening) and (a') replaces it; (b) and (c) hold against the soft continuum.
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
    """(c) at alpha = 1 pN: Gamma(+2) + Gamma(-2) within 15 % of the soft continuum's
    (measured -4.78 against -4.55, +5 %; the hard continuum's -4.72)."""
    assert row1["continuum_success"] and row1["soft_success"]
    bead, soft = row1["bead_torque_sum_pN_nm"], row1["soft_torque_sum_pN_nm"]
    assert bead < 0 and soft < 0
    assert bead == pytest.approx(soft, rel=cz.TORQUE_RTOL)
    assert row1["c_ok"]


def test_disfavoured_hand_opens_by_the_soft_continuums_gap(row1, contact0):
    """(a') at alpha = 1 pN: the disfavoured braid is open (contact -2 more than rho = 0.446 nm
    beyond the alpha = 0 value: the issue's (a) fails, as the flat weight predicts) and its
    contact distance is the soft continuum's axis distance within the tolerance of
    contact_tolerance_nm (measured 6.514 against 6.565 nm, tolerance 0.19 nm); the favoured
    hand is the soft continuum's too (4.897 against 4.901)."""
    assert row1["contact_minus_nm"] - contact0 > 0.446
    assert row1["a_ok"] is False
    for tag in ("plus", "minus"):
        dev = row1[f"contact_{tag}_nm"] - row1[f"soft_axis_{tag}_nm"]
        assert abs(dev) <= row1[f"contact_tol_{tag}_nm"]["total"], (tag, dev)
    assert row1["a2_ok"]


def test_extension_asymmetry_matches_the_soft_continuum(row1):
    """(b) at alpha = 1 pN: z(+2) - z(-2) has the soft continuum's sign (positive: the open
    disfavoured braid is shorter) and lies within 30 % + 0.05 nm of it (measured +3.08
    against +2.85 nm); the hard continuum's is -0.17 nm, the other sign."""
    assert row1["bead_dz_nm"] > 0 and row1["soft_dz_nm"] > 0 and row1["cont_dz_nm"] < 0
    assert row1["b_ok"], row1
    assert not row1["b_hard_ok"]


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.5, 2.0])
def test_checks_against_the_soft_continuum_other_alphas(contact0, alpha):
    """(a'), (b), (c) at alpha = 0.5 and 2 pN (measured: dz +2.04 / +3.96 against the soft
    +2.18 / +3.10 nm; torque sums -3.07 / -8.00 against -3.07 / -7.03 pN nm, +0.2 / +13.8 %;
    contact -2 at 6.020 / 7.156 against 6.073 / 7.214 nm); the favoured hand keeps the
    alpha = 0 contact (a)."""
    r = cz.check_alpha(N, alpha, contact0)
    assert r["contact_plus_nm"] == pytest.approx(contact0, abs=cz.CONTACT_TOL_NM)
    assert r["a2_ok"] and r["b_ok"] and r["c_ok"], r


@pytest.mark.slow
def test_checks_pass_at_20_pN():
    """Ten times the force, ten times the contact pressure: at alpha = 0.5 pN both hands keep
    the alpha = 0 contact, and the soft continuum is the hard one (both in contact): (a),
    (a'), (b), (c) hold (measured: shift 0.001 nm, dz +0.038 against +0.009 nm, torque sum
    -2.29 against -2.62 pN nm; workflows/results/chiral_zero_t.md)."""
    over = {"force_pN": 20.0}
    c0 = cz.baseline(N, overrides=over).contact_nm
    r = cz.check_alpha(N, 0.5, c0, overrides=over)
    assert r["soft_dz_nm"] == pytest.approx(r["cont_dz_nm"], abs=1e-9)
    assert r["a_ok"] and r["a2_ok"] and r["b_ok"] and r["c_ok"], r


@pytest.mark.slow
def test_metastable_open_branch_at_20_pN():
    """20 pN, alpha = 2 pN: the soft continuum's disfavoured hand has two minima, contact
    (lower by 5.9 pN nm) and open by 0.667 nm; turned from apart it stops in the open one, and
    so does the bead braid (measured contact -2 at 5.536 against 5.567 nm; dz +1.150 against
    +1.077 nm, the hard continuum's -0.017; torque sum -11.90 against -12.05 pN nm)."""
    over = {"force_pN": 20.0}
    c0 = cz.baseline(N, overrides=over).contact_nm
    r = cz.check_alpha(N, 2.0, c0, overrides=over)
    assert len(r["soft_minima_minus"]) == 2 and r["soft_minima_minus"][0]["gap_nm"] == 0.0
    assert r["soft_axis_minus_nm"] - r["D_c_nm"] > 0.446
    assert r["contact_minus_nm"] - c0 > 0.446
    assert r["a2_ok"] and r["b_ok"] and r["c_ok"], r
    assert not r["b_hard_ok"]


@pytest.mark.slow
@pytest.mark.parametrize("force,turns,alpha", [
    pytest.param(20.0, 2.0, 1.0, marks=pytest.mark.xfail(
        reason="(b) at 20 pN, alpha = 1 pN: dz +0.076 nm against the soft (= hard) "
               "continuum's +0.014 nm, tolerance 0.054 nm (misses by 0.008 nm); both hands in "
               "contact", strict=False)),
    pytest.param(2.0, 1.0, 1.0, marks=pytest.mark.xfail(
        reason="(b) at n = 1, alpha = 1 pN: dz +0.718 nm against the soft continuum's "
               "+0.070 nm (tolerance 0.071 nm; alpha = 0.5: +0.690 against +0.427, alpha = 2: "
               "+0.023 against +0.150); at one turn the ply is short and dz is a small "
               "difference of the tails, straight and chiral-free in the continuum",
        strict=False)),
])
def test_extension_asymmetry_rows_that_miss(force, turns, alpha):
    over = {"force_pN": force}
    c0 = cz.baseline(turns, overrides=over).contact_nm
    r = cz.check_alpha(turns, alpha, c0, overrides=over)
    assert r["b_ok"], r


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
    # the compiled moves evaluate the capsules too (tests/test_kernels_segments.py)
    assert make_scene("braid", {"contact": "capsules", "mc_moves": 10}).build().moves
    with pytest.raises(SceneError, match="contact"):
        make_scene("braid", {"contact": "tubes"})
