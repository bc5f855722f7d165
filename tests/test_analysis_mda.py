"""MDAnalysis classes on a synthetic OpenMM-written (PDB + DCD) helix-braid trajectory."""

import warnings

import MDAnalysis as mda
import numpy as np
import pytest
from openmm import app, unit

from dnabraid.analysis import geometry
from dnabraid.analysis.mda import (
    BendingPersistence,
    Catenation,
    CrossingAngles,
    Extension,
    select_strands,
)

N_BEADS = 41
RADIUS = 1.0  # nm
LENGTH = 30.0  # nm
TURNS = [0.0, 0.5, 1.25, 2.0, -0.75]  # one frame each
#: float32 DCD storage in Angstrom limits agreement to ~1e-5 nm.
TOL = 1e-3


def helix(n_turns, k):
    t = np.linspace(0.0, 1.0, N_BEADS)
    ang = 2 * np.pi * n_turns * t + k * np.pi
    return np.c_[RADIUS * np.cos(ang), RADIUS * np.sin(ang), LENGTH * t]


@pytest.fixture(scope="module")
def braid_universe(tmp_path_factory):
    """Two chains A/B written exactly as the engine does (PDBFile + DCDFile)."""
    tmp = tmp_path_factory.mktemp("braid")
    top = app.Topology()
    carbon = app.Element.getBySymbol("C")
    for chain_id in "AB":
        chain = top.addChain(chain_id)
        prev = None
        for _ in range(N_BEADS):
            res = top.addResidue("DNA", chain)
            atom = top.addAtom("C", carbon, res)
            if prev is not None:
                top.addBond(prev, atom)
            prev = atom
    frames = [np.vstack([helix(n, 0), helix(n, 1)]) for n in TURNS]
    pdb, dcd = tmp / "braid.pdb", tmp / "braid.dcd"
    with open(pdb, "w") as fh:
        app.PDBFile.writeFile(top, frames[0] * unit.nanometer, fh)
    with open(dcd, "wb") as fh:
        writer = app.DCDFile(fh, top, 0.01 * unit.picosecond)
        for x in frames:
            writer.writeModel(x * unit.nanometer)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # DCDReader timestep notice
        u = mda.Universe(str(pdb), str(dcd))
    return u


def test_chain_ids_are_exposed_as_chainid_and_segid(braid_universe):
    u = braid_universe
    s1, s2 = select_strands(u)
    assert len(s1) == len(s2) == N_BEADS
    assert set(s1.chainIDs) == {"A"} and set(s2.chainIDs) == {"B"}
    assert np.array_equal(s1.indices, u.select_atoms("segid A").indices)
    assert np.all(np.diff(s1.indices) > 0)
    with pytest.raises(ValueError, match="chainID"):
        select_strands(u, chains=("A", "Z"))


def test_extension_in_nm(braid_universe):
    s1, _ = select_strands(braid_universe)
    ext = Extension(s1, reference_z_nm=1.0).run()
    assert ext.results.extension_nm.shape == (len(TURNS),)
    np.testing.assert_allclose(ext.results.extension_nm, LENGTH - 1.0, atol=TOL)
    assert ext.results.mean == pytest.approx(LENGTH - 1.0, abs=TOL)
    assert ext.results.sem == pytest.approx(0.0, abs=TOL)


def test_catenation_per_frame(braid_universe):
    s1, s2 = select_strands(braid_universe)
    cat = Catenation(s1, s2).run()
    np.testing.assert_allclose(cat.results.catenation, TURNS, atol=TOL)
    assert cat.results.mean == pytest.approx(np.mean(TURNS), abs=TOL)
    part = Catenation(s1, s2).run(start=1, stop=3)
    np.testing.assert_allclose(part.results.catenation, TURNS[1:3], atol=TOL)


def test_crossing_angles_histogram(braid_universe):
    s1, s2 = select_strands(braid_universe)
    ca = CrossingAngles(s1, s2, cutoff_nm=2.5 * RADIUS).run(start=1, stop=4)
    res = ca.results
    edges, counts = res.histogram
    assert counts.sum() == res.eta.size == 3 * (N_BEADS - 1)
    assert edges[0] == pytest.approx(-np.pi / 2) and edges[-1] == pytest.approx(np.pi / 2)
    for i, n in enumerate(TURNS[1:4]):  # frame_index counts analysed frames
        dang = 2 * np.pi * n / (N_BEADS - 1)
        # closest approach: bond midpoints, at radius R cos(dang / 2) from the axis
        sel = res.frame_index == i
        np.testing.assert_allclose(res.distance_nm[sel], 2 * RADIUS * np.cos(dang / 2), atol=TOL)
        theta = np.arctan(2 * RADIUS * np.sin(dang / 2) / (LENGTH / (N_BEADS - 1)))
        np.testing.assert_allclose(res.eta[res.frame_index == i], -2 * theta, atol=TOL)
    with pytest.raises(ValueError):
        CrossingAngles(s1, s2, cutoff_nm=-1.0)


def test_bending_persistence(braid_universe):
    s1, _ = select_strands(braid_universe)
    bp = BendingPersistence(s1).run()
    dz = LENGTH / (N_BEADS - 1)
    expected = []
    for n in TURNS:
        dang = 2 * np.pi * n / (N_BEADS - 1)
        h2 = (2 * RADIUS * np.sin(dang / 2)) ** 2
        expected.append((h2 * np.cos(dang) + dz**2) / (h2 + dz**2))
    np.testing.assert_allclose(bp.results.mean_cos_per_frame, expected, atol=1e-6)
    assert bp.results.mean_cos == pytest.approx(np.mean(expected), abs=1e-6)
    b = np.mean([geometry.bond_lengths(helix(n, 0)).mean() for n in TURNS])
    assert bp.results.bond_length_nm == pytest.approx(b, abs=TOL)
    assert bp.results.persistence_nm == pytest.approx(
        geometry.persistence_length_from_cosines(np.mean(expected), b), rel=1e-3
    )


def test_strands_from_different_universes_rejected(braid_universe, tmp_path):
    s1, _ = select_strands(braid_universe)
    other = mda.Universe.empty(3, trajectory=True)
    with pytest.raises(ValueError, match="same Universe"):
        Catenation(s1, other.atoms)
