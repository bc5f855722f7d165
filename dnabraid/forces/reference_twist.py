"""Numpy twin of the twist energy (:mod:`dnabraid.forces.twist_frames`), with explicit gradients.

Each function returns ``(energy_pN_nm, forces_pN)`` with forces of shape (N, 3), like
:mod:`dnabraid.forces.reference`. The joint angle is

    omega = atan2(S, K),  S = (t1 + t2) . (u1 x u2),
                          K = (1 + t1 . t2)(u1 . u2) - (t1 . u2)(t2 . u1),

with t = T / |T| the unit tangents and u = W - (W . t) t the material vectors; the
gradient is carried by hand through the atan2, the projections and the normalisations
(independently of the OpenMM expression; the tests also check it by finite differences
and check omega against the parallel-transport definition in
:func:`dnabraid.geometry.ribbon.twist_angles`).
"""

from __future__ import annotations

import numpy as np


def _unit(T):
    n = np.linalg.norm(T, axis=1, keepdims=True)
    return T / n, n


def _project(W, t):
    return W - np.sum(W * t, axis=1, keepdims=True) * t


def joint_angles(T1, W1, T2, W2):
    """omega and its gradients with respect to the raw vectors T1, W1, T2, W2 (shape (n, 3))."""
    t1, n1 = _unit(T1)
    t2, n2 = _unit(T2)
    u1 = _project(W1, t1)
    u2 = _project(W2, t2)
    x = np.cross(u1, u2)
    S = np.sum((t1 + t2) * x, axis=1)
    c = np.sum(t1 * t2, axis=1)
    uu = np.sum(u1 * u2, axis=1)
    a = np.sum(t1 * u2, axis=1)  # t1 . u2
    bb = np.sum(t2 * u1, axis=1)  # t2 . u1
    K = (1 + c) * uu - a * bb
    om = np.arctan2(S, K)
    den = S**2 + K**2
    wS = (K / den)[:, None]
    wK = (-S / den)[:, None]
    col = lambda v: v[:, None]  # noqa: E731
    # partial derivatives of S and K at fixed t, u
    g_t1 = wS * x + wK * (t2 * col(uu) - u2 * col(bb))
    g_t2 = wS * x + wK * (t1 * col(uu) - u1 * col(a))
    g_u1 = wS * np.cross(u2, t1 + t2) + wK * (col(1 + c) * u2 - col(a) * t2)
    g_u2 = wS * np.cross(t1 + t2, u1) + wK * (col(1 + c) * u1 - col(bb) * t1)
    out = []
    for g_t, g_u, t, n, W in ((g_t1, g_u1, t1, n1, W1), (g_t2, g_u2, t2, n2, W2)):
        gu_t = np.sum(g_u * t, axis=1, keepdims=True)
        # u = W - (W.t) t: d/dW = g_u - (g_u.t) t ; extra d/dt = -(g_u.t) W - (W.t) g_u
        g_W = g_u - gu_t * t
        g_tt = g_t - gu_t * W - np.sum(W * t, axis=1, keepdims=True) * g_u
        g_T = (g_tt - np.sum(g_tt * t, axis=1, keepdims=True) * t) / n
        out += [g_T, g_W]
    return om, out


def _energy_forces(pos, om, grads, slots, g):
    """Scatter -g omega d omega into forces; ``slots`` maps each gradient to (plus, minus)."""
    g = np.broadcast_to(np.asarray(g, float), om.shape)
    e = float(np.sum(0.5 * g * om**2))
    f = np.zeros_like(pos)
    for grad, (plus, minus) in zip(grads, slots):
        if plus is None:
            continue
        gg = (g * om)[:, None] * grad
        np.add.at(f, plus, -gg)
        np.add.at(f, minus, gg)
    return e, f


def twist(pos, joints, g):
    """Interior joints ``(r_i, r_{i+1}, r_{i+2}, s_i, s_{i+1})``: U = sum g/2 omega^2."""
    pos = np.asarray(pos, float)
    j = np.asarray(joints, int).reshape(-1, 5)
    r0, r1, r2, s1, s2 = (j[:, k] for k in range(5))
    om, grads = joint_angles(pos[r1] - pos[r0], pos[s1] - pos[r0], pos[r2] - pos[r1],
                             pos[s2] - pos[r1])
    return _energy_forces(pos, om, grads, [(r1, r0), (s1, r0), (r2, r1), (s2, r1)], g)


def twist_ring(pos, ring, sides, g):
    """A closed ring: U = sum over its n joints (seam included) of g/2 omega^2.

    Bond i joins ``ring[i] -> ring[(i+1) % n]`` with side particle ``sides[i]``; joint i
    takes bond i to bond i + 1 (mod n). Built here from the ring directly (not from
    :func:`dnabraid.forces.twist_frames.ring_joints`), so the seam is checked independently.
    """
    r = np.asarray(ring, int).ravel()
    s = np.asarray(sides, int).ravel()
    joints = np.stack([r, np.roll(r, -1), np.roll(r, -2), s, np.roll(s, -1)], axis=1)
    return twist(pos, joints, g)


def twist_anchor(pos, bonds, tangent, material, g):
    """Fixed frame (tangent, material) against bonds ``(r_0, r_1, s_0)``."""
    pos = np.asarray(pos, float)
    bd = np.asarray(bonds, int).reshape(-1, 3)
    n = len(bd)
    t = np.asarray(tangent, float) / np.linalg.norm(tangent)
    T1 = np.tile(t, (n, 1))
    W1 = np.tile(np.asarray(material, float), (n, 1))
    om, grads = joint_angles(T1, W1, pos[bd[:, 1]] - pos[bd[:, 0]], pos[bd[:, 2]] - pos[bd[:, 0]])
    return _energy_forces(pos, om, grads, [(None, None), (None, None), (bd[:, 1], bd[:, 0]),
                                           (bd[:, 2], bd[:, 0])], g)


def twist_bead(pos, bonds, g, axis=(0.0, 0.0, 1.0)):
    """Bonds ``(r_{N-1}, r_N, s_{N-1}, m)`` against the bead frame (axis, m - r_N)."""
    pos = np.asarray(pos, float)
    bd = np.asarray(bonds, int).reshape(-1, 4)
    n = len(bd)
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    om, grads = joint_angles(pos[bd[:, 1]] - pos[bd[:, 0]], pos[bd[:, 2]] - pos[bd[:, 0]],
                             np.tile(a, (n, 1)), pos[bd[:, 3]] - pos[bd[:, 1]])
    return _energy_forces(pos, om, grads, [(bd[:, 1], bd[:, 0]), (bd[:, 2], bd[:, 0]),
                                           (None, None), (bd[:, 3], bd[:, 1])], g)


def bead_plane(pos, attachment, particles, k):
    """U = sum k/2 (z_i - z_att)^2 for z_i > z_att."""
    pos = np.asarray(pos, float)
    p = np.asarray(particles, int)
    pen = np.clip(pos[p, 2] - pos[attachment, 2], 0, None)
    e = 0.5 * k * float(np.sum(pen**2))
    f = np.zeros_like(pos)
    f[p, 2] = -k * pen
    f[attachment, 2] = k * float(np.sum(pen))
    return e, f
