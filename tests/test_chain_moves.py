"""Metropolis crankshaft, pivot and bead moves of tethers (dnabraid.run.chain_moves).

The moves alone (no Brownian steps) must sample the Boltzmann distribution exactly: for a
tether without wall and self-avoidance that is the discrete worm-like chain with harmonic
bonds under force, whose mean end height and its variance the transfer matrix gives
exactly (:func:`dnabraid.continuum.wlc.discrete_wlc_exact`). Crankshafts and pivots keep
bond lengths; the bead moves sample them, so all three together are ergodic.

Tolerance: ``TOL_SEM`` = 4 standard errors of the estimate, each from Flyvbjerg-Petersen
blocking of the chain's own samples (:func:`dnabraid.analysis.stats.blocking_sem`), fixed
seed.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from dnabraid.analysis.stats import blocking_sem
from dnabraid.continuum.wlc import discrete_wlc_exact
from dnabraid.run.chain_moves import KINDS, ChainMoves
from dnabraid.run.driver import moves_summary
from dnabraid.run.engine import Engine
from dnabraid.scenes import make_scene
from dnabraid.scenes.base import SceneError

TOL_SEM = 4.0


def _tether(**kw):
    return make_scene("tether", dict({"length_nm": 150.0, "force_pN": 0.5, "replicas": 1},
                                     **kw)).build()


def _moves(m, **kw):
    args = dict(moves_per_call=50, crank_angle_rad=1.5, pivot_angle_rad=0.6,
                bead_move_nm=0.3, seed=7)
    args.update(kw)
    return ChainMoves.for_model(m, **args)


def test_moves_alone_sample_the_exact_discrete_wlc():
    m = _tether(self_avoidance=False, surface=False, mc_moves=0)
    d = m.dna
    ex = discrete_wlc_exact(0.5, len(m.positions) - 1, d.bead_spacing_nm, d.kappa_kT, d.kT,
                            stretch_k_pN_per_nm=d.k_bond)
    mv = _moves(m)
    pos, _ = mv.run(m.positions, 5000)
    z = np.empty(40000)
    for k in range(len(z)):
        pos, _ = mv.run(pos, 50)
        z[k] = pos[-1, 2]
    mean = blocking_sem(z)
    assert abs(z.mean() - ex["extension_nm"]) < TOL_SEM * mean["sem"], (
        z.mean(), ex["extension_nm"], mean["sem"])
    dz2 = (z - z.mean()) ** 2
    var = blocking_sem(dz2)
    assert abs(dz2.mean() - ex["extension_var_nm2"]) < TOL_SEM * var["sem"], (
        dz2.mean(), ex["extension_var_nm2"], var["sem"])
    assert mean["sem"] < 0.005 * ex["extension_nm"]  # the check has teeth
    for k in KINDS:  # detailed-balance sanity: neither frozen nor accepting everything
        assert 0.05 < mv.stats[k].acceptance < 0.95, (k, mv.stats[k].acceptance)


def test_crankshaft_and_pivot_keep_bonds_and_the_fixed_bead():
    m = _tether()
    b0 = np.linalg.norm(np.diff(m.positions, axis=0), axis=1)
    for w in ((1, 0, 0), (0, 1, 0)):
        mv = _moves(m, weights=w)
        pos, _ = mv.run(m.positions, 4000)
        assert np.allclose(np.linalg.norm(np.diff(pos, axis=0), axis=1), b0, atol=1e-9)
        assert np.array_equal(pos[0], m.positions[0])
        assert mv.stats[KINDS[w.index(1)]].accepted > 100
    mv = _moves(m, weights=(0, 0, 1))
    pos, _ = mv.run(m.positions, 4000)
    assert np.array_equal(pos[0], m.positions[0])
    assert not np.allclose(np.linalg.norm(np.diff(pos, axis=0), axis=1), b0, atol=1e-3)


def test_streams_are_reproducible_and_distinct():
    m = _tether()
    a, b, c = _moves(m), _moves(m), _moves(m)
    for mv in (a, b, c):
        mv.restart(3)
    c.restart(4)
    pa, _ = a.run(m.positions, 500)
    pb, _ = b.run(m.positions, 500)
    pc, _ = c.run(m.positions, 500)
    assert np.array_equal(pa, pb)
    assert not np.array_equal(pa, pc)
    a.restart(3)  # a resumed segment repeats its moves
    pa2, _ = a.run(m.positions, 500)
    assert np.array_equal(pa, pa2)


def _drive(mv, engine, calls):
    def get():
        return engine.positions()

    def put(p):
        engine.set_positions(p)

    for _ in range(calls):
        mv.attempt(get, put, engine.energy_pN_nm)


def test_guard_agrees_with_the_engine_and_catches_a_wrong_energy():
    m = _tether(force_pN=0.1)
    eng = Engine.for_model(m, platform="Reference")
    mv = _moves(m, guard_every=1)
    _drive(mv, eng, 5)
    assert mv.guard_checks == 5 and mv.guard_max_diff < 1e-6
    e0 = mv.energy.total(eng.positions())
    assert abs(e0 - eng.energy_pN_nm()) < 1e-6 * abs(e0) + 1e-6
    # an engine energy the kernels do not reproduce (here: a constant) is caught
    bad = _moves(m, guard_every=1)
    with pytest.raises(RuntimeError, match="engine's energy"):
        bad.attempt(eng.positions, eng.set_positions, lambda: 0.0)


def test_summary_aggregates_as_the_driver_reads_it(tmp_path):
    m = _tether()
    dirs = []
    for r in range(2):
        mv = _moves(m, seed=r)
        mv.run(m.positions, 300)
        d = tmp_path / f"r{r}"
        d.mkdir()
        (d / "moves.json").write_text(json.dumps(mv.summary()))
        dirs.append(str(d))
    tot = moves_summary(dirs)
    for k in KINDS:
        assert set(tot[k]) == {"attempted", "refused_by_constraint", "accepted", "acceptance"}
        assert 0 < tot[k]["accepted"] < tot[k]["attempted"]
    assert sum(tot[k]["attempted"] for k in KINDS) == 600


def test_tether_scene_wires_the_moves():
    m = _tether()
    assert isinstance(m.moves, ChainMoves) and m.moves.kinds == list(KINDS)
    assert set(m.moves.energy.terms) == set(m.forces)
    assert _tether(mc_moves=0).moves is None
    with pytest.raises(SceneError, match="mc_moves"):
        make_scene("tether", {"alpha": 0.5})
    with pytest.raises(SceneError, match="mc_moves"):
        make_scene("tether", {"stretch": "constraints"})
    with pytest.raises(SceneError, match="pivot_angle_rad"):
        make_scene("tether", {"pivot_angle_rad": 4.0})
    make_scene("tether", {"stretch": "constraints", "mc_moves": 0})


def test_a_short_tether_run_writes_the_move_counts(tmp_path):
    from dnabraid.run.driver import run

    s = make_scene("tether", {"length_nm": 50.0, "steps": 1000, "equilibration_steps": 200,
                              "frame_interval": 500, "replicas": 2, "workers": 1,
                              "mc_moves": 100})
    out = run(s, str(tmp_path / "run"), platform="CPU", threads=1)
    mv = out["points"][0]["rigid_moves"]
    assert mv["moves_per_call"] == 100 and mv["guard_checks"] >= 1
    assert sum(mv[k]["attempted"] for k in KINDS) == 2 * 100 * 12
