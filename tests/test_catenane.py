"""Scene ``catenane``: two linked DNA rings (or one) at room temperature.

Known answers: a ring's half-twist difference has <dTw_half^2> = L / (4 pi^2 C) exactly for
the model whatever the writhe (scenes/catenane.py docstring); Lk_i = Tw_i + Wr_i and Lk_12
are conserved; the model is mirror symmetric with alpha -> -alpha (the exact basis of
<Wr>(alpha, dLk) = -<Wr>(-alpha, -dLk)); the MDAnalysis ring classes agree with
geometry.curves on the run's trajectory."""

import csv
import math
import os

import numpy as np
import openmm
import pytest
from openmm import unit as u

from dnabraid import units
from dnabraid.geometry.curves import gauss_linking_number, writhe
from dnabraid.geometry.ribbon import ring_twist
from dnabraid.scenes import SceneError, make_scene

#: Statistical tolerance of a thermal average against theory, in standard errors.
N_SEM = 3.0
#: float32 trajectory positions: geometry from the DCD against the run's float64 values.
TOL_DCD = 2e-3
#: Topology invariants: the discrete White theorem holds to round-off.
TOL_LK = 1e-9

SMALL = {"length_nm": 72.0, "bead_spacing_nm": 3.0, "salt_mM": 1000.0}


_CONTEXTS: dict = {}


def _energy(model, pos, groups=None):
    """Energy (pN nm) on the Reference platform; one Context per model (compiling the twist
    expression is the slow part)."""
    held = _CONTEXTS.get(id(model))
    if held is None or held[0] is not model:  # ids of dead models are reused
        ctx = openmm.Context(model.system, openmm.VerletIntegrator(0.001),
                             openmm.Platform.getPlatformByName("Reference"))
        if len(_CONTEXTS) > 1:
            _CONTEXTS.clear()
        _CONTEXTS[id(model)] = (model, ctx)  # the model is held, so its id stays its own
    ctx = _CONTEXTS[id(model)][1]
    ctx.setPositions(pos * u.nanometer)
    kw = {} if groups is None else {"groups": set(groups)}
    e = ctx.getState(getEnergy=True, **kw).getPotentialEnergy().value_in_unit(
        u.kilojoule_per_mole)
    return units.energy_from_openmm(e)


def _contact_positions(m, gap=1.05, tilt=0.6):
    """The model's start with ring 2 (and its side particles) translated so that its bead
    nearest ring 1 sits ``gap`` diameters from ring 1's nearest bead (chiral contact)."""
    r1, r2 = m.rings
    x = m.positions.copy()
    d = np.linalg.norm(x[r1][:, None] - x[r2][None], axis=-1)
    i, j = np.unravel_index(np.argmin(d), d.shape)
    sep = x[r1[i]] - x[r2[j]]
    # tilt ring 2 about the line of centres by `tilt` rad: a 90 deg crossing (the start's)
    # has no chiral energy (apolar fold)
    k = sep / np.linalg.norm(sep)
    both = np.r_[r2, m.ring_sides[1]]
    v = x[both] - x[r2[j]]
    c, s = np.cos(tilt), np.sin(tilt)
    x[both] = x[r2[j]] + c * v + s * np.cross(k, v) + (1 - c) * np.outer(v @ k, k)
    shift = sep * (1 - gap * m.dna.diameter_nm / np.linalg.norm(sep))
    x[both] += shift
    return x


@pytest.mark.parametrize("moves", [{"rigid_moves": 0}, {"steps": 96000}],
                         ids=["bd", "bd+crankshaft"])
def test_single_ring_half_twist_variance_is_L_over_4pi2C(tmp_path, moves):
    """<dTw_half^2> = L / (4 pi^2 C), exact for the model (the ring's Tw itself is tied to its
    writhe, <dTw^2> = <dWr^2>); Leimkuhler-Matthews keeps the time-step bias ~1 %
    (a 40000-step check: per-joint <delta omega^2> within 1 % of b/C (1 - 1/n)). With the
    scene's default crankshaft moves (dnabraid.moves; their pivots' twist and bend change)
    the distribution must be the same: Metropolis moves keep the Boltzmann weight."""
    s = make_scene("catenane", {"rings": 1, "length_nm": 48.0, "twist_persistence_nm": 50.0,
                                "delta_lk": -1, "integrator": "lm", "steps": 48000,
                                "equilibration_steps": 4000, "replicas": 1, "workers": 1,
                                "frame_interval": 8000, "seed": 3, "start_spread": 0.0,
                                **moves})
    # the regular ring (start_spread = 0): this one replica's check of the variance was
    # sized on it (sem 0.11 / 0.06 x theory); a spread start adds a bend relaxation that
    # the 4000 equilibration steps do not remove (sem 0.18 x theory, seed 3)
    # (with the moves the twist's SEM is larger at equal steps: twice the steps keep the
    # check's power, sem < 0.15 x theory)
    summ = s.run(str(tmp_path / "ring"), threads=1)
    pt = summ["points"][0]
    theory = 48.0 / (4 * math.pi**2 * 50.0)
    assert pt["twist_half_variance_theory"] == pytest.approx(theory)
    v = pt["twist_half_variance_1"]
    print("dTw_half^2:", v["mean"], "+-", v["sem"], "theory", theory)
    assert v["sem"] < 0.15 * theory  # the check has power
    assert abs(v["mean"] - theory) < N_SEM * v["sem"], (v, theory)
    # Lk_1 = Tw + Wr = -1 at every sample; the ring's Tw and Wr fluctuate together
    assert pt["lk_error_max"] < TOL_LK and pt["lk_conserved"]
    assert pt["twist_1"]["mean"] + pt["writhe_1"]["mean"] == pytest.approx(-1.0, abs=1e-9)
    assert pt["twist_variance_1"]["mean"] == pytest.approx(pt["writhe_variance_1"]["mean"],
                                                           rel=1e-6)


def test_catenane_run_conserves_topology_and_mda_agrees(tmp_path):
    """Two linked rings with the chiral term and supercoiling: Lk_12 = link and
    Tw_i + Wr_i = delta_lk at every sample; the run directory's trajectory read back with
    the MDAnalysis ring classes gives the same writhe and linking as the run."""
    import MDAnalysis as mda

    from dnabraid.analysis.mda import RingLinking, RingWrithe, select_rings

    s = make_scene("catenane", {**SMALL, "alpha": 1.0, "delta_lk": -1, "link": -1,
                                "steps": 2000, "equilibration_steps": 400,
                                "frame_interval": 500, "replicas": 1, "workers": 1})
    out = str(tmp_path / "cat")
    summ = s.run(out, threads=1)
    pt = summ["points"][0]
    assert "chiral" in summ["forces"] and "twist" in summ["forces"]
    assert pt["lk12_conserved"] and pt["lk12_min"] == pytest.approx(-1.0, abs=1e-6)
    assert pt["lk_conserved"] and pt["lk_error_max"] < TOL_LK
    for k in (1, 2):
        assert pt[f"twist_{k}"]["mean"] + pt[f"writhe_{k}"]["mean"] == pytest.approx(-1.0,
                                                                                      abs=1e-9)
    # one replica has no between-replica error, so the handedness cannot be called: it is
    # 'undetermined' when the rings touched, 'no contact' when they never did
    eta = pt["braid_angle_rad"]
    assert eta["sem"] is None
    assert pt["handedness"] == ("no contact" if eta["mean"] is None else "undetermined")
    assert (eta["mean"] is None) == (pt["contact_fraction"]["mean"] == 0.0)

    uni = mda.Universe(os.path.join(out, "topology.pdb"), os.path.join(out, "trajectory.dcd"))
    rings, sides = select_rings(uni)
    assert [len(r) for r in rings] == [24, 24] and [len(x) for x in sides] == [24, 24]
    w = RingWrithe(rings[0], sides[0]).run()
    lk = RingLinking(rings[0], rings[1]).run()
    assert lk.results.conserved and np.allclose(lk.results.linking, -1.0, atol=1e-3)
    assert np.allclose(w.results.linking, -1.0, atol=TOL_DCD)
    # against geometry.curves on the same frames and against the run's own float64 values
    with open(os.path.join(out, "observables.csv")) as fh:
        rows = [r for r in csv.DictReader(fh) if r["chiral_energy_pN_nm"] != ""]
    assert len(rows) == uni.trajectory.n_frames == 4
    for i, ts in enumerate(uni.trajectory):
        x = rings[0].positions.astype(float) / 10.0
        assert w.results.writhe[i] == pytest.approx(writhe(x), abs=1e-12)
        assert w.results.twist[i] == pytest.approx(
            ring_twist(x, sides[0].positions.astype(float) / 10.0), abs=1e-12)
        assert lk.results.linking[i] == pytest.approx(
            gauss_linking_number(x, rings[1].positions.astype(float) / 10.0), abs=1e-12)
        assert w.results.writhe[i] == pytest.approx(float(rows[i]["writhe_1"]), abs=TOL_DCD)


def test_handedness_is_called_two_standard_errors_from_zero():
    """The mean braid angle (< 0 right-handed) names a hand only when it lies more than two
    standard errors from 0; otherwise 'undetermined', and 'no contact' without contacts."""
    call = type(make_scene("catenane", SMALL)).handedness
    assert call({"mean": -0.3, "sem": 0.1}) == "right"
    assert call({"mean": 0.3, "sem": 0.1}) == "left"
    assert call({"mean": -0.19, "sem": 0.1}) == "undetermined"
    assert call({"mean": 0.19, "sem": 0.1}) == "undetermined"
    assert call({"mean": 0.3, "sem": None}) == "undetermined"
    assert call({"mean": None, "sem": None}) == "no contact"


def test_model_is_mirror_symmetric_with_alpha_and_delta_lk_reversed():
    """E_{alpha}(x) = E_{-alpha}(M x) for a mirror M (z -> -z), every term included: bonds,
    bending, WCA and twist are achiral (omega -> -omega, energy in omega^2), the chiral
    term is odd in alpha and in the mirror. The scene built with (-alpha, -dLk, -link)
    starts as the mirror image's topology: Lk_i -> -Lk_i, Lk_12 -> -Lk_12. Together this
    makes <Wr>(alpha, dLk) = -<Wr>(-alpha, -dLk) exact (workflows/catenane.py measures it)."""
    a = make_scene("catenane", {**SMALL, "alpha": 1.5, "delta_lk": -1, "link": 1})
    b = make_scene("catenane", {**SMALL, "alpha": -1.5, "delta_lk": 1, "link": -1})
    ma, mb = a.build(), b.build()
    rng = np.random.default_rng(4)
    r1, r2 = ma.rings
    x = _contact_positions(ma) + rng.normal(0, 0.15, ma.positions.shape)
    mirror = x * np.array([1.0, 1.0, -1.0])
    g = {ma.forces["chiral"]}
    ea, ea_chiral = _energy(ma, x), _energy(ma, x, g)
    eb, eb_chiral = _energy(mb, mirror), _energy(mb, x, g)
    assert ea == pytest.approx(eb, rel=1e-9)
    # and not trivially: the chiral part is non-zero and flips with alpha at fixed x
    assert abs(ea_chiral) > 1e-3
    assert eb_chiral == pytest.approx(-ea_chiral, rel=1e-9)
    pa, pb = ma.positions, mb.positions
    for k, (r, sd) in enumerate(zip(ma.rings, ma.ring_sides)):
        lka = ring_twist(pa[r], pa[sd]) + writhe(pa[r])
        rb, sb = mb.rings[k], mb.ring_sides[k]
        lkb = ring_twist(pb[rb], pb[sb]) + writhe(pb[rb])
        assert lka == pytest.approx(-1.0, abs=TOL_LK) and lkb == pytest.approx(1.0, abs=TOL_LK)
    assert gauss_linking_number(pa[r1], pa[r2]) == pytest.approx(1.0, abs=1e-9)
    assert gauss_linking_number(pb[r1], pb[r2]) == pytest.approx(-1.0, abs=1e-9)


def test_chiral_energy_of_a_contact_flips_under_the_mirror():
    """With the rings pushed into contact the chiral term is really there (non-zero) and
    odd under the mirror at fixed alpha."""
    s = make_scene("catenane", {**SMALL, "alpha": 1.5})
    m = s.build()
    r1, r2 = m.rings
    x = _contact_positions(m)
    from dnabraid.scenes.catenane import ChiralEnergy

    ob = ChiralEnergy([r1, r2], 1.5, m.dna.diameter_nm, m.dna.debye_nm, 3.0)
    e = ob(x, {}, {})["chiral_energy_pN_nm"]
    e_m = ob(x * np.array([1, 1, -1.0]), {}, {})["chiral_energy_pN_nm"]
    assert abs(e) > 1e-3 and e_m == pytest.approx(-e, rel=1e-9)
    assert _energy(m, x, {m.forces["chiral"]}) == pytest.approx(e, rel=1e-9)


@pytest.mark.parametrize("link", [1, -1])
def test_contact_start_is_linked_and_near_contact(link):
    """start = 'contact': Lk_12 = link, Lk_i = delta_lk, strands 1.3 diameters apart (to
    half a bead step), no overlap."""
    m = make_scene("catenane", {**SMALL, "start": "contact", "link": link,
                                "delta_lk": 1}).build()
    p = m.positions
    r1, r2 = m.rings
    assert gauss_linking_number(p[r1], p[r2]) == pytest.approx(link, abs=1e-9)
    dmin = np.linalg.norm(p[r1][:, None] - p[r2][None], axis=-1).min()
    assert 1.3 * m.dna.diameter_nm <= dmin < 1.3 * m.dna.diameter_nm + 0.5 * 3.0
    for r, sd in zip(m.rings, m.ring_sides):
        assert ring_twist(p[r], p[sd]) + writhe(p[r]) == pytest.approx(1.0, abs=TOL_LK)


def test_alpha_zero_leaves_the_chiral_term_out_and_no_wall_no_bead():
    m = make_scene("catenane", SMALL).build()
    assert "chiral" not in m.forces
    assert not ({"wall", "pull", "trap", "beadwall"} & set(m.forces))
    assert set(m.forces) >= {"stretch", "bend", "wca", "twist", "frame"}


@pytest.mark.parametrize("over, words", [
    ({"delta_lk": 0.5}, ["delta_lk", "integer"]),
    ({"delta_lk": -5}, ["delta_lk", "45 deg"]),
    ({"link": 0}, ["link", "+1 or -1"]),
    ({"start": "touching"}, ["start", "contact"]),
    ({"rings": 3}, ["rings", "1 or 2"]),
    ({"length_nm": 75.0}, ["length_nm", "even"]),
    ({"length_nm": 73.0}, ["length_nm", "multiple"]),
    ({"bead_spacing_nm": 4.5, "length_nm": 144.0}, ["bead_spacing_nm", "pass through"]),
    ({"length_nm": 24.0, "bead_spacing_nm": 2.0}, ["length_nm", "linked ring"]),
    ({"twist_persistence_nm": 1.0}, ["twist_persistence_nm"]),
    ({"alpha": "lots"}, ["alpha", "salt"]),
    ({"force_pN": 1.0}, ["force_pN", "allowed keys"]),
])
def test_bad_input_names_the_key(over, words):
    with pytest.raises(SceneError) as e:
        make_scene("catenane", {**SMALL, **over})
    for w in words:
        assert w in str(e.value)


def test_alpha_salt_resolves():
    s = make_scene("catenane", {"alpha": "salt"})
    assert s.alpha == pytest.approx(0.4)  # forcefields/chiral.toml at 1 M


def test_single_ring_replicas_start_apart():
    """rings = 1: every replica's start is the regular ring deformed by its own random
    crankshafts: bond lengths exact (1e-9 nm), no two beads three or more apart along the
    ring within the diameter, writhes that differ (sd > 0.02 turns over 8 seeds), and not
    minimised; start_spread = 0 gives the same regular ring to every replica."""
    from dnabraid.geometry.curves import writhe
    wr = []
    for seed in range(1, 9):
        s = make_scene("catenane", {"rings": 1, "seed": seed})
        m = s.build()
        r = m.positions[m.rings[0]]
        b = np.linalg.norm(np.roll(r, -1, axis=0) - r, axis=1)
        assert np.allclose(b, s.bead_spacing_nm, atol=1e-9)
        n = len(r)
        d = np.linalg.norm(r[:, None] - r[None], axis=-1)
        sep = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
        assert np.all(d[np.minimum(sep, n - sep) >= 3] > s.effective_diameter_nm)
        assert m.exact_start
        wr.append(writhe(r))
    assert np.std(wr) > 0.02, wr
    flat = [make_scene("catenane", {"rings": 1, "seed": k, "start_spread": 0.0}).build()
            for k in (1, 2)]
    assert np.array_equal(flat[0].positions, flat[1].positions)
    assert not flat[0].exact_start


@pytest.mark.parametrize("start", ["apart", "contact"])
def test_linked_rings_start_apart_linked_and_as_built(start):
    """Two rings: each replica deforms both by its own crankshafts, keeping Lk_12 (1e-9),
    every bond length (1e-9 nm), and a contact start within half a bead step of its own
    closest distance (1.3 diameters), an apart start above half of its (R); writhes
    differ between seeds."""
    gaps, wr = [], []
    for seed in (1, 2, 3):
        s = make_scene("catenane", {"seed": seed, "start": start})
        m = s.build()
        p = m.positions
        r1, r2 = (p[r] for r in m.rings)
        assert gauss_linking_number(r1, r2) == pytest.approx(s.link, abs=1e-9)
        for r in (r1, r2):
            b = np.linalg.norm(np.roll(r, -1, axis=0) - r, axis=1)
            assert np.allclose(b, s.bead_spacing_nm, atol=1e-9)
        gaps.append(np.linalg.norm(r1[:, None] - r2[None], axis=-1).min())
        wr.append(writhe(r1))
    fs = make_scene("catenane", {"start": start, "start_spread": 0.0})
    flat, flat_b = fs.build(), fs.bead_spacing_nm
    f1, f2 = (flat.positions[r] for r in flat.rings)
    g0 = np.linalg.norm(f1[:, None] - f2[None], axis=-1).min()
    if start == "contact":
        assert all(g0 - 1e-9 <= g <= g0 + 0.5 * flat_b for g in gaps), (gaps, g0)
    else:
        assert all(g >= 0.5 * g0 for g in gaps), (gaps, g0)
    assert np.ptp(wr) > 0.02, wr
