"""Replica exchange over the trap angle (a ladder of trap angles) for a torsionally
constrained tether: moves-only chains at trap angles theta_k, neighbours swapped through a
map that spreads the bead's turn over the frames.

Past buckling the plectoneme's twist-aware moves (:mod:`dnabraid.run.twist_moves`) mix
slowly: contour passes between the tails and the plectoneme (docs/validation.md 2.3l, 2.3m).
Below buckling they mix fast. A ladder of chains at theta_k = theta_0 + k D passes states
mixed at low turns up to high turns (Swendsen & Wang, Phys. Rev. Lett. 57, 2607 (1986);
Hukushima & Nemoto, J. Phys. Soc. Jpn. 65, 1604 (1996), here over the trap angle instead of
the temperature). A bare swap is refused: the trap holds the bead's angle within
sqrt(kT / K) ~ 0.014 rad. The swap is mapped (docs/validation.md 2.3n): chain j (angle
theta_i + D) receives T_D(x_i) and chain i receives T_-D(x_j), where T_D turns the bead's
orientation particle by D about the vertical through the attachment and spins the frame of
bond q about its own bond by D (q + 1/2) / N (N bonds; :func:`swap_map`). Each particle it
moves is turned about an axis fixed by particles it does not move (Jacobian 1) and T_-D
undoes T_D, so Metropolis acceptance of the pair,

    min(1, exp(-[U_j(T_D x_i) - U_i(x_i) + U_i(T_-D x_j) - U_j(x_j)] / kT)),

on the full energy (every term, through the model's :class:`~dnabraid.kernels.LocalEnergy`)
keeps every chain's Boltzmann distribution at its own angle. Chain positions never change
in a swap, so the linking number Tw + Wr of every state equals its rung's turns.

:class:`TrapLadder` holds the rungs' positions, runs rounds (moves on every rung, then swap
attempts between even or odd neighbour pairs, alternating) and counts acceptances and round
trips (a state carried from the lowest rung to the highest and back). For ``dnabraid run``
(:func:`run_ladder_replica`) one replica is one independent ladder from its own start; the
driver judges a ladder run's points together (:func:`judge_ladder`): swaps carry states
between all rungs, so one rung that has not converged biases the others alike in every
ladder (docs/validation.md 2.3o). Replicas fill their ladders from both ends by default
(:func:`ramp_up`, :func:`ramp_down`), so that R-hat across them sees a bias the filling
leaves; the states' walks over the rungs are saved for ``workflows/ladder_walks.py``. Past
buckling a state's rung follows its writhe, which only the moves change, so round trips
are rare on long ladders (docs/validation.md 2.3p).
"""

from __future__ import annotations

import abc
import contextlib
import dataclasses
import json
import math
import os
import shutil
from collections.abc import Callable

import numba
import numpy as np

__all__ = ["swap_map", "ExchangeLadder", "TrapLadder", "ForceLadder", "rung_turns",
           "LadderPlan", "run_ladder_replica", "ladder_summary", "judge_ladder",
           "direction_split", "ramp_up", "ramp_down", "start_direction",
           "LADDER_STARTS", "MIN_ROUND_TRIPS", "MIN_LADDERS_PER_END"]

#: Round trips (a state carried from the lowest rung to the highest and back) every ladder
#: must make before any of its points can be judged converged, unless the ladders were
#: filled from both ends (:data:`MIN_LADDERS_PER_END` each; :func:`judge_ladder`).
MIN_ROUND_TRIPS = 2
#: Ladders filled from each end (``starts = alternate``) that stand in for round trips.
MIN_LADDERS_PER_END = 2
#: The ends a ladder can be filled from (``LadderPlan.starts``): every replica from below,
#: or replicas 0, 2, 4 ... from below and 1, 3, 5 ... from above.
LADDER_STARTS = ("up", "alternate")


@numba.njit(cache=True)
def _swap_map(pos, beads, sides, m, d, out):
    nb = sides.shape[0]
    for i in range(pos.shape[0]):
        for k in range(3):
            out[i, k] = pos[i, k]
    for q in range(nb):
        a = beads[q]
        b = beads[q + 1]
        ax = pos[b, 0] - pos[a, 0]
        ay = pos[b, 1] - pos[a, 1]
        az = pos[b, 2] - pos[a, 2]
        n = math.sqrt(ax * ax + ay * ay + az * az)
        ax /= n
        ay /= n
        az /= n
        ang = d * (q + 0.5) / nb
        c = math.cos(ang)
        s = math.sin(ang)
        p = sides[q]
        vx = pos[p, 0] - pos[a, 0]
        vy = pos[p, 1] - pos[a, 1]
        vz = pos[p, 2] - pos[a, 2]
        dot = ax * vx + ay * vy + az * vz
        cx = ay * vz - az * vy
        cy = az * vx - ax * vz
        cz = ax * vy - ay * vx
        out[p, 0] = pos[a, 0] + vx * c + cx * s + ax * dot * (1.0 - c)
        out[p, 1] = pos[a, 1] + vy * c + cy * s + ay * dot * (1.0 - c)
        out[p, 2] = pos[a, 2] + vz * c + cz * s + az * dot * (1.0 - c)
    if m >= 0:
        t = beads[beads.shape[0] - 1]
        c = math.cos(d)
        s = math.sin(d)
        vx = pos[m, 0] - pos[t, 0]
        vy = pos[m, 1] - pos[t, 1]
        out[m, 0] = pos[t, 0] + vx * c - vy * s
        out[m, 1] = pos[t, 1] + vx * s + vy * c
        out[m, 2] = pos[m, 2]


def swap_map(pos, chain, sides, orientation, d: float) -> np.ndarray:
    """T_d(pos): the bead's orientation particle turned by ``d`` (rad) about the vertical
    through the attachment (the chain's last bead), the side particle of bond q turned about
    its bond by d (q + 1/2) / N; a new array (nm)."""
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    out = np.empty_like(pos)
    _swap_map(pos, np.asarray(chain, np.int64), np.asarray(sides, np.int64),
              -1 if orientation is None else int(orientation), float(d), out)
    return out


def rung_turns(turns, per_turn: int) -> list[float]:
    """The rungs of a ladder through ``turns``: k + 1 rungs evenly spaced from the lowest to
    the highest, k = ceil((highest - lowest) x ``per_turn``) (at most 1 / per_turn turn
    apart); every requested value must sit on a rung (to 1e-9 turn)."""
    if per_turn < 1:
        raise ValueError("per_turn must be >= 1")
    t = sorted(float(x) for x in turns)
    lo, hi = t[0], t[-1]
    k = int(math.ceil((hi - lo) * per_turn - 1e-9))
    grid = [lo + (hi - lo) * i / k for i in range(k + 1)] if k > 0 else [lo]
    for x in t:
        if min(abs(x - g) for g in grid) > 1e-9:
            raise ValueError(f"turns {x:g} is not on the ladder's grid ({k + 1} rungs from "
                             f"{lo:g} to {hi:g}, at most 1/{per_turn} turn apart): choose "
                             "turns on that grid or another ladder_per_turn")
    return grid


class ExchangeLadder(abc.ABC):
    """Replica exchange between rungs of one chain of moves-only samplers: the part shared
    by :class:`TrapLadder` (rungs at trap angles, mapped swaps) and :class:`ForceLadder`
    (rungs at pulling forces, plain swaps). Subclasses say how a rung's energy is set
    (:meth:`set_rung`) and what a swap proposes (:meth:`proposal`).

    A swap of rungs k, k + 1 proposes (y_k, y_k+1) from (x_k, x_k+1) by an involution
    (applied twice it gives the states back) and accepts it with probability

        min(1, J exp(-[U_k(y_k) - U_k(x_k) + U_k+1(y_k+1) - U_k+1(x_k+1)] / kT)),

    J the involution's Jacobian (1 for both ladders here): detailed balance for the
    product of the rungs' Boltzmann distributions. Round trips count a state carried from
    the lowest rung to the highest and back."""

    def __init__(self, moves, n_rungs: int, kT: float, seed: int):
        self.moves = moves
        self.kT = float(kT)
        self.rng = np.random.default_rng([int(seed), 7])
        K = int(n_rungs)
        self.pos: list = [None] * K
        self.who = list(range(K))  # the state id on each rung
        self._up: list = [None] * K  # per state: True once it touched rung 0, False after top
        self.round_trips = 0
        self.tries = np.zeros(max(K - 1, 0), np.int64)
        self.accepted = np.zeros(max(K - 1, 0), np.int64)
        self.refused = np.zeros(max(K - 1, 0), np.int64)  # proposals refused before energy
        self.rounds = 0
        self.trace: list = []  # ``who`` after each round (the states' walks over the rungs)

    @abc.abstractmethod
    def set_rung(self, k: int) -> None:
        """Make the moves' energy rung k's."""

    @abc.abstractmethod
    def proposal(self, k: int):
        """(y_k, y_k+1) proposed from the states on rungs k, k + 1, or None when refused
        (a constraint the states must keep)."""

    def run_rung(self, k: int, n_moves: int) -> None:
        """``n_moves`` moves of rung k at its own energy."""
        self.set_rung(k)
        self.pos[k], _ = self.moves.run(self.pos[k], n_moves)

    def swap(self, k: int) -> bool:
        """One swap attempt between rungs k and k + 1; True when accepted."""
        e = self.moves.energy
        xi, xj = self.pos[k], self.pos[k + 1]
        self.tries[k] += 1
        prop = self.proposal(k)
        if prop is None:
            self.refused[k] += 1
            return False
        yi, yj = prop
        self.set_rung(k)
        du = e.total(yi) - e.total(xi)
        self.set_rung(k + 1)
        du += e.total(yj) - e.total(xj)
        x = du / self.kT
        if x <= 0 or self.rng.random() < math.exp(-x):
            self.accepted[k] += 1
            self.pos[k], self.pos[k + 1] = yi, yj
            self.who[k], self.who[k + 1] = self.who[k + 1], self.who[k]
            return True
        return False

    def round(self, n_moves: int) -> None:
        """Moves on every rung, then swaps of the even (odd on odd rounds) neighbour pairs;
        round trips counted."""
        K = len(self.pos)
        for k in range(K):
            self.run_rung(k, n_moves)
        for k in range(self.rounds % 2, K - 1, 2):
            self.swap(k)
        if K > 1:
            s = self.who[0]
            if self._up[s] is False:
                self.round_trips += 1
            self._up[s] = True
            s = self.who[-1]
            if self._up[s] is True:
                self._up[s] = False
        self.trace.append(tuple(self.who))
        self.rounds += 1

    def acceptance(self) -> list:
        """Swap acceptance of each neighbour pair (None before the first attempt)."""
        return [int(a) / int(t) if t else None for a, t in zip(self.accepted, self.tries)]


class TrapLadder(ExchangeLadder):
    """A ladder of moves-only chains at trap angles 2 pi ``turns`` (rad), neighbours
    swapped through :func:`swap_map` (the bead's turn spread over the frames).

    Parameters
    ----------
    moves : dnabraid.run.twist_moves.PlectonemeMoves
        The moves (and, through ``moves.energy``, the energy) shared by every rung.
    chain, sides, orientation
        The strand's beads, the side particle of each bond and the bead's orientation
        particle.
    turns : sequence of float
        The rungs' trap angles in turns, increasing.
    kT : float
        pN nm.
    seed : int
        Seed of the swaps' acceptance draws.
    """

    def __init__(self, moves, chain, sides, orientation, turns, kT: float, seed: int):
        self.chain = np.asarray(chain, np.int64)
        self.sides = np.asarray(sides, np.int64)
        self.orientation = int(orientation)
        self.turns = [float(x) for x in turns]
        if any(b <= a for a, b in zip(self.turns, self.turns[1:])):
            raise ValueError("ladder turns must increase")
        self.thetas = [2 * math.pi * x for x in self.turns]
        super().__init__(moves, len(self.turns), kT, seed)

    def set_angle(self, theta: float) -> None:
        self.moves.energy.set_trap_angle(theta)

    def set_rung(self, k: int) -> None:
        self.set_angle(self.thetas[k])

    def proposal(self, k: int):
        d = self.thetas[k + 1] - self.thetas[k]
        return (swap_map(self.pos[k + 1], self.chain, self.sides, self.orientation, -d),
                swap_map(self.pos[k], self.chain, self.sides, self.orientation, d))


class ForceLadder(ExchangeLadder):
    """A ladder of moves-only chains at pulling forces ``forces_pN`` (increasing), one trap
    angle for all: parallel tempering in the force (Geyer 1991; Hukushima & Nemoto, J.
    Phys. Soc. Jpn. 65, 1604 (1996), with the force in place of the temperature).

    Every rung holds the same catenation (the trap angle is common and the moves never
    pass a strand through the other), so a swap exchanges the two states unmapped (J = 1)
    and only the pull term changes: -ln(acceptance ratio) = (F_k+1 - F_k)(z_k - z_k+1)
    / kT with z the pulled particles' weighted height. Low (or high) forces, where a
    buckled braid's loops come and go faster, hand their states to the others
    (docs/validation.md 2.3s).

    Parameters
    ----------
    moves : dnabraid.run.chain_moves.BraidMoves (or any moves on a LocalEnergy with a pull)
    forces_pN : sequence of float
        The rungs' forces, increasing, pN.
    trap_angle_rad : float
        The common trap angle (2 pi n).
    kT : float
        pN nm.
    seed : int
    """

    def __init__(self, moves, forces_pN, trap_angle_rad: float, kT: float, seed: int):
        self.forces = [float(f) for f in forces_pN]
        if any(b <= a for a, b in zip(self.forces, self.forces[1:])) or min(self.forces) <= 0:
            raise ValueError("ladder forces must be > 0 and increase")
        self.trap_angle = float(trap_angle_rad)
        moves.energy.set_trap_angle(self.trap_angle)
        super().__init__(moves, len(self.forces), kT, seed)

    def set_rung(self, k: int) -> None:
        self.moves.energy.set_pull_force(self.forces[k])

    def proposal(self, k: int):
        return self.pos[k + 1], self.pos[k]


@dataclasses.dataclass(frozen=True)
class LadderPlan:
    """How a scene's states are sampled by a ladder (one independent ladder per replica).

    Attributes
    ----------
    per_turn : int
        Rungs per turn (D = 2 pi / per_turn); the rungs run from the lowest to the highest
        requested turns, every requested value on a rung.
    round_moves : int
        Moves per rung between swap phases.
    rounds : int
        Sampling rounds (a sample of every requested point after each).
    equilibration_rounds : int
        Rounds with swaps before sampling (after the ramp).
    ramp_moves_per_turn : int
        Moves per turn of the ramp up the ladder (in stages of ``RAMP_STAGE_MOVES``).
    rung_equilibration_moves : int
        Moves at each rung's angle after the ramp reaches it.
    frame_every : int
        Rounds between trajectory frames (and the per-frame observables).
    starts : str
        "alternate": odd replicas fill their ladder from the highest rung down
        (:func:`ramp_down`), even ones from the lowest up; "up": all from below.
    make_moves : callable(model) -> PlectonemeMoves
        The Metropolis moves the ladder runs on a replica's model (the scene's mix and
        amplitudes).
    """

    make_moves: Callable
    per_turn: int
    round_moves: int
    rounds: int
    equilibration_rounds: int
    ramp_moves_per_turn: int
    rung_equilibration_moves: int
    frame_every: int
    starts: str = "alternate"

    def __post_init__(self):
        if self.starts not in LADDER_STARTS:
            raise ValueError(f"starts must be one of {LADDER_STARTS}, not {self.starts!r}")

    def moves_per_replica(self, n_rungs: int) -> int:
        """Moves of one ladder after its ramp (the progress bar's unit)."""
        return (self.rounds + self.equilibration_rounds) * self.round_moves * n_rungs


#: Moves per stage of a ramp (the trap angle changes between stages).
RAMP_STAGE_MOVES = 2000


def _ramp_to(ladder: TrapLadder, pos, now: float, n: float, plan: LadderPlan):
    """Moves at trap angles stepped from ``now`` to ``n`` turns (``plan.ramp_moves_per_turn``
    in stages of :data:`RAMP_STAGE_MOVES`), then ``rung_equilibration_moves`` at ``n``."""
    stages = max(1, int(math.ceil(abs(n - now) * plan.ramp_moves_per_turn
                                  / RAMP_STAGE_MOVES)))
    if n != now:
        for i in range(1, stages + 1):
            ladder.set_angle(2 * math.pi * (now + (n - now) * i / stages))
            pos, _ = ladder.moves.run(pos, RAMP_STAGE_MOVES)
    ladder.set_angle(2 * math.pi * n)
    if plan.rung_equilibration_moves:
        pos, _ = ladder.moves.run(pos, plan.rung_equilibration_moves)
    return pos


def ramp_up(ladder: TrapLadder, start, plan: LadderPlan) -> None:
    """Fill the rungs from below: the start (Lk = 0) ramped from 0 to the lowest rung, then
    from each rung to the next, at ``plan.ramp_moves_per_turn``, with
    ``rung_equilibration_moves`` at each rung's angle; every rung's positions are the
    ramp's state at its angle."""
    pos = np.array(start, np.float64)
    now = 0.0
    for k, n in enumerate(ladder.turns):
        pos = _ramp_to(ladder, pos, now, n, plan)
        ladder.pos[k] = pos.copy()
        now = n


def ramp_down(ladder: TrapLadder, start, plan: LadderPlan) -> None:
    """Fill the rungs from above: the start (Lk = 0) ramped from 0 to the highest rung
    without stopping at the others, then down from each rung to the next, as
    :func:`ramp_up` but the other way. A ramp lags behind the angle (too little writhe on
    the way up, too much on the way down), so ladders filled from both ends start on both
    sides of equilibrium (Gelman & Rubin, Stat. Sci. 7, 457 (1992): overdispersed starts)
    and a bias that the protocol leaves shows as disagreement between them."""
    pos = np.array(start, np.float64)
    now = 0.0
    for k in reversed(range(len(ladder.turns))):
        n = ladder.turns[k]
        pos = _ramp_to(ladder, pos, now, n, plan)
        ladder.pos[k] = pos.copy()
        now = n


def start_direction(plan: LadderPlan, r: int) -> str:
    """"up" or "down": the end replica r's ladder is filled from."""
    return "down" if plan.starts == "alternate" and r % 2 == 1 else "up"


def run_ladder_replica(job, progress=None) -> dict:
    """One replica of a ladder run: ``job`` = (scene, replica index, run directory). The
    replica's own model and start (its seed), one :class:`TrapLadder` through the scene's
    turns, and the requested points written as a thermal run's are
    (``replicas/rNN/points/<tag>/``: samples, frames, trajectory, moves.json, done.json;
    ``replicas/rNN/ladder.json``: rungs, acceptance, round trips, the end it was filled
    from; ``replicas/rNN/ladder_who.npy``: the state on each rung after every round),
    so that the driver summarises and judges them as any other run. The step column counts
    the rung's moves. Returns the driver's per-replica record."""
    from .. import rundir
    from ..observables import ObserveContext, columns_of
    from . import reporters
    from .segments import moves_since, observe_values, point_dir, start_fingerprint

    progress = progress or (lambda n: None)
    base, r, out = job
    scene = base.replica(r)
    plan = scene.ladder_plan()
    model = scene.build()
    segs = list(scene.states())
    rdir = os.path.join(out, "replicas", f"r{r:02d}")
    pdirs = [point_dir(rdir, seg) for seg in segs]
    rungs = rung_turns([seg.turns for seg in segs], plan.per_turn)
    direction = start_direction(plan, r)
    rec = {"kind": f"the replica's own start, ramped {direction} its ladder",
           "fingerprint": start_fingerprint(model.positions)}
    record = {"replica": r, "dirs": pdirs, "integrator_seed": None, "resumed": False,
              "pack": (r,), "starts_not_built": [], "starts": [dict(rec) for _ in segs]}
    lpath = os.path.join(rdir, "ladder.json")
    if all(os.path.exists(os.path.join(p, "done.json")) for p in pdirs) and os.path.exists(
            lpath):
        progress(plan.moves_per_replica(len(rungs)))
        record["resumed"] = True
        return record
    for p in pdirs:  # an interrupted ladder runs again from its start
        if os.path.isdir(p):
            shutil.rmtree(p)
    mv = plan.make_moves(model)
    chain = np.asarray(model.chains[0])
    lad = TrapLadder(mv, chain, model.sides, model.bead_orientation, rungs, model.dna.kT,
                     seed=scene.seed)
    (ramp_down if direction == "down" else ramp_up)(lad, model.positions, plan)
    K = len(rungs)
    step_moves = plan.round_moves * K
    for _ in range(plan.equilibration_rounds):
        lad.round(plan.round_moves)
        progress(step_moves)
    at = [min(range(K), key=lambda k: abs(rungs[k] - seg.turns)) for seg in segs]
    obs = [scene.observables(model) for _ in segs]
    sample_cols = columns_of(obs[0], "sample")
    frame_cols = columns_of(obs[0], "frame")
    ctxs = [ObserveContext(trap_turns=seg.turns) for seg in segs]
    for o, k, seg in zip(obs, at, segs):
        for ob in o:
            ob.reset(seg.turns, lad.pos[k])
    stats0 = mv.summary()
    with contextlib.ExitStack() as stack:
        ws = [stack.enter_context(reporters.PointWriter(
            p, model.topology, 0.0, 1, sample_cols, frame_cols, seg.turns))
            for p, seg in zip(pdirs, segs)]
        for i in range(plan.rounds):
            lad.round(plan.round_moves)
            frame = (i + 1) % plan.frame_every == 0
            for o, k, c, w in zip(obs, at, ctxs, ws):
                pos = lad.pos[k]
                values, msg = observe_values(o, pos, c, frame)
                if msg:
                    raise RuntimeError(f"ladder replica {r}, turns {rungs[k]:g}, round "
                                       f"{lad.rounds}: {msg}")
                step = (i + 1) * plan.round_moves
                w.sample(step, values)
                if frame:
                    w.frame(step, pos.astype("float32"), values)
            progress(step_moves)
    moves = moves_since(mv.summary(), stats0)
    info = {"turns": rungs, "per_turn": plan.per_turn, "round_moves": plan.round_moves,
            "rounds": plan.rounds, "equilibration_rounds": plan.equilibration_rounds,
            "swap_acceptance": lad.acceptance(), "swap_attempts": lad.tries.tolist(),
            "round_trips": lad.round_trips, "start": direction}
    for p, w, seg in zip(pdirs, ws, segs):
        rundir.atomic_write_text(os.path.join(p, "moves.json"), json.dumps(moves) + "\n")
        rundir.atomic_write_text(os.path.join(p, "done.json"), json.dumps(
            {"turns": seg.turns, "step": plan.rounds * plan.round_moves,
             "frames": w.n_frames}) + "\n")
    # the state on each rung after every round (rounds x rungs; the states' walks)
    np.save(os.path.join(rdir, "ladder_who.npy"), np.asarray(lad.trace, np.int16))
    rundir.atomic_write_text(lpath, json.dumps(info) + "\n")
    return record


def ladder_summary(out: str, replicas) -> dict:
    """The ladders' swap acceptance (pooled per neighbour pair), round trips per replica and
    the rungs, from each replica's ``ladder.json``."""
    infos = []
    for r in replicas:
        with open(os.path.join(out, "replicas", f"r{r:02d}", "ladder.json")) as fh:
            infos.append(json.load(fh))
    att = np.sum([i["swap_attempts"] for i in infos], axis=0)
    acc = np.sum([[0 if a is None else a * t for a, t in zip(i["swap_acceptance"],
                                                            i["swap_attempts"])]
                  for i in infos], axis=0)
    rates = [float(a / t) if t else None for a, t in zip(acc, att)]
    return {"rungs_turns": infos[0]["turns"], "per_turn": infos[0]["per_turn"],
            "round_moves": infos[0]["round_moves"], "rounds": infos[0]["rounds"],
            "equilibration_rounds": infos[0]["equilibration_rounds"],
            "swap_acceptance_min": min(x for x in rates if x is not None) if att.size
            else None,
            "swap_acceptance": rates,
            "round_trips": [i["round_trips"] for i in infos],
            "starts": [i.get("start", "up") for i in infos]}


def direction_split(points: list, lad: dict, key: str = "extension_nm") -> None:
    """Per point, the ladders filled from above against those filled from below: the
    difference of their mean ``key`` (down - up) and Welch's t from the replica means
    (added as ``point["ladder_direction"]``; None unless each end has two ladders). A
    diagnostic beside R-hat, which already sees the same spread."""
    starts = lad.get("starts") or []
    up = [i for i, d in enumerate(starts) if d == "up"]
    down = [i for i, d in enumerate(starts) if d == "down"]
    for pt in points:
        obs = pt.get(key) or {}
        means = obs.get("replica_means")
        if len(up) < 2 or len(down) < 2 or not means or len(means) != len(starts):
            pt["ladder_direction"] = None
            continue
        a = np.array([means[i] for i in up], float)
        b = np.array([means[i] for i in down], float)
        se = math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
        diff = float(b.mean() - a.mean())
        pt["ladder_direction"] = {"observable": key, "down_minus_up": diff, "se": se,
                                  "t": diff / se if se > 0 else None,
                                  "ladders_up": len(up), "ladders_down": len(down)}


def judge_ladder(points: list, lad: dict) -> None:
    """Judge a ladder run's points together (adds ``ladder`` to each point). Swaps carry
    states between all rungs, so a rung that has not converged biases the others, and
    independent ladders run by one protocol can share that bias, which R-hat across them
    cannot see (docs/validation.md 2.3o suspected this of the default plectoneme's n = 3;
    2.3p found the same reading in ladders filled from above, so the offset there has
    another cause). A point is converged only if every point of the run is, and either
    every ladder made at least :data:`MIN_ROUND_TRIPS` round trips or the ladders were
    filled from both ends, at least :data:`MIN_LADDERS_PER_END` from each (``starts =
    alternate``): then a bias the filling leaves has opposite signs in the two groups and
    R-hat across them sees it (Gelman & Rubin 1992)."""
    trips = min(lad["round_trips"]) if lad["round_trips"] else 0
    starts = lad.get("starts") or []
    ends = min(starts.count("up"), starts.count("down"))
    direction_split(points, lad)
    bad = [pt.get("label", "") for pt in points if not pt["converged"]]
    why = []
    if bad:
        why.append(f"point(s) {', '.join(bad)} of the same ladders did not converge and the "
                   "swaps carry their states to every rung")
    if trips < MIN_ROUND_TRIPS and ends < MIN_LADDERS_PER_END:
        why.append(f"a ladder made {trips} round trip(s) (< {MIN_ROUND_TRIPS}) and "
                   f"{ends} ladder(s) were filled from the scarcer end (< "
                   f"{MIN_LADDERS_PER_END}): set ladder_starts = alternate with replicas >= "
                   f"{2 * MIN_LADDERS_PER_END}, or raise ladder_rounds")
    for pt in points:
        pt["ladder"] = lad
        if why and pt["converged"]:
            pt["converged"] = False
            pt["convergence_reason"] = "judged with its ladder: " + "; ".join(why)
