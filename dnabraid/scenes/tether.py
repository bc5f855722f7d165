"""Scene ``tether``: one nicked DNA molecule between the surface and a bead pulled with a
force F (force-extension; not turned).

The chain runs from its surface tether (immobile) to the bead attachment, which carries the
bead's friction and the force. It starts from an exact equilibrium draw of the discrete worm-like chain under the force
(:meth:`Tether.equilibrium_start`), not minimised.
``self_avoidance = false`` and ``surface = false`` leave out the excluded volume and the wall:
the exact discrete WLC under force (:mod:`dnabraid.continuum.wlc`) is then the same model.

Brownian dynamics relaxes the chain's slowest mode in a time ~ zeta L^2 / (pi^2 F), too
slow for long tethers at low force; ``mc_moves`` Metropolis crankshaft, pivot and bead
moves after every report interval (:class:`dnabraid.run.chain_moves.ChainMoves`, local
energies from numba kernels, :mod:`dnabraid.kernels`) sample the same Boltzmann
distribution in far fewer steps (workflows/results/benchmark_chain_moves.txt). The moves'
time correlations are not physical: ``mc_moves = 0`` for kinetics.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import numpy as np
from scipy.spatial import cKDTree

from .. import observables as ob
from .. import units
from ..forces import pull_force
from ..geometry import random_tether
from ..run.chain_moves import ChainMoves
from .base import key
from .tweezer_base import TweezerScene

#: Default Metropolis move attempts per report interval (workflows/benchmark_chain_moves.py).
MC_MOVES = 500
MC_MOVES_HELP = ("Metropolis moves after every report interval (crankshaft, pivot and bead moves "
                 "2:1:1; dnabraid.run.chain_moves): the same equilibrium, sampled far faster. "
                 "600 nm at 0.3 pN, 4 replicas, default steps: 500 moves converge (ESS 922-1160, "
                 "43-44 s wall on 2 shared cores) where Brownian dynamics alone does not (ESS "
                 "4-5, 34 s); ~3 us per move at 81 beads "
                 "(workflows/results/benchmark_chain_moves.txt). 0 = Brownian dynamics alone "
                 "(physical kinetics; the moves' time correlations are not physical)")
CRANK_HELP = ("largest crankshaft angle (an arc of 1-8 beads turned about the line through its "
              "two neighbours); acceptance 0.54-0.56 at 0.3 pN, 0.60 at 1 pN, 0.72 at 5 pN")
PIVOT_HELP = ("largest pivot angle (the chain's end beyond a bead turned about it, random "
              "axis); acceptance 0.52-0.62 at 0.3 pN, 0.52 at 1 pN, 0.32 at 5 pN")
BEAD_HELP = ("radius of a single-bead displacement's ball (samples the bond lengths); "
             "acceptance 0.56 at 0.3-5 pN")


@dataclasses.dataclass(frozen=True)
class Tether(TweezerScene):
    name: ClassVar[str] = "tether"
    help: ClassVar[str] = ("one nicked DNA molecule between surface and bead under force: "
                           "force-extension")

    force_pN: float = key(1.0, "pN", "constant force pulling the magnetic bead up (> 0)")
    length_nm: float = key(300.0, "nm", "contour length of the DNA molecule")
    turns: tuple = key((0.0,), "turns", "a nicked tether holds no turns: [0]")
    self_avoidance: bool = key(True, "", "false: no excluded volume between DNA beads (the "
                               "exact discrete WLC's model, for calibration)")
    integrator: str = key("lm", "", "'lm' (Leimkuhler-Matthews, the default here) or 'euler' "
                          "(Euler-Maruyama): at the default 300 nm / 1 pN with moves, "
                          "Euler-Maruyama read 257.17 +- 0.07 and 257.20 +- 0.27 nm (seeds 1, "
                          "2) against the independent reference 256.96 +- 0.08 nm, a "
                          "time-step bias of +0.2 nm (2-3 SE: its stiff bonds' variance "
                          "inflated by 1/(1 - h/2)); LM read 256.91 +- 0.16 and 256.93 +- "
                          "0.12 nm (2026-12-02)); 'mala' (Metropolis-adjusted steps, no "
                          "time-step bias at any step)")
    mc_moves: int = key(MC_MOVES, "", MC_MOVES_HELP)
    crank_angle_rad: float = key(2.0, "rad", CRANK_HELP)
    pivot_angle_rad: float = key(0.6, "rad", PIVOT_HELP)
    bead_move_nm: float = key(0.3, "nm", BEAD_HELP)
    start: str = key("equilibrium", "", "'equilibrium': each replica from its own exact draw of "
                     "the discrete WLC at force_pN (conditioned on wall and self-avoidance); "
                     "'force': from its own exact draw at start_force_pN instead, a start away "
                     "from equilibrium, so that the equilibration cut and the verdict are "
                     "tested (workflows/calibration_dynamics.py)")
    start_force_pN: float = key(0.0, "pN", "force of the 'force' start's draws (> 0)")

    def validate(self) -> None:
        super().validate()
        need = self.need
        need(self.turns == (0.0,), "turns",
             "a nicked single tether cannot hold turns; use turns=[0]")
        need(self.mc_moves >= 0, "mc_moves", "must be >= 0 (0 = Brownian dynamics alone)")
        need(0 <= self.crank_angle_rad <= math.pi, "crank_angle_rad", "must be in [0, pi]")
        need(0 <= self.pivot_angle_rad <= math.pi, "pivot_angle_rad", "must be in [0, pi]")
        need(self.bead_move_nm >= 0, "bead_move_nm", "must be >= 0")
        need(self.start in ("equilibrium", "force"), "start",
             "must be 'equilibrium' or 'force'")
        need(self.start != "force" or self.start_force_pN > 0, "start_force_pN",
             "start = 'force' needs start_force_pN > 0")
        if self.mc_moves > 0:
            need(self.crank_angle_rad > 0 or self.pivot_angle_rad > 0
                 or self.bead_move_nm > 0, "mc_moves",
                 "needs a move: crank_angle_rad, pivot_angle_rad or bead_move_nm > 0")
            need(self.stretch == "bonds", "mc_moves",
                 "the Metropolis moves need stretch='bonds' (bead moves change bond "
                 "lengths); set mc_moves=0 for rigid bonds")
            need(self.alpha == 0.0, "mc_moves",
                 "the moves' local energies have no chiral term; set alpha=0 or mc_moves=0")

    def attach(self, kit) -> dict:
        d = kit.dna
        zeta_phys = units.stokes_friction(self.bead_radius_nm)
        zeta_attach = max(d.zeta_bead, self.bead_friction_factor * zeta_phys)
        f = self.start_force_pN if self.start == "force" else self.force_pN
        pos = self.equilibrium_start(d, force_pN=f)
        if pos is None:
            pos = random_tether(self.n_beads, self.bead_spacing_nm, d.kappa_kT, self.seed,
                                z_min=0.5 * d.diameter_nm if self.surface else None)
        else:
            kit.exact_start = True  # a thermal draw: minimising would straighten it
        chain = kit.add_chain(pos, "A", last_friction=zeta_attach)
        kit.add_stretch(self.stretch)
        kit.add_bend()
        n_excl = kit.add_excluded_volume() if self.self_avoidance else 0
        if self.surface:
            kit.add_wall()
        att = int(chain[-1])
        kit.add_force(pull_force([att], [1.0], self.force_pN, name="pull"), "pull")
        kit.bound("stretch", "bend", "wca", "chiral")
        kit.bound("wall", "stretch")
        kit.attachments = [att]
        if self.mc_moves > 0:
            # the LocalEnergy is built from the finished System at the first call
            kit.moves = ChainMoves(kit.system, [chain], kit.fixed, d.kT,
                                   moves_per_call=self.mc_moves,
                                   crank_angle_rad=self.crank_angle_rad,
                                   pivot_angle_rad=self.pivot_angle_rad,
                                   bead_move_nm=self.bead_move_nm, seed=self.seed)
        return {"zeta_attach_pN_ns_per_nm": zeta_attach,
                "zeta_center_pN_ns_per_nm": zeta_attach,
                "zeta_bead_physical_pN_ns_per_nm": zeta_phys,
                "wall_k_pN_per_nm": d.wall_k if self.surface else 0.0,
                "n_exclusions": n_excl}

    def equilibrium_start(self, d, tries: int = 64, *, force_pN: float | None = None):
        """An exact draw of the discrete WLC under the force (``force_pN``, default the
        scene's; stretching included;
        :func:`dnabraid.continuum.wlc.sample_discrete_wlc`), or None.

        Draws that put a bead below the wall or two non-neighbouring beads closer than
        0.8 d (when they repel) are rejected: the start is then exact for the model without
        wall and self-avoidance, conditioned on being allowed with them. The run starts from
        it without minimisation, so no equilibration of the slow stretching modes is needed.
        """
        from ..continuum.wlc import sample_discrete_wlc

        n = self.n_beads - 1
        k = self.stretch_modulus_pN / self.bead_spacing_nm if self.stretch == "bonds" else None
        gap = max(1, int(np.ceil(2 ** (1 / 6) * d.diameter_nm / self.bead_spacing_nm + 0.5)))
        rng = np.random.default_rng(self.seed)
        for _ in range(tries // 8):  # batches of 8 draws: most scenes accept the first
            f = self.force_pN if force_pN is None else force_pN
            for x in sample_discrete_wlc(f, n, self.bead_spacing_nm, d.kappa_kT,
                                         d.kT, stretch_k_pN_per_nm=k, n_samples=8, rng=rng):
                if self.surface and np.any(x[1:, 2] <= 0.5 * d.diameter_nm):
                    continue
                if self.self_avoidance and n > gap:
                    pairs = cKDTree(x).query_pairs(0.8 * d.diameter_nm, output_type="ndarray")
                    if np.any(np.abs(pairs[:, 1] - pairs[:, 0]) >= gap):
                        continue
                return x
        return None

    @property
    def start_is_exact(self) -> bool:
        """True when every replica starts from an exact draw of the simulated model's own
        equilibrium (no wall, no excluded volume: the discrete WLC under force, drawn at
        the scene's own force)."""
        return not self.surface and not self.self_avoidance and self.start == "equilibrium"

    def verdict_rule(self) -> dict:
        """With exact starts each replica mean is an unbiased estimate and the replicas are
        independent, so nothing is discarded as a transient (``equilibration=None``); the
        verdict still asks R-hat <= 1.05 and ESS >= 100 across the replicas, so it fails
        for replicas that did not move or sampled too little (it could not fail before:
        R-hat and ESS were switched off). Otherwise the relaxed rule of every thermal
        scene with a data-driven equilibration."""
        rule = super().verdict_rule()
        if self.start_is_exact:
            rule["equilibration"] = None
        return rule

    def observables(self, model) -> list:
        return [ob.Extension(model.attachments)]

    def notes(self, model) -> list[str]:
        p = model.params
        return self.bead_notes(p["zeta_attach_pN_ns_per_nm"],
                               p["zeta_bead_physical_pN_ns_per_nm"])

    def default_short_run(self) -> dict:
        return {"steps": 2000, "equilibration_steps": 500, "frame_interval": 500}
