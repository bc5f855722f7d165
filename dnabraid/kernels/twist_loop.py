"""The plectoneme's twist-aware Metropolis loop, compiled with numba, on the local energies
of :mod:`dnabraid.kernels.chain` and :mod:`dnabraid.kernels.twist` (documented in
:mod:`dnabraid.run.twist_moves`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from . import chain as _ch
from .twist import joint_energy, omega

#: The index of the twist term in the per-term arrays (a compile-time constant).
_I_TWIST = _ch.TERMS.index("twist")

__all__ = ["passage_free", "run_twist_moves", "spread_spins"]


# ------------------------------------------------------------------------ Monte Carlo
@numba.njit(cache=True)
def _axis_rot(R, ax, ay, az, c, s):
    t = 1.0 - c
    R[0, 0] = c + ax * ax * t
    R[0, 1] = ax * ay * t - az * s
    R[0, 2] = ax * az * t + ay * s
    R[1, 0] = ay * ax * t + az * s
    R[1, 1] = c + ay * ay * t
    R[1, 2] = ay * az * t - ax * s
    R[2, 0] = az * ax * t - ay * s
    R[2, 1] = az * ay * t + ax * s
    R[2, 2] = c + az * az * t


@numba.njit(cache=True)
def _wrap(x):
    """x mapped to [0, 2 pi)."""
    tp = 2.0 * math.pi
    return x - tp * math.floor(x / tp)


#: Marks an azimuth not yet computed in :func:`passage_free` (outside [-pi, pi]).
_NO_ANGLE = 10.0


@numba.njit(cache=True)
def _azimuth(pos, p, cx, cy, cz, e1x, e1y, e1z, e2x, e2y, e2z):
    x = pos[p, 0] - cx
    y = pos[p, 1] - cy
    z = pos[p, 2] - cz
    return math.atan2(x * e2x + y * e2y + z * e2z, x * e1x + y * e1y + z * e1z)


@numba.njit(cache=True)
def passage_free(pos, beads, lo, hi, cx, cy, cz, ax, ay, az, theta, bmax, hb, rb, ab, order):
    """True when turning beads ``lo..hi`` of the strand ``beads`` by ``theta`` about the
    unit axis (ax, ay, az) through (cx, cy, cz) can carry no bond through an unmoved one.

    A bond crossing another at some angle between 0 and theta puts an endpoint of each
    within half a bond of the crossing point, so some moved bead p and unmoved bead q
    (or a bead on the axis and an unmoved q) come within ``bmax`` (the longest bond) of
    each other at some angle in between. In cylinder coordinates about the axis (h, rho,
    alpha), |q - R(t) p|^2 = dh^2 + rho_p^2 + rho_q^2 - 2 rho_p rho_q cos(alpha_q -
    alpha_p - t), whose minimum over t in [0, theta] is exact. Bonds that share a bead
    cannot cross: chain neighbours are not tested. Unmoved beads are binned by rho (bins of
    bmax, a counting sort) so that each moved bead meets only those of its own and the
    two neighbouring bins. ``hb, rb, ab, order``:
    work arrays of the strand's length."""
    nb = beads.shape[0]
    # a basis (e1, e2) normal to the axis
    if abs(ax) < 0.9:
        e1x, e1y, e1z = 0.0, -az, ay
    else:
        e1x, e1y, e1z = az, 0.0, -ax
    nn = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    e1x /= nn
    e1y /= nn
    e1z /= nn
    e2x = ay * e1z - az * e1y
    e2y = az * e1x - ax * e1z
    e2z = ax * e1y - ay * e1x
    for k in range(nb):
        p = beads[k]
        x = pos[p, 0] - cx
        y = pos[p, 1] - cy
        z = pos[p, 2] - cz
        hb[k] = x * ax + y * ay + z * az
        u = x * e1x + y * e1y + z * e1z
        v = x * e2x + y * e2y + z * e2z
        rb[k] = math.sqrt(u * u + v * v)
        ab[k] = _NO_ANGLE  # the azimuth, computed when a pair needs it
    # unmoved beads binned by distance from the axis (counting sort into ``order``)
    inv = 1.0 / bmax
    nbin = 1
    for k in range(nb):
        nbin = max(nbin, int(rb[k] * inv) + 2)
    start = np.zeros(nbin + 1, np.int64)
    for k in range(nb):
        if k < lo or k > hi:
            start[int(rb[k] * inv) + 1] += 1
    for i in range(nbin):
        start[i + 1] += start[i]
    fill = start.copy()
    for k in range(nb):
        if k < lo or k > hi:
            i = int(rb[k] * inv)
            order[fill[i]] = k
            fill[i] += 1
    b2 = bmax * bmax
    tlo = min(0.0, theta)
    span = abs(theta)
    for k in range(lo, hi + 1):
        i = int(rb[k] * inv)
        for c in range(start[max(i - 1, 0)], start[min(i + 2, nbin)]):
            q = order[c]
            dr = rb[q] - rb[k]
            if q == k - 1 or q == k + 1:
                continue
            dh = hb[k] - hb[q]
            if dh * dh + dr * dr > b2:
                continue
            if ab[k] == _NO_ANGLE:
                ab[k] = _azimuth(pos, beads[k], cx, cy, cz, e1x, e1y, e1z, e2x, e2y, e2z)
            if ab[q] == _NO_ANGLE:
                ab[q] = _azimuth(pos, beads[q], cx, cy, cz, e1x, e1y, e1z, e2x, e2y, e2z)
            d = ab[q] - ab[k]
            if _wrap(d - tlo) <= span:
                cmax = 1.0
            else:
                cmax = max(math.cos(d - tlo), math.cos(d - tlo - span))
            if dh * dh + rb[k] * rb[k] + rb[q] * rb[q] - 2.0 * rb[k] * rb[q] * cmax <= b2:
                return False
    # beads on the axis (the pivots, unmoved) against unmoved non-neighbours
    for k in (lo - 1, hi + 1):
        if k < 0 or k >= nb:
            continue
        p = beads[k]
        for q in range(nb):
            if lo <= q <= hi or abs(q - k) < 2:
                continue
            r = beads[q]
            dx = pos[r, 0] - pos[p, 0]
            dy = pos[r, 1] - pos[p, 1]
            dz = pos[r, 2] - pos[p, 2]
            if dx * dx + dy * dy + dz * dz <= b2:
                return False
    return True


@numba.njit(cache=True)
def _wrap_pi(x):
    """x mapped to [-pi, pi)."""
    return x - 2.0 * math.pi * math.floor((x + math.pi) / (2.0 * math.pi))


@numba.njit(cache=True)
def _at(pos, new, moved, p, c):
    s = moved[p]
    return new[s - 1, c] if s > 0 else pos[p, c]


@numba.njit(cache=True)
def spread_spins(pos, new, moved, idx, m, P, beads, sides, bnd, ba, bb):
    """Spin the frames of a rigid crankshaft or pivot (already in ``new``; ``m`` moved
    particles) so that its twist is shared by all joints; returns the new count.

    The rigid rotation changes the joint angles only at the two frame boundaries ``ba``
    and ``bb`` (boundary b: the joint between the frames of bonds b - 1 and b; 0 the
    surface clamp, N the bead clamp), by c_a and c_b, which depend on the beads alone
    (spinning a frame about its own bond by psi adds psi to the joint after it and -psi to
    the joint before it, for every joint type: parallel transport commutes with the spin).
    Spinning the frame of bond q by psi_q = sum_{b <= q} (s_b - c_b), s_b = (c_a + c_b)
    (1 / g_b) / sum (1 / g), changes joint b by s_b in all: the twist the rotation made is
    shared in inverse proportion to the joints' stiffness (the least twist energy), and
    psi_N = 0, so the bead's orientation particle is not turned. The map is its own
    reverse with the opposite angle (the reverse rotation meets -c_a, -c_b, whatever the
    spins: they commute) and, for given beads, a rotation of each side particle about its
    bond: Jacobian 1, so the proposal stays symmetric."""
    nbd = sides.shape[0]
    ca = 0.0
    cb = 0.0
    if ba >= 0 and ba <= nbd and bnd[ba] >= 0:
        ca = _wrap_pi(omega(pos, new, moved, P, bnd[ba], True)
                      - omega(pos, new, moved, P, bnd[ba], False))
    if bb >= 0 and bb <= nbd and bnd[bb] >= 0:
        cb = _wrap_pi(omega(pos, new, moved, P, bnd[bb], True)
                      - omega(pos, new, moved, P, bnd[bb], False))
    d = ca + cb
    winv = 0.0
    for b in range(nbd + 1):
        if bnd[b] >= 0:
            winv += 1.0 / P.j_g[bnd[b]]
    if winv == 0.0:
        return m
    psi = 0.0
    R = np.empty((3, 3))
    for q in range(nbd):
        if bnd[q] >= 0:
            psi += d / (P.j_g[bnd[q]] * winv)
        if q == ba:
            psi -= ca
        if q == bb:
            psi -= cb
        if psi == 0.0:
            continue
        r0 = beads[q]
        r1 = beads[q + 1]
        x0 = _at(pos, new, moved, r0, 0)
        y0 = _at(pos, new, moved, r0, 1)
        z0 = _at(pos, new, moved, r0, 2)
        ax = _at(pos, new, moved, r1, 0) - x0
        ay = _at(pos, new, moved, r1, 1) - y0
        az = _at(pos, new, moved, r1, 2) - z0
        nrm = math.sqrt(ax * ax + ay * ay + az * az)
        _axis_rot(R, ax / nrm, ay / nrm, az / nrm, math.cos(psi), math.sin(psi))
        p = sides[q]
        x = _at(pos, new, moved, p, 0) - x0
        y = _at(pos, new, moved, p, 1) - y0
        z = _at(pos, new, moved, p, 2) - z0
        s = moved[p]
        if s == 0:
            idx[m] = p
            m += 1
            moved[p] = m
            s = m
        new[s - 1, 0] = R[0, 0] * x + R[0, 1] * y + R[0, 2] * z + x0
        new[s - 1, 1] = R[1, 0] * x + R[1, 1] * y + R[1, 2] * z + y0
        new[s - 1, 2] = R[2, 0] * x + R[2, 1] * y + R[2, 2] * z + z0
    return m


@numba.njit(cache=True)
def run_twist_moves(pos, P, beads, sides, morient, bnd, mobile, cum, crank_max, crank_angle,
                    pivot_angle, sweep_nm, crank_reach, reach_nm, bond_max_nm, frame_angle,
                    frame_max, ball_nm, kT, uni, gau, stats, terms, span, cpos, lab,
                    spread=False):
    """Metropolis crankshaft, pivot, frame and particle moves of a torsionally constrained
    tether on ``pos`` (modified in place); see :mod:`dnabraid.run.twist_moves`.

    ``beads`` (N + 1: surface ... attachment), ``sides`` (N, side particle of bond i),
    ``morient`` the bead's orientation particle; ``bnd`` (N + 1,) the joint at each frame
    boundary (0: surface clamp, 1 ... N - 1: interior joints, N: bead clamp; -1 none);
    ``mobile`` the particles of particle moves; a rigid move turns by at most
    ``reach_nm`` / rho (rho: the farthest moved bead's distance from the axis or centre)
    and, when a bead travels more than ``sweep_nm``, is refused unless
    :func:`passage_free` (bonds up to ``bond_max_nm``); ``cum`` (4,) cumulative kind
    probabilities; ``stats`` (4, 3) attempted / refused / accepted per kind; ``terms``
    (NTERMS,) the accepted change per term; ``span``: the largest spread of a bonded
    term's members in chain order (bead q at 2q, the side particle of bond q at 2q + 1, m
    at 2N; -1: unknown), so that a pivot about bead k searches the bonds, hinges and
    joints of the moved particles at 2k + 1 ... 2k + span alone (the others move with all
    their partners), and of the moved particles in ``lab`` (the members of the clamps,
    which the lab frame prices even when all of them move); ``cpos`` the chain order of
    each particle. ``spread``: crankshafts and pivots also spin the frames about their own
    bonds so that the twist their rotation puts on the two pivot joints is shared by all the
    joints of the chain (:func:`spread_spins`). Returns the sum of |dE| of accepted moves.
    """
    nbd = beads.shape[0] - 1  # bonds N; attachment beads[N]
    att = beads[nbd]
    nmob = mobile.shape[0]
    i_tw = _I_TWIST  # the index of 'twist' in TERMS ('trap' is 6)
    H, ncon, n_on, dcon, moved, idx, new, dterm = _ch.loop_setup(pos, P, terms.shape[0])
    rinv = np.eye(3)
    center = np.zeros(3)
    R = np.eye(3)
    nbe = beads.shape[0]
    hb = np.empty(nbe)
    rb = np.empty(nbe)
    ab = np.empty(nbe)
    order = np.empty(nbe, np.int64)
    bl = np.empty(pos.shape[0], np.int64)
    nbl = 0
    absum = 0.0
    for t in range(uni.shape[0]):
        r = uni[t, 0]
        kind = 0
        while kind < 3 and r >= cum[kind]:
            kind += 1
        stats[kind, 0] += 1
        flip = False
        rigid = True
        m = 0
        thr = -kT * math.log(uni[t, 5]) if uni[t, 5] > 0.0 else np.inf
        i = 0
        j = 0
        k0 = 0
        if kind == 0:
            # crankshaft: beads i..j (1 <= i <= j <= N-1) and the sides of bonds i-1..j
            # turned about the line through beads i-1 and j+1
            mmax = min(crank_max, nbd - 1)
            if mmax < 1:
                stats[kind, 1] += 1
                continue
            ln = 1 + min(int(uni[t, 3] * mmax), mmax - 1)
            i = 1 + min(int(uni[t, 2] * (nbd - ln)), nbd - 1 - ln)
            j = i + ln - 1
            pa = beads[i - 1]
            pb = beads[j + 1]
            ax = pos[pb, 0] - pos[pa, 0]
            ay = pos[pb, 1] - pos[pa, 1]
            az = pos[pb, 2] - pos[pa, 2]
            nrm = math.sqrt(ax * ax + ay * ay + az * az)
            if nrm < 1e-9:
                stats[kind, 1] += 1
                continue
            ax /= nrm
            ay /= nrm
            az /= nrm
            rho = 0.0
            for k in range(i, j + 1):
                p = beads[k]
                x = pos[p, 0] - pos[pa, 0]
                y = pos[p, 1] - pos[pa, 1]
                z = pos[p, 2] - pos[pa, 2]
                h = x * ax + y * ay + z * az
                rho = max(rho, x * x + y * y + z * z - h * h)
            rho = math.sqrt(max(rho, 0.0))
            amp = crank_angle if rho * crank_angle <= crank_reach else crank_reach / rho
            theta = amp * (2.0 * uni[t, 4] - 1.0)
            if rho * abs(theta) > sweep_nm and not passage_free(
                    pos, beads, i, j, pos[pa, 0], pos[pa, 1], pos[pa, 2], ax, ay, az, theta,
                    bond_max_nm, hb, rb, ab, order):
                stats[kind, 1] += 1
                continue
            R = _ch.rotation_matrix(ax, ay, az, theta)
            for k in range(i, j + 1):
                p = beads[k]
                _ch.rotate_into(pos, R, pos[pa, 0], pos[pa, 1], pos[pa, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
            for k in range(i - 1, j + 1):
                p = sides[k]
                _ch.rotate_into(pos, R, pos[pa, 0], pos[pa, 1], pos[pa, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
        elif kind == 1:
            # pivot: beads k+1..N, the sides of bonds k..N-1 turned about bead k; the
            # orientation particle translated with the attachment (the bead keeps its angle)
            k0 = min(int(uni[t, 2] * nbd), nbd - 1)
            gx = gau[t, 0]
            gy = gau[t, 1]
            gz = gau[t, 2]
            nrm = math.sqrt(gx * gx + gy * gy + gz * gz)
            if nrm == 0.0:
                stats[kind, 1] += 1
                continue
            pc = beads[k0]
            rho = 0.0
            for k in range(k0 + 1, nbd + 1):
                p = beads[k]
                x = pos[p, 0] - pos[pc, 0]
                y = pos[p, 1] - pos[pc, 1]
                z = pos[p, 2] - pos[pc, 2]
                rho = max(rho, x * x + y * y + z * z)
            rho = math.sqrt(rho)
            amp = pivot_angle if rho * pivot_angle <= reach_nm else reach_nm / rho
            theta = amp * (2.0 * uni[t, 4] - 1.0)
            if rho * abs(theta) > sweep_nm and not passage_free(
                    pos, beads, k0 + 1, nbd, pos[pc, 0], pos[pc, 1], pos[pc, 2], gx / nrm,
                    gy / nrm, gz / nrm, theta, bond_max_nm, hb, rb, ab, order):
                stats[kind, 1] += 1
                continue
            R = _ch.rotation_matrix(gx / nrm, gy / nrm, gz / nrm, theta)
            m_on = 0
            for k in range(k0 + 1, nbd + 1):
                p = beads[k]
                _ch.rotate_into(pos, R, pos[pc, 0], pos[pc, 1], pos[pc, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
                if P.has_wca and P.w_on[p]:
                    m_on += 1
            for k in range(k0, nbd):
                p = sides[k]
                _ch.rotate_into(pos, R, pos[pc, 0], pos[pc, 1], pos[pc, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
            if morient >= 0:
                sa = moved[att] - 1
                for c in range(3):
                    new[m, c] = pos[morient, c] + new[sa, c] - pos[att, c]
                idx[m] = morient
                m += 1
                moved[morient] = m
            if span >= 0 and not spread:
                # the moved particles that share a bonded term with an unmoved one
                nbl = 0
                for k in range(k0 + 1, nbd + 1):
                    if 2 * k > 2 * k0 + span:
                        break
                    bl[nbl] = beads[k]
                    nbl += 1
                for k in range(k0, nbd):
                    if 2 * k + 1 > 2 * k0 + span:
                        break
                    bl[nbl] = sides[k]
                    nbl += 1
                if morient >= 0 and 2 * nbd <= 2 * k0 + span:
                    bl[nbl] = morient
                    nbl += 1
                for a in range(lab.shape[0]):
                    p = lab[a]
                    if moved[p] > 0 and cpos[p] > 2 * k0 + span:
                        bl[nbl] = p
                        nbl += 1
            if n_on - m_on < m_on and not spread:
                flip = True
                rinv = _ch.rotation_matrix(gx / nrm, gy / nrm, gz / nrm, -theta)
                for c in range(3):
                    center[c] = pos[pc, c]
        elif kind == 2:
            # frame: frames k..j (slot q < N: side q about bond q; slot N: the bead's
            # orientation particle about the vertical through the attachment) turned by
            # the same angle; only the joints at the run's two ends change
            nsl = nbd + 1 if morient >= 0 else nbd
            lmax = min(frame_max, nsl)
            ln = 1 + min(int(uni[t, 3] * lmax), lmax - 1)
            k0 = min(int(uni[t, 2] * (nsl - ln + 1)), nsl - ln)
            k1 = k0 + ln - 1
            psi = frame_angle * (2.0 * uni[t, 4] - 1.0)
            cp = math.cos(psi)
            sp = math.sin(psi)
            for q in range(k0, k1 + 1):
                if q < nbd:
                    p = sides[q]
                    r0 = beads[q]
                    r1 = beads[q + 1]
                    ax = pos[r1, 0] - pos[r0, 0]
                    ay = pos[r1, 1] - pos[r0, 1]
                    az = pos[r1, 2] - pos[r0, 2]
                    nrm = math.sqrt(ax * ax + ay * ay + az * az)
                    _axis_rot(R, ax / nrm, ay / nrm, az / nrm, cp, sp)
                else:
                    p = morient
                    r0 = att
                    _axis_rot(R, 0.0, 0.0, 1.0, cp, sp)
                _ch.rotate_into(pos, R, pos[r0, 0], pos[r0, 1], pos[r0, 2], p, new, m)
                idx[m] = p
                m += 1
                moved[p] = m
            for c in range(dterm.shape[0]):
                dterm[c] = 0.0
            for b in (k0, k1 + 1):
                if b <= nbd and bnd[b] >= 0:
                    jj = bnd[b]
                    dterm[i_tw] += joint_energy(pos, new, moved, P, jj, True) \
                        - joint_energy(pos, new, moved, P, jj, False)
            if k1 == nbd and P.has_trap:
                # the orientation particle turned: the trap
                i0 = P.t_i
                j0 = P.t_j
                dterm[6] += _ch._trap_at(pos, new, moved, P) - _ch._trap_e(
                    pos[i0, 0], pos[i0, 1], pos[i0, 2], pos[j0, 0], pos[j0, 1], pos[j0, 2], P)
            dE = 0.0
            for c in range(dterm.shape[0]):
                dE += dterm[c]
            if dE <= 0.0 or dE < thr:
                stats[kind, 2] += 1
                absum += abs(dE)
                _ch.apply_accepted(pos, new, idx, m, P, H, terms, dterm)
            for a in range(m):
                moved[idx[a]] = 0
            continue
        else:
            p = _ch.ball_proposal(pos, mobile, nmob, ball_nm, gau[t, 0], gau[t, 1], gau[t, 2],
                              uni[t, 2], uni[t, 3], new)
            if p < 0:
                stats[kind, 1] += 1
                continue
            idx[0] = p
            m = 1
            moved[p] = 1
            rigid = False
        if spread and kind <= 1:
            # crankshaft i..j or pivot about k0: the pivot boundaries' twist shared by all
            m = spread_spins(pos, new, moved, idx, m, P, beads, sides, bnd,
                             i - 1 if kind == 0 else k0, j + 1 if kind == 0 else nbd)
            rigid = False
            flip = False
            bonded = idx[:m]
        else:
            bonded = bl[:nbl] if kind == 1 and span >= 0 else idx[:m]
        dE = _ch.delta_kernel(pos, idx[:m], new[:m], moved, rigid, P, H, dterm, thr, ncon, dcon,
                              flip, rinv, center, bonded)
        if math.isfinite(dE) and (dE <= 0.0 or dE < thr):
            ncon += dcon[0]
            stats[kind, 2] += 1
            absum += abs(dE)
            _ch.apply_accepted(pos, new, idx, m, P, H, terms, dterm)
        for a in range(m):
            moved[idx[a]] = 0
    return absum
