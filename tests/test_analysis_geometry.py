"""Known-answer tests for dnabraid.analysis.geometry (lengths in nm)."""

import numpy as np
import pytest

from dnabraid.analysis import geometry as g

MIRROR = np.array([-1.0, 1.0, 1.0])  # reflection x -> -x
#: Tolerance on topological integers (round-off only).
TOL_INT = 1e-9
#: Tolerance on discretised smooth-curve quantities.
TOL_DISC = 1e-3


def helix_pair(n_turns, n_points=401, radius=1.0, length=20.0):
    """Ideal two-strand braid: strand_k(t) = (R cos(2 pi n t + k pi), R sin(.), L t)."""
    t = np.linspace(0.0, 1.0, n_points)
    out = []
    for k in (0, 1):
        ang = 2 * np.pi * n_turns * t + k * np.pi
        out.append(np.c_[radius * np.cos(ang), radius * np.sin(ang), length * t])
    return out


def closed_double_helix(n_twist, n_points=300, big_r=10.0, a=1.0):
    """Two strands wound n_twist times (right-handed for n_twist > 0) about a circle."""
    phi = np.linspace(0, 2 * np.pi, n_points, endpoint=False)
    er = np.c_[np.cos(phi), np.sin(phi), 0 * phi]
    ez = np.array([0.0, 0.0, 1.0])
    strands = []
    for k in (0, 1):
        psi = n_twist * phi + k * np.pi
        # offset rotates from z towards e_r; z x e_r = e_phi (the tangent): right-handed
        off = a * (np.cos(psi)[:, None] * ez + np.sin(psi)[:, None] * er)
        strands.append(big_r * er + off)
    return strands


def test_pair_solid_angle_matches_quadrature():
    rng = np.random.default_rng(7)
    s = (np.arange(1500) + 0.5) / 1500
    for _ in range(5):
        a, b, c, d = rng.normal(size=(4, 3))
        exact = g.pair_solid_angles(a, b, c, d) / (4 * np.pi)
        x1 = a + s[:, None] * (b - a)
        x2 = c + s[:, None] * (d - c)
        r = x1[:, None, :] - x2[None, :, :]
        integrand = (r @ np.cross(b - a, d - c)) / np.linalg.norm(r, axis=-1) ** 3
        assert exact == pytest.approx(integrand.mean() / (4 * np.pi), abs=1e-6)


def test_hopf_link_and_unlink():
    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    c1 = np.c_[np.cos(t), np.sin(t), 0 * t]
    c2 = np.c_[1 + np.cos(t), 0 * t, np.sin(t)]
    lk = g.gauss_linking_number(c1, c2)
    assert abs(abs(lk) - 1.0) < TOL_INT
    assert g.gauss_linking_number(c1 * MIRROR, c2 * MIRROR) == pytest.approx(-lk, abs=TOL_INT)
    assert g.gauss_linking_number(c1, c2[::-1]) == pytest.approx(-lk, abs=TOL_INT)
    assert g.gauss_linking_number(c2, c1) == pytest.approx(lk, abs=TOL_INT)
    far = c2 + [5.0, 0.0, 0.0]
    assert abs(g.gauss_linking_number(c1, far)) < TOL_INT


@pytest.mark.parametrize("n_twist", [1, 3, -4])
def test_closed_double_helix_linking_is_signed_integer(n_twist):
    s1, s2 = closed_double_helix(n_twist)
    assert g.gauss_linking_number(s1, s2) == pytest.approx(n_twist, abs=1e-8)


def torus_knot_ribbon(p=2, q=3, n=600, big_r=3.0, r=1.0, eps=0.05):
    """(p, q) torus knot with the torus-normal ribbon; returns curve, normal, edge."""
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False)
    er = np.c_[np.cos(p * phi), np.sin(p * phi), 0 * phi]
    ez = np.array([0.0, 0.0, 1.0])
    w = np.cos(q * phi)[:, None] * er + np.sin(q * phi)[:, None] * ez
    c = big_r * er + r * w
    return c, w, c + eps * w


def smooth_twist(c, u):
    """Tw = (1/2pi) sum (t x u) . du of a finely sampled closed ribbon (test oracle)."""
    tang = np.roll(c, -1, 0) - np.roll(c, 1, 0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    du = 0.5 * (np.roll(u, -1, 0) - np.roll(u, 1, 0))
    return np.sum(np.einsum("ij,ij->i", np.cross(tang, u), du)) / (2 * np.pi)


def test_writhe_calugareanu_lk_equals_tw_plus_wr():
    c, w, edge = torus_knot_ribbon()
    lk = g.gauss_linking_number(c, edge)
    assert lk == pytest.approx(round(lk), abs=1e-6)
    wr = g.writhe(c)
    tw = smooth_twist(c, w)
    assert abs(wr) > 0.5  # a trefoil is far from planar
    assert lk == pytest.approx(tw + wr, abs=TOL_DISC)


def test_writhe_planar_zero_and_mirror():
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    assert abs(g.writhe(np.c_[np.cos(t), 2 * np.sin(t), 0 * t])) < TOL_INT
    c, _, _ = torus_knot_ribbon(n=200)
    assert g.writhe(c * MIRROR) == pytest.approx(-g.writhe(c), abs=TOL_INT)
    assert g.writhe(2.5 * c) == pytest.approx(g.writhe(c), abs=TOL_INT)  # scale-free


@pytest.mark.parametrize("n_turns", [3.0, 2.3, -1.7, 0.25, 0.0])
def test_catenation_of_ideal_helix_equals_turns(n_turns):
    s1, s2 = helix_pair(n_turns)
    ca = g.catenation_number(s1, s2)
    assert ca == pytest.approx(n_turns, abs=TOL_DISC)
    assert g.catenation_number(s2, s1) == pytest.approx(ca, abs=1e-9)
    assert g.catenation_number(s1 * MIRROR, s2 * MIRROR) == pytest.approx(-ca, abs=1e-9)


def test_catenation_right_handed_is_positive_and_ray_insensitive():
    s1, s2 = helix_pair(0.6)  # top chord rotated +0.6 turn counter-clockwise
    assert g.catenation_number(s1, s2) > 0
    a = g.catenation_number(s1, s2, ray_length=1e5)
    b = g.catenation_number(s1, s2, ray_length=1e7)
    assert a == pytest.approx(b, abs=1e-3)
    with pytest.raises(ValueError):
        g.catenation_number(s1, s2, ray_length=-1.0)


def test_catenation_is_chord_angle_plus_integer_for_irregular_braid():
    rng = np.random.default_rng(3)
    s1, s2 = helix_pair(1.35, n_points=120)
    s1 = s1 + rng.normal(scale=0.15, size=s1.shape)
    s2 = s2 + rng.normal(scale=0.15, size=s2.shape)
    s2[:, 2] += 0.3  # unequal heights are fine
    ca = g.catenation_number(s1, s2)
    phi = g.chord_angle(s1[-1], s2[-1]) - g.chord_angle(s1[0], s2[0])
    frac = (ca - phi / (2 * np.pi)) % 1.0
    assert min(frac, 1 - frac) < TOL_DISC
    assert abs(ca - 1.35) < 0.5


def test_chord_angle_batched_and_unwrap():
    p1 = np.zeros((4, 3))
    p2 = np.array([[1, 0, 5], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], float)
    np.testing.assert_allclose(g.chord_angle(p1, p2), [0, np.pi / 2, np.pi, -np.pi / 2])
    assert isinstance(g.chord_angle([0, 0, 0], [1, 1, 0]), float)
    turns = np.linspace(0, 5 * np.pi, 50)
    wrapped = np.arctan2(np.sin(turns), np.cos(turns))
    np.testing.assert_allclose(g.unwrap_angle(wrapped), turns, atol=1e-12)


def test_segment_distances_against_sampling():
    rng = np.random.default_rng(11)
    s = np.linspace(0, 1, 801)
    for _ in range(20):
        a, b, c, d = rng.normal(size=(4, 3))
        if rng.random() < 0.3:
            d = c + (b - a) * 0.7  # parallel segments
        dist, ss, tt = g.segment_distances(a, b, c, d)
        x1 = a + s[:, None] * (b - a)
        x2 = c + s[:, None] * (d - c)
        brute = np.min(np.linalg.norm(x1[:, None] - x2[None], axis=-1))
        assert dist <= brute + 1e-12
        assert dist == pytest.approx(brute, abs=2e-3)
        p, q = a + ss * (b - a), c + tt * (d - c)
        assert np.linalg.norm(q - p) == pytest.approx(dist, abs=1e-12)


@pytest.mark.parametrize("theta_deg", [15.0, 30.0, 40.0])
def test_crossing_angle_of_ideal_ply_is_twice_helix_angle(theta_deg):
    radius, n_turns = 1.0, 3.0
    length = 2 * np.pi * radius * n_turns / np.tan(np.radians(theta_deg))
    n_points = 600
    s1, s2 = helix_pair(n_turns, n_points=n_points, radius=radius, length=length)
    # helix angle of the discretised chords (slightly below theta)
    dang = 2 * np.pi * n_turns / (n_points - 1)
    theta_disc = np.arctan(2 * radius * np.sin(dang / 2) / (length / (n_points - 1)))
    eta, dist = g.crossing_angles(s1, s2, cutoff=2.5 * radius)
    assert eta.size == n_points - 1
    np.testing.assert_allclose(dist, 2 * radius, atol=1e-3)
    np.testing.assert_allclose(eta, -2 * theta_disc, atol=1e-6)  # right-handed -> eta < 0
    eta_m, _ = g.crossing_angles(s1 * MIRROR, s2 * MIRROR, cutoff=2.5 * radius)
    np.testing.assert_allclose(eta_m, 2 * theta_disc, atol=1e-6)
    # apolar: reversing a strand's direction leaves eta unchanged
    eta_r, _ = g.crossing_angles(s1, s2[::-1], cutoff=2.5 * radius)
    np.testing.assert_allclose(eta_r, eta, atol=1e-6)
    assert np.degrees(-eta).mean() == pytest.approx(2 * theta_deg, abs=0.1)


def test_crossing_angles_cutoff_and_folding():
    s1, s2 = helix_pair(2.0, n_points=100)
    eta, dist = g.crossing_angles(s1, s2, cutoff=1.5)  # strands are 2 nm apart
    assert eta.size == 0 and dist.size == 0
    # perpendicular crossing: +pi/2 (folded interval is (-pi/2, pi/2])
    a = np.array([[-1.0, 0, 0], [1.0, 0, 0]])
    b = np.array([[0, -1.0, 1.0], [0, 1.0, 1.0]])
    eta, dist = g.crossing_angles(a, b, cutoff=2.0)
    assert eta[0] == pytest.approx(np.pi / 2) and dist[0] == pytest.approx(1.0)
    eta, _ = g.crossing_angles(a, b[::-1], cutoff=2.0)
    assert eta[0] == pytest.approx(np.pi / 2)
    with pytest.raises(ValueError):
        g.crossing_angles(a, b, cutoff=0.0)


def test_bonds_bending_persistence():
    n = 64
    t = np.linspace(0, 2 * np.pi, n + 1)
    ring = np.c_[np.cos(t), np.sin(t), 0 * t]
    np.testing.assert_allclose(g.bond_lengths(ring), 2 * np.sin(np.pi / n))
    np.testing.assert_allclose(g.bending_cosines(ring), np.cos(2 * np.pi / n))
    assert g.persistence_length_from_cosines(np.exp(-2.5 / 50.0), 2.5) == pytest.approx(50.0)
    assert g.persistence_length_from_cosines(1.0, 2.5) == np.inf
    assert g.extension([0.1, 3.0, 7.5]) == pytest.approx(7.4)
    with pytest.raises(ValueError):
        g.persistence_length_from_cosines(-0.1, 2.5)
    with pytest.raises(ValueError):
        g.bond_lengths(np.zeros((4, 2)))
    with pytest.raises(ValueError):
        g.gauss_linking_number(np.full((5, 3), np.nan), ring)
