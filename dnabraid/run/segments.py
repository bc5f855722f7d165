"""Run a schedule of states on an engine: ramp, equilibrate, sample; observables and frames
streamed. The run driver (:mod:`dnabraid.run.driver`) calls this; it reads no scene.

:func:`run_members` executes every :class:`~dnabraid.run.states.Segment` of a schedule
for one replica alone in its Context or for R replicas packed into one Context
(:mod:`dnabraid.run.packing`): one engine steps all of them, and every replica keeps its own
start, observables, invariant checks and point directories, exactly as if it ran alone.
A segment that follows another loads that segment's checkpoint (positions and the
random-number state); an independent segment gets a fresh Context with its own random
stream (:meth:`Engine.restart`, a hash of the seed and the segment's index) and starts
from the saved initial state or from the start the scene built for it
(:attr:`Member.starts`). Either way an interrupted run that is started again repeats
exactly what the uninterrupted one did and ends with the same numbers (same platform).
Finished segments are skipped.

A model with ``moves`` (:class:`dnabraid.run.moves.RigidMoves`) gets its Metropolis moves
after every report interval of the ramp, equilibration and sampling (each packed replica in
its own frame); their counts go to ``moves.json`` in each point directory. A ramp also runs
the invariant checks of the per-frame observables (a linking number, a catenation) every
frame interval and at its end, and names its turn rate when one fails: until 2026-12-03 a
ramp ran by Brownian dynamics alone and unchecked, and a 1-um plectoneme turned at 1e-3
turns/step lost one turn of Lk there, reported only after equilibration as a time-step
problem (docs/validation.md 2.3i).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import math
import os
import shutil

import numpy as np

from .. import rundir
from ..observables import ObserveContext, columns_of
from ..units import TWO_PI
from . import reporters
from .engine import Engine
from .moves import apply_moves
from .states import Segment

log = logging.getLogger(__name__)

__all__ = ["run_members", "point_dir", "Member", "RunSettings", "start_fingerprint",
           "observe_values"]


def start_fingerprint(positions) -> str:
    """A short hash of start positions (rounded to 1e-6 nm): equal for equal starts."""
    x = np.round(np.asarray(positions, float), 6) + 0.0  # -0.0 -> 0.0
    return hashlib.sha1(x.tobytes()).hexdigest()[:12]


def point_dir(out: str, seg: Segment) -> str:
    return os.path.join(out, "points", seg.tag)


@dataclasses.dataclass(frozen=True)
class RunSettings:
    """How the segments run, the same for every member of a pack.

    Attributes
    ----------
    report_interval, frame_interval : int
        Steps between observable samples and between trajectory frames.
    minimise : bool
        Minimise the initial state (False for exact equilibrium starts).
    trap_parameter : str or None
        Global parameter of the trap angle (radians); None when nothing is turned.
    turn_rate : float or None
        Turns per step of a ramp from 0 when a built start is missing.
    mirror_axis : int or None
        For the image of a mirror-coupled pair: the axis its start is mirrored along.
    """

    report_interval: int
    frame_interval: int
    minimise: bool = True
    trap_parameter: str | None = None
    turn_rate: float | None = None
    mirror_axis: int | None = None


@dataclasses.dataclass
class Member:
    """One replica of a run: its model, observables, run directory and built starts.

    ``starts`` maps a segment index to the positions (nm) the scene built for it (None: it
    could not be built; the pack then ramps there from 0). ``sl`` and ``offset`` place the
    replica's particles in the engine's positions (the whole array and no offset when it
    runs alone).
    """

    model: object
    observables: list
    out: str
    starts: dict = dataclasses.field(default_factory=dict)
    sl: slice = dataclasses.field(default_factory=lambda: slice(None))
    offset: np.ndarray | float = 0.0
    label: str = ""


def observe_values(observables, pos, ctx, every_frame: bool) -> tuple[dict, str | None]:
    """The observables' values at ``pos`` (per-frame ones only when ``every_frame``) and
    the first broken invariant's message (None when all hold)."""
    values: dict = {}
    for ob in observables:
        if ob.every == "frame" and not every_frame:
            continue
        values.update(ob(pos, ctx, values))
        msg = ob.check(values, ctx)
        if msg:
            return values, msg
    return values, None


def run_members(engine: Engine, schedule, members: list, settings: RunSettings, out: str, *,
                pack=None, progress=None) -> list[list[str]]:
    """Run (or skip, when finished) every segment for ``members``; return each member's
    point directories in order.

    Parameters
    ----------
    engine : Engine
        Runs the member's model alone, or ``pack.model`` for packed members.
    schedule : dnabraid.run.states.Schedule
    members : list of Member
    settings : RunSettings
    out : str
        Directory of this Context's checkpoints (``out/checkpoints``): the replica's own
        run directory when it runs alone, the pack's directory otherwise. Each member writes
        its points under its own ``member.out``.
    pack : dnabraid.run.packing.Pack, optional
        The members' pack (one copy per member, in order).
    progress : callable(int), optional
        Called with the number of replica-steps just taken.
    """
    ckdir = os.path.join(out, "checkpoints")
    if pack is None:
        if len(members) != 1:
            raise ValueError("several members need their pack")
        return _run_members(engine, schedule, members, settings, ckdir,
                            lambda seg: os.path.join(point_dir(members[0].out, seg),
                                                     "state.chk"), progress=progress)
    for r, m in enumerate(members):
        m.sl, m.offset = pack.slice(r), pack.offsets[r]
    return _run_members(engine, schedule, members, settings, ckdir,
                        lambda seg: os.path.join(ckdir, f"{seg.tag}.chk"),
                        progress=progress, check=pack.check_apart)


def _run_members(engine, schedule, members, settings, ckdir, chk_path, *, progress=None,
                 check=None) -> list[list[str]]:
    progress = progress or (lambda n: None)
    m0 = members[0]
    ri = settings.report_interval
    every = max(1, settings.frame_interval // ri)
    os.makedirs(ckdir, exist_ok=True)
    init = os.path.join(ckdir, "initial.xml")
    if not os.path.exists(init):
        if settings.minimise:
            engine.minimise()
        engine.save_state(init)
    obs0 = m0.observables
    sample_cols = columns_of(obs0, "sample")
    frame_cols = columns_of(obs0, "frame")
    trap = settings.trap_parameter
    axis = settings.mirror_axis
    if axis is not None and any(np.broadcast_to(np.asarray(m.offset, float), (3,))[axis]
                                != 0.0 for m in members):
        raise ValueError("mirror-coupled replicas pack only along the other axes "
                         "(dnabraid.run.packing.pack_models(line=True))")
    dirs: list[list[str]] = [[] for _ in members]
    for seg in schedule:
        pdirs = [point_dir(m.out, seg) for m in members]
        for d, p in zip(dirs, pdirs):
            d.append(p)
        if all(os.path.exists(os.path.join(p, "done.json")) for p in pdirs):
            progress(seg.steps * len(members))
            log.info("turns=%g loaded from %s", seg.turns, pdirs[0])
            continue
        if seg.start_from is None:
            # an independent start: its own random stream, from the initial state or from a
            # start built at its turn value (made, minimised and saved once)
            engine.restart(seg.index)
            start = init
            if seg.built_start:
                start = os.path.join(ckdir, f"initial_{seg.tag}.xml")
                if not os.path.exists(start):
                    _build_start(engine, members, seg, init, trap, axis)
                    engine.save_state(start)
            engine.load_state(start)
            if seg.start_turns != 0.0 and trap is not None and abs(
                    engine.context.getParameter(trap) - TWO_PI * seg.start_turns) > 1e-9:
                # the start could not be built at the turn value: ramp there from 0
                rate = settings.turn_rate
                ramp = int(math.ceil(abs(seg.turns) / rate / ri)) * ri
                seg = dataclasses.replace(seg, start_turns=0.0, ramp_steps=ramp)
        else:
            engine.load_checkpoint(chk_path(schedule.segments[seg.start_from]))
        for p in pdirs:
            if os.path.isdir(p):
                shutil.rmtree(p)  # an interrupted point: run it again from its start
        ctxs = [ObserveContext(trap_turns=seg.start_turns) for _ in members]
        split = _splitter(members)
        # Metropolis rigid-body moves (dnabraid.run.moves), where a scene asks for them: after
        # every report interval of equilibration and sampling, on their own random stream
        movers = [m.model.moves for m in members]
        has_moves = any(mv is not None for mv in movers)
        for mv in movers:
            if mv is not None:
                mv.restart(seg.index)
        # the movers' statistics run on over the points; each point records its own share
        moves_before = [mv.summary() if mv is not None else None for mv in movers]
        mala_before = engine.mala_acceptance()

        def advance(n, fail_dir, has_moves=has_moves):
            pos = engine.advance(n, fail_dir)
            if not has_moves:
                return pos
            apply_moves(engine, members)
            return engine.positions()

        for m, p in zip(members, split(engine.positions())):
            for ob in m.observables:
                ob.reset(seg.start_turns, p)
        fail_dir = m0.out if len(members) == 1 else os.path.dirname(ckdir)

        def observe(pos, every_frame, writers=None, advice=None, split=split, ctxs=ctxs):
            parts = split(pos)
            if check is not None:
                check(parts)
            for m, c, p, w in zip(members, ctxs, parts, writers or [None] * len(members)):
                values, msg = observe_values(m.observables, p, c, every_frame)
                if msg:
                    engine.blow_up(msg if len(members) == 1 else f"{m.label}: {msg}",
                                   advice="" if advice and "turn_rate" in msg else advice)
                if w is not None:
                    w.sample(engine.step, values)
                    if every_frame:
                        w.frame(engine.step, p.astype("float32"), values)

        with contextlib.ExitStack() as stack:
            ws = [stack.enter_context(reporters.PointWriter(
                p, m.model.topology, engine.dt_ns * 1e3, settings.frame_interval, sample_cols,
                frame_cols, seg.turns)) for m, p in zip(members, pdirs)]
            # 1. ramp the trap angle, moves included, the per-frame checks every frame
            # interval and at the end
            nramp = seg.ramp_steps // ri
            if nramp:
                rate = abs(seg.turns - seg.start_turns) / (nramp * ri)
                ramp_advice = (f"This happened while the trap turned from {seg.start_turns:g} "
                               f"to {seg.turns:g} turns at {rate:.3g} turns/step: try a "
                               "smaller turn_rate.")
            for i in range(1, nramp + 1):
                tt = seg.start_turns + (seg.turns - seg.start_turns) * i / nramp
                engine.set_parameter(trap, TWO_PI * tt)
                pos = advance(ri, fail_dir)
                for c in ctxs:
                    c.trap_turns = tt
                observe(pos, i % every == 0 or i == nramp, advice=ramp_advice)
                progress(ri * len(members))
            if trap is not None:
                engine.set_parameter(trap, TWO_PI * seg.turns)
            for c in ctxs:
                c.trap_turns = seg.turns
            # 2. equilibrate
            left = seg.equilibration_steps
            while left > 0:
                n = min(left, ri)
                pos = advance(n, fail_dir)
                observe(pos, False)
                progress(n * len(members))
                left -= n
            # 3. sample
            for i in range(seg.sample_steps // ri):
                pos = advance(ri, fail_dir)
                progress(ri * len(members))
                observe(pos, (i + 1) % every == 0, ws)
        engine.save_checkpoint(chk_path(seg))
        for p, mv, b in zip(pdirs, movers, moves_before):
            if mv is not None:
                rundir.atomic_write_text(os.path.join(p, "moves.json"),
                                         json.dumps(moves_since(mv.summary(), b)) + "\n")
        done = {"turns": seg.turns, "step": engine.step}
        mala = engine.mala_acceptance()
        if mala is not None:
            # the Metropolis-adjusted steps of this point (ramp, equilibration, sampling);
            # packed members share them (one accept/reject for the whole Context)
            done["mala"] = {"accepted": mala[0] - mala_before[0],
                            "tried": mala[1] - mala_before[1], "packed": len(members)}
        for p, w in zip(pdirs, ws):
            rundir.atomic_write_text(os.path.join(p, "done.json"), json.dumps(
                dict(done, frames=w.n_frames)) + "\n")
    return dirs


def moves_since(now: dict, before: dict) -> dict:
    """A mover's summary for the moves made since ``before`` (an earlier summary of the same
    mover): per-kind counts and the guard's checks differenced, the acceptance recomputed;
    settings and the guard's largest disagreement as ``now``. A mover runs over all the
    points of its replica, so its summary alone counts every point before this one too
    (until 2026-12-03 the braid's moves.json of turns +3 held the counts of -3 ... +3)."""
    out = dict(now)
    for k, v in now.items():
        b = before.get(k)
        if isinstance(v, dict) and isinstance(b, dict):
            d = {c: int(v[c]) - int(b.get(c, 0)) for c in ("attempted", "refused_by_constraint",
                                                         "accepted") if c in v}
            if "acceptance" in v:
                d["acceptance"] = d["accepted"] / d["attempted"] if d.get("attempted") else None
            out[k] = dict(v, **d)
        elif k == "guard_checks" and b is not None:
            out[k] = int(v) - int(b)
    return out


def _splitter(members):
    """Positions of the engine -> each member's positions in its own frame."""
    if len(members) == 1 and members[0].sl == slice(None):
        return lambda pos: [pos]
    return lambda pos: [pos[m.sl] - m.offset for m in members]


def _build_start(engine, members, seg, init, trap, axis) -> None:
    """Set the engine to the members' built starts at ``seg.start_turns``, minimised.

    When a member's start could not be built (``member.starts`` holds None for this
    segment), every member keeps the initial state (the caller then ramps there from 0:
    one trap angle drives them all).
    """
    built = [m.starts.get(seg.index) for m in members]
    engine.load_state(init)
    if any(b is None for b in built):
        log.info("turns=%g: a member's start could not be built; ramping from 0 instead",
                 seg.turns)
        return
    if axis is None:
        pos = engine.positions()
        for m, b in zip(members, built):
            pos[m.sl] = np.asarray(b, float) + m.offset
        engine.set_positions(pos)
        if trap is not None:
            engine.set_parameter(trap, TWO_PI * seg.start_turns)
        engine.minimise()
    else:
        # the image of a mirror-coupled pair: minimise in the original's frame (the
        # minimiser is not mirror-symmetric to round-off), then mirror, so that without a
        # chiral term the image starts exactly where the original's mirror does. Packed
        # copies sit on the mirror plane's axis (offsets 0 along ``axis``), so mirroring
        # the whole pack mirrors every copy in place.
        pos = engine.positions()
        for m, b in zip(members, built):
            pos[m.sl] = _mirrored(b, axis) + m.offset
        engine.set_positions(pos)
        engine.set_parameter(trap, -TWO_PI * seg.start_turns)
        engine.minimise()
        engine.set_positions(_mirrored(engine.positions(), axis))
        engine.set_parameter(trap, TWO_PI * seg.start_turns)


def _mirrored(pos, axis: int):
    """Positions reflected through the plane normal to ``axis`` (through the origin)."""
    out = np.array(pos, float, copy=True)
    out[:, axis] = -out[:, axis]
    return out
