"""What the magnetic-tweezer scenes (braid, tether, plectoneme) share: keys, checks, build.

A tweezer scene builds DNA strands between a surface and a magnetic bead with the chain
kit (:mod:`dnabraid.chains`), adds its own attachments in :meth:`TweezerScene.attach`,
names its observables and samples its turn values (:class:`dnabraid.run.states.TurnSchedule`);
the run driver (:mod:`dnabraid.run.driver`) does the rest.
"""

from __future__ import annotations

import abc
import dataclasses
import math
import os
from typing import ClassVar

from .. import forcefield
from ..chains import (
    ChainKit,
    Model,
)
from ..run.driver import MAX_REPLICAS
from ..run.engine import MAX_SEED
from ..run.states import TurnSchedule
from .base import key, resolve_salt_alpha
from .thermal import ThermalScene

#: Largest number of DNA beads a tweezer scene may have (memory and time stay sane).
MAX_BEADS = 20000
#: Two-sided p-value below which the torque identity <spread torque> = <trap torque> counts
#: as violated (Student t on the replicas' paired differences): one false alarm in 1000
#: points.
IDENTITY_P = 1e-3


#: Help of the ``pack`` key (tweezer scenes and the catenane).
PACK_HELP = ("replicas packed into one OpenMM Context (one System of non-interacting copies, "
             "dnabraid.run.packing; the chiral term is built over all copies, mirror pairs pack "
             "along x). 2 x 60 nm braid: 1.8x faster at 2, 2.9x at 4, 4.2x at 8 "
             "(workflows/results/benchmark_replicas_small.txt). 0 = replicas / workers "
             "(1 with integrator = mala, whose accept/reject is per Context), 1 = off")


def _default_turns():
    return (-4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0)


_MECH = forcefield.mechanics()


@dataclasses.dataclass(frozen=True)
class TweezerScene(ThermalScene):
    """Keys every tweezer scene has (all lengths nm, forces pN, energies pN nm)."""

    force_pN: float = key(2.0, "pN", "constant force pulling the magnetic bead up (> 0)")
    turns: tuple = key((0.0,), "turns", "list of bead turn values n")
    salt_mM: float = key(150.0, "mM", "monovalent salt; sets the effective DNA diameter "
                         "(Stigter 1977)")
    length_nm: float = key(200.0, "nm", "contour length of each DNA molecule")
    bead_spacing_nm: float = key(5.0, "nm", "distance b between beads along a strand")
    persistence_nm: float = key(float(_MECH["persistence_nm"]), "nm",
                                "bending persistence length (forcefields/dna.toml)")
    temperature_K: float = key(298.15, "K", "temperature")
    steps: int = key(180000, "steps", "sampling steps per turn value (after equilibration)")
    equilibration_steps: int = key(40000, "steps", "equilibration steps after each change "
                                   "of turns")
    seed: int = key(1, "", f"random seed of the Brownian integrator (0 ... {MAX_SEED})")
    diameter_nm: float = key(0.0, "nm", "effective DNA diameter; 0 = from salt (Stigter 1977)")
    stretch_modulus_pN: float = key(float(_MECH["stretch_modulus_pN"]), "pN",
                                    "stretch modulus S of the double helix (bond stiffness "
                                    "S/b; forcefields/dna.toml)")
    stretch: str = key("bonds", "", "'bonds' (harmonic springs) or 'constraints' (rigid bonds)")
    bead_radius_nm: float = key(500.0, "nm", "radius of the magnetic bead (sets its physical "
                                "friction)")
    bead_friction_factor: float = key(0.01, "", "bead friction used / physical Stokes "
                                      "friction (<1 speeds sampling)")
    report_interval: int = key(100, "steps", "steps between observable samples")
    frame_interval: int = key(5000, "steps", "steps between trajectory frames (multiple of "
                              "report_interval)")
    surface: bool = key(True, "", "true: a wall at z = 0 keeps DNA above the surface")
    timestep_safety: float = key(0.3, "", "time step = safety x 2 / (mobility x largest "
                                 "stiffness)")
    alpha: float = key(0.0, "pN", "chiral strength alpha of phi = alpha tan(eta/2) (energy per "
                       "contact length, pN = pN nm/nm; 1 kT/nm = 4.11 pN); 0 = no chiral term; "
                       "'salt' = the estimate at salt_mM from forcefields/chiral.toml; > 0 "
                       "favours right-handed braids (n > 0)")

    replicas: int = key(4, "", "independent replicas per turn value, each from its own start "
                        "(seed); the error bar is the scatter of their means (Student t)")
    protocol: str = key("independent", "", "'independent': every turn value starts from the "
                        "initial state (ramped there from 0), no path dependence; 'ramp': up "
                        "and down branches through the turn values (hysteresis)")
    workers: int = key(0, "", "processes running replicas at once; 0 = one per usable core")
    target_sem_nm: float = key(0.0, "nm", "target standard error of each point's extension; "
                               "0 = none. Replicas are added (up to max_replicas) until met")
    target_sem_pN_nm: float = key(0.0, "pN nm", "target standard error of each point's trap "
                                  "torque; 0 = none")
    max_replicas: int = key(16, "", "budget: most replicas per point when a target is set")
    pack: int = key(0, "", PACK_HELP)
    integrator: str = key("euler", "", "'euler': Euler-Maruyama (OpenMM BrownianIntegrator); "
                          "'lm': Leimkuhler-Matthews, same cost per step, smaller time-step "
                          "bias (workflows/results/integrator_bias.md); 'mala': each "
                          "Euler-Maruyama step accepted by Metropolis on the total energy (Rossky, Doll & Friedman "
                          "1978): no time-step bias at any step, about twice the cost per "
                          "step; acceptance in summary.json (lower timestep_safety to raise it)")

    #: The trap's global parameter (None: the bead is not turned).
    trap_parameter: ClassVar[str | None] = None

    # -- derived -----------------------------------------------------------------------
    @property
    def n_beads(self) -> int:
        """Beads per strand (both ends included)."""
        return int(round(self.length_nm / self.bead_spacing_nm)) + 1

    # -- keys ----------------------------------------------------------------------------
    @classmethod
    def resolve(cls, values: dict) -> dict:
        return resolve_salt_alpha(values, cls.salt_mM)

    #: True when the strands must not pass through each other whatever their length.
    needs_passage_barrier: ClassVar[bool] = False
    #: DNA molecules between surface and bead (1: tether, plectoneme; 2: braid).
    strands: ClassVar[int] = 1
    #: True when the DNA is torsionally constrained (twist frames; the plectoneme).
    torsionally_constrained: ClassVar[bool] = False

    def validate(self) -> None:
        need = self.need
        need(self.force_pN > 0, "force_pN", "the pulling force must be > 0 pN")
        need(self.force_pN <= 100, "force_pN",
             "above ~65 pN DNA overstretches; this model allows <= 100 pN")
        need(self.salt_mM > 0, "salt_mM", "salt must be > 0 mM")
        need(self.salt_mM <= 5000, "salt_mM", "salt must be <= 5000 mM")
        need(self.length_nm > 0, "length_nm", "must be > 0")
        need(self.bead_spacing_nm > 0, "bead_spacing_nm", "must be > 0")
        need(self.n_beads >= 3, "length_nm", f"gives only {self.n_beads} beads; need >= 3 "
             "(length >= 2 x bead_spacing_nm)")
        need(self.n_beads <= MAX_BEADS, "length_nm",
             f"gives {self.n_beads} beads per strand (> {MAX_BEADS}): too large to simulate; "
             "shorten the DNA or coarsen bead_spacing_nm")
        need(abs(self.n_beads - 1 - self.length_nm / self.bead_spacing_nm) < 1e-6, "length_nm",
             f"must be a whole multiple of bead_spacing_nm={self.bead_spacing_nm}")
        need(self.persistence_nm > 0, "persistence_nm", "must be > 0")
        need(self.persistence_nm >= self.bead_spacing_nm, "persistence_nm",
             "must be >= bead_spacing_nm (a bead chain cannot resolve a shorter persistence)")
        need(150 <= self.temperature_K <= 400, "temperature_K", "must be between 150 and 400 K")
        need(self.diameter_nm >= 0, "diameter_nm", "must be >= 0 (0 = from salt)")
        need(self.stretch_modulus_pN > 10 * self.force_pN, "stretch_modulus_pN",
             "must be much larger than the force (> 10 x force_pN)")
        need(self.stretch in ("bonds", "constraints"), "stretch",
             "allowed: 'bonds', 'constraints'")
        need(self.bead_radius_nm > 0, "bead_radius_nm", "must be > 0")
        need(0 < self.bead_friction_factor <= 1, "bead_friction_factor", "must be in (0, 1]")
        need(self.protocol in ("independent", "ramp"), "protocol",
             "allowed: 'independent', 'ramp'")
        need(self.target_sem_nm >= 0, "target_sem_nm", "must be >= 0 (0 = no target)")
        need(self.target_sem_pN_nm >= 0, "target_sem_pN_nm", "must be >= 0 (0 = no target)")
        need(self.replicas <= self.max_replicas <= MAX_REPLICAS, "max_replicas",
             f"must be in [replicas={self.replicas}, {MAX_REPLICAS}]")
        need(abs(self.alpha) <= 50.0, "alpha",
             "|alpha| must be <= 50 pN (~12 kT/nm; literature estimates are 0.01-1.5 pN, "
             "forcefields/chiral.toml)")
        self.check_run_keys()
        if self.needs_passage_barrier or self.length_nm > 3 * self.persistence_nm:
            self.check_passage_barrier()

    # -- build ---------------------------------------------------------------------------
    def build(self) -> Model:
        """The OpenMM model: DNA from the chain kit, then this scene's attachments."""
        kit = ChainKit(self.dna())
        params = self.attach(kit)
        if self.alpha != 0.0:
            # Kornyshev chiral term between facing segments (docs/chirality.md); left out at
            # alpha = 0. It is a PythonForce, which cannot be copied: packed replicas
            # (dnabraid.run.packing) build one over every copy's strands instead.
            kit.add_chiral(self.alpha, kit.chains)
        params["alpha_pN"] = self.alpha
        return kit.finish(safety=self.timestep_safety, params=params,
                          length_nm=self.length_nm, force_pN=self.force_pN)

    @abc.abstractmethod
    def attach(self, kit: ChainKit) -> dict:
        """Add strands and attachments to ``kit`` (setting ``kit.attachments`` and, where
        they exist, ``kit.sides``, ``kit.bead_orientation``, ``kit.bead_center``,
        ``kit.exact_start``); return the numbers to record in the model's params."""

    @abc.abstractmethod
    def observables(self, model: Model) -> list:
        """The observables of a run, in the order they are computed."""

    def states(self) -> TurnSchedule:
        """The turn values, ramped by the trap (turned scenes) or held (the tether)."""
        return TurnSchedule(self.turns, turn_rate=self.turn_rate_or_none,
                            equilibration_steps=self.equilibration_steps,
                            sample_steps=self.steps, report_interval=self.report_interval,
                            mode=self.protocol, built_start=self.builds_turned_start,
                            trap_parameter=self.trap_parameter)

    #: True when :meth:`start` builds a start at every turn value.
    builds_turned_start: ClassVar[bool] = False
    @property
    def turn_rate_or_none(self) -> float | None:
        """The ramp speed of the trap angle (turns per step; None: the bead is not turned)."""
        return None

    state_widths: ClassVar[dict] = {"turns": 7}

    def state_of(self, segment) -> dict:
        return {"turns": float(segment.turns)}

    def point_summary(self, segment, reps: list, columns: dict) -> dict:
        pt = super().point_summary(segment, reps, columns)
        for c in ("extension_nm", "torque_pN_nm", "catenation", "bead_angle_turns"):
            pt.setdefault(c, {"mean": None, "sem": None})
        ident = self.torque_identity(reps)
        if ident is not None:
            pt["torque_identity_pN_nm"] = ident
            if not ident["holds"]:  # samples that break an exact identity are not a result
                why = (f"torque identity <spread> = <trap> violated ({ident['mean']:+.3g} +- "
                       f"{ident['sem']:.2g} pN nm, p = {ident['p']:.2g})")
                pt["converged"] = False
                pt["convergence_reason"] = (why if pt["convergence_reason"] == "ok"
                                            else f"{pt['convergence_reason']}; {why}")
        return pt

    def torque_identity(self, reps: list) -> dict | None:
        """The exact identity <torque_spread> = <torque> (trap) checked on the replicas'
        paired differences: the spread turn preserves volume, so the total energy's
        derivative along it averages to zero in the Boltzmann distribution
        (:class:`dnabraid.observables.SpreadTorque`). A violation means the samples are not
        Boltzmann (the time step's bias, a point not equilibrated, or an energy term's
        derivative wrong). Mean, SEM, t = mean / SEM, its two-sided p (n_replicas - 1
        degrees of freedom) and ``holds`` (p >= :data:`IDENTITY_P`); None without both
        columns or with one replica. The SEM is the larger of the spread of the replica
        means and the within-replica SEM (``sem_within``): with few replicas the spread
        alone can come out small by chance and flag a violation that is not there
        (measured 2026-12-04: four ladders' trap-torque means 38.7, 38.9, 39.1, 34.5 pN nm,
        each +- ~12 from its own samples, gave a spread SEM of 0.53 and p = 4e-5)."""
        s0 = reps[0][0]
        if len(reps) < 2 or "torque_spread_pN_nm" not in s0 or "torque_pN_nm" not in s0:
            return None
        from scipy import stats

        d = self.summarise([s["torque_spread_pN_nm"] - s["torque_pN_nm"] for s, _ in reps])
        if d.get("mean") is None or not d.get("sem"):
            return None
        sem = max(float(d["sem"]), float(d.get("sem_within") or 0.0))
        t = d["mean"] / sem
        p = float(2 * stats.t.sf(abs(t), d["n_replicas"] - 1))
        return {"mean": d["mean"], "sem": sem, "sem_between": d["sem"],
                "sem_within": d.get("sem_within"), "t": float(t), "p": p,
                "n_replicas": d["n_replicas"], "holds": p >= IDENTITY_P,
                "what": "<torque_spread_pN_nm - torque_pN_nm>, 0 exactly for Boltzmann samples"}

    def finish_point(self, point: dict, stopped_by: str) -> None:
        point["precision"] = self.precision_verdict(point, stopped_by)

    def plot(self, summary: dict, out: str) -> None:
        from .. import plots

        plots.extension_torque_plot(summary, os.path.join(out, "extension_torque.png"))

    def has_targets(self) -> bool:
        return self.target_sem_nm > 0 or self.target_sem_pN_nm > 0

    def _targets(self):
        return [(c, t) for c, t in (("extension_nm", self.target_sem_nm),
                                    ("torque_pN_nm", self.target_sem_pN_nm)) if t > 0]

    def replicas_needed(self, points: list, R: int) -> int:
        """Replicas that would bring every point's SEM to its target (the across-replica
        SEM falls as 1/sqrt(R)); R when there is no target. Convergence is not a target:
        more replicas cannot fix replicas that are each too short (R-hat stays large)."""
        need = R
        for c, target in self._targets():
            for pt in points:
                sem = pt.get(c, {}).get("sem")
                if sem is not None and sem > target:
                    need = max(need, math.ceil(R * (sem / target) ** 2))
        return need

    def precision_verdict(self, pt: dict, stopped_by: str) -> dict:
        """Whether the point met its targets, and what ended its sampling."""
        met = {c: (pt.get(c, {}).get("sem") is not None and pt[c]["sem"] <= t)
               for c, t in self._targets()}
        return {"targets": dict(self._targets()), "met": met,
                "stopped_by": stopped_by, "n_replicas": pt["n_replicas"]}

    def report_extra(self, summary: dict, file) -> None:
        ids = [(pt, pt["torque_identity_pN_nm"]) for pt in summary["points"]
               if "torque_identity_pN_nm" in pt]
        if ids:
            bad = [f"turns {pt['turns']:g} ({d['mean']:+.1f} +- {d['sem']:.1f} pN nm, "
                   f"p = {d['p']:.1g})" for pt, d in ids if not d["holds"]]
            if bad:
                print("torque identity <spread> = <trap> VIOLATED at " + ", ".join(bad)
                      + ": these samples are not Boltzmann (time step, equilibration)",
                      file=file)
            else:
                print("torque identity <spread> = <trap> holds at every point (largest |t| "
                      f"{max(abs(d['t']) for _, d in ids):.1f})", file=file)
        if self.has_targets():
            pr = summary["points"][0]["precision"]
            met = all(all(pt["precision"]["met"].values()) for pt in summary["points"])
            print(f"precision targets {pr['targets']}: "
                  + ("met" if met else f"NOT met, the budget of {self.max_replicas} replicas "
                     "ended")
                  + f" ({pr['n_replicas']} replicas per point)", file=file)

    row_columns: ClassVar[tuple] = ("turns", "extension_nm", "extension_sem_nm", "torque_pN_nm",
                                    "torque_sem_pN_nm", "catenation", "catenation_sem",
                                    "n_samples")

    def bead_notes(self, zeta_bead: float, zeta_phys: float) -> list[str]:
        if zeta_bead < zeta_phys:
            return [f"bead friction reduced for sampling: {zeta_bead:.3g} pN ns/nm instead of "
                    f"the physical Stokes friction {zeta_phys:.3g} pN ns/nm of a "
                    f"{self.bead_radius_nm} nm bead (bead_friction_factor = "
                    f"{self.bead_friction_factor}); equilibrium averages are unaffected, times "
                    "are not physical"]
        return []


@dataclasses.dataclass(frozen=True)
class TurnedScene(TweezerScene):
    """A tweezer scene whose bead is turned by a rotational trap (braid, plectoneme)."""

    trap_parameter: ClassVar[str] = "trap_angle"
    needs_passage_barrier: ClassVar[bool] = True

    trap_stiffness_pN_nm: float = key(20000.0, "pN nm", "rotational trap: U = -K cos(phi - "
                                      "2 pi n)")
    turn_rate: float = key(5e-5, "turns/step", "speed at which the trap angle is ramped "
                           "between turn values")

    @property
    def turn_rate_or_none(self) -> float | None:
        return self.turn_rate

    def validate(self) -> None:
        super().validate()
        self.need(self.trap_stiffness_pN_nm > 0, "trap_stiffness_pN_nm", "must be > 0")
        self.need(0 < self.turn_rate <= 0.01, "turn_rate",
                  "must be in (0, 0.01] turns per step")


def lockup_turns(length_nm: float, diameter_nm: float) -> float:
    """Most turns a braid of two strands of length L and diameter d can hold: the two-ply
    locks up at theta = 45 deg (van der Heijden's talk on elastic braids, lock-up of the
    two-ply), n = L sin(theta) / (2 pi r) = L / (sqrt(2) pi d)."""
    return length_nm / (math.sqrt(2.0) * math.pi * diameter_nm)
