"""Metropolis rigid-body and crankshaft moves (dnabraid.run.moves) against exact distributions.

The moves are driven here with numpy energies (no OpenMM), so the sampled distribution is
the Metropolis chain's alone: a symmetric proposal with the Metropolis rule must reproduce
the Boltzmann distribution exactly (Metropolis et al. 1953). Exact references:

* translation: a rigid group of N particles in U = k/2 sum |r_i|^2 has a Gaussian centroid
  of variance kT / (N k) per axis;
* rotation: a rigid dumbbell of half-length l in U = -h . (r_1 - r_2) has
  <cos theta> = L(x) = coth(x) - 1/x, x = 2 h l / kT (Langevin function), theta the angle
  of r_1 - r_2 to h;
* crankshaft: a free ring (U = 0) keeps its bond lengths to round-off, its pivots stay, and
  a move reversed (same arc, opposite angle) returns the start: the proposal is symmetric.

Tolerances: 4 standard errors of the estimate (the chains' error from batch means), fixed
seeds.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.run.moves import RigidMoves, random_rotation


def _drive(mv, pos, energy, calls):
    state = {"p": np.array(pos, float)}
    out = []

    def get():
        return state["p"].copy()

    def put(p):
        state["p"] = np.array(p, float)

    def e():
        return energy(state["p"])

    for _ in range(calls):
        mv.attempt(get, put, e)
        out.append(state["p"].copy())
    return np.array(out)


def _batch_sem(x, nb=50):
    x = np.asarray(x, float)
    m = len(x) // nb
    b = x[: m * nb].reshape(nb, m).mean(axis=1)
    return float(b.std(ddof=1) / math.sqrt(nb))


def test_shift_samples_the_gaussian_centroid_exactly():
    kT, k, N = 4.1, 2.0, 3
    pos = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    mv = RigidMoves([np.arange(N)], kT, shift_nm=1.5, angle_rad=0.0, moves_per_call=1,
                    seed=3)
    traj = _drive(mv, pos, lambda p: 0.5 * k * np.sum(p * p), 60000)
    c = traj.mean(axis=1)[5000:]  # centroid
    var = c.var(axis=0)
    exact = kT / (N * k)
    for ax in range(3):
        sem = _batch_sem((c[:, ax] - c[:, ax].mean()) ** 2)
        assert abs(var[ax] - exact) < 4 * sem, (ax, var[ax], exact, sem)
    assert 0.2 < mv.stats["shift"].acceptance < 0.95


def test_turn_samples_the_langevin_orientation_exactly():
    kT, half, h = 4.1, 1.0, 3.0
    field = np.array([0.0, 0.0, h])
    pos = np.array([[half, 0.0, 0.0], [-half, 0.0, 0.0]])
    mv = RigidMoves([np.arange(2)], kT, shift_nm=0.0, angle_rad=0.8, moves_per_call=1,
                    seed=5)
    traj = _drive(mv, pos, lambda p: -field @ (p[0] - p[1]), 60000)[5000:]
    u = traj[:, 0] - traj[:, 1]
    cos = u[:, 2] / np.linalg.norm(u, axis=1)
    x = 2 * h * half / kT
    exact = 1 / math.tanh(x) - 1 / x
    assert abs(cos.mean() - exact) < 4 * _batch_sem(cos), (cos.mean(), exact)
    # the rotation is about the centroid: it stays at the origin
    assert np.max(np.abs(traj.mean(axis=1))) < 1e-12


def test_two_groups_shift_relatively_and_keep_their_centroid():
    pos = np.array([[0.0, 0, 0], [1, 0, 0], [5, 0, 0], [6, 0, 0]])
    mv = RigidMoves([np.array([0, 1]), np.array([2, 3])], 1.0, shift_nm=2.0, angle_rad=0.0,
                    moves_per_call=1, seed=1)
    traj = _drive(mv, pos, lambda p: 0.0, 200)
    assert np.allclose(traj.mean(axis=1), pos.mean(axis=0), atol=1e-12)
    # each group moves rigidly
    assert np.allclose(np.linalg.norm(traj[:, 1] - traj[:, 0], axis=1), 1.0)
    assert np.allclose(np.linalg.norm(traj[:, 3] - traj[:, 2], axis=1), 1.0)


def _ring(n=12, r=5.0):
    s = 2 * np.pi * np.arange(n) / n
    beads = np.c_[r * np.cos(s), r * np.sin(s), np.zeros(n)]
    nxt = np.roll(beads, -1, axis=0)
    sides = beads + 0.3 * np.cross(nxt - beads, [0, 0, 1.0]) / np.linalg.norm(
        nxt - beads, axis=1)[:, None]
    return np.vstack([beads, sides]), np.arange(n), n + np.arange(n)


def test_crankshaft_keeps_bonds_and_pivots_and_is_reversible():
    pos, beads, sides = _ring()
    mv = RigidMoves([np.r_[beads, sides]], 1.0, shift_nm=0.0, angle_rad=0.0, rings=[(beads,
                    sides)], arc_angle_rad=1.0, moves_per_call=1, seed=2)
    b0 = np.linalg.norm(np.roll(pos[beads], -1, axis=0) - pos[beads], axis=1)
    arm0 = np.linalg.norm(pos[sides] - pos[beads], axis=1)
    diag0 = np.linalg.norm(pos[sides] - np.roll(pos[beads], -1, axis=0), axis=1)
    p = pos
    for _ in range(200):
        rng_state = mv.rng.bit_generator.state
        kind, new = mv.propose(p)
        assert kind == "arc"
        moved = np.any(np.abs(new - p) > 1e-12, axis=1)
        assert 1 <= moved[beads].sum() <= mv.arc_max
        # the reverse: same arc, opposite angle
        mv.rng.bit_generator.state = rng_state
        mv._i -= 1
        mv.arc_angle = -mv.arc_angle  # phi = a (2u - 1): the same u with -a draws -phi
        _, back = mv.propose(new)
        mv.arc_angle = -mv.arc_angle
        # the reverse turns about the axis through the same (unmoved) pivots
        assert np.allclose(back, p, atol=1e-9)
        p = new
        b = np.linalg.norm(np.roll(p[beads], -1, axis=0) - p[beads], axis=1)
        assert np.allclose(b, b0, atol=1e-9)
        assert np.allclose(np.linalg.norm(p[sides] - p[beads], axis=1), arm0, atol=1e-9)
        assert np.allclose(np.linalg.norm(p[sides] - np.roll(p[beads], -1, axis=0), axis=1),
                           diag0, atol=1e-9)


def test_refused_moves_leave_the_state_and_are_counted():
    pos, beads, sides = _ring()
    mv = RigidMoves([np.r_[beads, sides]], 1.0, shift_nm=1.0, angle_rad=0.5,
                    rings=[(beads, sides)], arc_angle_rad=0.5, moves_per_call=3, seed=4,
                    allowed=lambda p, kind: False)
    traj = _drive(mv, pos, lambda p: 0.0, 50)
    assert np.array_equal(traj[-1], pos)
    for k in ("shift", "turn", "arc"):
        assert mv.stats[k].refused == mv.stats[k].attempted == 50
        assert mv.stats[k].accepted == 0


def test_random_rotation_is_orthogonal_and_bounded():
    rng = np.random.default_rng(0)
    for _ in range(100):
        R = random_rotation(rng, 0.4)
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert abs(np.linalg.det(R) - 1) < 1e-12
        assert math.acos(min(1.0, (np.trace(R) - 1) / 2)) <= 0.4 + 1e-12


@pytest.mark.parametrize("kw, words", [
    ({"shift_nm": 0.0, "angle_rad": 0.0}, "not all 0"),
    ({"shift_nm": -1.0, "angle_rad": 0.1}, ">= 0"),
    ({"shift_nm": 1.0, "angle_rad": 4.0}, "<= pi"),
    ({"shift_nm": 1.0, "angle_rad": 0.1, "arc_angle_rad": 0.3}, "need rings"),
])
def test_bad_move_settings_are_refused(kw, words):
    with pytest.raises(ValueError, match=words):
        RigidMoves([np.arange(3)], 1.0, **kw)
