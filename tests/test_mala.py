"""Metropolis-adjusted Brownian dynamics (``integrator = 'mala'``): exact at any step.

The references are exact: the Boltzmann moments of a quartic well by quadrature, a
harmonic well's kT / k, the exact discrete worm-like chain (transfer matrix). Euler-
Maruyama and Leimkuhler-Matthews run beside MALA at the same large step as controls: their
bias must be resolved by the same test, so the test can fail. Tolerances are Z standard
errors of the sampled moment (blocked, Flyvbjerg & Petersen 1989).
"""

import math

import numpy as np
import openmm
import pytest
from scipy import integrate

from dnabraid.errors import UserError
from dnabraid.run.engine import KB_KJ_PER_MOL_K, Engine, IntegratorSettings

T_K = 300.0
KT = KB_KJ_PER_MOL_K * T_K  # kJ/mol
MASS = 100.0  # amu: mobility 1 / (m gamma) = 0.01 mol ps / g
MOB = 1.0 / MASS
#: agreement within Z standard errors ...
Z = 4.0
#: ... and a control's bias must exceed Z_CONTROL of its standard errors
Z_CONTROL = 6.0


def well_system(n, expr, **params):
    """n particles of mass MASS in the external well ``expr`` (x, y, z in nm, kJ/mol) with
    the given global parameters."""
    s = openmm.System()
    for _ in range(n):
        s.addParticle(MASS)
    f = openmm.CustomExternalForce(expr)
    for k, v in params.items():
        f.addGlobalParameter(k, v)
    for i in range(n):
        f.addParticle(i, [])
    s.addForce(f)
    return s


def quartic_system(n, a):
    """n particles in the well U = a (x^4 + y^4 + z^4)."""
    return well_system(n, "a*(x^4 + y^4 + z^4)", a=a)


def harmonic_system(n, k):
    """n particles in the well U = k r^2 / 2."""
    return well_system(n, "0.5*k*(x^2 + y^2 + z^2)", k=k)


def blocked_mean_se(x, blocks=40):
    """Mean and standard error from `blocks` contiguous block means."""
    m = np.asarray(x, float)[: len(x) // blocks * blocks].reshape(blocks, -1).mean(1)
    return float(m.mean()), float(m.std(ddof=1) / math.sqrt(blocks))


def sample_x2(system, start, dt_ps, integrator, n_samples, every, seed=11, warm=2000):
    eng = Engine(system, start, IntegratorSettings(T_K, dt_ps * 1e-3, integrator),
                 platform="Reference", seed=seed)
    eng.advance(warm)
    x2 = np.array([np.mean(eng.advance(every) ** 2) for _ in range(n_samples)])
    return x2, eng


def logcosh_system(n, c, w):
    """n particles in U = c (ln cosh(x / w) + ln cosh(y / w) + ln cosh(z / w)): harmonic
    (curvature c / w^2) near 0, linear beyond w; the force is bounded, so Euler-Maruyama
    stays stable at any step and its bias can be measured."""
    return well_system(n, "c*(log(cosh(x/w)) + log(cosh(y/w)) + log(cosh(z/w)))", c=c, w=w)


def boltzmann_x2(u):
    """<x^2> in exp(-u(x) / kT) by quadrature."""
    z = integrate.quad(lambda x: math.exp(-u(x) / KT), -np.inf, np.inf)[0]
    return integrate.quad(lambda x: x * x * math.exp(-u(x) / KT), -np.inf, np.inf)[0] / z


def test_mala_is_exact_in_an_anharmonic_well_where_euler_is_not():
    """The log-cosh well at h = dt mu c / w^2 = 1 (the largest curvature): MALA's <x^2>
    within Z SE of the quadrature; Euler-Maruyama's off by more than Z_CONTROL SE
    (measured 2026-12-07, seeds 11 and 12: MALA -0.4 %, +0.5 % (0.8, 0.9 SE), acceptance
    0.37; EM +75 %, +74 % (129-165 SE); LM -0.4 %, -0.3 %, within its errors here, so it
    is no control)."""
    c, w = 4.0 * KT, 0.1
    exact = boltzmann_x2(lambda x: c * (abs(x / w) + math.log1p(math.exp(-2 * abs(x / w)))
                                        - math.log(2.0)))
    dt = 1.0 / (MOB * c / w**2)
    start = np.random.default_rng(3).normal(size=(4, 3)) * math.sqrt(exact)
    x2, eng = sample_x2(logcosh_system(4, c, w), start, dt, "mala", 16000, 5)
    m, se = blocked_mean_se(x2)
    assert abs(m - exact) < Z * se, f"mala {m:.5g} +- {se:.2g} against exact {exact:.5g}"
    assert se < 0.01 * exact  # the test resolves a 4 % bias
    acc, tried = eng.mala_acceptance()
    assert 0.2 < acc / tried < 0.6, (acc, tried)
    x2e, _ = sample_x2(logcosh_system(4, c, w), start, dt, "euler", 16000, 5)
    me, see = blocked_mean_se(x2e)
    assert abs(me - exact) > Z_CONTROL * see, (
        f"control euler {me:.5g} +- {see:.2g} not resolved from exact {exact:.5g}: the test "
        "could not tell a biased integrator")


def test_mala_is_stable_and_exact_in_a_quartic_well_where_euler_blows_up():
    """A quartic well U = a x^4 (cubic force) at h = 0.7 at the mean curvature 12 a <x^2>:
    Euler-Maruyama and LM blow up (SimulationBlowUp), MALA rejects the overshooting
    proposals and samples <x^2> = (kT / a)^(1/2) G(3/4) / G(1/4) within Z SE (measured
    2026-12-07: 1.0023 +- 0.0051 of it, acceptance 0.28)."""
    from dnabraid.run.engine import SimulationBlowUp

    a = 2.0e4
    exact = math.sqrt(KT / a) * math.gamma(0.75) / math.gamma(0.25)
    assert abs(boltzmann_x2(lambda x: a * x**4) / exact - 1) < 1e-8
    dt = 0.7 / (MOB * 12 * a * exact)
    start = np.random.default_rng(3).normal(size=(4, 3)) * math.sqrt(exact)
    x2, eng = sample_x2(quartic_system(4, a), start, dt, "mala", 8000, 5)
    m, se = blocked_mean_se(x2)
    assert abs(m - exact) < Z * se, (m, se, exact)
    for name in ("euler", "lm"):
        with pytest.raises(SimulationBlowUp):
            sample_x2(quartic_system(4, a), start, dt, name, 8000, 5)


def test_mala_harmonic_variance_exact_at_euler_maruyamas_inflation():
    """One particle in a harmonic well at h = dt mu k = 1.5: Euler-Maruyama's variance is
    inflated by 1 / (1 - h / 2) = 4 (exact for this scheme); MALA's is kT / k."""
    k = 1000.0
    s = harmonic_system(1, k)
    dt = 1.5 / (MOB * k)
    start = np.zeros((1, 3)) + math.sqrt(KT / k)
    x2, _ = sample_x2(s, start, dt, "mala", 8000, 5)
    m, se = blocked_mean_se(x2)
    assert abs(m - KT / k) < Z * se, (m, se, KT / k)
    x2e, _ = sample_x2(s, start, dt, "euler", 8000, 5)
    me, see = blocked_mean_se(x2e)
    assert abs(me - 4 * KT / k) < Z * see, (me, see)


def test_proposals_with_non_finite_energy_are_rejected():
    """A well whose energy is NaN outside |x| < w (U = -c ln(1 - (x / w)^2)): at a step
    that makes many proposals leave it, MALA never accepts one (step(NaN) = 0) and its
    <x^2> is the Boltzmann value; Euler-Maruyama would leave and go NaN."""
    w, c = 1.0, 5.0 * KT
    s = well_system(1, "-c*(log(1 - (x/w)^2) + log(1 - (y/w)^2) + log(1 - (z/w)^2))", c=c, w=w)
    dt = 0.3 * w * w / (MOB * KT)  # proposals' spread ~ 0.8 w
    x2, eng = sample_x2(s, np.zeros((1, 3)), dt, "mala", 6000, 5)
    assert np.all(np.isfinite(x2)) and np.all(x2 < w * w)
    acc, tried = eng.mala_acceptance()
    assert acc < 0.8 * tried  # many proposals were refused
    boltz = lambda x: (1 - (x / w) ** 2) ** (c / KT)  # noqa: E731
    exact = (integrate.quad(lambda x: x * x * boltz(x), -w, w)[0]
             / integrate.quad(boltz, -w, w)[0])
    m, se = blocked_mean_se(x2)
    assert abs(m - exact) < Z * se, (m, se, exact)


def test_energy_is_recomputed_after_outside_changes():
    """Positions set straight on the Context (as a Metropolis move might) and a parameter
    set through the engine: the next step's current energy E0 is the new state's."""
    k = 1000.0
    s = harmonic_system(1, k)
    # a step so small that a proposal is the current state to 1e-5 of its energy: E0
    # (kept, or the accepted proposal's E1) must then be the state's energy
    eng = Engine(s, np.zeros((1, 3)), IntegratorSettings(T_K, 1e-14, "mala"),
                 platform="Reference", seed=5)
    eng.advance(3)
    new = np.array([[0.3, -0.2, 0.1]])
    eng.context.setPositions(new * openmm.unit.nanometer)  # not through the engine
    eng.integrator.step(1)
    e0 = eng.integrator.getGlobalVariableByName("E0")
    e1 = eng.integrator.getGlobalVariableByName("E1")
    u_new = 0.5 * k * float(np.sum(new**2))
    assert abs(e0 - u_new) < 1e-4 * u_new and abs(e1 - u_new) < 1e-4 * u_new, (e0, e1, u_new)
    eng.set_parameter("k", 2 * k)
    pos = eng.positions()
    eng.integrator.step(1)
    e0 = eng.integrator.getGlobalVariableByName("E0")
    e1 = eng.integrator.getGlobalVariableByName("E1")
    u2 = k * float(np.sum(pos**2))
    assert abs(e0 - u2) < 1e-4 * u2 and abs(e1 - u2) < 1e-4 * u2, (e0, e1, u2)


def test_mala_refuses_constraints():
    s = openmm.System()
    s.addParticle(MASS)
    s.addParticle(MASS)
    s.addConstraint(0, 1, 1.0)
    with pytest.raises(UserError, match="constraints"):
        Engine(s, np.array([[0, 0, 0], [1.0, 0, 0]]), IntegratorSettings(T_K, 1e-3, "mala"),
               platform="Reference")


def test_tether_scene_with_mala_matches_the_exact_discrete_wlc(tmp_path):
    """The tether scene end to end with integrator = mala at a step twice the default
    (timestep_safety 0.6) and Brownian steps alone (mc_moves = 0): the extension within
    Z SE of the exact discrete WLC (no model tolerance: nothing here is approximate), the
    acceptance recorded per point and named in the notes."""
    from dnabraid.continuum.wlc import discrete_wlc_extension
    from dnabraid.scenes import make_scene

    s = make_scene("tether", {"force_pN": 3.0, "length_nm": 25.0, "steps": 300_000,
                              "equilibration_steps": 10_000, "surface": False,
                              "self_avoidance": False, "mc_moves": 0, "seed": 7,
                              "integrator": "mala", "timestep_safety": 0.6,
                              "frame_interval": 10_000, "replicas": 4})
    summ = s.run(str(tmp_path / "run"))
    pt = summ["points"][0]
    ext = pt["extension_nm"]
    m = s.build()
    p = m.params
    theory = discrete_wlc_extension(s.force_pN, s.n_beads - 1, s.bead_spacing_nm,
                                    p["kappa_kT"], p["kT_pN_nm"],
                                    stretch_k_pN_per_nm=p["k_bond_pN_per_nm"])["extension_nm"]
    assert abs(ext["mean"] - theory) < Z * ext["sem"], (ext["mean"], ext["sem"], theory)
    assert 0.2 < pt["mala"]["acceptance"] < 1.0
    assert pt["mala"]["tried"] >= 4 * 310_000
    assert any("mala" in n for n in summ["notes"])
