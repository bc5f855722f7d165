"""Twist of torsionally constrained DNA: a material frame per bond and the twist energy.

Frame construction (one side particle per bond)
-----------------------------------------------
Bond i joins beads r_i -> r_{i+1}; its unit tangent is t_i. A side particle s_i is held
near r_i, perpendicular to the bond, at the arm length a, by two harmonic springs
(|s_i - r_i| = a and |s_i - r_{i+1}| = sqrt(a^2 + b^2); :func:`frame_springs`). The
bond's material vector is the part of ``w_i = s_i - r_i`` perpendicular to t_i,

    u_i = w_i - (w_i . t_i) t_i     (normalisation is not needed, see below),

so the frame {t_i, u_i, t_i x u_i} is exactly orthonormal whatever the springs do, and the
twist energy does not depend on where on its circle of rest the side particle sits
radially or axially: the springs only keep ``u_i`` well defined. The free energy of the
springs is independent of the frame angle and of the bond direction (the rest set of
s_i is a circle about the bond), so the frame angle is sampled with a flat measure and the
twist statistics are those of the energy below alone. (This is the "one side particle per
bond" frame of many coarse-grained DNA models, e.g. Chirico & Langowski, Biopolymers 34,
415 (1994); here the particle carries no excluded volume and no mass of its own beyond
a friction chosen for the time step.)

Twist angle between consecutive frames
--------------------------------------
The twist angle omega of joint (i, i+1) is the rotation about t_{i+1} that takes the
parallel transport of u_i (the minimal rotation carrying t_i onto t_{i+1}, about
t_i x t_{i+1}) onto u_{i+1}. With c = t_i . t_{i+1},

    cos omega ~ (1 + c)(u_i . u_{i+1}) - (t_i . u_{i+1})(t_{i+1} . u_i)
    sin omega ~ (t_i + t_{i+1}) . (u_i x u_{i+1})

(both scaled by the same positive factor (1 + c) |u_i| |u_{i+1}|, so
omega = atan2(sin, cos) needs no normalisation of u). This is the sum alpha + gamma of
the Euler angles between the frames used by Olson et al. and Chirico & Langowski. The
twist of a chain is Tw = sum omega / 2 pi. Because discrete parallel transport along a
polygon is rotation along great-circle arcs of the tangent indicatrix, its holonomy
around a closed polygon equals 2 pi x the polygon's exact (Gauss) writhe modulo 2 pi
(Fuller 1978; Cimasoni 2001), so Lk = Tw + Wr holds exactly for the closed ribbon
(tested in tests/test_twist.py).

Energy
------
U = (g / 2) omega^2 per joint with g = C kT / l, C the twist persistence length and l
the contour length the joint stands for (b for an interior joint, b / 2 for the two
clamps at the ends, so the chain's total twist compliance is L / (C kT)). Harmonic in
omega (not 1 - cos omega) so that <omega^2> = l / C exactly: the twist of a free chain
has variance L / (4 pi^2 C) turns^2. Twist-stretch and twist-bend couplings are left out.

Clamps. ``twist_anchor_force``: a fixed reference frame (the surface) against the frame
of the first bond. ``twist_bead_force``: the frame of the last bond against the bead's
frame, whose tangent is a fixed direction (the bead's axis, +z, kept by the magnetic
field) and whose material vector is the horizontal part of ``m - r_att`` for the bead's
orientation particle m (held by the rotational trap, :func:`~dnabraid.forces.trap_force`).
Turning the bead thus changes the linking number.

Rings (closed chains). A ring of n beads has n bonds, n side particles and n joints; the
seam joint ``(r_{n-1}, r_0, r_1, s_{n-1}, s_0)`` is an ordinary joint
(:func:`ring_joints`), every joint stands for a bond length b, and there are no clamps. The
ribbon's linking number Lk = Tw + Wr is then fixed by the frames the ring starts with
(:func:`dnabraid.geometry.ribbon.ring_side_positions`) and changes only if the ring passes
through itself or a joint angle passes through pi (the atan2 branch cut, at g pi^2 / 2 =
C pi^2 / (2 b) kT: ~99 kT for C = 100 nm, b = 5 nm). The twist of a ring relaxes as a whole
only through writhe: Tw + Wr = Lk (White 1969).
"""

from __future__ import annotations

import numpy as np
import openmm

from ..units import PN_NM_IN_KJ_MOL

_AX = "xyz"


def _vec(defs, name, comps):
    for a, c in zip(_AX, comps):
        defs.append(f"{name}{a}={c}")


def _dot(p, q):
    return "+".join(f"{p}{a}*{q}{a}" for a in _AX)


def omega_expression(t1, w1, t2, w2, *, unit_t1=False, unit_t2=False) -> str:
    """Lepton expression for 0.5 g omega^2 from component strings of tangents and side vectors.

    ``t1, t2``: 3 component strings of the (unnormalised unless ``unit_*``) tangents;
    ``w1, w2``: of the raw side vectors (projected here onto the planes normal to t).
    With raw tangents T1, T2 of lengths n1, n2, sin and cos of omega are both multiplied by
    n1 n2 > 0 (atan2 is unchanged): S = (n2 T1 + n1 T2) . (u1 x u2),
    K = (n1 n2 + T1 . T2)(u1 . u2) - (T1 . u2)(T2 . u1), and u = W - (W . T) T / (T . T):
    one square root per tangent and no normalisations (cheaper in OpenMM).
    """
    defs = ["0.5*g*om^2", "om=atan2(sn,cs)",
            "sn=(n2*ta1x+n1*ta2x)*(u1y*u2z-u1z*u2y)+(n2*ta1y+n1*ta2y)*(u1z*u2x-u1x*u2z)"
            "+(n2*ta1z+n1*ta2z)*(u1x*u2y-u1y*u2x)",
            f"cs=(n1*n2+{_dot('ta1', 'ta2')})*({_dot('u1', 'u2')})"
            f"-({_dot('ta1', 'u2')})*({_dot('ta2', 'u1')})"]
    for k, t, w, unit in ((1, t1, w1, unit_t1), (2, t2, w2, unit_t2)):
        # u = w - (w . T) T / (T . T)
        # (a Lepton definition may only use names defined after it)
        _vec(defs, f"u{k}", [f"wv{k}{a}-pr{k}*ta{k}{a}" for a in _AX])
        if unit:
            defs.append(f"pr{k}={_dot(f'wv{k}', f'ta{k}')}")
            defs.append(f"n{k}=1")
        else:
            defs.append(f"pr{k}=({_dot(f'wv{k}', f'ta{k}')})/nn{k}")
            defs.append(f"n{k}=sqrt(nn{k})")
            defs.append(f"nn{k}={_dot(f'ta{k}', f'ta{k}')}")
        _vec(defs, f"wv{k}", w)
        _vec(defs, f"ta{k}", t)
    return "; ".join(defs)


def diff_expression(i, j):
    """Components of r_j - r_i for compound-bond particle slots i, j (1-based)."""
    return [f"{a}{j}-{a}{i}" for a in _AX]


def _new_force(n, expr, name):
    f = openmm.CustomCompoundBondForce(n, expr)
    f.setName(name)
    f.addPerBondParameter("g")
    return f


def twist_force(joints, g_pN_nm, *, name: str = "twist") -> openmm.CustomCompoundBondForce:
    """Twist energy U = g/2 omega^2 between consecutive bond frames along a chain.

    Parameters
    ----------
    joints : array_like of int, shape (n, 5)
        ``(r_i, r_{i+1}, r_{i+2}, s_i, s_{i+1})``: the three beads of two consecutive bonds
        and the side particles of those bonds (s_i is attached at r_i).
    g_pN_nm : float or array_like, shape (n,)
        Joint stiffness g = C kT / b (pN nm per rad^2).
    """
    joints = np.asarray(joints, dtype=int).reshape(-1, 5)
    expr = omega_expression(diff_expression(1, 2), diff_expression(1, 4), diff_expression(2, 3), diff_expression(2, 5))
    f = _new_force(5, expr, name)
    g = np.broadcast_to(np.asarray(g_pN_nm, float), (len(joints),))
    for jt, gg in zip(joints, g):
        f.addBond([int(x) for x in jt], [float(gg) * PN_NM_IN_KJ_MOL])
    return f


def twist_anchor_force(bonds, tangent, material, g_pN_nm, *,
                       name: str = "twist_anchor") -> openmm.CustomCompoundBondForce:
    """Twist between a fixed reference frame (the surface) and a bond's frame.

    Parameters
    ----------
    bonds : array_like of int, shape (n, 3)
        ``(r_0, r_1, s_0)``: the bond and its side particle.
    tangent, material : array_like, shape (3,)
        The fixed frame: unit tangent and a unit material vector perpendicular to it
        (e.g. +z and +x for a surface tether).
    g_pN_nm : float
        Clamp stiffness (C kT / (b/2) for a clamp standing for half a bond).
    """
    t = np.asarray(tangent, float)
    m = np.asarray(material, float)
    t = t / np.linalg.norm(t)
    m = m - np.dot(m, t) * t
    m = m / np.linalg.norm(m)
    expr = omega_expression([repr(float(x)) for x in t], [repr(float(x)) for x in m],
                             diff_expression(1, 2), diff_expression(1, 3), unit_t1=True)
    f = _new_force(3, expr, name)
    for bd in np.asarray(bonds, dtype=int).reshape(-1, 3):
        f.addBond([int(x) for x in bd], [float(g_pN_nm) * PN_NM_IN_KJ_MOL])
    return f


def twist_bead_force(bonds, g_pN_nm, axis=(0.0, 0.0, 1.0), *,
                     name: str = "twist_bead") -> openmm.CustomCompoundBondForce:
    """Twist between a bond's frame and the bead's frame (fixed tangent ``axis``).

    Parameters
    ----------
    bonds : array_like of int, shape (n, 4)
        ``(r_{N-1}, r_N, s_{N-1}, m)``: the last bond, its side particle and the bead's
        orientation particle m; the bead frame's material vector is the part of
        ``m - r_N`` perpendicular to ``axis``.
    g_pN_nm : float
        Clamp stiffness.
    axis : array_like, shape (3,)
        The bead's axis (unit tangent of its frame).
    """
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    expr = omega_expression(diff_expression(1, 2), diff_expression(1, 3), [repr(float(x)) for x in a],
                             diff_expression(2, 4), unit_t2=True)
    f = _new_force(4, expr, name)
    for bd in np.asarray(bonds, dtype=int).reshape(-1, 4):
        f.addBond([int(x) for x in bd], [float(g_pN_nm) * PN_NM_IN_KJ_MOL])
    return f


def ring_joints(ring, sides) -> np.ndarray:
    """Joints of a closed ring, seam included: ``(r_i, r_{i+1}, r_{i+2}, s_i, s_{i+1})`` mod n.

    Parameters
    ----------
    ring : array_like of int, shape (n,)
        Beads of the ring (bond i joins ring[i] -> ring[(i + 1) % n]).
    sides : array_like of int, shape (n,)
        Side particle of each bond.

    Returns
    -------
    ndarray of int, shape (n, 5)
        Joint i takes bond i to bond i + 1 (mod n); the last one is the seam's.
    """
    r = np.asarray(ring, int).ravel()
    s = np.asarray(sides, int).ravel()
    n = r.size
    if n < 3 or s.size != n:
        raise ValueError(f"a ring needs >= 3 beads and one side particle per bond; got "
                         f"{n} beads and {s.size} side particles")
    i = np.arange(n)
    return np.stack([r[i], r[(i + 1) % n], r[(i + 2) % n], s[i], s[(i + 1) % n]], axis=1)


def frame_springs(chain, sides, arm_nm: float, bond_nm: float, k_pN_per_nm: float, *,
                  name: str = "frame") -> openmm.HarmonicBondForce:
    """Springs holding side particle s_i at r_i + a (perpendicular to bond i).

    |s_i - r_i| = a and |s_i - r_{i+1}| = sqrt(a^2 + b^2): the rest set of s_i is a circle of
    radius a about the bond, so the springs cost nothing to twist.

    Parameters
    ----------
    chain : array_like of int, shape (n,)
        Beads of the strand (for a ring of m beads pass the m beads and the first again,
        n = m + 1, so that bond m - 1 closes the ring).
    sides : array_like of int, shape (n - 1,)
        Side particle of each bond.
    arm_nm, bond_nm : float
        Arm length a and rest bond length b.
    k_pN_per_nm : float
        Spring constant of both springs.
    """
    chain = np.asarray(chain, int)
    sides = np.asarray(sides, int)
    f = openmm.HarmonicBondForce()
    f.setName(name)
    k = float(k_pN_per_nm) * PN_NM_IN_KJ_MOL
    diag = float(np.hypot(arm_nm, bond_nm))
    for i, s in enumerate(sides):
        f.addBond(int(chain[i]), int(s), float(arm_nm), k)
        f.addBond(int(chain[i + 1]), int(s), diag, k)
    return f


def initial_side_positions(chain_pos, arm_nm: float, first=(1.0, 0.0, 0.0)) -> np.ndarray:
    """Side-particle positions of an untwisted frame: ``first`` parallel-transported.

    Parameters
    ----------
    chain_pos : ndarray, shape (n, 3)
    arm_nm : float
    first : array_like, shape (3,)
        Material vector of the reference (surface) frame; projected on the first bond's
        normal plane by parallel transport from +z.

    Returns
    -------
    ndarray, shape (n - 1, 3)
    """
    from ..geometry.ribbon import parallel_transport

    p = np.asarray(chain_pos, float)
    t = np.diff(p, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    u = np.empty_like(t)
    cur = np.asarray(first, float)
    prev_t = np.array([0.0, 0.0, 1.0])
    for i in range(len(t)):
        cur = parallel_transport(cur, prev_t, t[i])
        cur = cur - np.dot(cur, t[i]) * t[i]
        cur /= np.linalg.norm(cur)
        u[i] = cur
        prev_t = t[i]
    return p[:-1] + arm_nm * u


def bead_plane_force(attachment: int, particles, k_pN_per_nm: float, *,
                     name: str = "beadwall") -> openmm.CustomCompoundBondForce:
    """The magnetic bead's lower surface as a plane through its attachment point.

    U = k/2 (z_i - z_att)^2 for z_i > z_att. The bead (radius ~500 nm) is far larger than
    the DNA's excursions, so its surface near the attachment is the plane z = z_att. For a
    torsionally constrained tether this keeps the DNA off the vertical ray above the
    attachment that closes the chain for the writhe: the linking number stays Tw + Wr.

    Parameters
    ----------
    attachment : int
        The bead's attachment particle.
    particles : array_like of int
        DNA beads kept below it (not the attachment itself).
    k_pN_per_nm : float
    """
    f = openmm.CustomCompoundBondForce(2, f"0.5*{name}_k*step(dz)*dz^2; dz=z2-z1")
    f.setName(name)
    f.addGlobalParameter(f"{name}_k", float(k_pN_per_nm) * PN_NM_IN_KJ_MOL)
    for i in np.asarray(particles, dtype=int).ravel():
        f.addBond([int(attachment), int(i)], [])
    return f
