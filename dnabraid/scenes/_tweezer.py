"""What the magnetic-tweezer scenes (braid, tether, plectoneme) share: keys, checks, run.

A tweezer scene builds DNA strands between a surface and a magnetic bead with the chain
kit (:mod:`dnabraid.chains`), adds its own attachments in :meth:`TweezerScene.attach`,
names its observables, and runs the turn schedule (:mod:`dnabraid.protocols`) with the
runner (:mod:`dnabraid.runner`), streaming into the run directory (:mod:`dnabraid.rundir`).
"""

from __future__ import annotations

import abc
import dataclasses
import math
import os
import time
from typing import ClassVar

import numpy as np

from .. import forcefield, reporters, rundir
from ..chains import (
    MIN_PASSAGE_BARRIER_KT,
    ChainKit,
    Model,
    max_bead_spacing_nm,
    passage_barrier_kT,
)
from ..engine import INTEGRATORS, MAX_SEED, Engine, check_platform
from ..forces.chiral import chiral_force
from ..protocols import TurnSchedule
from ..runner import run_schedule
from .base import DNAQuantities, Scene, SceneError, key, resolve_salt_alpha

#: Largest number of DNA beads a tweezer scene may have (memory and time stay sane).
MAX_BEADS = 20000
#: Most replicas per point; replica r of seed s runs integrator stream s x MAX_REPLICAS + r.
MAX_REPLICAS = 64

UNITS = {"extension": "nm", "torque": "pN nm (torque the trap applies; > 0 holds n > 0)",
         "catenation": "turns (Gauss linking number, strands closed by vertical rays)",
         "sem": "standard error of the mean, autocorrelation-corrected (Sokal window)"}


#: Help of the ``pack`` key (tweezer scenes and the catenane).
PACK_HELP = ("replicas packed into one OpenMM Context (one System of non-interacting copies, "
             "dnabraid.packing; the chiral term is built over all copies, mirror pairs pack "
             "along x). 2 x 60 nm braid: 1.8x faster at 2, 2.9x at 4, 4.2x at 8 "
             "(workflows/results/benchmark_replicas_small.txt). 0 = replicas / workers, "
             "1 = off")


def _default_turns():
    return (-4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0)


_MECH = forcefield.mechanics()


@dataclasses.dataclass(frozen=True)
class TweezerScene(DNAQuantities, Scene):
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
                          "bias (workflows/results/integrator_bias.md)")

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
        need(self.report_interval >= 1, "report_interval", "must be >= 1")
        need(self.steps >= self.report_interval, "steps",
             f"must be >= report_interval={self.report_interval}")
        need(self.equilibration_steps >= 0, "equilibration_steps", "must be >= 0")
        need(self.frame_interval >= self.report_interval
             and self.frame_interval % self.report_interval == 0, "frame_interval",
             f"must be a multiple of report_interval={self.report_interval}")
        need(self.diameter_nm >= 0, "diameter_nm", "must be >= 0 (0 = from salt)")
        need(self.stretch_modulus_pN > 10 * self.force_pN, "stretch_modulus_pN",
             "must be much larger than the force (> 10 x force_pN)")
        need(self.stretch in ("bonds", "constraints"), "stretch",
             "allowed: 'bonds', 'constraints'")
        need(self.bead_radius_nm > 0, "bead_radius_nm", "must be > 0")
        need(0 < self.bead_friction_factor <= 1, "bead_friction_factor", "must be in (0, 1]")
        need(0 < self.timestep_safety <= 0.9, "timestep_safety", "must be in (0, 0.9]")
        need(0 <= self.seed <= MAX_SEED // MAX_REPLICAS, "seed",
             f"must be in [0, {MAX_SEED // MAX_REPLICAS}] (replica r runs seed x "
             f"{MAX_REPLICAS} + r)")
        need(1 <= self.replicas <= MAX_REPLICAS, "replicas", f"must be in [1, {MAX_REPLICAS}]")
        need(self.protocol in ("independent", "ramp"), "protocol",
             "allowed: 'independent', 'ramp'")
        need(self.workers >= 0, "workers", "must be >= 0 (0 = one per usable core)")
        need(self.target_sem_nm >= 0, "target_sem_nm", "must be >= 0 (0 = no target)")
        need(self.target_sem_pN_nm >= 0, "target_sem_pN_nm", "must be >= 0 (0 = no target)")
        need(self.replicas <= self.max_replicas <= MAX_REPLICAS, "max_replicas",
             f"must be in [replicas={self.replicas}, {MAX_REPLICAS}]")
        need(0 <= self.pack <= MAX_REPLICAS, "pack", f"must be in [0, {MAX_REPLICAS}] (0 = auto)")
        need(self.integrator in INTEGRATORS, "integrator", f"allowed: {', '.join(INTEGRATORS)}")
        need(abs(self.alpha) <= 50.0, "alpha",
             "|alpha| must be <= 50 pN (~12 kT/nm; literature estimates are 0.01-1.5 pN, "
             "forcefields/chiral.toml)")
        if self.needs_passage_barrier or self.length_nm > 3 * self.persistence_nm:
            self.check_passage_barrier()

    def check_passage_barrier(self) -> None:
        """Strands must not pass through each other (the barrier includes bond stretch)."""
        d = self.effective_diameter_nm
        k_kT = None
        if self.stretch == "bonds":
            k_kT = self.stretch_modulus_pN / self.bead_spacing_nm / self.kT
        barrier = passage_barrier_kT(self.bead_spacing_nm, d, k_kT)
        if barrier >= MIN_PASSAGE_BARRIER_KT:
            return
        s_kT = None if k_kT is None else self.stretch_modulus_pN / self.kT
        self.need(False, "bead_spacing_nm",
                  f"too coarse for the effective DNA diameter {d:.2f} nm at {self.salt_mM} mM "
                  f"salt: strands could pass through each other (barrier {barrier:.1f} kT < "
                  f"{MIN_PASSAGE_BARRIER_KT} kT, bond stretch included). Use bead_spacing_nm "
                  f"<= {max_bead_spacing_nm(d, s_kT):.2f}")

    # -- build ---------------------------------------------------------------------------
    def build(self) -> Model:
        """The OpenMM model: DNA from the chain kit, then this scene's attachments."""
        kit = ChainKit(self.dna())
        params = self.attach(kit)
        if self.alpha != 0.0:
            # Kornyshev chiral term between facing segments (docs/chirality.md); left out at
            # alpha = 0. Its curvature per unit alpha is at most ~0.1 A / lambda_D^2 per nm
            # of partner (A ~ 1/(2 Delta)), summed over ~2 Delta of partner and both ends.
            d = kit.dna

            def make_chiral(chains, d=d, alpha=self.alpha):
                return chiral_force(chains, alpha, delta_nm=d.diameter_nm, debye_nm=d.debye_nm,
                                    bead_spacing_nm=d.bead_spacing_nm, name="chiral")

            kit.add_force(make_chiral(kit.chains), "chiral",
                          rate=abs(self.alpha) * 0.1 / d.debye_nm**2 * 4.0 / d.zeta_bead)
            # the chiral term is a PythonForce, which cannot be copied: packed replicas
            # (dnabraid.packing) build one over every copy's strands instead
            kit.extra["rebuild_forces"] = {"chiral": (make_chiral, [c.copy() for c in
                                                                   kit.chains])}
        params["alpha_pN"] = self.alpha
        return kit.finish(self, safety=self.timestep_safety, params=params)

    @abc.abstractmethod
    def attach(self, kit: ChainKit) -> dict:
        """Add strands and attachments to ``kit`` (setting ``kit.attachments`` and, where
        they exist, ``kit.sides``, ``kit.bead_orientation``, ``kit.extra``); return the
        numbers to record in the model's params."""

    @abc.abstractmethod
    def observables(self, model: Model) -> list:
        """The observables of a run, in the order they are computed."""

    def schedule(self) -> TurnSchedule:
        return TurnSchedule(self.turns, turn_rate=getattr(self, "turn_rate", None)
                            if self.trap_parameter else None,
                            equilibration_steps=self.equilibration_steps,
                            sample_steps=self.steps, report_interval=self.report_interval,
                            mode=self.protocol, built_start=self.builds_turned_start)

    #: True when :meth:`start_positions` builds a start at any turn value.
    builds_turned_start: ClassVar[bool] = False

    def start_positions(self, model: Model, turns: float):
        """Positions (nm) of a start at ``turns`` (scenes with ``builds_turned_start``)."""
        raise SceneError(f"scene {self.name!r} builds no start at a turn value")

    # -- run -----------------------------------------------------------------------------
    def notes(self, model: Model) -> list[str]:
        return []

    def units(self) -> dict:
        return dict(UNITS)

    #: Observables whose convergence decides a point's verdict.
    verdict_observables: ClassVar[tuple] = ("extension_nm", "torque_pN_nm")
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

    def pack_groups(self, replicas, workers: int, platform: str, model) -> list[tuple]:
        """Replicas grouped into packs (:func:`replica_groups`)."""
        return replica_groups(self, replicas, workers, platform, model)

    def replica_seed(self, r: int) -> int:
        return self.seed * MAX_REPLICAS + r

    def summarise(self, series: list) -> dict:
        """Mean and error of one observable from its per-replica series."""
        series = [np.asarray(x, float) for x in series]
        if not series or any(x.size == 0 or not np.all(np.isfinite(x)) for x in series):
            return {"mean": None, "sem": None}
        if len(series) == 1:
            d = reporters.mean_sem_entry(series[0])
            d.update(converged=False, reason="one replica: no between-replica check",
                     n_replicas=1)
            return d
        from ..analysis.convergence import replica_summary

        r = replica_summary(series, **self.verdict_rule())
        return {"mean": float(r["mean"]), "sem": float(r["sem"]),
                "ci_halfwidth": float(r["ci_halfwidth"]), "confidence": r["confidence"],
                "n_replicas": int(r["n_replicas"]), "sem_within": float(r["sem_within"]),
                "rhat": float(r["rhat"]), "ess": float(r["ess"]),
                "equilibration_samples": [int(x) for x in r["equilibration_samples"]],
                "replica_means": [float(x) for x in r["replica_means"]],
                "converged": bool(r["converged"]), "reason": r["reason"]}

    def verdict_rule(self) -> dict:
        """Keyword arguments of :func:`~dnabraid.analysis.convergence.replica_summary`:
        the relaxed R-hat <= 1.05 and ESS >= 100 with a data-driven equilibration."""
        from ..analysis.convergence import MIN_ESS_RELAXED, RHAT_MAX_RELAXED

        return {"rhat_max": RHAT_MAX_RELAXED, "min_ess": MIN_ESS_RELAXED}

    def point_summary(self, reps: list) -> dict:
        """Per turn value, from the replicas' (samples, frames) of that point."""
        s0 = reps[0][0]
        pt = {"turns": float(s0["turns"][0]) if len(s0["turns"]) else None}
        cols = [c for c in s0 if c not in ("turns", "step", "time_ns")]
        for c in cols:
            pt[c] = self.summarise([s[c] for s, _ in reps])
        fcols = [c for c in reps[0][1] if c not in ("turns", "frame", "step", "time_ns")]
        for c in fcols:
            pt[c] = self.summarise([f[c] for _, f in reps])
        for c in ("extension_nm", "torque_pN_nm", "catenation", "bead_angle_turns"):
            pt.setdefault(c, {"mean": None, "sem": None})
        pt["n_samples"] = int(sum(len(s["step"]) for s, _ in reps))
        pt["n_frames"] = int(sum(len(f["step"]) for _, f in reps))
        pt["n_replicas"] = len(reps)
        verdict = [(c, pt[c]) for c in self.verdict_observables if pt[c]["mean"] is not None]
        pt["converged"] = all(v.get("converged", False) for _, v in verdict)
        pt["convergence_reason"] = "; ".join(f"{c}: {v.get('reason', '')}" for c, v in verdict
                                             if not v.get("converged", False)) or "ok"
        pt["effective_sample_size"] = {c: v.get("ess") for c, v in verdict}
        return pt

    def run(self, out: str, *, platform: str = "CPU", threads: int | None = None,
            progress_factory=None) -> dict:
        t0 = time.perf_counter()
        check_platform(platform)
        model = self.build()
        rundir.prepare_out_dir(self, out)
        sched = self.schedule()
        obs = self.observables(model)
        workers = self.workers or _usable_cores()
        results: list = []
        points: list = []
        R = self.replicas
        stopped_by = "replicas"
        while True:
            # run replicas len(results) .. R-1 (all of them the first time)
            groups, nw, jobs = replica_jobs(self, range(len(results), R), workers, platform,
                                            threads, out, model)
            bar = progress_factory(sched.total_steps * (R - len(results))) \
                if progress_factory else None
            try:
                results += [x for res in _run_jobs(jobs, nw, bar) for x in res]
            finally:
                if bar:
                    bar.close()
            points = [self.point_summary([reporters.read_point(r["dirs"][k]) for r in results])
                      for k in range(len(sched))]
            need = self.replicas_needed(points, R)
            if need <= R:
                stopped_by = "target" if self.has_targets() else "replicas"
                break
            if R >= self.max_replicas:
                stopped_by = "budget"
                break
            R = min(need, self.max_replicas)
        wall = time.perf_counter() - t0
        resumed = any(r["resumed"] for r in results)
        total = sched.total_steps * R
        p = model.params
        dt_ns = model.timestep.time_step_ns
        rundir.write_topology(os.path.join(out, "topology.pdb"), model.topology, model.positions)
        sample_cols = {k: v for ob in obs if ob.every == "sample" for k, v in ob.columns.items()}
        frame_cols = {k: v for ob in obs if ob.every == "frame" for k, v in ob.columns.items()}
        reporters.combine(out, [d for r in results for d in r["dirs"]], model.topology,
                          dt_ns * 1e3, self.frame_interval, sample_cols, frame_cols)
        for pt in points:
            pt["precision"] = self.precision_verdict(pt, stopped_by)
        points.sort(key=lambda pt: pt["turns"])
        notes = self.notes(model)
        if resumed:
            notes.append("resumed from checkpoints; wall_time_s counts this invocation only")
        bad = [pt["turns"] for pt in points if not pt["converged"]]
        if bad:
            notes.append(f"NOT CONVERGED at turns {bad}: the replicas disagree more than their "
                         "sampling allows or sampled too few independent configurations "
                         "(see convergence_reason per point); raise `steps` or `replicas`")
        n_part = model.system.getNumParticles()
        notes += packing_notes(sorted({r["pack"] for r in results}))
        summary = rundir.Summary(
            scene=self.to_dict(), wall_time_s=wall, platform=platform,
            time_step_ps=dt_ns * 1e3, time_step_reason=model.timestep.reason,
            relaxation_rates_per_ns=model.timestep.rates_per_ns, total_steps=total,
            steps_per_second=total / wall if not resumed else None,
            ns_per_bead_per_step=(wall / total / n_part * 1e9 * workers) if not resumed
            else None,
            n_particles=n_part, forces=sorted(model.forces),
            effective_diameter_nm=p["diameter_nm"], bending_kappa_kT=p["kappa_kT"],
            units=self.units(), notes=notes, versions=rundir.versions(), points=points,
            seed=self.seed, integrator_seed=results[0]["integrator_seed"])
        rundir.write_summary(os.path.join(out, "summary.json"), summary)
        from .. import plots

        plots.extension_torque_plot(summary.to_dict(), os.path.join(out, "extension_torque.png"))
        return summary.to_dict()

    # -- CLI and sweeps ------------------------------------------------------------------
    def report(self, summary: dict, out: str, file) -> None:
        print(f"time step {summary['time_step_ps']:.4g} ps: {summary['time_step_reason']}",
              file=file)
        for n in summary["notes"]:
            print(f"note: {n}", file=file)
        print(f"{'turns':>7} {'extension_nm':>20} {'torque_pN_nm':>20} {'catenation':>18}",
              file=file)

        def fmt(d, p=2):
            if d["mean"] is None:
                return "-"
            sem = d["sem"]
            if sem and sem > 0 and math.isfinite(sem):  # two significant digits of the SEM
                p = min(4, max(p, 1 - math.floor(math.log10(sem))))
            return f"{d['mean']:.{p}f} +- {sem:.{p}f}"

        for pt in summary["points"]:
            mark = "" if pt.get("converged", True) else "  NOT CONVERGED"
            print(f"{pt['turns']:>7g} {fmt(pt['extension_nm'], 1):>20} "
                  f"{fmt(pt['torque_pN_nm'], 1):>20} {fmt(pt['catenation'], 3):>18}{mark}",
                  file=file)
        print("+- : standard error of the mean across independent replicas (Student-t 95% "
              "intervals in summary.json)", file=file)
        pts = summary["points"]
        if pts and all(pt.get("converged", False) for pt in pts):
            ess = min(v for pt in pts for v in pt.get("effective_sample_size", {}).values()
                      if v is not None)
            print(f"all {len(pts)} points converged (split R-hat and bulk ESS across "
                  f"replicas; smallest ESS {ess:.0f})", file=file)
        if self.has_targets():
            pr = summary["points"][0]["precision"]
            met = all(all(pt["precision"]["met"].values()) for pt in summary["points"])
            print(f"precision targets {pr['targets']}: "
                  + ("met" if met else f"NOT met, the budget of {self.max_replicas} replicas "
                     "ended")
                  + f" ({pr['n_replicas']} replicas per point)", file=file)
        print(f"wall time {summary['wall_time_s']:.1f} s on {summary['platform']}; results in "
              f"{out}/", file=file)

    row_columns: ClassVar[tuple] = ("turns", "extension_nm", "extension_sem_nm", "torque_pN_nm",
                                    "torque_sem_pN_nm", "catenation", "catenation_sem",
                                    "n_samples")

    def rows(self, summary: dict) -> list[dict]:
        out = []
        for pt in summary["points"]:
            out.append({"turns": pt["turns"],
                        "extension_nm": pt["extension_nm"]["mean"],
                        "extension_sem_nm": pt["extension_nm"]["sem"],
                        "torque_pN_nm": pt["torque_pN_nm"]["mean"],
                        "torque_sem_pN_nm": pt["torque_pN_nm"]["sem"],
                        "catenation": pt["catenation"]["mean"],
                        "catenation_sem": pt["catenation"]["sem"],
                        "n_samples": pt["n_samples"]})
        return out

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


# ------------------------------------------------------------------------------ replicas
def replica_groups(scene, replicas, workers: int, platform: str, model) -> list[tuple]:
    """Replicas grouped into packs (one OpenMM Context each): ``scene.pack`` per group, or
    with ``pack = 0`` as many as spread the replicas evenly over the workers; one per group
    when the scene cannot be packed (a force that cannot be copied, unless the model says
    how to rebuild it over all copies, as the chiral term does). Mirror-coupled pairs pack
    along x (``pack_models(line=True)``), which keeps the image pack the exact mirror of
    the original's."""
    from ..packing import group_replicas, packable

    can = packable(model.system, model.extra.get("rebuild_forces"))[0]
    return group_replicas(replicas, scene.pack, workers, platform, can)


def replica_jobs(scene, replicas, workers: int, platform: str, threads, out: str, model):
    """(groups, worker processes, jobs) for :func:`_run_jobs`: one job per pack."""
    groups = replica_groups(scene, replicas, workers, platform, model)
    nw = max(1, min(workers, len(groups))) if platform == "CPU" else 1
    jobs = [(scene.to_dict(), g, out, platform, threads if nw == 1 else 1) for g in groups]
    return groups, nw, jobs


def packing_notes(groups) -> list[str]:
    """The summary note saying how replicas were packed (none when each ran alone)."""
    if not any(len(g) > 1 for g in groups):
        return []
    return [f"replicas packed into {len(groups)} OpenMM Context(s) of "
            f"{', '.join(str(len(g)) for g in groups)} non-interacting copies (key `pack`; "
            "each replica keeps its own start, checks and files)"]


def _usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def _run_replica(scene_dict, group, out, platform, threads, progress) -> list[dict]:
    """Run the replicas ``group`` of a scene: alone in its own Context (one replica), or
    packed into one Context (:mod:`dnabraid.packing`); each writes ``out/replicas/rNN``."""
    from ..packing import pack_models
    from ..runner import Member, run_packed
    from . import make_scene

    d = dict(scene_dict)
    name = d.pop("scene")
    base = make_scene(name, d)
    members, scenes = [], []
    for r in group:
        scene = dataclasses.replace(base, seed=base.replica_seed(r))
        scenes.append(scene)
        model = scene.build()
        rdir = os.path.join(out, "replicas", f"r{r:02d}")
        ctx = {"trap_parameter": scene.trap_parameter,
               "trap_stiffness": getattr(scene, "trap_stiffness_pN_nm", None),
               "turn_rate": getattr(scene, "turn_rate", None),
               "minimise": not model.extra.get("exact_start", False),
               "start_positions": (lambda sc, mo: lambda t: sc.start_positions(mo, t))(scene,
                                                                                        model)}
        members.append(Member(model, scene.observables(model), rdir, ctx, label=f"replica {r}"))
    first = scenes[0]
    if len(group) == 1:
        m = members[0]
        engine = Engine(m.model, platform=platform, seed=first.seed, threads=threads,
                        integrator=first.integrator)
        resumed = os.path.isdir(os.path.join(m.out, "checkpoints"))
        os.makedirs(m.out, exist_ok=True)
        dirs = [run_schedule(m.model, engine, first.schedule(), m.observables, m.out,
                             ctx=m.ctx, progress=progress)]
    else:
        pack = pack_models([m.model for m in members],
                           line=getattr(first, "mirror", "off") != "off")
        engine = Engine(pack.model, platform=platform, seed=first.seed, threads=threads,
                        integrator=first.integrator)
        pdir = os.path.join(out, "replicas", f"pack_r{group[0]:02d}-r{group[-1]:02d}")
        resumed = os.path.isdir(os.path.join(pdir, "checkpoints"))
        for m in members:
            os.makedirs(m.out, exist_ok=True)
        dirs = run_packed(pack, engine, first.schedule(), members, pdir, progress=progress)
    return [{"dirs": ds, "integrator_seed": engine.seed, "resumed": resumed,
             "pack": tuple(group)} for ds in dirs]


def _worker(args):
    k, job, queue = args
    pin_to_one_core_of(k)  # job k of the batch on core k mod cores
    acc = [0]

    def progress(n):  # batch the messages: one per >= 20000 steps
        acc[0] += n
        if acc[0] >= 20000:
            queue.put(acc[0])
            acc[0] = 0

    try:
        res = _run_replica(*job, progress)
        queue.put(acc[0])
        return res
    except Exception as exc:  # hand the failure to the parent intact
        return {"error": exc}


def pin_to_one_core_of(r: int) -> None:
    """Pin a worker process to one usable core, job r to core r mod n."""
    try:
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[r % len(cores)]})
    except (AttributeError, OSError):  # pragma: no cover
        pass


def _run_jobs(jobs, workers: int, bar) -> list:
    """Run replica jobs, ``workers`` processes at a time (serially in-process for 1)."""
    upd = bar.update if bar else None
    # a job: (scene dict, replica group, run directory, platform, threads); its result:
    # one dict per replica of the group
    if workers <= 1:
        return [_run_replica(*job, upd) for job in jobs]
    import multiprocessing as mp
    import queue as _queue

    ctx = mp.get_context("spawn")
    with ctx.Manager() as mgr:
        q = mgr.Queue()
        with ctx.Pool(workers) as pool:
            res = pool.map_async(_worker, [(k, job, q) for k, job in enumerate(jobs)])
            while not res.ready():
                try:
                    n = q.get(timeout=0.5)
                    if upd:
                        upd(n)
                except _queue.Empty:
                    pass
            out = res.get()
            while upd:
                try:
                    upd(q.get_nowait())
                except _queue.Empty:
                    break
    for r in out:
        if isinstance(r, dict) and "error" in r:
            raise r["error"]
    return out
