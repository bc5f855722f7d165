"""The braid-buckling workflow's split of the catenation into the axis's writhe and the
strands' winding about it (workflows/braid_buckling.py), against the Calugareanu-White
theorem Lk = Tw + Wr with the ribbon's twist computed independently by quadrature."""

import math

import numpy as np
import pytest

from conftest import load_workflow


@pytest.fixture(scope="module")
def wf():
    return load_workflow("braid_buckling")


def _ribbon(n_pts: int, turns: float, A: float, B: float, H: float, r: float):
    """Axis m(z) with vertical tangents at both ends (so the vertical closing rays join it
    smoothly), strands m -+ u/2 with u = r (cos phi e1 + sin phi e2), phi = 2 pi turns z/H,
    e1 the x direction made normal to the tangent, e2 = t x e1; and the ribbon's twist
    Tw = (1/2 pi) int t . (u x u') / |u|^2 ds by the trapezoidal rule."""
    z = np.linspace(0.0, H, n_pts)
    k = math.pi / H
    m = np.c_[A * np.sin(k * z) ** 2, B * np.sin(k * z) ** 2 * np.cos(k * z), z]
    s_, c_ = np.sin(k * z), np.cos(k * z)
    dm = np.c_[A * k * np.sin(2 * k * z), B * k * (2 * s_ * c_**2 - s_**3), np.ones_like(z)]
    t = dm / np.linalg.norm(dm, axis=1)[:, None]
    ex = np.array([1.0, 0.0, 0.0])
    e1 = ex - (t @ ex)[:, None] * t
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(t, e1)
    phi = 2 * math.pi * turns * z / H
    u = r * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)
    du = np.gradient(u, z, axis=0)
    integrand = np.einsum("ij,ij->i", t, np.cross(u, du)) / r**2
    # t . (u x du/ds) ds = t . (u x du/dz) dz
    tw = float(np.sum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(z))) / (2 * math.pi)
    return m - 0.5 * u, m + 0.5 * u, tw


def test_straight_axis_has_no_writhe(wf):
    p1, p2, tw = _ribbon(400, 2.0, 0.0, 0.0, 100.0, 2.5)
    wr, ca = wf.split_catenation(p1, p2)
    assert abs(wr) < 1e-9
    assert ca == pytest.approx(2.0, abs=2e-3)
    assert tw == pytest.approx(2.0, abs=1e-3)


@pytest.mark.parametrize("turns", [-1.5, 3.0])
def test_catenation_splits_into_twist_and_axis_writhe(wf, turns):
    """A writhing axis (Wr = -0.138, so the split matters): Ca - Wr_ax equals the
    ribbon's twist to 5e-4 turns (measured 1e-5 and 1e-4 at 1500 beads)."""
    p1, p2, tw = _ribbon(1500, turns, 30.0, 20.0, 100.0, 2.5)
    wr, ca = wf.split_catenation(p1, p2)
    assert abs(wr) > 0.05
    assert ca - wr == pytest.approx(tw, abs=5e-4)


def test_unequal_strands_are_refused(wf):
    with pytest.raises(ValueError, match="pairs"):
        wf.split_catenation(np.zeros((5, 3)), np.zeros((6, 3)))


def test_buckling_interval_and_slope(wf):
    """Rows made by hand: Wr_ax flat then rising 0.6 per turn after n = 1; the slope is the
    exact line through the points past it."""
    rows = []
    for n, w in [(0, 0.0), (0.5, 0.01), (1, 0.02), (1.5, 0.32), (2, 0.62), (2.5, 0.92)]:
        z = 80.0 - 5 * n if n <= 1 else 75.0 - 20.0 * (n - 1)
        rows.append({"turns": n, "wr_axis": (w, 0.01),
                     "extension_nm": {"mean": z, "sem": 0.5},
                     "torque_pN_nm": {"mean": 10 * n if n <= 1 else 20.0, "sem": 1.0}})
    b = wf.buckling(rows)
    assert b["interval"] == [1, 1.5]
    assert b["slope_nm_per_turn"][0] == pytest.approx(-20.0, abs=1e-9)
    assert b["torque_after_pN_nm"][0] == pytest.approx(20.0)
    assert b["torque_before_max_pN_nm"][2] == 1
