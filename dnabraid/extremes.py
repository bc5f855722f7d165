"""Stiff and extreme cases: run a scene briefly and report whether its invariants held.

Each case of the matrix (:data:`CASES`) is built and run for a few thousand Brownian steps.
The outcome is one of

* ``ok``: the run finished and its invariants held: finite positions, every bond within
  ``MAX_BOND_STRETCH`` x b (checked every report interval by the engine), catenation equal
  to the bead turns (checked on every frame by the protocol), and a bounded final energy
  (potential energy per bead below :data:`MAX_ENERGY_PER_BEAD_KT`);
* ``refused``: the scene was rejected at validation with a :class:`~dnabraid.scene.SceneError`
  whose message names the key and what is allowed;
* ``stopped``: the engine raised :class:`~dnabraid.engine.SimulationBlowUp`, naming the step
  and the force term (or the check) that failed.

Anything else (an unexpected exception, an invariant broken silently) is a bug and is
reported as ``error``. ``workflows/extremes.py`` runs the whole matrix and writes the table;
``tests/test_extremes.py`` runs it with short runs.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import tempfile
import time

import numpy as np

from .engine import SimulationBlowUp
from .scene import SceneError, make_scene

log = logging.getLogger(__name__)

#: A potential energy above this many kT per bead after a run means it was not bounded.
MAX_ENERGY_PER_BEAD_KT = 50.0

#: Short-run settings shared by all cases (overridable per case).
SHORT = {"steps": 2000, "equilibration_steps": 500, "report_interval": 100,
         "frame_interval": 500, "length_nm": 100.0, "turns": [0.0, 1.0]}


@dataclasses.dataclass(frozen=True)
class Case:
    """One row of the matrix: a name, a base scene and its overrides (flat keys)."""

    name: str
    scene: str
    overrides: dict
    expect: str = "ok"  # the outcome(s) the test accepts, '|'-separated


CASES = [
    Case("force 0.05 pN (floppy)", "braid", {"force_pN": 0.05}),
    Case("force 50 pN (taut)", "braid", {"force_pN": 50.0}),
    Case("force 150 pN (overstretching)", "braid", {"force_pN": 150.0}, "refused"),
    Case("force -1 pN", "braid", {"force_pN": -1.0}, "refused"),
    Case("salt 1 mM, tethers 40 nm", "braid", {"salt_mM": 1.0}, "refused"),
    Case("salt 1 mM, 1 turn past lock-up", "braid", {"salt_mM": 1.0,
                                                      "tether_separation_nm": 60.0}, "refused"),
    Case("salt 1 mM, 400 nm, 1 turn", "braid", {"salt_mM": 1.0, "tether_separation_nm": 60.0,
                                                "length_nm": 400.0, "bead_spacing_nm": 10.0}),
    Case("salt 3 M, spacing 5 nm", "braid", {"salt_mM": 3000.0}, "refused"),
    Case("salt 3 M, spacing 2.5 nm", "braid", {"salt_mM": 3000.0, "bead_spacing_nm": 2.5,
                                               "tether_separation_nm": 20.0, "length_nm": 50.0}),
    Case("bead spacing 1 nm", "braid", {"bead_spacing_nm": 1.0, "length_nm": 40.0,
                                        "tether_separation_nm": 10.0}),
    # 0.87 of the lock-up turns: the crushing contact force can beat the passage barrier;
    # the protocol must then stop with the strand-passage error, never go on silently
    Case("4 turns, near lock-up", "braid", {"turns": [0.0, 4.0], "turn_rate": 2e-4,
                                            "tether_separation_nm": 10.0}, "ok|stopped"),
    Case("6 turns, past lock-up", "braid", {"turns": [0.0, 6.0], "tether_separation_nm": 10.0},
         "refused"),
    Case("turns ramped too fast", "braid", {"turns": [0.0, 3.0], "turn_rate": 1e-2,
                                            "trap_stiffness_pN_nm": 200.0}, "stopped"),
    Case("alpha 20 pN (strongly chiral)", "braid", {"alpha": 20.0, "turns": [-1.0, 1.0]}),
    Case("alpha 100 pN", "braid", {"alpha": 100.0}, "refused"),
    Case("tether 10 pN, stiff bonds S=5000 pN", "tether",
         {"force_pN": 10.0, "stretch_modulus_pN": 5000.0, "turns": [0.0]}),
    Case("time step at the stability limit", "braid", {"timestep_safety": 0.9}),
    Case("persistence 5 nm = spacing", "tether", {"persistence_nm": 5.0, "turns": [0.0]}),
]


def run_case(case: Case, *, short: dict | None = None, workdir: str | None = None) -> dict:
    """Run one case briefly; return its outcome row (see the module docstring).

    Parameters
    ----------
    case : Case
    short : dict, optional
        Short-run settings; default :data:`SHORT` (case overrides win).
    workdir : str, optional
        Where the run directory goes (default: a temporary directory, removed after).
    """
    from .build import build
    from .engine import Engine
    from .protocols import TweezerProtocol

    over = dict(SHORT if short is None else short)
    if case.scene == "tether":
        over.pop("turns", None)
    over.update(case.overrides)
    row = {"case": case.name, "scene": case.scene, "expect": case.expect, "outcome": None,
           "detail": "", "time_step_ps": math.nan, "stiffest_term": "", "max_bond_ratio": math.nan,
           "catenation_error": math.nan, "energy_per_bead_kT": math.nan, "wall_time_s": 0.0}
    t0 = time.perf_counter()
    try:
        scene = make_scene(case.scene, over)
    except SceneError as exc:
        row.update(outcome="refused", detail=str(exc), wall_time_s=time.perf_counter() - t0)
        return row
    tmp = tempfile.TemporaryDirectory(dir=workdir)
    try:
        model = build(scene)
        row["time_step_ps"] = model.params["time_step_ns"] * 1e3
        row["stiffest_term"] = model.params["stiffest_term"]
        engine = Engine(model, platform="CPU", seed=scene.seed, threads=1)
        proto = TweezerProtocol(model, engine, os.path.join(tmp.name, "checkpoints"))
        results = proto.run()
        pos = engine.positions()
        b = scene.bead_spacing_nm
        r = np.linalg.norm(pos[model.bonds[:, 1]] - pos[model.bonds[:, 0]], axis=1)
        row["max_bond_ratio"] = float(r.max() / b)
        cat = [abs(float(np.nanmean(p.catenation)) - p.turns) for p in results
               if p.catenation.size and np.all(np.isfinite(p.catenation))]
        row["catenation_error"] = float(max(cat)) if cat else math.nan
        e_kT = engine.energy_pN_nm() / scene.kT / model.system.getNumParticles()
        row["energy_per_bead_kT"] = float(e_kT)
        if not math.isfinite(e_kT) or e_kT > MAX_ENERGY_PER_BEAD_KT:
            row.update(outcome="error", detail=f"energy not bounded: {e_kT:.3g} kT per bead")
        else:
            row.update(outcome="ok", detail="invariants kept")
    except SimulationBlowUp as exc:
        row.update(outcome="stopped", detail=str(exc))
    except Exception as exc:  # noqa: BLE001 - an unexpected failure is the finding
        row.update(outcome="error", detail=f"{type(exc).__name__}: {exc}")
    finally:
        tmp.cleanup()
    row["wall_time_s"] = time.perf_counter() - t0
    return row


def run_matrix(cases=CASES, *, short: dict | None = None, progress=None) -> list[dict]:
    """Run every case; return the rows in order."""
    rows = []
    for case in cases:
        rows.append(run_case(case, short=short))
        if progress:
            progress(rows[-1])
    return rows
