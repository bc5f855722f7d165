"""The knot scene: energy twins, Newton relaxation, topology and scene validation."""

import numpy as np
import pytest

from dnabraid import scenes as scn
from dnabraid.forces import reference as ref
from dnabraid.forces import segment_contact as segc
from dnabraid.statics import open_knot as K

SEED = 7


def _rod(eps=0.3, **kw):
    R = 1.0 / eps**2
    return K.KnotRod(n=1, tension_pN=1000.0 / (2 * R * R), **kw)


@pytest.fixture(scope="module", params=["segments", "beads"])
def rod(request):
    # eps = 0.3: a tight trefoil, a few hundred beads; both contact models
    return _rod(contact=request.param)


def _perturbed(rod):
    x0 = K.initial_geometry(rod)
    return x0, x0 + 0.05 * np.random.default_rng(SEED).normal(size=x0.shape)


def _central(f, x, i, h=1e-6):
    """Central difference of f (a function of the flat coordinates) along coordinate i."""
    xp, xm = x.ravel().copy(), x.ravel().copy()
    xp[i] += h
    xm[i] -= h
    return (f(xp.reshape(-1, 3)) - f(xm.reshape(-1, 3))) / (2 * h)


def test_gradient_matches_finite_differences_and_reference_twins(rod):
    x0, x = _perturbed(rod)
    prob = K.make_problem(rod, x0)
    g, _ = K.gradient_hessian(x, prob, gauss_newton=False)
    rng = np.random.default_rng(SEED)
    for i in rng.choice(x.size, 15, replace=False):
        fd = _central(lambda y: K.energy(y, prob), x, i)
        assert fd == pytest.approx(g[i], abs=1e-4 * max(1.0, abs(g[i])))
    # the chain and contact terms against the independent numpy twins
    b = rod.bead_spacing_nm
    N = len(x)
    e_s, f_s = ref.stretch(x, [(i, i + 1) for i in range(N - 1)], rod.stretch_modulus_pN / b, b)
    e_b, f_b = ref.bending(x, [(i, i + 1, i + 2) for i in range(N - 2)],
                           rod.bending_stiffness_pN_nm2 / b)
    if rod.contact == "beads":
        e_c, f_c = ref.contact(x, rod.thickness_nm, rod.contact_stiffness_pN_nm,
                               rod.exclusion_range)
    else:
        # every pair of segments more than exclusion_range apart, by brute force
        seg = segc.chain_segments(N)
        s, t = np.triu_indices(len(seg), rod.exclusion_range + 1)
        e_c = segc.contact_energy(x, seg, np.column_stack([s, t]), 2 * rod.thickness_nm,
                                  rod.contact_stiffness_pN_nm)
    terms = K.energy_terms(x, prob)
    assert terms["stretch"] == pytest.approx(e_s, rel=1e-12)
    assert terms["bend"] == pytest.approx(e_b, rel=1e-12)
    assert terms["contact"] == pytest.approx(e_c, rel=1e-12, abs=1e-12)
    assert e_c > 0  # the perturbation makes contacts overlap: the term is exercised


def test_hessian_matches_finite_differences(rod):
    x0, x = _perturbed(rod)
    prob = K.make_problem(rod, x0)
    _, H = K.gradient_hessian(x, prob, gauss_newton=False)
    rng = np.random.default_rng(SEED)
    for i in rng.choice(x.size, 8, replace=False):
        col = _central(lambda y: K.gradient_hessian(y, prob, gauss_newton=False)[0], x, i)
        assert np.abs(col - H[:, i].toarray().ravel()).max() <= 1e-6 * max(1.0, np.abs(col).max())


def test_openmm_system_is_the_same_energy(rod):
    x0, x = _perturbed(rod)
    prob = K.make_problem(rod, x0)
    g, _ = K.gradient_hessian(x, prob)
    e, f = K.openmm_forces(rod, x, x0)
    assert e == pytest.approx(K.energy(x, prob), rel=1e-10)
    assert np.abs(f + g.reshape(-1, 3)).max() < 1e-8 * np.abs(f).max()


#: Tolerance on the spread |tight - loose| / mean of 2 T R^2 / B between the two starts
#: (found 2026-11-30: "the two starts within 2 % of each other").
BAND_SPREAD = 0.02


def _band(rod):
    out = {}
    for name, rf in (("tight", 0.8), ("loose", 1.25)):
        out[name] = K.compare(rod, radius_factor=rf, check_openmm=(name == "tight"))
    return out


def _spread(band, key):
    a, b = band["tight"][key], band["loose"][key]
    return abs(a - b) / (0.5 * (a + b))


def test_trefoil_band_collapses_with_segment_contact():
    """eps = 0.3, b = h/2 (the fast case): from a tight (loop 0.8 R) and a loose (1.25 R)
    start the frictionless segment contact reaches one equilibrium. The bead contact does
    not (its corrugation pins the loop: workflows/results/knot_crosscheck.md, 2TR_apex^2/B
    = 0.97 / 1.06 at eps = 0.3 and 1.06 / 1.54 at eps = 0.2)."""
    rod = _rod()
    band = _band(rod)
    r = band["tight"]
    for b in band.values():
        assert b["converged"]
        # topology (2, 2n+1): the half-difference winds 2 pi n between the outer crossings
        assert b["winding_turns"] == pytest.approx(1.0, abs=0.01)
        assert b["crossings"] == 3
        assert b["max_overlap_nm"] < 0.01 * rod.thickness_nm
    assert r["openmm_max_force_pN"] < 1e-4 * rod.tension_pN
    # the band: R = Delta L / 2 pi (the seed's measure) and 1 / curvature at the apex;
    # measured spreads 0.0008 and 0.0001
    assert _spread(band, "tension_ratio_dL") < BAND_SPREAD
    assert _spread(band, "tension_ratio_curvature") < BAND_SPREAD
    # continuum (Audoly et al. 2007, Eq. 1 and 7) is the leading order in eps; at eps = 0.3 the
    # braid is 2 sqrt(2) w_c eps = 3 loop radii long, so the corrections are large:
    # measured 2TR_dL^2/B = 1.54, l / l_theory = 0.73 (workflows/results/knot_band.md shows
    # them shrinking with eps). Characterisation bands round those numbers:
    assert r["tension_ratio_dL"] == pytest.approx(1.54, abs=0.05)
    assert r["braid_ratio"] == pytest.approx(0.73, abs=0.05)


@pytest.mark.slow
def test_trefoil_band_at_eps_02_converges_towards_the_seed_law():
    """eps = 0.2, b = h/2 (the 2026-11-30 check): the two starts within 2 %, and the
    deviation from T = EI / (2 R_dL^2) (Audoly, Clauvelin & Neukirch 2007, Eq. 1) smaller
    than at eps = 0.3 (the theory is the eps -> 0 limit). The 5 % target against Eq. 1 at
    eps = 0.2 is NOT met: measured 2TR_dL^2/B = 1.29 (b = h/2 and h/4 alike)."""
    band = _band(_rod(0.2))
    assert _spread(band, "tension_ratio_dL") < BAND_SPREAD
    assert _spread(band, "tension_ratio_curvature") < BAND_SPREAD
    dev02 = abs(band["tight"]["tension_ratio_dL"] - 1.0)
    dev03 = abs(K.compare(_rod(0.3), check_openmm=False)["tension_ratio_dL"] - 1.0)
    assert dev02 < dev03


def test_cinquefoil_winds_twice():
    # bead contact: with the frictionless segment contact the cinquefoil at eps = 0.3
    # tightens until its braid is ~6.5 loop radii long (2 sqrt2 w_c eps, w_c = 7.64) and the
    # crossing-based measurement sees half a winding (the limit noted for eps = 0.5 below)
    rod = _rod(contact="beads")
    rod = K.KnotRod(n=2, tension_pN=rod.tension_pN, contact="beads")
    r = K.compare(rod, check_openmm=False)
    assert r["converged"]
    assert r["winding_turns"] == pytest.approx(2.0, abs=0.02)


def test_knot_scene_keys_and_limits():
    s = scn.make_scene("knot")
    assert s.scene == "knot" and s.bead_spacing_nm == 0.5
    assert s.contact == "segments" and s.rod().contact == "segments"
    assert scn.make_scene("knot", {"contact": "beads"}).rod().contact == "beads"
    with pytest.raises(scn.SceneError, match="contact.*segments"):
        scn.make_scene("knot", {"contact": "capsules"})
    with pytest.raises(ValueError, match="contact"):
        K.KnotRod(contact="capsules")
    assert "force_pN" not in scn.SCENES["knot"].keys()
    assert "tension_pN" not in scn.SCENES["braid"].keys()
    with pytest.raises(scn.SceneError, match="tension_pN.*eps"):
        scn.make_scene("knot", {"tension_pN": 100.0})
    with pytest.raises(scn.SceneError, match="bead_spacing_nm"):
        scn.make_scene("knot", {"bead_spacing_nm": 2.0})
    with pytest.raises(scn.SceneError, match="beads"):
        scn.make_scene("knot", {"tension_pN": 1e-4})
    with pytest.raises(scn.SceneError, match="unknown key"):
        scn.make_scene("knot", {"force_pN": 1.0})


@pytest.mark.slow
def test_tight_knot_eps_half_relaxes():
    # the extreme of the matrix: eps = 0.5 (Audoly, Clauvelin & Neukirch 2007, Fig. 6: 0.52)
    s = scn.make_scene("knot", {"tension_pN": 1000.0 * 0.5**4 / 2})
    r = K.compare(s.rod())
    assert r["converged"] and r["openmm_max_force_pN"] < 1e-4 * s.tension_pN
    # contact forces grow as eps^3: the penalty's overlap is 0.016 h here (0.0005 h at 0.2)
    assert r["max_overlap_nm"] < 0.025
    # The winding is not asserted here: the crossing-based braid measurement sees only half
    # a winding at eps = 0.5 (the loop is no longer separate from the braid), a known
    # limit of the measurement, not a property of the knot.


def test_cli_run_knot(tmp_path):
    from dnabraid.cli import main

    out = tmp_path / "k"
    assert main(["run", "knot", "--set", "tension_pN=5.0", "--out", str(out), "--quiet"]) == 0
    import json

    summ = json.loads((out / "summary.json").read_text())
    assert summ["measured"]["winding_turns"] == pytest.approx(1.0, abs=0.01)
    assert (out / "knot.png").exists() and (out / "topology.pdb").exists()
    import MDAnalysis as mda

    assert mda.Universe(str(out / "topology.pdb")).atoms.n_atoms == summ["beads"]
