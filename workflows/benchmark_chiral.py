"""Cost of the chiral term per Brownian step against a bonds + bending + WCA force field.

Two strands of n beads each (n = 50, 200, 800; bead spacing 3 nm) start as a right-handed
two-ply (eta = -30 deg) at the 150 mM effective diameter; OpenMM CPU platform, Threads=1,
BrownianIntegrator. For each size and q (sample points per segment: 1, the default rule at
3 nm beads, and 2) we time (a) bonds + bending + WCA, (b) the same plus the chiral
PythonForce with the numba evaluator and (c) with the numpy one (fewer steps), and report the
chiral term's cost as (b) - (a) per step and relative to (a). The last two columns are the
cost of one ``ChiralEvaluator.energy_grad`` call on the conformation reached by (b) (Verlet
list already built), numpy and numba, outside OpenMM. The table is printed and written to
workflows/results/benchmark_chiral.txt. Times are CPU time of this process
(``time.process_time``), which other jobs on a shared machine disturb far less than wall
time; pin it to one core (taskset -c 0).

``--range helix`` (default) uses the chiral weight's range rho = 1/sqrt(lambda_D^-2 + g^2)
(0.446 nm at 150 mM; docs/chiral_range.md); ``--range debye`` the Debye length (0.785 nm), the
range before that fix, for comparison (docs/chiral_range.md).

Usage: python workflows/benchmark_chiral.py [--steps 2000] [--range helix|debye] [--out F]
"""

from __future__ import annotations

import argparse
import itertools
import math
import pathlib
import platform
import time

import numpy as np
import openmm
from openmm import unit as u

from dnabraid.forcefield import salt_parameters
from dnabraid.forces.chiral import HAVE_NUMBA, ChiralEvaluator, chiral_force, default_exclusion
from dnabraid.forces.reference_chiral import (
    ChiralKernel,
    chiral_range_nm,
    default_subdivisions,
    segments_of,
)
from dnabraid.units import PN_NM_IN_KJ_MOL, kT

B_NM = 3.0
ETA = math.radians(-30.0)
SALT_MM = 150.0


def two_ply(n, delta, b=B_NM, eta=ETA):
    R = 0.5 * delta
    th = 0.5 * abs(eta)
    pitch = R / math.tan(th)
    ph = np.arange(n) * b / math.hypot(R, pitch)
    x = np.stack([R * np.cos(ph), R * np.sin(ph), pitch * ph], 1)  # right-handed
    y = x.copy()
    y[:, :2] *= -1
    return np.vstack([x, y]), [np.arange(n), n + np.arange(n)]


def base_system(pos, chains, delta):
    n = len(pos)
    kt = kT(298.15) * PN_NM_IN_KJ_MOL
    s = openmm.System()
    for _ in range(n):
        s.addParticle(1000.0)
    bonds = openmm.HarmonicBondForce()
    ang = openmm.CustomAngleForce("kappa*(1+cos(theta))")
    ang.addGlobalParameter("kappa", 50.0 / B_NM * kt)
    for c in chains:
        for i, j in itertools.pairwise(c):
            bonds.addBond(int(i), int(j), B_NM, 500.0)
        for i, j, k in zip(c[:-2], c[1:-1], c[2:]):
            ang.addAngle(int(i), int(j), int(k), [])
    wca = openmm.CustomNonbondedForce(
        "step(rc-r)*(4*eps*(sr6*sr6-sr6)+eps); sr6=(sigma/r)^6")
    wca.addGlobalParameter("eps", kt)
    wca.addGlobalParameter("sigma", delta)
    wca.addGlobalParameter("rc", 2 ** (1 / 6) * delta)
    wca.setNonbondedMethod(openmm.CustomNonbondedForce.CutoffNonPeriodic)
    wca.setCutoffDistance(2.5 * delta)
    for _ in range(n):
        wca.addParticle([])
    for c in chains:
        for i, j in itertools.pairwise(c):
            wca.addExclusion(int(i), int(j))
        for i, j in zip(c[:-2], c[2:]):
            wca.addExclusion(int(i), int(j))
    for f in (bonds, ang, wca):
        s.addForce(f)
    return s


def time_steps(system, pos, steps):
    integ = openmm.BrownianIntegrator(298.15 * u.kelvin, 1.0 / u.picosecond, 0.5 * u.picosecond)
    integ.setRandomNumberSeed(1)
    plat = openmm.Platform.getPlatformByName("CPU")
    ctx = openmm.Context(system, integ, plat, {"Threads": "1"})
    ctx.setPositions(pos * u.nanometer)
    integ.step(50)  # warm up
    t0 = time.process_time()
    integ.step(steps)
    dt = (time.process_time() - t0) / steps
    return dt, ctx


def per_call_us(evaluator, pos, calls=200, repeats=5):
    """Best-of-``repeats`` mean time of one energy_grad call (us)."""
    evaluator.energy_grad(pos)  # build the list (and compile/load numba)
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        for _ in range(calls):
            evaluator.energy_grad(pos)
        best = min(best, (time.process_time() - t0) / calls)
    return best * 1e6


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--out", default=str(pathlib.Path(__file__).parent / "results"
                                         / "benchmark_chiral.txt"))
    ap.add_argument("--range", choices=("helix", "debye"), default="helix",
                    help="decay length of the weight: 1/sqrt(lambda_D^-2 + g^2) (default) or "
                         "the Debye length (before the range of the first helical harmonic (docs/chiral_range.md))")
    args = ap.parse_args(argv)
    sp = salt_parameters(SALT_MM)
    delta, lam = sp.diameter_nm, sp.debye_nm
    rho = chiral_range_nm(lam) if args.range == "helix" else lam
    qdef = default_subdivisions(B_NM, delta, lam, range_nm=rho)
    kernel = ChiralKernel(delta, lam, range_nm=rho)
    backends = ("numba", "numpy") if HAVE_NUMBA else ("numpy",)
    np_steps = max(50, args.steps // 10)
    rows = []
    for n in (50, 200, 800):
        pos, chains = two_ply(n, delta)
        t_base, _ = time_steps(base_system(pos, chains, delta), pos, args.steps)
        for q in sorted({1, qdef, 2}):
            t_all, call = {}, {}
            for be in backends:
                s = base_system(pos, chains, delta)
                s.addForce(chiral_force(chains, 1.0, delta_nm=delta, debye_nm=lam,
                                        range_nm=rho, bead_spacing_nm=B_NM, subdivisions=q,
                                        backend=be))
                t_all[be], ctx = time_steps(s, pos, args.steps if be == "numba" else np_steps)
                if be == backends[0]:
                    end = ctx.getState(getPositions=True).getPositions(asNumpy=True)._value
            seg, cid, pic, nseg, ring = segments_of(chains)
            excl = default_exclusion(B_NM, delta, lam, range_nm=rho)
            for be in backends:
                ev = ChiralEvaluator(seg, cid, pic, nseg, ring, kernel, excl, q, 2.0, "x",
                                     backend=be)
                call[be] = per_call_us(ev, np.asarray(end), calls=max(20, 20000 // n))
            npairs = len(ev.candidate_pairs(np.asarray(end))[0])
            t_nb = t_all.get("numba", np.nan)
            rows.append((2 * n, q, npairs, t_base * 1e6, t_nb * 1e6, t_all["numpy"] * 1e6,
                         (t_nb - t_base) * 1e6, (t_nb - t_base) / t_base,
                         (t_all["numpy"] - t_base) / t_base,
                         call["numpy"], call.get("numba", np.nan)))
    head = (f"# chiral term cost per BrownianIntegrator step, OpenMM {openmm.__version__} CPU "
            f"platform Threads=1, {platform.processor() or platform.machine()}\n"
            f"# 150 mM: Delta = {delta:.2f} nm, lambda_D = {lam:.3f} nm, range of the weight "
            f"rho = {rho:.3f} nm ({args.range}), cutoff r_c = {kernel.r_c:.2f} nm, "
            f"exclusion {default_exclusion(B_NM, delta, lam, range_nm=rho)} segments, "
            f"b = {B_NM} nm, "
            f"two-ply eta = -30 deg, {args.steps} steps ({np_steps} with numpy); q = sample "
            f"points per segment (default rule now gives q = {qdef}); pairs = Verlet-list "
            f"candidates (skin 2 nm)\n"
            f"# CPU time per step (us): base = bonds + bending + WCA; +nb / +np = base + chiral"
            f" with the numba / numpy evaluator; chiral_us = (+nb) - base; call_us: one"
            f" energy_grad call\n"
            f"{'beads':>6} {'q':>2} {'pairs':>6} {'base_us':>8} {'+nb_us':>8} {'+np_us':>8}"
            f" {'chiral_us':>9} {'chiral/base':>11} {'np:chiral/base':>14}"
            f" {'call_np_us':>10} {'call_nb_us':>10}\n")
    body = "".join(f"{r[0]:>6d} {r[1]:>2d} {r[2]:>6d} {r[3]:>8.1f} {r[4]:>8.1f} {r[5]:>8.1f}"
                   f" {r[6]:>9.1f} {r[7]:>11.2f} {r[8]:>14.2f} {r[9]:>10.1f} {r[10]:>10.1f}\n"
                   for r in rows)
    print(head + body, end="")
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(head + body)


if __name__ == "__main__":
    main()
