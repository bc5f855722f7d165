"""The one argument checker of the continuum solvers (dnabraid.continuum._validate) and its
use in ply, knot, overhand and tweezer: same refusals, same wording, everywhere."""

import math

import numpy as np
import pytest

from dnabraid.continuum import knot_braid, overhand, ply, tweezer
from dnabraid.continuum._validate import check_finite, check_n, check_nonnegative, check_positive

NOT_NUMBERS = [True, False, np.bool_(True), "1.5", "nan", None, [1.0], np.array([1.0, 2.0]),
               1 + 0j]


# ------------------------------------------------------------------------- check_positive
@pytest.mark.parametrize("value", [1.5, 3, np.float64(0.25), np.int64(7), np.float32(2.0),
                                   np.array(4.0), 1e-300])
def test_check_positive_accepts(value):
    out = check_positive("x", value)
    assert type(out) is float and out == float(value)


@pytest.mark.parametrize("value", [0.0, -0.0, -1.0, -3, math.nan, math.inf, -math.inf,
                                   np.float64("nan"), *NOT_NUMBERS])
def test_check_positive_refuses(value):
    with pytest.raises(ValueError, match=r"^x must be a positive finite number, got "):
        check_positive("x", value)


# ------------------------------------------------------------------------- check_nonnegative
@pytest.mark.parametrize("value", [0.0, -0.0, 0, 2.5, np.float64(1.0), np.array(0.0)])
def test_check_nonnegative_accepts(value):
    out = check_nonnegative("mu", value)
    assert type(out) is float and out == float(value)


@pytest.mark.parametrize("value", [-1e-12, -2, math.nan, math.inf, -math.inf, *NOT_NUMBERS])
def test_check_nonnegative_refuses(value):
    with pytest.raises(ValueError, match=r"^mu must be a finite number >= 0, got "):
        check_nonnegative("mu", value)


# ------------------------------------------------------------------------- check_finite
@pytest.mark.parametrize("value", [0.0, -1.0, -7, 1e300, np.float64(-2.5), np.array(-1.0)])
def test_check_finite_accepts(value):
    out = check_finite("torque", value)
    assert type(out) is float and out == float(value)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, np.float64("inf"),
                                   *NOT_NUMBERS])
def test_check_finite_refuses(value):
    with pytest.raises(ValueError, match=r"^torque must be a finite number, got "):
        check_finite("torque", value)


# ------------------------------------------------------------------------- check_n
@pytest.mark.parametrize("value, expected", [(1, 1), (3, 3), (np.int64(2), 2), (2.0, 2),
                                             (np.float64(5.0), 5), (np.array(4), 4)])
def test_check_n_accepts_integers(value, expected):
    out = check_n(value)
    assert type(out) is int and out == expected


@pytest.mark.parametrize("value", [0, -1, 2.5, 1.0 + 1e-9, -2.0, math.nan, math.inf, -math.inf,
                                   *NOT_NUMBERS])
def test_check_n_refuses(value):
    with pytest.raises(ValueError, match=r"^n must be an integer >= 1, got "):
        check_n(value)


def test_check_n_message_and_minimum():
    with pytest.raises(ValueError) as exc:
        check_n(2.5)
    assert str(exc.value) == "n must be an integer >= 1, got 2.5"
    assert check_n(0, minimum=0) == 0
    with pytest.raises(ValueError, match=r"^turns must be an integer >= 2 \(crossings\), got 1$"):
        check_n(1, minimum=2, name="turns", what="crossings")


# ------------------------------------------------------------------------- the solvers use it
@pytest.mark.parametrize("n", [0, 1.5, True, "2", None, math.nan])
def test_knot_and_overhand_refuse_the_same_n(n):
    for fn in (knot_braid.turning_angle, knot_braid.default_half_width, overhand.w_c_helical):
        with pytest.raises(ValueError, match=r"^n must be an integer >= 1 \("):
            fn(n)


def test_knot_and_overhand_agree_on_integral_floats():
    # the two former copies disagreed: knot refused 2.0, overhand took it; both take it now
    assert knot_braid.turning_angle(2.0) == knot_braid.turning_angle(2) == 5 * math.pi
    assert overhand.w_c_helical(2.0) == overhand.w_c_helical(np.int64(2))


@pytest.mark.parametrize("bad", [True, "1.0", math.nan, math.inf, -1.0, None])
def test_positive_arguments_refused_alike(bad):
    with pytest.raises(ValueError, match=r"^delta_nm must be a positive finite number"):
        ply.solve_uniform_ply(1.0, 0.0, bad)
    with pytest.raises(ValueError, match=r"^delta_nm must be a positive finite number"):
        tweezer.solve_tweezer(2.0, 1.0, 500.0, 20.0, bad)
    with pytest.raises(ValueError, match=r"^radius must be a positive finite number"):
        knot_braid.braid_length(bad, 1.0)
    with pytest.raises(ValueError, match=r"^h must be a positive finite number"):
        overhand.helical_braid(2, bad, 1.0)


@pytest.mark.parametrize("bad", [True, "0.1", math.nan, math.inf, -0.1])
def test_nonnegative_arguments_refused_alike(bad):
    with pytest.raises(ValueError, match=r"^mu must be a finite number >= 0"):
        knot_braid.scaled_tension(0.3, bad)
    with pytest.raises(ValueError, match=r"^mu must be a finite number >= 0"):
        overhand.solve_overhand(0.3, 3, 1e-3, 1.0, bad)
    with pytest.raises(ValueError, match=r"^force_pN must be a finite number >= 0"):
        ply.solve_uniform_ply(bad, 0.0, 2.0)


@pytest.mark.parametrize("bad", [True, "1", math.nan, math.inf, -math.inf])
def test_finite_arguments_refused_alike(bad):
    with pytest.raises(ValueError, match=r"^torque_pN_nm must be a finite number"):
        ply.solve_uniform_ply(1.0, bad, 2.0)
    with pytest.raises(ValueError, match=r"^turns must be a finite number"):
        tweezer.solve_tweezer(bad, 1.0, 500.0, 20.0, 2.0)
