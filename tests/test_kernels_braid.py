"""The braid's terms in the compiled local energies (link, trap, beadwall, pull on the bead
centre, with the strands' stretch, bend, WCA and wall) against OpenMM (Reference platform),
the compiled catenation against dnabraid.geometry.curves, and the braid moves' loop.

Configurations: the built start at several turn values, randomly perturbed (beads shaken
by 1.5 nm: WCA overlaps, wall contacts), the top tilted and turned against the trap, DNA
beads pushed into the magnetic bead. Tolerance as tests/test_kernels.py: relative 1e-9 or
1e-6 pN nm absolute.
"""

from __future__ import annotations

import numpy as np
import pytest

from dnabraid.analysis.stats import blocking_sem
from dnabraid.geometry.curves import catenation_number
from dnabraid.kernels import TERMS, LocalEnergy
from dnabraid.kernels.braid_moves import catenation
from dnabraid.run.chain_moves import BraidMoves
from dnabraid.run.engine import Engine
from dnabraid.scenes import make_scene

REL = 1e-9
ABS = 1e-6


def _scene(**kw):
    return make_scene("braid", dict({"length_nm": 100.0, "force_pN": 2.0, "replicas": 1,
                                     "turns": [0.0], "mc_moves": 0}, **kw))


def _configs(sc, m, rng, turns=(0.0, 1.5, -2.0)):
    out = []
    R = sc.bead_radius_nm
    c = m.bead_center
    dna = [int(i) for ch in m.chains for i in ch[1:-2]]
    for n in turns:
        pos = sc.start_positions(m, n)
        out.append((n, pos))
        p = pos + rng.normal(scale=1.5, size=pos.shape)
        for ch in m.chains:
            p[ch[0]] = pos[ch[0]]
        p[m.chains[0][3], 2] = -1.0  # into the wall
        # a DNA bead pushed into the magnetic bead, the top turned and tilted
        k = dna[-1]
        p[k] = p[c] + (R - 3.0) * (p[k] - p[c]) / np.linalg.norm(p[k] - p[c])
        p[m.attachments[1]] += np.array([1.0, 3.0, 2.0])
        out.append((n, p))
    return out


def _openmm(eng, m, pos):
    eng.set_positions(pos)
    return {t: eng.energy_pN_nm(groups=[g]) for t, g in m.forces.items()}


def _set_angle(eng, le, n):
    eng.context.setParameter("trap_angle", 2 * np.pi * n)
    le.set_trap_angle(2 * np.pi * n)


def test_braid_terms_equal_openmm():
    sc = _scene()
    m = sc.build()
    le = LocalEnergy(m)
    assert set(le.terms) == set(m.forces) <= set(TERMS)
    eng = Engine.for_model(m, platform="Reference")
    rng = np.random.default_rng(3)
    seen = dict.fromkeys(le.terms, False)
    for n, pos in _configs(sc, m, rng):
        _set_angle(eng, le, n)
        ref = _openmm(eng, m, pos)
        mine = le.total_terms(pos)
        for t in le.terms:
            assert abs(mine[t] - ref[t]) <= max(REL * abs(ref[t]), ABS), (n, t, mine[t], ref[t])
            seen[t] |= abs(ref[t]) > 1.0
    assert all(seen.values()), seen


def test_braid_delta_equals_openmm_difference():
    sc = _scene()
    m = sc.build()
    le = LocalEnergy(m)
    eng = Engine.for_model(m, platform="Reference")
    rng = np.random.default_rng(4)
    top = [m.bead_center, *m.attachments]
    for n, pos in _configs(sc, m, rng, turns=(0.5, -1.0)):
        _set_angle(eng, le, n)
        before = _openmm(eng, m, pos)
        for _ in range(10):
            for idx in (np.array(top), np.array([m.attachments[0]]), np.array([m.bead_center]),
                        rng.choice(len(pos), 6, replace=False),
                        # large moved sets: the WCA change from two sweeps along z
                        rng.choice(len(pos), 30, replace=False), np.arange(len(pos))):
                new = pos[idx] + rng.normal(scale=2.0, size=(len(idx), 3))
                moved = pos.copy()
                moved[idx] = new
                after = _openmm(eng, m, moved)
                mine = le.delta_terms(pos, idx, new)
                for t in le.terms:
                    want = after[t] - before[t]
                    tol = max(REL * max(abs(after[t]), abs(before[t])), ABS)
                    assert abs(mine[t] - want) <= tol, (t, mine[t], want)


def test_compiled_catenation_equals_numpy():
    sc = _scene()
    m = sc.build()
    rng = np.random.default_rng(5)
    for n, pos in _configs(sc, m, rng, turns=(0.0, 1.0, -2.5)):
        want = catenation_number(pos[m.chains[0]], pos[m.chains[1]])
        assert abs(catenation(pos, *m.chains) - want) < 1e-9
        assert abs(want - n) < 0.2


@pytest.mark.parametrize("turns", [0.0, 1.5])
def test_braid_moves_add_up_to_the_openmm_change_and_keep_the_topology(turns):
    sc = _scene()
    m = sc.build()
    eng = Engine.for_model(m, platform="Reference")
    pos = sc.start_positions(m, turns)
    mv = BraidMoves.for_model(m, moves_per_call=1, crank_angle_rad=2.5, bead_move_nm=0.4,
                              shear_nm=3.0, shear_z_nm=1.0, twist_rad=0.05, sway_rad=0.1,
                              pivot_rad=0.15, tilt_rad=0.1, stretch_eps=0.01,
                              breathe_eps=0.1, breathe_max_beads=12,
                              weights=(1.0,) * 9, seed=2)
    _set_angle(eng, mv.energy, turns)
    before = _openmm(eng, m, pos)
    new, terms = mv.run(pos, 8000)
    after = _openmm(eng, m, new)
    for k, t in enumerate(TERMS):
        want = after[t] - before[t] if t in after else 0.0
        assert abs(terms[k] - want) <= 1e-8 * (1.0 + abs(after.get(t, 0.0))
                                               + abs(before.get(t, 0.0))), t
    assert all(mv.stats[k].accepted > 50 for k in mv.kinds)
    cat = catenation_number(new[m.chains[0]], new[m.chains[1]])
    assert abs(cat - turns) < 0.5 and abs(cat - mv.catenation) < 1e-6
    # fixed beads never move
    assert np.array_equal(new[list(m.fixed)], pos[list(m.fixed)])


def _passage_geometry():
    """Strands straight up at x = -3 and +3 nm, strand 1's beads 9 and 11 beside bead 10
    horizontally: (positions, strand 1, strand 2)."""
    m = _scene(tether_separation_nm=6.0).build()
    pos = m.positions.copy()
    a, b = m.chains
    for k, (i, j) in enumerate(zip(a, b)):
        pos[i] = (-3.0, 0.0, 5.0 * k)
        pos[j] = (3.0, 0.0, 5.0 * k)
    pos[a[9]] = (-3.0, -2.0, 50.0)
    pos[a[11]] = (-3.0, 2.0, 50.0)
    return pos, a, b


def test_a_strand_passage_changes_the_catenation_by_one():
    """Strands straight up at x = -3 and +3 nm; strand 1's beads 9 and 11 placed beside
    bead 10 horizontally, so that bead 10 pulled to x = +9 sweeps the triangle through
    strand 2: the catenation (compiled and numpy) jumps by 1, which the moves refuse."""
    pos, a, b = _passage_geometry()
    c0 = catenation(pos, a, b)
    for x, want in ((1.0, 0.0), (9.0, 1.0)):
        p = pos.copy()
        p[a[10], 0] = x
        got = catenation(p, a, b)
        assert abs(got - catenation_number(p[a], p[b])) < 1e-9
        assert abs(abs(got - c0) - want) < 1e-3, (x, got, c0)


def _extended(pos, strand, ray=1e5):
    v = pos[strand]
    return np.vstack([v[0] - (0, 0, ray), v, v[-1] + (0, 0, ray)])


def test_no_passage_sees_the_strand_passage_and_only_allows_what_the_gauss_sum_allows():
    """The topology pre-test of the braid moves (kernels.braid_moves.no_passage): the
    strand passage of the test above is not declared safe; of random collective and local
    displacements of a braid at n = 1.5 (relative displacements up to ~10 nm against
    strand distances of ~5 nm, so both answers occur), every one declared safe changes
    the Gauss catenation by < 0.1 turn (no crossing changed), the test is symmetric
    (forward = reverse), and it never declares safe a displacement that moved a strand
    through the other (|change| > 0.5)."""
    from dnabraid.kernels.braid_moves import no_passage
    pos, a, b = _passage_geometry()
    S = np.empty((4, max(len(a), len(b)) + 1, 4))
    n1, n2 = len(a), len(b)
    V1, V2 = _extended(pos, a), _extended(pos, b)
    for x, safe in ((-2.0, True), (9.0, False)):
        p = pos.copy()
        p[a[10], 0] = x
        W1 = _extended(p, a)
        assert no_passage(V1, W1, V2, V2, 0, n1, 0, n2, S) == safe, x
        assert no_passage(V1, W1, V2, V2, 9, 11, 0, n2, S) == safe, x
    sc = _scene()
    m = sc.build()
    a, b = m.chains
    n1, n2 = len(a), len(b)
    rng = np.random.default_rng(11)
    base = sc.start_positions(m, 1.5)
    seen = {True: 0, False: 0}
    for trial in range(300):
        scale = rng.choice([0.5, 2.0, 5.0])
        p = base + rng.normal(scale=scale, size=base.shape)
        for ch in m.chains:
            p[ch[0]] = base[ch[0]]
        V1, V2, W1, W2 = (_extended(x, c) for x, c in ((base, a), (base, b), (p, a), (p, b)))
        safe = no_passage(V1, W1, V2, W2, 0, n1, 0, n2, S)
        assert safe == no_passage(W1, V1, W2, V2, 0, n1, 0, n2, S)
        d = catenation_number(p[a], p[b]) - catenation_number(base[a], base[b])
        if safe:
            assert abs(d) < 0.1, (trial, d)
        seen[bool(safe)] += 1
    assert min(seen.values()) > 20, seen


def test_the_passage_pretest_changes_no_decision():
    """Moves with and without the pre-test (same seed, all nine kinds, 4000 moves of the
    100 nm braid at n = 1.5): the same positions to the last bit and the same counts: the
    pre-test only skips Gauss sums whose answer it knows."""
    sc = _scene()
    m = sc.build()
    pos = sc.start_positions(m, 1.5)
    res = []
    for pt in (True, False):
        mv = BraidMoves.for_model(m, moves_per_call=1, crank_angle_rad=2.5, bead_move_nm=0.4,
                                  shear_nm=3.0, shear_z_nm=1.0, twist_rad=0.05, sway_rad=0.1,
                                  pivot_rad=0.15, tilt_rad=0.1, stretch_eps=0.01,
                                  breathe_eps=0.1, crank_max_beads=20, weights=(1.0,) * 9,
                                  seed=5,
                                  guard_every=0, passage_test=pt)
        mv.energy.set_trap_angle(2 * np.pi * 1.5)
        new, _ = mv.run(pos, 4000)
        res.append((new, {k: v.to_dict() for k, v in mv.stats.items()}, mv.catenation))
    assert np.array_equal(res[0][0], res[1][0])
    assert res[0][1] == res[1][1]
    assert sum(v["refused_by_constraint"] for v in res[0][1].values()) > 0
    assert abs(res[0][2] - res[1][2]) < 1e-9


def test_braid_scene_keys():
    # moves are on by default since 2026-12-06 (docs/validation.md 1.6); 0 = dynamics alone
    assert _scene().mc_moves == 0 and make_scene("braid").mc_moves == 3000
    assert _scene().build().moves is None
    assert isinstance(make_scene("braid").build().moves, BraidMoves)
    m = _scene(mc_moves=10).build()
    assert isinstance(m.moves, BraidMoves)
    # the chiral term has its compiled twin (tests/test_kernels_segments.py)
    m = _scene(mc_moves=10, alpha=0.5, contact="capsules").build()
    assert {"chiral", "capsule"} <= set(m.moves.energy.terms)


def _small_braid_samples(turns, amps, moves, samples, seed=7):
    """Attachment height, bead-centre x and y and catenation of a small braid (2 x 30 nm,
    tethers 20 nm apart, a 30 nm bead at 2 pN) sampled by the moves alone."""
    sc = make_scene("braid", {"length_nm": 30.0, "force_pN": 2.0, "turns": [turns],
                              "replicas": 1, "tether_separation_nm": 20.0,
                              "bead_radius_nm": 30.0, "seed": seed})
    m = sc.build()
    pos = np.array(sc.start_positions(m, turns), float)
    mv = BraidMoves.for_model(m, moves_per_call=moves, seed=seed, guard_every=0, **amps)
    mv.energy.set_trap_angle(2 * np.pi * turns)
    for _ in range(samples // 10):
        pos, _ = mv.run(pos)
    out = []
    for _ in range(samples):
        pos, _ = mv.run(pos)
        c = pos[m.bead_center]
        out.append((pos[list(m.attachments), 2].mean(), c[0], c[1], mv.catenation))
    return np.array(out)


def test_every_braid_move_keeps_the_distribution_of_a_rigid_move_sampler():
    """Two samplers of one Boltzmann distribution: a reference of the simplest moves (one
    particle in a symmetric ball; the bead centre turned about the fixed line through the
    attachments; the sway, a rigid turn of each strand about its fixed anchor with the
    centre translated by a function of the strands), and all eight kinds together
    (crankshaft, bead, shear, twist, sway, pivot, tilt, stretch, the last a
    Metropolis-Hastings move with its Jacobian). They must give the same extension
    (attachment height; means within 4 combined standard errors, Flyvbjerg-Petersen
    blocking of each chain) and the same spreads of it and of the bead centre's x and y
    (standard deviations within 15 %, about 3 standard errors of a standard deviation
    at these sample sizes); the catenation stays at 0. (Single-particle moves alone do
    not converge the top's spread in a test's time: x's sd read 3.2 against 7.1 nm; at
    n = 0.5 the reference's seeds differ by 1.2 nm in z, so braided states are left to
    the workflow's replica checks.)"""
    turns = 0.0
    ref = _small_braid_samples(turns, dict(crank_angle_rad=0.0, bead_move_nm=0.3,
                                           shear_nm=0.0, twist_rad=0.0, sway_rad=0.1,
                                           tilt_rad=0.2), 400, 1200)
    got = _small_braid_samples(turns, dict(crank_angle_rad=2.0, bead_move_nm=0.3,
                                           shear_nm=3.0, shear_z_nm=1.0, twist_rad=0.05,
                                           sway_rad=0.1, pivot_rad=0.15, tilt_rad=0.1,
                                           stretch_eps=0.01, breathe_eps=0.1,
                                           breathe_max_beads=6, crank_max_beads=6),
                               400, 1200, seed=8)
    se = np.hypot(blocking_sem(ref[:, 0])["sem"], blocking_sem(got[:, 0])["sem"])
    assert abs(ref[:, 0].mean() - got[:, 0].mean()) < 4 * se, (ref[:, 0].mean(),
                                                              got[:, 0].mean(), se)
    for col in (0, 1, 2):
        assert abs(got[:, col].std() / ref[:, col].std() - 1) < 0.15, (
            col, got[:, col].std(), ref[:, col].std())
    assert np.all(np.abs(got[:, 3] - turns) < 0.25)


def _breathe(pos, m, eps, u_w, u_k, wmax=40):
    """One breathe proposal on ``pos``: (new positions or None if refused, log J)."""
    from dnabraid.kernels.braid_moves import _breathe_proposal
    b1, b2 = (np.asarray(c, np.int64) for c in m.chains)
    c_ptr = np.array([0, len(b1), len(b1) + len(b2)], np.int64)
    fixed = set(int(i) for i in m.fixed)
    isf = np.array([int(i) in fixed for i in np.concatenate([b1, b2])], np.int64)
    c_fixed = np.concatenate([[0], np.cumsum(isf)]).astype(np.int64)
    n = len(pos)
    new = np.zeros((n, 3))
    idx = np.zeros(n, np.int64)
    moved = np.zeros(n, np.int64)
    lj = np.zeros(1)
    k = _breathe_proposal(pos, b1, b2, c_ptr, c_fixed, wmax, eps, u_w, u_k, new, idx, moved,
                          lj)
    if k < 0:
        return None, 0.0
    out = pos.copy()
    out[idx[:k]] = new[:k]
    return out, float(lj[0])


@pytest.mark.parametrize("turns", [0.0, 0.75])
def test_breathe_move_keeps_bonds_is_undone_by_its_reverse_and_has_its_jacobian(turns):
    """The breathe proposal (kernels.braid_moves, kind 8) on shaken braids: every strand
    bond keeps its length to round-off; the reverse move (-eps, same window) returns the
    positions to 1e-9 nm; the anchors do not move; and its log Jacobian equals log |det|
    of the map's derivative by central differences (to 1e-5) over the coordinates it
    changes (the strands' beads; the bead centre follows in the scene, not here)."""
    sc = _scene()
    m = sc.build()
    rng = np.random.default_rng(3)
    base = sc.start_positions(m, turns) + rng.normal(scale=0.3, size=(len(m.positions), 3))
    a, b = (np.asarray(c) for c in m.chains)
    for ch in m.chains:
        base[ch[0]] = sc.start_positions(m, turns)[ch[0]]
    bond = lambda p: np.r_[np.linalg.norm(np.diff(p[a], axis=0), axis=1),
                           np.linalg.norm(np.diff(p[b], axis=0), axis=1)]
    done = 0
    for eps, uw, uk in ((0.08, 0.3, 0.5), (-0.06, 0.6, 0.2), (0.05, 0.0, 0.5)):
        new, lj = _breathe(base, m, eps, uw, uk)
        assert new is not None
        assert np.allclose(bond(new), bond(base), atol=1e-9)
        assert np.array_equal(new[[a[0], b[0]]], base[[a[0], b[0]]])
        back, lj_back = _breathe(new, m, -eps, uw, uk)
        assert np.allclose(back, base, atol=1e-9)
        assert abs(lj + lj_back) < 1e-9
        # numerical Jacobian over the strands' mobile coordinates
        beads = np.r_[a[1:], b[1:]]
        x0 = base[beads].ravel()

        def f(x):
            p = base.copy()
            p[beads] = x.reshape(-1, 3)
            q, _ = _breathe(p, m, eps, uw, uk)
            return q[beads].ravel()

        h = 1e-5
        J = np.empty((len(x0), len(x0)))
        for i in range(len(x0)):
            e = np.zeros_like(x0)
            e[i] = h
            J[:, i] = (f(x0 + e) - f(x0 - e)) / (2 * h)
        sign, logdet = np.linalg.slogdet(J)
        assert sign > 0 and abs(logdet - lj) < 1e-5, (logdet, lj)
        assert abs(lj) > 0.01  # the test would see a missing factor
        done += 1
    assert done == 3
