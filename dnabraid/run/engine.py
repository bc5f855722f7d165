"""Engine: Context, platform, Brownian integrator, time step, blow-up guards, state I/O.

The engine takes a finished OpenMM ``System`` and :class:`IntegratorSettings` (as OpenMM's
``Simulation`` takes a System and an integrator); it knows no scene. :meth:`Engine.for_model`
builds one from a :class:`dnabraid.chains.Model`.
"""

from __future__ import annotations

import dataclasses
import logging
import os

import numpy as np
import openmm
from openmm import unit as u

from .. import units
from ..errors import DnabraidError, UserError
from .workers import usable_cores

log = logging.getLogger(__name__)

#: Friction coefficient handed to OpenMM's BrownianIntegrator; per-particle friction is
#: carried by the masses (D = kT / (m gamma)), see :func:`dnabraid.units.friction_to_mass_amu`.
GAMMA_PER_PS = 1.0
#: A bond longer than this multiple of its rest length means the integration blew up.
MAX_BOND_STRETCH = 1.5


#: Largest scene seed: OpenMM takes seeds in [1, 2^31 - 1] (0 means "pick one at random").
MAX_SEED = 2**31 - 2


def integrator_seed(seed: int) -> int:
    """OpenMM seed of a scene seed: seed + 1, one-to-one on [0, MAX_SEED].

    (The earlier ``seed % (2^31 - 1) or 1`` gave seeds 0, 1 and 2^31 - 1 the same stream.)
    """
    seed = int(seed)
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be in [0, {MAX_SEED}], got {seed}")
    return seed + 1


#: Boltzmann constant in kJ/(mol K) (OpenMM's energy unit).
KB_KJ_PER_MOL_K = 0.0083144626181532

#: Brownian integrators a scene may choose.
INTEGRATORS = ("euler", "lm", "mala")


def euler_maruyama_integrator(temperature_K: float, dt_ps: float, masses_amu,
                              gamma_per_ps: float = 1.0,
                              noise_sign=(1.0, 1.0, 1.0)) -> openmm.CustomIntegrator:
    """Overdamped Langevin by Euler-Maruyama as a ``CustomIntegrator``, with signed noise.

    x_{n+1} = x_n + dt mu F(x_n) + sqrt(2 kT mu dt) s xi_n, the scheme of OpenMM's
    ``BrownianIntegrator`` (same mobility mu = 1 / (m gamma) per particle), with a sign
    ``s`` per Cartesian component. ``s = (1, -1, 1)`` drives the mirror image (y -> -y) of
    the trajectory that ``s = (1, 1, 1)`` drives with the same seed: the two members of a
    mirror-coupled pair (:mod:`dnabraid.analysis.mirror`). The random stream differs from
    ``BrownianIntegrator``'s, so both members of a pair use this integrator.
    """
    integ = openmm.CustomIntegrator(dt_ps)
    integ.addGlobalVariable("kT", KB_KJ_PER_MOL_K * float(temperature_K))
    integ.addPerDofVariable("mob", 0.0)
    integ.addPerDofVariable("sgn", 1.0)
    integ.addUpdateContextState()
    integ.addComputePerDof("x", "x + dt*mob*f + sqrt(2*kT*mob*dt)*sgn*gaussian")
    integ.addConstrainPositions()
    _set_mobility_and_sign(integ, masses_amu, gamma_per_ps, noise_sign)
    return integ


def _set_mobility_and_sign(integ, masses_amu, gamma_per_ps, noise_sign) -> None:
    mob = [openmm.Vec3(*(3 * [0.0 if m == 0 else 1.0 / (m * gamma_per_ps)])) for m in masses_amu]
    integ.setPerDofVariableByName("mob", mob)
    sg = openmm.Vec3(*(float(c) for c in noise_sign))
    integ.setPerDofVariableByName("sgn", [sg] * len(mob))


def leimkuhler_matthews_integrator(temperature_K: float, dt_ps: float, masses_amu,
                                   gamma_per_ps: float = 1.0,
                                   noise_sign=(1.0, 1.0, 1.0)) -> openmm.CustomIntegrator:
    """Overdamped Langevin by the Leimkuhler-Matthews scheme (a ``CustomIntegrator``).

    x_{n+1} = x_n + dt mu F(x_n) + sqrt(2 kT mu dt) (xi_n + xi_{n+1}) / 2, with the
    mobility mu = 1 / (m gamma) per particle (the masses carry the friction, as for OpenMM's
    ``BrownianIntegrator``) and xi standard normal, the same draw used in two consecutive
    steps. Its invariant measure is exact for harmonic forces and has O(dt^2) error in
    general, against O(dt) for Euler-Maruyama, for the same one force evaluation per step
    (Leimkuhler, Matthews & Stoltz, IMA J. Numer. Anal. 36, 13 (2016), Eq. 3.4; Leimkuhler
    & Matthews, Appl. Math. Res. Express 2013, 34). Immobile (massless) particles do not move.
    """
    integ = openmm.CustomIntegrator(dt_ps)
    kT = KB_KJ_PER_MOL_K * float(temperature_K)
    integ.addGlobalVariable("kT", kT)
    integ.addPerDofVariable("mob", 0.0)
    integ.addPerDofVariable("xi_old", 0.0)
    integ.addPerDofVariable("xi", 0.0)
    integ.addPerDofVariable("sgn", 1.0)
    integ.addGlobalVariable("started", 0.0)
    integ.beginIfBlock("started = 0")
    integ.addComputePerDof("xi_old", "gaussian")
    integ.addComputeGlobal("started", "1")
    integ.endBlock()
    integ.addUpdateContextState()
    integ.addComputePerDof("xi", "gaussian")
    integ.addComputePerDof("x", "x + dt*mob*f + sqrt(0.5*kT*mob*dt)*sgn*(xi + xi_old)")
    integ.addConstrainPositions()
    integ.addComputePerDof("xi_old", "xi")
    _set_mobility_and_sign(integ, masses_amu, gamma_per_ps, noise_sign)
    return integ


def mala_integrator(temperature_K: float, dt_ps: float, masses_amu,
                    gamma_per_ps: float = 1.0,
                    noise_sign=(1.0, 1.0, 1.0)) -> openmm.CustomIntegrator:
    """Metropolis-adjusted Brownian dynamics (a ``CustomIntegrator``): no time-step bias.

    Each step proposes the Euler-Maruyama step y = x + dt mu F(x) + sqrt(2 kT mu dt) s xi
    (mu = 1 / (m gamma) per particle, as OpenMM's ``BrownianIntegrator``) and accepts it
    with probability min(1, exp(-(U(y) - U(x)) / kT) q(x | y) / q(y | x)), where
    q(y | x) ~ exp(-|y - x - dt mu F(x)|^2 / (4 kT mu dt)) is the proposal's Gaussian
    density (per degree of freedom, with its own mu); otherwise x is kept. This is
    Rossky, Doll & Friedman's "smart Monte Carlo" (J. Chem. Phys. 69, 4628 (1978),
    Eqs. 6-10), known in statistics as MALA (Roberts & Tweedie, Bernoulli 2, 341 (1996)):
    the chain is reversible with respect to exp(-U / kT) for every dt, so equilibrium
    averages carry no time-step bias at all; dt sets only the acceptance and how fast the
    chain moves. Immobile (massless) particles do not move and do not enter q. A proposal
    whose energy is not finite (a blow-up) is rejected.

    The acceptance ratio needs the total energy at both points: one force-and-energy
    evaluation per step at the proposal (the current point's energy and forces are kept
    from the last accepted step; ``stale`` = 1, set by :meth:`Engine.positions_changed`,
    makes the next step recompute them after positions or parameters were changed from
    outside; positions set from outside are detected in the step itself). Counters
    ``n_try`` / ``n_acc`` give the acceptance. All replicas of a packed Context share one
    accept/reject (the joint chain is exact; its acceptance is the product of the
    replicas'). Constraints are not allowed (the proposal density would need the
    constraint manifold's).
    """
    integ = openmm.CustomIntegrator(dt_ps)
    kT = KB_KJ_PER_MOL_K * float(temperature_K)
    integ.addGlobalVariable("kT", kT)
    for g in ("E0", "E1", "lnfwd", "lnrev", "acc", "n_try", "n_acc"):
        integ.addGlobalVariable(g, 0.0)
    integ.addGlobalVariable("stale", 1.0)
    integ.addPerDofVariable("mob", 0.0)
    integ.addPerDofVariable("imob", 0.0)  # 1 / mob, 0 for immobile dofs
    integ.addPerDofVariable("sgn", 1.0)
    integ.addPerDofVariable("x0", 0.0)
    integ.addPerDofVariable("fk", 0.0)
    integ.addPerDofVariable("xi", 0.0)
    integ.addPerDofVariable("xe", 0.0)  # positions at the end of the last step
    integ.addGlobalVariable("moved", 0.0)
    integ.addUpdateContextState()
    # positions set from outside since the last step (Metropolis moves, a new state) make
    # the kept energy and forces stale without any call: detected here
    integ.addComputeSum("moved", "(x - xe)^2")
    integ.beginIfBlock("stale + moved > 0")
    integ.addComputeGlobal("E0", "energy")
    integ.addComputePerDof("fk", "f")
    integ.addComputeGlobal("stale", "0")
    integ.endBlock()
    integ.addComputePerDof("x0", "x")
    integ.addComputePerDof("xi", "gaussian")
    integ.addComputePerDof("x", "x0 + dt*mob*fk + sqrt(2*kT*mob*dt)*sgn*xi")
    integ.addComputeGlobal("E1", "energy")
    integ.addComputeSum("lnfwd", "0.5*xi*xi*mob*imob")
    integ.addComputeSum("lnrev", "(x0 - x - dt*mob*f)^2*imob/(4*kT*dt)")
    # step(NaN) = 0: a proposal with a non-finite energy is rejected
    integ.addComputeGlobal("acc", "step(exp(-(E1 - E0)/kT + lnfwd - lnrev) - uniform)")
    integ.addComputeGlobal("n_try", "n_try + 1")
    integ.addComputeGlobal("n_acc", "n_acc + acc")
    integ.addComputePerDof("fk", "select(acc, f, fk)")
    integ.addComputeGlobal("E0", "select(acc, E1, E0)")
    integ.addComputePerDof("x", "select(acc, x, x0)")
    integ.addComputePerDof("xe", "x")
    _set_mobility_and_sign(integ, masses_amu, gamma_per_ps, noise_sign)
    imob = [openmm.Vec3(*(3 * [0.0 if m == 0 else m * gamma_per_ps])) for m in masses_amu]
    integ.setPerDofVariableByName("imob", imob)
    return integ


class PlatformError(UserError):
    """The requested OpenMM platform is not available here."""


def check_platform(platform: str) -> None:
    """Raise :class:`PlatformError` unless OpenMM has ``platform`` here."""
    names = available_platforms()
    if platform not in names:
        raise PlatformError(f"platform {platform!r} is not available here; available: "
                            + ", ".join(names))


class SimulationBlowUp(DnabraidError, RuntimeError):
    """The integration went unstable.

    Attributes
    ----------
    step : int
        Step at which it was detected.
    term : str
        Force term with the largest force in the bad state (or the check that failed).
    saved : str or None
        Path of the last good state (OpenMM XML).
    """

    def __init__(self, message, *, step, term, saved=None):
        super().__init__(message)
        self.step = step
        self.term = term
        self.saved = saved

    def __reduce__(self):
        # replicas run in worker processes: the error must survive pickling back to the
        # parent (the default reduce drops the keyword-only arguments and the pool hangs)
        return (_rebuild_blow_up, (str(self), self.step, self.term, self.saved))


def _rebuild_blow_up(message, step, term, saved):
    return SimulationBlowUp(message, step=step, term=term, saved=saved)


def available_platforms() -> list[str]:
    return [openmm.Platform.getPlatform(i).getName() for i in range(openmm.Platform.getNumPlatforms())]


@dataclasses.dataclass(frozen=True)
class IntegratorSettings:
    """How the engine integrates: temperature, time step, scheme and noise signs.

    Attributes
    ----------
    temperature_K : float
    time_step_ns : float
    integrator : str
        'euler' (Euler-Maruyama) or 'lm' (Leimkuhler-Matthews).
    noise_sign : tuple of 3 float or None
        None: OpenMM's BrownianIntegrator for 'euler'; a sign per axis: the signed-noise
        CustomIntegrators (the image of a mirror-coupled pair gets (1, -1, 1)).
    """

    temperature_K: float
    time_step_ns: float
    integrator: str = "euler"
    noise_sign: tuple | None = None

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got "
                             f"{self.integrator!r}")


class Engine:
    """Brownian dynamics of a finished OpenMM System.

    Parameters
    ----------
    system : openmm.System
    positions : ndarray (N, 3), nm
    settings : IntegratorSettings
    bonds : ndarray (n, 2), optional
        Bonds checked after every :meth:`advance` (a bond stretched past
        MAX_BOND_STRETCH x ``bond_length_nm`` is a blow-up).
    bond_length_nm : float
    terms : dict name -> force group, optional
        The force terms a blow-up message may name.
    platform : str
        'CPU' (default), 'Reference', 'CUDA' or 'OpenCL'.
    seed : int
        Seed of the integrator's random numbers.
    threads : int, optional
        CPU platform threads.
    """

    def __init__(self, system: openmm.System, positions, settings: IntegratorSettings, *,
                 bonds=None, bond_length_nm: float = 0.0, terms: dict | None = None,
                 platform: str = "CPU", seed: int = 1, threads: int | None = None):
        self.system = system
        self.settings = settings
        self.terms = dict(terms or {})
        self.dt_ns = settings.time_step_ns
        self.integrator_name = settings.integrator
        self.noise_sign = settings.noise_sign
        self.seed = integrator_seed(seed)
        check_platform(platform)
        self.platform = platform
        self._props = {}
        if platform == "CPU" and self.noise_sign is not None:
            # a mirror-coupled pair must be reproducible to the last bit: with several
            # threads the CPU platform's force sums depend on thread scheduling (measured:
            # one replica pair in three started 0.35 nm apart after minimisation)
            threads = 1
        if platform == "CPU" and not threads and len(usable_cores()) == 1:
            # a process pinned to one core (replica workers, the tests): OpenMM would still
            # start one thread per machine core, which then take turns on that core
            # (measured for the default braid: 2.5-2.8k steps/s with 2 threads, 4.0-4.8k with 1)
            threads = 1
        if platform == "CPU" and threads:
            self._props["Threads"] = str(int(threads))
        if platform in ("CUDA", "OpenCL"):
            self._props["Precision"] = "mixed"
        self._temperature_K = settings.temperature_K
        self._make_context(self.seed)
        self.context.setPositions(np.asarray(positions, float) * u.nanometer)
        self.step = 0
        self._bonds = np.zeros((0, 2), int) if bonds is None else np.asarray(bonds, int)
        self._b = float(bond_length_nm)

    @classmethod
    def for_model(cls, model, *, integrator: str = "euler", noise_sign=None,
                  platform: str = "CPU", seed: int = 1, threads: int | None = None) -> Engine:
        """An engine for a :class:`dnabraid.chains.Model` at its own temperature and time
        step, checking its strands' bonds."""
        settings = IntegratorSettings(model.dna.temperature_K, model.timestep.time_step_ns,
                                      integrator, noise_sign)
        return cls(model.system, model.positions, settings, bonds=model.bonds,
                   bond_length_nm=model.dna.bead_spacing_nm, terms=model.forces,
                   platform=platform, seed=seed, threads=threads)

    def _make_context(self, openmm_seed: int) -> None:
        dt_ps = units.ns_to_ps(self.dt_ns)
        if self.integrator_name == "euler" and self.noise_sign is None:
            integ = openmm.BrownianIntegrator(self._temperature_K * u.kelvin,
                                              GAMMA_PER_PS / u.picosecond, dt_ps * u.picoseconds)
        else:
            sysm = self.system
            masses = [sysm.getParticleMass(i).value_in_unit(u.dalton)
                      for i in range(sysm.getNumParticles())]
            if self.integrator_name == "mala" and sysm.getNumConstraints():
                raise UserError("integrator 'mala' cannot run a system with constraints "
                                f"({sysm.getNumConstraints()}): use stretch = 'bonds'")
            make = {"euler": euler_maruyama_integrator, "lm": leimkuhler_matthews_integrator,
                    "mala": mala_integrator}[self.integrator_name]
            integ = make(self._temperature_K, dt_ps, masses, GAMMA_PER_PS,
                         noise_sign=self.noise_sign or (1.0, 1.0, 1.0))
        integ.setRandomNumberSeed(int(openmm_seed))
        integ.setConstraintTolerance(1e-6)
        self.integrator = integ
        self.context = openmm.Context(self.system, integ,
                                      openmm.Platform.getPlatformByName(self.platform),
                                      self._props)

    def restart(self, stream: int) -> None:
        """A fresh Context whose random numbers are stream ``stream`` of this engine's seed.

        OpenMM seeds its generator only when a Context is made (and a checkpoint restores
        it), so independent points of one run get their own streams this way; the state is
        then set with :meth:`load_state`. The stream is a hash of (seed, stream): distinct
        for every point and replica, and the same when a run is resumed.
        """
        import numpy as np

        h = int(np.random.SeedSequence([self.seed, int(stream)]).generate_state(1)[0])
        self._make_context(h % MAX_SEED + 1)

    def save_state(self, path: str) -> str:
        """Positions and parameters (no random-number state) as OpenMM XML, atomically."""
        st = self.context.getState(getPositions=True, getParameters=True)
        tmp = path + ".tmp"
        with open(tmp, "w") as fh:
            fh.write(openmm.XmlSerializer.serialize(st))
        os.replace(tmp, path)
        return path

    def load_state(self, path: str, step: int = 0) -> None:
        """Set positions and parameters from :meth:`save_state`'s file; the step counter to
        ``step``."""
        with open(path) as fh:
            st = openmm.XmlSerializer.deserialize(fh.read())
        self.context.setPositions(st.getPositions())
        for k, v in st.getParameters().items():
            self.context.setParameter(k, v)
        self.positions_changed()
        self.step = int(step)

    # -- state ---------------------------------------------------------------
    def positions(self) -> np.ndarray:
        st = self.context.getState(getPositions=True)
        return st.getPositions(asNumpy=True).value_in_unit(u.nanometer)

    def set_positions(self, pos_nm) -> None:
        self.context.setPositions(np.asarray(pos_nm) * u.nanometer)
        self.positions_changed()

    def positions_changed(self) -> None:
        """Tell a Metropolis-adjusted integrator ('mala') that the positions or parameters
        were changed from outside, so that it recomputes the current energy and forces
        (no effect for the other integrators)."""
        if self.integrator_name == "mala":
            self.integrator.setGlobalVariableByName("stale", 1.0)

    def mala_acceptance(self) -> tuple[int, int] | None:
        """(accepted, tried) steps of the 'mala' integrator since its Context was made;
        None for the other integrators."""
        if self.integrator_name != "mala":
            return None
        g = self.integrator.getGlobalVariableByName
        return int(round(g("n_acc"))), int(round(g("n_try")))

    def parameters(self) -> dict:
        """The Context's global parameters now (name -> value, OpenMM units)."""
        return {k: float(v) for k, v in self.context.getParameters().items()}

    def forget_noise(self) -> None:
        """Draw the Leimkuhler-Matthews noise memory (``xi_old``) afresh at the next step.

        LM uses each Gaussian draw in two consecutive steps; after a Metropolis move has
        turned or displaced particles, the remembered draw belongs to positions they no
        longer have (a rotated arc keeps its unrotated noise). A fresh, independent draw
        makes the next step an Euler-Maruyama step from the moved state (one step per
        report interval), after which LM proceeds. No effect for Euler-Maruyama.
        """
        if self.integrator_name == "lm":
            self.integrator.setGlobalVariableByName("started", 0.0)

    def set_parameter(self, name: str, value: float) -> None:
        self.context.setParameter(name, float(value))
        self.positions_changed()

    def energy_pN_nm(self, groups=None) -> float:
        kw = {"getEnergy": True}
        if groups is not None:
            kw["groups"] = set(groups)
        e = self.context.getState(**kw).getPotentialEnergy().value_in_unit(u.kilojoule_per_mole)
        return units.energy_from_openmm(e)

    def forces_pN(self, groups=None) -> np.ndarray:
        kw = {"getForces": True}
        if groups is not None:
            kw["groups"] = set(groups)
        f = self.context.getState(**kw).getForces(asNumpy=True)
        return units.force_from_openmm(f.value_in_unit(u.kilojoule_per_mole / u.nanometer))

    def minimise(self, tolerance_pN: float = 1.0, max_iterations: int = 2000) -> None:
        """Local energy minimisation (immobile tethers stay put)."""
        openmm.LocalEnergyMinimizer.minimize(
            self.context, units.force_to_openmm(tolerance_pN), max_iterations)
        self.positions_changed()

    def save_checkpoint(self, path: str) -> str:
        """Write the full state (positions, parameters, random-number state) and the step
        counter to ``path``, atomically (``Context.createCheckpoint``; same platform only)."""
        data = self.context.createCheckpoint()
        tmp = path + ".tmp"
        with open(tmp, "wb") as fh:
            fh.write(int(self.step).to_bytes(8, "little"))
            fh.write(data)
        os.replace(tmp, path)
        return path

    def load_checkpoint(self, path: str) -> None:
        """Restore a state written by :meth:`save_checkpoint` (the run continues exactly)."""
        with open(path, "rb") as fh:
            raw = fh.read()
        self.step = int.from_bytes(raw[:8], "little")
        self.context.loadCheckpoint(raw[8:])
        self.positions_changed()

    # -- dynamics ------------------------------------------------------------
    def advance(self, nsteps: int, fail_dir: str | None = None) -> np.ndarray:
        """Take ``nsteps`` steps, then check the state; return positions (nm).

        Raises
        ------
        SimulationBlowUp
            On NaN/inf positions (OpenMM's own NaN check inside the steps included) or a
            bond stretched past MAX_BOND_STRETCH x rest length; the last good state is
            saved to ``fail_dir/last_good_state.xml``.
        """
        good = self.context.getState(getPositions=True, getParameters=True) if fail_dir else None
        try:
            self.integrator.step(int(nsteps))
        except openmm.OpenMMException as exc:
            # OpenMM checks coordinates itself and throws inside the step ("Particle
            # coordinate is NaN"): a blow-up within these steps, reported as one
            first = self.step + 1
            self.step += int(nsteps)
            self.blow_up(f"OpenMM stopped inside steps {first}-{self.step}: {exc}", good,
                         fail_dir)
        self.step += int(nsteps)
        pos = self.positions()
        problem = None
        if not np.all(np.isfinite(pos)):
            problem = "non-finite positions"
        elif len(self._bonds):
            r = np.linalg.norm(pos[self._bonds[:, 1]] - pos[self._bonds[:, 0]], axis=1)
            worst = int(np.argmax(r))
            if r[worst] > MAX_BOND_STRETCH * self._b:
                problem = (f"bond {tuple(self._bonds[worst])} stretched to {r[worst]:.3g} nm "
                           f"(> {MAX_BOND_STRETCH} x {self._b} nm)")
        if problem:
            self.blow_up(problem, good, fail_dir)
        return pos

    def largest_force_term(self) -> tuple[str, float]:
        """Name and size (pN) of the term with the largest force in the current state."""
        worst, fmax = "unknown", -1.0
        for name, g in self.terms.items():
            try:
                f = self.forces_pN(groups=[g])
                m = float(np.nanmax(np.abs(f))) if np.all(np.isfinite(f)) else float("inf")
            except Exception:  # noqa: BLE001 - a NaN state can make OpenMM throw
                m = float("inf")
            if m > fmax:
                worst, fmax = name, m
        return worst, fmax

    def blow_up(self, problem: str, good_state=None, fail_dir: str | None = None,
                advice: str | None = None):
        """Raise :class:`SimulationBlowUp` naming the step, the term with the largest force
        (in the bad state, or, when that state is not finite, in the last good one) and
        where the last good state was saved; ``advice`` replaces the closing suggestion
        (a smaller time step or a finer bead spacing) where the caller knows better."""
        term, fmax = self.largest_force_term()
        where = ""
        if not np.isfinite(fmax) and good_state is not None:
            # a NaN state has no largest term: name the one that was largest just before
            self.context.setPositions(good_state.getPositions())
            term, fmax = self.largest_force_term()
            where = " in the last good state"
        saved = None
        if good_state is not None and fail_dir:
            os.makedirs(fail_dir, exist_ok=True)
            saved = os.path.join(fail_dir, "last_good_state.xml")
            with open(saved, "w") as fh:
                fh.write(openmm.XmlSerializer.serialize(good_state))
        msg = (f"simulation blew up at step {self.step}: {problem}; largest force{where} from "
               f"term '{term}' ({fmax:.3g} pN); time step {self.dt_ns * 1e3:.4g} ps. "
               + (f"Last good state saved to {saved}. " if saved else "")
               + ("Try a smaller timestep_safety or a finer bead spacing." if advice is None
                  else advice))
        raise SimulationBlowUp(msg, step=self.step, term=term, saved=saved)
