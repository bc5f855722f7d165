"""The Brownian integrators against exact answers for a harmonic well.

For U = k x^2 / 2 and mobility mu, Euler-Maruyama with h = dt mu k samples a Gaussian of
variance (kT/k) / (1 - h/2) (the AR(1) recursion x' = (1 - h) x + sqrt(2 h kT / k) xi);
the Leimkuhler-Matthews scheme samples the exact variance kT / k for any stable h
(Leimkuhler, Matthews & Stoltz 2016). Independent particles give many samples per step.
"""

import numpy as np
import openmm
import pytest
from openmm import unit as u

from dnabraid.run.engine import (
    GAMMA_PER_PS,
    KB_KJ_PER_MOL_K,
    euler_maruyama_integrator,
    leimkuhler_matthews_integrator,
)

N = 2000          # independent particles
K = 100.0         # kJ/mol/nm^2
T = 300.0
MASS = 10.0       # amu -> mobility 1 / (m gamma)
H = 1.0           # dt mu k


def _variance(kind: str, noise_sign=(1.0, 1.0, 1.0)) -> float:
    mu = 1.0 / (MASS * GAMMA_PER_PS)
    dt = H / (mu * K)
    s = openmm.System()
    f = openmm.CustomExternalForce("0.5*k*(x^2+y^2+z^2)")
    f.addGlobalParameter("k", K)
    for i in range(N):
        s.addParticle(MASS)
        f.addParticle(i, [])
    s.addForce(f)
    if kind == "euler":
        integ = openmm.BrownianIntegrator(T * u.kelvin, GAMMA_PER_PS / u.picosecond, dt)
        integ.setRandomNumberSeed(7)
    elif kind == "em":
        integ = euler_maruyama_integrator(T, dt, [MASS] * N, GAMMA_PER_PS, noise_sign=noise_sign)
        integ.setRandomNumberSeed(7)
    else:
        integ = leimkuhler_matthews_integrator(T, dt, [MASS] * N, GAMMA_PER_PS,
                                               noise_sign=noise_sign)
        integ.setRandomNumberSeed(7)
    ctx = openmm.Context(s, integ, openmm.Platform.getPlatformByName("Reference"))
    ctx.setPositions(np.zeros((N, 3)))
    integ.step(50)
    xs = []
    for _ in range(40):
        integ.step(5)
        xs.append(ctx.getState(getPositions=True).getPositions(asNumpy=True)._value)
    return float(np.var(np.array(xs)))


def test_euler_maruyama_variance_is_biased_by_one_over_one_minus_h_over_2():
    exact = KB_KJ_PER_MOL_K * T / K
    # 40 x 2000 x 3 samples, correlated over ~1/h = 1 step (samples 5 steps apart): rel.
    # sampling error ~ sqrt(2 / 240000) = 0.3 %; tolerance 2 %
    assert _variance("euler") == pytest.approx(exact / (1 - H / 2), rel=0.02)


@pytest.mark.parametrize("sign", [(1.0, 1.0, 1.0), (1.0, -1.0, 1.0)])
def test_signed_noise_euler_maruyama_has_the_same_bias(sign):
    """The CustomIntegrator Euler-Maruyama used for mirror-coupled pairs samples what
    OpenMM's BrownianIntegrator does: (kT/k) / (1 - h/2); the noise sign does not matter."""
    exact = KB_KJ_PER_MOL_K * T / K
    assert _variance("em", sign) == pytest.approx(exact / (1 - H / 2), rel=0.02)


def test_leimkuhler_matthews_variance_is_exact():
    exact = KB_KJ_PER_MOL_K * T / K
    assert _variance("lm") == pytest.approx(exact, rel=0.02)


def test_restart_gives_each_point_its_own_reproducible_stream():
    """Independent points of a run must not share noise (they did: every point loaded the
    same checkpoint, random-number state included, so the points' torques moved together).
    Engine.restart(k) gives stream k: different for different k, the same for the same k."""
    from dnabraid.run.engine import Engine
    from dnabraid.scenes import make_scene

    m = make_scene("tether", {"length_nm": 50.0, "replicas": 1}).build()
    e = Engine.for_model(m, platform="Reference", seed=4)
    ends = []
    for k in (0, 1, 0):
        e.restart(k)
        e.context.setPositions(m.positions * u.nanometer)
        ends.append(e.advance(50)[-1].copy())
    assert not np.allclose(ends[0], ends[1])
    np.testing.assert_array_equal(ends[0], ends[2])


def test_blow_up_error_survives_pickling():
    """Replicas run in worker processes: a blow-up must reach the parent intact (the default
    exception pickling dropped the keyword-only fields, and the pool hung on the TypeError)."""
    import pickle

    from dnabraid.run.engine import SimulationBlowUp

    e = SimulationBlowUp("blew up at step 7", step=7, term="stretch", saved="/x/last.xml")
    e2 = pickle.loads(pickle.dumps(e))
    assert (str(e2), e2.step, e2.term, e2.saved) == (str(e), 7, "stretch", "/x/last.xml")
