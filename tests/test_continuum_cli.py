"""`dnabraid continuum ply|knot|overhand|tweezer [--json]`."""

import json

import pytest

from dnabraid.cli import main


def _json(capsys, argv):
    rc = main(argv)
    out = capsys.readouterr().out
    return rc, json.loads(out)


def test_knot_json_has_the_promised_keys(capsys):
    rc, d = _json(capsys, ["continuum", "knot", "--n", "1", "--json"])
    assert rc == 0
    for key in ("w_c", "sigma", "contact_half_width", "max_gap", "max_gap_at",
                "isolated_contact_at", "success", "wall_time_s"):
        assert key in d, key
    assert d["success"] is True
    assert d["w_c"] == pytest.approx(3.506, abs=0.002)  # Audoly et al. 2007, Eq. 7
    assert d["sigma"] == pytest.approx(0.492, abs=0.002)  # Audoly et al. 2007, Eq. 8


@pytest.mark.parametrize("argv, key", [
    (["continuum", "ply", "--force-pN", "2", "--torque-pN-nm", "10"], "theta_rad"),
    (["continuum", "tweezer", "--turns", "2"], "rows"),
    (["continuum", "overhand", "--n", "2"], "w_c_helical"),
])
def test_every_problem_runs_from_the_cli(capsys, argv, key):
    rc, d = _json(capsys, argv + ["--json"])
    assert rc == 0 and d["success"] is True and key in d


def test_unknown_problem_is_an_error(capsys):
    with pytest.raises(SystemExit):
        main(["continuum", "nosuch"])


def test_bad_continuum_input_is_a_user_error(capsys):
    """A bad argument ends with one line on stderr and exit status 2, not a traceback."""
    from dnabraid.cli import main

    assert main(["continuum", "closed", "--n", "4", "--topology", "knot"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dnabraid: error:") and "odd" in err
