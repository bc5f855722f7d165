"""Replica exchange over the trap angle (dnabraid.run.ladder): the mapped swap is exact, and a
ladder run through the driver samples each rung's Boltzmann distribution.

The swap of neighbours i, j = i + 1 proposes (T_-D x_j, T_D x_i); Metropolis acceptance on
the energies alone is detailed balance only if T_-D inverts T_D and T_D keeps volume
(Jacobian 1). Both are checked on a wound chain, the Jacobian by central finite differences
of the whole map (every coordinate but the fixed surface bead's). The run check uses the
exact reference of tests/test_twist_moves.py (60 nm, 2 pN, no surface: exact free-chain
draws reweighted by the twist energy at fixed Lk), at two of the ladder's rungs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.continuum.wlc import sample_discrete_wlc
from dnabraid.geometry import ribbon as atw
from dnabraid.run.ladder import TrapLadder, rung_turns, swap_map
from dnabraid.run.twist_moves import PlectonemeMoves
from dnabraid.scenes import make_scene
from dnabraid.scenes.base import SceneError

TOL_SEM = 4.0


def _rot(v, axis, ang):
    c, s = math.cos(ang), math.sin(ang)
    return v * c + np.cross(axis, v) * s + axis * np.dot(axis, v) * (1 - c)


def _wound(length=60.0, turns=0.5, seed=3):
    s = make_scene("plectoneme", {"length_nm": length, "force_pN": 1.0, "turns": [turns],
                                  "mc_moves": 0, "seed": seed})
    m = s.build()
    mv = PlectonemeMoves.for_model(m, moves_per_call=100, seed=seed)
    pos = np.array(m.positions)
    for k in range(21):
        mv.energy.set_trap_angle(2 * math.pi * turns * k / 20)
        pos, _ = mv.run(pos, 500)
    pos[:, :2] += 7.0  # off the origin: the map must turn about the attachment's vertical
    return m, mv, pos


def test_swap_map_is_the_stated_rotations_and_its_own_inverse():
    """Against a plain numpy statement of T_D (Rodrigues rotations), and T_-D T_D = 1."""
    m, _, x = _wound()
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
    d = 1.1
    want = x.copy()
    nb = len(sides)
    for q in range(nb):
        a, b = x[c[q]], x[c[q + 1]]
        want[sides[q]] = a + _rot(x[sides[q]] - a, (b - a) / np.linalg.norm(b - a),
                                  d * (q + 0.5) / nb)
    att = x[c[-1]]
    want[mo] = att + _rot(x[mo] - att, np.array([0.0, 0.0, 1.0]), d)
    y = swap_map(x, c, sides, mo, d)
    assert np.abs(y - want).max() < 1e-10
    assert np.abs(swap_map(y, c, sides, mo, -d) - x).max() < 1e-10


def test_swap_map_keeps_volume():
    """log |det dT_D/dx| = 0 (central differences, h = 1e-6 nm; measured 4e-8 on 100 nm)."""
    m, _, x = _wound(length=40.0)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
    n = x.size
    h = 1e-6
    J = np.empty((n, n))
    for i in range(n):
        y = x.ravel().copy()
        y[i] += h
        yp = swap_map(y.reshape(x.shape), c, sides, mo, 1.0).ravel()
        y[i] -= 2 * h
        ym = swap_map(y.reshape(x.shape), c, sides, mo, 1.0).ravel()
        J[:, i] = (yp - ym) / (2 * h)
    keep = np.ones(n, bool)
    keep[3 * int(c[0]): 3 * int(c[0]) + 3] = False  # the fixed surface bead is not sampled
    sign, logdet = np.linalg.slogdet(J[np.ix_(keep, keep)])
    assert sign > 0 and abs(logdet) < 1e-5, logdet


def test_rung_grid_and_refusals():
    assert rung_turns([0, 1], 3) == pytest.approx([0, 1 / 3, 2 / 3, 1])
    assert rung_turns([2.0], 6) == [2.0]
    assert rung_turns([0, 0.25], 6) == pytest.approx([0, 0.125, 0.25])
    with pytest.raises(ValueError, match="grid"):
        rung_turns([0, 0.3, 1], 6)
    with pytest.raises(SceneError, match="grid"):
        make_scene("plectoneme", {"sampler": "ladder", "turns": [0, 0.3, 1]})
    with pytest.raises(SceneError, match="sampler"):
        make_scene("plectoneme", {"sampler": "replica"})


def test_ladder_keeps_every_rungs_linking_number():
    """After rounds with accepted swaps every rung's state has Tw + Wr = its turns."""
    m, mv, x = _wound(length=60.0, turns=0.0)
    turns = [0.0, 1 / 6, 1 / 3]
    lad = TrapLadder(mv, m.chains[0], m.sides, m.bead_orientation, turns, m.dna.kT, seed=2)
    lad.pos = [x.copy() for _ in turns]
    for k, n in enumerate(turns):
        for i in range(1, 11):
            lad.set_angle(2 * math.pi * n * i / 10)
            lad.pos[k], _ = mv.run(lad.pos[k], 300)
    for _ in range(40):
        lad.round(200)
    assert all(a is not None and a > 0.3 for a in lad.acceptance()), lad.acceptance()
    c = m.chains[0]
    for p, n in zip(lad.pos, turns):
        lk = atw.tether_twist(p[c], p[m.sides], p[m.bead_orientation] - p[c[-1]]) \
            + atw.writhe_open(p[c])
        assert abs(lk - n) < 0.01, (lk, n)


def _exact(turns, L=60.0, F=2.0, n_draws=8000, batches=20, seed=2):
    """<z> and its batch SE at each of ``turns`` from exact free-chain draws reweighted by
    the twist energy at fixed Lk (tests/test_twist_moves.py's reference)."""
    m = make_scene("plectoneme", {"length_nm": L, "force_pN": F, "turns": [0.0],
                                  "surface": False, "mc_moves": 0}).build()
    d = m.dna
    var_s = L / 100.0 + d.kT / 20000.0
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(batches):
        x = sample_discrete_wlc(F, len(m.chains[0]) - 1, d.bead_spacing_nm, d.kappa_kT, d.kT,
                                stretch_k_pN_per_nm=d.k_bond, n_samples=n_draws // batches,
                                rng=rng)
        wr = np.array([atw.writhe_open(c) for c in x])
        z = x[:, -1, 2] - x[:, 0, 2]
        row = []
        for n in turns:
            lw = -(2 * math.pi * (n - wr)) ** 2 / (2 * var_s)
            w = np.exp(lw - lw.max())
            row.append(np.sum(w * z) / w.sum())
        out.append(row)
    out = np.array(out)
    return out.mean(axis=0), out.std(axis=0, ddof=1) / math.sqrt(batches)


def test_ladder_run_samples_each_rung_against_exact_draws(tmp_path):
    """``sampler = ladder`` through the driver (two independent ladders, rungs 0, 1/6, 1/3,
    1/2; the default ``ladder_starts = alternate`` fills the second from the top): <z> at
    turns 0 and 0.5 within 4 SE of the exact reweighted draws (measured z = -2.1, -0.7),
    every point's linking number on its turns, swaps accepted, the step column counting
    moves."""
    turns = [0.0, 0.5]
    s = make_scene("plectoneme", {"length_nm": 60.0, "force_pN": 2.0, "turns": turns,
                                  "surface": False, "sampler": "ladder", "replicas": 2,
                                  "ladder_rounds": 600, "ladder_round_moves": 200,
                                  "ladder_equilibration_rounds": 20, "ladder_frame_every": 20,
                                  "seed": 4})
    summ = s.run(str(tmp_path / "run"))
    ref, ref_sem = _exact(turns)
    for pt, z, zs in zip(summ["points"], ref, ref_sem):
        e = pt["extension_nm"]
        assert abs(e["mean"] - z) < TOL_SEM * math.hypot(e["sem"], zs), (pt["turns"], e, z)
        assert abs(pt["linking"]["mean"] - pt["turns"]) < 0.02
        assert pt["n_samples"] == 2 * 600
    lad = summ["points"][0]["ladder"]
    assert lad["rungs_turns"] == pytest.approx([0, 1 / 6, 1 / 3, 0.5])
    assert all(0.3 < a < 1.0 for a in lad["swap_acceptance"]), lad
    assert summ["total_steps"] == 0 and summ["steps_per_second"] is None
    assert any("replica exchange over the trap angle" in n for n in summ["notes"])


def test_a_ladders_points_are_judged_together():
    """One unconverged point, or a ladder with fewer than MIN_ROUND_TRIPS round trips, fails
    every point of the run (swaps carry states between all rungs; docs/validation.md 2.3o)."""
    from dnabraid.run.ladder import MIN_ROUND_TRIPS, judge_ladder

    def pts(ok):
        return [{"label": f"turns {k}", "converged": c, "convergence_reason": "ok" if c
                 else "R-hat"} for k, c in enumerate(ok)]

    p = pts([True, True])
    judge_ladder(p, {"round_trips": [MIN_ROUND_TRIPS, MIN_ROUND_TRIPS + 3]})
    assert all(x["converged"] for x in p) and p[0]["ladder"]["round_trips"]
    p = pts([True, False])
    judge_ladder(p, {"round_trips": [9, 9]})
    assert not p[0]["converged"] and "turns 1" in p[0]["convergence_reason"]
    assert p[1]["convergence_reason"] == "R-hat"
    p = pts([True, True])
    judge_ladder(p, {"round_trips": [MIN_ROUND_TRIPS - 1, 9]})
    assert not any(x["converged"] for x in p) and "round trip" in p[0]["convergence_reason"]


def test_ladders_filled_from_both_ends_stand_in_for_round_trips():
    """With no round trips, ladders filled from both ends (>= MIN_LADDERS_PER_END each) let
    converged points stand; from one end only they fail; an unconverged point still fails
    all. The split reports down - up of the replica means with Welch's t (numbers by
    hand: up 1, 3; down 6, 8: difference 5, se sqrt(2/2 + 2/2) = sqrt 2)."""
    from dnabraid.run.ladder import MIN_LADDERS_PER_END, judge_ladder

    def pts(ok):
        return [{"label": f"turns {k}", "converged": c, "convergence_reason": "ok" if c
                 else "R-hat", "extension_nm": {"replica_means": [1.0, 6.0, 3.0, 8.0]}}
                for k, c in enumerate(ok)]

    assert MIN_LADDERS_PER_END == 2
    both = ["up", "down", "up", "down"]
    p = pts([True, True])
    judge_ladder(p, {"round_trips": [0, 0, 0, 0], "starts": both})
    assert all(x["converged"] for x in p)
    split = p[0]["ladder_direction"]
    assert split["down_minus_up"] == pytest.approx(5.0)
    assert split["se"] == pytest.approx(math.sqrt(2.0))
    assert split["t"] == pytest.approx(5.0 / math.sqrt(2.0))
    p = pts([True, True])
    judge_ladder(p, {"round_trips": [0, 0, 0, 0], "starts": ["up", "up", "up", "down"]})
    assert not any(x["converged"] for x in p) and "scarcer end" in p[0]["convergence_reason"]
    assert p[0]["ladder_direction"] is None
    p = pts([False, True])
    judge_ladder(p, {"round_trips": [0, 0, 0, 0], "starts": both})
    assert not p[1]["converged"] and "turns 0" in p[1]["convergence_reason"]


def test_ramp_down_fills_the_rungs_from_the_top():
    """ramp_down steps the trap angle from 0 to the top rung, then down through every rung,
    each rung keeping the state reached at its own angle; ramp_up the mirror order. A stub
    of the moves records the angle of each call and stamps the state with it."""
    from dnabraid.run.ladder import LadderPlan, TrapLadder, ramp_down, ramp_up

    class Energy:
        theta = 0.0

        def set_trap_angle(self, t):
            self.theta = t

    class Moves:
        def __init__(self):
            self.energy = Energy()
            self.angles = []

        def run(self, pos, n):
            self.angles.append(self.energy.theta)
            out = pos.copy()
            out[0, 0] = self.energy.theta
            return out, None

    plan = LadderPlan(make_moves=None, per_turn=2, round_moves=1, rounds=2,
                      equilibration_rounds=0, ramp_moves_per_turn=4000,
                      rung_equilibration_moves=10, frame_every=1)
    turns = [1.0, 1.5, 2.0]
    for fill, first, order in ((ramp_down, 2.0, [2.0, 1.5, 1.0]),
                               (ramp_up, 1.0, [1.0, 1.5, 2.0])):
        mv = Moves()
        lad = TrapLadder(mv, [0, 1, 2], [3, 4], 5, turns, 4.1, seed=1)
        fill(lad, np.zeros((6, 3)), plan)
        got = [a / (2 * math.pi) for a in mv.angles]
        ramp = got[:got.index(first) + 1]
        assert ramp == sorted(ramp) and ramp[-1] == first  # 0 -> first rung, increasing
        stops = [g for g, h in zip(got, got[1:] + [None]) if g == h and g in turns]
        assert stops == order, got
        for k, n in enumerate(turns):
            assert lad.pos[k][0, 0] == pytest.approx(2 * math.pi * n)
    with pytest.raises(ValueError, match="starts"):
        LadderPlan(make_moves=None, per_turn=2, round_moves=1, rounds=2,
                   equilibration_rounds=0, ramp_moves_per_turn=1, rung_equilibration_moves=0,
                   frame_every=1, starts="sideways")
