"""Numpy twin of the chiral DNA-DNA interaction (dnabraid units: nm, pN, pN nm).

Continuum model (seed: van der Heijden, "Equilibrium theory of elastic braids", slides 5 and
32, after Kornyshev, Lee, Leikin & Wynveen, Rev. Mod. Phys. 79, 943 (2007)): two strands in
contact carry the energy per unit length of contact

    phi = alpha tan(eta / 2),                                            (slide 32)

where eta is the braid angle, the signed angle by which the tangent t1 must be turned about
the unit chord d1 (from strand 1 to strand 2) to reach t2 (braid frame {t1, d1, u1}, slide 5:
t2 = cos(eta) t1 - sin(eta) u1, u1 = t1 x d1), so that

    eta = atan2((t1 x t2) . d1, t1 . t2).

The bead model replaces the contact integral  E = int phi ds  (slide 5, E = int_0^L phi ds)
by a sum over sample points of each segment against the lines of the partner's segments,
see :func:`pair_terms`:

    E = alpha sum_{a<b} (1/2) [ sum_k (l_a/q) psi(t_{k|b}) w(r_{k|b}) G(c, s_{k|b}) + (a <-> b) ]   (C1)

with q sample points p_k = x_a0 + (k + 1/2)/q e_a on segment a, t_{k|b} the parameter of the
foot of p_k on the (infinite) line of segment b (0 and 1 at its ends), r_{k|b} the distance
from p_k to that line and d the unit vector from p_k to the foot (perpendicular to t_b).

* psi(t) = sigma(t + 1/2) - sigma(t - 1/2) (sigma the C2 step 0 -> 1 on [0, 1]) is the share
  of segment b in the partner seen from p_k: shares of consecutive collinear segments add up to
  exactly 1, so a point facing a straight partner counts once whatever the beads' register.
* w(r) (C2) is the distance weight, a function of the point's distance to the partner (the
  closest distance between the point and the partner's segment line): w = 1 for r <= D_c, the
  contact distance (the capsule contact's D_c in the scenes, docs/chirality.md), and
  w = (1 + x/rho) exp(-x/rho), x = r - D_c, beyond it (C1 at D_c: no slope at contact), times
  a C2 switch to zero between r_s = D_c + 4 rho and r_c = D_c + 6 rho. It is normalised by
  construction: a strand facing its partner at D_c carries g per unit length (A = 1).
* The decay length rho is that of the first helical harmonic of the DNA charge pattern
  (:func:`chiral_range_nm`, Eq. C6), rho = 1/kappa_1 = 1/sqrt(lambda_D^-2 + g^2),
  g = 2 pi / H, H = 3.4 nm: 0.53 nm at 10 mM, 0.45 nm at 150 mM, 0.27 nm at 1 M (it was the
  Debye length lambda_D, 3.04-0.30 nm, before the range of the first helical harmonic ; docs/chiral_range.md).
* G(c, s) = c s rho_f / (rho_f + |c|), rho_f = sqrt(c^2 + s^2) (C3), with c = t_a . t_b and
  s = (t_a x t_b) . d: with eta' = atan(s/c) (eta folded into [-pi/2, pi/2], apolar DNA),
  G = rho_f^2 cos(eta') tan(eta'/2). It vanishes at |eta'| = pi/2 with the same slope from
  both sides (C1 through the fold, no switch) and where eta is undefined (c = s = 0).
* The factor cos(eta') is a Jacobian (C4): the feet of the points of one helix of a two-ply on
  the lines of the other's segments advance by cos(eta) per unit length (the partner curves
  towards the point: 1 - kappa D = 1 - 2 sin^2(eta/2)), so the shares sum to 1/cos(eta) on
  average, and an ideal two-ply carries alpha tan(eta/2) per unit strand length for every
  |eta| < pi/2 (0.3 % for 0.5 nm beads; 2 % low at eta = 26 deg for the 5 nm beads of the
  braid scene, 8 % at 45 deg). A straight crossing at angle eta gets cos(eta) tan(eta/2) per
  unit length of overlap instead.
* Optionally (``bead_spacing_nm`` given to :class:`ChiralKernel`; the capsule scenes) G is
  divided by N(eta'), an even cubic in eta'^2 fitted so that the ideal two-ply of that bead
  spacing carries tan(eta/2) per unit length (C5; within 1 % for 10-60 deg).

Why rho = 1/kappa_1 (C6)
------------------------
Kornyshev & Leikin's mean-field theory of helical molecules (J. Chem. Phys. 107, 3656
(1997); reviewed in Kornyshev et al., Rev. Mod. Phys. 79, 943 (2007), Sec. III) expands the
surface charge of each molecule in helical harmonics n (cos n(phi - g z), g = 2 pi / H, H the
helical pitch). Screened electrostatics (Debye-Hueckel, kappa_D = 1/lambda_D) turns the
harmonic n of the potential outside a molecule into K_n(kappa_n r) cos n(phi - g z), with

    kappa_n = sqrt(kappa_D^2 + n^2 g^2),                                        (C6)

because Laplace(psi) = kappa_D^2 psi with a z-dependence exp(i n g z) leaves the radial
equation of the modified Bessel functions with kappa_D^2 + n^2 g^2. The pair energy per unit
length of two parallel molecules at axis distance R is then a sum of terms
a_n(R) cos(n Phi) with a_n proportional to K_0(kappa_n R) (Kornyshev & Leikin 1997). The
n = 0 term does not depend on the molecules' helical structure or its sense: it is the
achiral, lambda_D-ranged repulsion, here part of the excluded volume. Every chiral effect
(the torque between tilted molecules, Kornyshev & Leikin, Phys. Rev. E 62, 2576 (2000); the
braid-handedness preference, Cortini et al., Biophys. J. 101, 875 (2011)) needs n >= 1 and is
dominated by n = 1 (n = 2 decays with kappa_2 ~ 2 g, twice as fast). So the chiral energy at
axis distance r falls like K_0(kappa_1 r) ~ sqrt(pi / (2 kappa_1 r)) exp(-kappa_1 r):
relative to contact, exp(-kappa_1 (r - Delta)) sqrt(Delta / r). The weight keeps the
exponential, rho = 1/kappa_1, and neglects the algebraic factor sqrt(Delta / r) (> 0.95 at
r - Delta = rho for every diameter of forcefields/dna.toml; the normalisation (C2)/(C5)
absorbs what is left at contact) and the tilt's small change of the effective g for
|eta| <= 60 deg. H = 3.4 nm is the B-DNA helical repeat (10-10.5 bp x 0.33-0.34 nm), the value
the Kornyshev papers use. The equation numbers of these papers were not checked here (not at
hand); the statement (C6) is their standard result. alpha stays defined at the reference
distance D_c (C2, C5); with the capsule contact the strands touch there; with the bead WCA
contact they sit farther apart (~2^(1/6) Delta), where the weight leaves less of alpha:
docs/chiral_range.md.

Everything here is brute force over all segment pairs: it is the oracle for the pair search
and the OpenMM force in :mod:`dnabraid.forces.chiral`, which share :func:`pair_terms`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

#: r_c = Delta + CUTOFF_RANGES rho: the weight is exactly zero beyond (rho = chiral_range_nm).
CUTOFF_RANGES = 6.0
#: The distance switch starts at r_s = Delta + SWITCH_RANGES rho.
SWITCH_RANGES = 4.0
#: Helical pitch H of B-DNA (nm): the wavenumber of the charge pattern is g = 2 pi / H
#: (forcefields/chiral.toml [helix] pitch_nm; tested equal).
HELIX_PITCH_NM = 3.4
#: Former start of the angular switch (rad); kept for callers, unused since the apolar factor
#: cos(eta') tan(eta'/2) (Eq. C3) vanishes at 90 deg by itself.
ETA_ON = math.pi / 3.0


def chiral_range_nm(debye_nm, pitch_nm=HELIX_PITCH_NM):
    """Decay length rho = 1/kappa_1 = 1/sqrt(lambda_D^-2 + g^2) of the chiral weight (nm).

    Eq. (C6) of the module docstring: the first helical harmonic of the DNA charge pattern
    (Kornyshev & Leikin, J. Chem. Phys. 107, 3656 (1997); Kornyshev et al., Rev. Mod. Phys.
    79, 943 (2007)), g = 2 pi / ``pitch_nm``. Shorter than both lambda_D and 1/g = 0.54 nm.
    """
    debye = float(debye_nm)
    pitch = float(pitch_nm)
    if not (debye > 0 and pitch > 0 and math.isfinite(debye) and math.isfinite(pitch)):
        raise ValueError(f"chiral_range_nm: debye_nm and pitch_nm must be finite and > 0, got "
                         f"{debye_nm!r}, {pitch_nm!r}")
    g = 2.0 * math.pi / pitch
    return 1.0 / math.sqrt(debye**-2 + g * g)


def _smootherstep(x):
    """C2 switch 1 -> 0 on x in [0, 1]: 1 - 10x^3 + 15x^4 - 6x^5, and its derivative."""
    x = np.clip(x, 0.0, 1.0)
    s = 1.0 - x**3 * (10.0 - 15.0 * x + 6.0 * x * x)
    ds = -30.0 * x * x * (1.0 - x) ** 2
    return s, ds


class ChiralKernel:
    """Distance weight w(d) and angular factor G(c, s) of Eq. (C1); see the module docstring.

    Parameters
    ----------
    delta_nm : float
        Contact distance D_c: the weight is 1 (flat) at and below it.
    debye_nm : float
        Debye length lambda_D of the salt.
    range_nm : float, optional
        Decay length rho of the weight. Default :func:`chiral_range_nm` of ``debye_nm`` and
        ``pitch_nm`` (Eq. C6); give it only to study another range.
    pitch_nm : float
        Helical pitch H in Eq. (C6).
    cutoff_ranges, switch_ranges : float
        r_c = D_c + cutoff_ranges rho, r_s = D_c + switch_ranges rho.
    eta_on_rad : float
        Kept for the call signature of older code; the angular factor has no switch any
        more (Eq. C3), so it is unused.

    Attributes
    ----------
    delta, debye, pitch, range, r_s, r_c
        D_c, lambda_D, H, rho (nm), the switch and cutoff distances (nm).
    amplitude : float
        1: w = 1 at contact is the normalisation (Eq. C2), per unit length of strand.
    """

    def __init__(self, delta_nm, debye_nm, *, range_nm=None, pitch_nm=HELIX_PITCH_NM,
                 cutoff_ranges=CUTOFF_RANGES, switch_ranges=SWITCH_RANGES, eta_on_rad=ETA_ON,
                 calibrate=True, bead_spacing_nm=None, subdivisions=None):
        self.delta = float(delta_nm)
        self.debye = float(debye_nm)
        if not (self.delta > 0 and self.debye > 0):
            raise ValueError(f"delta_nm and debye_nm must be > 0, got {delta_nm!r}, {debye_nm!r}")
        self.pitch = float(pitch_nm)
        self.range = (chiral_range_nm(self.debye, self.pitch) if range_nm is None
                      else float(range_nm))
        if not (self.range > 0 and math.isfinite(self.range)):
            raise ValueError(f"range_nm must be finite and > 0, got {range_nm!r}")
        if not 0 < switch_ranges < cutoff_ranges:
            raise ValueError("need 0 < switch_ranges < cutoff_ranges, got "
                             f"{switch_ranges!r}, {cutoff_ranges!r}")
        self.r_c = self.delta + cutoff_ranges * self.range
        self.r_s = self.delta + switch_ranges * self.range
        self.eta_on = float(eta_on_rad)
        self.amplitude = 1.0
        self.ncoef = np.array([1.0])
        if calibrate and bead_spacing_nm is not None:
            q = (default_subdivisions(bead_spacing_nm, self.delta, self.debye,
                                      range_nm=self.range)
                 if subdivisions is None else int(subdivisions))
            self.ncoef = np.array(_two_ply_ncoef(self.delta, self.range, self.r_s, self.r_c,
                                                 float(bead_spacing_nm), q))

    def __setstate__(self, st):
        # A kernel pickled before the range of the first helical harmonic has no ``range``:
        # it decayed with the Debye length, and a restored copy keeps that range.
        st.setdefault("range", st["debye"])
        st.setdefault("pitch", HELIX_PITCH_NM)
        self.__dict__.update(st)

    def weight(self, r):
        """w(r) and dw/dr (Eq. C2): 1 for r <= D_c, (1 + x/rho) exp(-x/rho) beyond
        (x = r - D_c), times a C2 switch to 0 between r_s and r_c."""
        r = np.asarray(r, float)
        x = np.maximum(r - self.delta, 0.0) / self.range
        ex = np.exp(-x)
        f = (1.0 + x) * ex
        df = -x * ex / self.range
        c, dc = _smootherstep((r - self.r_s) / (self.r_c - self.r_s))
        dc = dc / (self.r_c - self.r_s)
        return f * c, df * c + f * dc

    def angular(self, c, s):
        """G(c, s) = c s rho / ((rho + |c|) N(eta')), rho = sqrt(c^2 + s^2), and dG/dc, dG/ds
        (Eq. C3).

        ``c = t1 . t2`` and ``s = (t1 x t2) . d``. With eta' = atan(s / c), eta folded into
        [-pi/2, pi/2] (apolar DNA), G = rho^2 cos(eta') tan(eta'/2) / N(eta'): the apolar
        fold's c s (unchanged by t -> -t of either strand) times 1 / (1 + cos eta'). G vanishes
        at |eta'| = pi/2 with the same slope from both sides (C1 across the fold; N is even)
        and where eta is undefined (c = s = 0). The factor cos(eta') is the Jacobian of a
        two-ply (Eq. C4); N(eta') = polyval(ncoef, eta'^2) the bead two-ply's (Eq. C5).
        """
        c = np.asarray(c, float)
        s = np.asarray(s, float)
        rho = np.sqrt(c * c + s * s)
        ok = rho > 1e-12
        rr = np.where(ok, rho, 1.0)
        A = rr + np.abs(c)
        G = c * s * rr / A
        dGc = s * rr / A + c * s * (c / rr) / A - G * (c / rr + np.sign(c)) / A
        dGs = c * rr / A + c * s * (s / rr) / A - G * (s / rr) / A
        if len(self.ncoef) > 1 or self.ncoef[0] != 1.0:
            sg = np.where(c < 0.0, -1.0, 1.0)
            eta = np.arctan2(sg * s, np.abs(c))  # folded, [-pi/2, pi/2]
            e2 = eta * eta
            n = np.polyval(self.ncoef, e2)
            dn = np.polyval(np.polyder(self.ncoef), e2) * 2.0 * eta
            r2 = rr * rr
            dGc = (dGc - G * dn * (-s / r2) / n) / n
            dGs = (dGs - G * dn * (c / r2) / n) / n
            G = G / n
        return (np.where(ok, G, 0.0), np.where(ok, dGc, 0.0), np.where(ok, dGs, 0.0))

    def target(self, eta):
        """alpha-free energy per unit strand length of an ideal two-ply: tan(eta/2)
        (Eq. C4-C5; |eta| < pi/2)."""
        return np.tan(0.5 * np.asarray(eta, float))


def _share(t):
    """psi(t) = sigma(t + 1/2) - sigma(t - 1/2) and dpsi/dt (sigma: C2 step 0 -> 1 on [0, 1]).

    The share of a segment in the partner polyline seen from a point whose foot on the
    segment's line is at parameter t: the shares of consecutive collinear segments add up to 1
    exactly (Eq. C1)."""
    s1, d1 = _smootherstep(t + 0.5)
    s2, d2 = _smootherstep(t - 0.5)
    return s2 - s1, d2 - d1


def bead_two_ply(eta, delta_nm, bead_spacing_nm, n_beads, shift=0.0):
    """Ideal two-ply of two polylines with beads every ``bead_spacing_nm`` of arc on helices
    of radius delta/2 (braid angle ``eta``; right-handed for eta < 0), strand 2's beads shifted
    by ``shift`` spacings along its arc. Returns (positions, chains)."""
    R = 0.5 * float(delta_nm)
    th = 0.5 * abs(float(eta))
    hand = 1.0 if eta <= 0 else -1.0
    pitch = R / math.tan(th)
    ds = math.hypot(R, pitch)
    b = float(bead_spacing_nm)
    out = []
    for off, sh in ((0.0, 0.0), (math.pi, shift * b)):
        ph = (np.arange(n_beads) * b + sh) / ds
        out.append(np.stack([R * np.cos(hand * ph + off), R * np.sin(hand * ph + off),
                             pitch * ph], 1))
    return np.vstack(out), [np.arange(n_beads), n_beads + np.arange(n_beads)]


#: Braid angles (deg) of the calibration of N(eta) (Eq. C5).
CALIBRATION_DEG = (5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0, 85.0)


@functools.lru_cache(maxsize=64)
def _two_ply_ncoef(delta, rho, r_s, r_c, b, q, iterations=3):
    """Coefficients of N(eta) (a cubic in eta^2) such that the ideal bead two-ply
    (:func:`bead_two_ply`, spacing b, q samples) carries tan(eta/2) per unit strand length
    (Eq. C5): the energy per unit length of the middle (difference of a 24- and a 48-bead
    ply, two registers) over tan(eta/2), at :data:`CALIBRATION_DEG`; fixed-point passes
    N <- N x ratio, since off-contact sample points see other angles than the ply's."""
    k = ChiralKernel.__new__(ChiralKernel)
    k.delta, k.range, k.r_s, k.r_c = delta, rho, r_s, r_c
    k.ncoef = np.array([1.0])
    etas = np.radians(CALIBRATION_DEG)
    geometry = []
    for eta in etas:
        for shift in (0.0, 0.5):
            for nb in (24, 48):
                pos, ch = bead_two_ply(-eta, delta, b, nb, shift)
                seg, cid, _, _, _ = segments_of(ch)
                a, bb = np.triu_indices(len(seg), 1)
                keep = cid[a] != cid[bb]
                geometry.append((pos, seg, a[keep], bb[keep]))
    for _ in range(iterations):
        e = np.array([pair_terms(pos, seg, a, bb, k, q)[0] for pos, seg, a, bb in geometry])
        e = e.reshape(len(etas), 2, 2)
        per_length = (e[:, :, 1] - e[:, :, 0]).mean(axis=1) / (24 * b)
        ratio = per_length / np.tan(-0.5 * etas)
        k.ncoef = np.polyfit(etas**2, np.polyval(k.ncoef, etas**2) * ratio, 3)
    return tuple(k.ncoef)


def segments_of(chains, closed=False):
    """Segments of a list of chains.

    Parameters
    ----------
    chains : list of int arrays
        Ordered particle indices of each strand.
    closed : bool or sequence of bool
        Whether each chain is a ring (a segment joins the last bead to the first).

    Returns
    -------
    seg : (M, 2) int array
        Bead indices (i0, i1) of each segment.
    chain_id : (M,) int array
    pos_in_chain : (M,) int array
    chain_nseg : (M,) int array
        Number of segments of the segment's chain.
    ring : (M,) bool array
    """
    chains = [np.asarray(c, dtype=np.int64).ravel() for c in chains]
    if np.ndim(closed) == 0:
        closed = [bool(closed)] * len(chains)
    if len(closed) != len(chains):
        raise ValueError(f"closed: expected {len(chains)} flags, got {len(closed)}")
    seg, cid, pos, nseg, ring = [], [], [], [], []
    for k, (c, cl) in enumerate(zip(chains, closed)):
        if len(c) < 2:
            continue
        s = np.stack([c[:-1], c[1:]], axis=1)
        if cl and len(c) > 2:
            s = np.vstack([s, [[c[-1], c[0]]]])
        seg.append(s)
        cid.append(np.full(len(s), k))
        pos.append(np.arange(len(s)))
        nseg.append(np.full(len(s), len(s)))
        ring.append(np.full(len(s), bool(cl and len(c) > 2)))
    if not seg:
        e = np.zeros(0, np.int64)
        return np.zeros((0, 2), np.int64), e, e, e, np.zeros(0, bool)
    return (np.vstack(seg), np.concatenate(cid), np.concatenate(pos), np.concatenate(nseg),
            np.concatenate(ring))


def pair_allowed(a, b, chain_id, pos_in_chain, chain_nseg, ring, exclude_neighbours):
    """Mask of segment pairs (a, b) that interact: different chains, or on the same chain
    more than ``exclude_neighbours`` segments apart (cyclically on a ring)."""
    same = chain_id[a] == chain_id[b]
    sep = np.abs(pos_in_chain[a] - pos_in_chain[b])
    sep = np.where(ring[a], np.minimum(sep, chain_nseg[a] - sep), sep)
    return (~same) | (sep > exclude_neighbours)


def _directed(pos, seg, a, b, kernel, q, r_cut, grad):
    """Points of segments ``a`` against the lines of segments ``b`` (one direction of
    Eq. C1); adds dE/dx to ``grad``, returns E (both in units of alpha)."""
    i0, i1, j0, j1 = seg[a, 0], seg[a, 1], seg[b, 0], seg[b, 1]
    xa0, xb0 = pos[i0], pos[j0]
    ea = pos[i1] - xa0
    eb = pos[j1] - xb0
    la = np.linalg.norm(ea, axis=1)
    lb = np.linalg.norm(eb, axis=1)
    ta = ea / la[:, None]
    tb = eb / lb[:, None]
    npair = len(a)
    p = np.repeat(np.arange(npair), q)
    f = np.tile((np.arange(q) + 0.5) / q, npair)
    w0 = xa0[p] + f[:, None] * ea[p] - xb0[p]
    L2 = (lb * lb)[p]
    t = np.einsum("ij,ij->i", w0, eb[p]) / L2
    r = t[:, None] * eb[p] - w0
    rn = np.linalg.norm(r, axis=1)
    live = (rn < r_cut) & (t > -0.5) & (t < 1.5) & (rn > 1e-12)
    if not np.any(live):
        return 0.0
    p, f, w0, L2, t, r, rn = p[live], f[live], w0[live], L2[live], t[live], r[live], rn[live]
    d = r / rn[:, None]
    tap, tbp, ebp = ta[p], tb[p], eb[p]
    cr = np.cross(tap, tbp)
    c = np.einsum("ij,ij->i", tap, tbp)
    s = np.einsum("ij,ij->i", cr, d)
    psi, dpsi = _share(t)
    W, dW = kernel.weight(rn)
    G, dGc, dGs = kernel.angular(c, s)
    lq = la[p] / q
    e = float(np.sum(lq * psi * W * G))
    # primitive gradients: l_a, t, r, t_a, t_b
    g_la = psi * W * G / q
    g_t = lq * dpsi * W * G
    g_r = (lq * psi)[:, None] * ((dW * G)[:, None] * d
                                + (W * dGs / rn)[:, None] * (cr - s[:, None] * d))
    k = (lq * psi * W)[:, None]
    g_ta = k * (dGc[:, None] * tbp + dGs[:, None] * np.cross(tbp, d))
    g_tb = k * (dGc[:, None] * tap + dGs[:, None] * np.cross(d, tap))
    # r = t e_b - w0; t = (w0 . e_b) / |e_b|^2
    g_tt = g_t + np.einsum("ij,ij->i", g_r, ebp)
    g_w0 = -g_r + (g_tt / L2)[:, None] * ebp
    g_eb = t[:, None] * g_r + (g_tt / L2)[:, None] * (w0 - 2.0 * t[:, None] * ebp)
    g_eb += (g_tb - np.einsum("ij,ij->i", g_tb, tbp)[:, None] * tbp) / lb[p][:, None]
    g_ea = (g_ta - np.einsum("ij,ij->i", g_ta, tap)[:, None] * tap) / la[p][:, None] \
        + g_la[:, None] * tap + f[:, None] * g_w0
    # w0 = x_a0 + f e_a - x_b0, e_a = x_a1 - x_a0, e_b = x_b1 - x_b0
    np.add.at(grad, i0[p], g_w0 - g_ea)
    np.add.at(grad, i1[p], g_ea)
    np.add.at(grad, j0[p], -g_w0 - g_eb)
    np.add.at(grad, j1[p], g_eb)
    return e


def pair_terms(pos, seg, a, b, kernel, q, r_cut=None):
    """Energy (in units of alpha, i.e. nm) and gradient of Eq. (C1) over segment pairs (a, b).

    Each unordered pair is taken both ways (points of a against the line of b and points of
    b against the line of a), each with weight 1/2.

    Parameters
    ----------
    pos : (N, 3) float array, nm
    seg : (M, 2) int array of segments
    a, b : (P,) int arrays of segment indices (each unordered pair once)
    kernel : ChiralKernel
    q : int
        Sample points per segment, at fractions (k + 1/2)/q.

    Returns
    -------
    e : float
        Eq. (C1) in nm (multiply by alpha for the energy).
    grad : (N, 3) float array
        dE/dx in the same units (1; the force is -alpha grad).
    """
    pos = np.asarray(pos, float)
    grad = np.zeros_like(pos)
    a = np.asarray(a, np.int64)
    b = np.asarray(b, np.int64)
    if len(a) == 0:
        return 0.0, grad
    if r_cut is None:
        r_cut = kernel.r_c
    g1 = np.zeros_like(pos)
    e = _directed(pos, seg, a, b, kernel, int(q), r_cut, g1)
    e += _directed(pos, seg, b, a, kernel, int(q), r_cut, g1)
    return 0.5 * e, 0.5 * g1


def default_subdivisions(bead_spacing_nm, delta_nm, debye_nm, *, range_nm=None):
    """Sample points per segment so that the sample spacing b/q <= 1.6 sqrt(Delta rho).

    Along a partner strand the weight is close to a Gaussian of width w = sqrt(Delta rho) in
    the offset u (rho = ``range_nm``, default :func:`chiral_range_nm` of ``debye_nm``); a sum
    over samples spaced by h reproduces the integral to ~2 exp(-2 pi^2 w^2 / h^2) (Poisson
    summation), <= 1e-3 for h <= 1.6 w; and at least 2: the shares psi of a curved partner
    (Eq. C1) sum to 1/cos(eta) only on average over where the feet land, and one midpoint
    per segment of two strands in perfect register sees the same phase everywhere (0.5 nm
    two-ply at 35 deg: 11 % low with q = 1, 0.3 % with q = 2).
    """
    rho = chiral_range_nm(debye_nm) if range_nm is None else float(range_nm)
    width = 1.6 * math.sqrt(float(delta_nm) * rho)
    return max(2, math.ceil(float(bead_spacing_nm) / width - 1e-9))


def chiral_energy_forces(positions_nm, chains, alpha_pN, *, delta_nm, debye_nm,
                         exclude_neighbours, subdivisions=1, closed=False, range_nm=None,
                         cutoff_ranges=CUTOFF_RANGES, switch_ranges=SWITCH_RANGES,
                         eta_on_rad=ETA_ON, calibrate_spacing_nm=None):
    """Chiral energy (pN nm) and forces (pN) by brute force over all segment pairs.

    Parameters
    ----------
    positions_nm : (N, 3) array, nm
    chains : list of int arrays
        Ordered bead indices of each strand.
    alpha_pN : float
        alpha, energy per unit contact length (pN nm / nm = pN). alpha > 0 favours eta < 0,
        i.e. right-handed braids (docs/chirality.md).
    delta_nm, debye_nm : float
        Effective diameter and Debye length (the weight decays with
        :func:`chiral_range_nm` of it, Eq. C6).
    exclude_neighbours : int
        Segments on the same chain at most this many segments apart do not interact.
    subdivisions : int
        Sample points per segment (q in Eq. C1).
    closed : bool or sequence of bool
        Ring chains.
    range_nm, cutoff_ranges, switch_ranges, eta_on_rad
        Passed to :class:`ChiralKernel`.
    calibrate_spacing_nm : float, optional
        Bead spacing of the two-ply calibration N(eta) (Eq. C5; the twin of
        ``chiral_force(..., calibrate_two_ply=True)``); None: N = 1.

    Returns
    -------
    energy_pN_nm : float
    forces_pN : (N, 3) float array
    """
    pos = np.asarray(positions_nm, float)
    kernel = ChiralKernel(delta_nm, debye_nm, range_nm=range_nm, cutoff_ranges=cutoff_ranges,
                          switch_ranges=switch_ranges, eta_on_rad=eta_on_rad,
                          bead_spacing_nm=calibrate_spacing_nm, subdivisions=subdivisions)
    seg, cid, pic, nseg, ring = segments_of(chains, closed)
    a, b = np.triu_indices(len(seg), 1)
    keep = pair_allowed(a, b, cid, pic, nseg, ring, int(exclude_neighbours))
    e, g = pair_terms(pos, seg, a[keep], b[keep], kernel, int(subdivisions))
    return float(alpha_pN) * e, -float(alpha_pN) * g
