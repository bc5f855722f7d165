"""Zero-temperature bead braid (dnabraid.validation.crosscheck) on a small braid: 2 x 60 nm, tethers
10 nm apart, 150 mM (d = 4.9 nm), F = 2 pN, one turn; each braid takes ~1 s."""

import pytest

from dnabraid.validation.crosscheck import compare_tweezer, zero_temperature_braid

SMALL = {"length_nm": 60.0, "tether_separation_nm": 10.0}


def test_mirror_symmetry_without_chirality():
    """At alpha = 0 braiding left- and right-handed are mirror images: the same extension,
    opposite torque and catenation; the strands touch at the WCA contact, compressed below
    2^(1/6) d by the braid's pressure."""
    p = zero_temperature_braid(1.0, SMALL, increments=10)
    m = zero_temperature_braid(-1.0, SMALL, increments=10)
    assert p.catenation == pytest.approx(1.0, abs=1e-3)
    assert m.catenation == pytest.approx(-1.0, abs=1e-3)
    assert p.extension_nm == pytest.approx(m.extension_nm, abs=1e-6)
    assert p.torque_pN_nm == pytest.approx(-m.torque_pN_nm, abs=1e-6)
    assert p.torque_pN_nm > 0  # the trap holds n > 0 against the braid's untwisting torque
    assert p.diameter_nm < p.contact_nm < 2 ** (1 / 6) * p.diameter_nm


#: Chiral strength of the tests below (pN): large enough that the torque sum is ~5x the
#: minimiser's path noise (~3 %) on these short strands.
ALPHA = 5.0


def test_chiral_braid_is_the_mirror_image_at_opposite_chirality():
    """The model is mirror symmetric with alpha -> -alpha (chiral_force is odd in alpha, the
    rest even; the straight start and the quasi-static path are mirror images): the braid at
    (+n, alpha) and at (-n, -alpha) have the same extension and contact and opposite torque
    and catenation. Tolerances: the minimiser stops at slightly different points on the two
    paths (measured: 1e-11 with 10 increments, 0.5 % of the torque and 0.01 nm with 40);
    a broken symmetry gives the other hand's braid, (-n, +alpha): torque -12.5 instead of
    +9.7 pN nm, extension 0.7 nm and contact 1.9 nm off."""
    p = zero_temperature_braid(1.0, {**SMALL, "alpha": ALPHA}, increments=10)
    m = zero_temperature_braid(-1.0, {**SMALL, "alpha": -ALPHA}, increments=10)
    assert p.alpha_pN == -m.alpha_pN == ALPHA
    assert p.torque_pN_nm < 0  # the chiral drive (~ -Delta alpha / 2) exceeds +7.6 at alpha = 0
    assert p.catenation == pytest.approx(-m.catenation, abs=1e-3)
    assert p.torque_pN_nm == pytest.approx(-m.torque_pN_nm, rel=0.02)
    assert p.extension_nm == pytest.approx(m.extension_nm, abs=0.1)
    assert p.contact_nm == pytest.approx(m.contact_nm, abs=0.1)


def test_chiral_torque_sum_has_the_continuum_sign_and_size():
    """alpha > 0 favours right-handed braids: less torque holds +n than -n, so the torque
    sum Gamma(+n) + Gamma(-n) is negative in both models, and of the same size. Measured
    (2026-12): bead -21.9, continuum -25.8 pN nm (ratio 0.85). Not a 15 % match: alpha is
    normalised at Delta = 4.9 nm but these strands touch at ~5.5 nm, where the chiral weight
    (range 0.446 nm at 150 mM, docs/chiral_range.md) is smaller; the tolerance is a factor
    of 2, far from the measured ratio, and fails for a wrong sign or a missing term."""
    r = compare_tweezer(1.0, ALPHA, SMALL)
    assert r["plus"]["continuum_success"] and r["minus"]["continuum_success"]
    assert r["plus"]["bead_catenation"] == pytest.approx(1.0, abs=1e-3)
    assert r["minus"]["bead_catenation"] == pytest.approx(-1.0, abs=1e-3)
    bead, cont = r["bead_torque_sum_pN_nm"], r["continuum_torque_sum_pN_nm"]
    assert bead < 0 and cont < 0
    assert 0.5 < bead / cont < 2.0, (bead, cont)
    # continuum: the chiral torque per hand is ~ -r alpha / cos(theta) with r = Delta/2, so
    # the sum is close to -2 r alpha = -Delta alpha (tests/test_handedness.py, 10 % there)
    assert cont == pytest.approx(-r["contact_nm"] * ALPHA, rel=0.25)
