"""The chiral interaction: twin, finite differences, mirror, normalisation, sign,
pair search, apolar fold and cutoff continuity; its range (docs/chiral_range.md).

Tolerances: OpenMM (Reference platform, double) against the numpy twin 1e-9 relative;
finite differences (central, h = 1e-6 nm) 1e-6 relative; the mirror image flips the sign of
the energy to 1e-12 relative; the ideal two-ply (0.5 nm beads) carries alpha tan(eta/2) to
1 %; straight strands at axis distance R <= D_c carry exactly alpha g per unit length,
whatever the beads' register, and the weight has zero slope at D_c (flat at contact). The
range tests compare with kappa_1 = sqrt(lambda_D^-2 + (2 pi / 3.4 nm)^2) computed here from
the Debye formula (Kornyshev & Leikin 1997; reference_chiral Eq. C6) to 1e-12 (1e-9 through
OpenMM).
"""

import math

import numpy as np
import pytest
from _openmm_eval import openmm_energy_forces

from dnabraid import forcefield, units
from dnabraid.forcefield import load_toml
from dnabraid.forces.chiral import (
    HAVE_NUMBA,
    ChiralEvaluator,
    _pair_loop,
    chiral_force,
    grid_pairs,
    pair_terms_fast,
    pair_terms_numba,
)
from dnabraid.forces.reference_chiral import (
    HELIX_PITCH_NM,
    ChiralKernel,
    chiral_energy_forces,
    pair_allowed,
    pair_terms,
    segments_of,
)

SEED = 20261122
DELTA, DEBYE = 4.9, 0.785  # 150 mM
KW = {"delta_nm": DELTA, "debye_nm": DEBYE, "exclude_neighbours": 3, "subdivisions": 2}


def walk(rng, n, b=3.0):
    st = rng.normal(size=(n, 3))
    st /= np.linalg.norm(st, axis=1)[:, None]
    return np.cumsum(st * b, axis=0)


def scene(rng, n=14):
    """Two random walks crossing near each other, plus a stray non-chain particle."""
    p1 = walk(rng, n)
    p2 = walk(rng, n) + p1[n // 2] - walk(rng, 1)[0] + rng.normal(size=3)
    pos = np.vstack([p1, p2, [[50.0, 0.0, 0.0]]])
    return pos, [np.arange(n), n + np.arange(n)]


def two_ply(eta, delta=DELTA, h=0.5, length=100.0):
    """Ideal two-ply, strand arc-length spacing h; right-handed for eta < 0."""
    R = 0.5 * delta
    th = 0.5 * abs(eta)
    hand = 1.0 if eta <= 0 else -1.0
    pitch = R / math.tan(th) if th > 0 else np.inf
    ds = math.hypot(R, pitch) if th > 0 else None
    z = np.arange(0.0, length, h)
    if th == 0:
        x = np.stack([np.full_like(z, R), 0 * z, z], 1)
    else:
        ph = z / ds
        x = np.stack([R * np.cos(hand * ph), R * np.sin(hand * ph), pitch * ph], 1)
    y = x.copy()
    y[:, :2] *= -1
    n = len(z)
    return np.vstack([x, y]), [np.arange(n), n + np.arange(n)]


def fast_energy(pos, chains, q=1, excl=10**6):
    seg, cid, pic, nseg, ring = segments_of(chains)
    ev = ChiralEvaluator(seg, cid, pic, nseg, ring, ChiralKernel(DELTA, DEBYE), excl, q, 1.0, "x")
    return ev.energy_grad(pos)




def all_pairs(chains, excl=3, closed=False):
    seg, cid, pic, nseg, ring = segments_of(chains, closed)
    a, b = np.triu_indices(len(seg), 1)
    keep = pair_allowed(a, b, cid, pic, nseg, ring, excl)
    return seg, a[keep], b[keep]


def test_twin_against_finite_differences():
    rng = np.random.default_rng(SEED)
    kern = ChiralKernel(DELTA, DEBYE)
    for _ in range(3):
        pos, chains = scene(rng, 10)
        e, f = chiral_energy_forces(pos, chains, 3.0, **KW)
        assert e != 0.0
        seg, a, b = all_pairs(chains, KW["exclude_neighbours"])
        h = 1e-6
        fd = np.zeros_like(pos)
        for i in range(len(pos)):
            for k in range(3):
                p = pos.copy()
                p[i, k] += h
                ep = pair_terms(p, seg, a, b, kern, KW["subdivisions"])[0]
                p[i, k] -= 2 * h
                em = pair_terms(p, seg, a, b, kern, KW["subdivisions"])[0]
                fd[i, k] = -3.0 * (ep - em) / (2 * h)
        assert np.allclose(f, fd, rtol=1e-6, atol=1e-6 * np.abs(f).max())


@pytest.mark.parametrize("q,backend", [(1, "auto"), (3, "auto"), (2, "numpy")])
def test_openmm_equals_twin(q, backend):
    rng = np.random.default_rng(SEED + q)
    kw = dict(KW, subdivisions=q)
    for _ in range(3):
        pos, chains = scene(rng)
        force = chiral_force(chains, 2.5, backend=backend, **kw)
        assert force.getName() == "chiral"
        e, f = openmm_energy_forces(force, pos)
        er, fr = chiral_energy_forces(pos, chains, 2.5, **kw)
        assert e == pytest.approx(er, rel=1e-9, abs=1e-12)
        assert np.allclose(f, fr, rtol=1e-9, atol=1e-9 * np.abs(fr).max())
        assert np.all(f[-1] == 0.0)  # the stray particle is not in a chain


def test_mirror_flips_sign_exactly():
    rng = np.random.default_rng(SEED + 7)
    for _ in range(4):
        pos, chains = scene(rng)
        nrm = rng.normal(size=3)
        nrm /= np.linalg.norm(nrm)
        c0 = rng.normal(size=3) * 5
        refl = np.eye(3) - 2 * np.outer(nrm, nrm)
        mir = (pos - c0) @ refl + c0
        e, f = chiral_energy_forces(pos, chains, 1.7, **KW)
        em, fm = chiral_energy_forces(mir, chains, 1.7, **KW)
        assert abs(e) > 1e-3
        assert em == pytest.approx(-e, rel=1e-12)
        # forces of the mirror image: minus the mirrored forces
        assert np.allclose(fm, -(f @ refl), atol=1e-10 * np.abs(f).max())


def helix_pair(R, eta, h=0.5, shift=0.0, length=60.0):
    """Ideal two-ply at strand (axis) distance R and braid angle eta; strand 2's beads
    shifted by ``shift`` along its arc (the beads' register)."""
    r = 0.5 * R
    th = 0.5 * abs(eta)
    hand = 1.0 if eta <= 0 else -1.0
    pitch = r / math.tan(th)
    ds = math.hypot(r, pitch)
    out = []
    for off, sh in ((0.0, 0.0), (math.pi, shift)):
        ph = (np.arange(0.0, length, h) + sh) / ds
        out.append(np.stack([r * np.cos(hand * ph + off), r * np.sin(hand * ph + off),
                             pitch * ph], 1))
    n = len(out[0])
    return np.vstack(out), [np.arange(n), n + np.arange(n)]


@pytest.mark.parametrize("shift", [0.0, 0.2])
def test_two_ply_flat_at_contact_and_register_free(shift):
    """Energy per unit length of the middle of an ideal two-ply (eta = -30 deg, 0.5 nm beads)
    against its strand distance R: tan(eta/2) at R = D_c (1.5 %), the same at R < D_c (the
    weight is 1 there), zero slope at D_c (the weight is flat at contact: no radial pull or
    push; the old Fermi weight had -1.8/nm), w(R) beyond; the beads' register moves it by
    < 1 %."""
    eta = math.radians(-30.0)
    k = ChiralKernel(DELTA, DEBYE)

    def per_length(R, sh):
        vals = []
        for length in (60.0, 120.0):
            pos, ch = helix_pair(R, eta, shift=sh, length=length)
            vals.append(fast_energy(pos, ch, q=2)[0])
        return (vals[1] - vals[0]) / 60.0

    e0 = per_length(DELTA, shift)
    assert e0 == pytest.approx(math.tan(eta / 2), rel=0.015)
    assert per_length(DELTA - 0.5, shift) == pytest.approx(e0, rel=1e-3)
    slope = (per_length(DELTA + 0.01, shift) - e0) / 0.01
    assert abs(slope) < 0.05 * abs(e0)
    assert per_length(DELTA + 0.3, shift) == pytest.approx(
        e0 * float(k.weight(DELTA + 0.3)[0]), rel=0.01)
    if shift:
        assert e0 == pytest.approx(per_length(DELTA, 0.0), rel=0.01)


def test_weight_is_flat_at_contact():
    w, dw = ChiralKernel(DELTA, DEBYE).weight(np.array([DELTA - 1.0, DELTA, DELTA + 1e-6]))
    assert np.all(w[:2] == 1.0) and np.all(dw[:2] == 0.0) and abs(dw[2]) < 1e-5


@pytest.mark.parametrize("deg", [-50, -20, 35])
def test_normalisation_beads_fine(deg):
    """Bead two-ply, spacing 0.5 nm, two sample points per segment: energy per unit strand
    length = alpha tan(eta/2)."""
    eta = math.radians(deg)
    e = []
    for length in (60.0, 120.0):
        pos, ch = two_ply(eta, length=length)
        e.append(fast_energy(pos, ch, q=2)[0])
    per_length = (e[1] - e[0]) / 60.0
    assert per_length == pytest.approx(math.tan(eta / 2), rel=0.01)


def test_sign_energy_falls_with_eta():
    """alpha > 0: the two-ply energy falls as eta falls; right-handed (eta < 0) is lower."""
    dens = []
    for deg in (-60, -40, -20, -5, 5, 20, 40, 60):
        pos, ch = two_ply(math.radians(deg), h=1.0, length=60.0)
        dens.append(fast_energy(pos, ch, q=2)[0])
    assert np.all(np.diff(dens) > 0)
    # bead model, alpha = 1 pN
    pos_r, ch = two_ply(math.radians(-30), h=3.0, length=150)
    pos_l, _ = two_ply(math.radians(30), h=3.0, length=150)
    e_r = chiral_energy_forces(pos_r, ch, 1.0, delta_nm=DELTA, debye_nm=DEBYE,
                               exclude_neighbours=6, subdivisions=2)[0]
    e_l = chiral_energy_forces(pos_l, ch, 1.0, delta_nm=DELTA, debye_nm=DEBYE,
                               exclude_neighbours=6, subdivisions=2)[0]
    assert e_r < 0 < e_l
    assert e_r == pytest.approx(-e_l, rel=1e-9)


def test_apolar_fold_and_continuity():
    """Reversing one strand leaves the energy unchanged; G is smooth through eta' = +-pi/2."""
    rng = np.random.default_rng(SEED + 3)
    pos, chains = scene(rng)
    e1, _ = chiral_energy_forces(pos, chains, 1.0, **KW)
    e2, _ = chiral_energy_forces(pos, [chains[0], chains[1][::-1]], 1.0, **KW)
    assert e2 == pytest.approx(e1, rel=1e-12)
    k = ChiralKernel(DELTA, DEBYE)
    for eps in (1e-3, 1e-5):
        # across c = 0 (eta' = +-90 deg) at s = 1: G -> 0 with the same slope dG/dc = s
        g, dgc, dgs = k.angular(np.array([-eps, eps]), np.array([1.0, 1.0]))
        assert np.all(np.abs(g) < 2 * eps) and np.allclose(dgc, 1.0, atol=3 * eps)
        assert np.all(np.abs(dgs) < 3 * eps)
    # G = cos(eta) tan(eta/2) at unit facing factor; derivatives against differences
    eta = np.radians(np.linspace(-89.0, 89.0, 41))
    g, dgc, dgs = k.angular(np.cos(eta), np.sin(eta))
    assert np.allclose(g, np.cos(eta) * np.tan(0.5 * eta), rtol=1e-12, atol=1e-15)
    c, s_, h = np.cos(eta) * 0.9, np.sin(eta) * 0.9, 1e-7
    gc = (k.angular(c + h, s_)[0] - k.angular(c - h, s_)[0]) / (2 * h)
    gs = (k.angular(c, s_ + h)[0] - k.angular(c, s_ - h)[0]) / (2 * h)
    _, dgc, dgs = k.angular(c, s_)
    assert np.allclose(dgc, gc, atol=1e-7) and np.allclose(dgs, gs, atol=1e-7)
    # near c = s = 0 (eta undefined) G -> 0
    g, _, _ = k.angular(np.array([1e-4]), np.array([1e-4]))
    assert abs(g[0]) < 1e-7


def test_weight_vanishes_smoothly_at_cutoff():
    k = ChiralKernel(DELTA, DEBYE)
    w, dw = k.weight(np.array([k.r_c - 1e-4, k.r_c, k.r_c + 1.0]))
    assert w[0] < 1e-9 and w[1] == 0.0 and w[2] == 0.0
    assert abs(dw[0]) < 1e-5 and dw[1] == 0.0
    assert k.amplitude == 1.0  # normalised at contact: w(D_c) = 1


# --- the range (docs/chiral_range.md) ----------------------------------------------------------

#: (salt mM, effective diameter nm of forcefields/dna.toml) at three salts.
RANGE_SALTS = [(10.0, 15.0), (150.0, 4.9), (1000.0, 2.9)]


def kappa_1(salt_mM, pitch_nm=3.4):
    """sqrt(lambda_D^-2 + g^2), lambda_D = 0.304 nm / sqrt(I/M), g = 2 pi / H (1/nm):
    the screening of the first helical harmonic (Kornyshev & Leikin 1997)."""
    lam = 0.304 / math.sqrt(salt_mM / 1000.0)
    return math.sqrt(lam**-2 + (2.0 * math.pi / pitch_nm) ** 2)


@pytest.mark.parametrize("salt,delta", RANGE_SALTS)
def test_weight_decays_with_first_helical_harmonic(salt, delta):
    """The weight falls like (1 + x) exp(-x), x = (r - D_c) kappa_1 (not lambda_D), is cut at
    Delta + 6/kappa_1, and the force field reports the same range."""
    lam = 0.304 / math.sqrt(salt / 1000.0)
    kap = kappa_1(salt)
    k = ChiralKernel(delta, lam, calibrate=False)
    assert k.range == pytest.approx(1.0 / kap, rel=1e-12)
    assert k.r_c == pytest.approx(delta + 6.0 / kap, rel=1e-12)
    assert k.r_s == pytest.approx(delta + 4.0 / kap, rel=1e-12)
    # tail ratio before the switch (r < r_s): the amplitude cancels
    w1, w3 = k.weight(np.array([delta + 1.0 / kap, delta + 3.0 / kap]))[0]
    assert w3 / w1 == pytest.approx(2.0 * math.exp(-2.0), rel=1e-12)
    assert k.weight(delta + 6.0 / kap + 1e-9)[0] == 0.0 < k.weight(delta + 5.9 / kap)[0]
    out = forcefield.chiral_parameters(salt)
    assert out["range_nm"] == pytest.approx(1.0 / kap, rel=1e-12)


def test_range_table_matches_the_formula():
    """chiral.toml's range_nm entries are 1/kappa_1 rounded to 4 digits; its pitch is the
    kernel's."""
    table = load_toml("chiral.toml")
    assert table["helix"]["pitch_nm"] == HELIX_PITCH_NM
    for key, entry in table["salt"].items():
        assert entry["range_nm"] == pytest.approx(1.0 / kappa_1(float(key)), abs=6e-5)


def test_openmm_force_from_debye_length_decays_with_kappa_1():
    """The scene's call (chiral_force with the Debye length only): one segment pair at
    braid angle -30 deg, chord perpendicular to both, pulled apart along the chord. Energies
    at Delta + 1/kappa_1 and Delta + 3/kappa_1 are in the ratio 4 e^-3 / (2 e^-1); beyond
    Delta + 6/kappa_1 (still inside the old cutoff Delta + 6 lambda_D = 9.6 nm) energy and
    forces are exactly zero."""
    lam = 0.304 / math.sqrt(0.15)
    kap = kappa_1(150.0)
    eta = math.radians(-30.0)
    ta = np.array([1.0, 0.0, 0.0])
    tb = np.array([math.cos(eta), math.sin(eta), 0.0])  # (ta x tb) . z = sin(eta)
    energies = []
    for gap in (1.0 / kap, 3.0 / kap, 7.0 / kap):
        force = chiral_force([np.array([0, 1]), np.array([2, 3])], 2.0, delta_nm=DELTA,
                             debye_nm=lam, exclude_neighbours=0, subdivisions=1)
        zb = np.array([0.0, 0.0, DELTA + gap])
        pos = np.vstack([-ta, ta, zb - tb, zb + tb])
        e, f = openmm_energy_forces(force, pos)
        energies.append((e, f))
    (e1, _), (e3, _), (e7, f7) = energies
    assert e1 < 0.0  # alpha > 0 favours eta < 0
    assert e3 / e1 == pytest.approx(2.0 * math.exp(-2.0), rel=1e-9)
    assert DELTA + 7.0 / kap < DELTA + 6.0 * lam
    assert e7 == 0.0 and np.all(f7 == 0.0)


def test_default_rules_follow_the_range():
    """Sample points and neighbour exclusion scale with rho = 1/kappa_1 at 150 mM, b = 3 nm:
    q = ceil(b / (1.6 sqrt(Delta rho))) = 2, exclusion ceil(pi (Delta + 6 rho) / (2 b)) = 4."""
    from dnabraid.forces.chiral import default_exclusion
    from dnabraid.forces.reference_chiral import default_subdivisions

    lam = 0.304 / math.sqrt(0.15)
    rho = 1.0 / kappa_1(150.0)
    q = math.ceil(3.0 / (1.6 * math.sqrt(DELTA * rho)))
    excl = math.ceil(0.5 * math.pi * (DELTA + 6.0 * rho) / 3.0)
    assert (q, excl) == (2, 4)
    assert default_subdivisions(3.0, DELTA, lam) == q
    assert default_exclusion(3.0, DELTA, lam) == excl


def test_kernel_pickled_before_the_range_fix_keeps_its_weight():
    """A kernel pickled without ``range`` decayed with lambda_D and is restored so."""
    import pickle

    k = ChiralKernel(DELTA, DEBYE, range_nm=DEBYE, calibrate=False)
    st = dict(k.__dict__)
    del st["range"], st["pitch"]
    old = ChiralKernel.__new__(ChiralKernel)
    old.__setstate__(st)
    back = pickle.loads(pickle.dumps(old))
    r = np.linspace(DELTA - 1.0, k.r_c + 1.0, 50)
    assert np.array_equal(back.weight(r)[0], k.weight(r)[0])


def test_pair_search_never_misses_a_pair():
    rng = np.random.default_rng(SEED + 11)
    pts = rng.uniform(0, 40, size=(1500, 3))
    i, j = grid_pairs(pts, 4.0)
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    bi, bj = np.nonzero(np.triu(d < 4.0, 1))
    assert set(zip(i.tolist(), j.tolist())) == set(zip(bi.tolist(), bj.tolist()))
    # Verlet list under motion: the evaluator equals brute force over all pairs at each step
    chains = [np.arange(40), 40 + np.arange(40), 80 + np.arange(30)]
    pos = np.vstack([walk(rng, 40, 2.5), walk(rng, 40, 2.5), walk(rng, 30, 2.5)]) * 0.6
    seg, cid, pic, nseg, ring = segments_of(chains, closed=[False, False, True])
    kern = ChiralKernel(DELTA, DEBYE)
    ev = ChiralEvaluator(seg, cid, pic, nseg, ring, kern, 3, 2, 1.0, "x")
    a, b = np.triu_indices(len(seg), 1)
    keep = pair_allowed(a, b, cid, pic, nseg, ring, 3)
    a, b = a[keep], b[keep]
    for _ in range(25):
        pos = pos + rng.normal(size=pos.shape) * 0.12
        e, g = ev.energy_grad(pos)
        er, gr = pair_terms(pos, seg, a, b, kern, 2)
        assert e == pytest.approx(er, rel=1e-10, abs=1e-12)
        assert np.allclose(g, gr, atol=1e-10 * max(1.0, np.abs(gr).max()))
    assert 1 < ev.n_builds < 25
    e1, _ = pair_terms_fast(pos, seg, a, b, kern, 2)
    assert e1 == pytest.approx(er, rel=1e-10)


def test_alpha_zero_is_left_out_and_parameters_file():
    assert chiral_force([np.arange(5)], 0.0, delta_nm=DELTA, debye_nm=DEBYE,
                        exclude_neighbours=2) is None
    f = chiral_force([np.arange(5), 5 + np.arange(5)], 2.0, delta_nm=DELTA, debye_nm=DEBYE,
                     bead_spacing_nm=3.0, name="chi")
    assert f.getName() == "chi"
    assert dict(f.getGlobalParameters())["chi_alpha"] == pytest.approx(
        2.0 * units.PN_NM_IN_KJ_MOL)
    with pytest.raises(ValueError):
        chiral_force([np.arange(5)], 1.0, delta_nm=DELTA, debye_nm=DEBYE)
    table = load_toml("chiral.toml")
    for key, entry in table["salt"].items():
        assert float(key) > 0 and entry["alpha_pN"] > 0 and entry["source"]


# --- the compiled loop (numba) against the twin and the numpy evaluator --------------------


def kernel_scenes(rng):
    """Random walks (most pairs beyond the cutoff), a near-antiparallel pair of strands (the
    fold: c close to -1), a near-perpendicular crossing (eta' near 90 deg) and an ideal
    two-ply with one strand reversed."""
    out = []
    for _ in range(2):
        out.append(scene(rng))
    t = walk(rng, 12, 2.0) * 0.4
    back = t[::-1] + np.array([DELTA, 0.0, 0.0]) + rng.normal(size=(12, 3)) * 0.3
    out.append((np.vstack([t, back]), [np.arange(12), 12 + np.arange(12)]))
    z = np.linspace(-15, 15, 11)
    line1 = np.stack([z, 0 * z, 0 * z], 1)
    ang = math.radians(88.0)
    line2 = np.stack([z * math.cos(ang), z * math.sin(ang), np.full_like(z, DELTA)], 1)
    out.append((np.vstack([line1, line2]) + rng.normal(size=(22, 3)) * 0.05,
                [np.arange(11), 11 + np.arange(11)]))
    pos, ch = two_ply(math.radians(-40), h=2.0, length=40.0)
    out.append((pos, [ch[0], ch[1][::-1]]))
    return out


def compiled(pos, seg, a, b, kern, q, loop):
    grad = np.zeros_like(pos)
    e = loop(pos, seg, a, b, q, kern.delta, kern.range, kern.r_s, kern.r_c,
             np.ascontiguousarray(kern.ncoef, np.float64), 1.0, grad)
    return e, grad


def assert_same(e, g, er, gr):
    assert e == pytest.approx(er, rel=1e-10, abs=1e-13)
    assert np.allclose(g, gr, rtol=0.0, atol=1e-10 * max(np.abs(gr).max(), 1e-300))


def test_loop_equals_twin_uncompiled():
    """The loop as plain Python (what numba compiles) on a few pairs: runs without numba."""
    rng = np.random.default_rng(SEED + 21)
    kern = ChiralKernel(DELTA, DEBYE)
    scenes = kernel_scenes(rng)
    for q, (pos, chains) in zip((1, 2, 3), scenes[2:]):
        seg, a, b = all_pairs(chains)
        er, gr = pair_terms(pos, seg, a, b, kern, q)
        assert er != 0.0
        assert_same(*compiled(pos, seg, a, b, kern, q, _pair_loop), er, gr)


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
@pytest.mark.parametrize("q", [1, 2, 3])
def test_numba_equals_twin_and_numpy(q):
    rng = np.random.default_rng(SEED + 30 + q)
    kern = ChiralKernel(DELTA, DEBYE)
    for pos, chains in kernel_scenes(rng):
        seg, a, b = all_pairs(chains)
        er, gr = pair_terms(pos, seg, a, b, kern, q)
        ef, gf = pair_terms_fast(pos, seg, a, b, kern, q)
        en, gn = pair_terms_numba(pos, seg, a, b, kern, q)
        assert er != 0.0
        assert_same(en, gn, er, gr)
        assert_same(en, gn, ef, gf)
        assert_same(ef, gf, er, gr)
    # the folded (antiparallel) scene: reversing a strand leaves energy and forces unchanged
    pos, chains = kernel_scenes(rng)[-1]
    seg, a, b = all_pairs(chains)
    seg2, a2, b2 = all_pairs([chains[0][::-1], chains[1]])
    assert_same(*pair_terms_numba(pos, seg2, a2, b2, kern, q),
                *pair_terms_numba(pos, seg, a, b, kern, q))


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_numba_evaluator_equals_numpy_evaluator_under_motion():
    """Same Verlet list, same energies and forces along a random path; __call__ via OpenMM."""
    rng = np.random.default_rng(SEED + 40)
    chains = [np.arange(30), 30 + np.arange(30), 60 + np.arange(20)]
    pos = np.vstack([walk(rng, 30, 2.5), walk(rng, 30, 2.5), walk(rng, 20, 2.5)]) * 0.6
    seg, cid, pic, nseg, ring = segments_of(chains, closed=[False, False, True])
    kern = ChiralKernel(DELTA, DEBYE)
    ev = {k: ChiralEvaluator(seg, cid, pic, nseg, ring, kern, 3, 2, 1.0, "x", backend=k)
          for k in ("numpy", "numba")}
    assert ev["numba"].uses_numba and not ev["numpy"].uses_numba
    for _ in range(15):
        pos = pos + rng.normal(size=pos.shape) * 0.15
        assert_same(*ev["numba"].energy_grad(pos), *ev["numpy"].energy_grad(pos))
    assert ev["numba"].n_builds == ev["numpy"].n_builds > 1
    # the compiled Verlet-list build finds the same pairs as grid_pairs + pair_allowed
    pairs = {k: set(zip(e._a.tolist(), e._b.tolist())) for k, e in ev.items()}
    assert pairs["numba"] == pairs["numpy"] and len(pairs["numba"]) > 100
    with pytest.raises(ValueError):
        ChiralEvaluator(seg, cid, pic, nseg, ring, kern, 3, 2, 1.0, "x", backend="cuda")


# --- the two-ply calibration N(eta) of the capsule scenes (Eq. C5) ----------------------------


def test_two_ply_calibration_at_the_bead_spacing():
    """With the calibration of the braid scene's beads (b = 5 nm, q = 3), the ideal bead two-ply
    carries alpha tan(eta/2) per unit length within 1 % for 10-60 deg in a register the fit
    did not see (without it: 2 % low at 26 deg, 8 % at 45 deg); N is even, so the mirror and
    the fold are untouched."""
    from dnabraid.forces.reference_chiral import bead_two_ply

    k = ChiralKernel(DELTA, DEBYE, bead_spacing_nm=5.0, subdivisions=3)
    k1 = ChiralKernel(DELTA, DEBYE)
    for deg in (10.0, 26.0, 45.0, 60.0):
        eta = -math.radians(deg)
        e, e1 = [], []
        for n in (24, 48):
            pos, ch = bead_two_ply(eta, DELTA, 5.0, n, shift=0.25)
            seg, a, b = all_pairs(ch, excl=10**6)
            e.append(pair_terms(pos, seg, a, b, k, 3)[0])
            e1.append(pair_terms(pos, seg, a, b, k1, 3)[0])
        per = (e[1] - e[0]) / 120.0
        assert per == pytest.approx(math.tan(eta / 2), rel=0.01), deg
        if deg == 45.0:
            assert (e1[1] - e1[0]) / 120.0 == pytest.approx(0.923 * math.tan(eta / 2), rel=0.01)


@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_calibrated_force_equals_twin_and_fd(backend):
    rng = np.random.default_rng(SEED + 50)
    kw = dict(KW, subdivisions=3)
    pos, chains = scene(rng)
    force = chiral_force(chains, 1.5, backend=backend, bead_spacing_nm=5.0,
                         calibrate_two_ply=True, **kw)
    e, f = openmm_energy_forces(force, pos)
    er, fr = chiral_energy_forces(pos, chains, 1.5, calibrate_spacing_nm=5.0, **kw)
    e0, _ = chiral_energy_forces(pos, chains, 1.5, **kw)
    assert e == pytest.approx(er, rel=1e-9) and er != pytest.approx(e0, rel=1e-4)
    assert np.allclose(f, fr, rtol=1e-9, atol=1e-9 * np.abs(fr).max())
    h = 1e-6
    for i in rng.choice(len(pos) - 1, 5, replace=False):
        for ax in range(3):
            p = pos.copy()
            p[i, ax] += h
            ep = chiral_energy_forces(p, chains, 1.5, calibrate_spacing_nm=5.0, **kw)[0]
            p[i, ax] -= 2 * h
            em = chiral_energy_forces(p, chains, 1.5, calibrate_spacing_nm=5.0, **kw)[0]
            assert -(ep - em) / (2 * h) == pytest.approx(fr[i, ax], abs=1e-6 * np.abs(fr).max())
    mir = pos.copy()
    mir[:, 2] *= -1
    em, _ = chiral_energy_forces(mir, chains, 1.5, calibrate_spacing_nm=5.0, **kw)
    assert em == pytest.approx(-er, rel=1e-12)
