"""workflows/braid_force_ladder.py on a short run: the ladder keeps every rung at the trap's
catenation (the rungs differ in force only), the swaps only permute the states, and each
rung is judged by the braid scene's rule. A smoke test of the plumbing: its
sampling is far too short for a converged point, and the verdicts must say so."""

from __future__ import annotations

import argparse

import numpy as np
from conftest import load_workflow


def test_force_ladder_workflow_keeps_the_catenation(tmp_path):
    wf = load_workflow("braid_force_ladder")
    a = argparse.Namespace(length=100.0, turns=1.5, forces=[1.0, 2.0], salt=150.0,
                           separation=40.0, replicas=2, rounds=20, eq_rounds=2,
                           round_moves=300, rung_moves=3000, frame_every=5, seed=1)
    paths = [wf.run_ladder((a, r, str(tmp_path / f"l{r}.npz"))) for r in range(2)]
    for p in paths:
        d = np.load(p)
        ca = d["f_catenation"]
        assert ca.shape == (2, 4)
        assert np.all(np.abs(ca - 1.5) < 0.1), ca  # the trap holds n = 1.5 on both rungs
        assert all(sorted(w) == [0, 1] for w in d["who"])  # states only permuted
    res = wf.summarise(a, paths)
    assert [r["force_pN"] for r in res["rows"]] == [1.0, 2.0]
    for row in res["rows"]:
        assert not row["converged"]  # 20 rounds: ESS far below 100
        assert "ESS" in row["reason"]
    assert "| 1 |" in wf.render([res])
