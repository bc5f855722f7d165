"""The tether with a wall and excluded volume against an independent reference.

:func:`dnabraid.validation.tether_reference.tether_reference` weights exact draws of the
free discrete WLC by exp(-(U_wall + U_wca)/kT): an exact importance sample of the full model
that uses no dynamics and no Monte Carlo moves. The scene (Brownian dynamics + Metropolis
moves on local energies) must agree with it.
"""

import math

import pytest

from dnabraid.scenes import make_scene
from dnabraid.validation.tether_reference import tether_reference


def test_reference_without_wall_and_excluded_volume_is_the_exact_wlc():
    """Without the two terms every weight is 1: the reference is the plain mean of exact
    draws, within its error of the transfer-matrix value."""
    from dnabraid.continuum.wlc import discrete_wlc_exact

    s = make_scene("tether", {"length_nm": 100.0, "force_pN": 0.5, "surface": False,
                              "self_avoidance": False})
    r = tether_reference(s, n_draws=4000, batches=20, seed=5)
    d = s.dna()
    exact = discrete_wlc_exact(s.force_pN, s.n_beads - 1, s.bead_spacing_nm, d.kappa_kT, d.kT,
                               stretch_k_pN_per_nm=d.k_bond)["extension_nm"]
    assert r["kish_fraction"] == pytest.approx(1.0)
    assert abs(r["extension_nm"] - exact) < 4 * r["extension_sem_nm"]


def test_tether_with_wall_and_excluded_volume_matches_the_reference(tmp_path):
    """150 nm at 0.2 pN, where the wall lifts the chain by ~7 nm (free 93.2 nm, reference
    100.4 +- 0.3 nm): 4 replicas of BD + moves (seed 2: 100.43 +- 0.44 nm, converged)
    agree within 3 combined standard errors."""
    s = make_scene("tether", {"length_nm": 150.0, "force_pN": 0.2, "steps": 40000,
                              "equilibration_steps": 2000, "workers": 1,
                              "frame_interval": 40000, "seed": 2})
    ref = tether_reference(s, n_draws=8000, batches=20, seed=12345)
    assert ref["extension_nm"] - ref["free_extension_nm"] > 5.0  # the wall matters here
    assert ref["kish_fraction"] > 0.3
    pt = s.run(str(tmp_path / "t"))["points"][0]
    e = pt["extension_nm"]
    assert pt["converged"], pt["convergence_reason"]
    assert abs(e["mean"] - ref["extension_nm"]) < 3 * math.hypot(e["sem"],
                                                                ref["extension_sem_nm"])
