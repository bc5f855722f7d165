"""Observables of a thermal run: each declares its columns (unit, meaning, how reported)
once, when it is sampled and its invariant.

An observable is computed from the positions (nm) of one state, in a fixed order, so that
later ones may use earlier values (``values``). ``every`` is ``"sample"`` (each report
interval) or ``"frame"`` (each trajectory frame). An invariant check returns a message
when a conservation law is broken (the strands passed through each other, the bead slipped
in its trap); the run driver turns that into :class:`dnabraid.run.engine.SimulationBlowUp`.

Each produced name has one :class:`Column`: its unit and meaning (the run's CSV headers and
``summary.json``'s ``units``), whether it is a result (``reported``: the printed table, the
sweep rows and the plots read it) and whether its convergence decides a point's verdict.
Adding an observable to a scene is one class here and one line in the scene's
``observables``.
"""

from __future__ import annotations

import abc
import dataclasses
import math

import numpy as np

from .geometry.curves import catenation_number
from .geometry.ribbon import plectoneme_summary, tether_twist, writhe_open
from .units import TWO_PI

__all__ = ["Column", "ObserveContext", "Observable", "Extension", "BeadAngle", "TrapTorque",
           "Catenation", "StrandDistance", "StrandTorque", "SpreadTorque", "TwistWrithe",
           "TwistTorque", "Plectonemes", "columns_of",
           "error_name"]


@dataclasses.dataclass(frozen=True)
class Column:
    """One observable column, declared once.

    Attributes
    ----------
    unit : str
        Its unit ("" for a pure number).
    meaning : str
    reported : bool
        A result: printed in the run's table (mean +- error), written to the sweep rows
        (mean and ``error_name``) and plotted.
    digits : int
        Decimals printed at least (more when the error needs them, at most 4).
    width : int
        Width of its column in the printed table.
    verdict : bool
        Its convergence decides the point's verdict.
    summarised : bool
        The point summary gives its mean and error (False for a check or a quantity the
        scene summarises its own way, e.g. a linking number or an angle that is NaN
        without contact).
    """

    unit: str
    meaning: str
    reported: bool = False
    digits: int = 2
    width: int = 20
    verdict: bool = False
    summarised: bool = True

    def describe(self) -> str:
        """Unit and meaning as ``summary.json`` writes them."""
        return f"{self.unit}: {self.meaning}" if self.unit else self.meaning


def error_name(name: str, unit: str) -> str:
    """Name of a column's standard error in sweep rows: the unit stays last
    (``extension_nm`` -> ``extension_sem_nm``, ``torque_pN_nm`` -> ``torque_sem_pN_nm``,
    ``catenation`` -> ``catenation_sem``)."""
    suffix = "_" + unit.replace(" ", "_") if unit else ""
    if suffix and name.endswith(suffix):
        return name[: -len(suffix)] + "_sem" + suffix
    return name + "_sem"


@dataclasses.dataclass
class ObserveContext:
    """What an observable may know of the run besides the positions: the trap angle now
    (turns; 0 for scenes without a trap)."""

    trap_turns: float = 0.0


class Observable(abc.ABC):
    """Base: ``columns`` maps each produced name to its :class:`Column`."""

    every = "sample"
    columns: dict = {}

    def reset(self, trap_turns: float, pos) -> None:  # noqa: B027 - optional hook
        """Called when a point starts or resumes (stateful observables re-sync)."""

    @abc.abstractmethod
    def __call__(self, pos, ctx: ObserveContext, values: dict) -> dict:
        """Values (name -> float) at positions ``pos`` (nm); ``values`` holds earlier ones."""

    def check(self, values: dict, ctx: ObserveContext) -> str | None:
        """A message if an invariant is broken, else None."""
        return None


def columns_of(observables, every: str | None = None) -> dict:
    """name -> :class:`Column` of ``observables`` (only those sampled ``every``, if given),
    in the order they are computed."""
    return {k: c for ob in observables if every is None or ob.every == every
            for k, c in ob.columns.items()}


class Extension(Observable):
    """Height (nm) of the bead attachment points above the surface (their mean)."""

    def __init__(self, attachments):
        self.att = list(attachments)
        self.columns = {"extension_nm": Column("nm", "mean height of the bead attachment "
                                               "points", reported=True, digits=1,
                                               verdict=True)}

    def __call__(self, pos, ctx, values):
        return {"extension_nm": float(np.mean(pos[self.att, 2]))}


class BeadAngle(Observable):
    """The bead's angle about z (turns), unwrapped continuously; it must follow the trap.

    ``pair`` = (p, q): the angle of q - p in the xy plane.
    """

    def __init__(self, pair, trap_stiffness_pN_nm: float, turn_rate: float):
        self.p, self.q = pair
        self.K = float(trap_stiffness_pN_nm)
        self.rate = float(turn_rate)
        self._phi = 0.0
        self.columns = {"bead_angle_turns": Column("turns", "bead angle, unwrapped")}

    def reset(self, trap_turns, pos):
        self._phi = TWO_PI * trap_turns
        self._update(pos)

    def _update(self, pos):
        u = pos[self.q] - pos[self.p]
        raw = math.atan2(u[1], u[0])
        self._phi += (raw - self._phi + math.pi) % TWO_PI - math.pi
        return self._phi

    def __call__(self, pos, ctx, values):
        return {"bead_angle_turns": self._update(pos) / TWO_PI}

    def check(self, values, ctx):
        lag = values["bead_angle_turns"] - ctx.trap_turns
        if abs(lag) > 0.25:
            return (f"the bead slipped in the rotational trap (bead "
                    f"{values['bead_angle_turns']:.3f} turns, trap {ctx.trap_turns:.3f} turns)"
                    f": the torque exceeded the trap stiffness K = {self.K} pN nm "
                    f"or the turns were ramped too fast (turn_rate = {self.rate}); raise "
                    "trap_stiffness_pN_nm or lower turn_rate")
        return None


class TrapTorque(Observable):
    """Torque the rotational trap applies, -K sin(2 pi (bead - trap)) (pN nm)."""

    def __init__(self, stiffness_pN_nm: float):
        self.K = float(stiffness_pN_nm)
        self.columns = {"torque_pN_nm": Column("pN nm", "torque the trap applies; > 0 holds "
                                               "n > 0", reported=True, digits=1,
                                               verdict=True)}

    def __call__(self, pos, ctx, values):
        lag = TWO_PI * (values["bead_angle_turns"] - ctx.trap_turns)
        return {"torque_pN_nm": -self.K * math.sin(lag)}


class StrandTorque(Observable):
    """Torque about the vertical that everything but the trap exerts on the top (the bead
    centre and the attachments), -dU_rest/d theta, times -1: dU_rest/d theta for a rigid
    turn theta of the top about the vertical through the bead centre (pN nm), by a central
    difference of the compiled local energies (:class:`dnabraid.kernels.LocalEnergy`,
    every term but ``trap``; step 1e-4 rad, error O(1e-8) relative).

    A turn of a subset of particles is volume preserving, so <dU/d theta> = 0 for the total
    energy in equilibrium (integration by parts): the mean of this column equals the mean
    of ``torque_pN_nm`` (the trap's), from forces the trap's libration does not set. Their
    difference has mean zero exactly, a control variate (workflows/torque_estimators.py).
    """

    STEP_RAD = 1e-4

    def __init__(self, model, top):
        from .kernels import LocalEnergy

        self.le = LocalEnergy(model)
        self.top = np.asarray(top, np.int64)
        self.center = int(model.bead_center)
        self.columns = {"torque_strands_pN_nm": Column(
            "pN nm", "dU/d theta of all terms but the trap for a turn of the top about the "
                     "vertical (equal in mean to the trap torque)", digits=1)}

    def _turned(self, pos, th):
        return _turn_about_z(pos, self.top, self.center, th)

    def __call__(self, pos, ctx, values):
        return {"torque_strands_pN_nm": _dU_dtheta(self.le, pos, self.top, self._turned,
                                                   self.STEP_RAD)}


def _turn_about_z(pos, idx, axis, angle):
    """Positions of particles ``idx`` turned by ``angle`` (rad; scalar or one per
    particle) about the vertical through particle ``axis``."""
    c = pos[axis]
    d = pos[idx] - c
    co, si = np.cos(angle), np.sin(angle)
    out = d.copy()
    out[:, 0] = co * d[:, 0] - si * d[:, 1]
    out[:, 1] = si * d[:, 0] + co * d[:, 1]
    return out + c


def _dU_dtheta(le, pos, idx, turned, h):
    """Central difference (step ``h`` rad) of every term but the trap for the map
    ``turned(pos, theta)`` of particles ``idx`` (pN nm per rad)."""
    pos = np.ascontiguousarray(pos, dtype=float)
    up = le.delta_terms(pos, idx, turned(pos, h))
    dn = le.delta_terms(pos, idx, turned(pos, -h))
    return sum(up[t] - dn[t] for t in up if t != "trap") / (2 * h)


class SpreadTorque(Observable):
    """Torque about the vertical on the top from everything but the trap, with the turn
    spread along the strands: dU_rest/d theta when particle i turns by theta w_i about the
    vertical through the ``axis`` particle, w = 1 on the top (bead, attachments, its
    orientation particle), w = s / L on a strand (its contour fraction from the surface;
    side particles of a bond take its midpoint's), 0 on fixed particles (pN nm; central
    difference of the compiled local energies, step 1e-4 rad, every term but ``trap``).

    Why it equals the trap torque in mean: the map turns each particle about a common
    vertical by its own fixed angle, a volume-preserving map (the velocity field w_i
    z x (r_i - c) has zero divergence: w_i does not depend on r_i, and the axis particle
    itself does not move), so <dU/d theta> = 0 for the total energy by integration by
    parts, and the trap's part is the trap torque (the top turns with w = 1). Why it can
    be less noisy than :class:`StrandTorque` (the top turned alone): there the stiff bonds
    at the attachments carry the whole turn; here each bond of N carries 1/N of it, so the
    bonds' independent fluctuations enter with weight 1/N each (bending, contact and, in a
    twisted chain, the frames still contribute). Measured: tests/test_spread_torque.py
    (plectoneme) and docs/validation.md (braid); where the twist torque exists it is far
    less noisy still.
    """

    STEP_RAD = 1e-4

    def __init__(self, model, strands, top, axis: int, sides=None):
        from .kernels import LocalEnergy

        self.le = LocalEnergy(model)
        fixed = {int(i) for i in model.fixed}
        w = {}
        for ch in strands:
            ch = [int(i) for i in ch]
            n = len(ch) - 1
            for k, p in enumerate(ch):
                w[p] = k / n
            if sides is not None:  # one side particle per bond of this strand
                for k, p in enumerate(sides):
                    w[int(p)] = (k + 0.5) / n
        for p in top:
            w[int(p)] = 1.0
        for p in fixed:
            w.pop(p, None)
        self.idx = np.array(sorted(p for p, x in w.items() if x > 0.0), np.int64)
        self.w = np.array([w[int(p)] for p in self.idx])
        self.axis = int(axis)
        self.columns = {"torque_spread_pN_nm": Column(
            "pN nm", "dU/d theta of all terms but the trap for a turn spread along the "
                     "strands (equal in mean to the trap torque, lower variance)", digits=1)}

    def _turned(self, pos, th):
        return _turn_about_z(pos, self.idx, self.axis, th * self.w)

    def __call__(self, pos, ctx, values):
        return {"torque_spread_pN_nm": _dU_dtheta(self.le, pos, self.idx, self._turned,
                                                  self.STEP_RAD)}


class Catenation(Observable):
    """Gauss catenation of two strands (turns); it must follow the bead angle."""

    every = "frame"

    def __init__(self, chains):
        self.c0, self.c1 = chains
        self.columns = {"catenation": Column("turns", "Gauss linking number, strands closed "
                                             "by vertical rays", reported=True, digits=3,
                                             width=18)}

    def __call__(self, pos, ctx, values):
        return {"catenation": catenation_number(pos[self.c0], pos[self.c1])}

    def check(self, values, ctx):
        if abs(values["catenation"] - values["bead_angle_turns"]) > 0.5:
            return (f"catenation {values['catenation']:.3f} no longer follows the bead angle "
                    f"{values['bead_angle_turns']:.3f} turns: the strands passed through each "
                    "other")
        return None


class StrandDistance(Observable):
    """The strands' distance in the ply of a braid, the ply's length and its chiral weight.

    For every segment of strand 1, the closest distance d to any segment of strand 2
    (capsules: :func:`dnabraid.forces.segment_contact.segment_distance`). The ply is the set
    of segments with d < ``ply_factor`` x D_c (D_c the contact distance of ``kernel``; the
    legs splay to the tether separation); columns: its length (the segments' contour), the
    mean of d over it and the mean chiral weight w(d) over it
    (:meth:`dnabraid.forces.reference_chiral.ChiralKernel.weight`, 1 at d <= D_c). The mean
    weight is the factor by which thermal opening scales the contact's alpha (issue
    "Chirality that agrees with its theory", item 4: the continuum x <w>). Without a ply
    (strands apart) d is the closest approach and the weight 0.
    """

    def __init__(self, chains, kernel, ply_factor: float = 2.0):
        c0, c1 = (np.asarray(c, int) for c in chains)
        self.a0, self.a1 = c0[:-1], c0[1:]
        self.b0, self.b1 = c1[:-1], c1[1:]
        self.kernel = kernel
        self.cut = float(ply_factor) * kernel.delta
        self.columns = {
            "ply_length_nm": Column("nm", f"contour of strand 1 closer than {ply_factor:g} D_c "
                                    "to strand 2 (the ply)"),
            "axis_distance_nm": Column("nm", "mean closest distance from strand 1's ply "
                                       "segments to strand 2"),
            "chiral_weight": Column("", "mean chiral weight w(d) over the ply (1 at contact)",
                                    digits=3)}

    def __call__(self, pos, ctx, values):
        from .forces.segment_contact import segment_distance

        d = segment_distance(pos[self.a0][:, None], pos[self.a1][:, None],
                             pos[self.b0][None], pos[self.b1][None])[0].min(axis=1)
        ply = d < self.cut
        if not ply.any():
            return {"ply_length_nm": 0.0, "axis_distance_nm": float(d.min()),
                    "chiral_weight": 0.0}
        w, _ = self.kernel.weight(d[ply])
        lengths = np.linalg.norm(pos[self.a1] - pos[self.a0], axis=1)
        return {"ply_length_nm": float(lengths[ply].sum()),
                "axis_distance_nm": float(d[ply].mean()), "chiral_weight": float(np.mean(w))}


class TwistWrithe(Observable):
    """Tw and Wr of a torsionally constrained tether (turns); Lk = Tw + Wr = bead angle."""

    every = "frame"

    def __init__(self, chain, sides, bead_orientation):
        self.c, self.sides, self.m = chain, sides, bead_orientation
        self.columns = {"twist": Column("turns", "Tw, clamps included"),
                        "writhe": Column("turns", "Wr, Gauss integral, chain closed by "
                                         "vertical rays")}

    def __call__(self, pos, ctx, values):
        c = self.c
        tw = tether_twist(pos[c], pos[self.sides], pos[self.m] - pos[c[-1]])
        return {"twist": tw, "writhe": writhe_open(pos[c])}

    def check(self, values, ctx):
        lk = values["twist"] + values["writhe"]
        if abs(lk - values["bead_angle_turns"]) > 0.5:
            return (f"Tw + Wr = {lk:.3f} no longer equals the bead angle "
                    f"{values['bead_angle_turns']:.3f} turns: the DNA passed through itself (or "
                    "a closing ray) and changed its linking number")
        return None


class TwistTorque(Observable):
    """Torque from the twist, 2 pi Tw C kT / L (pN nm): exact in the mean, far less noisy than
    the trap's -K sin(lag) (each joint's <g omega> equals the torque on the bead)."""

    def __init__(self, chain, sides, bead_orientation, C_nm: float, kT: float, L_nm: float):
        self.c, self.sides, self.m = chain, sides, bead_orientation
        self.f = TWO_PI * C_nm * kT / L_nm
        self.columns = {"twist_torque_pN_nm": Column("pN nm", "2 pi Tw C kT / L")}

    def __call__(self, pos, ctx, values):
        c = self.c
        return {"twist_torque_pN_nm":
                self.f * tether_twist(pos[c], pos[self.sides], pos[self.m] - pos[c[-1]])}


class Plectonemes(Observable):
    """Number of plectonemes, DNA in them (nm) and the longest one's tip (nm of contour)."""

    every = "frame"

    def __init__(self, chain):
        self.c = chain
        self.columns = {"plectonemes": Column("", "number per frame"),
                        "plectoneme_length_nm": Column("nm", "DNA in plectonemes"),
                        "plectoneme_tip_nm": Column("nm", "tip of the longest, contour from "
                                                    "surface")}

    def __call__(self, pos, ctx, values):
        pl = plectoneme_summary(pos[self.c])
        return {"plectonemes": float(pl["count"]), "plectoneme_length_nm": pl["length_nm"],
                "plectoneme_tip_nm": pl["tip_nm"]}
