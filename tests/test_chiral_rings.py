"""Tests of dnabraid.statics.chiral_rings (two linked rings with twist and the chiral term).

Every reference is independent of the code under test: finite differences of the energies,
dnabraid.geometry (Gauss writhe, linking number, ribbon twist), the closed_braid solver,
and tan(eta/2) of the exact uniform ply. Small models (Delta/L = 0.05, b = Delta/2: 40 beads
per ring) keep the file under ~15 s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnabraid.errors import UserError
from dnabraid.geometry.curves import gauss_linking_number, writhe
from dnabraid.geometry.ribbon import ring_twist
from dnabraid.statics import chiral_rings as cr
from dnabraid.statics import closed_braid as cb

SMALL = dict(diameter_over_length=0.05, spacing_over_diameter=0.5, window_over_diameter=2.0)

#: central-difference gradient checks: |analytic - FD| <= FD_REL x max|gradient|
FD_REL = 1e-6


def _trefoilish(M=48, seed=3):
    u = np.linspace(0, 2 * math.pi, M, endpoint=False)
    x = np.column_stack([np.cos(u) + 0.4 * np.cos(2 * u), np.sin(u) - 0.3 * np.sin(2 * u),
                         0.5 * np.sin(3 * u)])
    return x + 0.01 * np.random.default_rng(seed).normal(size=x.shape)


def _fd_check(f, g, x, idx, h=1e-7):
    err, scale = 0.0, np.max(np.abs(g))
    for i in idx:
        for k in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, k] += h
            xm[i, k] -= h
            err = max(err, abs((f(xp) - f(xm)) / (2 * h) - g[i, k]))
    return err, scale


def _perturbed(model, amp=0.02, seed=0):
    prob = cr.make_problem(model)
    x = cr.initial_geometry(model)
    x = x + amp * prob.delta * np.random.default_rng(seed).normal(size=x.shape)
    return prob, x


def test_writhe_gradient_matches_finite_differences_of_the_gauss_writhe():
    x = _trefoilish()
    g = cr.writhe_gradient(x)
    err, scale = _fd_check(writhe, g, x, range(0, 48, 5), h=1e-6)
    assert err <= FD_REL * scale


def test_writhe_obeys_lk_equals_tw_plus_wr():
    # ribbon: push-off along the part of the radial direction normal to each bond
    x = _trefoilish(M=120)
    t = np.roll(x, -1, 0) - x
    t /= np.linalg.norm(t, axis=1)[:, None]
    rad = np.column_stack([x[:, 0], x[:, 1], np.zeros(len(x))])
    u = rad - np.sum(rad * t, axis=1)[:, None] * t
    u /= np.linalg.norm(u, axis=1)[:, None]
    sides = x + 1e-3 * u
    lk = gauss_linking_number(x, sides)
    tw, wr = ring_twist(x, sides), writhe(x)
    assert abs(lk - round(lk)) < 1e-6
    # White's theorem for the polygonal ribbon (discretisation 1e-3 at 120 vertices)
    assert abs(tw + wr - lk) < 1e-3


def test_twist_energy_gradient_matches_finite_differences():
    model = cr.ChiralRings(lk_ring=3.0, alpha_B_per_L2=0.0, **SMALL)
    prob, x = _perturbed(model, amp=0.2)
    g = cr.twist_gradient(x, prob)
    err, scale = _fd_check(lambda y: cr.twist_energy(y, prob), g, x, range(0, 80, 7))
    assert err <= FD_REL * scale


def _chiral_fd_check(x, prob, pairs):
    """The chiral gradient against finite differences of its energy; returns the energy."""
    E, g = cr.chiral_energy_gradient(x, prob, pairs)
    err, scale = _fd_check(lambda y: cr.chiral_energy_gradient(y, prob, pairs,
                                                               want_grad=False)[0],
                           g, x, range(0, 80, 7))
    assert err <= FD_REL * scale
    return E


@pytest.mark.parametrize("alpha", [800.0, -300.0])
def test_chiral_energy_gradient_matches_finite_differences(alpha):
    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=alpha, **SMALL)
    prob, x = _perturbed(model, amp=0.2)
    pairs = cr.chiral_pairs(x, prob, margin=0.5 * prob.delta)
    E = _chiral_fd_check(x, prob, pairs)
    assert E != 0.0


def test_bilateral_gradient_matches_finite_differences():
    model = cr.ChiralRings(lk_ring=0.0, **SMALL)
    prob, x = _perturbed(model, amp=0.02)
    cand = cr.bilateral_candidates(x, prob)
    _, g = cr.bilateral_energy_gradient(x, prob, cand)
    err, scale = _fd_check(lambda y: cr.bilateral_energy_gradient(y, prob, cand,
                                                                  want_grad=False)[0],
                           g, x, range(0, 80, 7), h=1e-9)
    assert err <= 1e-5 * scale


def test_chiral_energy_flips_sign_under_reflection():
    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=1000.0, **SMALL)
    prob, x = _perturbed(model, amp=0.1)
    mirror = x * np.array([1.0, 1.0, -1.0])
    E = cr.chiral_energy_gradient(x, prob, want_grad=False)[0]
    Em = cr.chiral_energy_gradient(mirror, prob, want_grad=False)[0]
    assert E > 0                     # the left-handed (Lk_12 = -1) link is disfavoured
    assert Em == pytest.approx(-E, rel=1e-12)


def test_chiral_energy_is_alpha_times_the_contact_integral_of_tan_half_eta():
    # the uniform start has eta = 2 asin(pi Delta/L) along the whole contact (length L)
    # the seed's Delta/L = 0.02 (no relaxation here, so the full size is cheap)
    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=1.0, start_noise=0.0)
    prob = cr.make_problem(model)
    x = cr.initial_geometry(model)
    E = cr.chiral_energy_gradient(x, prob, want_grad=False)[0]
    eta = 2 * math.asin(math.pi * model.diameter_over_length)
    # 0.2 %: the ply on a torus differs from the straight uniform ply at O((Delta/L)^2)
    assert E == pytest.approx(math.tan(eta / 2) * 1.0, rel=2e-3)
    # and against closed_braid's own braid-angle measurement (closest point on the
    # polyline) on the same torus ply sampled four times finer (its O(b^2) error < 0.1 %)
    fine = cb.ClosedBraid(topology="link", n=1, diameter_nm=0.02, diameter_over_length=0.02,
                          bending_stiffness_pN_nm2=1.0, spacing_over_radius=0.25,
                          start_noise=0.0)
    m = cb.measure(np.vstack(cb.initial_geometry(fine)), fine)
    ref = float(np.sum(np.tan(m["eta"] / 2)) * fine.bead_spacing_nm)
    assert E == pytest.approx(ref, rel=2e-3)


def test_small_alpha_energy_slope_is_the_contact_integral():
    """Hellmann-Feynman: dE*/dalpha at alpha = 0 is int tan(eta/2) w ds at the alpha = 0
    minimum (here measured by closed_braid.measure, an independent partner search)."""
    base = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=0.0, start_noise=0.0, **SMALL)
    r0 = cr.solve(base, stability=False)
    assert r0["converged"]
    alpha = 2.0
    r1 = cr.solve(dataclass_replace(base, alpha_B_per_L2=alpha), r0["x"], stability=False)
    assert r1["converged"]
    slope = (r1["energy_B_per_L"] - r0["energy_B_per_L"]) / alpha
    prob = cr.make_problem(base)
    ref = cr.chiral_energy_gradient(r0["x"], prob, alpha=1.0, want_grad=False)[0]
    # the second-order term (alpha/2) d^2E*/dalpha^2 is below 1e-3 of the slope here
    assert slope == pytest.approx(ref, rel=1e-3)
    # and the slope is tan(eta/2) over the contact (length L) of the uniform ply, within
    # the torus ply's O((Delta/L)^2) difference
    eta = 2 * math.asin(math.pi * base.diameter_over_length)
    assert slope == pytest.approx(math.tan(eta / 2), rel=5e-3)


@pytest.mark.slow
def test_reproduces_closed_braid_without_twist_load():
    """Slow (two relaxations, ~30 s on a loaded 2-core machine): run with -m slow."""
    braid = cb.ClosedBraid(topology="link", n=2, diameter_nm=0.05, diameter_over_length=0.05,
                           bending_stiffness_pN_nm2=1.0, spacing_over_radius=1.0,
                           start_noise=0.0)
    ref = cb.solve(braid, check_saddle=False)
    wr = np.mean(ref["writhe_per_ring"])
    model = cr.ChiralRings(lk_ring=float(wr), alpha_B_per_L2=0.0, n=2, contact="hard",
                           start_noise=0.0, **SMALL)
    res = cr.solve(model, stability=False)
    assert res["converged"]
    # same energy (bending) within 1e-4 relative, same mean braid angle within 1e-3 rad
    assert res["energy_terms_B_per_L"]["bend"] == pytest.approx(
        ref["bending_energy_over_B_per_L"], rel=1e-4)
    mine = cb.measure(res["x"], braid)          # closed_braid's own measurement
    assert mine["eta_mean"] == pytest.approx(ref["eta_mean"], abs=1e-3)
    assert mine["pressure_mean"] == pytest.approx(ref["pressure_mean"], rel=1e-2)
    assert res["linking_number"] == pytest.approx(-2.0, abs=1e-6)


def test_bad_input_is_refused():
    with pytest.raises(UserError, match="contact"):
        cr.ChiralRings(contact="glue")
    with pytest.raises(UserError, match="spacing_over_diameter"):
        cr.ChiralRings(spacing_over_diameter=0.8)
    with pytest.raises(UserError, match="twist_over_bend"):
        cr.ChiralRings(twist_over_bend=-1.0)


def dataclass_replace(obj, **kw):
    import dataclasses

    return dataclasses.replace(obj, **kw)


# -- the apolar fold, contact partners, Michell's threshold, continuation (session 14) ------

def _reversed_ring2(x, prob):
    y = x.copy()
    sl = prob.ring(1)
    y[sl] = x[sl][::-1]
    return y


def test_chiral_energy_is_apolar():
    """DNA is apolar: reversing ring 2's direction (every t_j -> -t_j, an antiparallel
    contact) leaves the folded term unchanged (docs/chirality.md, Eq. C3); tan(eta/2) itself
    diverges there."""
    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=700.0, **SMALL)
    prob, x = _perturbed(model, amp=0.1)
    E = cr.chiral_energy_gradient(x, prob, want_grad=False)[0]
    Er = cr.chiral_energy_gradient(_reversed_ring2(x, prob), prob, want_grad=False)[0]
    assert E > 0
    assert Er == pytest.approx(E, rel=1e-12)


def test_antiparallel_chiral_gradient_matches_finite_differences():
    """The fold's |x| branch (antiparallel tangents, ring 2 reversed) against central
    differences of the folded energy."""
    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=800.0, **SMALL)
    prob, x = _perturbed(model, amp=0.2)
    x = _reversed_ring2(x, prob)
    pairs = cr.chiral_pairs(x, prob, margin=0.5 * prob.delta)
    assert _chiral_fd_check(x, prob, pairs) > 0


def test_partner_window_finds_the_global_closest_point():
    model = cr.ChiralRings(lk_ring=0.0, **SMALL)
    prob, x = _perturbed(model, amp=0.05)
    E_global = cr.bilateral_energy_gradient(x, prob, want_grad=False)[0]
    d_global = cr.closest_on_other_ring(x, prob, cr.bilateral_candidates(x, prob))[3]
    cr.update_partners(x, prob)
    assert prob.partner is not None
    d_window = cr.closest_on_other_ring(x, prob, cr.bilateral_candidates(x, prob))[3]
    np.testing.assert_allclose(d_window, d_global, rtol=0, atol=1e-14)
    assert cr.bilateral_energy_gradient(x, prob, want_grad=False)[0] == pytest.approx(
        E_global, rel=1e-12)
    # partners lie on the other ring
    assert np.all(prob.ring_of[prob.partner] != prob.ring_of)


def test_stale_partners_are_recentred_not_clamped():
    """Partners left 2 PARTNER_WINDOW beads behind (a step that slid the rings further than
    the window): the windowed search re-centres until it finds the global closest point."""
    model = cr.ChiralRings(lk_ring=0.0, **SMALL)
    prob, x = _perturbed(model, amp=0.05)
    d_global = cr.closest_on_other_ring(x, prob, cr.bilateral_candidates(x, prob))[3]
    true = cr.update_partners(x, prob).copy()
    prob.partner = prob.along(true, np.full(len(true), -2 * cr.PARTNER_WINDOW))
    cr.update_partners(x, prob)
    d = cr.closest_on_other_ring(x, prob, cr.bilateral_candidates(x, prob))[3]
    np.testing.assert_allclose(d, d_global, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(prob.partner, true)


@pytest.fixture(scope="module")
def small_circles():
    r = cr.solve(cr.ChiralRings(lk_ring=0.0, start_noise=0.0, **SMALL), stability=False)
    assert r["converged"]
    return r


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_twisted_circles_buckle_at_michells_threshold(small_circles, sign):
    """The twisted circles are an equilibrium at every Lk_i; they lose stability where
    C Tw / B = sqrt(3) (Michell 1889; Zajac 1962): the ply of two rings has twice a ring's
    bending stiffness and carries twice its twisting moment, so the threshold is a single
    ring's, Lk_i = sqrt(3)/1.5 = 1.155. Bracket +-5 % (the pair's link splits the threshold
    of the two hands by O(Delta/L): measured at Delta/L = 0.05, 40 beads per ring, the zero
    lies at +1.170 and -1.151; at the seed's 0.02 at +1.157)."""
    lk_m = math.sqrt(3) / cr.DNA_TWIST_OVER_BEND
    lam = {}
    for f in (0.95, 1.05):
        prob = cr.make_problem(cr.ChiralRings(lk_ring=sign * f * lk_m, **SMALL))
        lam[f] = cr.lowest_modes(small_circles["x"], prob)[0][0]
    assert lam[0.95] > 0 > lam[1.05]


def test_continuation_follows_the_twisted_circles(small_circles):
    """Below Michell's threshold the continued rings stay circles: T1 = 2 pi C Lk_i / L."""
    model = cr.ChiralRings(lk_ring=0.0, start_noise=0.0, **SMALL)
    rows = list(cr.continuation(model, small_circles, "lk_ring", 0.5, 0.25, stability=False))
    assert [r["parameter_value"] for r in rows] == [0.25, 0.5]
    for r in rows:
        assert not r["branch_left"]
        assert r["torque_per_ring_B_per_L"][0] == pytest.approx(
            2 * math.pi * cr.DNA_TWIST_OVER_BEND * r["parameter_value"], abs=1e-6)
    with pytest.raises(UserError, match="parameter"):
        next(cr.continuation(model, small_circles, "n", 1.0, 0.25))
    with pytest.raises(UserError, match="min_step"):
        next(cr.continuation(model, small_circles, "lk_ring", 1.0, 0.25, min_step=0.0))


@pytest.mark.slow
def test_continuation_leaves_the_circles_past_michells_threshold(small_circles):
    """Past Lk_i = 1.17 (Delta/L = 0.05) the circles are a saddle: the continued state
    escapes it and writhes (Zajac 1962: a subcritical jump), marked as a branch left
    (measured: 1.125 -> 1.25 in one step, Wr 0.72 per ring, converged in 165 Newton steps
    from the writhed state of 1.1875; ~1-4 min on one core, hence slow)."""
    model = cr.ChiralRings(lk_ring=1.125, start_noise=0.0, **SMALL)
    start = cr.solve(model, small_circles["x"], stability=False)
    assert not any(abs(w) > 1e-6 for w in start["writhe_per_ring"])
    rows = list(cr.continuation(model, start, "lk_ring", 1.25, 0.125, min_step=0.125,
                                max_iter=300))
    assert [r["parameter_value"] for r in rows] == [1.25]
    assert rows[0]["branch_left"]
    assert min(abs(w) for w in rows[0]["writhe_per_ring"]) > cr.WRITHE_JUMP


def test_lk12_sign_is_ring_2s_orientation_not_the_links_handedness():
    """DNA is apolar: reversing ring 2's direction flips the Gauss Lk_12 (-1 -> +1) and
    changes neither the energy (the chiral term folds eta, docs/chirality.md Eq. C3) nor the
    folded braid angle that the thermal catenane measures (geometry.curves.crossing_angles):
    the catenane's "Lk_12 = +1" (hopf_start orients ring 2 to give +1) and this solver's
    "Lk_12 = -1" (both rings run parallel along the ply) can name the same left-handed
    link. The handedness is the sign of the folded eta (+0.126 = 2 asin(pi Delta/L) at
    Delta/L = 0.02, the uniform ply), not the sign of Lk_12."""
    from dnabraid.geometry.curves import crossing_angles
    from dnabraid.scenes.catenane import hopf_start

    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=500.0)
    prob, x = _perturbed(model, amp=0.05)
    sl = prob.ring(1)
    y = x.copy()
    y[sl] = x[sl][::-1]
    r1 = x[prob.ring(0)]
    assert gauss_linking_number(r1, x[sl]) == pytest.approx(-1.0, abs=1e-6)
    assert gauss_linking_number(r1, y[sl]) == pytest.approx(+1.0, abs=1e-6)
    assert cr.energy(y, prob) == pytest.approx(cr.energy(x, prob), rel=1e-12)
    assert cr.chiral_energy_gradient(y, prob, want_grad=False)[0] > 0   # disfavoured hand
    # the folded angle on the unperturbed ply, per segment of ring 1 at its closest segment
    # of ring 2 (on the polygon that closest point is often a bead shared by two segments,
    # and the order picks one: per-segment values move, 0.072-0.158 rad, their mean 3e-4)
    x0 = cr.initial_geometry(cr.ChiralRings(lk_ring=0.0, start_noise=0.0))
    c1, c2 = x0[prob.ring(0)], x0[sl]
    cut = 1.05 * prob.delta
    e_x = crossing_angles(np.vstack([c1, c1[:1]]), np.vstack([c2, c2[:1]]), cut)[0]
    c2 = c2[::-1]
    e_y = crossing_angles(np.vstack([c1, c1[:1]]), np.vstack([c2, c2[:1]]), cut)[0]
    assert len(e_x) == len(e_y) == len(c1)
    assert np.mean(e_y) == pytest.approx(np.mean(e_x), abs=1e-3)
    # both left-handed, as the uniform ply's 2 asin(pi Delta/L) = +0.1257 (segment
    # closest points read 3 % low at b = Delta/2)
    eta_ply = 2 * math.asin(math.pi * 0.02)
    assert min(np.mean(e_x), np.mean(e_y)) == pytest.approx(eta_ply, rel=0.05)
    # the catenane's start: link = -1 is link = +1 with ring 2 run backwards
    a, b = hopf_start(24, 3.0, link=1), hopf_start(24, 3.0, link=-1)
    np.testing.assert_allclose(a[0], b[0])
    np.testing.assert_allclose(np.sort(a[1], axis=0), np.sort(b[1], axis=0))
    assert round(gauss_linking_number(*a)) == -round(gauss_linking_number(*b))


def test_folded_eta_is_apolar_and_mirror_odd():
    """The solver's reported braid angle (``eta_folded_mean_rad``) is the apolar one: eta and
    eta +- pi fold to one value in (-pi/2, pi/2] (docs/chirality.md, Eq. C3, as the chiral
    term folds them), so reversing ring 2 (every contact's eta moves by pi) leaves it
    unchanged to round-off while the plain atan2 mean moves by radians; a mirror image
    flips its sign (the energy, achiral at alpha = 0, is unchanged)."""
    assert cr.fold_eta(2.281) == pytest.approx(2.281 - math.pi, abs=1e-12)
    assert cr.fold_eta(-0.4) == pytest.approx(-0.4, abs=1e-12)
    assert cr.fold_eta(-math.pi / 2) == pytest.approx(math.pi / 2, abs=1e-12)
    model = cr.ChiralRings(lk_ring=0.0, alpha_B_per_L2=0.0)
    prob, x = _perturbed(model, amp=0.05)
    sl = prob.ring(1)
    rev = x.copy()
    rev[sl] = x[sl][::-1]
    mir = x * np.array([-1.0, 1.0, 1.0])
    a, b, c = (cr.measure(y, prob) for y in (x, rev, mir))
    assert a["eta_folded_mean_rad"] == pytest.approx(2 * math.asin(math.pi * 0.02), rel=0.1)
    assert b["eta_folded_mean_rad"] == pytest.approx(a["eta_folded_mean_rad"], abs=1e-9)
    # the plain mean: each eta moves by pi, and those that wrap at +-pi pull the mean back
    # (2.05 rad here), so it is no measure of the hand
    assert abs(b["eta_mean_rad"] - a["eta_mean_rad"]) > 1.5
    assert c["eta_folded_mean_rad"] == pytest.approx(-a["eta_folded_mean_rad"], abs=1e-9)
    assert c["energy_B_per_L"] == pytest.approx(a["energy_B_per_L"], rel=1e-12)


def test_mirror_image_is_the_opposite_hand_at_minus_lk_with_equal_energy():
    """:func:`cr.mirror_image` (z -> -z, ring 2 reversed, partners mapped): every twist,
    writhe and the folded eta change sign, the Gauss Lk_12 stays -1 (the solver's
    convention), the alpha = 0 energy at -Lk_i equals the original's at Lk_i to round-off,
    and the chiral energy changes sign (mirror-odd, reversal-even)."""
    model = cr.ChiralRings(lk_ring=0.7, alpha_B_per_L2=0.0, **SMALL)
    prob, x = _perturbed(model, amp=0.1, seed=4)
    cr.update_partners(x, prob)
    y, p2 = cr.mirror_image(x, prob.partner, prob)
    img = cr.make_problem(dataclass_replace(model, lk_ring=-0.7))
    img.partner = p2
    a, b = cr.measure(x, prob), cr.measure(y, img)
    assert b["linking_number"] == pytest.approx(a["linking_number"], abs=1e-9)
    assert round(a["linking_number"]) == -1
    assert np.allclose(b["writhe_per_ring"], -np.asarray(a["writhe_per_ring"]), atol=1e-12)
    assert np.allclose(b["twist_per_ring"], -np.asarray(a["twist_per_ring"]), atol=1e-12)
    assert b["eta_folded_mean_rad"] == pytest.approx(-a["eta_folded_mean_rad"], abs=1e-9)
    assert cr.energy(y, img) == pytest.approx(cr.energy(x, prob), rel=1e-12)
    chi = cr.make_problem(dataclass_replace(model, alpha_B_per_L2=900.0))
    chi.partner = prob.partner
    chi_img = cr.make_problem(dataclass_replace(model, lk_ring=-0.7, alpha_B_per_L2=900.0))
    chi_img.partner = p2
    E = cr.chiral_energy_gradient(x, chi, want_grad=False)[0]
    assert E != 0.0
    assert cr.chiral_energy_gradient(y, chi_img, want_grad=False)[0] == pytest.approx(
        -E, rel=1e-10)
