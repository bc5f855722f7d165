"""The segment-pair terms in the compiled local energies (dnabraid.kernels.segment_terms): the
capsule contact between strands and the chiral term, against OpenMM (their PythonForces,
Reference platform) and against the numpy twins (the evaluators' numpy backends), their
change under moves of a few, many and all particles, and the braid moves' loop with both
terms summing to OpenMM's change.

Configurations: the braid's built start at alpha = 2 pN with the capsule contact, at
several turn values, beads shaken by 0.8 nm (capsule overlaps, facing segments inside the
chiral range). Tolerance: relative 1e-9 or 1e-6 pN nm absolute (round-off; the kernels
evaluate the same expressions in another order).
"""

from __future__ import annotations

import numpy as np
import pytest

from dnabraid.forces.chiral import ChiralEvaluator
from dnabraid.forces.segment_contact import CapsuleEvaluator
from dnabraid.kernels import TERMS, LocalEnergy
from dnabraid.kernels.segment_terms import read_python_force
from dnabraid.run.chain_moves import BraidMoves
from dnabraid.run.engine import Engine
from dnabraid.scenes import make_scene

REL = 1e-9
ABS = 1e-6


def _scene(**kw):
    return make_scene("braid", dict({"length_nm": 100.0, "force_pN": 2.0, "replicas": 1,
                                     "turns": [0.0], "contact": "capsules", "alpha": 2.0},
                                    **kw))


def _configs(sc, m, rng, turns=(0.0, 1.5, -2.0)):
    out = []
    for n in turns:
        pos = sc.start_positions(m, n)
        p = pos + rng.normal(scale=0.8, size=pos.shape)
        for ch in m.chains:
            p[ch[0]] = pos[ch[0]]
        out.append((n, p))
    return out


def _group_energies(eng, m, pos):
    eng.set_positions(pos)
    return {g: eng.energy_pN_nm(groups=[g]) for g in set(m.forces.values())}


def _by_group(m, terms):
    out = {}
    for t, v in terms.items():
        out[m.forces[t]] = out.get(m.forces[t], 0.0) + v
    return out


def _set_angle(eng, le, n):
    eng.context.setParameter("trap_angle", 2 * np.pi * n)
    le.set_trap_angle(2 * np.pi * n)


@pytest.fixture(scope="module")
def braid():
    sc = _scene()
    m = sc.build()
    return sc, m, LocalEnergy(m), Engine.for_model(m, platform="Reference")


def test_segment_terms_equal_openmm_and_the_numpy_twins(braid):
    sc, m, le, eng = braid
    assert {"capsule", "chiral"} <= set(le.terms)
    forces = {m.system.getForce(i).getName(): m.system.getForce(i)
              for i in range(m.system.getNumForces())}
    cap = read_python_force(forces["capsule"])
    chi = read_python_force(forces["chiral"])
    assert isinstance(cap, CapsuleEvaluator) and isinstance(chi, ChiralEvaluator)
    cap.numba = False
    chi.backend = "numpy"
    parts = np.array(list(forces["chiral"].getParticles()))
    alpha = 2.0
    seen = {"capsule": False, "chiral": False}
    for n, pos in _configs(sc, m, np.random.default_rng(3)):
        _set_angle(eng, le, n)
        ref = _group_energies(eng, m, pos)
        mine = le.total_terms(pos)
        got = _by_group(m, mine)
        for g in ref:
            assert abs(got[g] - ref[g]) <= max(REL * abs(ref[g]), ABS), (n, g, got[g], ref[g])
        # the numpy twins, in the forces' own particle numbering
        e_cap, _ = cap.energy_grad(pos[list(forces["capsule"].getParticles())], cap_k(m))
        e_chi, _ = chi.energy_grad(pos[parts])
        assert abs(mine["capsule"] - e_cap) <= max(REL * abs(e_cap), ABS)
        assert abs(mine["chiral"] - alpha * e_chi) <= max(REL * abs(alpha * e_chi), ABS)
        seen["capsule"] |= mine["capsule"] > 1.0
        seen["chiral"] |= abs(mine["chiral"]) > 1.0
    assert all(seen.values()), seen


def cap_k(m):
    from dnabraid.units import PN_NM_IN_KJ_MOL

    f = [m.system.getForce(i) for i in range(m.system.getNumForces())
         if m.system.getForce(i).getName() == "capsule"][0]
    return f.getGlobalParameters()["capsule_k"] / PN_NM_IN_KJ_MOL


def test_segment_deltas_equal_openmm_differences(braid):
    sc, m, le, eng = braid
    rng = np.random.default_rng(4)
    n_pos = m.system.getNumParticles()
    strand = np.asarray(m.chains[0])
    for n, pos in _configs(sc, m, rng, turns=(0.5, -1.0)):
        _set_angle(eng, le, n)
        before = _group_energies(eng, m, pos)
        for _ in range(6):
            # one bead, a few (the per-segment loop), many and all (the sweeps along z)
            for idx in (strand[rng.integers(1, len(strand))][None],
                        rng.choice(n_pos, 5, replace=False),
                        rng.choice(n_pos, 40, replace=False), np.arange(n_pos)):
                new = pos[idx] + rng.normal(scale=1.0, size=(len(idx), 3))
                moved = pos.copy()
                moved[idx] = new
                after = _group_energies(eng, m, moved)
                got = _by_group(m, le.delta_terms(pos, idx, new))
                for g in after:
                    want = after[g] - before[g]
                    tol = max(REL * max(abs(after[g]), abs(before[g])), ABS)
                    assert abs(got.get(g, 0.0) - want) <= tol, (g, got.get(g), want)


@pytest.mark.parametrize("turns", [1.5, -1.5])
def test_braid_moves_with_capsules_and_chirality_add_up_to_the_openmm_change(braid, turns):
    sc, m, le, eng = braid
    pos = sc.start_positions(m, turns)
    mv = BraidMoves(le, m.chains, m.fixed, m.bead_center, m.dna.kT, moves_per_call=1,
                    crank_angle_rad=2.5, bead_move_nm=0.4, shear_nm=3.0, shear_z_nm=1.0,
                    twist_rad=0.05, sway_rad=0.1, pivot_rad=0.15, tilt_rad=0.1,
                    stretch_eps=0.01, breathe_eps=0.1, breathe_max_beads=12,
                    weights=(1.0,) * 9, seed=2)
    _set_angle(eng, le, turns)
    e0 = {t: v for t, v in le.total_terms(pos).items()}
    before = _group_energies(eng, m, pos)
    new, terms = mv.run(pos, 4000)
    after = _group_energies(eng, m, new)
    got = _by_group(m, {t: terms[TERMS.index(t)] for t in le.terms})
    for g in after:
        want = after[g] - before[g]
        assert abs(got[g] - want) <= 1e-8 * (1.0 + abs(after[g]) + abs(before[g])), g
    e1 = le.total_terms(new)
    for t in ("capsule", "chiral"):  # the terms moved, and by their local differences
        assert abs(terms[TERMS.index(t)] - (e1[t] - e0[t])) <= 1e-8 * (1 + abs(e0[t]))
    assert abs(e1["chiral"] - e0["chiral"]) > 0.1
    assert all(mv.stats[k].accepted > 20 for k in mv.kinds)
