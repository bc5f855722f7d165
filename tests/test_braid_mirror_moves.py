"""The braid's compiled Metropolis moves are handedness-neutral, sample path by sample path.

A braid at turns +n and its y -> -y mirror image at -n (trap angle negated) have the same
energy at alpha = 0. Fed the mirrored random numbers (per kind: the rotation angles'
uniforms u -> 1 - u for crankshaft, twist, sway, pivot and tilt, the shear's and the
sway's azimuth u -> 1 - u, the bead move's Gaussian y negated; everything else kept), the
chain from the mirrored start must be the exact mirror of the original chain, move by move:
every proposal, every Metropolis(-Hastings) decision and every topology (catenation)
decision mirror-covariant. Then no move kind can make z(+n) differ from z(-n) in law.
The chains are re-set to the exact mirror after every block of 1000 moves, so round-off
(1e-12 nm measured per block, workflows/results/braid_mirror_moves.md) does not grow; a
single handedness-dependent decision in a block separates the chains by ~0.1-10 nm, and
also changes the per-kind counts. Tolerance: 1e-6 nm.

The negative control (twist's angle not mirrored) shows that the comparison sees a kind
whose proposal is not covariant. See workflows/braid_mirror_moves.py for the statistical
counterpart (independent chains at +-n with batch-means errors).
"""

from __future__ import annotations

import numpy as np
import pytest

from dnabraid.run.chain_moves import MIRRORED_UNIFORMS, BraidMoves, mirror_random
from dnabraid.scenes import make_scene

MIRROR = np.array([1.0, -1.0, 1.0])
#: a handedness-dependent decision moves beads by >> this; round-off is ~1e-12 nm
TOL_NM = 1e-6
AMPS = dict(crank_angle_rad=2.0, bead_move_nm=0.3, shear_nm=3.0, shear_z_nm=1.0,
            twist_rad=0.05, sway_rad=0.1, pivot_rad=0.15, tilt_rad=0.1, stretch_eps=0.01,
            breathe_eps=0.1, breathe_max_beads=40, crank_max_beads=40)


def _mirror_random(cum, uni, gau, mirrored=MIRRORED_UNIFORMS):
    return mirror_random(cum, uni, gau, mirrored)


def _run(mv, pos, uni, gau):
    return mv.run_with(pos, uni, gau)[2]


def _coupled(turns, blocks, mirrored=MIRRORED_UNIFORMS, seed=1):
    sc = make_scene("braid", {"length_nm": 100.0, "force_pN": 2.0, "turns": [turns],
                              "replicas": 1, "seed": seed})
    m = sc.build()
    pos = np.array(sc.start_positions(m, turns), float)
    mp = BraidMoves.for_model(m, moves_per_call=1000, seed=seed, guard_every=0, **AMPS)
    mm = BraidMoves.for_model(m, moves_per_call=1000, seed=seed, guard_every=0, **AMPS)
    mp.energy.set_trap_angle(2 * np.pi * turns)
    mm.energy.set_trap_angle(-2 * np.pi * turns)
    mm.stretch_ratio = mp._ratio(pos)
    rng = np.random.default_rng([seed, 0xC0])
    worst, same, cat = 0.0, True, 0.0
    for _ in range(blocks):
        neg = pos * MIRROR
        uni, gau = rng.random((1000, 6)), rng.standard_normal((1000, 3))
        u2, g2 = _mirror_random(mp._cum, uni, gau, mirrored)
        sp, sm = mp._stats.copy(), mm._stats.copy()
        cp = _run(mp, pos, uni, gau)
        cm = _run(mm, neg, u2, g2)
        worst = max(worst, float(np.abs(neg - pos * MIRROR).max()))
        same &= bool(np.array_equal(mp._stats - sp, mm._stats - sm))
        cat = max(cat, abs(cp + cm))
    return worst, same, cat, mp._stats.copy()


@pytest.mark.parametrize("turns", [1.0, 1.25])
def test_every_braid_move_kind_is_mirror_covariant(turns):
    worst, same, cat, stats = _coupled(turns, 40)
    assert worst < TOL_NM and same, (worst, same)
    assert cat < 1e-9
    # every kind accepted, and the topology refused crankshafts: the branches were taken
    assert np.all(stats[:, 2] > 100), stats
    assert stats[0, 1] > 0
    assert abs(stats[0, 2] / stats[0, 0] - 0.25) < 0.2  # not a frozen chain


def test_the_mirror_comparison_sees_a_kind_that_is_not_covariant():
    """Negative control: the twist's angle left unmirrored (as if the kernel turned both
    images the same way) separates the chains at once."""
    broken = {k: v for k, v in MIRRORED_UNIFORMS.items() if k != 3}
    worst, _, _, _ = _coupled(1.25, 5, broken)
    assert worst > 1e-3


def test_the_image_of_a_mirror_pair_draws_the_mirrored_moves():
    """``mirror = "image"`` gives the scene's moves the mirrored random numbers
    (dnabraid.run.chain_moves.mirror_random, the map the tests above use): with one
    seed, the image's chain from the mirrored start is the mirror of the original's
    through the public ``run``, the per-kind counts equal."""
    keys = {"length_nm": 100.0, "force_pN": 2.0, "turns": [1.25], "replicas": 1,
            "mc_moves": 1000, "seed": 3}
    orig = make_scene("braid", dict(keys, mirror="original"))
    img = make_scene("braid", dict(keys, mirror="image"))
    mo, mi = orig.build(), img.build()
    assert not mo.moves.mirror and mi.moves.mirror
    po = np.array(orig.start_positions(mo, 1.25), float)
    pi = np.array(img.start_positions(mi, -1.25), float)
    assert np.abs(pi - po * MIRROR).max() < 1e-9
    mo.moves.energy.set_trap_angle(2 * np.pi * 1.25)
    mi.moves.energy.set_trap_angle(-2 * np.pi * 1.25)
    mi.moves.stretch_ratio = mo.moves._ratio(po)
    for _ in range(10):
        po, _ = mo.moves.run(po)
        pi, _ = mi.moves.run(pi)
        assert np.abs(pi - po * MIRROR).max() < TOL_NM
    assert np.array_equal(mo.moves._stats, mi.moves._stats)
