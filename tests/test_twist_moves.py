"""Twist-aware Metropolis moves of the plectoneme (dnabraid.run.twist_moves).

The moves alone (no Brownian steps) must sample the Boltzmann distribution of a
torsionally constrained chain. Two exact references on a short chain (60 nm, 13 beads,
2 pN, no wall; excluded volume and the bead's plane cost nothing at this force: two
beads two apart meet only past a ~20 kT bend):

* A bead free to turn (trap stiffness ~0): the joint angles are then independent of the
  shape and of each other (the side angles and the bead angle map one to one, with unit
  Jacobian, onto the joint angles), so Tw is Gaussian with <Tw> = 0 and
  <Tw^2> = sum_j kT / g_j / (2 pi)^2 = L / (4 pi^2 C) (interior joints g = C kT / b, the
  clamps 2g), whatever the shape; the shape is the free discrete WLC, whose <z> and
  var(z) the transfer matrix gives (dnabraid.continuum.wlc.discrete_wlc_exact).
* A stiff trap at n turns: given the shape, the joint angles are Gaussian with their sum
  fixed to 2 pi (Lk - Wr) and Lk held by the trap, so the shape is the free WLC reweighted
  by exp(-(2 pi (n - Wr))^2 / (2 (L / C + kT / K))) (the harmonic trap in series with
  the chain's twist compliance). Exact draws of the free chain
  (dnabraid.continuum.wlc.sample_discrete_wlc) weighted so give <z>, <Wr> and
  <Tw> = n - <Wr> independently (no dynamics, no moves).

Tolerance: ``TOL_SEM`` = 4 standard errors (the moves' from blocking of their own samples,
the reference's from batches), fixed seeds. The linking number Tw + Wr must follow the
bead angle in every sample (no strand passage).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.analysis.stats import blocking_sem
from dnabraid.continuum.wlc import discrete_wlc_exact, sample_discrete_wlc
from dnabraid.geometry import ribbon as atw
from dnabraid.run.engine import Engine
from dnabraid.run.twist_moves import TWIST_KINDS, PlectonemeMoves
from dnabraid.scenes import make_scene
from dnabraid.scenes.base import SceneError

TOL_SEM = 4.0
L_NM, F_PN = 60.0, 2.0


def _model(**kw):
    return make_scene("plectoneme", dict({"length_nm": L_NM, "force_pN": F_PN,
                                          "turns": [0.0], "surface": False, "replicas": 1,
                                          "mc_moves": 0}, **kw)).build()


def _sample(m, mv, angle, n_samples, every, burn, writhe_every=1):
    mv.energy.set_trap_angle(angle)
    c, s, mo = m.chains[0], m.sides, m.bead_orientation
    pos, _ = mv.run(m.positions, burn)
    z, tw, wr, lk_err = (np.empty(n_samples) for _ in range(4))
    for k in range(n_samples):
        pos, _ = mv.run(pos, every)
        v = pos[mo] - pos[c[-1]]
        z[k] = pos[c[-1], 2] - pos[c[0], 2]
        tw[k] = atw.tether_twist(pos[c], pos[s], v)
        if k % writhe_every:
            wr[k] = lk_err[k] = np.nan
            continue
        wr[k] = atw.writhe_open(pos[c])
        lk_err[k] = tw[k] + wr[k] - math.atan2(v[1], v[0]) / (2 * math.pi)
    return z, tw, wr, lk_err


def _batch_sem(x, batches=10):
    """Standard error from the means of ``batches`` contiguous batches."""
    n = len(x) // batches
    b = np.asarray(x[:n * batches]).reshape(batches, n).mean(axis=1)
    return float(b.std(ddof=1) / math.sqrt(batches))


def _check(x, want, want_sem=0.0):
    # the larger of the blocking SEM and a 10-batch-means SEM: blocking alone read 0.020 nm
    # for the free-bead extension at seed 11 where seeds 12 and 13 read 0.13-0.15 (a slow
    # mode it missed), and the test failed at 12.8 of those underestimated SEs
    se = max(blocking_sem(x)["sem"], _batch_sem(x))
    sem = math.hypot(se, want_sem)
    assert abs(x.mean() - want) < TOL_SEM * sem, (x.mean(), want, se, want_sem)
    return se


def test_free_bead_moves_alone_give_the_exact_twist_and_extension():
    m = _model(trap_stiffness_pN_nm=1e-6)
    d = m.dna
    # frame moves weighted up: a free bead's angle is a random walk of the frame runs
    mv = PlectonemeMoves.for_model(m, moves_per_call=100, seed=11, weights=(2, 1, 6, 1))
    z, tw, wr, lk_err = _sample(m, mv, 0.0, 10000, 100, 5000, writhe_every=50)
    var_tw = L_NM / (4 * math.pi**2 * 100.0)
    _check(tw, 0.0)
    sem = _check(tw**2, var_tw)
    assert sem < 0.05 * var_tw  # the check has teeth
    ex = discrete_wlc_exact(F_PN, len(m.chains[0]) - 1, d.bead_spacing_nm, d.kappa_kT, d.kT,
                            stretch_k_pN_per_nm=d.k_bond)
    _check(z, ex["extension_nm"])
    _check((z - z.mean()) ** 2, ex["extension_var_nm2"])
    # Lk = Tw + Wr follows the (free) bead angle modulo whole turns: no passage
    lk_err = lk_err[np.isfinite(lk_err)]
    assert np.all(np.abs(lk_err - np.round(lk_err)) < 1e-6)
    for k in TWIST_KINDS:
        assert 0.05 < mv.stats[k].acceptance < 0.98, (k, mv.stats[k].acceptance)


def _reference(m, n_turns, K, n_draws=6000, batches=20, seed=2):
    """<z>, <Wr> (and batch SEs) of exact free-chain draws weighted by the twist energy at
    fixed Lk = n_turns (module docstring)."""
    d = m.dna
    C, L = 100.0, L_NM
    var_s = L / C + d.kT / K  # rad^2: twist compliance in series with the trap
    rng = np.random.default_rng(seed)
    zs = []
    for _ in range(batches):
        x = sample_discrete_wlc(F_PN, len(m.chains[0]) - 1, d.bead_spacing_nm, d.kappa_kT,
                                d.kT, stretch_k_pN_per_nm=d.k_bond,
                                n_samples=n_draws // batches, rng=rng)
        wr = np.array([atw.writhe_open(c) for c in x])
        logw = -(2 * math.pi * (n_turns - wr)) ** 2 / (2 * var_s)
        w = np.exp(logw - logw.max())
        zs.append((np.sum(w * (x[:, -1, 2] - x[:, 0, 2])) / w.sum(), np.sum(w * wr) / w.sum()))
    zs = np.array(zs)
    return zs.mean(axis=0), zs.std(axis=0, ddof=1) / math.sqrt(batches)


@pytest.mark.parametrize("spread", [False, True])
def test_trapped_moves_alone_partition_twist_and_writhe_exactly(spread):
    """Moves alone (with and without ``twist_spread``) against exact free-chain draws
    reweighted by the twist energy at fixed Lk: <z>, <Wr>, <Tw>."""
    n_turns = 0.3
    m = _model()
    K = 20000.0  # the scene's default trap
    mv = PlectonemeMoves.for_model(m, moves_per_call=100, seed=5, twist_spread=spread)
    z, tw, wr, lk_err = _sample(m, mv, 2 * math.pi * n_turns, 5000, 80, 8000)
    (z_ref, wr_ref), (z_sem, wr_sem) = _reference(m, n_turns, K)
    _check(z, z_ref, z_sem)
    wr_mc_sem = _check(wr, wr_ref, wr_sem)
    _check(tw, n_turns - wr_ref, wr_sem)
    # the writhe really takes up part of the turns, resolved by both estimates
    assert wr_ref > 5 * wr_sem and wr_ref > 5 * wr_mc_sem, (wr_ref, wr_sem, wr_mc_sem)
    # Lk = Tw + Wr equals the bead angle in every sample: the moves pass no strand
    assert np.all(np.abs(lk_err) < 1e-6), np.abs(lk_err).max()


@pytest.mark.parametrize("spread", [False, True])
def test_linking_number_is_kept_through_a_wound_chain(spread):
    """A longer chain wound 3 times at low force (the trap turned in small steps; writhe and
    contacts): over many rigid moves Tw + Wr keeps equal to the unwrapped bead angle
    (continuous, never a whole-turn jump), with and without ``twist_spread``."""
    m = make_scene("plectoneme", {"length_nm": 150.0, "force_pN": 0.3, "turns": [0.0],
                                  "replicas": 1, "mc_moves": 0}).build()
    mv = PlectonemeMoves.for_model(m, moves_per_call=200, seed=9, twist_spread=spread)
    c, s, mo = m.chains[0], m.sides, m.bead_orientation
    pos = m.positions
    unwrapped = 0.0
    prev = 0.0
    for k in range(300):
        mv.energy.set_trap_angle(min(0.1 * k, 3 * 2 * math.pi))
        pos, _ = mv.run(pos, 200)
        v = pos[mo] - pos[c[-1]]
        a = math.atan2(v[1], v[0]) / (2 * math.pi)
        unwrapped += (a - prev) - round(a - prev)
        prev = a
        lk = atw.linking_number(pos[c], pos[s], v)
        assert abs(lk - unwrapped) < 1e-6, (lk, unwrapped)
    assert unwrapped > 2.5  # the bead really turned and the chain took up the turns
    assert abs(atw.writhe_open(pos[c])) > 0.1


def test_guard_agrees_with_the_engine_and_catches_a_wrong_energy():
    m = _model()
    eng = Engine.for_model(m, platform="Reference")
    mv = PlectonemeMoves.for_model(m, moves_per_call=200, guard_every=1, seed=2)
    for _ in range(4):
        mv.attempt(eng.positions, eng.set_positions, eng.energy_pN_nm,
                   parameters=eng.parameters())
    assert mv.guard_checks == 4 and mv.guard_max_diff < 1e-6
    assert sum(mv.stats[k].accepted for k in mv.kinds) > 100
    bad = PlectonemeMoves.for_model(m, moves_per_call=200, guard_every=1, seed=2)
    with pytest.raises(RuntimeError, match="engine's energy"):
        bad.attempt(eng.positions, eng.set_positions, lambda: 0.0,
                    parameters=eng.parameters())
    with pytest.raises(RuntimeError, match="trap_angle"):
        bad.attempt(eng.positions, eng.set_positions, eng.energy_pN_nm)


def test_plectoneme_scene_wires_the_moves():
    s = make_scene("plectoneme", {"length_nm": 60.0})
    m = s.build()
    assert isinstance(m.moves, PlectonemeMoves) and m.moves.kinds == list(TWIST_KINDS)
    assert set(m.moves.energy.terms) == set(m.forces)
    assert _model().moves is None
    with pytest.raises(SceneError, match="mc_moves"):
        make_scene("plectoneme", {"alpha": 0.5})
    with pytest.raises(SceneError, match="mc_moves"):
        make_scene("plectoneme", {"stretch": "constraints"})
    with pytest.raises(SceneError, match="frame_angle_rad"):
        make_scene("plectoneme", {"frame_angle_rad": 4.0})
    with pytest.raises(SceneError, match="sweep_nm"):
        make_scene("plectoneme", {"sweep_nm": 0.0})


def test_passage_check_sees_a_bond_swept_through_another():
    """A rod pivoted about bead 2 through a bond across its path is refused; a short turn
    that stays clear is not (dnabraid.kernels.twist.passage_free)."""
    from dnabraid.kernels.twist_loop import passage_free

    pos = np.array([[10.0, -3.0, 0.0], [10.0, 3.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 5.0],
                    [0.0, 0.0, 10.0]])
    beads = np.arange(5)
    work = [np.empty(5), np.empty(5), np.empty(5), np.empty(5, np.int64)]

    def free(theta):
        return passage_free(pos, beads, 3, 4, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, theta, 6.0,
                            *work)

    assert not free(math.pi / 2)  # bead 4 sweeps through (10, 0, 0) on the bond 0-1
    assert not free(math.pi)  # past it
    assert free(0.2) and free(-math.pi / 2)
