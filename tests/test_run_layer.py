"""The thermal run layer's contract: what a scene gives the driver, what the driver reads.

* every thermal scene implements :class:`dnabraid.run.contract.ThermalContract` (the
  driver reads nothing else of a scene) and its model carries no scene;
* the run layer (``dnabraid/run/``) reads no scene attribute through ``getattr`` and no
  ``.scene`` of a model, and nothing in the package uses a dict of string keys between
  modules (``model.extra``);
* an observable declares each column once (unit, meaning, reported, verdict) and the
  summary's units, table, rows and verdict come from those declarations;
* progress for log files is plain lines with the rate and the time left.
"""

import ast
import io
import pathlib

import pytest

import dnabraid
from dnabraid.observables import Column, error_name
from dnabraid.progress import LineProgress
from dnabraid.run.contract import ThermalContract
from dnabraid.run.summary import point_verdict
from dnabraid.scenes import SCENES, make_scene
from dnabraid.scenes.thermal import ThermalScene

ROOT = pathlib.Path(dnabraid.__file__).parent
THERMAL = [name for name, cls in SCENES.items() if issubclass(cls, ThermalScene)]


def test_thermal_scenes_keep_the_contract():
    """The four thermal scenes are ThermalContract subclasses with nothing abstract left
    (a missing member would make them impossible to instantiate)."""
    assert sorted(THERMAL) == ["braid", "catenane", "plectoneme", "tether"]
    for name in THERMAL:
        s = make_scene(name)
        assert isinstance(s, ThermalContract)
        assert not type(s).__abstractmethods__
        for key in ("seed", "replicas", "workers", "pack", "report_interval",
                    "frame_interval", "integrator"):
            assert key in type(s).keys(), f"{name} lacks the driver's key {key}"


@pytest.mark.parametrize("name", ["braid", "catenane", "tether"])
def test_model_is_typed_and_knows_no_scene(name):
    m = make_scene(name).build()
    assert not hasattr(m, "scene") and not hasattr(m, "extra")
    assert m.length_nm == pytest.approx(make_scene(name).length_nm)
    assert m.dna.temperature_K == pytest.approx(make_scene(name).temperature_K)


def _source(path: pathlib.Path) -> ast.AST:
    return ast.parse(path.read_text())


def test_run_layer_reads_no_scene():
    """No ``getattr`` and no ``.scene`` attribute in dnabraid/run/, and no ``.extra``
    anywhere in the package."""
    for p in sorted((ROOT / "run").glob("*.py")):
        for node in ast.walk(_source(p)):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "getattr":
                raise AssertionError(f"{p.name}:{node.lineno} calls getattr")
            if isinstance(node, ast.Attribute) and node.attr == "scene":
                raise AssertionError(f"{p.name}:{node.lineno} reads .scene")
    for p in sorted(ROOT.rglob("*.py")):
        for node in ast.walk(_source(p)):
            if isinstance(node, ast.Attribute) and node.attr == "extra":
                raise AssertionError(f"{p.relative_to(ROOT)}:{node.lineno} uses .extra")


def test_no_private_names_imported_across_modules():
    """No module imports another module's private name (``from x import _name``), and a
    private module (``_validate``) is imported only by its own package."""
    for p in sorted(ROOT.rglob("*.py")):
        rel = p.relative_to(ROOT.parent).with_suffix("")
        package = ".".join(rel.parts[:-1])
        for node in ast.walk(_source(p)):
            if isinstance(node, ast.ImportFrom):
                mod = node.module or ""
                if node.level:
                    base = package.split(".")[:len(package.split(".")) - node.level + 1]
                    mod = ".".join(base + ([mod] if mod else []))
                bad = [a.name for a in node.names if a.name.startswith("_")
                       and not a.name.startswith("__")]
                parts = mod.split(".")
                private_mod = any(
                    part.startswith("_") and not part.startswith("__")
                    and ".".join(parts[:i]) != package for i, part in enumerate(parts))
                assert not bad and not private_mod, (
                    f"{p.relative_to(ROOT)}:{node.lineno} imports a private name: "
                    f"from {mod} import {', '.join(a.name for a in node.names)}")


def test_error_names_keep_the_unit_last():
    assert error_name("extension_nm", "nm") == "extension_sem_nm"
    assert error_name("torque_pN_nm", "pN nm") == "torque_sem_pN_nm"
    assert error_name("catenation", "turns") == "catenation_sem"
    assert error_name("plectonemes", "") == "plectonemes_sem"


def test_braid_declares_its_reported_columns_once():
    """The braid's table, rows and verdict columns come from its observables' columns."""
    s = make_scene("braid")
    m = s.build()
    cols = {k: c for ob in s.observables(m) for k, c in ob.columns.items()}
    assert all(isinstance(c, Column) for c in cols.values())
    assert [k for k, c in cols.items() if c.reported] == ["extension_nm", "torque_pN_nm",
                                                           "catenation"]
    assert [k for k, c in cols.items() if c.verdict] == ["extension_nm", "torque_pN_nm"]
    # the sweep header the tweezer scenes declare is what rows() produces from them
    summary = {"columns": {k: {"unit": c.unit, "reported": c.reported}
                           for k, c in cols.items()},
               "points": [{"turns": 1.0, "extension_nm": {"mean": 1.0, "sem": 0.1},
                           "torque_pN_nm": {"mean": 2.0, "sem": 0.2},
                           "catenation": {"mean": 1.0, "sem": 0.0}, "n_samples": 7}]}
    (row,) = s.rows(summary)
    assert list(row) == list(type(s).row_columns)


def test_catenane_verdict_columns():
    s = make_scene("catenane")
    m = s.build()
    cols = {k: c for ob in s.observables(m) for k, c in ob.columns.items()}
    assert sorted(k for k, c in cols.items() if c.verdict) == [
        "contact_length_nm", "writhe_1", "writhe_2"]


def test_verdict_without_a_deciding_column_is_not_converged():
    """A point whose deciding columns have no value is not converged (a verdict that cannot
    fail is not a verdict)."""
    pt = {"extension_nm": {"mean": None, "sem": None}}
    point_verdict(pt, ["extension_nm"])
    assert pt["converged"] is False
    pt = {"extension_nm": {"mean": 1.0, "converged": True, "ess": 500.0}}
    point_verdict(pt, ["extension_nm"])
    assert pt["converged"] is True and pt["convergence_reason"] == "ok"


def test_line_progress_prints_plain_lines_with_rate_and_time_left():
    buf = io.StringIO()
    bar = LineProgress(1000, unit="step", desc="braid", every=0.25, file=buf)
    for _ in range(10):
        bar.update(100)
    bar.close()
    lines = buf.getvalue().splitlines()
    assert "\r" not in buf.getvalue()
    assert len(lines) == 4  # at 30 %, 50 %, 80 % (every 25 %, crossed) and the end
    assert lines[-1].startswith("braid: 100.0 %") and "step/s" in lines[-1]
    assert "left" in lines[0]


def test_nan_inside_a_step_is_a_blow_up_naming_step_term_and_state(tmp_path):
    """OpenMM's own NaN check throws inside ``integrator.step``; the engine reports it as a
    SimulationBlowUp with the step range, the largest term and the saved state (it escaped
    as a raw OpenMMException before)."""
    import os

    import numpy as np

    from dnabraid.run.engine import Engine, SimulationBlowUp

    m = make_scene("tether", {"length_nm": 50.0, "replicas": 1}).build()
    e = Engine.for_model(m, platform="CPU", seed=3, threads=1)
    pos = np.array(m.positions, float)
    pos[5] = pos[4]  # two beads on one point: 0/0 forces, NaN coordinates in the next step
    e.set_positions(pos)
    with pytest.raises(SimulationBlowUp) as exc:
        e.advance(5, str(tmp_path))
    assert "OpenMM stopped inside steps 1-5" in str(exc.value)
    assert exc.value.step == 5 and exc.value.term in m.forces
    assert exc.value.saved and os.path.exists(exc.value.saved)


def test_shared_starts_and_frozen_replicas_fail_the_verdict():
    """Replicas that share a start, or a verdict column that stayed constant in a replica,
    make a point not converged, whatever R-hat says."""
    import numpy as np

    from dnabraid.run.driver import shared_starts, start_fingerprint
    from dnabraid.run.summary import frozen_replicas

    a = np.arange(12.0).reshape(4, 3)
    recs = [{"fingerprint": start_fingerprint(a)}, {"fingerprint": start_fingerprint(a + 1)},
            {"fingerprint": start_fingerprint(a.copy())}, {"fingerprint": None}]
    assert shared_starts(recs) == [[0, 2]]
    moving = {"extension_nm": np.array([1.0, 2.0, 1.5])}
    stuck = {"extension_nm": np.array([3.0, 3.0, 3.0])}
    assert frozen_replicas([(moving, {}), (stuck, {})], ["extension_nm"]) == {
        "extension_nm": [1]}
    assert frozen_replicas([(moving, {}), (moving, {})], ["extension_nm"]) == {}


def test_braid_replicas_from_one_start_are_not_converged(tmp_path):
    """start_spread = 0 gives every replica the same built start: the summary records the
    starts and no point may be called converged, however long the run."""
    s = make_scene("braid", {"steps": 2000, "equilibration_steps": 500, "replicas": 2,
                             "turns": [1.0], "start_spread": 0.0, "workers": 1})
    pt = s.run(str(tmp_path / "b"))["points"][0]
    assert not pt["converged"] and "share a start" in pt["convergence_reason"]
    assert [r["kind"] for r in pt["starts"]] == ["built at its state"] * 2
    own = make_scene("braid", {"steps": 2000, "equilibration_steps": 500, "replicas": 2,
                               "turns": [1.0], "workers": 1})
    pt = own.run(str(tmp_path / "o"))["points"][0]
    assert "share a start" not in pt["convergence_reason"]
    assert len({r["fingerprint"] for r in pt["starts"]}) == 2


def test_each_point_records_only_its_own_moves(tmp_path):
    """A replica's mover runs over all its points; each point's ``rigid_moves`` counts only
    the moves made at that point: (equilibration + sampling steps) / report interval calls
    of ``mc_moves`` moves per replica, the same at both points (the counts of the second
    point were those of both until 2026-12-03). The small bead (R = 30 nm, its centre 8x
    more mobile than a DNA bead) also checks that the time step sees the centre's links:
    this braid went NaN within 100 steps before."""
    s = make_scene("braid", {"length_nm": 30.0, "force_pN": 2.0, "turns": [0.0, 0.5],
                             "replicas": 2, "workers": 1, "mc_moves": 7, "steps": 400,
                             "equilibration_steps": 200, "report_interval": 100,
                             "frame_interval": 400, "tether_separation_nm": 20.0,
                             "bead_radius_nm": 30.0})
    summ = s.run(str(tmp_path / "run"))
    want = 2 * (200 + 400) // 100 * 7
    for pt in summ["points"]:
        mv = pt["rigid_moves"]
        tot = sum(v["attempted"] for v in mv.values() if isinstance(v, dict))
        assert tot == want, (pt["turns"], tot, want)
        acc = [v["acceptance"] for v in mv.values() if isinstance(v, dict) and v["attempted"]]
        assert all(0.0 <= a <= 1.0 for a in acc)
