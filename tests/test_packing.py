"""Packed replicas (dnabraid.run.packing): R copies of a scene in one System must be exactly R
independent systems: the same energy and forces as each copy alone, no coupling through the
excluded volume, and the same statistics as replicas in their own Contexts (the packed
tether's error bars are calibrated against the exact discrete WLC)."""

import math

import numpy as np
import openmm
import pytest
from openmm import unit as u

from dnabraid.continuum.wlc import discrete_wlc_exact
from dnabraid.run.driver import replica_groups
from dnabraid.run.packing import PackError, grid_offsets, pack_models, packable, replicate_system
from dnabraid.scenes import make_scene

#: packing is about Euler-Maruyama's Contexts: with the braid's default integrator 'mala'
#: (one accept/reject per Context) pack = 0 means one replica per Context
BRAID = {"length_nm": 60.0, "force_pN": 10.0, "turns": [1.0], "integrator": "euler"}


def _energy_forces(system, pos):
    integ = openmm.VerletIntegrator(1e-3)
    ctx = openmm.Context(system, integ, openmm.Platform.getPlatformByName("Reference"))
    ctx.setPositions(pos * u.nanometer)
    st = ctx.getState(getEnergy=True, getForces=True)
    e = st.getPotentialEnergy().value_in_unit(u.kilojoule_per_mole)
    f = st.getForces(asNumpy=True).value_in_unit(u.kilojoule_per_mole / u.nanometer)
    return e, np.asarray(f)


def _members(scene_name, over, R, turns=None):
    """R replicas' models; each copy's positions get their own 0.1 nm noise, so that no two
    copies are alike (a term pointing into the wrong copy would then show)."""
    base = make_scene(scene_name, over)
    rng = np.random.default_rng(11)
    out = []
    for r in range(R):
        s = make_scene(scene_name, dict(over, seed=base.seed + r + 1))
        m = s.build()
        if turns is not None:
            m.positions[:] = s.start_positions(m, turns)
        m.positions[:] += rng.normal(0.0, 0.1, m.positions.shape)
        out.append(m)
    return out


@pytest.mark.parametrize("scene_name, over, turns", [
    ("braid", BRAID, 1.0),  # braided and in contact: WCA, bead sphere, trap, links
    ("braid", dict(BRAID, alpha=2.0), 1.0),  # the chiral PythonForce, rebuilt over copies
    ("plectoneme", {"length_nm": 60.0, "force_pN": 2.0}, None),  # twist and frames
    ("tether", {"length_nm": 50.0}, None),
    ("catenane", {"alpha": 2.0, "start": "contact", "delta_lk": -1}, None),  # rings, twist
])
def test_packed_system_is_the_sum_of_its_copies(scene_name, over, turns):
    """Energy = sum of the copies' energies and forces = each copy's own forces (to round-
    off), at each replica's own configuration, with copies on the packing grid. The braid
    copies are braided at n = 1 and in contact, so WCA, bead sphere and (alpha != 0) the
    chiral term all act."""
    members = _members(scene_name, over, 3, turns)
    pack = pack_models(members)
    e, f = _energy_forces(pack.model.system, pack.model.positions)
    e_sum = 0.0
    for r, m in enumerate(members):
        er, fr = _energy_forces(m.system, m.positions)
        e_sum += er
        np.testing.assert_allclose(f[pack.slice(r)], fr, rtol=1e-9, atol=1e-7)
    assert e == pytest.approx(e_sum, rel=1e-10, abs=1e-8)
    # the copies sit on a centred grid, their starts within their cells
    assert np.allclose(pack.offsets.max(axis=0) + pack.offsets.min(axis=0), 0.0)
    pack.check_apart(pack.split(pack.model.positions))


def test_copies_do_not_interact_even_when_close():
    """A nonbonded term is the only one that could couple copies: bring two braid copies
    within the WCA range of each other and the packed energy changes (so the test can
    fail), while at the grid spacing it equals the sum of the copies'."""
    members = _members("braid", BRAID, 2, 1.0)
    pack = pack_models(members)
    sys2 = pack.model.system
    e_far, _ = _energy_forces(sys2, pack.model.positions)
    close = pack.model.positions.copy()
    n = pack.n_per_copy
    close[n:] = members[1].positions + pack.offsets[0] + np.array([3.0, 0, 0])  # overlapping
    e_close, _ = _energy_forces(sys2, close)
    assert e_close > e_far + 1.0  # kJ/mol: the overlapping copies repel
    with pytest.raises(PackError, match="could interact"):
        parts = pack.split(pack.model.positions)
        parts[1] = parts[1] + np.array([pack.half_cell_nm + 1.0, 0.0, 0.0])
        pack.check_apart(parts)


def test_only_interacting_particles_must_stay_in_their_cell():
    """The bead centre is in no nonbonded term (WCA switch 0; its wall is bonded to its own
    strands), so its swing does not stop a packed run (a 2 x 100 nm braid with moves did
    stop when its centre reached 122 nm, 2026-12-03); a DNA bead that far still does."""
    from dnabraid.run.packing import interacting_particles
    members = _members("braid", BRAID, 2, 1.0)
    m = members[0]
    mask = interacting_particles(m.system)
    assert not mask[m.bead_center]
    assert all(mask[int(i)] for ch in m.chains for i in ch)
    pack = pack_models(members)
    parts = pack.split(pack.model.positions)
    parts[1] = parts[1].copy()
    parts[1][m.bead_center, 0] += pack.half_cell_nm + 50.0
    pack.check_apart(parts)
    parts[1][int(m.chains[0][5]), 0] += pack.half_cell_nm + 50.0
    with pytest.raises(PackError, match="could interact"):
        pack.check_apart(parts)


def test_grid_offsets():
    for R in (1, 2, 3, 4, 5, 9):
        o = grid_offsets(R, 100.0)
        assert o.shape == (R, 3) and np.all(o[:, 2] == 0)
        d = np.linalg.norm(o[:, None] - o[None], axis=-1) + np.eye(R) * 1e9
        assert d.min() >= 100.0 - 1e-9
        assert np.abs(o[:, :2]).max() <= 100.0 * math.ceil(math.sqrt(R)) / 2


def test_chiral_and_mirror_scenes_pack():
    """The chiral term is a PythonForce: it cannot be copied, so a packed System builds one
    over every copy's strands (model.rebuild_forces); without that recipe the
    System cannot be packed. Mirror pairs pack too, along x only (tests/test_mirror.py
    checks that the packed image is still the exact mirror)."""
    s = make_scene("braid", dict(BRAID, alpha=1.0))
    m = s.build()
    assert not packable(m.system)[0]
    with pytest.raises(PackError, match="cannot pack"):
        replicate_system(m.system, 2)
    assert packable(m.system, m.rebuild_forces)[0]
    assert replica_groups(s, range(4), 1, "CPU", m) == [(0, 1, 2, 3)]
    s = make_scene("braid", dict(BRAID, mirror="original"))
    assert replica_groups(s, range(4), 1, "CPU", s.build()) == [(0, 1, 2, 3)]
    members = _members("braid", dict(BRAID, mirror="image"), 3, 1.0)
    assert np.all(pack_models(members, line=True).offsets[:, 1:] == 0.0)
    s = make_scene("braid", BRAID)
    m = s.build()
    assert replica_groups(s, range(4), 2, "CPU", m) == [(0, 1), (2, 3)]
    assert replica_groups(s, range(5), 2, "CPU", m) == [(0, 1, 2), (3, 4)]
    assert replica_groups(make_scene("braid", dict(BRAID, pack=1)), range(2), 1, "CPU", m) \
        == [(0,), (1,)]
    mala = make_scene("braid", dict(BRAID, integrator="mala"))
    assert replica_groups(mala, range(4), 2, "CPU", m) == [(0,), (1,), (2,), (3,)]
    assert replica_groups(make_scene("braid", dict(BRAID, integrator="mala", pack=2)),
                          range(4), 2, "CPU", m) == [(0, 1), (2, 3)]


def test_packed_tether_is_calibrated_against_the_exact_wlc(tmp_path):
    """Eight replicas in one Context (exact starts, no wall or self-avoidance): the mean's
    99 % Student-t interval covers the exact discrete WLC (transfer matrix, computed
    independently), and the replica means scatter as those of eight replicas run in their
    own Contexts (F test of the two variances, two-sided 1 %): packing changes the cost, not
    the statistics. (The within-replica SEM is no yardstick here: the 0.24 us replicas are
    shorter than the pivot mode, ~1.3 us, and only the exact starts make them honest.)"""
    from scipy import stats

    base = {"force_pN": 3.0, "length_nm": 25.0, "surface": False, "self_avoidance": False,
            "steps": 10_000, "equilibration_steps": 0, "frame_interval": 10_000,
            "replicas": 8, "workers": 1, "seed": 7}
    d = make_scene("tether", base).dna()
    res = {}
    for pack in (8, 1):
        s = make_scene("tether", dict(base, pack=pack, seed=7 + pack))
        summ = s.run(str(tmp_path / f"p{pack}"))
        packed = any("packed into 1 OpenMM Context" in n for n in summ["notes"])
        assert packed == (pack == 8)
        res[pack] = summ["points"][0]["extension_nm"]
    exact = discrete_wlc_exact(s.force_pN, s.n_beads - 1, s.bead_spacing_nm, d.kappa_kT, d.kT,
                               stretch_k_pN_per_nm=d.k_bond)["extension_nm"]
    t99 = stats.t(7).ppf(0.995)  # one study per layout: a 99 % interval (fails 1 % by chance)
    for ext in res.values():
        assert abs(ext["mean"] - exact) <= t99 * ext["sem"], (ext, exact)
    a, b = (np.array(res[k]["replica_means"]) for k in (8, 1))
    assert len(a) == 8 and len(set(np.round(a, 9))) == 8  # distinct replicas
    F = a.var(ddof=1) / b.var(ddof=1)
    lo, hi = stats.f(7, 7).ppf([0.005, 0.995])
    assert lo <= F <= hi, (F, a, b)


def test_packed_catenane_keeps_each_replicas_topology(tmp_path):
    """Two catenane replicas in one Context: each keeps its own Lk_12 and Tw + Wr = Lk_i
    (checked every sample by the scene's observables), and the run says it packed them."""
    s = make_scene("catenane", {"alpha": 2.0, "start": "contact", "delta_lk": -1,
                                "steps": 2000, "equilibration_steps": 200,
                                "frame_interval": 1000, "replicas": 2, "workers": 1})
    summ = s.run(str(tmp_path / "c"))
    assert any("packed into 1 OpenMM Context(s) of 2" in n for n in summ["notes"])
    pt = summ["points"][0]
    assert pt["n_replicas"] == 2
    assert pt["lk12_conserved"] and pt["lk_conserved"]
