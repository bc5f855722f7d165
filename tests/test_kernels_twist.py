"""Compiled twins of the plectoneme's terms (dnabraid.kernels.twist through LocalEnergy)
against OpenMM.

A plectoneme's System holds, besides the tether's terms, the frame springs, three twist
forces (interior joints, surface clamp, bead clamp: one term ``twist``), the rotational
trap, the link of the orientation particle and the bead's plane (``beadwall``). References:
OpenMM on the Reference platform (double precision), term by term through the force
groups, at random configurations: crumpled chains (WCA contacts and overlaps, beads below
the wall and above the bead's plane), side particles scattered about their beads (joint
angles anywhere in (-pi, pi]) and the orientation particle anywhere near the attachment.

Tolerances as tests/test_kernels.py: relative 1e-9 or absolute 1e-6 pN nm (round-off).
"""

from __future__ import annotations

import numpy as np
import pytest

from dnabraid.kernels import TERMS, LocalEnergy
from dnabraid.run.engine import Engine
from dnabraid.run.moves import axis_rotation, random_rotation
from dnabraid.scenes import make_scene

REL = 1e-9
ABS = 1e-6  # pN nm


@pytest.fixture(scope="module")
def plect():
    m = make_scene("plectoneme", {"length_nm": 100.0, "force_pN": 0.5, "turns": [0.0],
                                  "replicas": 1, "mc_moves": 0}).build()
    return m, LocalEnergy(m), Engine.for_model(m, platform="Reference")


def _random_conf(m, rng, b=5.0):
    c = np.asarray(m.chains[0])
    n = len(c)
    steps = rng.normal(size=(n - 1, 3))
    steps /= np.linalg.norm(steps, axis=1)[:, None]
    steps *= rng.uniform(0.85 * b, 1.15 * b, size=(n - 1, 1))
    steps[:, 2] += 1.0  # upwards on average; some beads still end above the attachment
    pos = np.array(m.positions, float)
    pos[c[0]] = m.positions[c[0]]
    pos[c[1:]] = pos[c[0]] + np.cumsum(steps, axis=0) - [0.0, 0.0, 3.0]
    pos[m.sides] = pos[c[:-1]] + rng.normal(scale=3.0, size=(n - 1, 3))
    pos[m.bead_orientation] = pos[c[-1]] + rng.normal(scale=12.0, size=3)
    return pos


def _terms(eng, m, pos):
    eng.set_positions(pos)
    return {t: eng.energy_pN_nm(groups=[g]) for t, g in m.forces.items()}


def _close(a, b):
    return abs(a - b) <= max(REL * max(abs(a), abs(b)), ABS)


def test_plectoneme_terms_are_known():
    m = make_scene("plectoneme", {"length_nm": 60.0, "mc_moves": 0}).build()
    le = LocalEnergy(m)
    assert set(le.terms) == set(m.forces) == {"stretch", "bend", "wca", "wall", "pull",
                                              "frame", "twist", "trap", "link", "beadwall"}
    P = le.params
    assert list(np.bincount(P.j_type)) == [len(m.chains[0]) - 2, 1, 1]


def test_total_equals_openmm_term_by_term(plect):
    m, le, eng = plect
    rng = np.random.default_rng(21)
    seen = dict.fromkeys(le.terms, False)
    for pos in [m.positions] + [_random_conf(m, rng) for _ in range(8)]:
        le.set_trap_angle(rng.uniform(-np.pi, np.pi))
        eng.set_parameter("trap_angle", le.trap_angle)
        mine = le.total_terms(pos)
        ref = _terms(eng, m, pos)
        for t in le.terms:
            assert _close(mine[t], ref[t]), (t, mine[t], ref[t])
            seen[t] |= abs(ref[t]) > 1.0
    assert all(seen.values()), seen


def _moves(m, pos, rng, n_each):
    """Crankshafts and pivots with the frames (and the orientation particle), frame
    rotations, attachment moves and scattered particles: (kind, idx, new)."""
    c = np.asarray(m.chains[0])
    s = np.asarray(m.sides)
    mo = m.bead_orientation
    n = len(c)
    out = []
    for _ in range(n_each):
        i = int(rng.integers(1, n - 1))
        j = int(rng.integers(i, min(n - 2, i + 6) + 1))
        a, b = pos[c[i - 1]], pos[c[j + 1]]
        R = axis_rotation((b - a) / np.linalg.norm(b - a), rng.uniform(-np.pi, np.pi))
        idx = np.concatenate([c[i:j + 1], s[i - 1:j + 1]])
        out.append(("crankshaft", idx, (pos[idx] - a) @ R.T + a))
        k = int(rng.integers(0, n - 1))
        R = random_rotation(rng, np.pi)
        idx = np.concatenate([c[k + 1:], s[k:]])
        new = (pos[idx] - pos[c[k]]) @ R.T + pos[c[k]]
        att_new = new[len(c[k + 1:]) - 1]
        out.append(("pivot", np.append(idx, mo),
                    np.vstack([new, pos[mo] + att_new - pos[c[-1]]])))
        q = int(rng.integers(0, n - 1))
        t = pos[c[q + 1]] - pos[c[q]]
        R = axis_rotation(t / np.linalg.norm(t), rng.uniform(-np.pi, np.pi))
        out.append(("frame", np.array([s[q]]), (pos[[s[q]]] - pos[c[q]]) @ R.T + pos[c[q]]))
        out.append(("attachment", np.array([c[-1]]),
                    pos[[c[-1]]] + rng.normal(scale=3.0, size=(1, 3))))
        out.append(("orientation", np.array([mo]), pos[[mo]] + rng.normal(scale=5.0,
                                                                          size=(1, 3))))
        idx = rng.choice(len(pos), size=6, replace=False)
        out.append(("scatter", idx, pos[idx] + rng.normal(scale=3.0, size=(6, 3))))
    return out


def test_delta_equals_the_difference_of_two_openmm_energies(plect):
    m, le, eng = plect
    le.set_trap_angle(0.0)
    eng.set_parameter("trap_angle", 0.0)
    rng = np.random.default_rng(8)
    changed = dict.fromkeys(le.terms, 0)
    for pos in (m.positions, _random_conf(m, rng), _random_conf(m, rng)):
        before = _terms(eng, m, pos)
        for kind, idx, new in _moves(m, pos, rng, 6):
            moved = pos.copy()
            moved[idx] = new
            after = _terms(eng, m, moved)
            mine = le.delta_terms(pos, idx, new)
            for t in le.terms:
                want = after[t] - before[t]
                tol = max(REL * max(abs(after[t]), abs(before[t])), ABS)
                assert abs(mine[t] - want) <= tol, (kind, t, mine[t], want)
                changed[t] += abs(want) > 1.0
    assert all(v > 3 for v in changed.values()), changed


@pytest.mark.parametrize("spread", [False, True])
def test_rigid_moves_in_the_loop_add_up_to_the_openmm_change(plect, spread):
    """The compiled loop (rigid crankshafts and pivots, frame runs with their own two-joint
    difference, particle moves, the trap) summed over accepted moves equals OpenMM's
    change, term by term, from a crumpled, twisted start; with ``twist_spread`` the
    crankshafts and pivots also spin every frame (their energy change is then that of all
    joints)."""
    from dnabraid.run.twist_moves import PlectonemeMoves

    m, le, eng = plect
    le.set_trap_angle(0.7)
    eng.set_parameter("trap_angle", 0.7)
    rng = np.random.default_rng(3)
    pos = _random_conf(m, rng)
    mv = PlectonemeMoves(le, m.chains[0], m.sides, m.bead_orientation, m.fixed, m.dna.kT,
                         moves_per_call=4000, sweep_nm=20.0, seed=5, twist_spread=spread)
    before = _terms(eng, m, pos)
    new, terms = mv.run(pos, 4000)
    after = _terms(eng, m, new)
    for k, t in enumerate(TERMS):
        if t not in after:  # a term the plectoneme does not have (capsule, chiral)
            assert terms[k] == 0.0, t
            continue
        want = after[t] - before[t]
        assert abs(terms[k] - want) <= 1e-8 * (1.0 + abs(after[t]) + abs(before[t])), (
            t, terms[k], want)
    assert all(mv.stats[k].accepted > 50 for k in mv.kinds), mv.summary()


def test_changed_twist_expression_is_refused():
    m = make_scene("plectoneme", {"length_nm": 60.0, "mc_moves": 0}).build()
    for f in m.system.getForces():
        if f.getName() == "twist":
            f.setEnergyFunction(f.getEnergyFunction().replace("0.5*g*om^2", "g*(1-cos(om))"))
    with pytest.raises(ValueError, match="'twist' has the energy"):
        LocalEnergy(m)
