"""The thermal run driver: replicas, workers, packing, the schedule of states, moves,
verdicts and the run's summary, for any scene that keeps :class:`ThermalContract`.

:func:`run` is the whole of a thermal run (OpenMM's ``Simulation`` and MDAnalysis'
``AnalysisBase.run`` are the models: the scene prepares, the driver steps and concludes):

1. build the scene's model once (topology, time step, the notes) and prepare the run
   directory (``scene.toml``; a directory holding the same scene is resumed);
2. group replicas into packs (:func:`dnabraid.run.packing.group_replicas`: copies of one
   System in one Context; one Context per replica when a force cannot be packed) and run
   the packs in worker processes, one pinned core each (:mod:`dnabraid.run.workers`);
   every replica builds its own model from its own seed (:meth:`ThermalContract.replica`),
   its own starts, and writes ``replicas/rNN/points/...``;
3. summarise every point from the replicas' files (:meth:`ThermalContract.point_summary`:
   means, errors across replicas and the convergence verdict), add replicas while a
   precision target is unmet and the budget allows, and write ``summary.json``, the
   combined ``observables.csv``, ``frames.csv``, ``trajectory.dcd``, ``topology.pdb`` and
   the scene's figure.

The driver reads the scene only through the contract and the model only through its typed
fields; the engine (:class:`dnabraid.run.engine.Engine`) gets a System and integrator
settings.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time

import numpy as np

from .. import rundir
from ..observables import columns_of
from . import reporters
from .contract import StartError, ThermalContract
from .engine import Engine, IntegratorSettings, check_platform
from .ladder import judge_ladder, ladder_summary, run_ladder_replica, rung_turns
from .packing import group_replicas, pack_models, packable
from .segments import Member, RunSettings, run_members, start_fingerprint
from .workers import run_jobs, usable_cores

__all__ = ["run", "run_pack", "replica_groups", "packing_notes", "moves_summary",
           "MAX_REPLICAS"]

#: Most replicas per point; replica r of seed s runs seed s x MAX_REPLICAS + r.
MAX_REPLICAS = 64


def replica_groups(scene: ThermalContract, replicas, workers: int, platform: str,
                   model) -> list[tuple]:
    """Replicas grouped into packs (one OpenMM Context each): ``scene.pack`` per group, or
    with ``pack = 0`` as many as spread the replicas evenly over the workers; one per group
    when the model cannot be packed (a force that cannot be copied, unless the model says
    how to rebuild it over all copies, as the chiral term does)."""
    can = packable(model.system, model.rebuild_forces)[0]
    pack = scene.pack
    if pack == 0 and scene.integrator == "mala":
        # Metropolis-adjusted steps accept or reject a whole Context: packed replicas would
        # multiply their acceptances, so by default each runs alone
        pack = 1
    return group_replicas(replicas, pack, workers, platform, can)


def packing_notes(groups) -> list[str]:
    """The summary note saying how replicas were packed (none when each ran alone)."""
    if not any(len(g) > 1 for g in groups):
        return []
    return [f"replicas packed into {len(groups)} OpenMM Context(s) of "
            f"{', '.join(str(len(g)) for g in groups)} non-interacting copies (key `pack`; "
            "each replica keeps its own start, checks and files)"]


def moves_summary(dirs) -> dict | None:
    """Metropolis move counts summed over the replicas' ``moves.json`` of one point, with
    the acceptance of each kind (guard checks summed, the guard's largest disagreement
    kept); None when no replica made moves."""
    tot: dict = {}
    for d in dirs:
        path = os.path.join(d, "moves.json")
        if not os.path.exists(path):
            continue
        with open(path) as fh:
            m = json.load(fh)
        for k, v in m.items():
            if isinstance(v, dict):
                t = tot.setdefault(k, {"attempted": 0, "refused_by_constraint": 0,
                                       "accepted": 0})
                for c in t:
                    t[c] += int(v[c])
            elif k == "guard_checks":
                tot[k] = tot.get(k, 0) + int(v)
            elif k == "guard_max_diff_pN_nm":
                tot[k] = max(tot.get(k, 0.0), float(v))
            else:  # the moves' settings, the same in every replica
                tot[k] = v
    if not tot:
        return None
    for v in tot.values():
        if isinstance(v, dict):
            v["acceptance"] = v["accepted"] / v["attempted"] if v["attempted"] else None
    return tot


#: Below this acceptance of the Metropolis-adjusted steps the summary warns (the chain
#: is still exact; it moves by the Metropolis moves alone).
MALA_LOW_ACCEPTANCE = 0.2


def mala_summary(dirs) -> dict | None:
    """Acceptance of the Metropolis-adjusted Brownian steps (integrator 'mala') of one
    point, summed over the replicas' ``done.json`` (a packed Context's shared steps counted
    once per member); None for the other integrators."""
    acc = tried = 0
    packed = set()
    for d in dirs:
        path = os.path.join(d, "done.json")
        if not os.path.exists(path):
            continue
        with open(path) as fh:
            m = json.load(fh).get("mala")
        if m is None:
            continue
        acc += int(m["accepted"])
        tried += int(m["tried"])
        packed.add(int(m.get("packed", 1)))
    if not tried:
        return None
    return {"accepted": acc, "tried": tried, "acceptance": acc / tried,
            "replicas_per_context": sorted(packed)}


def _settings(scene: ThermalContract, schedule, model) -> RunSettings:
    return RunSettings(report_interval=scene.report_interval,
                       frame_interval=scene.frame_interval,
                       minimise=not model.exact_start,
                       trap_parameter=schedule.trap_parameter, turn_rate=schedule.turn_rate,
                       mirror_axis=scene.mirror_axis)


def _starts(scene: ThermalContract, model, schedule) -> tuple[dict, list[str], list[dict]]:
    """The starts the scene builds for this replica (segment index -> positions or None),
    a note for each that could not be built, and what each segment starts from (its kind
    and a fingerprint of the positions, so that shared starts can be seen)."""
    out, failed, record = {}, [], []
    for seg in schedule:
        if seg.start_from is not None:
            record.append({"kind": f"continues point {seg.start_from}", "fingerprint": None})
            continue
        if not seg.built_start:
            record.append({"kind": "the model's start", "fingerprint":
                           start_fingerprint(model.positions)})
            continue
        try:
            out[seg.index] = scene.start(model, seg)
            record.append({"kind": "built at its state",
                           "fingerprint": start_fingerprint(out[seg.index])})
        except (StartError, ValueError) as exc:
            out[seg.index] = None
            failed.append(f"{seg.tag}: {exc}")
            record.append({"kind": "not built: the model's start, ramped",
                           "fingerprint": start_fingerprint(model.positions)})
    return out, failed, record


def shared_starts(records: list[dict]) -> list[list[int]]:
    """Groups of replicas (indices into ``records``) whose starts are the same."""
    groups: dict = {}
    for i, rec in enumerate(records):
        if rec.get("fingerprint"):
            groups.setdefault(rec["fingerprint"], []).append(i)
    return [g for g in groups.values() if len(g) > 1]


def _engine(scene: ThermalContract, model, platform, threads) -> Engine:
    settings = IntegratorSettings(model.dna.temperature_K, model.timestep.time_step_ns,
                                  scene.integrator, scene.noise_sign)
    return Engine(model.system, model.positions, settings, bonds=model.bonds,
                  bond_length_nm=model.dna.bead_spacing_nm, terms=model.forces,
                  platform=platform, seed=scene.seed, threads=threads)


def run_pack(job, progress=None) -> list[dict]:
    """Run the replicas of one group: alone in its own Context (one replica), or packed
    into one Context; each writes ``out/replicas/rNN``. ``job`` is (scene, replica indices,
    run directory, platform, threads); returns one record per replica."""
    base, group, out, platform, threads = job
    members, scenes, failed, records = [], [], [], []
    schedule = base.states()
    for r in group:
        scene = base.replica(r)
        scenes.append(scene)
        model = scene.build()
        starts, bad, rec = _starts(scene, model, schedule)
        failed.append(bad)
        records.append(rec)
        rdir = os.path.join(out, "replicas", f"r{r:02d}")
        members.append(Member(model, scene.observables(model), rdir, starts,
                              label=f"replica {r}"))
    first = scenes[0]
    settings = _settings(first, schedule, members[0].model)
    if len(group) == 1:
        m = members[0]
        engine = _engine(first, m.model, platform, threads)
        resumed = os.path.isdir(os.path.join(m.out, "checkpoints"))
        os.makedirs(m.out, exist_ok=True)
        dirs = run_members(engine, schedule, [m], settings, m.out, progress=progress)
    else:
        pack = pack_models([m.model for m in members], line=first.pack_along_line)
        engine = _engine(first, pack.model, platform, threads)
        pdir = os.path.join(out, "replicas", f"pack_r{group[0]:02d}-r{group[-1]:02d}")
        resumed = os.path.isdir(os.path.join(pdir, "checkpoints"))
        for m in members:
            os.makedirs(m.out, exist_ok=True)
        dirs = run_members(engine, schedule, members, settings, pdir, pack=pack,
                           progress=progress)
    return [{"replica": r, "dirs": ds, "integrator_seed": engine.seed, "resumed": resumed,
             "pack": tuple(group), "starts_not_built": bad, "starts": rec}
            for r, ds, bad, rec in zip(group, dirs, failed, records)]


def _pack_job(job, report):
    return run_pack(job, report)


def _ladder_job(job, report):
    return run_ladder_replica(job, report)


def run(scene: ThermalContract, out: str, *, platform: str = "CPU", threads: int | None = None,
        progress_factory=None) -> dict:
    """Run a thermal scene into the run directory ``out``; return the summary dict.

    Parameters
    ----------
    scene : ThermalContract
    out : str
    platform : str
        OpenMM platform ('CPU', 'Reference', 'CUDA', 'OpenCL').
    threads : int, optional
        CPU threads of a Context (one per worker when several workers run).
    progress_factory : callable(total_steps) -> bar, optional
        A progress bar with ``update(n)`` and ``close()`` (the CLI's).
    """
    t0 = time.perf_counter()
    check_platform(platform)
    model = scene.build()
    rundir.prepare_out_dir(scene, out)
    sched = scene.states()
    obs = scene.observables(model)
    workers = scene.workers or len(usable_cores())
    results: list = []
    points: list = []
    R = scene.replicas
    stopped_by = "replicas"
    plan = scene.ladder_plan()
    while True:
        # run replicas len(results) .. R-1 (all of them the first time)
        if plan is not None:
            # replica exchange over the trap angle: one independent ladder per replica,
            # moves only, one pinned core each (dnabraid.run.ladder)
            todo = list(range(len(results), R))
            n_rungs = len(rung_turns([seg.turns for seg in sched], plan.per_turn))
            fn, jobs, nw = _ladder_job, [(scene, r, out) for r in todo], max(1, min(workers,
                                                                                    len(todo)))
            work = plan.moves_per_replica(n_rungs) * len(todo)
        else:
            groups = replica_groups(scene, range(len(results), R), workers, platform, model)
            nw = max(1, min(workers, len(groups))) if platform == "CPU" else 1
            fn, jobs = _pack_job, [(scene, g, out, platform, threads if nw == 1 else 1)
                                   for g in groups]
            work = sched.total_steps * (R - len(results))
        bar = progress_factory(work) if progress_factory else None
        try:
            done = run_jobs(fn, jobs, nw, progress=bar.update if bar else None)
            results += done if plan is not None else [x for res in done for x in res]
        finally:
            if bar:
                bar.close()
        columns = columns_of(obs)
        points = []
        for k, seg in enumerate(sched):
            dirs = [r["dirs"][k] for r in results]
            pt = scene.point_summary(seg, [reporters.read_point(d) for d in dirs], columns)
            mv = moves_summary(dirs)
            if mv is not None:
                pt["rigid_moves"] = mv
            ma = mala_summary(dirs)
            if ma is not None:
                pt["mala"] = ma
            _check_starts(pt, [dict(r["starts"][k], replica=r["replica"]) for r in results])
            points.append(pt)
        need = scene.replicas_needed(points, R)
        if need <= R:
            stopped_by = "target" if scene.has_targets() else "replicas"
            break
        if R >= scene.max_replicas:
            stopped_by = "budget"
            break
        R = min(need, scene.max_replicas)
    if plan is not None:
        # a ladder's points share their states: judged together (dnabraid.run.ladder)
        lad = ladder_summary(out, [r["replica"] for r in results])
        judge_ladder(points, lad)
    wall = time.perf_counter() - t0
    resumed = any(r["resumed"] for r in results)
    total = sched.total_steps * R if plan is None else 0
    p = model.params
    dt_ns = model.timestep.time_step_ns
    rundir.write_topology(os.path.join(out, "topology.pdb"), model.topology, model.positions)
    reporters.combine(out, [d for r in results for d in r["dirs"]], model.topology,
                      dt_ns * 1e3, scene.frame_interval, columns_of(obs, "sample"),
                      columns_of(obs, "frame"))
    for pt in points:
        scene.finish_point(pt, stopped_by)
    notes = scene.notes(model)
    if resumed:
        notes.append("resumed from checkpoints; wall_time_s counts this invocation only")
    bad = [pt.get("label", "") for pt in points if not pt["converged"]]
    if bad:
        notes.append(f"NOT CONVERGED at {', '.join(bad)}: the replicas disagree more than "
                     "their sampling allows or sampled too few independent configurations "
                     "(see convergence_reason per point); raise `steps` or `replicas`")
    not_built = [f"replica {r['replica']}: {m}" for r in results
                 for m in r.get("starts_not_built", [])]
    if not_built:
        notes.append("starts that could not be built (those points ramped from the shared "
                     "initial state): " + "; ".join(not_built))
    n_part = model.system.getNumParticles()
    notes += packing_notes(sorted({r["pack"] for r in results}))
    mala = [pt["mala"]["acceptance"] for pt in points if pt.get("mala")]
    if mala:
        notes.append(
            f"Brownian steps Metropolis-adjusted (integrator = mala: Rossky, Doll & Friedman "
            f"1978; no time-step bias): acceptance {min(mala):.2f}-{max(mala):.2f} over the "
            "points" + (" (one accept/reject per packed Context)"
                        if any(len(r["pack"]) > 1 for r in results) else ""))
        if min(mala) < MALA_LOW_ACCEPTANCE:
            notes.append(f"mala acceptance below {MALA_LOW_ACCEPTANCE}: the Brownian steps "
                         "hardly move; lower timestep_safety (or pack = 1)")
    if plan is not None:
        rates = [x for x in lad["swap_acceptance"] if x is not None]
        notes.append(
            f"sampled by replica exchange over the trap angle (sampler = ladder): "
            f"{R} independent ladders of {len(lad['rungs_turns'])} rungs "
            f"(1/{plan.per_turn} turn apart), moves only, no Brownian steps (the step "
            f"column counts moves; no time step applies); swap acceptance "
            + (f"{min(rates):.2f}-{max(rates):.2f}" if rates else "-")
            + f", round trips per ladder {lad['round_trips']}")
    summary = rundir.Summary(
        scene=scene.to_dict(), wall_time_s=wall, platform=platform,
        time_step_ps=dt_ns * 1e3, time_step_reason=model.timestep.reason,
        relaxation_rates_per_ns=model.timestep.rates_per_ns, total_steps=total,
        steps_per_second=total / wall if not resumed and total else None,
        ns_per_bead_per_step=(wall / total / n_part * 1e9 * workers) if not resumed and total
        else None,
        n_particles=n_part, forces=sorted(model.forces),
        effective_diameter_nm=p["diameter_nm"], bending_kappa_kT=p["kappa_kT"],
        units=_units(columns_of(obs)), notes=notes, versions=rundir.versions(),
        points=points, seed=scene.seed, integrator_seed=results[0]["integrator_seed"],
        columns={k: dataclasses.asdict(c) for k, c in columns_of(obs).items()})
    rundir.write_summary(os.path.join(out, "summary.json"), summary)
    d = summary.to_dict()
    scene.plot(d, out)
    return d


def _check_starts(pt: dict, records: list[dict]) -> None:
    """Record each replica's start in the point and fail its verdict when replicas share a
    start (R-hat compares replicas that must have begun apart)."""
    pt["starts"] = records
    shared = shared_starts(records)
    if shared:
        pt["converged"] = False
        why = "; ".join("replicas " + ", ".join(str(records[i]["replica"]) for i in g)
                        + " share a start" for g in shared)
        pt["convergence_reason"] = (why if pt.get("convergence_reason") in (None, "ok")
                                    else f"{pt['convergence_reason']}; {why}")


def _units(columns: dict) -> dict:
    u = {k: c.describe() for k, c in columns.items()}
    u["sem"] = ("standard error of the mean across independent replicas (Student-t "
                "intervals: ci_halfwidth)")
    return u
