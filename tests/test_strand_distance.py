"""The braid's StrandDistance observable (the ply's length, distance and mean chiral weight)
on geometries whose answers are known by hand."""

from __future__ import annotations

import numpy as np

from dnabraid.forces.reference_chiral import ChiralKernel
from dnabraid.observables import StrandDistance
from dnabraid.scenes import make_scene


def _strands(gap_nm, n=21, b=5.0, splay_from=None):
    """Two straight vertical strands gap_nm apart (x = 0 and x = gap), beads every b; from
    bead ``splay_from`` on, strand 2 leaves at 45 degrees."""
    z = b * np.arange(n)
    s1 = np.c_[np.zeros(n), np.zeros(n), z]
    x2 = np.full(n, float(gap_nm))
    if splay_from is not None:
        x2[splay_from:] += z[splay_from:] - z[splay_from]
    s2 = np.c_[x2, np.zeros(n), z]
    return np.vstack([s1, s2]), (np.arange(n), np.arange(n, 2 * n))


def test_parallel_strands_at_contact_and_apart():
    k = ChiralKernel(4.9, 0.78)  # D_c 4.9 nm, Debye 0.78 nm (150 mM)
    pos, chains = _strands(4.9)
    ob = StrandDistance(chains, k)
    v = ob(pos, None, {})
    assert abs(v["axis_distance_nm"] - 4.9) < 1e-12
    assert abs(v["chiral_weight"] - 1.0) < 1e-12
    assert abs(v["ply_length_nm"] - 100.0) < 1e-9  # all 20 segments of 5 nm
    # one range beyond contact: w = (1 + 1) e^-1 (inside the switch's flat part)
    pos, chains = _strands(4.9 + k.range)
    v = StrandDistance(chains, k)(pos, None, {})
    assert abs(v["chiral_weight"] - 2.0 * np.exp(-1.0)) < 1e-12
    # beyond 2 D_c: no ply, the closest approach, weight 0
    pos, chains = _strands(10.0)
    v = StrandDistance(chains, k)(pos, None, {})
    assert v["ply_length_nm"] == 0.0 and v["chiral_weight"] == 0.0
    assert abs(v["axis_distance_nm"] - 10.0) < 1e-12


def test_a_splayed_leg_is_not_in_the_ply():
    """Strand 2 leaves at 45 degrees from bead 10: strand 1's segments whose closest
    distance to strand 2 stays below 2 D_c are the 10 straight ones and those within
    (2 D_c - D_c) / sin 45 of the kink's height."""
    k = ChiralKernel(4.9, 0.78)
    pos, chains = _strands(4.9, splay_from=10)
    v = StrandDistance(chains, k)(pos, None, {})
    assert 50.0 <= v["ply_length_nm"] <= 50.0 + 5.0 * np.ceil(4.9 / np.sin(np.pi / 4) / 5.0)
    assert v["chiral_weight"] < 1.0


def test_the_braid_reports_it_with_the_capsule_contact_only():
    def names(**kw):
        s = make_scene("braid", {"replicas": 1, "turns": [1.0], **kw})
        return {c for ob in s.observables(s.build()) for c in ob.columns}

    assert {"ply_length_nm", "chiral_weight", "axis_distance_nm"} <= names(contact="capsules")
    assert "chiral_weight" not in names()
