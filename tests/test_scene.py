"""Bad input gives clear errors naming the key; nothing is written for a refused scene."""

import os

import pytest

from dnabraid import cli
from dnabraid.scene import (
    MIN_PASSAGE_BARRIER_KT,
    SceneError,
    make_scene,
    max_bead_spacing_nm,
    passage_barrier_kT,
)


def test_defaults_resolve_and_roundtrip(tmp_path):
    s = make_scene("braid")
    assert s.n_beads == 41 and s.n_strands == 2
    assert s.effective_diameter_nm == pytest.approx(4.9)
    p = tmp_path / "s.toml"
    p.write_text(s.to_toml())
    assert make_scene(str(p)) == s


@pytest.mark.parametrize("over, words", [
    ({"forse_pN": 2}, ["forse_pN", "allowed keys", "force_pN"]),
    ({"force_pN": -1}, ["force_pN", "> 0"]),
    ({"bead_spacing_nm": 10.0, "length_nm": 200.0}, ["bead_spacing_nm", "pass through", "<="]),
    ({"tether_separation_nm": 400.0}, ["tether_separation_nm", "length_nm"]),
    ({"tether_separation_nm": 2.0}, ["tether_separation_nm", "diameter"]),
    ({"turns": "many"}, ["turns", "list"]),
    ({"stretch": "springs"}, ["stretch", "constraints"]),
    ({"length_nm": 203.0}, ["length_nm", "multiple"]),
])
def test_bad_input_names_key(over, words):
    with pytest.raises(SceneError) as e:
        make_scene("braid", over)
    for w in words:
        assert w in str(e.value)


def test_missing_file_and_unknown_scene():
    with pytest.raises(FileNotFoundError, match="does not exist"):
        make_scene("no/such/scene.toml")
    with pytest.raises(SceneError, match="built-in scenes"):
        make_scene("plectonemez")


def test_tether_refuses_turns():
    with pytest.raises(SceneError, match="turns"):
        make_scene("tether", {"turns": [1]})


def test_passage_barrier():
    """Crossing bonds through each other's midpoints: 4 pairs at b/sqrt(2) (WCA, eps = kT)."""
    d = 4.9
    bmax = max_bead_spacing_nm(d)
    assert passage_barrier_kT(bmax, d) == pytest.approx(MIN_PASSAGE_BARRIER_KT, rel=1e-6)
    # independent number: at b = d the pairs sit at d/sqrt 2: 4 (4 (8^2 - 8) + 1) = 900 kT
    assert passage_barrier_kT(d, d) == pytest.approx(900.0)


def test_cli_bad_input_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    rc = cli.main(["run", "braid", "--set", "force_pN=-2", "--out", str(out), "--quiet"])
    assert rc == 2
    assert "force_pN" in capsys.readouterr().err
    assert not os.path.exists(out)
    rc = cli.main(["run", "braid", "--set", "colour=3", "--out", str(out), "--quiet"])
    assert rc == 2 and not os.path.exists(out)
    rc = cli.main(["run", "braid", "--platform", "Warp", "--out", str(out), "--quiet"])
    assert rc == 2 and not os.path.exists(out)
    assert "Warp" in capsys.readouterr().err


def test_scenes_lists_keys_with_units(capsys):
    assert cli.main(["scenes"]) == 0
    text = capsys.readouterr().out
    for key in ("force_pN", "turns", "salt_mM", "length_nm", "bead_spacing_nm",
                "tether_separation_nm", "persistence_nm", "temperature_K", "steps", "seed"):
        assert key in text
    assert "[pN]" in text and "tether" in text
