"""Scene ``braid``: two nicked DNA molecules between a surface and a magnetic bead, braided
by turning the bead; extension, torque and catenation against turns.

Particle layout: each strand is a chain from its surface tether (immobile) to its bead
attachment point; the two attachment points and the bead centre C form a rigid triangle
(links of stiffness S/b), C lying at the bead radius R from both attachments, above them.
C carries the bead's friction and the magnetic force; the sphere of radius R around C
excludes DNA, so strands cannot slip over the bead and unbraid. The rotational trap
U = -K cos(phi - 2 pi n) holds the attachment chord's angle phi. No twist (nicked DNA).

``mc_moves`` > 0 adds Metropolis moves after every report interval
(:class:`dnabraid.run.chain_moves.BraidMoves`, local energies from numba kernels): crankshafts
inside each strand (arcs up to the whole strand), single-particle moves, the shear of the
whole top and its twist in the trap, the sway (the pendulum with the strands' shapes kept),
the pivot of both strands above a bead, the bead's tilt about its attachments and the
stretch (the extension with the strands' slack), refusing any move that would pass a
strand through the other (dnabraid.kernels.braid_moves). They sample the same Boltzmann
distribution; their time correlations are not physical.
On by default since 2026-12-06 (3000 per report interval; ``mc_moves = 0``: Brownian
dynamics alone, for kinetics; workflows/results/benchmark_braid_moves.txt,
docs/validation.md 1.6).
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import numpy as np

from .. import observables as ob
from .. import units
from ..forces import bead_exclusion_force, pull_force, stretch_force, trap_force
from ..run.chain_moves import BraidMoves
from ..run.contract import StartError
from .base import SceneError, key
from .tweezer_base import TurnedScene, lockup_turns

#: values of the ``mirror`` key
MIRROR_MODES = ("off", "original", "image")
#: values of the ``contact`` key
CONTACT_MODES = ("beads", "capsules")
#: largest bow of an overdispersed start's braid axis, as a fraction of the strand length
MAX_START_BOW = 0.25
#: Draws of a replica's built start before it is declared impossible (StartError).
MAX_START_DRAWS = 200
#: The long braid: 2 x 200 nm at 2 pN and timestep_safety 0.3, the braid's defaults before
#: 2026-12-01 (a developed two-ply up to n = +-3). The zero-temperature cross-checks, the
#: extremes matrix and several workflows were set up and measured on it; the thermal
#: default is now 2 x 100 nm at 2 pN with moves (README, docs/validation.md 1.6).
LONG_BRAID = {"length_nm": 200.0, "force_pN": 2.0, "timestep_safety": 0.3}
#: The toy braid: the thermal default from 2026-12-01 to 2026-12-05 (2 x 60 nm at 20 pN,
#: Brownian dynamics alone, a stiff trap). Tests and workflows written against it pin it.
TOY_BRAID = {"length_nm": 60.0, "force_pN": 20.0, "steps": 450000, "replicas": 8,
             "equilibration_steps": 20000, "mc_moves": 0, "trap_stiffness_pN_nm": 20000.0}

MC_MOVES_HELP = ("Metropolis moves after every report interval (crankshaft, bead, shear, twist, "
                 "sway, pivot, tilt, stretch, breathe 4:4:0.5:0.5:1:2:1:2:2; "
                 "dnabraid.run.chain_moves.BraidMoves): the same equilibrium, sampled "
                 "faster (workflows/results/benchmark_braid_moves.txt); their local energies carry "
                 "every term, the capsule contact and the chiral term included. 0 = Brownian "
                 "dynamics alone (physical kinetics). Needs stretch = 'bonds'")


@dataclasses.dataclass(frozen=True)
class Braid(TurnedScene):
    name: ClassVar[str] = "braid"
    help: ClassVar[str] = ("two nicked DNA molecules between a surface and a magnetic bead, "
                           "braided by turning the bead: extension, torque and catenation "
                           "against turns")

    # The default scene (2026-12-06, docs/validation.md 1.6): 2 x 100 nm at 2 pN (the
    # forces of magnetic-tweezer braiding; Charvin et al. 2005 braid at 0.5-5 pN), half and
    # whole turns to +-1 (the braid buckles between 1 and 2 turns at this length and force:
    # n = +-2 read 45.7-49.4 nm with R-hat 1.6-1.8), 4 replicas of 1e4 + 5e4 steps with 3000
    # compiled Metropolis moves after every report interval, a rotational trap of
    # K = 2000 pN nm (magnetic torque tweezers: 1e2-1e4 pN nm/rad, Lipfert et al. 2010): every
    # point converged in 161-170 s on 2 cores (six seeds). The previous default (2026-12-01 to
    # 2026-12-05: 2 x 60 nm at 20 pN, Brownian dynamics alone, 8 replicas of 4.5e5 steps,
    # K = 2e4) is `TOY_BRAID` above, kept for the tests and workflows written against it.
    force_pN: float = key(2.0, "pN", "constant force pulling the magnetic bead up (> 0)")
    length_nm: float = key(100.0, "nm", "contour length of each DNA molecule")
    turns: tuple = key((-1.0, -0.5, 0.0, 0.5, 1.0), "turns", "list of bead turn values n "
                       "(catenation imposed by the rotational trap)")
    steps: int = key(50000, "steps", "sampling steps per turn value and replica (after "
                     "equilibration)")
    replicas: int = key(4, "", "independent replicas per turn value, each from its own start "
                        "(seed); the error bar is the scatter of their means (Student t)")
    timestep_safety: float = key(0.3, "", "time step = safety x 2 / (mobility x largest "
                                 "stiffness); with integrator = mala it sets only the "
                                 "acceptance (0.68 at 0.3, 0.26 at 0.6: "
                                 "workflows/results/benchmark_mala.txt), not the answer")
    integrator: str = key("mala", "", "'mala' (the default since 2026-12-07): Euler-Maruyama "
                          "steps accepted by Metropolis on the total energy (Rossky, Doll & "
                          "Friedman 1978), no time-step bias at any step, ~2x the cost per "
                          "step (+17 % wall at the default, the moves dominate); 'euler': "
                          "Euler-Maruyama (OpenMM's BrownianIntegrator), biased at O(dt) "
                          "(the earlier default at safety 0.6 read the n = 0 extension "
                          "0.14 +- 0.07 nm above mala: docs/validation.md 2.4''); 'lm': "
                          "Leimkuhler-Matthews")
    equilibration_steps: int = key(10000, "steps", "equilibration steps after each change "
                                   "of turns (more is cut from the data where it is detected)")
    trap_stiffness_pN_nm: float = key(2000.0, "pN nm", "rotational trap: U = -K cos(phi - "
                                      "2 pi n); the trap torque's per-sample noise is "
                                      "sqrt(K kT) (2000: 91 pN nm; 2e4: 287), its lag "
                                      "sqrt(kT / K) (0.045 rad at 2000)")
    tether_separation_nm: float = key(40.0, "nm", "distance between the two tether points "
                                      "(surface and bead)")
    start_spread: float = key(1.0, "", "how far the replicas' built starts differ (0 = all "
                              "the same; 1 = plateau steepness in [2.5, 6] and a braid-axis "
                              "bow up to 0.25 L, from each replica's seed): overdispersed "
                              "starts let R-hat see an unforgotten start")
    mc_moves: int = key(3000, "", MC_MOVES_HELP)
    crank_angle_rad: float = key(2.0, "rad", "largest crankshaft angle (an arc of 1-8 beads of "
                                 "one strand turned about the line through its neighbours)")
    bead_move_nm: float = key(0.3, "nm", "radius of a single-particle move's ball")
    shear_nm: float = key(3.0, "nm", "largest horizontal shift of the top (bead centre and "
                          "attachments) in a shear move; strand bead k moves by k/(beads-1) "
                          "of it (the pendulum mode)")
    shear_z_nm: float = key(1.0, "nm", "largest vertical shift of a shear move")
    twist_rad: float = key(0.05, "rad", "largest turn of the top about the vertical through "
                           "the bead centre in a twist move (strand bead k: k/(beads-1) of it)")
    sway_rad: float = key(0.1, "rad", "largest angle of a sway move: each strand turned "
                          "rigidly about its anchor by one rotation about a horizontal axis, "
                          "the bead centre following the attachments (the pendulum mode "
                          "with the strands' shapes kept)")
    pivot_rad: float = key(0.15, "rad", "largest angle of a pivot move: both strands above "
                           "bead k and the bead centre turned about the line through the "
                           "strands' beads k - 1 (the extension's move)")
    tilt_rad: float = key(0.1, "rad", "largest angle of a tilt move: the bead centre turned "
                          "about the line through the attachments")
    stretch_eps: float = key(0.01, "", "largest |log lambda| of a stretch move: each strand's "
                             "heights scaled by lambda and its deviations from the line "
                             "anchor-attachment by lambda^-a (the extension with the "
                             "strands' slack; Metropolis-Hastings)")
    breathe_eps: float = key(0.1, "", "largest |log mu| of a breathe move: a window of the "
                             "braid opened about its bead pairs' midpoints by mu (a tent "
                             "profile), every bond's length kept, the top lowered with it "
                             "(the braid's radius with the extension; Metropolis-Hastings)")
    breathe_max_beads: int = key(40, "beads", "most bead pairs in a breathe move's window")
    crank_max_beads: int = key(40, "beads", "most beads of a crankshaft arc (arcs of the whole "
                               "strand turn its bow, the slowest mode of local moves)")
    mirror: str = key("off", "", "mirror-coupled pairs (variance reduction for handedness "
                      "asymmetries): 'off'; 'original' or 'image' run the two members of a "
                      "pair with one seed and negated turn lists: the image starts from and is "
                      "driven by the y -> -y mirror of the original's start and noise "
                      "(dnabraid.analysis.mirror)")
    contact: str = key("beads", "", "excluded volume between the two strands: 'beads' (WCA "
                       "between beads, contact ~2^(1/6) d) or 'capsules' (segment-segment "
                       "contact k/2 (D_c - d)^2 at D_c = d, the contact distance the chiral "
                       "weight and the continuum cross-checks use; docs/chirality.md)")

    def validate(self) -> None:
        super().validate()
        need = self.need
        need(self.mirror in MIRROR_MODES, "mirror", f"must be one of {MIRROR_MODES}")
        need(self.contact in CONTACT_MODES, "contact", f"must be one of {CONTACT_MODES}")
        need(0.0 <= self.start_spread <= 1.0, "start_spread", "must be in [0, 1]")
        d = self.effective_diameter_nm
        need(self.tether_separation_nm >= d, "tether_separation_nm",
             f"must be >= the effective diameter {d:.2f} nm (the tethers would overlap)")
        need(self.tether_separation_nm < self.length_nm, "tether_separation_nm",
             f"must be < length_nm={self.length_nm} (tethers farther apart than the strands "
             "are long cannot be bridged)")
        need(self.tether_separation_nm < 2 * self.bead_radius_nm, "tether_separation_nm",
             f"must be < the bead diameter 2 x {self.bead_radius_nm} nm")
        need(self.mc_moves >= 0, "mc_moves", "must be >= 0 (0 = Brownian dynamics alone)")
        need(0 <= self.crank_angle_rad <= math.pi, "crank_angle_rad", "must be in [0, pi]")
        need(0 <= self.twist_rad <= math.pi, "twist_rad", "must be in [0, pi]")
        need(0 <= self.sway_rad <= math.pi, "sway_rad", "must be in [0, pi]")
        need(0 <= self.pivot_rad <= math.pi, "pivot_rad", "must be in [0, pi]")
        need(0 <= self.tilt_rad <= math.pi, "tilt_rad", "must be in [0, pi]")
        need(0 <= self.stretch_eps <= 0.5, "stretch_eps", "must be in [0, 0.5]")
        need(0 <= self.breathe_eps <= 0.5, "breathe_eps", "must be in [0, 0.5]")
        need(self.breathe_max_beads >= 2, "breathe_max_beads", "must be >= 2")
        need(self.crank_max_beads >= 1, "crank_max_beads", "must be >= 1")
        for k in ("bead_move_nm", "shear_nm", "shear_z_nm"):
            need(getattr(self, k) >= 0, k, "must be >= 0")
        if self.mc_moves > 0:
            need(max(self.crank_angle_rad, self.bead_move_nm, self.shear_nm,
                     self.twist_rad, self.sway_rad, self.pivot_rad, self.tilt_rad,
                     self.stretch_eps, self.breathe_eps) > 0,
                 "mc_moves", "needs a move: crank_angle_rad, bead_move_nm, shear_nm, "
                 "twist_rad, sway_rad, pivot_rad, tilt_rad, stretch_eps or breathe_eps > 0")
            need(self.stretch == "bonds", "mc_moves",
                 "the Metropolis moves need stretch='bonds' (they change bond lengths); "
                 "set mc_moves=0 for rigid bonds")
        n_lock = lockup_turns(self.length_nm, d)
        need(max(abs(t) for t in self.turns) <= n_lock, "turns",
             f"|turns| must be <= {n_lock:.2f}: more turns than a {self.length_nm} nm braid "
             f"of diameter {d:.2f} nm can hold at the 45-degree lock-up (L / (sqrt(2) pi d); "
             "van der Heijden, elastic braids: the two-ply locks up at 45 degrees)")

    def attach(self, kit) -> dict:
        d = kit.dna
        b, n = self.bead_spacing_nm, self.n_beads
        half = 0.5 * self.tether_separation_nm
        chains = []
        for s, x in enumerate((-half, half)):
            pos = np.c_[np.full(n, x), np.zeros(n), b * np.arange(n)]
            chains.append(kit.add_chain(pos, "AB"[s]))
        att = [int(c[-1]) for c in chains]
        fixed = [int(c[0]) for c in chains]
        mu = 1.0 / d.zeta_bead
        kit.add_stretch(self.stretch)
        kit.add_bend()
        extra = [tuple(att), tuple(fixed)]
        if self.contact == "capsules":  # the strands meet through their segments only
            extra += [(int(i), int(j)) for i in chains[0] for j in chains[1]]
        n_excl = kit.add_excluded_volume(extra, dna_only=True)  # not the bead centre
        if self.contact == "capsules":
            kit.add_capsule_contact(chains)
        if self.surface:
            kit.add_wall()
        zeta_phys = units.stokes_friction(self.bead_radius_nm)
        zeta_center = self.bead_friction_factor * zeta_phys
        R = self.bead_radius_nm
        h = math.sqrt(R * R - half * half)
        top = kit.positions[att].mean(axis=0)
        center = kit.add_particle("M", "BEA", "MB", zeta_center, top + np.array([0.0, 0, h]))
        K = self.trap_stiffness_pN_nm
        kit.add_force(pull_force([center], [1.0], self.force_pN, name="pull"), "pull")
        kit.add_force(trap_force(att[0], att[1], K, 0.0, K / half**2, name="trap"), "trap",
                      rate=2 * K / half**2 * mu)
        # the links' rate: the attachments' (3 k mu), or the centre's Gershgorin bound 4 k
        # mu_c (its two links, 2k on the diagonal and 2k off it) when a small bead's centre
        # is the more mobile (R = 30 nm: zeta_c = 5.0 against 41.9 pN ns/nm; until
        # 2026-12-03 the step ignored it and the 30 nm braid went NaN in 100 steps)
        mu_c = 1.0 / zeta_center
        kit.add_force(stretch_force([att, (att[0], center), (att[1], center)], d.k_bond,
                                    [self.tether_separation_nm, R, R], name="link"), "link",
                      rate=max(3 * d.k_bond * mu, 4 * d.k_bond * mu_c))
        near = {int(c[-1]) for c in chains} | {int(c[-2]) for c in chains}
        dna = [int(i) for c in chains for i in c[1:] if int(i) not in near]
        kit.add_force(bead_exclusion_force(center, dna, R + 0.5 * d.diameter_nm, d.wall_k,
                                           name="beadwall"), "beadwall",
                      rate=d.wall_k * (mu + mu_c))
        kit.bound("stretch", "bend", "wca", "chiral")
        kit.bound("wall", "stretch")
        kit.bound("trap", "link")
        kit.bound("link", "beadwall")
        kit.attachments = att
        kit.bead_center = center
        if self.mc_moves > 0:
            # the LocalEnergy is built from the finished System at the first call
            kit.moves = BraidMoves(kit.system, chains, kit.fixed, center, d.kT,
                                   moves_per_call=self.mc_moves, **self.move_settings())
        return {"bead_center": center, "zeta_center_pN_ns_per_nm": zeta_center,
                "zeta_attach_pN_ns_per_nm": d.zeta_bead,
                "zeta_bead_physical_pN_ns_per_nm": zeta_phys,
                "wall_k_pN_per_nm": d.wall_k if self.surface else 0.0,
                "n_exclusions": n_excl}

    def move_settings(self) -> dict:
        """The scene's move amplitudes, arc lengths, seed and mirror as keyword arguments
        of :class:`~dnabraid.run.chain_moves.BraidMoves` (all but ``moves_per_call``)."""
        return {"crank_angle_rad": self.crank_angle_rad, "bead_move_nm": self.bead_move_nm,
                "shear_nm": self.shear_nm, "shear_z_nm": self.shear_z_nm,
                "twist_rad": self.twist_rad, "sway_rad": self.sway_rad,
                "pivot_rad": self.pivot_rad, "tilt_rad": self.tilt_rad,
                "stretch_eps": self.stretch_eps, "breathe_eps": self.breathe_eps,
                "breathe_max_beads": self.breathe_max_beads,
                "crank_max_beads": self.crank_max_beads, "seed": self.seed,
                "mirror": self.mirror == "image"}

    #: every turn value, n = 0 included, gets a built (overdispersed) start of its own
    builds_turned_start: ClassVar[bool] = True
    strands: ClassVar[int] = 2

    @property
    def noise_sign(self):
        """Signs of the Brownian noise per axis (None = OpenMM's BrownianIntegrator): the
        image of a mirror-coupled pair gets the y -> -y mirror of the original's noise."""
        return {"off": None, "original": (1.0, 1.0, 1.0), "image": (1.0, -1.0, 1.0)}[self.mirror]

    @property
    def mirror_axis(self):
        """1 (y) for the image of a mirror-coupled pair, else None (the run driver minimises
        the image's start in the original's frame and then mirrors it)."""
        return 1 if self.mirror == "image" else None

    @property
    def pack_along_line(self) -> bool:
        """Mirror-coupled pairs pack along x, which keeps the image pack the exact mirror of
        the original's."""
        return self.mirror != "off"

    def start(self, model, segment) -> np.ndarray:
        """The built start at the segment's start turns (:meth:`start_positions`)."""
        return self.start_positions(model, segment.start_turns)

    def start_positions(self, model, turns: float) -> np.ndarray:
        """The built start at ``turns`` (:meth:`built_start`); for the image of a
        mirror-coupled pair, the y -> -y mirror of the original's start at ``-turns`` (the
        tethers lie on the x axis, so the mirror is a state of the same system, with
        catenation and bead angle negated)."""
        turns = float(turns)
        if self.mirror == "image":
            pos = self.built_start(model, -turns)
            pos[:, 1] = -pos[:, 1]
            return pos
        return self.built_start(model, turns)

    def built_start(self, model, turns: float) -> np.ndarray:
        """A braid already at catenation ``turns``: each point starts there (no ramp).

        The strands run as a symmetric two-ply whose half-separation r(u) shrinks from the
        tethers' s/2 to 0.6 d (just apart at contact) over the braid (u = z/H in [0, 1],
        r = s/2 - (s/2 - r_c) w(u), w the smoothstep of min(1, 3 sin(pi u))) while the chord angle winds in
        proportion to w, flat at both ends, so the chord at the top is turned by n turns; the height H is chosen so that each strand's contour is
        L, and beads are placed every b along it. The bead centre sits above the
        attachments. The run driver then minimises with the trap at n (no strand passage: the
        excluded volume keeps the catenation), and the replicas' noise does the rest.
        """
        n = float(turns)
        # overdispersed starts (each replica's own, from its seed): the braid's plateau
        # steepness c and a bow of the braid's axis (amplitude a L sin(pi u) w(u) in a random
        # direction; at n = 0, a L sin(pi u) across the strands' plane), so that the
        # replicas' disagreement (R-hat) can reveal a start the run has not forgotten
        # (Gelman & Rubin 1992 ask for starts overdispersed relative to the target). A draw
        # that cannot be built, or whose strands' bond lengths would spread by more than
        # 10 %, is drawn again from the same stream (never replaced by a shared start: the
        # replicas' starts stay their own, so R-hat compares replicas that began apart).
        # start_spread = 0 gives the common start (c = 3, no bow) to every replica.
        if self.start_spread == 0.0:
            return self._two_ply(model, n, 3.0, 0.0, 0.0)[0]
        rng = np.random.default_rng([int(self.seed), 0xB4A1D])
        worst = None
        for _ in range(MAX_START_DRAWS):
            c = 3.0 + self.start_spread * (rng.uniform(2.5, 6.0) - 3.0)
            a = self.start_spread * rng.uniform(0.0, MAX_START_BOW)
            psi = rng.uniform(0.0, 2 * np.pi)
            try:
                pos, spread = self._two_ply(model, n, c, a, psi)
            except SceneError as exc:
                worst = str(exc)
                continue
            if spread <= 0.1:
                return pos
            worst = f"bond lengths spread by {100 * spread:.0f} % (> 10 %)"
        raise StartError(f"turns={n:g}: no start of {MAX_START_DRAWS} draws could be built "
                         f"(last: {worst})")

    def _two_ply(self, model, n, c, a, psi):
        """Positions of the built start, and the relative spread of its bond lengths."""
        d = model.dna.diameter_nm
        half = 0.5 * self.tether_separation_nm
        rc = min(0.6 * d, half)
        L, nb = self.length_nm, self.n_beads
        u = np.linspace(0.0, 1.0, 4001)
        t = np.clip(c * np.sin(np.pi * u), 0.0, 1.0)
        w = t * t * (3.0 - 2.0 * t)  # smooth: 0 at the ends, 1 over the braid
        r = half - (half - rc) * (w if n != 0.0 else 0.0)
        phi = np.r_[0.0, np.cumsum(0.5 * (w[1:] + w[:-1]))]
        phi = 2 * np.pi * n * phi / phi[-1]
        if n == 0.0:  # strands apart: a bow across their plane keeps their lengths equal
            psi = np.pi / 2 if np.cos(psi) >= 0 else -np.pi / 2
            bow = a * L * np.sin(np.pi * u)
        else:  # bow the braided part only
            bow = a * L * np.sin(np.pi * u) * w

        def strand(H, offset):
            return np.c_[r * np.cos(phi + offset) + bow * np.cos(psi),
                         r * np.sin(phi + offset) + bow * np.sin(psi), H * u]

        def length(H):
            return max(float(np.sum(np.linalg.norm(np.diff(strand(H, off), axis=0), axis=1)))
                       for off in (0.0, np.pi))

        if length(0.0) >= L:
            raise SceneError(f"turns={n:g}: a two-ply of {L} nm strands cannot hold {n:g} "
                             f"turns at separation {2 * rc:.2f} nm")
        lo, hi = 0.0, L
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if length(mid) < L else (lo, mid)
        pos = model.positions.copy()
        spacing = []
        for ch, off in zip(model.chains, (np.pi, 0.0)):
            x = strand(lo, off)
            sarc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
            tt = np.linspace(0.0, sarc[-1], nb)
            pos[ch] = np.c_[[np.interp(tt, sarc, x[:, k]) for k in range(3)]].T
            spacing.append(sarc[-1] / (nb - 1))
        att = model.attachments
        R = self.bead_radius_nm
        pos[model.bead_center] = (pos[att].mean(axis=0)
                                           + np.array([0.0, 0.0, np.sqrt(R * R - half * half)]))
        return pos, 1.0 - min(spacing) / max(spacing)

    def observables(self, model) -> list:
        att = model.attachments
        return [ob.Extension(att),
                ob.BeadAngle((att[0], att[1]), self.trap_stiffness_pN_nm, self.turn_rate),
                ob.TrapTorque(self.trap_stiffness_pN_nm), ob.Catenation(model.chains)] \
            + self.strand_torque(model) + self.spread_torque(model) \
            + self.strand_distance(model)

    def strand_distance(self, model) -> list:
        """With the capsule contact: the strands' distance in the braid's middle and the
        mean chiral weight there (:class:`dnabraid.observables.StrandDistance`; the weight
        of the contact distance D_c, the capsules' own)."""
        if self.contact != "capsules":
            return []
        from ..forces.reference_chiral import ChiralKernel

        d = model.dna
        return [ob.StrandDistance(model.chains, ChiralKernel(d.diameter_nm, d.debye_nm))]

    def spread_torque(self, model) -> list:
        """The strands' torque on the top with the turn spread along them
        (:class:`dnabraid.observables.SpreadTorque`: equal in mean to the trap torque, its
        bonds' noise averaged along the braid), for every contact and alpha."""
        att = model.attachments
        return [ob.SpreadTorque(model, model.chains, [model.bead_center, att[0], att[1]],
                                model.bead_center)]

    def strand_torque(self, model) -> list:
        """The strands' torque on the top (:class:`dnabraid.observables.StrandTorque`, the
        trap torque's control variate) where the compiled local energies hold every term
        (no chiral term, bead contact)."""
        if self.alpha != 0.0 or getattr(self, "contact", "beads") != "beads":
            return []
        att = model.attachments
        return [ob.StrandTorque(model, [model.bead_center, att[0], att[1]])]

    def notes(self, model) -> list[str]:
        p = model.params
        return self.bead_notes(p["zeta_center_pN_ns_per_nm"],
                               p["zeta_bead_physical_pN_ns_per_nm"])

    def default_short_run(self) -> dict:
        # the default turn rate: 1e-3 turns/step tears the last bond at the bead
        return {"steps": 2000, "equilibration_steps": 500, "turns": [0.0, 1.0],
                "frame_interval": 500}
