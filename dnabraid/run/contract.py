"""What a thermal scene gives the run driver: the contract, written down once.

:class:`ThermalContract` lists every member :func:`dnabraid.run.driver.run` uses; the
driver reads nothing else of a scene (no ``getattr``). A scene supplies its keys and their
validation (:class:`dnabraid.scenes.base.Scene`), a built System in a typed
:class:`dnabraid.chains.Model`, its observables and the states it samples; the driver owns
replicas, workers and core pinning, packing, the schedule, Metropolis moves between steps,
verdicts and the run's summary. :class:`dnabraid.scenes.thermal.ThermalScene` implements the
contract for every thermal scene with the defaults most scenes need.

Keys every thermal scene declares (frozen dataclass fields): ``seed`` (int), ``replicas``
(int), ``workers`` (int, 0 = one per usable core), ``pack`` (int, replicas per Context, 0 =
auto), ``report_interval`` and ``frame_interval`` (steps), ``integrator`` ('euler' or 'lm').
"""

from __future__ import annotations

import abc

__all__ = ["ThermalContract", "StartError"]


class StartError(ValueError):
    """A scene could not build the start it was asked for (the driver records it)."""


class ThermalContract(abc.ABC):
    """Every member of a thermal scene the run driver uses."""

    # -- keys (declared as dataclass fields by the scene) ------------------------------
    seed: int
    replicas: int
    workers: int
    pack: int
    report_interval: int
    frame_interval: int
    integrator: str

    # -- what the scene is ------------------------------------------------------------
    @abc.abstractmethod
    def build(self):
        """The :class:`dnabraid.chains.Model` of this scene (its replica's own start)."""

    @abc.abstractmethod
    def observables(self, model) -> list:
        """The :class:`dnabraid.observables.Observable` s of a run, in computing order."""

    @abc.abstractmethod
    def states(self):
        """The :class:`dnabraid.run.states.Schedule` of the states this scene samples."""

    @abc.abstractmethod
    def state_of(self, segment) -> dict:
        """The point summary's state keys of ``segment`` (e.g. ``{"turns": 1.0}``)."""

    @abc.abstractmethod
    def replica(self, r: int) -> ThermalContract:
        """The scene of replica ``r`` (its own seed, hence its own start and noise)."""

    @abc.abstractmethod
    def start(self, model, segment):
        """Positions (nm) of the start the scene builds for ``segment`` (segments with
        ``built_start``); raise :class:`StartError` when it cannot be built."""

    # -- how it runs ------------------------------------------------------------------
    @property
    @abc.abstractmethod
    def noise_sign(self) -> tuple | None:
        """Signs of the Brownian noise per axis (None: OpenMM's BrownianIntegrator)."""

    @property
    @abc.abstractmethod
    def mirror_axis(self) -> int | None:
        """For the image of a mirror-coupled pair, the axis of its mirror; else None."""

    @property
    @abc.abstractmethod
    def pack_along_line(self) -> bool:
        """Pack copies along x only (mirror-coupled pairs)."""

    # -- what its results are ---------------------------------------------------------
    @abc.abstractmethod
    def point_summary(self, segment, reps: list, columns: dict) -> dict:
        """The summary of one point from its replicas' (samples, frames) and the
        observables' columns (name -> :class:`dnabraid.observables.Column`)."""

    @abc.abstractmethod
    def notes(self, model) -> list[str]:
        """Notes for the summary (what was left out or reduced, and why)."""

    @abc.abstractmethod
    def has_targets(self) -> bool:
        """Whether the scene sets precision targets (replicas are added until met)."""

    @abc.abstractmethod
    def replicas_needed(self, points: list, replicas: int) -> int:
        """Replicas that would meet the scene's precision targets (``replicas`` when met
        or when there is none)."""

    @property
    @abc.abstractmethod
    def max_replicas(self) -> int:
        """The budget of replicas per point when precision targets are set."""

    @abc.abstractmethod
    def finish_point(self, point: dict, stopped_by: str) -> None:
        """Add what the scene says of a finished point (e.g. its precision verdict)."""

    def ladder_plan(self):
        """A :class:`dnabraid.run.ladder.LadderPlan` (which names the moves it runs) when
        the scene samples its states by replica exchange over the trap angle (moves only,
        no Brownian steps); None (the default) for Brownian dynamics with the scene's moves
        between steps."""
        return None

    @abc.abstractmethod
    def plot(self, summary: dict, out: str) -> None:
        """Write the run's figure(s) into ``out`` (nothing for scenes without one)."""
