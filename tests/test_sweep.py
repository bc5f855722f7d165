"""Sweeps: validation up front, local vs Dask identity, resume after a kill, failures as data."""

from __future__ import annotations

import csv
import glob
import json
import math
import os
import signal
import subprocess
import sys
import time

import pytest

from dnabraid import sweep
from dnabraid.scenes import SceneError, scene_class

WORKFLOWS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                         "workflows")

# A tiny braid: 13 beads per strand, one replica, 7400 steps per point (~0.6 s
# single-threaded). Faster ramps (turn_rate 5e-4) let the strands pass through each other
# for some seeds.
TINY = {"length_nm": 60, "steps": 1000, "equilibration_steps": 200, "turns": [0, 1],
        "frame_interval": 500, "report_interval": 100, "turn_rate": 2e-4, "seed": 7,
        "replicas": 1}
#: The results.csv header of a tweezer sweep over salt_mM (unchanged since the first sweeps).
TWEEZER_HEADER = ["salt_mM", "turns", "extension_nm", "extension_sem_nm", "torque_pN_nm",
                  "torque_sem_pN_nm", "catenation", "catenation_sem", "n_samples", "status",
                  "error", "point"]


def _spec(grid, **fixed):
    return {"scene": "braid", "fixed": {**TINY, **fixed}, "grid": grid}


def _write_spec(path, text):
    path.write_text(text)
    return str(path)


# --------------------------------------------------------------------------------------
# bad specs fail before anything runs
# --------------------------------------------------------------------------------------
def test_unknown_scene_key_fails_whole_sweep(tmp_path):
    out = tmp_path / "sw"
    with pytest.raises(SceneError, match=r"grid point salt_mM=150__nonsense_key=1: unknown key"):
        sweep.run_sweep(_spec({"salt_mM": [150], "nonsense_key": [1]}), out=str(out))
    assert not out.exists(), "nothing may be written for an invalid sweep"


def test_bad_value_names_point_and_scene_message(tmp_path):
    with pytest.raises(sweep.SweepError, match=r"force_pN=-1: .*force_pN=-1.0 pN: .*> 0 pN"):
        sweep.load_spec(_spec({"force_pN": [1, -1]}), out=str(tmp_path / "sw"))


@pytest.mark.parametrize("text, match", [
    ('scene = "braid"\n', "empty grid"),
    ('scene = "braid"\n[grid]\n', "empty grid"),
    ('scene = "braid"\n[grid]\nsalt_mM = []\n', "non-empty list"),
    ('scene = "braid"\n[grid]\nsalt_mM = [10, 10]\n', "repeated values"),
    ('scene = "braid"\n[fixed]\nsalt_mM = 10\n[grid]\nsalt_mM = [10, 20]\n', "both in"),
    ('scene = "braid"\nsalt_mM = 10\n[grid]\nforce_pN = [1]\n', "unknown sweep spec key"),
    ('scene = "braid"\n[grid]\nturns = [0, 1]\n', "each value is a list"),
    ('scene = "braid"\n[grid\n', "not valid TOML"),
])
def test_bad_spec_clear_error(tmp_path, text, match):
    with pytest.raises(sweep.SweepError, match=match):
        sweep.load_spec(_write_spec(tmp_path / "s.toml", text))


def test_missing_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="sweep spec .* does not exist"):
        sweep.load_spec(str(tmp_path / "nope.toml"))
    spec = _write_spec(tmp_path / "s.toml", 'scene = "missing.toml"\n[grid]\nforce_pN = [1]\n')
    with pytest.raises(FileNotFoundError, match="neither a built-in scene"):
        sweep.load_spec(spec)


def test_spec_file_scene_relative_and_names(tmp_path):
    (tmp_path / "base.toml").write_text('scene = "braid"\nlength_nm = 60.0\n')
    spec = sweep.load_spec(_write_spec(
        tmp_path / "s.toml",
        'scene = "base.toml"\n[fixed]\nsteps = 1000\n[grid]\nforce_pN = [1, 2.5]\n'
        'turns = [[0, 1], [0, -1]]\n'))
    assert [p.name for p in spec.points] == [
        "force_pN=1__turns=0_1", "force_pN=1__turns=0_-1",
        "force_pN=2.5__turns=0_1", "force_pN=2.5__turns=0_-1"]
    assert all(p.scene.length_nm == 60.0 and p.scene.steps == 1000 for p in spec.points)
    assert spec.out == os.path.join("runs", "s")


def test_spec_toml_round_trip(tmp_path):
    spec = sweep.load_spec({"scene": "braid", "fixed": {"steps": 1000, "surface": False,
                                                       "length_nm": 200.0},
                            "grid": {"turns": [[0, 1], [0, -1]], "salt_mM": [10, 150.5]}},
                           out=str(tmp_path / "sw"))
    path = tmp_path / "again.toml"
    path.write_text(spec.to_toml())
    again = sweep.load_spec(str(path))
    assert (again.scene, again.fixed, again.grid, again.out) == (
        spec.scene, spec.fixed, spec.grid, spec.out)
    assert [p.scene for p in again.points] == [p.scene for p in spec.points]


@pytest.mark.parametrize("path", sorted(glob.glob(os.path.join(WORKFLOWS, "*.toml"))),
                         ids=os.path.basename)
def test_workflow_specs_validate(path):
    """The sweep specs in workflows/ load and every grid point validates (nothing runs)."""
    spec = sweep.load_spec(path)
    assert len(spec.points) >= 2
    assert spec.out == os.path.join("runs", os.path.splitext(os.path.basename(path))[0])


# --------------------------------------------------------------------------------------
# gathering: every scene gives a table of its own columns
# --------------------------------------------------------------------------------------
def _csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_tweezer_table_columns_unchanged(tmp_path):
    """Points not run yet give one pending row each, under the tweezer header of old."""
    spec = sweep.load_spec(_spec({"salt_mM": [100, 150]}), out=str(tmp_path / "sw"))
    os.makedirs(spec.out)
    rows = sweep.gather(spec)
    assert spec.columns == TWEEZER_HEADER
    table = _csv(tmp_path / "sw" / "results.csv")
    assert list(table[0]) == TWEEZER_HEADER
    assert [(r["salt_mM"], r["turns"], r["status"]) for r in table] == [
        ("100", "", "pending"), ("150", "", "pending")]
    assert [r["extension_nm"] for r in rows] == [None, None]


def test_knot_sweep_gives_its_own_table(tmp_path):
    """Bug: a sweep over the knot scene ran every point and then failed in gather with
    KeyError: 'points' (gather read the tweezer summary's per-turn points). The table now
    holds the knot scene's own columns: one row per point, measured against the theory
    R = sqrt(B / 2T) (Audoly, Clauvelin & Neukirch 2007, Eq. 1)."""
    spec = {"scene": "knot", "fixed": {"bead_spacing_nm": 1.0},
            "grid": {"tension_pN": [3.0, 5.0]}}
    res = sweep.run_sweep(spec, out=str(tmp_path / "knot"), workers=1)
    assert not res.failed, res.failed
    rows = _csv(res.table)
    assert list(rows[0]) == ["tension_pN", *scene_class("knot").row_columns,
                             "status", "error", "point"]
    assert [(r["point"], r["status"]) for r in rows] == [("tension_pN=3", "done"),
                                                         ("tension_pN=5", "done")]
    for r, tension in zip(rows, (3.0, 5.0)):
        radius = math.sqrt(1000.0 / (2 * tension))  # B = 1000 pN nm^2 (the default)
        assert float(r["radius_theory_nm"]) == pytest.approx(radius)
        # the table holds the point's own measurement (the bug was in gathering it)
        with open(os.path.join(str(tmp_path / "knot"), r["point"],
                               "summary.json")) as fh:
            own = json.load(fh)
        assert float(r["radius_apex_nm"]) == pytest.approx(own["measured"]["radius_apex_nm"])
        assert float(r["winding_turns"]) == pytest.approx(1.0, abs=0.01)
        assert r["converged"] == "True"
    assert os.path.isfile(res.figure)
    text = sweep.format_table(res.rows, ["tension_pN"])
    assert "radius_apex_nm" in text.splitlines()[0] and "extension_nm" not in text


def test_handedness_analysis_in_the_package():
    """z(+n) - z(-n) per point and the torque sum Gamma(+n) + Gamma(-n) across seeds."""
    rows = []
    for alpha, seed, dz, tsum in [(0.0, 1, 0.5, 4.0), (0.0, 2, -0.5, -2.0),
                                  (12.0, 1, 16.0, -40.0), (12.0, 2, 18.0, -50.0)]:
        for n, z, t in ((-2.0, 50.0, -100.0), (2.0, 50.0 + dz, 100.0 + tsum)):
            rows.append({"alpha": alpha, "seed": seed, "turns": n, "extension_nm": z,
                         "extension_sem_nm": 0.3, "torque_pN_nm": t, "torque_sem_pN_nm": 9.0,
                         "status": "done", "error": "", "point": f"alpha={alpha}__seed={seed}"})
    asym = sweep.asymmetry(rows, ["alpha", "seed"])
    assert [a["asymmetry_nm"] for a in asym] == pytest.approx([0.5, -0.5, 16.0, 18.0])
    assert asym[0]["n"] == 2.0 and asym[0]["asymmetry_sem_nm"] == pytest.approx(0.3 * 2**0.5)
    h = sweep.handedness_across_seeds(rows, 2.0)
    assert [r["group"] for r in h] == [0.0, 12.0] and [r["seeds"] for r in h] == [2, 2]
    assert h[0]["torque_sum_pN_nm"] == pytest.approx(1.0)
    assert h[0]["torque_sum_se_pN_nm"] == pytest.approx(3.0)
    assert h[1]["torque_sum_pN_nm"] == pytest.approx(-45.0)
    assert h[1]["t"] == pytest.approx(-9.0)
    assert h[1]["delta_z_nm"] == pytest.approx(17.0)
    text = sweep.format_table(rows, ["alpha", "seed"])
    assert "z(+n) - z(-n)" in text and "16.00 +- 0.42 nm" in text


# --------------------------------------------------------------------------------------
# running
# --------------------------------------------------------------------------------------


@pytest.mark.integration
def test_local_and_dask_give_identical_tables(tmp_path):
    distributed = pytest.importorskip(
        "distributed", reason="dask.distributed not installed (pip install 'dnabraid[distributed]')")
    spec = _spec({"salt_mM": [100, 150], "force_pN": [1, 2]})
    local = sweep.run_sweep(spec, out=str(tmp_path / "local"), workers=2)
    assert not local.failed
    with distributed.LocalCluster(processes=True, n_workers=2, threads_per_worker=1,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = sweep.run_sweep(spec, out=str(tmp_path / "dask"), scheduler=client)
    assert not remote.failed
    a = (tmp_path / "local" / "results.csv").read_text()
    b = (tmp_path / "dask" / "results.csv").read_text()
    assert a == b
    rows = _csv(tmp_path / "local" / "results.csv")
    assert len(rows) == 4 * 2  # points x turn values
    assert list(rows[0])[:4] == ["salt_mM", "force_pN", "turns", "extension_nm"]
    assert {r["status"] for r in rows} == {"done"}
    # one turn of braiding shortens the tether and catenates the strands once
    for r in rows:
        if float(r["turns"]) == 1.0:
            assert abs(float(r["catenation"]) - 1.0) < 0.1
    assert os.path.isfile(local.figure)
    # the trajectories are readable through MDAnalysis, frames split per turn value
    ana = sweep.analyse_sweep(str(tmp_path / "local"))
    assert len(ana) == 8 and all(r["n_frames"] == 2 for r in ana)
    for r, t in zip(ana, rows):
        assert float(t["turns"]) == r["turns"]
        assert abs(r["catenation"] - float(t["catenation"])) < 0.1


def test_kill_midway_then_resume(tmp_path):
    spec_path = tmp_path / "kill.toml"
    # longer sampling (~1.5 s a point) so that the kill lands inside the second point
    fixed = "\n".join(f"{k} = {v!r}".replace("'", '"')
                      for k, v in {**TINY, "steps": 5000}.items())
    spec_path.write_text(f'scene = "braid"\nout = "{tmp_path / "sw"}"\n[fixed]\n{fixed}\n'
                         "[grid]\nforce_pN = [1, 1.5, 2]\n")
    spec = sweep.load_spec(str(spec_path))
    first = os.path.join(spec.out, spec.points[0].name, "summary.json")
    proc = subprocess.Popen([sys.executable, "-m", "dnabraid.cli", "sweep", str(spec_path),
                             "--workers", "1", "--quiet"], start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        # wait for the first point however slow the machine: the only limit is a hang guard
        # 100x the expected time (~3 s); a sweep that exits first fails the asserts below
        hang_guard = time.monotonic() + 300
        while not os.path.exists(first) and proc.poll() is None \
                and time.monotonic() < hang_guard:
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the CLI and its worker process
        proc.wait()
    assert os.path.exists(first), "the sweep exited (or hung) before its first point finished"
    mtime = os.stat(first).st_mtime_ns
    assert not all(os.path.exists(os.path.join(spec.out, p.name, "summary.json"))
                   for p in spec.points), "the sweep finished before it was killed"
    res = sweep.run_sweep(spec, workers=1)
    assert os.stat(first).st_mtime_ns == mtime, "a finished point was run again"
    assert res.status[spec.points[0].name]["skipped"] is True
    assert all(v["status"] == "done" for v in res.status.values())
    assert len([r for r in res.rows if r["status"] == "done"]) == 3 * 2
    # a third invocation runs nothing
    again = sweep.run_sweep(spec, workers=1)
    assert all(v["skipped"] for v in again.status.values())


def test_failing_point_recorded_others_finish(tmp_path):
    # a trap too soft to hold the braid's torque while the turns are ramped: valid scene,
    # blows up at run time
    spec = _spec({"trap_stiffness_pN_nm": [20000, 1]}, protocol="ramp")
    res = sweep.run_sweep(spec, out=str(tmp_path / "sw"), workers=2)
    ok, bad = "trap_stiffness_pN_nm=20000", "trap_stiffness_pN_nm=1"
    assert res.status[ok]["status"] == "done"
    assert res.status[bad]["status"] == "failed"
    err = res.status[bad]["error"]
    assert err["type"] == "SimulationBlowUp" and "slipped in the rotational trap" in err["message"]
    with open(tmp_path / "sw" / sweep.STATUS_FILE) as fh:
        saved = json.load(fh)["points"][bad]
    assert saved["status"] == "failed" and saved["error"]["type"] == "SimulationBlowUp"
    rows = _csv(tmp_path / "sw" / "results.csv")
    assert list(rows[0]) == ["trap_stiffness_pN_nm", *TWEEZER_HEADER[1:]]
    assert [r["status"] for r in rows] == ["done", "done", "failed"]
    assert rows[-1]["error"].startswith("SimulationBlowUp: ")
    assert os.path.isfile(tmp_path / "sw" / bad / "error.txt")


def test_dask_missing_gives_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails
    with pytest.raises(ImportError, match=r"dnabraid\[distributed\]"):
        sweep.run_sweep(_spec({"force_pN": [1]}), out=str(tmp_path / "sw"),
                        scheduler="tcp://127.0.0.1:1")
