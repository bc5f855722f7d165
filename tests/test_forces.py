"""Every energy term against its numpy twin and against finite differences.

OpenMM runs on the Reference platform (double precision). Tolerances: relative 1e-6 on
energies and forces against the twin; finite differences (central, h = 1e-5 nm) of the
twin's energy against its forces to 1e-5 relative.
"""

import numpy as np
import pytest
from _openmm_eval import openmm_energy_forces

from dnabraid import forces
from dnabraid.forces import reference as ref

RTOL_TWIN = 1e-6
RTOL_FD = 1e-5
SEED = 20261122




def finite_difference(fun, pos, h=1e-5):
    g = np.zeros_like(pos)
    for i in range(pos.shape[0]):
        for k in range(3):
            p1 = pos.copy()
            p1[i, k] += h
            p2 = pos.copy()
            p2[i, k] -= h
            g[i, k] = -(fun(p1) - fun(p2)) / (2 * h)
    return g


def random_chain(n, b=5.0, lp=50.0, rng=None):
    rng = rng or np.random.default_rng(SEED)
    pos = np.zeros((n, 3))
    t = np.array([0, 0, 1.0])
    for i in range(1, n):
        t = t + rng.normal(scale=np.sqrt(b / lp), size=3)
        t /= np.linalg.norm(t)
        pos[i] = pos[i - 1] + b * t * rng.uniform(0.9, 1.1)
    return pos


def check(force, twin, pos):
    e, f = openmm_energy_forces(force, pos)
    e_ref, f_ref = twin(pos)
    scale = max(1.0, np.max(np.abs(f_ref)))
    assert e == pytest.approx(e_ref, rel=RTOL_TWIN, abs=1e-9)
    np.testing.assert_allclose(f, f_ref, rtol=0, atol=RTOL_TWIN * scale)
    f_fd = finite_difference(lambda p: twin(p)[0], pos)
    np.testing.assert_allclose(f_ref, f_fd, rtol=0, atol=RTOL_FD * scale)


def test_stretch():
    pos = random_chain(12)
    bonds = np.array([(i, i + 1) for i in range(11)])
    k, r0 = 220.0, 5.0
    check(forces.stretch_force(bonds, k, r0), lambda p: ref.stretch(p, bonds, k, r0), pos)


def test_bending():
    pos = random_chain(12, lp=5.0)
    trip = np.array([(i, i + 1, i + 2) for i in range(10)])
    kappa = 41.3
    check(forces.bending_force(trip, kappa), lambda p: ref.bending(p, trip, kappa), pos)


def test_wca():
    rng = np.random.default_rng(SEED)
    pos = rng.uniform(0, 12, size=(30, 3))
    sigma, eps = 4.9, 4.114
    excl = forces.wca_exclusions([np.arange(15), np.arange(15, 30)], 5.0, sigma)
    f = forces.wca_force(30, sigma, eps, exclusions=excl)
    e_ref, _ = ref.wca(pos, sigma, eps, excl)
    assert e_ref > 0  # the random box has overlaps: the test exercises the repulsion
    check(f, lambda p: ref.wca(p, sigma, eps, excl), pos)


def test_wca_on_a_subset_of_particles():
    """Only ``particles`` interact (frame particles of twisted DNA are left out)."""
    rng = np.random.default_rng(5)
    pos = rng.uniform(0, 12.0, size=(30, 3))
    sigma, eps = 4.0, 4.1
    sub = list(range(0, 30, 3)) + [1, 2]
    f = forces.wca_force(30, sigma, eps, particles=sub)
    e_ref, _ = ref.wca(pos, sigma, eps, particles=sub)
    assert e_ref > 0
    check(f, lambda p: ref.wca(p, sigma, eps, particles=sub), pos)


def test_wall_and_pull():
    rng = np.random.default_rng(SEED)
    pos = rng.uniform(-3, 3, size=(8, 3))
    check(forces.wall_force(range(8), 2.45, 37.0), lambda p: ref.wall(p, range(8), 2.45, 37.0),
          pos)
    check(forces.pull_force([3, 5], [0.5, 0.5], 2.0),
          lambda p: ref.pull(p, [3, 5], [0.5, 0.5], 2.0), pos)


def test_trap():
    rng = np.random.default_rng(SEED)
    pos = rng.uniform(-20, 20, size=(2, 3))
    check(forces.trap_force(0, 1, 2000.0, 1.3, 3.0),
          lambda p: ref.trap(p, 0, 1, 2000.0, 1.3, 3.0), pos)


def test_analytic_points():
    """Zero at rest; WCA value and slope zero at the cutoff; trap torque = -K sin(lag)."""
    sigma, eps = 4.9, 4.114
    rc = 2 ** (1 / 6) * sigma
    for r in (rc, rc * (1 - 1e-7)):
        e, f = ref.wca(np.array([[0, 0, 0], [r, 0, 0]]), sigma, eps)
        assert abs(e) < 1e-5 and np.max(np.abs(f)) < 1e-4
    e, f = ref.stretch(np.array([[0, 0, 0], [5.0, 0, 0]]), [(0, 1)], 220.0, 5.0)
    assert e == 0 and np.all(f == 0)
    e, f = ref.bending(np.array([[0, 0, 0], [0, 0, 5.0], [0, 0, 10.0]]), [(0, 1, 2)], 40.0)
    assert abs(e) < 1e-12 and np.max(np.abs(f)) < 1e-12
    lag = 0.2
    p = np.array([[0, 0, 0], [20 * np.cos(1.0 + lag), 20 * np.sin(1.0 + lag), 0]])
    assert ref.trap_torque(p, 0, 1, 2000.0, 1.0) == pytest.approx(-2000 * np.sin(lag))
    # torque = -dU/dphi, checked by rotating the bead axis
    h = 1e-6
    rot = [np.array([[0, 0, 0], [20 * np.cos(1.0 + lag + s), 20 * np.sin(1.0 + lag + s), 0]])
           for s in (h, -h)]
    dU = (ref.trap(rot[0], 0, 1, 2000.0, 1.0)[0] - ref.trap(rot[1], 0, 1, 2000.0, 1.0)[0]) / (2 * h)
    assert -dU == pytest.approx(-2000 * np.sin(lag), rel=1e-6)
