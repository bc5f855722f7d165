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


def _synthetic(turns, forces, alpha, beta):
    """Rows with torque alpha n F and extension 80 - beta n^2 (+ F): they obey the Maxwell
    relation dGamma/dF = -(1/2 pi) dz/dn exactly when beta = pi alpha."""
    rows = [{"force_pN": F, "torque_pN_nm": {"mean": alpha * turns * F, "sem": 0.01},
             "extension_nm": {"mean": 80 - beta * turns**2 + F, "sem": 0.01}}
            for F in forces]
    return {"length_nm": 100.0, "salt_mM": 150.0, "forces_pN": forces, "turns": turns,
            "rows": rows}


def test_maxwell_table_on_rows_that_obey_it_and_rows_that_do_not():
    """Uneven forces (the three-point derivative must be exact for a torque linear in F)
    and three catenations (the central difference exact for z quadratic in n): z = 0 to
    round-off when beta = pi alpha, |z| >> 1 when beta = 2 pi alpha."""
    wf = load_workflow("braid_force_ladder")
    forces = [0.5, 0.8, 1.25, 2.0, 3.0]
    alpha = 6.0
    good = wf.maxwell_table([_synthetic(n, forces, alpha, np.pi * alpha) for n in (2, 2.5, 3)])
    zs = [float(line.split("|")[-2]) for line in good.splitlines() if line.startswith("| 2.5")]
    assert len(zs) == 3 and max(abs(z) for z in zs) < 1e-6, zs
    bad = wf.maxwell_table([_synthetic(n, forces, alpha, 2 * np.pi * alpha)
                            for n in (2, 2.5, 3)])
    zs = [float(line.split("|")[-2]) for line in bad.splitlines() if line.startswith("| 2.5")]
    assert min(abs(z) for z in zs) > 100, zs
