"""Twist: the energy against its numpy twin and finite differences, Lk = Tw + Wr, writhe on
known curves, the twist fluctuations of a free chain, and nicked scenes left untwisted.

Tolerances as in test_forces.py (Reference platform, double precision); statistical
checks use Z_TOL standard errors plus a named model tolerance.
"""

import math

import numpy as np
import openmm
import pytest
from openmm import unit as u
from test_forces import check, random_chain

from dnabraid.analysis import geometry as geo
from dnabraid.analysis.stats import mean_sem
from dnabraid.forces import bending_force, stretch_force
from dnabraid.forces import reference_twist as rt
from dnabraid.forces import twist_frames as tw
from dnabraid.geometry import ribbon as atw

SEED = 20261122
Z_TOL = 4.0
#: Euler-Maruyama bias of a variance is ~ lambda dt / 2 for a mode of rate lambda; the
#: fastest twist mode of the test chain has lambda dt / 2 ~ 0.03, slow modes far less.
EM_RTOL = 0.04
#: Identity checks of exact polygon formulas (round-off and the finite closing rays).
TOL_EXACT = 1e-8


def framed_chain(n, rng, lp=8.0, arm=3.0):
    p = random_chain(n, lp=lp, rng=rng)
    sides = p[:-1] + rng.normal(scale=arm, size=(n - 1, 3))
    m = p[-1] + rng.normal(scale=5.0, size=3)
    return p, sides, m


@pytest.fixture
def conf():
    rng = np.random.default_rng(SEED)
    n = 9
    p, sides, m = framed_chain(n, rng)
    pos = np.vstack([p, sides, m])
    side = lambda i: n + i  # noqa: E731
    return n, pos, side, len(pos) - 1


def test_twist_interior_against_twin_and_fd(conf):
    n, pos, side, m = conf
    joints = [(i, i + 1, i + 2, side(i), side(i + 1)) for i in range(n - 2)]
    g = 82.3
    check(tw.twist_force(joints, g), lambda p: rt.twist(p, joints, g), pos)


def test_twist_clamps_against_twin_and_fd(conf):
    n, pos, side, m = conf
    anchor = [(0, 1, side(0))]
    check(tw.twist_anchor_force(anchor, (0, 0, 1), (1, 0, 0), 164.6),
          lambda p: rt.twist_anchor(p, anchor, (0, 0, 1), (1, 0, 0), 164.6), pos)
    bead = [(n - 2, n - 1, side(n - 2), m)]
    check(tw.twist_bead_force(bead, 164.6), lambda p: rt.twist_bead(p, bead, 164.6), pos)
    check(tw.bead_plane_force(n - 1, range(n - 1), 37.0),
          lambda p: rt.bead_plane(p, n - 1, range(n - 1), 37.0), pos)


def test_joint_angle_is_parallel_transport_angle(conf):
    """The closed form of the force equals the Rodrigues parallel-transport definition."""
    n, pos, side, m = conf
    p, s = pos[:n], pos[n:n + n - 1]
    t, uu = atw.bond_frames(p, s)
    om_def = atw.twist_angles(t[:-1], uu[:-1], t[1:], uu[1:])
    om_force, _ = rt.joint_angles(np.diff(p, axis=0)[:-1], s[:-1] - p[:-2],
                                  np.diff(p, axis=0)[1:], s[1:] - p[1:-1])
    np.testing.assert_allclose(om_force, om_def, atol=1e-12)
    assert np.max(np.abs(om_def)) > 0.5  # a real test: large angles


def test_twist_analytic_points():
    """Zero for an untwisted (parallel-transported) frame; omega for a frame turned by omega."""
    rng = np.random.default_rng(SEED)
    p = random_chain(12, lp=10.0, rng=rng)
    sides = tw.initial_side_positions(p, 4.0)
    om = atw.tether_twist(p, sides, None, per_joint=True)
    assert np.max(np.abs(om)) < 1e-12
    # rotate the frame of bond 5 onwards by 0.3 rad about each bond: joint 5 (interior
    # joint 4 -> 5; clamp first) takes 0.3 rad, all else zero
    t, uu = atw.bond_frames(p, sides)
    v = np.cross(t, uu)
    uu2 = uu.copy()
    uu2[5:] = np.cos(0.3) * uu[5:] + np.sin(0.3) * v[5:]
    om2 = atw.tether_twist(p, p[:-1] + 4.0 * uu2, None, per_joint=True)
    expect = np.zeros_like(om2)
    expect[5] = 0.3
    np.testing.assert_allclose(om2, expect, atol=1e-12)
    e, f = rt.twist(np.vstack([p, p[:-1] + 4.0 * uu2]),
                    [(i, i + 1, i + 2, 12 + i, 13 + i) for i in range(10)], 10.0)
    assert e == pytest.approx(0.5 * 10.0 * 0.3**2, rel=1e-12)


# ----------------------------------------------------------------------------- Lk = Tw + Wr
def torus_knot(p, q, n, R=3.0, r=1.0):
    th = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[(R + r * np.cos(q * th)) * np.cos(p * th),
                 (R + r * np.cos(q * th)) * np.sin(p * th), r * np.sin(q * th)]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_calugareanu_white_fuller_closed_ribbon(seed):
    """Lk(curve, curve + eps u) = Tw + Wr exactly for a closed polygon with any frame."""
    rng = np.random.default_rng(seed)
    c = torus_knot(2, 3, 150) + rng.normal(scale=0.05, size=(150, 3))
    t = np.roll(c, -1, 0) - c
    t /= np.linalg.norm(t, axis=1)[:, None]
    # a parallel-transported frame turned by a random walk of angles (steps < pi)
    base = [np.cross(t[0], [0, 0, 1.0])]
    for i in range(1, 150):
        base.append(atw.parallel_transport(base[-1], t[i - 1], t[i]))
    base = np.array(base)
    ang = np.cumsum(rng.normal(scale=0.3, size=150))
    v = np.cross(t, base)
    uu = np.cos(ang)[:, None] * base + np.sin(ang)[:, None] * v
    uu /= np.linalg.norm(uu, axis=1)[:, None]
    twist = np.sum(atw.twist_angles(t, uu, np.roll(t, -1, 0), np.roll(uu, -1, 0))) / (2 * np.pi)
    wr = geo.writhe(c)
    eps = 1e-3
    edge = np.array([c[i] + eps * w for i in range(150) for w in (uu[i - 1], uu[i])])
    lk = geo.gauss_linking_number(c, edge)
    assert abs(lk - round(lk)) < 1e-6
    assert twist + wr == pytest.approx(round(lk), abs=TOL_EXACT)


def test_open_tether_linking_equals_bead_angle():
    """Tw (clamps included) + Wr (vertical-ray closure) = bead angle / 2 pi (mod 1 -> exact)."""
    from dnabraid.geometry import random_wlc

    rng = np.random.default_rng(SEED)
    for _ in range(5):
        p = random_wlc(30, 5.0, 8.0, rng)
        sides = p[:-1] + rng.normal(size=(29, 3))
        phi = rng.uniform(-np.pi, np.pi)
        bead = np.array([np.cos(phi), np.sin(phi), rng.normal(scale=0.2)])
        lk = atw.linking_number(p, sides, bead)
        k = round(lk - phi / (2 * np.pi))
        assert lk - k == pytest.approx(phi / (2 * np.pi), abs=1e-7)


# ----------------------------------------------------------------------------- writhe
def test_writhe_of_open_helix_is_fuller_cap_area():
    """A helix of N turns closed by rays along its axis: Wr = N (1 - cos theta) (Fuller 1971),
    exactly the spherical area of its tangent polygon / 2 pi for the polygon."""
    for N, theta_deg in ((3, 30.0), (2, 60.0)):
        th = math.radians(theta_deg)
        m = 400 * N
        s = np.linspace(0, 2 * np.pi * N, m + 1)
        r, pitch = math.sin(th), 2 * np.pi * math.cos(th)  # unit speed per radian
        h = np.c_[r * np.cos(s), r * np.sin(s), pitch * s / (2 * np.pi)]
        wr = atw.writhe_open(h)
        t = np.diff(h, axis=0)
        t /= np.linalg.norm(t, axis=1)[:, None]
        z = np.tile([0.0, 0, 1], (m, 1))
        area = np.sum(geo.triangle_solid_angle(z[:-1], t[:-1], t[1:]))
        assert wr == pytest.approx(area / (2 * np.pi), abs=1e-6)
        # the polygon's tangents cut the cap's corners: relative error ~ (2 pi / 400)^2 / 12
        assert wr == pytest.approx(N * (1 - math.cos(th)), rel=2e-3)  # right-handed: > 0
        assert atw.writhe_open(h * [-1, 1, 1]) == pytest.approx(-wr, abs=1e-9)


def test_writhe_planar_and_torus_knot():
    """Planar open chain (rays in its plane): 0. Torus knots: Lk of the (parallel-transport)
    ribbon is an integer, so Tw + Wr is one; Wr changes sign under mirroring."""
    x = np.linspace(0, 10, 30)
    planar = np.c_[np.sin(x) * 3, 0 * x, x * 2]
    assert abs(atw.writhe_open(planar)) < TOL_EXACT
    c = torus_knot(2, 3, 300)
    wr = geo.writhe(c)
    t = np.roll(c, -1, 0) - c
    t /= np.linalg.norm(t, axis=1)[:, None]
    # parallel transport around the knot: twist = 0 except the closing mismatch (holonomy)
    uu = [np.cross(t[0], [0, 0, 1.0])]
    for i in range(1, 300):
        uu.append(atw.parallel_transport(uu[-1], t[i - 1], t[i]))
    hol = atw.twist_angles(t[-1], uu[-1], t[0], uu[0]) / (2 * np.pi)
    assert (wr + hol) == pytest.approx(round(wr + hol), abs=TOL_EXACT)
    # this (2,3) torus knot (R=3, r=1) is a left-handed trefoil: |Wr| ~ 3.2, below the
    # ideal trefoil's 3.41 (Katritch et al., Nature 384, 142 (1996)); its mirror has -Wr
    assert -4.0 < wr < -2.5
    assert geo.writhe(c * [1, 1, -1]) == pytest.approx(-wr, abs=TOL_EXACT)


# ----------------------------------------------------------------------------- dynamics
def free_twisted_chain(n, b=5.0, C=100.0, kT=4.114, arm=5.0):
    """A framed chain hanging from a fixed bead, surface frame clamped, top end free."""
    from dnabraid import units
    from dnabraid.forcefield import bending_stiffness_kT

    zeta = units.stokes_friction(0.5 * b)
    system = openmm.System()
    chain = [system.addParticle(0.0)] + [system.addParticle(units.friction_to_mass_amu(zeta))
                                          for _ in range(n - 1)]
    sides = [system.addParticle(units.friction_to_mass_amu(0.1 * zeta)) for _ in range(n - 1)]
    p = np.c_[np.zeros(n), np.zeros(n), b * np.arange(n)]
    pos = np.vstack([p, tw.initial_side_positions(p, arm)])
    k = 1100.0 / b
    g = C * kT / b
    system.addForce(stretch_force([(chain[i], chain[i + 1]) for i in range(n - 1)], k, b))
    system.addForce(bending_force([(chain[i], chain[i + 1], chain[i + 2]) for i in range(n - 2)],
                                  bending_stiffness_kT(b, 50.0) * kT))
    system.addForce(tw.frame_springs(chain, sides, arm, b, 0.05 * k))
    system.addForce(tw.twist_force([(chain[i], chain[i + 1], chain[i + 2], sides[i], sides[i + 1])
                                    for i in range(n - 2)], g))
    system.addForce(tw.twist_anchor_force([(chain[0], chain[1], sides[0])], (0, 0, 1), (1, 0, 0),
                                          2 * g))
    return system, pos, chain, sides, g


def test_free_chain_twist_fluctuations():
    """<omega^2> = b / C per joint and <Tw^2> = L_tw / (4 pi^2 C) for a chain whose top end is
    free to rotate (L_tw = (n - 2) b + b / 2: the surface clamp stands for half a bond)."""
    n, b, C, kT = 8, 5.0, 100.0, 4.114
    system, pos, chain, sides, g = free_twisted_chain(n, b, C, kT)
    integ = openmm.BrownianIntegrator(kT / 0.0138065 * u.kelvin, 1 / u.picosecond, 20 * u.picosecond)
    integ.setRandomNumberSeed(7)
    ctx = openmm.Context(system, integ, openmm.Platform.getPlatformByName("CPU"), {"Threads": "1"})
    ctx.setPositions(pos * u.nanometer)
    integ.step(5000)
    tws, om2 = [], []
    for _ in range(6000):
        integ.step(50)
        x = ctx.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(u.nanometer)
        om = atw.tether_twist(x[chain], x[sides], None, per_joint=True)
        tws.append(om.sum() / (2 * np.pi))
        om2.append(np.mean(om[1:] ** 2))
    tws = np.array(tws)
    l_tw = (n - 2) * b + 0.5 * b
    theory = l_tw / (4 * np.pi**2 * C)
    r = mean_sem(tws**2)
    assert abs(r["mean"] - theory) < Z_TOL * r["sem"] + EM_RTOL * theory, (r, theory)
    assert r["n_eff"] > 100
    r2 = mean_sem(np.array(om2))
    assert abs(r2["mean"] - b / C) < Z_TOL * r2["sem"] + EM_RTOL * b / C, (r2, b / C)


# ----------------------------------------------------------------------------- scenes
@pytest.mark.parametrize("kind", ["braid", "tether"])
def test_nicked_scenes_have_no_twist(kind):
    from dnabraid.scenes import make_scene

    m = make_scene(kind, {"length_nm": 100.0}).build()
    names = {m.system.getForce(i).getName() for i in range(m.system.getNumForces())}
    assert not any(nm.startswith(("twist", "frame")) for nm in names)
    assert "twist" not in m.forces and "frame" not in m.forces
    assert m.sides is None and m.bead_orientation is None
    n_dna = sum(len(c) for c in m.chains)
    assert m.system.getNumParticles() == n_dna + (1 if kind == "braid" else 0)
    assert "twist" not in m.params["rates_per_ns"]


def test_plectoneme_builds_frames_and_twist():
    from dnabraid.scenes import make_scene

    s = make_scene("plectoneme", {"length_nm": 100.0})
    m = s.build()
    assert {"twist", "frame", "trap", "link", "beadwall"} <= set(m.forces)
    assert len(m.sides) == s.n_beads - 1
    assert m.system.getNumParticles() == 2 * s.n_beads  # beads, sides, bead orientation
    assert {"twist", "frame"} <= set(m.params["rates_per_ns"])
    # the twist and frame rates stay below the bonds': the time step is set by the bonds
    assert m.params["stiffest_term"] == "stretch"
    # start: Lk = 0 (Tw = -Wr of the random start), bead at angle 0
    p = m.positions
    c = m.chains[0]
    lk = atw.linking_number(p[c], p[m.sides], p[m.bead_orientation] - p[c[-1]])
    assert lk == pytest.approx(0.0, abs=1e-7)
