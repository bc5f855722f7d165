"""The chiral interaction (issue 4): twin, finite differences, mirror, normalisation, sign,
pair search, apolar fold and cutoff continuity.

Tolerances: OpenMM (Reference platform, double) against the numpy twin 1e-9 relative;
finite differences (central, h = 1e-6 nm) 1e-6 relative; the mirror image flips the sign of
the energy to 1e-12 relative; the ideal two-ply carries alpha tan(eta/2) to 1 %.
"""

import math

import numpy as np
import openmm
import pytest
from openmm import unit as u

from dnabraid import units
from dnabraid.forcefield import load_toml
from dnabraid.forces.chiral import ChiralEvaluator, chiral_force, grid_pairs, pair_terms_fast
from dnabraid.forces.reference_chiral import (
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


def openmm_energy_forces(force, pos):
    system = openmm.System()
    for _ in range(len(pos)):
        system.addParticle(1.0)
    system.addForce(force)
    ctx = openmm.Context(system, openmm.VerletIntegrator(0.001),
                         openmm.Platform.getPlatformByName("Reference"))
    ctx.setPositions(pos * u.nanometer)
    st = ctx.getState(getEnergy=True, getForces=True)
    e = units.energy_from_openmm(st.getPotentialEnergy().value_in_unit(u.kilojoule_per_mole))
    f = units.force_from_openmm(
        st.getForces(asNumpy=True).value_in_unit(u.kilojoule_per_mole / u.nanometer))
    return e, np.asarray(f)


def test_twin_against_finite_differences():
    rng = np.random.default_rng(SEED)
    for _ in range(3):
        pos, chains = scene(rng, 10)
        e, f = chiral_energy_forces(pos, chains, 3.0, **KW)
        assert e != 0.0
        h = 1e-6
        fd = np.zeros_like(pos)
        for i in range(len(pos)):
            for k in range(3):
                p = pos.copy()
                p[i, k] += h
                ep, _ = chiral_energy_forces(p, chains, 3.0, **KW)
                p[i, k] -= 2 * h
                em, _ = chiral_energy_forces(p, chains, 3.0, **KW)
                fd[i, k] = -(ep - em) / (2 * h)
        assert np.allclose(f, fd, rtol=1e-6, atol=1e-6 * np.abs(f).max())


@pytest.mark.parametrize("q", [1, 3])
def test_openmm_equals_twin(q):
    rng = np.random.default_rng(SEED + q)
    kw = dict(KW, subdivisions=q)
    for _ in range(3):
        pos, chains = scene(rng)
        force = chiral_force(chains, 2.5, **kw)
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


@pytest.mark.parametrize("delta,debye", [(15.0, 3.04), (4.9, 0.785), (2.9, 0.304)])
def test_normalisation_continuum(delta, debye):
    k = ChiralKernel(delta, debye)
    for deg in (-60, -45, -30, -10, -2, 5, 20, 40, 60):
        eta = math.radians(deg)
        assert k.two_ply_density(eta) == pytest.approx(math.tan(eta / 2), rel=0.01)


@pytest.mark.parametrize("deg", [-50, -20, 35])
def test_normalisation_beads_fine(deg):
    """Bead two-ply, spacing 0.5 nm: energy per unit strand length = alpha tan(eta/2)."""
    eta = math.radians(deg)
    e = []
    for length in (60.0, 120.0):
        pos, ch = two_ply(eta, length=length)
        e.append(fast_energy(pos, ch)[0])
    per_length = (e[1] - e[0]) / 60.0
    assert per_length == pytest.approx(math.tan(eta / 2), rel=0.01)


def test_sign_energy_falls_with_eta():
    """alpha > 0: the two-ply energy falls as eta falls; right-handed (eta < 0) is lower."""
    k = ChiralKernel(DELTA, DEBYE)
    etas = np.radians(np.arange(-85, 86, 5))
    dens = np.array([k.two_ply_density(e) for e in etas])
    assert np.all(np.diff(dens[np.abs(etas) <= math.radians(60)]) > 0)
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
        # across c = 0 at s = 1: G and its slope vanish from both sides
        g, dgc, _ = k.angular(np.array([-eps, eps]), np.array([1.0, 1.0]))
        assert np.all(np.abs(g) < 10 * eps**3) and np.all(np.abs(dgc) < 100 * eps**2)
    # near c = s = 0 (eta undefined) G -> 0
    g, _, _ = k.angular(np.array([1e-4]), np.array([1e-4]))
    assert abs(g[0]) < 1e-7


def test_weight_vanishes_smoothly_at_cutoff():
    k = ChiralKernel(DELTA, DEBYE)
    w, dw = k.weight(np.array([k.r_c - 1e-4, k.r_c, k.r_c + 1.0]))
    assert w[0] < 1e-9 and w[1] == 0.0 and w[2] == 0.0
    assert abs(dw[0]) < 1e-5 and dw[1] == 0.0
    # normalisation along a straight partner (Eq. C2)
    v = np.linspace(-k.r_c, k.r_c, 200001)
    assert np.trapezoid(k.weight(np.hypot(DELTA, v))[0], v) == pytest.approx(1.0, rel=1e-6)


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
