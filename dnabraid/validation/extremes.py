"""Stiff and extreme cases: run a scene briefly and report whether its invariants held.

Each case of the matrix (:data:`CASES`) names a registered scene and the keys that make it
extreme; it runs with the scene's own short-run settings
(:meth:`~dnabraid.scenes.base.Scene.default_short_run`), the matrix's common settings
(:data:`MATRIX`, where the scene has the key) and then the case's keys. The outcome is
one of

* ``ok``: the run finished and its invariants held. For a thermal (Brownian) scene: finite
  positions and every bond within ``MAX_BOND_STRETCH`` x b (checked every report interval
  by the engine), catenation following the bead (checked on every frame by the
  observables), the mean catenation of each turn value within
  :data:`MAX_CATENATION_ERROR` of it, and a bounded energy at the end of every turn value
  (potential energy per particle below :data:`MAX_ENERGY_PER_BEAD_KT`). For a scene whose
  rows say whether it converged (the zero-temperature knot): converged;
* ``refused``: the scene was rejected at validation with a
  :class:`~dnabraid.scenes.SceneError` whose message names the key and what is allowed;
* ``stopped``: the engine raised :class:`~dnabraid.run.engine.SimulationBlowUp`, naming the step
  and the force term (or the invariant) that failed.

Anything else (an unexpected exception, an invariant broken silently) is a bug and is
reported as ``error``. Every case states the outcome it must have and a part of the
message that outcome must carry (the key of a refusal, the check of a stop).
``workflows/extremes.py`` runs the whole matrix and writes the table;
``tests/test_extremes.py`` runs it.
"""

from __future__ import annotations

import dataclasses
import glob
import logging
import math
import os
import tempfile
import time

import numpy as np

from ..run.engine import SimulationBlowUp
from ..scenes import SceneError, make_scene
from ..scenes.braid import LONG_BRAID

log = logging.getLogger(__name__)

#: A potential energy above this many kT per particle after a turn value means it was not
#: bounded.
MAX_ENERGY_PER_BEAD_KT = 50.0
#: Largest |mean catenation - turns| of a turn value (the bead lags the trap by K-limited
#: fractions of a turn; a strand passage changes the catenation by a whole turn).
MAX_CATENATION_ERROR = 0.05

#: Settings every case starts from, where its scene has the key (the case's keys win):
#: 100 nm of DNA, one replica (the invariants hold per trajectory), run in this process.
#: The turned scenes' short runs keep the default ramp of 5e-5 turns per step (1e-3 tears
#: the default braid's last bond at the bead within ~700 steps; 2e-4 tears 1 nm beads).
MATRIX = {"length_nm": 100.0, "report_interval": 100, "replicas": 1, "workers": 1}
#: Per scene, the defaults the matrix was set up and measured with where they have changed
#: since: the long braid's force and time step (its length is the matrix's 100 nm), and
#: Brownian dynamics alone in the stiff trap (the braid's defaults until 2026-12-05).
SCENE_BASE = {"braid": {**{k: LONG_BRAID[k] for k in ("force_pN", "timestep_safety")},
                        "mc_moves": 0, "trap_stiffness_pN_nm": 2e4}}

OUTCOMES = ("ok", "refused", "stopped", "error")


@dataclasses.dataclass(frozen=True)
class Case:
    """One row of the matrix.

    Attributes
    ----------
    name : str
    scene : str
        A registered scene name (or a scene TOML file).
    overrides : dict
        Flat keys that make the case extreme.
    expect : str
        The outcome the case must have (one of ``ok``, ``refused``, ``stopped``).
    message : str
        A part of the outcome's message the case must carry: for ``refused`` the key and
        value as the scene names them (``force_pN=150.0 pN``), for ``stopped`` the check or
        the force term that failed.
    """

    name: str
    scene: str
    overrides: dict
    expect: str = "ok"
    message: str = "invariants kept"


CASES = [
    Case("force 0.05 pN (floppy)", "braid", {"force_pN": 0.05}),
    Case("force 50 pN (taut)", "braid", {"force_pN": 50.0}),
    Case("force 150 pN (overstretching)", "braid", {"force_pN": 150.0}, "refused",
         "force_pN=150.0 pN: above ~65 pN DNA overstretches"),
    Case("force -1 pN", "braid", {"force_pN": -1.0}, "refused",
         "force_pN=-1.0 pN: the pulling force must be > 0 pN"),
    Case("salt 1 mM, tethers 40 nm", "braid", {"salt_mM": 1.0}, "refused",
         "tether_separation_nm=40.0 nm: must be >= the effective diameter"),
    # 1 turn needs L >= sqrt(2) pi d: 100 nm of DNA at the 1 mM diameter holds < 1 turn
    Case("salt 1 mM, 1 turn past lock-up", "braid", {"salt_mM": 1.0,
                                                      "tether_separation_nm": 60.0}, "refused",
         "turns=(0.0, 1.0) turns: |turns| must be <="),
    Case("salt 1 mM, 400 nm, 1 turn", "braid", {"salt_mM": 1.0, "tether_separation_nm": 60.0,
                                                "length_nm": 400.0, "bead_spacing_nm": 10.0}),
    Case("salt 3 M, spacing 5 nm", "braid", {"salt_mM": 3000.0}, "refused",
         "bead_spacing_nm=5.0 nm: too coarse for the effective DNA diameter"),
    Case("salt 3 M, spacing 2.5 nm", "braid", {"salt_mM": 3000.0, "bead_spacing_nm": 2.5,
                                               "tether_separation_nm": 20.0, "length_nm": 50.0}),
    Case("bead spacing 1 nm", "braid", {"bead_spacing_nm": 1.0, "length_nm": 40.0,
                                        "tether_separation_nm": 10.0}),
    # 0.87 of the lock-up turns: the crushing contact force beats the passage barrier and
    # the strands pass through each other; the run must stop saying so, never go on
    # ramped there (the independent protocol, default since 2026-11-30, builds the braid
    # at its catenation and so never drives the strands through each other on the way)
    Case("4 turns, near lock-up", "braid", {"turns": [0.0, 4.0], "turn_rate": 2e-4,
                                            "tether_separation_nm": 10.0,
                                            "protocol": "ramp"}, "stopped",
         "the strands passed through each other"),
    Case("6 turns, past lock-up", "braid", {"turns": [0.0, 6.0], "tether_separation_nm": 10.0},
         "refused", "turns=(0.0, 6.0) turns: |turns| must be <="),
    Case("turns ramped too fast", "braid", {"turns": [0.0, 3.0], "turn_rate": 1e-2, "protocol": "ramp",
                                            "trap_stiffness_pN_nm": 200.0}, "stopped",
         "the bead slipped in the rotational trap"),
    Case("alpha 20 pN (strongly chiral)", "braid", {"alpha": 20.0, "turns": [-1.0, 1.0]}),
    Case("alpha 100 pN", "braid", {"alpha": 100.0}, "refused",
         "alpha=100.0 pN: |alpha| must be <= 50 pN"),
    Case("tether 10 pN, stiff bonds S=5000 pN", "tether",
         {"force_pN": 10.0, "stretch_modulus_pN": 5000.0}),
    Case("time step at the stability limit", "braid", {"timestep_safety": 0.9}),
    Case("persistence 5 nm = spacing", "tether", {"persistence_nm": 5.0}),
    Case("time step past the stability limit", "braid", {"timestep_safety": 1.5}, "refused",
         "timestep_safety=1.5: must be in (0, 0.9]"),
    Case("knot: trefoil at eps = 0.28", "knot", {"tension_pN": 3.0, "bead_spacing_nm": 1.0}),
    Case("knot: tension 50 pN (eps > 0.55)", "knot", {"tension_pN": 50.0}, "refused",
         "tension_pN=50.0 pN: gives eps = sqrt(h/R) = 0.562 > 0.55"),
    Case("knot: beads coarser than the rod", "knot", {"bead_spacing_nm": 2.0}, "refused",
         "bead_spacing_nm=2.0 nm: must be <= rod_radius_nm=1.0"),
]


def case_settings(case: Case, short: dict | None = None) -> dict:
    """The flat keys a case runs with: the scene's short run, :data:`MATRIX`, ``short``
    (both only where the scene has the key), :data:`SCENE_BASE`, then the case's own
    keys."""
    default = make_scene(case.scene)
    keys = type(default).keys()
    over = dict(default.default_short_run())
    over.update({k: v for k, v in {**MATRIX, **(short or {})}.items() if k in keys})
    over.update(SCENE_BASE.get(default.name, {}))
    over.update(case.overrides)
    return over


def _end_states(model, out: str, scene) -> tuple[float, float]:
    """Largest bond length / b and potential energy per particle (kT) over the states
    saved at the end of every turn value (every replica) of the run in ``out``."""
    from ..run.engine import Engine

    paths = sorted(glob.glob(os.path.join(out, "**", "state.chk"), recursive=True))
    if not paths:
        raise RuntimeError(f"no end-of-point state (state.chk) under {out}")
    engine = Engine.for_model(model, platform="CPU", seed=scene.seed, threads=1)
    kT = model.params["kT_pN_nm"]
    n = model.system.getNumParticles()
    b = scene.bead_spacing_nm
    ratio, energy = 0.0, -math.inf
    for path in paths:
        engine.load_checkpoint(path)
        pos = engine.positions()
        if not np.all(np.isfinite(pos)):
            return math.inf, math.inf
        r = np.linalg.norm(pos[model.bonds[:, 1]] - pos[model.bonds[:, 0]], axis=1)
        ratio = max(ratio, float(r.max() / b))
        energy = max(energy, engine.energy_pN_nm() / kT / n)
    return ratio, energy


def run_case(case: Case, *, short: dict | None = None, workdir: str | None = None) -> dict:
    """Run one case briefly; return its outcome row (see the module docstring).

    Parameters
    ----------
    case : Case
    short : dict, optional
        Extra settings (e.g. ``{"steps": 5000}``), applied where the scene has the key,
        before the case's own keys.
    workdir : str, optional
        Where the run directory goes (default: a temporary directory, removed after).

    Returns
    -------
    dict
        ``case, scene, expect, outcome, detail`` (the message), ``time_step_ps``,
        ``stiffest_term``, ``max_bond_ratio``, ``catenation_error``, ``energy_per_bead_kT``
        (NaN where they do not apply) and ``wall_time_s``.
    """
    row = {"case": case.name, "scene": case.scene, "expect": case.expect, "outcome": None,
           "detail": "", "time_step_ps": math.nan, "stiffest_term": "",
           "max_bond_ratio": math.nan, "catenation_error": math.nan,
           "energy_per_bead_kT": math.nan, "wall_time_s": 0.0}
    t0 = time.perf_counter()
    try:
        scene = make_scene(case.scene, case_settings(case, short))
    except SceneError as exc:
        row.update(outcome="refused", detail=str(exc), wall_time_s=time.perf_counter() - t0)
        return row
    tmp = tempfile.TemporaryDirectory(dir=workdir)
    out = os.path.join(tmp.name, "run")
    try:
        try:
            model = scene.build()
        except SceneError:  # a scene without a Brownian model (the knot relaxes at T = 0)
            model = None
        if model is not None:
            row["time_step_ps"] = model.timestep.time_step_ns * 1e3
            row["stiffest_term"] = model.timestep.stiffest_term
        summary = scene.run(out, platform="CPU", threads=1)
        rows = scene.rows(summary)
        cols = type(scene).row_columns
        problems = []
        if model is not None:
            ratio, e_kT = _end_states(model, out, scene)
            row.update(max_bond_ratio=ratio, energy_per_bead_kT=e_kT)
            if not math.isfinite(e_kT) or e_kT > MAX_ENERGY_PER_BEAD_KT:
                problems.append(f"energy not bounded: {e_kT:.3g} kT per particle "
                                f"(> {MAX_ENERGY_PER_BEAD_KT})")
        if "catenation" in cols and "turns" in cols:
            # rows hold the columns the scene's observables report (a tether has none)
            err = [abs(r["catenation"] - r["turns"]) for r in rows
                   if r.get("catenation") is not None and math.isfinite(r["catenation"])]
            if err:
                row["catenation_error"] = float(max(err))
                if row["catenation_error"] > MAX_CATENATION_ERROR:
                    problems.append(f"mean catenation off the bead turns by "
                                    f"{row['catenation_error']:.3g} turns")
        if "converged" in cols and not all(r["converged"] for r in rows):
            problems.append("not converged")
        if problems:
            row.update(outcome="error", detail="; ".join(problems))
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
