"""Observables of a tweezer run: each carries its unit, when it is sampled and its invariant.

An observable is computed from the positions (nm) of one state, in a fixed order, so that
later ones may use earlier values (``values``). ``every`` is ``"sample"`` (each report
interval) or ``"frame"`` (each trajectory frame). An invariant check returns a message
when a conservation law is broken (the strands passed through each other, the bead slipped
in its trap); the runner turns that into :class:`dnabraid.engine.SimulationBlowUp`.
"""

from __future__ import annotations

import abc
import math

import numpy as np

from .geometry.curves import catenation_number
from .geometry.twist import plectoneme_summary, tether_twist, writhe_open

TWO_PI = 2.0 * math.pi

__all__ = ["Observable", "Extension", "BeadAngle", "TrapTorque", "Catenation", "TwistWrithe",
           "TwistTorque", "Plectonemes"]


class Observable(abc.ABC):
    """Base: ``columns`` maps each produced name to its unit and meaning."""

    every = "sample"
    columns: dict = {}

    def reset(self, trap_turns: float, pos) -> None:  # noqa: B027 - optional hook
        """Called when a point starts or resumes (stateful observables re-sync)."""

    @abc.abstractmethod
    def __call__(self, pos, ctx: dict, values: dict) -> dict:
        """Values (name -> float) at positions ``pos`` (nm); ``values`` holds earlier ones."""

    def check(self, values: dict, ctx: dict) -> str | None:
        """A message if an invariant is broken, else None."""
        return None


class Extension(Observable):
    """Height (nm) of the bead attachment points above the surface (their mean)."""

    def __init__(self, attachments):
        self.att = list(attachments)
        self.columns = {"extension_nm": ("nm", "mean height of the bead attachment points")}

    def __call__(self, pos, ctx, values):
        return {"extension_nm": float(np.mean(pos[self.att, 2]))}


class BeadAngle(Observable):
    """The bead's angle about z (turns), unwrapped continuously; it must follow the trap.

    ``pair`` = (p, q): the angle of q - p in the xy plane.
    """

    def __init__(self, pair):
        self.p, self.q = pair
        self._phi = 0.0
        self.columns = {"bead_angle_turns": ("turns", "bead angle, unwrapped")}

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
        lag = values["bead_angle_turns"] - ctx["trap_turns"]
        if abs(lag) > 0.25:
            return (f"the bead slipped in the rotational trap (bead "
                    f"{values['bead_angle_turns']:.3f} turns, trap {ctx['trap_turns']:.3f} turns)"
                    f": the torque exceeded the trap stiffness K = {ctx['trap_stiffness']} pN nm "
                    f"or the turns were ramped too fast (turn_rate = {ctx['turn_rate']}); raise "
                    "trap_stiffness_pN_nm or lower turn_rate")
        return None


class TrapTorque(Observable):
    """Torque the rotational trap applies, -K sin(2 pi (bead - trap)) (pN nm)."""

    def __init__(self, stiffness_pN_nm: float):
        self.K = float(stiffness_pN_nm)
        self.columns = {"torque_pN_nm": ("pN nm", "torque the trap applies; > 0 holds n > 0")}

    def __call__(self, pos, ctx, values):
        lag = TWO_PI * (values["bead_angle_turns"] - ctx["trap_turns"])
        return {"torque_pN_nm": -self.K * math.sin(lag)}


class Catenation(Observable):
    """Gauss catenation of two strands (turns); it must follow the bead angle."""

    every = "frame"

    def __init__(self, chains):
        self.c0, self.c1 = chains
        self.columns = {"catenation": ("turns", "Gauss linking number, strands closed by "
                                                "vertical rays")}

    def __call__(self, pos, ctx, values):
        return {"catenation": catenation_number(pos[self.c0], pos[self.c1])}

    def check(self, values, ctx):
        if abs(values["catenation"] - values["bead_angle_turns"]) > 0.5:
            return (f"catenation {values['catenation']:.3f} no longer follows the bead angle "
                    f"{values['bead_angle_turns']:.3f} turns: the strands passed through each "
                    "other")
        return None


class TwistWrithe(Observable):
    """Tw and Wr of a torsionally constrained tether (turns); Lk = Tw + Wr = bead angle."""

    every = "frame"

    def __init__(self, chain, sides, bead_orientation):
        self.c, self.sides, self.m = chain, sides, bead_orientation
        self.columns = {"twist": ("turns", "Tw, clamps included"),
                        "writhe": ("turns", "Wr, Gauss integral, chain closed by vertical rays")}

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
        self.columns = {"twist_torque_pN_nm": ("pN nm", "2 pi Tw C kT / L")}

    def __call__(self, pos, ctx, values):
        c = self.c
        return {"twist_torque_pN_nm":
                self.f * tether_twist(pos[c], pos[self.sides], pos[self.m] - pos[c[-1]])}


class Plectonemes(Observable):
    """Number of plectonemes, DNA in them (nm) and the longest one's tip (nm of contour)."""

    every = "frame"

    def __init__(self, chain):
        self.c = chain
        self.columns = {"plectonemes": ("", "number per frame"),
                        "plectoneme_length_nm": ("nm", "DNA in plectonemes"),
                        "plectoneme_tip_nm": ("nm", "tip of the longest, contour from surface")}

    def __call__(self, pos, ctx, values):
        pl = plectoneme_summary(pos[self.c])
        return {"plectonemes": float(pl["count"]), "plectoneme_length_nm": pl["length_nm"],
                "plectoneme_tip_nm": pl["tip_nm"]}
