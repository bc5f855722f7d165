"""Run a scene end to end: build, simulate (resumably), write the run directory."""

from __future__ import annotations

import logging
import os
import sys
import time

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from . import plots, reporters
from .build import build
from .engine import Engine
from .protocols import TweezerProtocol, total_steps
from .scene import Scene, SceneError

log = logging.getLogger(__name__)


def twist_summary(r) -> dict:
    """Mean/SEM of the twist observables of one :class:`~dnabraid.protocols.PointResult`."""
    import numpy as np

    ms = reporters._ms
    lk = r.twist + r.writhe
    tip = r.plectoneme_tip_nm
    return {"twist_torque_pN_nm": ms(r.twist_torque_pN_nm), "twist": ms(r.twist),
            "writhe": ms(r.writhe), "linking": ms(lk),
            "plectonemes": ms(r.plectonemes),
            "plectoneme_length_nm": ms(r.plectoneme_length_nm),
            "plectoneme_fraction": float(np.mean(r.plectonemes > 0)) if r.plectonemes.size
            else None,
            "plectoneme_tip_nm": float(np.nanmedian(tip)) if np.any(np.isfinite(tip))
            else None}


def prepare_out_dir(scene: Scene, out: str) -> bool:
    """Create ``out`` for ``scene``; return True if it resumes an earlier run of the same scene.

    Raises SceneError if ``out`` holds something else (nothing is overwritten).
    """
    path = os.path.join(out, "scene.toml")
    if os.path.isdir(out) and os.listdir(out):
        if not os.path.exists(path):
            raise SceneError(f"output directory {out!r} exists, is not empty and holds no "
                             "scene.toml: choose another --out")
        with open(path, "rb") as fh:
            old = tomllib.load(fh)
        if old != tomllib.loads(scene.to_toml()):
            diff = sorted(k for k in set(old) | set(scene.to_dict())
                          if old.get(k) != tomllib.loads(scene.to_toml()).get(k))
            raise SceneError(f"output directory {out!r} holds a run of a different scene "
                             f"(differs in: {', '.join(diff)}); choose another --out")
        return True
    os.makedirs(out, exist_ok=True)
    reporters.atomic_write_text(path, scene.to_toml())
    return False


def run_scene(scene: Scene, out: str, *, platform: str = "CPU", threads: int | None = None,
              progress_factory=None) -> dict:
    """Simulate ``scene`` into directory ``out`` and return the summary dict.

    Parameters
    ----------
    scene : Scene
    out : str
        Run directory; an existing one of the same scene is resumed.
    platform : str
        OpenMM platform name.
    threads : int, optional
        CPU threads.
    progress_factory : callable(total_steps) -> object with update(n) and close(), optional
        For a progress bar (the CLI passes tqdm).
    """
    if scene.scene == "knot":
        from .knot import run_knot_scene

        return run_knot_scene(scene, out)
    t0 = time.perf_counter()
    model = build(scene)
    engine = Engine(model, platform=platform, seed=scene.seed, threads=threads)
    resumed = prepare_out_dir(scene, out)
    total = total_steps(model)
    bar = progress_factory(total) if progress_factory else None
    proto = TweezerProtocol(model, engine, os.path.join(out, "checkpoints"),
                            progress=bar.update if bar else None)
    try:
        results = proto.run()
    finally:
        if bar:
            bar.close()
    wall = time.perf_counter() - t0
    p = model.params
    dt_ns = p["time_step_ns"]
    reporters.write_topology(os.path.join(out, "topology.pdb"), model.topology, model.positions)
    frames = [fr for r in results for fr in r.frames]
    reporters.write_dcd(os.path.join(out, "trajectory.dcd"), model.topology, frames,
                        dt_ns * 1e3, scene.frame_interval)
    reporters.write_observables(os.path.join(out, "observables.csv"), results, dt_ns)
    n_part = model.system.getNumParticles()
    notes = []
    zeta_bead = p["zeta_center_pN_ns_per_nm"] if scene.n_strands == 2 else p["zeta_attach_pN_ns_per_nm"]
    if zeta_bead < p["zeta_bead_physical_pN_ns_per_nm"]:
        notes.append(
            f"bead friction reduced for sampling: {zeta_bead:.3g} pN ns/nm instead of the "
            f"physical Stokes friction {p['zeta_bead_physical_pN_ns_per_nm']:.3g} pN ns/nm of a "
            f"{scene.bead_radius_nm} nm bead (bead_friction_factor = "
            f"{scene.bead_friction_factor}); equilibrium averages are unaffected, times are "
            "not physical")
    if resumed:
        notes.append("resumed from checkpoints; wall_time_s counts this invocation only")
    summary = {
        "scene": scene.to_dict(),
        "wall_time_s": wall,
        "platform": engine.platform,
        "time_step_ps": dt_ns * 1e3,
        "time_step_reason": p["time_step_reason"],
        "relaxation_rates_per_ns": p["rates_per_ns"],
        "total_steps": total,
        "steps_per_second": total / wall if not resumed else None,
        "ns_per_bead_per_step": (wall / total / n_part * 1e9) if not resumed else None,
        "n_particles": n_part,
        "forces": sorted(model.forces),
        "effective_diameter_nm": p["diameter_nm"],
        "bending_kappa_kT": p["kappa_kT"],
        "units": {"extension": "nm", "torque": "pN nm (torque the trap applies; > 0 holds n > 0)",
                  "catenation": "turns (Gauss linking number, strands closed by vertical rays)",
                  "sem": "standard error of the mean, autocorrelation-corrected (Sokal window)"},
        "notes": notes,
        "versions": reporters.versions(),
        "points": reporters.summarise_points(results),
    }
    if scene.twisted:
        summary["units"].update({
            "twist_torque": "pN nm, 2 pi Tw C kT / L (exact in the mean; less noisy than the "
                            "trap torque)",
            "twist": "turns (Tw, clamps included)",
            "writhe": "turns (Wr, Gauss integral, chain closed by vertical rays)",
            "linking": "turns (Tw + Wr; equals the bead angle while the DNA does not pass "
                       "through itself)",
            "plectonemes": "number per frame; plectoneme_length in nm of DNA; tip in nm of "
                           "contour from the surface (analysis.twist.find_plectonemes)"})
        notes.append("torsionally constrained DNA: side-particle frames, twist persistence "
                     f"{scene.twist_persistence_nm} nm, twist-stretch coupling left out")
        for pt, r in zip(summary["points"], results):
            pt.update(twist_summary(r))
    short = [pt["turns"] for pt in summary["points"]
             if pt["extension_nm"].get("sem_reliable") is False]
    if short:
        notes.append(
            f"sampling at turns {short} spans fewer than {reporters.MIN_N_EFF} correlation times "
            "of the extension: its SEM is a rough estimate (likely too small); raise `steps`")
    reporters.write_summary(os.path.join(out, "summary.json"), summary)
    plots.extension_torque_plot(summary, os.path.join(out, "extension_torque.png"))
    return summary
