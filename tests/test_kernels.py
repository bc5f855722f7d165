"""Compiled local energies (dnabraid.kernels.LocalEnergy) against OpenMM.

The kernels reproduce every term of a tether (stretch, bend, WCA, wall, pull) from the
model's own System. References: OpenMM on the Reference platform (double precision), term
by term through the force groups, at random tether configurations of 41 beads that are
crumpled (many WCA contacts, a few deep overlaps) and pushed partly through the wall.

Tolerances: relative ``REL`` = 1e-9 or absolute ``ABS`` = 1e-6 pN nm, whichever is larger
(round-off: both sides are double precision; WCA energies of overlapping beads reach
1e6 pN nm, whose differences carry ~1e-10 absolute round-off).
"""

from __future__ import annotations

import numpy as np
import openmm
import pytest

from dnabraid.kernels import TERMS, LocalEnergy
from dnabraid.run.engine import Engine
from dnabraid.run.moves import axis_rotation, random_rotation
from dnabraid.scenes import make_scene

REL = 1e-9
ABS = 1e-6  # pN nm

VARIANTS = [(True, True), (True, False), (False, True), (False, False)]


def _model(self_avoidance: bool, surface: bool, **kw):
    return make_scene("tether", dict({"length_nm": 200.0, "force_pN": 0.7, "replicas": 1,
                                      "self_avoidance": self_avoidance, "surface": surface},
                                     **kw)).build()


def _crumpled(model, rng, b=5.0):
    """A random walk of bonds near b (so beads meet and overlap), partly below the wall."""
    n = len(model.positions)
    steps = rng.normal(size=(n - 1, 3))
    steps /= np.linalg.norm(steps, axis=1)[:, None]
    steps *= rng.uniform(0.85 * b, 1.15 * b, size=(n - 1, 1))
    pos = np.zeros((n, 3))
    pos[1:] = np.cumsum(steps, axis=0)
    pos[:, 2] -= 3.0  # some beads below the wall at z = d/2
    pos[0] = model.positions[0]
    return pos


def _close(a, b):
    return abs(a - b) <= max(REL * max(abs(a), abs(b)), ABS)


def _openmm_terms(engine, model, pos):
    engine.set_positions(pos)
    return {t: engine.energy_pN_nm(groups=[g]) for t, g in model.forces.items()}


@pytest.mark.parametrize("self_avoidance,surface", VARIANTS)
def test_total_equals_openmm_term_by_term(self_avoidance, surface):
    m = _model(self_avoidance, surface)
    le = LocalEnergy(m)
    assert set(le.terms) == set(m.forces)
    eng = Engine.for_model(m, platform="Reference")
    rng = np.random.default_rng(11)
    seen = dict.fromkeys(le.terms, False)
    for pos in [m.positions] + [_crumpled(m, rng) for _ in range(6)]:
        mine = le.total_terms(pos)
        ref = _openmm_terms(eng, m, pos)
        for t in le.terms:
            assert _close(mine[t], ref[t]), (t, mine[t], ref[t])
            seen[t] |= abs(ref[t]) > 1.0
        assert _close(le.total(pos), sum(ref.values()))
    assert all(seen.values()), seen  # every term was exercised with a non-trivial energy


def _moves(pos, rng, n_each):
    """Random crankshafts, pivots (large angles: overlaps and wall contacts) and bead
    displacements: (kind, idx, new positions)."""
    n = len(pos)
    out = []
    for _ in range(n_each):
        i = int(rng.integers(1, n - 2))
        j = int(rng.integers(i, min(n - 2, i + 10) + 1))
        a, b = pos[i - 1], pos[j + 1]
        ax = (b - a) / np.linalg.norm(b - a)
        R = axis_rotation(ax, rng.uniform(-np.pi, np.pi))
        idx = np.arange(i, j + 1)
        out.append(("crankshaft", idx, (pos[idx] - a) @ R.T + a))
        i = int(rng.integers(1, n))
        R = random_rotation(rng, np.pi)
        idx = np.arange(i, n)
        out.append(("pivot", idx, (pos[idx] - pos[i - 1]) @ R.T + pos[i - 1]))
        k = int(rng.integers(1, n))
        out.append(("bead", np.array([k]), pos[[k]] + rng.normal(scale=2.0, size=(1, 3))))
        idx = rng.choice(np.arange(1, n), size=5, replace=False)  # any particles at all
        out.append(("scatter", idx, pos[idx] + rng.normal(scale=3.0, size=(5, 3))))
    return out


@pytest.mark.parametrize("self_avoidance,surface", VARIANTS)
def test_delta_equals_the_difference_of_two_openmm_energies(self_avoidance, surface):
    m = _model(self_avoidance, surface)
    le = LocalEnergy(m)
    eng = Engine.for_model(m, platform="Reference")
    rng = np.random.default_rng(5)
    n_overlap = n_wall = 0
    for pos in (m.positions, _crumpled(m, rng), _crumpled(m, rng)):
        before = _openmm_terms(eng, m, pos)
        for kind, idx, new in _moves(pos, rng, 8):
            moved = pos.copy()
            moved[idx] = new
            after = _openmm_terms(eng, m, moved)
            mine = le.delta_terms(pos, idx, new)
            for t in le.terms:
                want = after[t] - before[t]
                tol = max(REL * max(abs(after[t]), abs(before[t])), ABS)
                assert abs(mine[t] - want) <= tol, (kind, t, mine[t], want)
            assert abs(le.delta(pos, idx, new) - sum(mine.values())) <= 1e-9 * (
                1.0 + sum(abs(v) for v in mine.values()))
            n_overlap += "wca" in le.terms and after["wca"] > before["wca"] + 1.0
            n_wall += "wall" in le.terms and after["wall"] > before["wall"] + 1.0
    if self_avoidance:
        assert n_overlap > 5  # moves that create WCA overlaps were tested
    if surface:
        assert n_wall > 5  # and moves into the wall


def test_moves_in_the_compiled_loop_add_up_to_the_openmm_change():
    """The Monte Carlo loop's own dE (rigid moves, pairs searched from the smaller side,
    early rejection, the hash updated in place) summed over accepted moves equals the
    OpenMM energy change, term by term, from a crumpled start full of contacts."""
    from dnabraid.run.chain_moves import ChainMoves

    m = _model(True, True, force_pN=0.05)
    eng = Engine.for_model(m, platform="Reference")
    rng = np.random.default_rng(2)
    pos = _crumpled(m, rng)
    pos[:, 2] += 3.5  # mostly above the wall; a relaxed, contact-rich start
    mv = ChainMoves.for_model(m, moves_per_call=3000, crank_angle_rad=1.0,
                              pivot_angle_rad=0.8, bead_move_nm=0.4, seed=4)
    before = _openmm_terms(eng, m, pos)
    assert mv.energy.total_terms(pos)["wca"] > 0.0
    new, terms = mv.run(pos, 3000)
    after = _openmm_terms(eng, m, new)
    for k, t in enumerate(TERMS):
        if t not in after:
            assert terms[k] == 0.0
            continue
        want = after[t] - before[t]
        assert abs(terms[k] - want) <= 1e-8 * (1.0 + abs(after[t]) + abs(before[t])), (
            t, terms[k], want)
    assert all(mv.stats[k].accepted > 50 for k in mv.kinds)


def test_rigid_large_moves_price_only_the_pairs_they_change():
    """A rigid motion of more than ``_SWEEP_MIN`` particles takes its WCA change from the
    moved-unmoved pairs alone (``_wca_cross``, bounding boxes and a sweep along z): the
    compiled kernel's rigid dE equals OpenMM's energy difference term by term on crumpled
    tethers full of contacts, pivots of 25-40 beads turned by up to pi; and searching the
    bonded terms from the particles next to the pivot alone gives the same change."""
    from dnabraid.kernels import chain as ch

    m = _model(True, True)
    le = LocalEnergy(m)
    P = le.params
    eng = Engine.for_model(m, platform="Reference")
    rng = np.random.default_rng(17)
    n = len(m.positions)
    checked = changed = 0
    for _ in range(3):
        pos = _crumpled(m, rng)
        H, ncon, _, dcon, moved, _, _, out = ch.loop_setup(pos, P, len(TERMS))
        before = _openmm_terms(eng, m, pos)
        for _ in range(12):
            i = int(rng.integers(1, n - ch._SWEEP_MIN - 1))
            idx = np.arange(i, n, dtype=np.int64)
            assert len(idx) > ch._SWEEP_MIN
            R = random_rotation(rng, np.pi)
            new = np.ascontiguousarray((pos[idx] - pos[i - 1]) @ R.T + pos[i - 1])
            moved[:] = 0
            moved[idx] = np.arange(1, len(idx) + 1)
            dE = ch.delta_kernel(pos, idx, new, moved, True, P, H, out, np.inf, ncon, dcon,
                                 False, np.eye(3), np.zeros(3), idx)
            # the bonded terms searched from the two beads next to the pivot alone (the
            # bond and the two hinges that hold an unmoved bead): the same change
            out2 = np.zeros_like(out)
            dE2 = ch.delta_kernel(pos, idx, new, moved, True, P, H, out2, np.inf, ncon, dcon,
                                  False, np.eye(3), np.zeros(3), idx[:2].copy())
            assert np.allclose(out2, out, rtol=1e-12, atol=1e-9) and abs(dE2 - dE) <= 1e-9 * (
                1.0 + abs(dE))
            after_pos = pos.copy()
            after_pos[idx] = new
            after = _openmm_terms(eng, m, after_pos)
            for k, t in enumerate(TERMS):
                if t in after:
                    want = after[t] - before[t]
                    tol = max(REL * max(abs(after[t]), abs(before[t])), ABS)
                    assert abs(out[k] - want) <= tol, (t, out[k], want)
            assert abs(dE - sum(after.values()) + sum(before.values())) <= 1e-8 * (
                1.0 + sum(abs(v) for v in after.values()) + sum(abs(v) for v in before.values()))
            checked += 1
            changed += abs(after["wca"] - before["wca"]) > 1.0
    assert checked == 36 and changed > 10  # the moves changed the WCA energy


def test_unknown_force_or_changed_expression_is_refused():
    m = _model(True, True)
    f = openmm.CustomExternalForce("x")
    f.setName("trap")
    m.system.addForce(f)
    with pytest.raises(ValueError, match="no kernel for force 'trap'"):
        LocalEnergy(m)
    m = _model(False, True)
    for f in m.system.getForces():
        if f.getName() == "wall":
            f.setEnergyFunction("0.5*wall_k*(wall_z-z)^2")
    with pytest.raises(ValueError, match="'wall' has the energy"):
        LocalEnergy(m)


def test_wrong_shapes_are_refused():
    m = _model(False, False)
    le = LocalEnergy(m)
    with pytest.raises(ValueError, match="shape"):
        le.total(m.positions[:-1])
    with pytest.raises(ValueError, match="distinct"):
        le.delta(m.positions, [3, 3], np.zeros((2, 3)))
