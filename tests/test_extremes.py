"""Stiff and extreme cases: each case of the matrix has one expected outcome and a part of
the message that outcome must carry (the key and value of a refusal, the check that stopped
a run, "invariants kept" for a run that held them).

Invariants (dnabraid.validation.extremes): finite positions, bonds < 1.5 b, mean catenation within
0.05 of the bead turns, potential energy < 50 kT per particle at the end of every turn
value; a zero-temperature knot must converge. The default run takes the refusals and the
cheap runs; the rest of the matrix is behind ``slow``.
"""

import math

import pytest

from dnabraid.validation.extremes import (
    CASES,
    MAX_ENERGY_PER_BEAD_KT,
    OUTCOMES,
    Case,
    case_settings,
    run_case,
)

CHEAP = {"force 50 pN (taut)", "tether 10 pN, stiff bonds S=5000 pN",
         "time step at the stability limit", "persistence 5 nm = spacing",
         "turns ramped too fast", "knot: trefoil at eps = 0.28"}


def _check(row, case):
    assert row["outcome"] == case.expect, row
    assert case.message in row["detail"], row
    if case.expect == "ok" and math.isfinite(row["time_step_ps"]):  # a Brownian run
        assert row["max_bond_ratio"] < 1.5, row
        assert row["energy_per_bead_kT"] < MAX_ENERGY_PER_BEAD_KT, row
    if case.expect == "stopped":
        assert row["detail"].startswith("simulation blew up at step "), row


FAST = [c for c in CASES if c.expect == "refused" or c.name in CHEAP]
SLOW = [c for c in CASES if c not in FAST]


def test_matrix_cases_are_well_formed():
    assert len({c.name for c in CASES}) == len(CASES)
    for c in CASES:
        assert c.expect in OUTCOMES[:3], c
        assert c.message, c
    assert {c.expect for c in CASES} == {"ok", "refused", "stopped"}


def test_short_run_settings_come_from_the_scene():
    """A case starts from its scene's short run: a tether gets no turns (it cannot hold
    any), a braid gets two turn values, and keys a scene lacks are left out (the knot has
    no DNA length or replicas)."""
    tether = case_settings(Case("t", "tether", {"force_pN": 3.0}))
    braid = case_settings(Case("b", "braid", {"turns": [0.0, 2.0]}))
    knot = case_settings(Case("k", "knot", {"tension_pN": 3.0}))
    assert "turns" not in tether and tether["steps"] == 2000 and tether["force_pN"] == 3.0
    assert tether["length_nm"] == 100.0 and tether["replicas"] == 1
    assert braid["turns"] == [0.0, 2.0] and braid["steps"] == 2000
    assert knot == {"tension_pN": 3.0}


@pytest.mark.parametrize("case", FAST, ids=[c.name for c in FAST])
def test_extreme_case(case):
    _check(run_case(case), case)


@pytest.mark.slow
@pytest.mark.parametrize("case", SLOW, ids=[c.name for c in SLOW])
def test_extreme_case_long(case):
    _check(run_case(case), case)


def test_time_step_follows_stiffest_mode():
    """Finer beads are stiffer (bond k = S/b, bending 16 kappa/b^2): the time step shrinks;
    at 1 nm beads the bond stretch is the stiffest term, and the reason names it."""
    from dnabraid.scenes import make_scene

    steps = [make_scene("braid", {"bead_spacing_nm": b, "length_nm": 60.0,
                                  "tether_separation_nm": 10.0, "turns": [0.0]}).build().timestep
             for b in (1.0, 2.5, 5.0)]
    dts = [t.time_step_ns for t in steps]
    assert dts[0] < dts[1] < dts[2]
    assert steps[0].stiffest_term == "stretch"
    assert all(f"stiffest term '{t.stiffest_term}'" in t.reason for t in steps)
