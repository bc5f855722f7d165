"""Run a schedule on an engine: ramp, equilibrate, sample; observables and frames streamed.

:func:`run_schedule` executes every :class:`~dnabraid.protocols.Segment` of a schedule.
A segment that follows another loads that segment's checkpoint (positions and the
random-number state); an independent segment gets a fresh Context with its own random
stream (:meth:`Engine.restart`, a hash of the seed and the segment's index) and starts
from the saved initial state. Either way an interrupted run that is started again repeats
exactly what the uninterrupted one did and ends with the same numbers (same platform).
Finished segments are skipped.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import os
import shutil

import numpy as np

from . import reporters, rundir
from .engine import Engine
from .protocols import Segment

log = logging.getLogger(__name__)

TWO_PI = 6.283185307179586

__all__ = ["run_schedule", "point_dir"]


def point_dir(out: str, seg: Segment) -> str:
    return os.path.join(out, "points", seg.tag)


def _observe(observables, pos, ctx, every_frame: bool) -> tuple[dict, str | None]:
    values: dict = {}
    for ob in observables:
        if ob.every == "frame" and not every_frame:
            continue
        values.update(ob(pos, ctx, values))
        msg = ob.check(values, ctx)
        if msg:
            return values, msg
    return values, None


def run_schedule(model, engine: Engine, schedule, observables, out: str, *, ctx: dict,
                 progress=None) -> list[str]:
    """Run (or skip, when finished) every segment; return the point directories in order.

    Parameters
    ----------
    model : dnabraid.chains.Model
    engine : Engine
    schedule : dnabraid.protocols.TurnSchedule
    observables : list of dnabraid.observables.Observable
    out : str
        Run directory.
    ctx : dict
        Context passed to observables (``trap_stiffness``, ``turn_rate``; the runner sets
        ``trap_turns``). ``ctx["trap_parameter"]`` names the trap angle's global parameter
        (None: the scene does not turn the bead). ``ctx["start_positions"]``, a function of
        the turn value returning positions (nm), builds the start of segments that begin at
        their own turn value (``start_from`` None and ``start_turns`` != 0).
    progress : callable(int), optional
        Called with the number of steps just taken.
    """
    progress = progress or (lambda n: None)
    s = model.scene
    ri = s.report_interval
    every = max(1, s.frame_interval // ri)
    ckdir = os.path.join(out, "checkpoints")
    os.makedirs(ckdir, exist_ok=True)
    init = os.path.join(ckdir, "initial.xml")
    if not os.path.exists(init):
        if ctx.get("minimise", True):
            engine.minimise()
        engine.save_state(init)
    sample_cols = {k: v for ob in observables if ob.every == "sample"
                   for k, v in ob.columns.items()}
    frame_cols = {k: v for ob in observables if ob.every == "frame"
                  for k, v in ob.columns.items()}
    trap = ctx.get("trap_parameter")
    dirs = []
    for seg in schedule:
        pdir = point_dir(out, seg)
        dirs.append(pdir)
        done = os.path.join(pdir, "done.json")
        if os.path.exists(done):
            progress(seg.steps)
            log.info("turns=%g loaded from %s", seg.turns, pdir)
            continue
        if seg.start_from is None:
            # an independent start: its own random stream, from the initial state or from a
            # start built at its turn value (made, minimised and saved once)
            engine.restart(seg.index)
            start = init
            if seg.start_turns != 0.0 or getattr(s, "builds_zero_start", False):
                start = os.path.join(ckdir, f"initial_{seg.tag}.xml")
                if not os.path.exists(start):
                    try:
                        built = ctx["start_positions"](seg.start_turns)
                    except ValueError as exc:  # the scene cannot build it: ramp from 0
                        log.info("turns=%g: %s; ramping from 0 instead", seg.turns, exc)
                        built = None
                    engine.load_state(init)
                    axis = getattr(s, "mirror_axis", None)
                    if built is not None and axis is None:
                        engine.set_positions(built)
                        engine.set_parameter(trap, TWO_PI * seg.start_turns)
                        engine.minimise()
                    elif built is not None:
                        # the image of a mirror-coupled pair: minimise in the original's
                        # frame (the minimiser is not mirror-symmetric to round-off), then
                        # mirror, so that without a chiral term the image starts exactly
                        # where the original's mirror does
                        engine.set_positions(_mirrored(built, axis))
                        engine.set_parameter(trap, -TWO_PI * seg.start_turns)
                        engine.minimise()
                        engine.set_positions(_mirrored(engine.positions(), axis))
                        engine.set_parameter(trap, TWO_PI * seg.start_turns)
                    engine.save_state(start)
            engine.load_state(start)
            if seg.start_turns != 0.0 and trap is not None and abs(
                    engine.context.getParameter(trap) - TWO_PI * seg.start_turns) > 1e-9:
                # the start could not be built at the turn value: ramp there from 0
                rate = ctx["turn_rate"]
                ramp = int(math.ceil(abs(seg.turns) / rate / ri)) * ri
                seg = dataclasses.replace(seg, start_turns=0.0, ramp_steps=ramp)
        else:
            engine.load_checkpoint(os.path.join(
                point_dir(out, schedule.segments[seg.start_from]), "state.chk"))
        if os.path.isdir(pdir):
            shutil.rmtree(pdir)  # an interrupted point: run it again from its start
        ctx = dict(ctx, trap_turns=seg.start_turns)
        pos = engine.positions()
        for ob in observables:
            ob.reset(seg.start_turns, pos)
        fail_dir = out
        with reporters.PointWriter(pdir, model.topology, engine.dt_ns * 1e3, s.frame_interval,
                                   sample_cols, frame_cols, seg.turns) as w:
            # 1. ramp the trap angle
            nramp = seg.ramp_steps // ri
            for i in range(1, nramp + 1):
                tt = seg.start_turns + (seg.turns - seg.start_turns) * i / nramp
                engine.set_parameter(trap, TWO_PI * tt)
                pos = engine.advance(ri, fail_dir)
                ctx["trap_turns"] = tt
                _, msg = _observe(observables, pos, ctx, False)
                if msg:
                    engine.blow_up(msg)
                progress(ri)
            if trap is not None:
                engine.set_parameter(trap, TWO_PI * seg.turns)
            ctx["trap_turns"] = seg.turns
            # 2. equilibrate
            left = seg.equilibration_steps
            while left > 0:
                n = min(left, ri)
                pos = engine.advance(n, fail_dir)
                _, msg = _observe(observables, pos, ctx, False)
                if msg:
                    engine.blow_up(msg)
                progress(n)
                left -= n
            # 3. sample
            for i in range(seg.sample_steps // ri):
                pos = engine.advance(ri, fail_dir)
                progress(ri)
                is_frame = (i + 1) % every == 0
                values, msg = _observe(observables, pos, ctx, is_frame)
                if msg:
                    engine.blow_up(msg)
                w.sample(engine.step, values)
                if is_frame:
                    w.frame(engine.step, pos.astype("float32"), values)
        engine.save_checkpoint(os.path.join(pdir, "state.chk"))
        rundir.atomic_write_text(done, json.dumps({"turns": seg.turns, "step": engine.step,
                                                   "frames": w.n_frames}) + "\n")
    return dirs


def _mirrored(pos, axis: int):
    """Positions reflected through the plane normal to ``axis`` (through the origin)."""
    out = np.array(pos, float, copy=True)
    out[:, axis] = -out[:, axis]
    return out
