"""Segment-segment contact (dnabraid.forces.segment_contact): closest distance against brute
force, gradient and Hessian against finite differences, the OpenMM force against the numpy
twin, the pair search and its exclusions, and the smoothness that motivates it."""

import numpy as np
import pytest
from _openmm_eval import openmm_energy_forces

from dnabraid.forces import segment_contact as sc

SEED = 11


def _brute_distance(p0, p1, q0, q1, n=401):
    """min over an n x n grid of (s, t) plus the exact point-segment distances of the four
    ends (the minimum of a convex function on the square is on the grid's hull or found by
    refinement: the grid bounds it from above within (1/n) * segment length)."""
    S = np.linspace(0.0, 1.0, n)
    P = p0[:, None, :] + S[None, :, None] * (p1 - p0)[:, None, :]
    Q = q0[:, None, :] + S[None, :, None] * (q1 - q0)[:, None, :]
    best = np.full(len(p0), np.inf)
    for k in range(n):
        best = np.minimum(best, np.linalg.norm(P[:, k:k + 1, :] - Q, axis=2).min(axis=1))
    return best


def _random_segments(rng, n, scale=1.0):
    return [scale * rng.normal(size=(n, 3)) for _ in range(4)]


def test_distance_matches_dense_sampling():
    rng = np.random.default_rng(SEED)
    p0, p1, q0, q1 = _random_segments(rng, 150)
    d, s, t = sc.segment_distance(p0, p1, q0, q1)
    brute = _brute_distance(p0, p1, q0, q1)
    # the grid can only be above the true minimum, by at most the grid step times the
    # segment length (first order) -> tolerance 2 * |seg| / 400
    seglen = np.maximum(np.linalg.norm(p1 - p0, axis=1), np.linalg.norm(q1 - q0, axis=1))
    assert np.all(brute >= d - 1e-12)
    assert np.all(brute - d <= 2.0 * seglen / 400)
    # the returned (s, t) realise d
    r = p0 + s[:, None] * (p1 - p0) - q0 - t[:, None] * (q1 - q0)
    assert np.allclose(np.linalg.norm(r, axis=1), d, rtol=0, atol=1e-12)
    # both ends clamped, one clamped and none clamped all occur in the sample
    fs = (s > 0) & (s < 1)
    ft = (t > 0) & (t < 1)
    assert np.any(fs & ft) and np.any(fs ^ ft) and np.any(~fs & ~ft)


@pytest.mark.parametrize("case, expected", [
    # crossing at right angles, 0.7 apart
    (([-1, 0, 0], [1, 0, 0], [0, -1, 0.7], [0, 1, 0.7]), (0.7, 0.5, 0.5)),
    # parallel, overlapping projections: the perpendicular distance
    (([0, 0, 0], [2, 0, 0], [1, 0.3, 0], [3, 0.3, 0]), (0.3, None, None)),
    # parallel, disjoint projections: end to end
    (([0, 0, 0], [1, 0, 0], [2, 0.0, 0], [3, 0.0, 0]), (1.0, 1.0, 0.0)),
    # anti-parallel, disjoint: end to end through the gap
    (([0, 0, 0], [1, 0, 0], [3, 0.4, 0], [2, 0.4, 0]), (np.hypot(1.0, 0.4), 1.0, 1.0)),
    # endpoint of one onto the interior of the other (T shape)
    (([0, 0, 0], [0, 0, 1], [-1, 0, 1.5], [1, 0, 1.5]), (0.5, 1.0, 0.5)),
    # collinear, touching
    (([0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0]), (0.0, 1.0, 0.0)),
])
def test_distance_special_cases(case, expected):
    p0, p1, q0, q1 = (np.array(v, float) for v in case)
    d, s, t = sc.segment_distance(p0, p1, q0, q1)
    assert float(d) == pytest.approx(expected[0], abs=1e-14)
    if expected[1] is not None:
        assert float(s) == pytest.approx(expected[1], abs=1e-14)
        assert float(t) == pytest.approx(expected[2], abs=1e-14)
    # symmetric in the two segments
    d2, s2, t2 = sc.segment_distance(q0, q1, p0, p1)
    assert float(d2) == pytest.approx(float(d), abs=1e-14)


def _tangle(rng, n=60):
    """A random walk folded into a small box: many segment pairs at d < D = 1."""
    steps = rng.normal(size=(n, 3))
    steps *= 0.5 / np.linalg.norm(steps, axis=1)[:, None]
    return np.cumsum(steps, axis=0)


def _fd(f, x, i, h=1e-6):
    xp, xm = x.ravel().copy(), x.ravel().copy()
    xp[i] += h
    xm[i] -= h
    return (f(xp.reshape(x.shape)) - f(xm.reshape(x.shape))) / (2 * h)


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(SEED)
    x = _tangle(rng)
    seg = sc.chain_segments(len(x))
    pairs = sc.segment_pairs(x, seg, 1.0, min_separation=1)
    assert len(pairs) > 20
    E = lambda y: sc.contact_energy(y, seg, pairs, 1.0, 50.0)  # noqa: E731
    g, _ = sc.contact_gradient_hessian(x, seg, pairs, 1.0, 50.0)
    g = g.ravel()
    assert np.abs(g).max() > 1.0
    for i in range(x.size):
        assert _fd(E, x, i) == pytest.approx(g[i], abs=1e-6 * max(1.0, np.abs(g).max()))


def test_exact_hessian_matches_finite_differences_of_the_gradient():
    rng = np.random.default_rng(SEED)
    x = _tangle(rng)
    seg = sc.chain_segments(len(x))
    pairs = sc.segment_pairs(x, seg, 1.0, min_separation=1)
    G = lambda y: sc.contact_gradient_hessian(y, seg, pairs, 1.0, 50.0)[0].ravel()  # noqa: E731
    _, H = sc.contact_gradient_hessian(x, seg, pairs, 1.0, 50.0, gauss_newton=False)
    H = H.toarray()
    assert np.allclose(H, H.T, atol=1e-9 * np.abs(H).max())
    for i in rng.choice(x.size, 60, replace=False):
        col = _fd(G, x, i, h=1e-7)
        assert np.abs(col - H[:, i]).max() <= 1e-5 * max(1.0, np.abs(H).max())


def test_gauss_newton_hessian_is_psd_and_exact_at_touching():
    rng = np.random.default_rng(SEED)
    x = _tangle(rng)
    seg = sc.chain_segments(len(x))
    pairs = sc.segment_pairs(x, seg, 1.0, min_separation=1)
    _, Hgn = sc.contact_gradient_hessian(x, seg, pairs, 1.0, 50.0)
    lam = np.linalg.eigvalsh(Hgn.toarray())
    assert lam.min() >= -1e-9 * lam.max()
    # J^T J is the exact Hessian where the penalty is zero (d -> D): touching segments
    _, Hx = sc.contact_gradient_hessian(x, seg, pairs, 1.0, 50.0, gauss_newton=False)
    d = sc.segment_distance(*(x[seg[pairs[:, k // 2], k % 2]] for k in range(4)))[0]
    Dt = float(d.max()) + 1e-9  # every pair in contact, the widest one just touching
    _, Hgn2 = sc.contact_gradient_hessian(x, seg, pairs[d == d.max()], Dt, 50.0)
    _, Hx2 = sc.contact_gradient_hessian(x, seg, pairs[d == d.max()], Dt, 50.0,
                                         gauss_newton=False)
    assert np.abs((Hgn2 - Hx2).toarray()).max() < 1e-6 * np.abs(Hgn2.toarray()).max()
    assert np.abs((Hgn - Hx).toarray()).max() > 1e-3  # the two differ inside the contact


def test_frozen_openmm_force_matches_numpy_twin():
    """The fast-to-build OpenMM force with the clamping cases frozen at x, at x."""
    rng = np.random.default_rng(SEED)
    x = _tangle(rng, 80)
    seg = sc.chain_segments(len(x))
    pairs = sc.segment_pairs(x, seg, 1.0, min_separation=1)
    quads = np.column_stack([seg[pairs[:, 0]], seg[pairs[:, 1]]])
    _, s, t = sc.segment_distance(*(x[quads[:, k]] for k in range(4)))
    free_s, free_t = (s > 0) & (s < 1), (t > 0) & (t < 1)
    # all four cases occur: line-line, end-line both ways, end-end
    assert all(np.any(m) for m in (free_s & free_t, free_s & ~free_t, ~free_s & free_t,
                                   ~free_s & ~free_t))
    e, f = openmm_energy_forces(sc.segment_contact_force(quads, 1.0, 50.0, frozen_at=x), x)
    g, _ = sc.contact_gradient_hessian(x, seg, pairs, 1.0, 50.0)
    assert e == pytest.approx(sc.contact_energy(x, seg, pairs, 1.0, 50.0), rel=1e-10)
    assert np.abs(f + g).max() < 1e-8 * np.abs(g).max()


@pytest.mark.slow
def test_openmm_force_matches_numpy_twin():
    """One OpenMM Context (building the Lepton derivatives costs ~8 s): a random tangle and,
    far from it, a parallel pair (no NaN from den = 0) and a collinear end-to-end pair."""
    rng = np.random.default_rng(SEED)
    x = _tangle(rng)
    seg = sc.chain_segments(len(x))
    pairs = sc.segment_pairs(x, seg, 1.0, min_separation=1)
    quads = np.column_stack([seg[pairs[:, 0]], seg[pairs[:, 1]]])
    n = len(x)
    y = np.array([[0, 0, 0], [1, 0, 0], [0.5, 0.3, 0], [1.5, 0.3, 0], [1.2, 0, 0], [2, 0, 0.]])
    quads_y = n + np.array([[0, 1, 2, 3], [0, 1, 4, 5]])
    e, f = openmm_energy_forces(sc.segment_contact_force(np.vstack([quads, quads_y]), 1.0, 50.0),
                                np.vstack([x, y + 100.0]))
    g, _ = sc.contact_gradient_hessian(x, seg, pairs, 1.0, 50.0)
    e_y = 0.5 * 50.0 * (0.7**2 + 0.8**2)  # parallel at 0.3, collinear 0.2 apart
    assert e == pytest.approx(sc.contact_energy(x, seg, pairs, 1.0, 50.0) + e_y, rel=1e-10)
    assert np.abs(f[:n] + g).max() < 1e-8 * np.abs(g).max()
    assert np.all(np.isfinite(f[n:]))
    # the parallel pair pushes the two segments apart along y, the collinear one along x
    assert f[n + 2, 1] > 0 and f[n + 4, 0] > 0


def test_pairs_match_brute_force_and_exclusions():
    rng = np.random.default_rng(SEED)
    x = _tangle(rng, 80)
    seg = sc.chain_segments(len(x))
    pairs = sc.segment_pairs(x, seg, 1.0, min_separation=3)
    M = len(seg)
    s, t = np.triu_indices(M, 1)
    d = sc.segment_distance(x[seg[s, 0]], x[seg[s, 1]], x[seg[t, 0]], x[seg[t, 1]])[0]
    keep = (d < 1.0) & (t - s > 3)
    assert {tuple(p) for p in pairs} == set(zip(s[keep], t[keep]))
    # a ring: separation counted the short way round
    segr = sc.chain_segments(len(x), closed=True)
    pr = sc.segment_pairs(x, segr, 100.0, min_separation=3, closed=True)
    sep = pr[:, 1] - pr[:, 0]
    assert np.all(np.minimum(sep, len(segr) - sep) > 3)
    assert len(pr) == len(segr) * (len(segr) - 7) // 2  # every other pair of the ring
    # two rings in one list: never excluded across rings
    exc = sc.chain_exclusion([(40, True), (40, True)], 3)
    assert exc(np.array([0, 0, 0, 0]), np.array([39, 36, 40, 41])).tolist() == \
        [True, False, False, False]
    with pytest.raises(ValueError, match="min_separation"):
        sc.segment_pairs(x, seg, 1.0, min_separation=0)


def test_straight_strands_slide_without_corrugation():
    """Two straight strands of beads b apart crossing at right angles, d0 apart, one slid
    along its axis by 0 ... b: the closest *segment* distance is d0 throughout (the tube
    round a straight polyline is a cylinder), while the closest *bead* distance ripples
    between d0 and sqrt(d0^2 + (b/2)^2 + (b/2)^2) (crossing midway between beads on both):
    the corrugation that pins bead-contact knots."""
    b, d0, n = 0.5, 2.0, 41
    z = b * (np.arange(n) - n // 2) + 0.5 * b  # crossing point midway between two beads
    A = np.column_stack([z, np.zeros(n), np.zeros(n)])
    seg = np.vstack([sc.chain_segments(n), n + sc.chain_segments(n)])
    dseg, dbead = [], []
    for delta in np.linspace(0.0, b, 21):
        B = np.column_stack([np.zeros(n), z + delta, np.full(n, d0)])
        x = np.vstack([A, B])
        pairs = sc.segment_pairs(x, seg, 3.0, exclude=lambda s, t: (s < n - 1) == (t < n - 1))
        d = sc.segment_distance(*(x[seg[pairs[:, k // 2], k % 2]] for k in range(4)))[0]
        dseg.append(d.min())
        dbead.append(np.linalg.norm(A[:, None] - B[None], axis=2).min())
    assert np.ptp(dseg) < 1e-12 and dseg[0] == pytest.approx(d0, abs=1e-12)
    assert max(dbead) == pytest.approx(np.sqrt(d0**2 + b**2 / 2), abs=1e-12)
    assert min(dbead) == pytest.approx(np.sqrt(d0**2 + b**2 / 4), abs=1e-12)


# --------------------------------------------------- the thermal capsule force (PythonForce)
def _two_walks(rng, n=25, b=5.0, gap=3.0):
    """Two random walks of n beads b apart, started ``gap`` apart: many close pairs."""
    out = []
    for k in range(2):
        st = rng.normal(size=(n, 3))
        st /= np.linalg.norm(st, axis=1)[:, None]
        out.append(np.cumsum(st * b, axis=0) * 0.5 + k * np.array([gap, 0.0, 0.0]))
    return np.vstack(out), [np.arange(n), n + np.arange(n)]


def _capsule_twin(x, chains, D, k):
    """contact_energy over every inter-chain segment pair: the numpy twin of capsule_force."""
    seg = np.vstack([np.column_stack([c[:-1], c[1:]]) for c in chains])
    m0 = len(chains[0]) - 1
    pairs = np.array([(i, j) for i in range(m0) for j in range(m0, len(seg))])
    g, _ = sc.contact_gradient_hessian(x, seg, pairs, D, k)
    return sc.contact_energy(x, seg, pairs, D, k), g


@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_capsule_force_matches_twin_and_finite_differences(backend):
    """capsule_force (OpenMM PythonForce, Reference platform) against contact_energy and its
    gradient over all inter-strand pairs (1e-10), and the twin against central differences;
    pairs within a strand do not interact."""
    rng = np.random.default_rng(SEED + 5)
    D, k = 4.9, 78.0
    x, chains = _two_walks(rng)
    e_ref, g_ref = _capsule_twin(x, chains, D, k)
    assert e_ref > 0
    e, f = openmm_energy_forces(sc.capsule_force(chains, D, k, backend=backend), x)
    assert e == pytest.approx(e_ref, rel=1e-10)
    assert np.abs(f + g_ref).max() < 1e-9 * np.abs(g_ref).max()
    h = 1e-6
    for i in rng.choice(len(x), 8, replace=False):
        for a in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, a] += h
            xm[i, a] -= h
            fd = (_capsule_twin(xp, chains, D, k)[0] - _capsule_twin(xm, chains, D, k)[0]) / (2 * h)
            assert fd == pytest.approx(g_ref[i, a], rel=1e-5, abs=1e-6 * np.abs(g_ref).max())


def test_capsule_verlet_list_under_motion():
    """The evaluator's Verlet list (rebuilt when a bead moves > skin/2) never misses a pair:
    energy and gradient equal the all-pairs twin along a random path, numba and numpy alike."""
    rng = np.random.default_rng(SEED + 6)
    D, k = 4.9, 78.0
    x, chains = _two_walks(rng, 30)
    seg = np.vstack([np.column_stack([c[:-1], c[1:]]) for c in chains])
    cid = np.repeat([0, 1], len(chains[0]) - 1)
    evs = [sc.CapsuleEvaluator(seg, cid, D, 1.0, "k", backend=b) for b in ("numpy", "auto")]
    for _ in range(20):
        x = x + rng.normal(size=x.shape) * 0.06
        e_ref, g_ref = _capsule_twin(x, chains, D, k)
        for ev in evs:
            e, g = ev.energy_grad(x, k)
            assert e == pytest.approx(e_ref, rel=1e-10, abs=1e-12)
            assert np.allclose(g, g_ref, atol=1e-9 * max(1.0, np.abs(g_ref).max()))
    assert all(1 < ev.n_builds < 20 for ev in evs)


def test_capsule_contact_distance_is_register_free():
    """Two parallel straight strands pressed together by a force per bead: their axis
    distance is D_c - F/k (one pair carries each bead's load) whatever the register, where
    bead WCA would give a rippling 2^(1/6) sigma-ish distance. Unloaded: exactly D_c."""
    D, k, b, n = 4.9, 78.0, 5.0, 11
    z = b * np.arange(n)
    for shift in (0.0, 1.3, 2.5):
        x = np.vstack([np.column_stack([0 * z, 0 * z, z]),
                       np.column_stack([0 * z + D - 0.01, 0 * z, z + shift])])
        chains = [np.arange(n), n + np.arange(n)]
        e, g = _capsule_twin(x, chains, D, k)
        # every interior segment overlaps the partner: the push is along x only
        assert np.allclose(g[:, 1:], 0.0, atol=1e-12)
        x[n:, 0] = D
        assert _capsule_twin(x, chains, D, k)[0] == 0.0


def test_capsule_force_refuses_bad_parameters():
    with pytest.raises(ValueError, match="contact_nm"):
        sc.capsule_force([np.arange(3), 3 + np.arange(3)], 0.0, 78.0)
