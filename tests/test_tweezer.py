"""Tweezer scenes end to end: worm-like chain, braid symmetry, catenation, outputs, resume.

Statistical tests use fixed seeds and tolerances built from the run's own standard errors
(autocorrelation-corrected): |sim - theory| < Z_TOL x SEM + a named model tolerance.
"""

import json
import math
import os

import numpy as np
import pytest
from conftest import without_guard_roundoff

from dnabraid.analysis.geometry import bending_cosines
from dnabraid.continuum.wlc import discrete_wlc_extension
from dnabraid.run.engine import Engine, SimulationBlowUp
from dnabraid.scenes import make_scene
from dnabraid.scenes.braid import LONG_BRAID

#: |simulation - theory| must be below Z_TOL standard errors of the mean ...
Z_TOL = 4.0
#: ... plus this fraction of the theory value (Euler-Maruyama bias at the default step,
#: excluded volume, first-order treatment of bond stretching in the theory).
MODEL_RTOL = 0.01


def discrete_theory(s):
    m = s.build()
    p = m.params
    return discrete_wlc_extension(s.force_pN, s.n_beads - 1, s.bead_spacing_nm, p["kappa_kT"],
                                  p["kT_pN_nm"], stretch_k_pN_per_nm=p["k_bond_pN_per_nm"])


# The slowest mode of a tether is the pivot of the whole chain about its surface hinge:
# tau ~ zeta b^2 N^3 / (3 F L) (measured ~1e6 steps for 100 nm at 1 pN) for Brownian
# dynamics alone; the scene's default Metropolis moves (mc_moves = 500 per report interval)
# decorrelate it in a few report intervals. Steps of the slow cases chosen by a probe
# (seed 7, 2026-12-06, 2 cores): n_eff 2414 (0.1 pN / 20 nm, 3e5 steps, 71 s with numba's
# compile), 1775 (1 pN / 100 nm, 3e5, 25 s), 106 (10 pN / 300 nm, 2e5, 23 s); z = +1.35,
# -2.02, -0.39 against the exact discrete WLC. They ran 1.2e7-4e7 steps (~45 min) before.
@pytest.mark.parametrize("force, length, steps", [
    (3.0, 25.0, 600_000),
    # covered in the default suite by tests/test_calibration.py (replicas against the exact
    # answer); kept as a long single-run check
    pytest.param(10.0, 50.0, 600_000, marks=pytest.mark.slow),
    pytest.param(0.1, 20.0, 300_000, marks=pytest.mark.slow),
    pytest.param(1.0, 100.0, 600_000, marks=pytest.mark.slow),
    pytest.param(10.0, 300.0, 600_000, marks=pytest.mark.slow),
])
def test_tether_matches_discrete_wlc(tmp_path, force, length, steps):
    s = make_scene("tether", {"force_pN": force, "length_nm": length, "steps": steps,
                              "equilibration_steps": 20_000, "surface": False, "seed": 7,
                              "frame_interval": 10_000, "replicas": 1})
    summ = s.run(str(tmp_path / "run"))
    ext = summ["points"][0]["extension_nm"]
    theory = discrete_theory(s)["extension_nm"]
    err = abs(ext["mean"] - theory)
    tol = Z_TOL * ext["sem"] + MODEL_RTOL * theory
    assert err < tol, f"F={force}: sim {ext['mean']:.2f}+-{ext['sem']:.2f} vs {theory:.2f} nm"
    # the SEM must be meaningful: sampling covers many correlation times (measured 17.8 at
    # 3 pN / 25 nm with the exact start: the within-run diagnostic, no transient to cut)
    assert ext["n_eff"] > 15


def test_persistence_from_bending_cosines(tmp_path):
    """<cos beta> between consecutive bonds gives lp = -b / ln<cos beta> = 50 nm (F -> 0.05 pN).

    Replicas from exact starts, the error from their scatter (Student t, 6 replicas): a
    single 200k-step run read lp = 56.1 +- 1.1 nm with its own autocorrelation error, while
    2M steps give 50.5 +- 1.2 (workflows/results/integrator_bias.md): the mean cosine of a
    floppy chain has a slow component one short run does not sample.
    """
    import glob

    import MDAnalysis as mda
    from scipy import stats

    R = 6
    s = make_scene("tether", {"force_pN": 0.05, "length_nm": 100.0, "steps": 20_000,
                              "equilibration_steps": 0, "surface": False, "seed": 3,
                              "frame_interval": 500, "replicas": R, "workers": 1})
    out = tmp_path / "run"
    s.run(str(out))
    means = []
    for dcd in sorted(glob.glob(str(out / "replicas" / "r*" / "points" / "*" / "trajectory.dcd"))):
        u = mda.Universe(str(out / "topology.pdb"), dcd)
        dna = u.select_atoms("chainID A")
        means.append(np.mean([bending_cosines(dna.positions / 10.0).mean()
                              for _ in u.trajectory]))
    assert len(means) == R
    m, sem = np.mean(means), np.std(means, ddof=1) / math.sqrt(R)
    half = stats.t.ppf(0.995, R - 1) * sem  # 99 % interval
    exact = math.exp(-s.bead_spacing_nm / s.persistence_nm)
    assert abs(m - exact) < half, (m, sem, exact)
    lp = -s.bead_spacing_nm / math.log(m)
    assert lp == pytest.approx(s.persistence_nm, rel=0.15)


@pytest.fixture(scope="module")
def braid_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("braid") / "run"
    s = make_scene("braid", {"length_nm": 150.0, "tether_separation_nm": 30.0,
                             "turns": [-2, 0, 2], "steps": 150_000,
                             "equilibration_steps": 30_000, "seed": 11, "replicas": 1})
    return s, str(out), s.run(str(out))


@pytest.mark.integration
def test_braid_symmetric_at_zero_chirality(braid_run):
    s, out, summ = braid_run
    pts = {p["turns"]: p for p in summ["points"]}
    zp, zm = pts[2.0]["extension_nm"], pts[-2.0]["extension_nm"]
    dz = zp["mean"] - zm["mean"]
    assert abs(dz) < Z_TOL * math.hypot(zp["sem"], zm["sem"]) + 0.01 * zp["mean"], (zp, zm)
    tp, tm = pts[2.0]["torque_pN_nm"], pts[-2.0]["torque_pN_nm"]
    assert abs(tp["mean"] + tm["mean"]) < Z_TOL * math.hypot(tp["sem"], tm["sem"]) + 2.0
    # braiding shortens the molecule pair and costs torque of the sign of the turns
    assert zp["mean"] < pts[0.0]["extension_nm"]["mean"] - 5 * zp["sem"]


@pytest.mark.integration
def test_catenation_follows_turns(braid_run):
    s, out, summ = braid_run
    for p in summ["points"]:
        # catenation = bead angle / 2 pi exactly (no passage); the bead lags the trap by
        # torque / K turns / 2 pi (K = the scene's trap stiffness, 2000 pN nm by default)
        lag = abs(p["torque_pN_nm"]["mean"]) / (2 * math.pi * s.trap_stiffness_pN_nm)
        cat = p["catenation"]
        assert abs(cat["mean"] - p["turns"]) < lag + Z_TOL * cat["sem"] + 1e-3, (p, lag)


@pytest.mark.integration
def test_run_directory_is_self_describing(braid_run):
    import MDAnalysis as mda

    from dnabraid.analysis.geometry import catenation_number

    s, out, summ = braid_run
    for f in ("scene.toml", "topology.pdb", "trajectory.dcd", "observables.csv", "summary.json",
              "extension_torque.png"):
        assert os.path.getsize(os.path.join(out, f)) > 0
    js = json.load(open(os.path.join(out, "summary.json")))
    for key in ("wall_time_s", "platform", "time_step_ps", "points"):
        assert key in js
    p0 = js["points"][0]
    for key in ("turns", "extension_nm", "torque_pN_nm", "catenation"):
        assert key in p0
    assert set(p0["extension_nm"]) >= {"mean", "sem"}
    u = mda.Universe(os.path.join(out, "topology.pdb"), os.path.join(out, "trajectory.dcd"))
    n_frames = sum(p["n_frames"] for p in js["points"])
    assert u.trajectory.n_frames == n_frames
    a = u.select_atoms("chainID A")
    b = u.select_atoms("chainID B")
    assert len(a) == len(b) == s.n_beads
    u.trajectory[-1]
    ca = catenation_number(a.positions / 10.0, b.positions / 10.0)
    assert ca == pytest.approx(2.0, abs=0.05)  # last frame belongs to turns = +2 (sorted)
    header = open(os.path.join(out, "observables.csv")).readline()
    assert "extension_nm" in header and "torque_pN_nm" in header


@pytest.mark.integration
def test_resume_skips_finished_points(braid_run, tmp_path):
    """A finished point is not run again; a removed one is rerun from its start checkpoint
    and ends with the same numbers (the checkpoint holds the random-number state)."""
    s, out, summ = braid_run
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    pts = copy / "replicas" / "r00" / "points"
    victim = sorted(os.listdir(pts))[-1]  # the last point run (turns = +2)
    shutil.rmtree(pts / victim)
    kept = {f: os.path.getmtime(pts / f / "done.json") for f in os.listdir(pts)}
    summ2 = s.run(str(copy))
    for f, t in kept.items():
        assert os.path.getmtime(pts / f / "done.json") == t  # not rerun
    assert os.path.exists(pts / victim / "done.json")
    assert without_guard_roundoff(summ2["points"]) == without_guard_roundoff(summ["points"])


@pytest.mark.integration
def test_resume_refuses_a_different_scene(braid_run):
    from dnabraid.rundir import RunDirError

    s, out, summ = braid_run
    other = make_scene("braid", {"length_nm": 150.0, "tether_separation_nm": 30.0,
                                 "turns": [-2, 0, 2], "force_pN": 3.0, "replicas": 1})
    with pytest.raises(RunDirError, match="force_pN"):
        other.run(out)


def test_blow_up_names_step_and_term(tmp_path):
    s = make_scene("braid", {"length_nm": 100.0, "tether_separation_nm": 20.0})
    m = s.build()
    e = Engine.for_model(m, seed=1)
    e.minimise()
    e.integrator.setStepSize(e.integrator.getStepSize() * 40)  # far past stability
    with pytest.raises(SimulationBlowUp) as exc:
        for _ in range(200):
            e.advance(50, str(tmp_path))
    msg = str(exc.value)
    assert "step" in msg and exc.value.term in m.forces
    assert exc.value.saved and os.path.exists(exc.value.saved)


@pytest.mark.parametrize("n", [-3.0, -1.0, 1.0, 2.5])
def test_braid_start_built_at_its_catenation(n):
    """The independent protocol builds each braid at its turn value: the two-ply start has
    Gauss catenation n exactly, bonds of length b (to 3 %) and the attachment chord turned
    by n turns."""
    from dnabraid.geometry.curves import catenation_number

    s = make_scene("braid", {**LONG_BRAID, "turns": [n], "start_spread": 0.0})
    m = s.build()
    p = s.start_positions(m, n)
    c = m.chains
    assert catenation_number(p[c[0]], p[c[1]]) == pytest.approx(n, abs=1e-3)
    bl = np.linalg.norm(np.diff(p[c[0]], axis=0), axis=1)
    assert np.all(np.abs(bl / s.bead_spacing_nm - 1) < 0.03)
    chord = p[m.attachments[1]] - p[m.attachments[0]]
    assert math.atan2(chord[1], chord[0]) == pytest.approx(
        math.remainder(2 * math.pi * n, 2 * math.pi), abs=1e-6)


def test_braid_replicas_start_overdispersed():
    """Replicas' built starts differ (plateau steepness and a bow of the braid axis drawn from
    each replica's seed) so that R-hat can see a start the run has not forgotten; each start
    keeps catenation n exactly and the chord turned by n, and the same seed gives the same
    start (a resumed run rebuilds it)."""
    import dataclasses

    from dnabraid.geometry.curves import catenation_number

    s = make_scene("braid", {**LONG_BRAID, "turns": [1.0]})
    m = s.build()
    heights = []
    for seed in range(64, 72):
        sr = dataclasses.replace(s, seed=seed)
        p = sr.start_positions(m, 1.0)
        c = m.chains
        assert catenation_number(p[c[0]], p[c[1]]) == pytest.approx(1.0, abs=1e-3)
        chord = p[m.attachments[1]] - p[m.attachments[0]]
        assert abs(math.remainder(math.atan2(chord[1], chord[0]), 2 * math.pi)) < 1e-6
        heights.append(p[m.attachments].mean(axis=0)[2])
        np.testing.assert_array_equal(p, sr.start_positions(m, 1.0))
    # the common start (start_spread = 0) is 184.7 nm high; the spread is tens of nm
    assert np.ptp(heights) > 10.0
