"""Zero-temperature bead braid (dnabraid.crosscheck) on a small braid: 2 x 60 nm, tethers
10 nm apart, 150 mM (d = 4.9 nm), F = 2 pN, one turn; each braid takes ~1 s."""

import pytest

from dnabraid.crosscheck import compare_tweezer, zero_temperature_braid

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


@pytest.mark.xfail(strict=True, reason=(
    "since the chiral weight decays with the first helical harmonic's range (0.446 nm at "
    "150 mM instead of the Debye length, docs/chiral_range.md, 2026-11-30), alpha is still "
    "normalised at Delta = 4.9 nm but these strands touch at ~5.5 nm: measured bead -21.9 vs "
    "continuum -25.8 pN nm (-15.1 %, just outside 15 %). Comparing like with like needs "
    "alpha evaluated at the bead contact distance (open question in the issue note)"))
def test_chiral_torque_sum_matches_the_continuum():
    """alpha > 0 favours right-handed braids: less torque holds +n than -n, so the torque
    sum Gamma(+n) + Gamma(-n) is negative; the bead model's sum is the continuum braid's
    (dnabraid.continuum.tweezer at the bead model's contact distance) within 15 %."""
    r = compare_tweezer(1.0, 5.0, SMALL)
    assert r["plus"]["continuum_success"] and r["minus"]["continuum_success"]
    assert r["plus"]["bead_catenation"] == pytest.approx(1.0, abs=1e-3)
    assert r["minus"]["bead_catenation"] == pytest.approx(-1.0, abs=1e-3)
    bead, cont = r["bead_torque_sum_pN_nm"], r["continuum_torque_sum_pN_nm"]
    assert bead < 0 and cont < 0
    assert bead == pytest.approx(cont, rel=0.15)
