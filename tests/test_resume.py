"""An interrupted run, started again, ends with the same numbers as an uninterrupted one.

Each point starts from the checkpoint (``Context.createCheckpoint``: positions, parameters
and the integrator's random-number state) of the point it follows, so rerunning the
interrupted point reproduces it exactly on the same platform.
"""

import json

import pytest
from conftest import without_guard_roundoff

from dnabraid.run.engine import Engine
from dnabraid.scenes import make_scene

SHORT = {"length_nm": 60.0, "tether_separation_nm": 20.0, "turns": [-1.0, 0.0, 1.0],
         "steps": 3000, "equilibration_steps": 500, "frame_interval": 500, "seed": 5,
         "replicas": 2, "workers": 1, "protocol": "ramp", "mc_moves": 300}
# with Metropolis moves (the braid's default since 2026-12-06): a resumed run repeated the
# uninterrupted one only after the moves' stretch ratio was taken per segment
# (BraidMoves.restart)


class Interrupt(Exception):
    pass


def test_interrupted_run_resumes_to_identical_numbers(tmp_path, monkeypatch):
    s = make_scene("braid", SHORT)
    full = s.run(str(tmp_path / "full"))

    calls = {"n": 0}
    real = Engine.advance

    def dying(self, n, fail_dir=None):
        calls["n"] += 1
        if calls["n"] == 60:  # inside the second point (each point takes > 35 calls)
            raise Interrupt
        return real(self, n, fail_dir)

    monkeypatch.setattr(Engine, "advance", dying)
    with pytest.raises(Interrupt):
        s.run(str(tmp_path / "cut"))
    monkeypatch.setattr(Engine, "advance", real)
    done = sorted(p.name for p in (tmp_path / "cut" / "replicas" / "r00" / "points").iterdir()
                  if (p / "done.json").exists())
    assert len(done) == 1  # the first point finished, the second was cut
    resumed = s.run(str(tmp_path / "cut"))
    assert without_guard_roundoff(resumed["points"]) == without_guard_roundoff(full["points"])
    a = json.loads((tmp_path / "full" / "summary.json").read_text())["points"]
    b = json.loads((tmp_path / "cut" / "summary.json").read_text())["points"]
    assert without_guard_roundoff(a) == without_guard_roundoff(b)
    assert ((tmp_path / "full" / "observables.csv").read_text()
            == (tmp_path / "cut" / "observables.csv").read_text())
