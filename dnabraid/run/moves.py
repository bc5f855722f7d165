"""Metropolis rigid-body and crankshaft moves interleaved with Brownian dynamics (hybrid
BD/MC).

Some slow modes of a bead model are rigid-body motions of a whole molecule: two linked DNA
minicircles slide through each other only by translating or turning one ring as a whole, and
a ring of length L diffuses as a whole with D = kT / (zeta_l L). For 144-nm rings (zeta_l =
8.4 pN ns / nm^2) that is 3.4e-3 nm^2/ns: crossing the ring's radius (23 nm) takes about R^2
/ (2 x 2 D) = 39 us, 3e6 Brownian steps of 12 ps. Equilibrium averages do not depend on how
a state is reached, so a Metropolis move that translates or turns a whole group of particles
(symmetric proposal; accepted with probability min(1, exp(-dU / kT)); Metropolis et al.
1953) leaves the Boltzmann distribution of the Brownian dynamics unchanged and decorrelates
those modes in tens of moves (workflows/results/benchmark_moves.txt: 48x the contact
length's effective samples per wall second). The moves' time correlations are not physical:
for dynamics, run without them.

Moves (each proposal symmetric, so the Metropolis rule alone gives detailed balance):

* ``shift``: a relative translation of two groups: group a by -d/2, group b by +d/2, d
  uniform in the ball of radius ``shift_nm``; the pair's centroid stays put (a single group,
  as in a lone ring, is shifted by d).
* ``turn``: one group, chosen uniformly, rotated about its own centroid (of its ``pivot``
  particles) by an angle uniform in [-``angle_rad``, ``angle_rad``] about a uniformly random
  axis (R and R^-1 equally likely: symmetric on SO(3)).
* ``arc``: the crankshaft move of ring polymer Monte Carlo (Vologodskii et al. 1992; Klenin
  & Langowski 2000): an arc of 1 ... ``arc_max_beads`` beads of a ring, with the side
  particles of its bonds, turned by an angle uniform in [-``arc_angle_rad``,
  ``arc_angle_rad``] about the line through the two beads that bound it (which stay put, so
  bond lengths are kept). The reverse move is the same arc turned back: symmetric. It
  changes the ring's shape and writhe, whose Brownian relaxation (the ring's slowest bending
  modes, ~1e5 steps for 144-nm rings) is the other slow mode of a minicircle.

A shift or turn changes no internal energy of a group (bonds, bends, twist frames move with
it); a crankshaft changes the bend and twist at its two pivots. dU is taken from the
engine's total potential energy either way. ``allowed(positions, kind)`` is a hard
constraint checked before the energy (for linked rings: the Gauss linking number and each
ring's Tw + Wr are unchanged, so no move passes a strand through another or a joint's twist
through pi); a proposal it refuses is rejected, which keeps detailed balance within the
allowed set (the topological class of the start).

Brownian steps and moves alternate (:func:`dnabraid.run.segments.run_members` calls
:func:`apply_moves` after every report interval of equilibration and sampling). With the
Leimkuhler-Matthews integrator, the previous step's noise is kept across a move; the
single ring's exact twist variance shows no effect at the few-% level (tests).

Random numbers come from ``numpy.random.default_rng`` seeded with (seed, stream), so a
resumed or repeated run makes the same moves.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

__all__ = ["RigidMoves", "axis_rotation", "random_rotation", "MoveStats", "apply_moves"]


def axis_rotation(axis, angle_rad: float) -> np.ndarray:
    """The rotation matrix by ``angle_rad`` about the unit vector ``axis`` (Rodrigues)."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                  [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle_rad) * K + (1.0 - math.cos(angle_rad)) * (K @ K)


def random_rotation(rng: np.random.Generator, max_angle_rad: float) -> np.ndarray:
    """A rotation matrix about a uniformly random axis by an angle uniform in
    [-max_angle_rad, max_angle_rad]."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    return axis_rotation(axis, rng.uniform(-max_angle_rad, max_angle_rad))


def _ball(rng: np.random.Generator, radius: float) -> np.ndarray:
    while True:
        v = rng.uniform(-radius, radius, size=3)
        if v @ v <= radius * radius:
            return v


@dataclasses.dataclass
class MoveStats:
    """Attempted, refused by the constraint, and accepted moves of one kind."""

    attempted: int = 0
    refused: int = 0
    accepted: int = 0

    @property
    def acceptance(self) -> float | None:
        return self.accepted / self.attempted if self.attempted else None

    def to_dict(self) -> dict:
        return {"attempted": self.attempted, "refused_by_constraint": self.refused,
                "accepted": self.accepted, "acceptance": self.acceptance}


class RigidMoves:
    """Metropolis rigid-body moves of particle groups and crankshaft moves of rings (module
    docstring).

    Parameters
    ----------
    groups : list of int arrays
        Particles of each rigid group (indices in the model's own numbering).
    kT_pN_nm : float
    shift_nm : float
        Radius of the relative translation's ball (0: no shifts).
    angle_rad : float
        Largest rotation angle (0: no turns).
    pivots : list of int arrays, optional
        Particles whose centroid is each group's rotation centre (default: the group).
    rings : list of (beads, sides), optional
        Closed chains for crankshaft moves: ``beads`` in ring order, ``sides[i]`` the side
        particle of bond i (beads i -> i + 1), which turns with the arc.
    arc_angle_rad : float
        Largest crankshaft angle (0: no crankshaft moves).
    arc_max_beads : int
        Most beads of a crankshaft arc (default: half a ring less one).
    allowed : callable(positions, kind) -> bool, optional
        Hard constraint on the model's positions (nm) after a move of ``kind`` ('shift',
        'turn' or 'arc').
    moves_per_call : int
        Proposals per call (per replica), cycling through the kinds in use (shift, turn,
        arc).
    seed : int
    """

    def __init__(self, groups, kT_pN_nm: float, *, shift_nm: float, angle_rad: float,
                 pivots=None, allowed: Callable | None = None, moves_per_call: int = 2,
                 seed: int = 1, rings=None, arc_angle_rad: float = 0.0,
                 arc_max_beads: int | None = None):
        if not groups:
            raise ValueError("RigidMoves needs at least one group")
        if min(shift_nm, angle_rad, arc_angle_rad) < 0 or not (
                shift_nm > 0 or angle_rad > 0 or arc_angle_rad > 0):
            raise ValueError("shift_nm, angle_rad and arc_angle_rad must be >= 0, not all 0")
        if angle_rad > math.pi or arc_angle_rad > math.pi:
            raise ValueError("angle_rad and arc_angle_rad must be <= pi")
        if arc_angle_rad > 0 and not rings:
            raise ValueError("crankshaft moves (arc_angle_rad > 0) need rings")
        self.rings = [(np.asarray(b, int), np.asarray(sd, int)) for b, sd in (rings or [])]
        for b, sd in self.rings:
            if len(b) < 4 or len(sd) != len(b):
                raise ValueError("a ring needs >= 4 beads and one side particle per bond")
        self.arc_angle = float(arc_angle_rad)
        nmin = min((len(b) for b, _ in self.rings), default=4)
        self.arc_max = int(arc_max_beads) if arc_max_beads else max(1, nmin // 2 - 1)
        if self.rings and not 1 <= self.arc_max <= nmin - 3:
            raise ValueError(f"arc_max_beads must be in [1, {nmin - 3}]")
        if moves_per_call < 1:
            raise ValueError("moves_per_call must be >= 1")
        self.groups = [np.asarray(g, int) for g in groups]
        self.pivots = [np.asarray(p, int) for p in (pivots or groups)]
        self.kT = float(kT_pN_nm)
        self.shift = float(shift_nm)
        self.angle = float(angle_rad)
        self.allowed = allowed
        self.moves_per_call = int(moves_per_call)
        self.seed = int(seed)
        kinds = ((["shift"] if self.shift > 0 else []) + (["turn"] if self.angle > 0 else [])
                 + (["arc"] if self.arc_angle > 0 else []))
        self.kinds = kinds
        self.stats = {k: MoveStats() for k in kinds}
        self.rng = np.random.default_rng([self.seed, 0])
        self._i = 0

    def restart(self, stream: int) -> None:
        """Random numbers from stream ``stream`` of this seed; statistics kept."""
        self.rng = np.random.default_rng([self.seed, 1 + int(stream)])
        self._i = 0

    def propose(self, pos: np.ndarray) -> tuple[str, np.ndarray]:
        """(kind, new positions) of one proposal from ``pos`` (the model's own, nm)."""
        kind = self.kinds[self._i % len(self.kinds)]
        self._i += 1
        new = np.array(pos, float, copy=True)
        rng = self.rng
        if kind == "shift":
            d = _ball(rng, self.shift)
            if len(self.groups) == 1:
                new[self.groups[0]] += d
            else:
                a, b = rng.choice(len(self.groups), size=2, replace=False)
                new[self.groups[a]] -= 0.5 * d
                new[self.groups[b]] += 0.5 * d
        elif kind == "arc":
            # crankshaft (Vologodskii et al. 1992): beads i+1 ... i+m and the side particles
            # of bonds i ... i+m turn about the axis through beads i and i+m+1, which stay
            beads, sides = self.rings[int(rng.integers(len(self.rings)))]
            n = len(beads)
            i = int(rng.integers(n))
            m = int(rng.integers(1, self.arc_max + 1))
            idx = (i + np.arange(m + 2)) % n
            a, b = pos[beads[idx[0]]], pos[beads[idx[-1]]]
            axis = b - a
            norm = float(np.linalg.norm(axis))
            if norm == 0.0:
                return kind, new
            axis /= norm
            R = axis_rotation(axis, self.arc_angle * (2.0 * rng.uniform() - 1.0))
            moved = np.concatenate([beads[idx[1:-1]], sides[idx[:-1]]])
            new[moved] = (pos[moved] - a) @ R.T + a
        else:
            k = int(rng.integers(len(self.groups)))
            g = self.groups[k]
            c = pos[self.pivots[k]].mean(axis=0)
            R = random_rotation(rng, self.angle)
            new[g] = (pos[g] - c) @ R.T + c
        return kind, new

    def attempt(self, get_pos: Callable, set_pos: Callable, energy: Callable, *,
                parameters: dict | None = None) -> None:
        """``moves_per_call`` Metropolis proposals on one replica.

        ``get_pos()`` / ``set_pos(p)`` read and write the replica's positions (its own
        frame); ``energy()`` is the potential energy (pN nm) of what ``set_pos`` wrote.
        """
        pos = get_pos()
        e0 = None
        for _ in range(self.moves_per_call):
            kind, new = self.propose(pos)
            st = self.stats[kind]
            st.attempted += 1
            u = self.rng.uniform()  # drawn every time: the stream does not depend on refusals
            if self.allowed is not None and not self.allowed(new, kind):
                st.refused += 1
                continue
            if e0 is None:
                e0 = energy()
            set_pos(new)
            e1 = energy()
            if np.isfinite(e1) and (e1 <= e0 or u < math.exp(-(e1 - e0) / self.kT)):
                st.accepted += 1
                pos, e0 = new, e1
            else:
                set_pos(pos)

    def summary(self) -> dict:
        return {"shift_nm": self.shift, "angle_rad": self.angle,
                "arc_angle_rad": self.arc_angle, "arc_max_beads": self.arc_max,
                "moves_per_call": self.moves_per_call,
                **{k: v.to_dict() for k, v in self.stats.items()}}


def apply_moves(engine, members) -> None:
    """One call of every member's ``model.moves`` on a (packed) engine.

    Each member is moved in its own frame (``member.sl``, ``member.offset``); copies in one
    Context do not interact, so the total energy's change is the moved copy's. The
    Leimkuhler-Matthews noise memory is then drawn afresh (:meth:`Engine.forget_noise`).
    """
    moved = False
    for m in members:
        mv = m.model.moves
        if mv is None:
            continue
        state = {"pos": engine.positions()}

        def get_pos(m=m, state=state):
            return state["pos"][m.sl] - m.offset

        def set_pos(p, m=m, state=state):
            full = state["pos"]
            full[m.sl] = np.asarray(p, float) + m.offset
            engine.set_positions(full)

        mv.attempt(get_pos, set_pos, engine.energy_pN_nm, parameters=engine.parameters())
        moved = True
    if moved:  # the integrator's noise memory belongs to the positions before the moves
        engine.forget_noise()
