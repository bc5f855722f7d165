"""Closed chains (rings) in the force kit: stretch, bend, excluded volume, twist and the chiral
term across the seam, against the numpy twins and finite differences; closed material frames
and White's theorem Lk = Tw + Wr (Lk from an independent Gauss linking integral)."""

import math

import numpy as np
import openmm
import pytest
from _openmm_eval import openmm_energy_forces

from dnabraid.chains import GROUPS, RING_FRAME_K_FRACTION, ChainKit, DNAParameters
from dnabraid.forces import reference as ref
from dnabraid.forces import reference_chiral as refc
from dnabraid.forces import reference_twist as reft
from dnabraid.forces.chiral import chiral_force, default_exclusion
from dnabraid.forces.twist_frames import ring_joints
from dnabraid.geometry.curves import gauss_linking_number, writhe
from dnabraid.geometry.ribbon import (
    parallel_transport,
    ring_bond_frames,
    ring_side_positions,
    ring_twist,
)

#: OpenMM (Reference platform, double) against the numpy twin: relative tolerance.
RTOL_TWIN = 1e-7
#: Central finite differences (step H_NM) against the twin's analytic forces.
H_NM = 1e-5
RTOL_FD = 1e-5
#: White's theorem on a discrete ribbon holds to round-off.
TOL_WHITE = 1e-8

B = 2.5  # bead spacing (nm)


def _dna(salt_mM=1000.0):
    return DNAParameters.make(temperature_K=298.15, bead_spacing_nm=B, persistence_nm=50.0,
                              stretch_modulus_pN=1000.0, salt_mM=salt_mM)


def _crumpled_ring(n, seed, radius=None):
    """A closed, non-planar ring of n beads about B apart, crumpled so that many bead pairs
    (across the seam too) are inside the WCA range."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0, 2 * np.pi, n, endpoint=False)
    R = radius or n * B / (2 * np.pi)
    p = np.c_[R * np.cos(s), R * np.sin(s), 0.3 * R * np.sin(3 * s)]
    return p + rng.normal(0, 0.25 * B, p.shape)


def _force(kit, group):
    """A clone of every force of ``group`` (one System per force for the evaluator)."""
    return [openmm.XmlSerializer.clone(f) for f in kit.system.getForces()
            if f.getForceGroup() == GROUPS[group]]


def _omm(kit, group, pos):
    e, f = 0.0, np.zeros_like(pos)
    for force in _force(kit, group):
        de, df = openmm_energy_forces(force, pos)
        e += de
        f += df
    return e, f


def _fd_check(energy, pos, atoms, rng):
    """Central finite differences of ``energy`` at a few coordinates of ``atoms``."""
    out = []
    for a in atoms:
        for k in rng.choice(3, 2, replace=False):
            p1, p2 = pos.copy(), pos.copy()
            p1[a, k] += H_NM
            p2[a, k] -= H_NM
            out.append((a, k, -(energy(p1) - energy(p2)) / (2 * H_NM)))
    return out


def _assert_twin_and_fd(omm, twin_fn, pos, seam_atoms, seed):
    e_omm, f_omm = omm
    e_ref, f_ref = twin_fn(pos)
    scale = max(1.0, float(np.abs(f_ref).max()))
    assert e_omm == pytest.approx(e_ref, rel=RTOL_TWIN, abs=1e-9)
    assert np.abs(f_omm - f_ref).max() <= RTOL_TWIN * scale
    for a, k, fd in _fd_check(lambda p: twin_fn(p)[0], pos, seam_atoms,
                              np.random.default_rng(seed)):
        assert f_ref[a, k] == pytest.approx(fd, rel=RTOL_FD, abs=RTOL_FD * scale), (a, k)


# --------------------------------------------------------------------------- stretch, bend, WCA
@pytest.fixture
def ring_kit():
    dna = _dna()
    kit = ChainKit(dna)
    n = 24
    pos = _crumpled_ring(n, seed=3, radius=4.0)  # crumpled: many WCA contacts
    ring = kit.add_chain(pos, "A", closed=True, fixed_first=False)
    kit.add_stretch()
    kit.add_bend()
    kit.add_excluded_volume()
    return kit, ring, pos


def test_ring_topology_has_the_seam():
    kit = ChainKit(_dna())
    ring = kit.add_chain(_crumpled_ring(10, 0), "A", closed=True, fixed_first=False)
    assert len(kit.bonds()) == 10 and tuple(kit.bonds()[-1]) == (ring[-1], ring[0])
    assert {tuple(t) for t in kit.triplets()} == {(ring[i - 1], ring[i], ring[(i + 1) % 10])
                                                  for i in range(10)}
    with pytest.raises(ValueError, match="no fixed tether"):
        ChainKit(_dna()).add_chain(_crumpled_ring(10, 0), "A", closed=True)


def test_ring_stretch_matches_twin_and_fd(ring_kit):
    kit, ring, pos = ring_kit
    n = len(ring)
    bonds = [(ring[i], ring[(i + 1) % n]) for i in range(n)]  # built here, seam included
    d = kit.dna

    def twin(p):
        return ref.stretch(p, bonds, d.k_bond, d.bead_spacing_nm)

    _assert_twin_and_fd(_omm(kit, "stretch", pos), twin, pos, [ring[0], ring[-1]], 1)
    # the seam bond is really there: stretching it costs k/2 x^2
    p = pos.copy()
    e0 = _omm(kit, "stretch", p)[0]
    p[ring[-1]] += 0.1 * (p[ring[-1]] - p[ring[0]]) / np.linalg.norm(p[ring[-1]] - p[ring[0]])
    assert _omm(kit, "stretch", p)[0] == pytest.approx(twin(p)[0], rel=RTOL_TWIN)
    assert _omm(kit, "stretch", p)[0] != pytest.approx(e0, rel=1e-3)


def test_ring_bend_matches_twin_and_fd(ring_kit):
    kit, ring, pos = ring_kit
    n = len(ring)
    trip = [(ring[i - 1], ring[i], ring[(i + 1) % n]) for i in range(n)]

    def twin(p):
        return ref.bending(p, trip, kit.dna.kappa)

    _assert_twin_and_fd(_omm(kit, "bend", pos), twin, pos, [ring[0], ring[1], ring[-1]], 2)


def test_ring_wca_excludes_seam_neighbours_like_interior_ones(ring_kit):
    """Exclusions by circular contour distance, k b < r_c + b/2 (forces/excluded.py), built
    here independently of the kit; the crumpled ring has WCA contacts across the seam."""
    kit, ring, pos = ring_kit
    d = kit.dna
    n = len(ring)
    rc = 2 ** (1 / 6) * d.diameter_nm
    excl = [(ring[i], ring[j]) for i in range(n) for j in range(i + 1, n)
            if min(j - i, n - (j - i)) * B < rc + B / 2]

    def twin(p):
        return ref.wca(p, d.diameter_nm, d.kT, excl)

    e, _ = twin(pos)
    assert e > 1.0  # contacts present
    seam_pairs = [(i, j) for i in range(n) for j in range(i + 1, n)
                  if (j - i) > n // 2 and np.linalg.norm(pos[ring[i]] - pos[ring[j]]) < rc
                  and (ring[i], ring[j]) not in excl]
    assert seam_pairs, "the test ring must have WCA contacts across the seam"
    _assert_twin_and_fd(_omm(kit, "wca", pos), twin, pos, [ring[0], ring[-1], ring[-2]], 3)


# --------------------------------------------------------------------------- twist
@pytest.fixture
def twisted_ring_kit():
    dna = _dna()
    kit = ChainKit(dna)
    n = 20
    pos = _crumpled_ring(n, seed=5)
    ring = kit.add_chain(pos, "A", closed=True, fixed_first=False)
    sides = kit.add_ring_twist(ring, 75.0, delta_lk=-1)
    return kit, ring, sides, 75.0 * dna.kT / B


def test_ring_twist_start_closes_with_delta_lk(twisted_ring_kit):
    """The built frames: Tw + Wr = Delta Lk, the twist spread evenly over the n joints (seam
    included), so the twist energy is n g/2 (2 pi (Delta Lk - Wr) / n)^2."""
    kit, ring, sides, g = twisted_ring_kit
    pos = kit.positions
    n = len(ring)
    wr = writhe(pos[ring])
    tw = ring_twist(pos[ring], pos[sides])
    assert tw + wr == pytest.approx(-1.0, abs=TOL_WHITE)
    om = ring_twist(pos[ring], pos[sides], per_joint=True)
    assert np.allclose(om, 2 * np.pi * (-1.0 - wr) / n, atol=1e-10)
    e, _ = _omm(kit, "twist", pos)
    assert e == pytest.approx(0.5 * g * n * (2 * np.pi * (-1 - wr) / n) ** 2, rel=RTOL_TWIN)


def test_ring_twist_matches_twin_and_fd(twisted_ring_kit):
    kit, ring, sides, g = twisted_ring_kit
    rng = np.random.default_rng(11)
    pos = kit.positions + rng.normal(0, 0.3, kit.positions.shape)

    def twin(p):
        return reft.twist_ring(p, ring, sides, g)

    _assert_twin_and_fd(_omm(kit, "twist", pos), twin, pos,
                        [ring[0], ring[1], ring[-1], sides[0], sides[-1]], 4)
    # the seam joint is one of them and the twin's joint angles are the geometry's
    om_geo = ring_twist(pos[ring], pos[sides], per_joint=True)
    e_geo = 0.5 * g * float(np.sum(om_geo**2))
    assert twin(pos)[0] == pytest.approx(e_geo, rel=1e-10)
    assert np.array_equal(ring_joints(ring, sides)[-1],
                          [ring[-1], ring[0], ring[1], sides[-1], sides[0]])


def test_ring_frame_springs_match_twin(twisted_ring_kit):
    kit, ring, sides, g = twisted_ring_kit
    rng = np.random.default_rng(12)
    pos = kit.positions + rng.normal(0, 0.3, kit.positions.shape)
    n = len(ring)
    d = kit.dna
    k = RING_FRAME_K_FRACTION * d.k_bond
    arm = B
    bonds = [(ring[i], sides[i]) for i in range(n)]
    diag = [(ring[(i + 1) % n], sides[i]) for i in range(n)]

    def twin(p):
        e1, f1 = ref.stretch(p, bonds, k, arm)
        e2, f2 = ref.stretch(p, diag, k, math.hypot(arm, B))
        return e1 + e2, f1 + f2

    _assert_twin_and_fd(_omm(kit, "frame", pos), twin, pos, [ring[0], sides[-1]], 5)


def test_add_ring_twist_refuses_an_open_chain():
    kit = ChainKit(_dna())
    c = kit.add_chain(_crumpled_ring(10, 0), "A", fixed_first=False)
    with pytest.raises(ValueError, match="not a closed chain"):
        kit.add_ring_twist(c, 50.0)
    kit2 = ChainKit(_dna())
    r = kit2.add_chain(_crumpled_ring(6, 0), "A", closed=True, fixed_first=False)
    with pytest.raises(ValueError, match="more beads"):
        kit2.add_ring_twist(r, 50.0, delta_lk=3)
    with pytest.raises(ValueError, match="integer"):
        ring_side_positions(_crumpled_ring(10, 0), 1.0, 0.5)


# --------------------------------------------------------------------------- White's theorem
def _random_framed_ring(n, seed, twist_sd):
    """A smooth random closed curve (a few Fourier modes) with frames turned by random
    joint angles (sd ``twist_sd`` rad) from parallel transport; the seam's mismatch is then
    spread evenly over all joints (frame i turned by i/n of it), so no joint is near pi."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0, 2 * np.pi, n, endpoint=False)
    p = np.zeros((n, 3))
    for k in range(1, 4):
        a = rng.normal(0, 10.0 / k, (2, 3))
        p += np.outer(np.cos(k * s), a[0]) + np.outer(np.sin(k * s), a[1])
    t = np.roll(p, -1, axis=0) - p
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    u = np.empty_like(t)
    u[0] = np.cross(t[0], rng.normal(size=3))
    u[0] /= np.linalg.norm(u[0])
    for i in range(1, n):
        v = parallel_transport(u[i - 1], t[i - 1], t[i])
        v /= np.linalg.norm(v)
        a = rng.normal(0, twist_sd)
        u[i] = np.cos(a) * v + np.sin(a) * np.cross(t[i], v)
    seam = ring_twist(p, p + u, per_joint=True)[-1]
    for i in range(n):
        a = seam * i / n
        u[i] = np.cos(a) * u[i] + np.sin(a) * np.cross(t[i], u[i])
    return p, p + 0.7 * u


def _pushoff_linking(p, sides, eps=1e-4):
    """Lk of the ribbon, independently: Gauss linking number of the ring and its push-off,
    the polygon r_i + eps u_i -> r_{i+1} + eps u_i -> r_{i+1} + eps u_{i+1} -> ... (each bond
    shifted along its material vector, the vertices joined by short segments)."""
    t, u = ring_bond_frames(p, sides)
    q = np.roll(p, -1, axis=0)
    e = np.stack([p + eps * u, q + eps * u], axis=1).reshape(-1, 3)
    return gauss_linking_number(p, e)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_white_theorem_on_random_framed_rings(seed):
    """Tw (joint angles, seam included) + Wr (Gauss self-integral) = Lk (Gauss linking with
    the push-off), an integer, to round-off (White 1969; Fuller 1978)."""
    p, sides = _random_framed_ring(60, seed, twist_sd=0.3)
    assert np.abs(ring_twist(p, sides, per_joint=True)).max() < np.pi / 2
    tw = ring_twist(p, sides)
    wr = writhe(p)
    lk = _pushoff_linking(p, sides)
    assert abs(lk - round(lk)) < 1e-6
    assert tw + wr == pytest.approx(round(lk), abs=TOL_WHITE)
    assert abs(wr) > 0.01  # a non-planar curve: the theorem is not trivial here


@pytest.mark.parametrize("dlk", [-2, -1, 0, 1, 3])
def test_built_frames_have_the_requested_linking_number(dlk):
    p, _ = _random_framed_ring(60, 7, 0.0)
    sides = ring_side_positions(p, 0.7, dlk)
    assert ring_twist(p, sides) + writhe(p) == pytest.approx(dlk, abs=TOL_WHITE)
    assert _pushoff_linking(p, sides) == pytest.approx(dlk, abs=1e-6)


# --------------------------------------------------------------------------- chiral on rings
def test_chiral_term_on_two_rings_matches_twin_and_fd():
    """The chiral term's public factory with ``closed`` rings against its numpy twin: the
    closing segments of both rings are in contact here."""
    dna = _dna(150.0)
    n = 16
    s = np.linspace(0, 2 * np.pi, n, endpoint=False)
    R = n * B / (2 * np.pi)
    delta = 1.05 * dna.diameter_nm
    r1 = np.c_[R * np.cos(s), R * np.sin(s), np.zeros(n)]
    # ring 2 threaded by ring 1: its bead 0 (end of its seam segment) delta from ring 1's
    # bead 0; tilted about the x axis so that the braid angle is not 90 deg
    c = R - delta + R
    r2 = np.c_[c + R * np.cos(s + np.pi), np.zeros(n), R * np.sin(s + np.pi)]
    rot = np.array([[1, 0, 0], [0, np.cos(0.6), -np.sin(0.6)], [0, np.sin(0.6), np.cos(0.6)]])
    r2 = r2 @ rot.T
    pos = np.vstack([r1, r2]) + np.random.default_rng(9).normal(0, 0.05, (2 * n, 3))
    assert abs(gauss_linking_number(pos[:n], pos[n:])) == pytest.approx(1.0, abs=1e-6)
    chains = [np.arange(n), np.arange(n, 2 * n)]
    alpha = 2.0
    kw = dict(delta_nm=dna.diameter_nm, debye_nm=dna.debye_nm)
    force = chiral_force(chains, alpha, bead_spacing_nm=B, closed=True, backend="numpy", **kw)
    excl = default_exclusion(B, dna.diameter_nm, dna.debye_nm)
    q = refc.default_subdivisions(B, dna.diameter_nm, dna.debye_nm)

    def twin(p):
        return refc.chiral_energy_forces(p, chains, alpha, exclude_neighbours=excl,
                                         subdivisions=q, closed=True, **kw)

    e_ref, _ = twin(pos)
    e_open, _ = refc.chiral_energy_forces(pos, chains, alpha, exclude_neighbours=excl,
                                          subdivisions=q, closed=False, **kw)
    assert e_ref != 0.0 and e_ref != pytest.approx(e_open, rel=1e-3)  # the seams matter
    _assert_twin_and_fd(openmm_energy_forces(force, pos), twin, pos, [0, n - 1, n, 2 * n - 1], 6)


@pytest.mark.parametrize("bad", [{"twist_persistence_nm": 0.0}, {"twist_persistence_nm": -50.0},
                                 {"twist_persistence_nm": float("nan")},
                                 {"twist_persistence_nm": 50.0, "k_fraction": 0.0}])
def test_ring_twist_refuses_bad_stiffness(bad):
    """A zero, negative or NaN twist stiffness would give a zero or negative rate and a
    meaningless time step: refused with the parameter's name."""
    import numpy as np

    from dnabraid.chains import ChainKit, DNAParameters

    d = DNAParameters.make(temperature_K=298.15, bead_spacing_nm=3.0, persistence_nm=50.0,
                           stretch_modulus_pN=1000.0, salt_mM=1000.0)
    kit = ChainKit(d)
    t = np.linspace(0, 2 * np.pi, 20, endpoint=False)
    r = 20 * 3.0 / (2 * np.pi)
    ring = kit.add_chain(np.c_[r * np.cos(t), r * np.sin(t), 0 * t], "A", closed=True,
                         fixed_first=False)
    name = [k for k in bad if k != "twist_persistence_nm"] or ["twist_persistence_nm"]
    with pytest.raises(ValueError, match=name[0]):
        kit.add_ring_twist(ring, **bad)
