"""The states a thermal scene samples, and in which order: schedules only, no sampling.

A :class:`Schedule` is a list of :class:`Segment` s, one per state (point) of a run.
:meth:`Schedule.single` is one equilibrium state (a scene whose state is fixed by its keys,
such as the catenane at its Delta Lk and alpha). :class:`TurnSchedule` is the
magnetic-tweezer turn schedule: the turn values run as two
branches that start from the value nearest zero, upwards through the positive values,
then, starting again from the state saved after the first value, downwards through the
negative ones, so no turn is ramped twice. Each :class:`Segment` says where it starts
(the state after which earlier segment, or the initial state), the turn value it ramps
to, and how many steps it ramps, equilibrates and samples.
"""

from __future__ import annotations

import dataclasses
import math

__all__ = ["Segment", "Schedule", "TurnSchedule", "branches"]


def branches(turns) -> list[list[float]]:
    """Split turn values into an upward branch from the value nearest 0 and a downward one."""
    ts = sorted(float(t) for t in turns)
    start = min(ts, key=lambda t: (abs(t), t))
    up = [t for t in ts if t >= start]
    down = [t for t in reversed(ts) if t < start]
    return [up, down]


@dataclasses.dataclass(frozen=True)
class Segment:
    """One point of a schedule.

    Attributes
    ----------
    index : int
        Position in the schedule (run order).
    start_from : int or None
        Index of the segment whose final state this one starts from (None: initial state).
    start_turns, turns : float
        Trap angle (turns) at the start and the target.
    ramp_steps, equilibration_steps, sample_steps : int
    built_start : bool
        The scene builds this segment's start (at ``start_turns``) instead of the shared
        initial state.
    label : str
        Name of a state that is not a turn value (its point directory's tag).
    """

    index: int
    start_from: int | None
    start_turns: float
    turns: float
    ramp_steps: int
    equilibration_steps: int
    sample_steps: int
    built_start: bool = False
    label: str = ""

    @property
    def steps(self) -> int:
        return self.ramp_steps + self.equilibration_steps + self.sample_steps

    @property
    def tag(self) -> str:
        if self.label:
            return f"{self.index:03d}_{self.label}"
        return f"{self.index:03d}_turns{self.turns:+09.4f}"


class Schedule:
    """The segments of a run, in run order; ``trap_parameter`` names the global parameter a
    segment's turns drive (None: nothing is turned) and ``turn_rate`` its ramp speed."""

    def __init__(self, segments=(), *, trap_parameter: str | None = None,
                 turn_rate: float | None = None):
        self.segments: list[Segment] = list(segments)
        self.trap_parameter = trap_parameter
        self.turn_rate = turn_rate

    @classmethod
    def single(cls, *, equilibration_steps: int, sample_steps: int, report_interval: int,
               label: str = "equilibrium") -> Schedule:
        """One state: equilibrate from the initial state, then sample."""
        ri = int(report_interval)
        return cls([Segment(0, None, 0.0, 0.0, 0, int(equilibration_steps),
                            (int(sample_steps) // ri) * ri, label=label)])

    @property
    def total_steps(self) -> int:
        return sum(s.steps for s in self.segments)

    def __iter__(self):
        return iter(self.segments)

    def __len__(self):
        return len(self.segments)


class TurnSchedule(Schedule):
    """The tweezer schedule of a scene's turn values.

    ``mode = "independent"``: every turn value starts from the initial (equilibrium) state
    and is ramped there from 0, or, with ``built_start``, from a start the scene builds at
    that turn value (no ramp), so points do not depend on each other or on the path;
    ``mode = "ramp"``: the up and down branches described in the module docstring (one
    ramp through all values: hysteresis shows as a difference between branches).

    Parameters
    ----------
    turns : sequence of float
    turn_rate : float or None
        Turns per step of the ramp; None for scenes that do not turn the bead.
    equilibration_steps, sample_steps, report_interval : int
    """

    def __init__(self, turns, *, turn_rate: float | None, equilibration_steps: int,
                 sample_steps: int, report_interval: int, mode: str = "ramp",
                 built_start: bool = False, trap_parameter: str | None = None):
        super().__init__(trap_parameter=trap_parameter, turn_rate=turn_rate)
        ri = int(report_interval)
        if mode == "independent":
            # every turn value from the initial state: no path dependence between points
            for t in sorted(float(x) for x in turns):
                ramp = 0 if turn_rate is None else int(math.ceil(abs(t) / turn_rate))
                ramp = int(math.ceil(ramp / ri)) * ri
                start = 0.0
                if built_start:  # the scene builds the start at the turn value: no ramp
                    start, ramp = t, 0
                self.segments.append(Segment(len(self.segments), None, start, t, ramp,
                                             int(equilibration_steps),
                                             (int(sample_steps) // ri) * ri,
                                             built_start=built_start))
            return
        if mode != "ramp":
            raise ValueError(f"schedule mode must be 'ramp' or 'independent', got {mode!r}")
        brs = branches(turns)
        for k, br in enumerate(brs):
            if not br:
                continue
            prev = None if k == 0 else 0
            cur = 0.0 if k == 0 else brs[0][0]
            for t in br:
                ramp = 0 if turn_rate is None else int(math.ceil(abs(t - cur) / turn_rate))
                ramp = int(math.ceil(ramp / ri)) * ri
                # the first segment starts from a state the scene builds at 0 turns, if it
                # builds starts; the others continue from earlier segments
                seg = Segment(len(self.segments), prev, cur, t, ramp, int(equilibration_steps),
                              (int(sample_steps) // ri) * ri,
                              built_start=built_start and prev is None)
                self.segments.append(seg)
                prev, cur = seg.index, t
