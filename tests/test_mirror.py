"""Mirror-coupled replica pairs (dnabraid.analysis.mirror).

Without a chiral term the braid's energy is invariant under y -> -y, which maps turns n to
-n, negates catenation, bead angle and trap torque and keeps the extension. The image run
(start and noise mirrored) must then be the original's mirror sample by sample, so the
paired asymmetries vanish to round-off: an exact statement, not a tolerance on noise.
"""

import json

import numpy as np
import pytest

from dnabraid.analysis.mirror import paired_asymmetry
from dnabraid.scenes import SceneError, make_scene

SMALL = dict(length_nm=60.0, force_pN=2.0, tether_separation_nm=30.0, replicas=2,
             steps=3000, equilibration_steps=1000, report_interval=100, frame_interval=1000,
             seed=5, workers=1, mc_moves=0)
# Brownian dynamics alone (mc_moves = 0): OpenMM's single-precision positions leave the pair
# ~1e-5 nm apart, and with the default's Metropolis moves a decision near its threshold
# flips sooner or later and the pair decorrelates (measured 2026-12-06, seed 5, n = +-2:
# after 27 of 30 report intervals in one replica, not within 30 in the other). Pairs with
# moves stay valid in law (the paired estimator's error is the scatter of the pairs), not
# sample by sample; the moves' own covariance is tests/test_braid_mirror_moves.py.


def _pair(tmp_path, alpha, n=2.0, pack=0):
    out = {}
    for mode, turns in (("original", [n]), ("image", [-n])):
        make_scene("braid", dict(SMALL, alpha=alpha, mirror=mode, turns=turns,
                                 pack=pack)).run(str(tmp_path / mode))
        out[mode] = json.loads((tmp_path / mode / "summary.json").read_text())
    return out


@pytest.mark.parametrize("pack", [1, 2])
def test_mirror_pair_is_exact_without_chirality(tmp_path, pack):
    """Alone in its Context (pack = 1) or with the other replica packed beside it along x
    (pack = 2), the image is the original's mirror."""
    out = _pair(tmp_path, 0.0, pack=pack)
    assert any("packed" in x for x in out["image"]["notes"]) == (pack == 2)
    z = paired_asymmetry(out["original"], out["image"], "extension_nm")[0]
    g = paired_asymmetry(out["original"], out["image"], "torque_pN_nm")[0]
    c = paired_asymmetry(out["original"], out["image"], "catenation")[0]
    # round-off only (positions are single precision in OpenMM's CPU nonbonded kernels)
    assert abs(z["asymmetry"]) < 1e-6 and z["sem"] < 1e-6
    assert abs(g["asymmetry"]) < 1e-4
    assert abs(c["asymmetry"]) < 1e-8
    # the runs themselves are noisy: the plain estimator's error is not small
    assert z["sem_unpaired"] > 1e-3
    # and the series agree sample by sample, not only on average
    from dnabraid.run.reporters import read_csv

    a = read_csv(str(tmp_path / "original" / "observables.csv"))
    b = read_csv(str(tmp_path / "image" / "observables.csv"))
    np.testing.assert_allclose(a["extension_nm"], b["extension_nm"], atol=1e-5)
    np.testing.assert_allclose(a["torque_pN_nm"], -b["torque_pN_nm"], atol=1e-3)
    assert np.ptp(a["extension_nm"]) > 0.1  # a thermal series, not a frozen one


def test_paired_asymmetry_parity_and_bad_input():
    def run(turns, z, g, mode):
        return {"scene": {"mirror": mode}, "points": [
            {"turns": turns, "extension_nm": {"replica_means": z, "sem": 1.0},
             "torque_pN_nm": {"replica_means": g, "sem": 2.0}}]}

    o = run(1.0, [10.0, 12.0, 14.0], [5.0, 6.0, 7.0], "original")
    i = run(-1.0, [9.0, 11.0, 13.0], [-4.0, -5.0, -6.0], "image")
    z = paired_asymmetry(o, i, "extension_nm")[0]
    assert z["asymmetry"] == pytest.approx(1.0) and z["sem"] == pytest.approx(0.0)
    g = paired_asymmetry(o, i, "torque_pN_nm")[0]
    assert g["asymmetry"] == pytest.approx(1.0)
    assert g["sem_unpaired"] == pytest.approx(np.hypot(2.0, 2.0))
    with pytest.raises(ValueError, match="no point at turns = -1"):
        paired_asymmetry(o, run(-2.0, [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], "image"))
    with pytest.raises(ValueError, match="mirror = 'image'"):
        paired_asymmetry(o, o)
    with pytest.raises(ValueError, match="parity"):
        paired_asymmetry(o, i, "writhe")


def test_bad_mirror_value_is_refused():
    with pytest.raises(SceneError, match="mirror"):
        make_scene("braid", {"mirror": "left"})


def test_one_pair_is_refused():
    o = {"points": [{"turns": 1.0, "extension_nm": {"replica_means": [10.0], "sem": 1.0}}]}
    i = {"points": [{"turns": -1.0, "extension_nm": {"replica_means": [9.0], "sem": 1.0}}]}
    with pytest.raises(ValueError, match="at least 2 replica pairs"):
        paired_asymmetry(o, i)
