"""Scene + force field -> OpenMM (Topology, System, positions), with only the terms needed.

Particle layout (``Model.chains``): each strand is an ordered chain of beads from the
surface tether (index 0 of the chain, immobile) to the bead attachment point (last
index of the chain). In the braid the two attachment points are joined by a rigid link
of length ``tether_separation_nm``: together they are the magnetic bead, pulled by the
force and held by the rotational trap. No bead-DNA excluded volume is modelled (the
bead is large and sits above the DNA under tension). Nicked scenes (braid, tether) have
no twist term and no frame particles.

Torsionally constrained DNA (``plectoneme``): after the DNA beads come one side
particle per bond (chain ``F``; the bond's material frame, :mod:`dnabraid.forces.twist`)
and the bead's orientation particle m (chain ``M``), held horizontal at ``BEAD_ARM_NM``
from the attachment and turned by the rotational trap; the twist energy couples the
surface frame (+z, +x), the bond frames and the bead frame (+z, m - r_att), so turning
the bead changes the linking number. Side particles and m carry no excluded volume.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import openmm
import openmm.app as app

from . import forcefield, units
from .forces import (
    bead_exclusion_force,
    bending_force,
    pull_force,
    stretch_force,
    trap_force,
    wall_force,
    wca_exclusions,
    wca_force,
)
from .forces.chiral import chiral_force
from .forces.twist import (
    bead_plane_force,
    frame_springs,
    initial_side_positions,
    twist_anchor_force,
    twist_bead_force,
    twist_force,
)
from .scene import Scene

#: Force groups, one per physical term, so blow-ups and benchmarks can name the term.
GROUPS = {"stretch": 0, "bend": 1, "wca": 2, "wall": 3, "pull": 4, "trap": 5, "link": 6,
          "beadwall": 7, "chiral": 8, "twist": 9, "frame": 10}

#: Frame arm a (side particle distance from the axis) in units of the bead spacing.
FRAME_ARM_FRACTION = 1.0
#: Side-particle friction / DNA bead friction. The frame angle's friction sets only how fast
#: twist relaxes (equilibrium does not depend on it); a light side particle relaxes twist
#: quickly without dragging the beads, and its rates stay below the bonds' (stiffest_mode).
FRAME_FRICTION_FRACTION = 0.1
#: Frame spring constant / bond spring constant. The springs only keep u_i well defined
#: (thermal wobble sqrt(kT/k) ~ 0.6 nm against the 5 nm arm); soft keeps the time step.
FRAME_K_FRACTION = 0.05
#: Distance of the bead's orientation particle m from the attachment (nm): the trap's
#: tangential stiffness K / arm^2 and its rate stay moderate.
BEAD_ARM_NM = 20.0


@dataclasses.dataclass
class Model:
    """A built scene: OpenMM objects plus the bookkeeping the engine and analysis need.

    Attributes
    ----------
    scene : Scene
    system : openmm.System
    topology : openmm.app.Topology
    positions : ndarray (N, 3), nm
    chains : list of int arrays (one per strand, surface -> bead)
    attachments : list of int (bead attachment particles)
    fixed : list of int (immobile tether particles)
    bonds : ndarray (n, 2) along the strands
    params : dict of derived numbers (kappa, k_bond, frictions, diameter, ...)
    forces : dict name -> force group of the terms actually present
    sides : int array (n_bonds,) or None
        Side particle of each bond (twisted scenes only).
    bead_orientation : int or None
        The bead's orientation particle m (twisted scenes only).
    """

    scene: Scene
    system: openmm.System
    topology: app.Topology
    positions: np.ndarray
    chains: list
    attachments: list
    fixed: list
    bonds: np.ndarray
    params: dict
    forces: dict
    sides: np.ndarray | None = None
    bead_orientation: int | None = None


def build(scene: Scene) -> Model:
    """Build the OpenMM model of ``scene`` (see module docstring for the layout)."""
    kT = scene.kT
    b = scene.bead_spacing_nm
    n = scene.n_beads
    d = scene.effective_diameter_nm
    kappa_kT = forcefield.bending_stiffness_kT(b, scene.persistence_nm)
    kappa = kappa_kT * kT
    k_bond = scene.stretch_modulus_pN / b
    zeta_dna = units.stokes_friction(
        forcefield.mechanics()["hydrodynamic_radius_fraction"] * b)
    zeta_bead_phys = units.stokes_friction(scene.bead_radius_nm)

    system = openmm.System()
    topology = app.Topology()
    positions = []
    chains = []
    n_str = scene.n_strands
    xs = [0.0] if n_str == 1 else [-0.5 * scene.tether_separation_nm,
                                   0.5 * scene.tether_separation_nm]
    zeta_center = scene.bead_friction_factor * zeta_bead_phys
    # tether: the bead is the attachment point itself; braid: the bead centre is its own particle
    zeta_attach = max(zeta_dna, zeta_center) if n_str == 1 else zeta_dna
    for s in range(n_str):
        chain = topology.addChain(id="AB"[s])
        idx = []
        for i in range(n):
            res = topology.addResidue("DNA", chain)
            topology.addAtom("C", app.element.carbon, res)
            if i == 0:
                mass = 0.0  # tethered to the surface: immobile
            elif i == n - 1:
                mass = units.friction_to_mass_amu(zeta_attach)
            else:
                mass = units.friction_to_mass_amu(zeta_dna)
            idx.append(system.addParticle(mass))
            positions.append((xs[s], 0.0, i * b))
        chains.append(np.array(idx))
    positions = np.array(positions, float)
    if n_str == 1:
        from .geometry import random_tether

        positions = random_tether(n, b, kappa_kT, scene.seed,
                                  z_min=0.5 * d if scene.surface else None)
        if scene.twisted:
            from .analysis.twist import writhe_open

            # Lk = 0 at the start: the bead clamp takes up -Wr of the random start, which
            # must stay on the principal branch of the clamp angle (|2 pi Wr| < pi/2)
            if abs(writhe_open(positions)) > 0.25:
                positions = np.c_[np.zeros(n), np.zeros(n), b * np.arange(n)]
    attachments = [int(c[-1]) for c in chains]
    fixed = [int(c[0]) for c in chains]
    bonds = np.array([(c[i], c[i + 1]) for c in chains for i in range(len(c) - 1)], int)
    triplets = np.array([(c[i], c[i + 1], c[i + 2]) for c in chains for i in range(len(c) - 2)],
                        int)
    present = {}

    def add(force, name):
        force.setForceGroup(GROUPS[name])
        system.addForce(force)
        present[name] = GROUPS[name]

    sides = bead_orient = None
    zeta_frame = FRAME_FRICTION_FRACTION * zeta_dna
    arm = FRAME_ARM_FRACTION * b
    g_twist = scene.twist_persistence_nm * kT / b if scene.twisted else 0.0
    k_frame = FRAME_K_FRACTION * k_bond
    if scene.twisted:
        chain = topology.addChain(id="F")
        sides = []
        for i in range(n - 1):
            res = topology.addResidue("FRM", chain)
            topology.addAtom("F", None, res)
            sides.append(system.addParticle(units.friction_to_mass_amu(zeta_frame)))
        sides = np.array(sides)
        chain = topology.addChain(id="M")
        res = topology.addResidue("BEO", chain)
        topology.addAtom("MO", None, res)
        bead_orient = system.addParticle(units.friction_to_mass_amu(zeta_dna))
        positions = np.vstack([positions, initial_side_positions(positions[chains[0]], arm),
                               positions[chains[0][-1]] + np.array([BEAD_ARM_NM, 0.0, 0.0])])

    # stretching: harmonic bonds or rigid constraints
    if scene.stretch == "bonds":
        add(stretch_force(bonds, k_bond, b, name="stretch"), "stretch")
    else:
        # OpenMM cannot constrain an immobile (massless) particle: the tether bonds stay
        # harmonic springs, all others are rigid.
        fixed_set = {int(c[0]) for c in chains}
        springs = [(i, j) for i, j in bonds if int(i) in fixed_set or int(j) in fixed_set]
        add(stretch_force(springs, k_bond, b, name="stretch"), "stretch")
        for i, j in bonds:
            if int(i) not in fixed_set and int(j) not in fixed_set:
                system.addConstraint(int(i), int(j), b)
    add(bending_force(triplets, kappa, name="bend"), "bend")
    excl_extra = []
    if n_str == 2:
        excl_extra = [tuple(attachments), tuple(fixed)]
    exclusions = wca_exclusions(chains, b, d, extra_pairs=excl_extra)
    dna_particles = [int(i) for c in chains for i in c] if scene.twisted else None
    add(wca_force(system.getNumParticles(), d, kT, particles=dna_particles,
                  exclusions=exclusions, name="wca"), "wca")
    mobile = [int(i) for c in chains for i in c[1:]]
    wall_k = 456.0 * kT / d**2  # = U''_WCA(sigma): as stiff as bead contact
    if scene.surface:
        add(wall_force(mobile, 0.5 * d, wall_k, name="wall"), "wall")
    bead_center = None
    if n_str == 2:
        # The magnetic bead: a rigid triangle of the two attachment points and the bead
        # centre C, which lies at the bead radius R from both attachments, above them.
        # C carries the bead's friction and the magnetic force; the sphere of radius R
        # around C excludes DNA, so strands cannot slip over the bead and unbraid.
        R = scene.bead_radius_nm
        half = 0.5 * scene.tether_separation_nm
        h = math.sqrt(R * R - half * half)
        chain = topology.addChain(id="M")
        res = topology.addResidue("BEA", chain)
        topology.addAtom("MB", None, res)
        bead_center = system.addParticle(units.friction_to_mass_amu(zeta_center))
        for f in system.getForces():  # give the centre a slot in per-particle forces (WCA):
            if isinstance(f, openmm.CustomNonbondedForce):  # it never comes near DNA there
                f.addParticle([])
        top = positions[attachments].mean(axis=0)
        positions = np.vstack([positions, top + np.array([0.0, 0.0, h])])
        add(pull_force([bead_center], [1.0], scene.force_pN, name="pull"), "pull")
        trap_r = half
        tilt_k = scene.trap_stiffness_pN_nm / trap_r**2
        add(trap_force(attachments[0], attachments[1], scene.trap_stiffness_pN_nm, 0.0,
                       tilt_k, name="trap"), "trap")
        add(stretch_force([attachments, (attachments[0], bead_center),
                           (attachments[1], bead_center)], k_bond,
                          [scene.tether_separation_nm, R, R], name="link"), "link")
        near = {int(c[-1]) for c in chains} | {int(c[-2]) for c in chains}
        dna = [int(i) for c in chains for i in c[1:] if int(i) not in near]
        add(bead_exclusion_force(bead_center, dna, R + 0.5 * d,
                                 wall_k, name="beadwall"), "beadwall")
    else:
        add(pull_force(attachments, [1.0], scene.force_pN, name="pull"), "pull")
    if scene.twisted:
        c0 = chains[0]
        add(frame_springs(c0, sides, arm, b, k_frame, name="frame"), "frame")
        joints = [(c0[i], c0[i + 1], c0[i + 2], sides[i], sides[i + 1]) for i in range(n - 2)]
        # interior joints stand for a bond length b, the two clamps for b/2 each: the
        # chain's twist compliance is L / (C kT) (forces/twist.py)
        add(twist_force(joints, g_twist, name="twist"), "twist")
        for f in (twist_anchor_force([(c0[0], c0[1], sides[0])], (0, 0, 1), (1, 0, 0),
                                     2 * g_twist, name="twist_anchor"),
                  twist_bead_force([(c0[-2], c0[-1], sides[-1], bead_orient)], 2 * g_twist,
                                   name="twist_bead")):
            f.setForceGroup(GROUPS["twist"])
            system.addForce(f)
        att = attachments[0]
        add(trap_force(att, bead_orient, scene.trap_stiffness_pN_nm, 0.0,
                       scene.trap_stiffness_pN_nm / BEAD_ARM_NM**2, name="trap"), "trap")
        add(stretch_force([(att, bead_orient)], k_bond, BEAD_ARM_NM, name="link"), "link")
        add(bead_plane_force(att, c0[1:-1], wall_k, name="beadwall"), "beadwall")
    debye = forcefield.salt_parameters(scene.salt_mM).debye_nm
    if scene.alpha != 0.0:
        # Kornyshev chiral term between facing segments (docs/chirality.md); left out at
        # alpha = 0. The immobile tether points take part like any other bead.
        add(chiral_force(chains, scene.alpha, delta_nm=d, debye_nm=debye, bead_spacing_nm=b,
                         name="chiral"), "chiral")
    params = {
        "kT_pN_nm": kT,
        "bead_center": bead_center,
        "zeta_center_pN_ns_per_nm": zeta_center,
        "kappa_kT": kappa_kT,
        "kappa_pN_nm": kappa,
        "k_bond_pN_per_nm": k_bond,
        "diameter_nm": d,
        "zeta_dna_pN_ns_per_nm": zeta_dna,
        "zeta_attach_pN_ns_per_nm": zeta_attach,
        "zeta_bead_physical_pN_ns_per_nm": zeta_bead_phys,
        "wall_k_pN_per_nm": wall_k if scene.surface else 0.0,
        "n_exclusions": len(exclusions),
        "debye_nm": debye,
        "alpha_pN": scene.alpha,
    }
    if scene.twisted:
        params.update({
            "twist_g_pN_nm": g_twist,
            "twist_persistence_nm": scene.twist_persistence_nm,
            "frame_arm_nm": arm,
            "frame_k_pN_per_nm": k_frame,
            "zeta_frame_pN_ns_per_nm": zeta_frame,
            "bead_arm_nm": BEAD_ARM_NM,
            "zeta_bead_orientation_pN_ns_per_nm": zeta_dna,
        })
    params.update(stiffest_mode(scene, params))
    return Model(scene, system, topology, positions, chains, attachments, fixed, bonds,
                 params, present, sides, bead_orient)


def stiffest_mode(scene: Scene, p: dict) -> dict:
    """Largest relaxation rate (1/ns) of the force field, term by term, and the time step.

    Euler-Maruyama (OpenMM's BrownianIntegrator) is stable for dt < 2 / (mu lambda_max)
    with mu the mobility and lambda_max the largest eigenvalue of the Hessian. Bounds per
    term for a bead chain: bonds 4 k (chain Laplacian), bending 16 kappa / b^2 (second
    difference squared), WCA contact 2 U''(sigma) = 2 x 456 eps / sigma^2, the wall
    U''; the trap K / r^2 and the link act on the bead. The rates of terms acting on the
    same beads add. The time step is ``timestep_safety`` x 2 / rate_max.

    Twisted scenes add, on the side particles (friction zeta_f, arm a): the frame springs
    4 k_f / zeta_f and the twist 2 (g_left + g_right) / (a^2 zeta_f) <= 6 g / (a^2 zeta_f)
    (the clamps count 2 g); on the DNA beads: the springs' reaction 4 k_f and the twist
    through the tangents, bounded by 12 g / b^2 (omega moves by at most ~1 rad per rad of
    tangent tilt, three joints touch a bead); on the bead's orientation particle m (arm
    R_m): the trap 2 K / R_m^2 and the link 2 k.
    """
    kT = p["kT_pN_nm"]
    b = scene.bead_spacing_nm
    d = p["diameter_nm"]
    mu = 1.0 / p["zeta_dna_pN_ns_per_nm"]
    mu_a = 1.0 / p["zeta_attach_pN_ns_per_nm"]
    rates = {
        # constraints: only the tether bond is a spring (one bead against a fixed point)
        "stretch": (4.0 if scene.stretch == "bonds" else 2.0) * p["k_bond_pN_per_nm"] * mu,
        "bend": 16.0 * p["kappa_pN_nm"] / b**2 * mu,
        "wca": 2.0 * 456.0 * kT / d**2 * mu,
        "wall": p["wall_k_pN_per_nm"] * mu,
    }
    if scene.alpha != 0.0:
        # The chiral weight K(r) ~ A/(1 + exp((r - Delta)/lambda_D)) with A ~ 1/(2 Delta):
        # its curvature per unit alpha is at most ~0.1 A / lambda_D^2 per nm of partner,
        # summed over the ~2 Delta of partner in range and over both segment ends.
        lam = p["debye_nm"]
        rates["chiral"] = abs(scene.alpha) * 0.1 / lam**2 * 4.0 * mu
    if scene.n_strands == 2:
        r = 0.5 * scene.tether_separation_nm
        rates["trap"] = 2 * scene.trap_stiffness_pN_nm / r**2 * mu_a
        rates["link"] = 3 * p["k_bond_pN_per_nm"] * mu_a
    dna_extra = 0.0
    side_total = 0.0
    if scene.twisted:
        g = p["twist_g_pN_nm"]
        zf = p["zeta_frame_pN_ns_per_nm"]
        a = p["frame_arm_nm"]
        kf = p["frame_k_pN_per_nm"]
        rates["frame"] = 4.0 * kf / zf
        rates["twist"] = 6.0 * g / (a * a * zf)
        dna_extra = (4.0 * kf + 12.0 * g / b**2) * mu
        side_total = rates["frame"] + rates["twist"]
        zm = p["zeta_bead_orientation_pN_ns_per_nm"]
        rates["trap"] = 2 * scene.trap_stiffness_pN_nm / p["bead_arm_nm"] ** 2 / zm
        rates["link"] = 2 * p["k_bond_pN_per_nm"] / zm
    total = rates["stretch"] + rates["bend"] + rates["wca"] + rates.get("chiral", 0.0) + dna_extra
    # the bead's plane (twisted tether) is as stiff as the wall and never acts with it
    total = max(total, rates["wall"] + rates["stretch"] + dna_extra, side_total,
                rates.get("trap", 0) + rates.get("link", 0))
    stiff = max(rates, key=rates.get)
    dt_ns = scene.timestep_safety * 2.0 / total
    reason = (f"stiffest term '{stiff}' (rate {rates[stiff]:.3g}/ns); summed bound "
              f"{total:.3g}/ns; dt = {scene.timestep_safety} x 2/rate = {dt_ns * 1e3:.4g} ps "
              f"(Euler-Maruyama stability limit 2/rate = {2e3 / total:.4g} ps)")
    return {"rates_per_ns": rates, "rate_max_per_ns": total, "stiffest_term": stiff,
            "time_step_ns": dt_ns, "time_step_reason": reason}


def scale_check(model: Model) -> None:
    """Raise if the single-precision nonbonded arithmetic would lose accuracy."""
    extent = float(np.max(np.abs(model.positions)))
    if extent > 1e5 * model.scene.bead_spacing_nm:
        raise ValueError(f"system extent {extent:.3g} nm is too large for single precision")


__all__ = ["Model", "build", "GROUPS", "stiffest_mode", "math"]
