"""Replica exchange over the pulling force (dnabraid.run.ladder.ForceLadder).

The swap is exact only if it changes nothing but the pull term and the acceptance uses both
rungs' energies; checked on a pulled harmonic spring, whose rung distributions are exact
(z ~ Normal(F / k, kT / k)), through a ladder whose rungs' own moves are too small to
cross between the rungs' means in the run (the swaps must do it), and on the braid's
LocalEnergy: ``set_pull_force`` changes the energy by -(F' - F) z of the bead centre.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.kernels.chain import LocalEnergy
from dnabraid.run.ladder import ForceLadder
from dnabraid.scenes import make_scene

TOL_SEM = 4.0


class _Spring:
    """U = k z^2 / 2 - F z for one coordinate (pN, nm), the LocalEnergy interface the
    ladder uses."""

    def __init__(self, k):
        self.k = k
        self.F = 0.0

    def set_trap_angle(self, a):
        pass

    def set_pull_force(self, f):
        self.F = f

    def total(self, pos):
        z = float(pos[0])
        return 0.5 * self.k * z * z - self.F * z


class _SpringMoves:
    """Metropolis steps of width ``step`` on the spring's energy."""

    def __init__(self, energy, kT, step, seed):
        self.energy = energy
        self.kT = kT
        self.step = step
        self.rng = np.random.default_rng(seed)

    def run(self, pos, n):
        z = float(pos[0])
        e = self.energy
        u = e.total([z])
        for _ in range(n):
            y = z + self.step * (2 * self.rng.random() - 1)
            v = e.total([y])
            if v <= u or self.rng.random() < math.exp(-(v - u) / self.kT):
                z, u = y, v
        return np.array([z]), None


def test_force_ladder_samples_each_rungs_exact_distribution():
    """Rungs at 1, 1.5, 2, 2.5, 3 pN on a spring of k = 0.05 pN/nm (kT 4.114 pN nm):
    <z> = F / k (20 ... 60 nm), var = kT / k (82.3 nm^2). Every state starts at the top
    rung's mean (60 nm) and moves by at most 2 nm per step, 20 steps per round (about
    5 nm rms per round against the rungs' 10 nm spacing and 9 nm spread; swaps carry the
    states between the rungs). Each rung's mean of z and of (z - F / k)^2 within 4 SEM
    (40 batch means) of F / k and kT / k."""
    kT, k = 4.114, 0.05
    forces = [1.0, 1.5, 2.0, 2.5, 3.0]
    e = _Spring(k)
    mv = _SpringMoves(e, kT, 2.0, seed=3)
    lad = ForceLadder(mv, forces, 0.0, kT, seed=4)
    for i in range(len(forces)):
        lad.pos[i] = np.array([forces[-1] / k])
    for _ in range(300):
        lad.round(20)
    zs = []
    for _ in range(4000):
        lad.round(20)
        zs.append([float(p[0]) for p in lad.pos])
    zs = np.array(zs)
    for i, F in enumerate(forces):
        x = zs[:, i]
        b = x.reshape(40, -1).mean(axis=1)
        sem = b.std(ddof=1) / math.sqrt(len(b))
        assert abs(x.mean() - F / k) < TOL_SEM * sem, (F, x.mean(), sem)
        q = ((x - F / k) ** 2).reshape(40, -1).mean(axis=1)
        qsem = q.std(ddof=1) / math.sqrt(len(q))
        assert abs(q.mean() - kT / k) < TOL_SEM * qsem, (F, q.mean(), qsem)
    acc = lad.acceptance()
    assert all(a is not None and 0.2 < a < 0.95 for a in acc), acc
    assert lad.round_trips >= 5


def test_set_pull_force_changes_only_the_pull_term():
    """On the braid: the total energy at F' minus that at F is -(F' - F) z_centre (the
    System's pull acts on the bead centre alone), to round-off; the other terms unchanged."""
    s = make_scene("braid", {"turns": [1.0], "mc_moves": 0})
    m = s.build()
    e = LocalEnergy(m)
    pos = s.built_start(m, 1.0)
    f0 = e.pull_force
    assert f0 == pytest.approx(s.force_pN, rel=1e-12)
    t0 = e.total_terms(pos)
    e.set_pull_force(3.7)
    t1 = e.total_terms(pos)
    z = pos[m.bead_center, 2]
    assert t1["pull"] - t0["pull"] == pytest.approx(-(3.7 - f0) * z, rel=1e-12)
    assert all(t1[k] == t0[k] for k in t0 if k != "pull")


def test_force_ladder_refuses_bad_rungs():
    e = _Spring(1.0)
    mv = _SpringMoves(e, 4.1, 0.5, 1)
    with pytest.raises(ValueError, match="increase"):
        ForceLadder(mv, [2.0, 1.0], 0.0, 4.1, 1)
    with pytest.raises(ValueError, match="> 0"):
        ForceLadder(mv, [0.0, 1.0], 0.0, 4.1, 1)
