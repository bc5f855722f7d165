"""The two approaches of the plectoneme's moves-only reference (workflows/
plectoneme_mc_reference.py, docs/validation.md 2.3q): the trap-angle protocol each one runs,
and the Welch comparison of their chain means."""

import math

from conftest import load_workflow
import numpy as np
import pytest

@pytest.fixture(scope="module")
def ref():
    return load_workflow("plectoneme_mc_reference")


class _Recorder:
    """Stands in for PlectonemeMoves: records each trap angle and the moves run at it."""

    def __init__(self):
        self.angles, self.moves = [], []
        self.energy = self

    def set_trap_angle(self, theta):
        self.angles.append(theta)

    def run(self, pos, n):
        self.moves.append((self.angles[-1], n))
        return pos, None


def test_up_is_the_stored_references_ramp(ref):
    """``up`` is the protocol the stored reference was made with: RAMP_STAGES + 1 stages of
    RAMP_MOVES from 0 to 2 pi n, then EQ_MOVES at 2 pi n."""
    mv = _Recorder()
    ref.approach(mv, None, 3.0, "up")
    assert len(mv.angles) == ref.RAMP_STAGES + 1
    assert mv.angles[0] == 0.0 and mv.angles[-1] == pytest.approx(6 * math.pi, abs=1e-12)
    assert mv.moves[-1] == (mv.angles[-1], ref.EQ_MOVES)
    assert sum(n for _, n in mv.moves) == (ref.RAMP_STAGES + 1) * ref.RAMP_MOVES + ref.EQ_MOVES


@pytest.mark.parametrize("n", [3.0, -2.0])
def test_down_overshoots_away_from_zero_at_the_same_speed(ref, n):
    """``down`` reaches n + 1 turn (away from 0 for either sign), holds it for EQ_MOVES, comes
    back to n and holds EQ_MOVES; every stage turns the trap by n / RAMP_STAGES turn, the
    speed of ``up`` (the probe of 2026-12-05 at n = 3: 3/400 turn per 2000 moves)."""
    mv = _Recorder()
    ref.approach(mv, None, n, "down", overshoot=1.0)
    top = 2 * math.pi * (n + math.copysign(1.0, n))
    turns = np.array(mv.angles) / (2 * math.pi)
    assert max(abs(turns)) == pytest.approx(abs(n) + 1, abs=1e-12)
    assert mv.angles[-1] == pytest.approx(2 * math.pi * n, abs=1e-12)
    steps = np.abs(np.diff(turns))
    steps = steps[steps > 0]
    # a ramp takes a whole number of stages: at n = 3, 533 up to 4 turns and 133 back,
    # 0.06 % and 0.25 % faster than 3/400 turn per stage
    assert np.allclose(steps, abs(n) / ref.RAMP_STAGES, rtol=5e-3)
    held = [(a, k) for a, k in mv.moves if k == ref.EQ_MOVES]
    assert [a for a, _ in held] == pytest.approx([top, 2 * math.pi * n], abs=1e-12)
    with pytest.raises(ValueError, match="overshoot"):
        ref.approach(_Recorder(), None, n, "down", overshoot=0.0)
    with pytest.raises(ValueError, match="approach"):
        ref.approach(_Recorder(), None, n, "sideways")


def test_approach_split_is_welchs_difference(ref):
    """down - up of the chain means with the Welch standard error sqrt(s_u^2/n_u + s_d^2/n_d),
    computed here by hand on made-up means; flagged beyond APPROACH_T standard errors, absent
    with fewer than two chains on a side. Chains stored before the option count as ``up``."""
    up = [180.0, 181.0, 179.5, 180.5]
    down = [181.0, 182.0, 180.0, 182.5, 181.5]
    chains = ([{"z_mean": z} for z in up]
              + [{"z_mean": z, "approach": "down"} for z in down])
    sp = ref.approach_split(chains)
    se = math.sqrt(np.var(up, ddof=1) / 4 + np.var(down, ddof=1) / 5)
    assert sp["diff"] == pytest.approx(np.mean(down) - np.mean(up), abs=1e-12)
    assert sp["se"] == pytest.approx(se, rel=1e-12)
    assert (sp["up_chains"], sp["down_chains"]) == (4, 5)
    assert sp["disagree"] == (abs(sp["diff"]) > ref.APPROACH_T * se)
    far = chains + [{"z_mean": z + 20, "approach": "down"} for z in down]
    assert ref.approach_split(far)["disagree"]
    assert ref.approach_split(chains[:4] + chains[4:5]) is None
