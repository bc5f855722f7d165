"""Scene ``plectoneme``: one torsionally constrained (un-nicked) DNA molecule between surface
and bead under force, turned n times: extension and torque against turns (the hat curve),
buckling, twist, writhe and plectonemes.

After the DNA beads come one side particle per bond (chain ``F``; the bond's material
frame, :mod:`dnabraid.forces.twist_frames`) and the bead's orientation particle m (chain ``M``),
held horizontal at ``BEAD_ARM_NM`` from the attachment and turned by the rotational trap;
the twist energy couples the surface frame (+z, +x), the bond frames and the bead frame
(+z, m - r_att), so turning the bead changes the linking number. Side particles and m carry
no excluded volume.

Brownian dynamics relaxes the extension and the exchange of twist and writhe far too slowly
for micrometre molecules; ``mc_moves`` twist-aware Metropolis moves after every report
interval (crankshafts that carry the arc's frames, pivots of the top with the bead,
frame rotations that carry twist along the chain, particle moves;
:class:`dnabraid.run.twist_moves.PlectonemeMoves`, local energies from numba kernels,
:mod:`dnabraid.kernels.twist`) sample the same Boltzmann distribution, the linking number
kept (the rotation amplitudes are bounded by the distance a bead may sweep). Their time
correlations are not physical: ``mc_moves = 0`` for kinetics.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import numpy as np

from .. import forcefield, units
from .. import observables as ob
from ..forces import pull_force, stretch_force, trap_force
from ..forces.twist_frames import (
    bead_plane_force,
    frame_springs,
    initial_side_positions,
    twist_anchor_force,
    twist_bead_force,
    twist_force,
)
from ..geometry.ribbon import writhe_open
from ..run.ladder import LADDER_STARTS, LadderPlan, rung_turns
from ..run.twist_moves import SWEEP_NM, PlectonemeMoves
from .base import SceneError, key
from .tweezer_base import TurnedScene

#: Frame arm a (side particle distance from the axis) in units of the bead spacing.
FRAME_ARM_FRACTION = 1.0
#: Side-particle friction / DNA bead friction. The frame angle's friction sets only how fast
#: twist relaxes (equilibrium does not depend on it); a light side particle relaxes twist
#: quickly without dragging the beads, and its rates stay below the bonds'.
FRAME_FRICTION_FRACTION = 0.1
#: Frame spring constant / bond spring constant. The springs only keep u_i well defined
#: (thermal wobble sqrt(kT/k) ~ 0.6 nm against the 5 nm arm); soft keeps the time step.
FRAME_K_FRACTION = 0.05
#: Distance of the bead's orientation particle m from the attachment (nm): the trap's
#: tangential stiffness K / arm^2 and its rate stay moderate.
BEAD_ARM_NM = 20.0

#: Default Metropolis move attempts per report interval (of REPORT_INTERVAL steps). Past
#: buckling a move costs ~55x less than a Brownian step of the 300 nm molecule (8.5 us
#: against 470 us), so the default samples mainly by moves: 400 moves per Brownian step
#: (docs/validation.md 2.3l; before 2026-12-04: 500 moves per 100 steps, 5 per step).
MC_MOVES = 20000
#: Default sampling of the plectoneme scene (docs/validation.md 2.3l): a sample every 50
#: steps (20 000 moves apart), 160 samples per replica and point after 2000 steps (800 000
#: moves) of equilibration, and ramps at 5e-4 turns/step (with moves; 2.3h, 2.3j).
REPORT_INTERVAL = 50
STEPS = 8000
EQUILIBRATION_STEPS = 2000
FRAME_INTERVAL = 500
TURN_RATE = 5e-4
MC_MOVES_HELP = ("twist-aware Metropolis moves after every report interval (crankshaft, pivot, "
                 "frame and particle moves 1:6:1:1; dnabraid.run.twist_moves): the same "
                 "equilibrium, sampled far faster. Default 20000 per 50 steps: the default hat "
                 "curve (300 nm, 1 pN, seed 1) converges at n = 0-3 and 5 in 1011 s (n = 3: "
                 "181.8 +- 1.8 nm against the moves-only reference 180.2 +- 0.4; n = 5: 89.5 "
                 "+- 1.1 against 92.8 +- 1.3, 1.97 SE below); n = 4 and 6 are NOT CONVERGED, "
                 "and n = 5 at seeds 2-5 too: past buckling the moves' own slow mode, the "
                 "twist-writhe partition, limits (docs/validation.md 2.3l). Earlier, at 500 "
                 "per 100 steps: 1000 nm at 0.5 pN, n = 0, converged (797.1 +- 1.0 nm against the "
                 "independent reference 799.1 +- 0.4 nm) where Brownian dynamics alone did not "
                 "(R-hat 2.6; ESS 5). 0 = Brownian dynamics alone (physical kinetics; the "
                 "moves' time correlations are not physical)")


SAMPLERS = ("hybrid", "ladder")
SAMPLER_HELP = ("hybrid: Brownian dynamics with mc_moves Metropolis moves between steps (the "
                "default); ladder: moves only, one ladder of chains per replica at trap angles "
                "1/ladder_per_turn turn apart from the lowest to the highest turns, neighbours "
                "swapped through a map that spreads the bead's turn over the frames "
                "(dnabraid.run.ladder, docs/validation.md 2.3n, 2.3o): no Brownian steps, no "
                "time-step bias, no kinetics")
#: The ladder's ramp: moves per turn up the ladder (the moves-only reference ramps 3 turns
#: in 8e5 moves, 2.7e5 per turn) and moves at each rung's angle when the ramp reaches it.
LADDER_RAMP_MOVES_PER_TURN = 200_000
LADDER_RUNG_EQ_MOVES = 20_000


@dataclasses.dataclass(frozen=True)
class Plectoneme(TurnedScene):
    name: ClassVar[str] = "plectoneme"
    help: ClassVar[str] = ("one torsionally constrained DNA molecule between surface and bead "
                           "under force, turned n times: extension and torque against turns "
                           "(the hat curve), buckling, twist, writhe and plectonemes")
    torsionally_constrained: ClassVar[bool] = True

    force_pN: float = key(1.0, "pN", "constant force pulling the magnetic bead up (> 0)")
    length_nm: float = key(300.0, "nm", "contour length of the DNA molecule")
    turns: tuple = key((0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0), "turns",
                       "list of bead turn values n (linking number imposed by the trap)")
    twist_persistence_nm: float = key(
        float(forcefield.mechanics()["twist_persistence_nm"]), "nm",
        "twist persistence length C of torsionally constrained DNA (Moroz & Nelson 1997, "
        "Bryant et al. 2003: C ~ 100 nm; twist-stretch coupling is left out)")

    steps: int = key(STEPS, "steps", "sampling steps per turn value (after equilibration); "
                     "with mc_moves moves after every report interval")
    equilibration_steps: int = key(EQUILIBRATION_STEPS, "steps", "equilibration steps after "
                                   "each change of turns (with moves)")
    report_interval: int = key(REPORT_INTERVAL, "steps", "steps between observable samples "
                               "(and between calls of the mc_moves moves)")
    frame_interval: int = key(FRAME_INTERVAL, "steps", "steps between trajectory frames "
                              "(multiple of report_interval)")
    turn_rate: float = key(TURN_RATE, "turns/step", "speed at which the trap angle is ramped "
                           "between turn values (moves run during the ramp; 3e-3 lost the "
                           "linking number once, docs/validation.md 2.3j)")
    mc_moves: int = key(MC_MOVES, "", MC_MOVES_HELP)
    crank_angle_rad: float = key(1.0, "rad", "largest crankshaft angle (an arc of 1-12 beads "
                                 "and its frames turned about the line through its two "
                                 "neighbours; bounded further by sweep_nm)")
    pivot_angle_rad: float = key(0.3, "rad", "largest pivot angle (the top beyond a bead, "
                                 "frames and bead included, turned about it; refused when a "
                                 "bond could pass through another on the way)")
    frame_angle_rad: float = key(0.3, "rad", "largest frame-rotation angle (a run of 1-40 "
                                 "frames turned about their bonds: carries twist along the "
                                 "chain)")
    bead_move_nm: float = key(0.3, "nm", "radius of a single-particle displacement's ball "
                              "(bond lengths, frame springs, the trap's tilt)")
    sweep_nm: float = key(SWEEP_NM, "nm", "most distance a bead may travel in a crankshaft or "
                          "pivot: keeps strands from passing through each other (the linking "
                          "number); <= 3 nm keeps any passage behind a > 50 kT excluded-volume "
                          "barrier at the default diameter")
    twist_spread: bool = key(False, "", "crankshafts and pivots also spin the frames so "
                             "that the twist their rotation puts on the two pivot joints is "
                             "shared by all joints of the chain in inverse proportion to their "
                             "stiffness (docs/validation.md 2.3m); false: the two joints take it")

    sampler: str = key("hybrid", "", SAMPLER_HELP)
    ladder_per_turn: int = key(6, "rungs/turn", "sampler = ladder: rungs per turn (the swap "
                               "turns the bead by 2 pi / ladder_per_turn; swap acceptance "
                               "0.62-0.71 at 6 on 300 nm at 1 pN, n = 3-6); the rungs are "
                               "evenly spaced from the lowest to the highest turns, at most "
                               "1/ladder_per_turn apart, and every value of turns must lie on "
                               "one")
    ladder_rounds: int = key(1000, "rounds", "sampler = ladder: sampling rounds per replica "
                             "(a sample of every point after each)")
    ladder_equilibration_rounds: int = key(100, "rounds", "sampler = ladder: rounds with swaps "
                                           "before sampling, after the ramp up the ladder")
    ladder_round_moves: int = key(1000, "moves", "sampler = ladder: moves per rung between "
                                  "swap phases")
    ladder_frame_every: int = key(10, "rounds", "sampler = ladder: rounds between trajectory "
                                  "frames (and the per-frame observables: Tw, Wr, plectonemes)")
    ladder_starts: str = key("alternate", "", "sampler = ladder: alternate: odd replicas fill "
                             "their ladder from the highest rung down, even ones from the "
                             "lowest up, so that R-hat across them sees a bias the filling "
                             "leaves (needed for a verdict when the ladders make < 2 round "
                             "trips); up: every replica from below")

    def validate(self) -> None:
        super().validate()
        need = self.need
        need(self.sampler in SAMPLERS, "sampler", f"allowed: {', '.join(SAMPLERS)}")
        if self.sampler == "ladder":
            for k in ("ladder_per_turn", "ladder_rounds", "ladder_round_moves",
                      "ladder_frame_every"):
                need(getattr(self, k) >= 1, k, "must be >= 1")
            need(self.ladder_equilibration_rounds >= 0, "ladder_equilibration_rounds",
                 "must be >= 0")
            need(self.ladder_starts in LADDER_STARTS, "ladder_starts",
                 f"allowed: {', '.join(LADDER_STARTS)}")
            need(self.ladder_rounds >= 2 * self.ladder_frame_every, "ladder_rounds",
                 f"must be >= 2 x ladder_frame_every = {2 * self.ladder_frame_every}")
            need(self.stretch == "bonds", "sampler",
                 "the ladder's moves need stretch='bonds'")
            need(self.alpha == 0.0, "sampler", "the moves' local energies have no chiral "
                 "term; set alpha=0")
            need(len(set(self.turns)) == len(self.turns), "turns", "must be distinct")
            try:
                rung_turns(self.turns, self.ladder_per_turn)
            except ValueError as exc:
                need(False, "turns", str(exc))
        need(self.mc_moves >= 0, "mc_moves", "must be >= 0 (0 = Brownian dynamics alone)")
        for k in ("crank_angle_rad", "pivot_angle_rad", "frame_angle_rad"):
            need(0 <= getattr(self, k) <= math.pi, k, "must be in [0, pi]")
        need(self.bead_move_nm >= 0, "bead_move_nm", "must be >= 0")
        need(self.sweep_nm > 0, "sweep_nm", "must be > 0")
        if self.mc_moves > 0:
            need(self.crank_angle_rad > 0 or self.pivot_angle_rad > 0
                 or self.frame_angle_rad > 0 or self.bead_move_nm > 0, "mc_moves",
                 "needs a move: crank_angle_rad, pivot_angle_rad, frame_angle_rad or "
                 "bead_move_nm > 0")
            need(self.stretch == "bonds", "mc_moves",
                 "the Metropolis moves need stretch='bonds' (particle moves change bond "
                 "lengths); set mc_moves=0 for rigid bonds")
            need(self.alpha == 0.0, "mc_moves",
                 "the moves' local energies have no chiral term; set alpha=0 or mc_moves=0")
        need(self.twist_persistence_nm >= self.bead_spacing_nm, "twist_persistence_nm",
             "must be >= bead_spacing_nm (a bead chain cannot resolve a shorter twist "
             "persistence)")
        need(self.twist_persistence_nm <= 1000.0, "twist_persistence_nm",
             "must be <= 1000 nm (DNA: ~100 nm)")

    def attach(self, kit) -> dict:
        d = kit.dna
        kT, b, n = d.kT, self.bead_spacing_nm, self.n_beads
        zeta_phys = units.stokes_friction(self.bead_radius_nm)
        zeta_attach = max(d.zeta_bead, self.bead_friction_factor * zeta_phys)
        pos = self.equilibrium_start(d)
        kit.exact_start = True  # a thermal draw: minimising would straighten it
        c0 = kit.add_chain(pos, "A", last_friction=zeta_attach)
        zeta_frame = FRAME_FRICTION_FRACTION * d.zeta_bead
        arm = FRAME_ARM_FRACTION * b
        g = self.twist_persistence_nm * kT / b
        k_frame = FRAME_K_FRACTION * d.k_bond
        side_pos = initial_side_positions(pos, arm)
        sides = kit.add_particles("F", "FRM", "F", zeta_frame, side_pos[: n - 1])
        att = int(c0[-1])
        m = kit.add_particle("M", "BEO", "MO", d.zeta_bead, pos[-1] + np.array([BEAD_ARM_NM,
                                                                                  0.0, 0.0]))
        kit.add_stretch(self.stretch)
        kit.add_bend()
        n_excl = kit.add_excluded_volume(dna_only=True)
        if self.surface:
            kit.add_wall()
        mu = 1.0 / d.zeta_bead
        kit.add_force(pull_force([att], [1.0], self.force_pN, name="pull"), "pull")
        kit.add_force(frame_springs(c0, sides, arm, b, k_frame, name="frame"), "frame",
                      rate=4.0 * k_frame / zeta_frame)
        joints = [(c0[i], c0[i + 1], c0[i + 2], sides[i], sides[i + 1]) for i in range(n - 2)]
        # interior joints stand for a bond length b, the two clamps for b/2 each: the
        # chain's twist compliance is L / (C kT) (forces/twist_frames.py)
        kit.add_force(twist_force(joints, g, name="twist"), "twist",
                      rate=6.0 * g / (arm * arm * zeta_frame))
        kit.add_force(twist_anchor_force([(c0[0], c0[1], sides[0])], (0, 0, 1), (1, 0, 0),
                                         2 * g, name="twist_anchor"), "twist_anchor",
                      group="twist")
        kit.add_force(twist_bead_force([(c0[-2], c0[-1], sides[-1], m)], 2 * g,
                                       name="twist_bead"), "twist_bead", group="twist")
        K = self.trap_stiffness_pN_nm
        kit.add_force(trap_force(att, m, K, 0.0, K / BEAD_ARM_NM**2, name="trap"), "trap",
                      rate=2 * K / BEAD_ARM_NM**2 / d.zeta_bead)
        kit.add_force(stretch_force([(att, m)], d.k_bond, BEAD_ARM_NM, name="link"), "link",
                      rate=2 * d.k_bond / d.zeta_bead)
        kit.add_force(bead_plane_force(att, c0[1:-1], d.wall_k, name="beadwall"), "beadwall")
        # on the DNA beads: the frame springs' reaction 4 k_f and the twist through the
        # tangents, bounded by 12 g / b^2 (three joints touch a bead)
        dna_extra = (4.0 * k_frame + 12.0 * g / b**2) * mu
        kit.bound("stretch", "bend", "wca", "chiral", dna_extra)
        kit.bound("wall", "stretch", dna_extra)
        kit.bound("frame", "twist")
        kit.bound("trap", "link")
        kit.attachments = [att]
        kit.sides = sides
        kit.bead_orientation = m
        if self.mc_moves > 0 and self.sampler == "hybrid":
            # the LocalEnergy is built from the finished System at the first call
            kit.moves = PlectonemeMoves(kit.system, c0, sides, m, kit.fixed, kT,
                                        moves_per_call=self.mc_moves,
                                        crank_angle_rad=self.crank_angle_rad,
                                        pivot_angle_rad=self.pivot_angle_rad,
                                        frame_angle_rad=self.frame_angle_rad,
                                        ball_nm=self.bead_move_nm, sweep_nm=self.sweep_nm,
                                        twist_spread=self.twist_spread, seed=self.seed)
        return {"zeta_attach_pN_ns_per_nm": zeta_attach,
                "zeta_center_pN_ns_per_nm": zeta_attach,
                "zeta_bead_physical_pN_ns_per_nm": zeta_phys,
                "wall_k_pN_per_nm": d.wall_k if self.surface else 0.0,
                "n_exclusions": n_excl,
                "twist_g_pN_nm": g, "twist_persistence_nm": self.twist_persistence_nm,
                "frame_arm_nm": arm, "frame_k_pN_per_nm": k_frame,
                "zeta_frame_pN_ns_per_nm": zeta_frame, "bead_arm_nm": BEAD_ARM_NM,
                "zeta_bead_orientation_pN_ns_per_nm": d.zeta_bead}

    def equilibrium_start(self, d) -> np.ndarray:
        """The replica's own start: an exact draw of the discrete WLC under the force
        (:func:`dnabraid.continuum.wlc.sample_tether_start`; bending and stretch exact, the
        untwisted frames added on it), conditioned by rejection on the wall, on no two
        non-neighbouring beads closer than 0.8 d, and on |Wr| <= 0.25 (Lk = 0 at the start:
        the bead clamp takes up -Wr, which must stay on the principal branch of the clamp
        angle, |2 pi Wr| < pi/2). A start that cannot be drawn is an error, never a shared
        straight rod (as before 2026-12-02)."""
        from ..continuum.wlc import StartDrawError, sample_tether_start

        gap = max(1, int(np.ceil(2 ** (1 / 6) * d.diameter_nm / self.bead_spacing_nm + 0.5)))
        k = self.stretch_modulus_pN / self.bead_spacing_nm if self.stretch == "bonds" else None
        try:
            return sample_tether_start(
                self.force_pN, self.n_beads - 1, self.bead_spacing_nm, d.kappa_kT, d.kT,
                np.random.default_rng([int(self.seed), 0x9E7]), stretch_k_pN_per_nm=k,
                wall_z_nm=0.5 * d.diameter_nm if self.surface else None,
                min_separation_nm=0.8 * d.diameter_nm, min_chemical_gap=gap,
                accept=lambda x: abs(writhe_open(x)) <= 0.25, tries=256)
        except StartDrawError as exc:
            raise SceneError(f"force_pN={self.force_pN} pN: {exc}; a plectoneme start needs "
                             "a chain that fits above the wall with |Wr| <= 0.25") from exc

    def ladder_plan(self) -> LadderPlan | None:
        if self.sampler != "ladder":
            return None
        return LadderPlan(make_moves=self.ladder_moves, per_turn=self.ladder_per_turn,
                          round_moves=self.ladder_round_moves,
                          rounds=self.ladder_rounds,
                          equilibration_rounds=self.ladder_equilibration_rounds,
                          ramp_moves_per_turn=LADDER_RAMP_MOVES_PER_TURN,
                          rung_equilibration_moves=LADDER_RUNG_EQ_MOVES,
                          frame_every=self.ladder_frame_every,
                          starts=self.ladder_starts)

    def ladder_moves(self, model) -> PlectonemeMoves:
        """The scene's moves (its amplitudes and mix) on the replica's own LocalEnergy."""
        return PlectonemeMoves.for_model(model, moves_per_call=self.ladder_round_moves,
                                         crank_angle_rad=self.crank_angle_rad,
                                         pivot_angle_rad=self.pivot_angle_rad,
                                         frame_angle_rad=self.frame_angle_rad,
                                         ball_nm=self.bead_move_nm, sweep_nm=self.sweep_nm,
                                         twist_spread=self.twist_spread, seed=self.seed)

    def observables(self, model) -> list:
        c = model.chains[0]
        m = model.bead_orientation
        return [ob.Extension(model.attachments),
                ob.BeadAngle((model.attachments[0], m), self.trap_stiffness_pN_nm,
                             self.turn_rate),
                ob.TrapTorque(self.trap_stiffness_pN_nm),
                ob.TwistTorque(c, model.sides, m, self.twist_persistence_nm, model.dna.kT,
                               self.length_nm),
                ob.SpreadTorque(model, [c], [model.attachments[0], m], model.attachments[0],
                                sides=model.sides),
                ob.TwistWrithe(c, model.sides, m), ob.Plectonemes(c)]

    def notes(self, model) -> list[str]:
        p = model.params
        return self.bead_notes(p["zeta_attach_pN_ns_per_nm"],
                               p["zeta_bead_physical_pN_ns_per_nm"]) + [
            "torsionally constrained DNA: side-particle frames, twist persistence "
            f"{self.twist_persistence_nm} nm, twist-stretch coupling left out"]

    def point_summary(self, segment, reps: list, columns: dict) -> dict:
        """Adds the linking number Tw + Wr (equal to the bead angle while the DNA does not
        pass through itself), the fraction of frames with a plectoneme and the median tip
        position (nm of contour from the surface)."""
        pt = super().point_summary(segment, reps, columns)
        pt["linking"] = self.summarise([f["twist"] + f["writhe"] for _, f in reps])
        pl = np.concatenate([f["plectonemes"] for _, f in reps])
        tip = np.concatenate([f["plectoneme_tip_nm"] for _, f in reps])
        pt["plectoneme_fraction"] = float(np.mean(pl > 0)) if pl.size else None
        pt["plectoneme_tip_nm"] = (float(np.nanmedian(tip)) if np.any(np.isfinite(tip))
                                   else None)
        return pt

    def default_short_run(self) -> dict:
        # the default turn rate: 1e-3 turns/step tears the last bond at the bead
        return {"steps": 2000, "equilibration_steps": 500, "turns": [0.0, 1.0],
                "frame_interval": 500}
