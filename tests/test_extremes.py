"""Stiff and extreme cases (issue 6, item 4): each scene of the matrix either keeps its
invariants over a short run or stops with a clear error naming the limit it hit.

Invariants (dnabraid.extremes): finite positions, bonds < 1.5 b, catenation = bead turns,
potential energy < 50 kT per bead. The default run takes the instant (refused) cases and the
cheap runs; the whole matrix (chiral and fine-bead cases, minutes) is behind ``slow``.
"""

import pytest

from dnabraid.extremes import CASES, run_case

CHEAP = {"force 50 pN (taut)", "tether 10 pN, stiff bonds S=5000 pN",
         "time step at the stability limit", "persistence 5 nm = spacing", "turns ramped too fast"}


def _check(row, case):
    allowed = case.expect.split("|")
    assert row["outcome"] in allowed, row
    if row["outcome"] == "ok":
        assert row["max_bond_ratio"] < 1.5
        assert row["energy_per_bead_kT"] < 50.0
        if case.scene == "braid":
            assert row["catenation_error"] < 0.05  # bead lag K-limited, no passage
    elif row["outcome"] == "refused":
        # the message names the key and what is allowed
        key = row["detail"].split("=")[0]
        assert key in {"force_pN", "salt_mM", "tether_separation_nm", "bead_spacing_nm",
                       "turns", "alpha"}, row["detail"]
        assert any(w in row["detail"] for w in ("must", "allow", "Use "))
    elif row["outcome"] == "stopped":
        assert "step" in row["detail"] and ("term" in row["detail"] or "passed" in row["detail"]
                                            or "slipped" in row["detail"])


FAST = [c for c in CASES if c.expect == "refused" or c.name in CHEAP]
SLOW = [c for c in CASES if c not in FAST]


@pytest.mark.parametrize("case", FAST, ids=[c.name for c in FAST])
def test_extreme_case(case):
    _check(run_case(case), case)


@pytest.mark.slow
@pytest.mark.parametrize("case", SLOW, ids=[c.name for c in SLOW])
def test_extreme_case_long(case):
    _check(run_case(case), case)


def test_time_step_follows_stiffest_mode():
    """Finer beads are stiffer (bond k = S/b, bending 16 kappa/b^2): the time step shrinks."""
    from dnabraid.build import build
    from dnabraid.scene import make_scene

    dts = [build(make_scene("braid", {"bead_spacing_nm": b, "length_nm": 60.0,
                                      "tether_separation_nm": 10.0, "turns": [0.0]}))
           .params["time_step_ns"] for b in (1.0, 2.5, 5.0)]
    assert dts[0] < dts[1] < dts[2]
