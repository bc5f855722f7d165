"""Numpy twins of every energy term (dnabraid units: nm, pN, pN nm).

Each function returns ``(energy_pN_nm, forces_pN)`` with forces of shape (N, 3).
They are the oracle the tests compare OpenMM against, and are written independently of
the OpenMM expressions (explicit gradients, not autodiff).
"""

from __future__ import annotations

import numpy as np


def stretch(pos, bonds, k, r0):
    """U = sum k/2 (r - r0)^2."""
    pos = np.asarray(pos, float)
    bonds = np.asarray(bonds, int).reshape(-1, 2)
    k = np.broadcast_to(np.asarray(k, float), (len(bonds),))
    r0 = np.broadcast_to(np.asarray(r0, float), (len(bonds),))
    d = pos[bonds[:, 1]] - pos[bonds[:, 0]]
    r = np.linalg.norm(d, axis=1)
    e = 0.5 * np.sum(k * (r - r0) ** 2)
    g = (k * (r - r0) / r)[:, None] * d  # dU/d(r_j)
    f = np.zeros_like(pos)
    np.add.at(f, bonds[:, 0], g)
    np.add.at(f, bonds[:, 1], -g)
    return e, f


def bending(pos, triplets, kappa):
    """U = sum kappa (1 - cos beta), cos beta = (b1 . b2) / (|b1| |b2|), b1 = r_j - r_i, b2 = r_k - r_j."""
    pos = np.asarray(pos, float)
    t = np.asarray(triplets, int).reshape(-1, 3)
    b1 = pos[t[:, 1]] - pos[t[:, 0]]
    b2 = pos[t[:, 2]] - pos[t[:, 1]]
    n1 = np.linalg.norm(b1, axis=1)
    n2 = np.linalg.norm(b2, axis=1)
    c = np.sum(b1 * b2, axis=1) / (n1 * n2)
    e = np.sum(kappa * (1.0 - c))
    # dc/db1 = b2/(n1 n2) - c b1/n1^2 ; dc/db2 = b1/(n1 n2) - c b2/n2^2
    dc_db1 = b2 / (n1 * n2)[:, None] - (c / n1**2)[:, None] * b1
    dc_db2 = b1 / (n1 * n2)[:, None] - (c / n2**2)[:, None] * b2
    # U = -kappa c ; F = -dU/dr = kappa dc/dr
    f = np.zeros_like(pos)
    np.add.at(f, t[:, 0], -kappa * dc_db1)
    np.add.at(f, t[:, 1], kappa * (dc_db1 - dc_db2))
    np.add.at(f, t[:, 2], kappa * dc_db2)
    return e, f


def wca(pos, sigma, eps, exclusions=(), particles=None):
    """U = sum_{i<j not excluded} 4 eps[(s/r)^12 - (s/r)^6] + eps for r < 2^(1/6) s (brute force)."""
    pos = np.asarray(pos, float)
    n = len(pos)
    idx = np.arange(n) if particles is None else np.asarray(sorted(set(map(int, particles))))
    i, j = np.triu_indices(len(idx), 1)
    i, j = idx[i], idx[j]
    excl = {(min(a, b), max(a, b)) for a, b in exclusions}
    keep = np.array([(a, b) not in excl for a, b in zip(i, j)], bool)
    i, j = i[keep], j[keep]
    d = pos[j] - pos[i]
    r = np.linalg.norm(d, axis=1)
    rc = 2 ** (1 / 6) * sigma
    m = r < rc
    i, j, d, r = i[m], j[m], d[m], r[m]
    sr6 = (sigma / r) ** 6
    e = np.sum(4 * eps * (sr6 * sr6 - sr6) + eps)
    dudr = 4 * eps * (-12 * sr6 * sr6 + 6 * sr6) / r
    g = (dudr / r)[:, None] * d  # dU/dr_j
    f = np.zeros_like(pos)
    np.add.at(f, i, g)
    np.add.at(f, j, -g)
    return e, f


def wall(pos, particles, z_wall, k):
    """U = sum k/2 (z_w - z)^2 for z < z_w."""
    pos = np.asarray(pos, float)
    p = np.asarray(particles, int)
    z = pos[p, 2]
    pen = np.clip(z_wall - z, 0, None)
    e = 0.5 * k * np.sum(pen**2)
    f = np.zeros_like(pos)
    f[p, 2] = k * pen
    return e, f


def pull(pos, particles, shares, force):
    """U = -F sum share_i z_i."""
    pos = np.asarray(pos, float)
    p = np.asarray(particles, int)
    s = np.asarray(shares, float)
    e = -force * np.sum(s * pos[p, 2])
    f = np.zeros_like(pos)
    f[p, 2] = force * s
    return e, f


def trap(pos, p1, p2, K, angle, ktilt=0.0):
    """U = -K cos(phi - phi0) + ktilt/2 dz^2 for the axis u = r2 - r1."""
    pos = np.asarray(pos, float)
    u = pos[p2] - pos[p1]
    rho = np.hypot(u[0], u[1])
    phi = np.arctan2(u[1], u[0])
    e = -K * np.cos(phi - angle) + 0.5 * ktilt * u[2] ** 2
    # dU/dphi = K sin(phi - phi0); dphi/du = (-u_y, u_x)/rho^2
    dudphi = K * np.sin(phi - angle)
    grad_u = np.array([-u[1] / rho**2 * dudphi, u[0] / rho**2 * dudphi, ktilt * u[2]])
    f = np.zeros_like(pos)
    f[p2] = -grad_u
    f[p1] = grad_u
    return e, f


def trap_torque(pos, p1, p2, K, angle):
    """Torque about +z that the trap exerts on the bead: -K sin(phi - phi0) (pN nm)."""
    u = np.asarray(pos, float)[p2] - np.asarray(pos, float)[p1]
    phi = np.arctan2(u[..., 1], u[..., 0])
    return -K * np.sin(phi - angle)


def contact(pos, thickness, k, exclusion_range):
    """U = sum k/2 (2h - r)^2 over bead pairs with r < 2h more than ``exclusion_range`` apart."""
    from scipy.spatial import cKDTree

    pos = np.asarray(pos, float)
    d0 = 2.0 * thickness
    pairs = np.array(sorted(cKDTree(pos).query_pairs(d0)), dtype=int).reshape(-1, 2)
    pairs = pairs[np.abs(pairs[:, 1] - pairs[:, 0]) > exclusion_range]
    f = np.zeros_like(pos)
    if len(pairs) == 0:
        return 0.0, f
    d = pos[pairs[:, 1]] - pos[pairs[:, 0]]
    r = np.linalg.norm(d, axis=1)
    pen = np.clip(d0 - r, 0.0, None)
    e = 0.5 * k * np.sum(pen**2)
    g = (-k * pen / r)[:, None] * d  # dU/d(r_j)
    np.add.at(f, pairs[:, 0], g)
    np.add.at(f, pairs[:, 1], -g)
    return e, f
