"""Local energies of torsionally constrained DNA (the plectoneme's twist frames), compiled
with numba.

Twins of the OpenMM forces of :mod:`dnabraid.forces.twist_frames` (dnabraid units: nm,
pN, pN nm), read by :class:`dnabraid.kernels.chain.LocalEnergy` into its parameters:

* ``twist`` (three ``CustomCompoundBondForce`` s named ``twist``, ``twist_anchor``,
  ``twist_bead``, one term): U = g/2 omega^2 per joint, omega = atan2(sin, cos) of the
  rotation about t_2 that takes the parallel transport of u_1 onto u_2, from the same
  unnormalised formula as the Lepton expression (:func:`_omega`, see
  ``twist_frames.omega_expression``). A joint is stored with its type (0: interior
  ``(r_i, r_i+1, r_i+2, s_i, s_i+1)``, 1: surface clamp ``(r_0, r_1, s_0)`` against a fixed
  unit tangent and material vector, 2: bead clamp ``(r_N-1, r_N, s_N-1, m)`` against the
  fixed bead axis), its particles, its stiffness g and its fixed vectors (the constants of
  the force's expression, read from it and checked by rebuilding the expression).
* ``frame`` (``HarmonicBondForce``): harmonic bonds, handled as ``stretch``.
* ``beadwall`` as the bead's plane (``CustomCompoundBondForce`` of
  :func:`~dnabraid.forces.twist_frames.bead_plane_force`): U = k/2 (z_i - z_att)^2 for
  z_i > z_att, every bond sharing the attachment ``att``.

Energy changes: a joint changes when one of its particles moves; it is counted once, from
its first moved member; an interior joint whose five particles all move rigidly is left
out (omega is invariant under a rotation of all five), but the clamps never are (their
fixed frames do not turn with a rigid move). The plane terms change for the moved DNA
beads, or all of them when the attachment moves (a pivot of the top).

The Monte Carlo loop that uses them is :mod:`dnabraid.kernels.twist_loop` (documented in
:mod:`dnabraid.run.twist_moves`).
"""

from __future__ import annotations

import math
import re

import numba
import numpy as np

from ..units import PN_NM_IN_KJ_MOL

__all__ = ["omega", "joint_energy", "twist_total", "twist_delta", "plane_total",
           "plane_delta", "TWIST_NAMES"]

#: Names of the twist forces (one term ``twist``), by the particles of a joint.
TWIST_NAMES = {"twist": 5, "twist_anchor": 3, "twist_bead": 4}


# ------------------------------------------------------------------------ reading forces
def _parse_vector(expr: str, name: str) -> list[str]:
    """The component strings of a constant vector ``name`` in a Lepton expression."""
    out = []
    for a in "xyz":
        m = re.search(rf"(?:^|; ){name}{a}=([^;]+)", expr)
        if m is None:
            raise ValueError(f"LocalEnergy: twist expression without {name}{a}")
        out.append(m.group(1))
    return out


def read_twist_force(f) -> list:
    """Joints ``(type, particles, g pN nm, fixed vector (6,))`` of a twist force
    (:func:`~dnabraid.forces.twist_frames.twist_force`, ``twist_anchor_force`` or
    ``twist_bead_force``), its expression checked against the factory's."""
    from ..forces.twist_frames import diff_expression, omega_expression

    name = f.getName()
    npart = f.getNumParticlesPerBond()
    expr = f.getEnergyFunction()
    vec = np.zeros(6)
    if name == "twist" and npart == 5:
        typ = 0
        want = omega_expression(diff_expression(1, 2), diff_expression(1, 4), diff_expression(2, 3), diff_expression(2, 5))
    elif name == "twist_anchor" and npart == 3:
        typ = 1
        t, m = _parse_vector(expr, "ta1"), _parse_vector(expr, "wv1")
        want = omega_expression(t, m, diff_expression(1, 2), diff_expression(1, 3), unit_t1=True)
        vec[:3] = [float(x) for x in t]
        vec[3:] = [float(x) for x in m]
    elif name == "twist_bead" and npart == 4:
        typ = 2
        a = _parse_vector(expr, "ta2")
        want = omega_expression(diff_expression(1, 2), diff_expression(1, 3), a, diff_expression(2, 4), unit_t2=True)
        vec[:3] = [float(x) for x in a]
    else:
        raise ValueError(f"LocalEnergy: twist force {name!r} with {npart} particles per bond")
    if expr != want or f.getNumPerBondParameters() != 1 or f.getNumGlobalParameters():
        raise ValueError(f"LocalEnergy: force {name!r} has the energy {expr!r}; the kernel "
                         f"reproduces {want!r} with one per-bond parameter g only")
    out = []
    for b in range(f.getNumBonds()):
        parts, par = f.getBondParameters(b)
        out.append((typ, [int(x) for x in parts], float(par[0]) / PN_NM_IN_KJ_MOL, vec))
    return out


def joint_params(n: int, joints: list) -> dict:
    """The twist fields of :class:`dnabraid.kernels.chain.LocalEnergy`'s parameters."""
    nj = len(joints)
    jp = np.full((nj, 5), -1, np.int64)
    jn = np.zeros(nj, np.int64)
    for k, (_, parts, _, _) in enumerate(joints):
        jp[k, :len(parts)] = parts
        jn[k] = len(parts)
    rows = np.repeat(np.arange(nj), jn)
    parts = np.concatenate([jp[k, :jn[k]] for k in range(nj)])
    order = np.argsort(parts, kind="stable")
    ptr = np.zeros(n + 1, np.int64)
    np.add.at(ptr, parts + 1, 1)
    return dict(has_twist=True, j_type=np.array([j[0] for j in joints], np.int64), j_p=jp,
                j_np=jn, j_g=np.array([j[2] for j in joints], float),
                j_vec=np.array([j[3] for j in joints], float).reshape(nj, 6),
                j_ptr=np.cumsum(ptr).astype(np.int64), j_list=rows[order].astype(np.int64))


def read_plane_force(f, n: int) -> dict:
    """The plane fields of the parameters from a ``beadwall`` bead plane
    (:func:`~dnabraid.forces.twist_frames.bead_plane_force`)."""
    from ..forces.twist_frames import bead_plane_force

    name = f.getName()
    want = bead_plane_force(0, [], 1.0, name=name).getEnergyFunction()
    if f.getEnergyFunction() != want or f.getNumPerBondParameters():
        raise ValueError(f"LocalEnergy: force {name!r} has the energy "
                         f"{f.getEnergyFunction()!r}; the kernel reproduces {want!r} only")
    k = None
    for i in range(f.getNumGlobalParameters()):
        if f.getGlobalParameterName(i) == f"{name}_k":
            k = float(f.getGlobalParameterDefaultValue(i)) / PN_NM_IN_KJ_MOL
    if k is None:
        raise ValueError(f"LocalEnergy: force {name!r} has no global parameter {name}_k")
    on = np.zeros(n, np.uint8)
    cnt = np.zeros(n)
    atts = set()
    for b in range(f.getNumBonds()):
        (a, q), _ = f.getBondParameters(b)
        atts.add(int(a))
        on[q] = 1
        cnt[q] += 1.0
    if len(atts) > 1:
        raise ValueError(f"LocalEnergy: force {name!r} must share one attachment particle")
    return dict(has_plane=bool(on.any()), pl_att=atts.pop() if atts else 0, pl_on=on,
                pl_cnt=cnt, pl_k=k)


@numba.njit(cache=True)
def _omega(t1x, t1y, t1z, w1x, w1y, w1z, t2x, t2y, t2z, w2x, w2y, w2z, unit1, unit2):
    """Joint angle omega (rad) from raw tangents t and side vectors w (the Lepton
    expression of ``twist_frames.omega_expression``, operation for operation)."""
    if unit1:
        pr1 = w1x * t1x + w1y * t1y + w1z * t1z
        n1 = 1.0
    else:
        nn1 = t1x * t1x + t1y * t1y + t1z * t1z
        pr1 = (w1x * t1x + w1y * t1y + w1z * t1z) / nn1
        n1 = math.sqrt(nn1)
    if unit2:
        pr2 = w2x * t2x + w2y * t2y + w2z * t2z
        n2 = 1.0
    else:
        nn2 = t2x * t2x + t2y * t2y + t2z * t2z
        pr2 = (w2x * t2x + w2y * t2y + w2z * t2z) / nn2
        n2 = math.sqrt(nn2)
    u1x = w1x - pr1 * t1x
    u1y = w1y - pr1 * t1y
    u1z = w1z - pr1 * t1z
    u2x = w2x - pr2 * t2x
    u2y = w2y - pr2 * t2y
    u2z = w2z - pr2 * t2z
    sn = ((n2 * t1x + n1 * t2x) * (u1y * u2z - u1z * u2y)
          + (n2 * t1y + n1 * t2y) * (u1z * u2x - u1x * u2z)
          + (n2 * t1z + n1 * t2z) * (u1x * u2y - u1y * u2x))
    cs = ((n1 * n2 + t1x * t2x + t1y * t2y + t1z * t2z) * (u1x * u2x + u1y * u2y + u1z * u2z)
          - (t1x * u2x + t1y * u2y + t1z * u2z) * (t2x * u1x + t2y * u1y + t2z * u1z))
    return math.atan2(sn, cs)


@numba.njit(cache=True)
def _c(pos, new, moved, p, c, after):
    if after:
        s = moved[p]
        if s > 0:
            return new[s - 1, c]
    return pos[p, c]


@numba.njit(cache=True)
def omega(pos, new, moved, P, j, after):
    """Angle (rad) of joint ``j`` at the old (``after`` False) or moved positions."""
    typ = P.j_type[j]
    a = P.j_p[j, 0]
    b = P.j_p[j, 1]
    ax = _c(pos, new, moved, a, 0, after)
    ay = _c(pos, new, moved, a, 1, after)
    az = _c(pos, new, moved, a, 2, after)
    bx = _c(pos, new, moved, b, 0, after)
    by = _c(pos, new, moved, b, 1, after)
    bz = _c(pos, new, moved, b, 2, after)
    if typ == 0:
        c = P.j_p[j, 2]
        s1 = P.j_p[j, 3]
        s2 = P.j_p[j, 4]
        return _omega(bx - ax, by - ay, bz - az,
                      _c(pos, new, moved, s1, 0, after) - ax,
                      _c(pos, new, moved, s1, 1, after) - ay,
                      _c(pos, new, moved, s1, 2, after) - az,
                      _c(pos, new, moved, c, 0, after) - bx,
                      _c(pos, new, moved, c, 1, after) - by,
                      _c(pos, new, moved, c, 2, after) - bz,
                      _c(pos, new, moved, s2, 0, after) - bx,
                      _c(pos, new, moved, s2, 1, after) - by,
                      _c(pos, new, moved, s2, 2, after) - bz, False, False)
    v = P.j_vec
    if typ == 1:
        s = P.j_p[j, 2]
        return _omega(v[j, 0], v[j, 1], v[j, 2], v[j, 3], v[j, 4], v[j, 5],
                      bx - ax, by - ay, bz - az,
                      _c(pos, new, moved, s, 0, after) - ax,
                      _c(pos, new, moved, s, 1, after) - ay,
                      _c(pos, new, moved, s, 2, after) - az, True, False)
    s = P.j_p[j, 2]
    m = P.j_p[j, 3]
    return _omega(bx - ax, by - ay, bz - az,
                  _c(pos, new, moved, s, 0, after) - ax,
                  _c(pos, new, moved, s, 1, after) - ay,
                  _c(pos, new, moved, s, 2, after) - az,
                  v[j, 0], v[j, 1], v[j, 2],
                  _c(pos, new, moved, m, 0, after) - bx,
                  _c(pos, new, moved, m, 1, after) - by,
                  _c(pos, new, moved, m, 2, after) - bz, False, True)


@numba.njit(cache=True)
def joint_energy(pos, new, moved, P, j, after):
    """g/2 omega^2 (pN nm) of joint ``j``."""
    om = omega(pos, new, moved, P, j, after)
    return 0.5 * P.j_g[j] * om * om


@numba.njit(cache=True)
def twist_total(pos, P):
    """Twist energy (pN nm) of every joint at ``pos``."""
    moved = np.zeros(0, np.int64)
    new = np.zeros((0, 3))
    e = 0.0
    for j in range(P.j_type.shape[0]):
        e += joint_energy(pos, new, moved, P, j, False)
    return e


@numba.njit(cache=True)
def twist_delta(pos, idx, new, moved, rigid, P):
    """Change of the twist energy (pN nm) when particles ``idx`` move to ``new``
    (``moved[p]`` = slot + 1); ``rigid``: all moved particles turned together."""
    d = 0.0
    for a in range(idx.shape[0]):
        p = idx[a]
        for t in range(P.j_ptr[p], P.j_ptr[p + 1]):
            j = P.j_list[t]
            first = -1
            allm = True
            for k in range(P.j_np[j]):
                q = P.j_p[j, k]
                if moved[q] > 0:
                    if first < 0:
                        first = q
                else:
                    allm = False
            if first != p:
                continue
            if rigid and allm and P.j_type[j] == 0:
                continue
            d += joint_energy(pos, new, moved, P, j, True) - joint_energy(pos, new, moved, P, j,
                                                                          False)
    return d


@numba.njit(cache=True)
def _plane_e(dz, k):
    if dz > 0.0:
        return 0.5 * k * dz * dz
    return 0.0


@numba.njit(cache=True)
def plane_total(pos, P):
    """Energy (pN nm) of the bead's plane at ``pos``."""
    za = pos[P.pl_att, 2]
    e = 0.0
    for q in range(P.n):
        if P.pl_on[q]:
            e += P.pl_cnt[q] * _plane_e(pos[q, 2] - za, P.pl_k)
    return e


@numba.njit(cache=True)
def plane_delta(pos, idx, new, moved, P):
    """Change of the plane energy (pN nm) when particles ``idx`` move to ``new``."""
    att = P.pl_att
    za0 = pos[att, 2]
    za1 = new[moved[att] - 1, 2] if moved[att] > 0 else za0
    d = 0.0
    if moved[att] > 0:
        for q in range(P.n):
            if P.pl_on[q]:
                z1 = new[moved[q] - 1, 2] if moved[q] > 0 else pos[q, 2]
                d += P.pl_cnt[q] * (_plane_e(z1 - za1, P.pl_k) - _plane_e(pos[q, 2] - za0,
                                                                         P.pl_k))
    else:
        for a in range(idx.shape[0]):
            q = idx[a]
            if P.pl_on[q]:
                d += P.pl_cnt[q] * (_plane_e(new[a, 2] - za0, P.pl_k)
                                    - _plane_e(pos[q, 2] - za0, P.pl_k))
    return d
