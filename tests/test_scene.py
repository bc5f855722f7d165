"""Scenes: keys declared per scene, bad input gives clear errors naming the key, nothing is
written for a refused scene; the bugs of the first build each have a test here."""

import os

import pytest

from dnabraid import cli
from dnabraid.chains import MIN_PASSAGE_BARRIER_KT, max_bead_spacing_nm, passage_barrier_kT
from dnabraid.run.engine import integrator_seed
from dnabraid.scenes import SCENES, SceneError, make_scene


def test_defaults_resolve_and_roundtrip(tmp_path):
    for name in SCENES:
        s = make_scene(name)
        p = tmp_path / f"{name}.toml"
        p.write_text(s.to_toml())
        assert make_scene(str(p)) == s
    s = make_scene("braid")
    assert s.n_beads == 21 and len(s.build().chains) == 2  # 100 nm / 5 nm + 1
    assert s.effective_diameter_nm == pytest.approx(4.9)


def test_each_scene_declares_its_own_keys():
    """A key belongs to the scenes that declare it (no set arithmetic between scenes)."""
    keys = {n: set(c.keys()) for n, c in SCENES.items()}
    assert "twist_persistence_nm" in keys["plectoneme"]
    assert "twist_persistence_nm" not in keys["braid"] | keys["tether"]
    assert "tether_separation_nm" in keys["braid"]
    assert "tether_separation_nm" not in keys["tether"] | keys["plectoneme"] | keys["knot"]
    assert "self_avoidance" in keys["tether"] and "self_avoidance" not in keys["braid"]
    assert keys["knot"] == {"knot_n", "tension_pN", "rod_radius_nm",
                            "bending_stiffness_pN_nm2", "bead_spacing_nm", "start_loop_factor",
                            "contact"}
    assert "tether_separation_nm" not in keys["closed"] | keys["catenane"]
    assert "force_pN" not in keys["closed"] | keys["catenane"]  # no tweezer bead
    for c in SCENES.values():
        for info in c.keys().values():
            assert info.help, info.name


@pytest.mark.parametrize("over, words", [
    ({"forse_pN": 2}, ["forse_pN", "allowed keys", "force_pN"]),
    ({"force_pN": -1}, ["force_pN", "> 0"]),
    ({"bead_spacing_nm": 10.0, "length_nm": 200.0}, ["bead_spacing_nm", "pass through", "<="]),
    ({"tether_separation_nm": 400.0}, ["tether_separation_nm", "length_nm"]),
    ({"tether_separation_nm": 2.0}, ["tether_separation_nm", "diameter"]),
    ({"turns": "many"}, ["turns", "list"]),
    ({"stretch": "springs"}, ["stretch", "constraints"]),
    ({"length_nm": 203.0}, ["length_nm", "multiple"]),
    ({"length_nm": 1e9}, ["length_nm", "beads"]),
    ({"seed": -1}, ["seed"]),
    ({"seed": 2**31}, ["seed"]),
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


def test_passage_barrier_rigid():
    """Crossing bonds through each other's midpoints: 4 pairs at b/sqrt(2) (WCA, eps = kT)."""
    d = 4.9
    bmax = max_bead_spacing_nm(d)
    assert passage_barrier_kT(bmax, d) == pytest.approx(MIN_PASSAGE_BARRIER_KT, rel=1e-6)
    # independent number: at b = d the pairs sit at d/sqrt 2: 4 (4 (8^2 - 8) + 1) = 900 kT
    assert passage_barrier_kT(d, d) == pytest.approx(900.0)


def test_passage_barrier_includes_bond_stretch():
    """Bug: the check assumed rigid bonds. With springs k = S/b the crossing bonds stretch:
    E(l) = k (l - b)^2 + 4 U_WCA(l / sqrt 2), minimised over l. Independent numbers for the
    default scene (b = 5, d = 4.9, S = 1100 pN, kT = 4.1164 pN nm): at l = 6.1 nm,
    k (1.1)^2 = 64.7 kT and 4 U(4.313 nm) = 43.6 kT, so the barrier is at most 108.3 kT
    (rigid: 694 kT)."""
    k = 1100.0 / 5.0 / 4.1164
    e = passage_barrier_kT(5.0, 4.9, k)
    assert 100.0 < e <= 108.3 + 1e-6
    assert passage_barrier_kT(5.0, 4.9) == pytest.approx(694.16, abs=0.01)
    # a spacing the rigid check allowed (barrier >= 20 kT) is refused with springs
    b = 0.5 * (max_bead_spacing_nm(4.9) + max_bead_spacing_nm(4.9, 1100.0 / 4.1164))
    assert passage_barrier_kT(b, 4.9) > MIN_PASSAGE_BARRIER_KT
    assert passage_barrier_kT(b, 4.9, 1100.0 / b / 4.1164) < MIN_PASSAGE_BARRIER_KT
    with pytest.raises(SceneError, match="bond stretch included"):
        make_scene("braid", {"bead_spacing_nm": 6.25, "length_nm": 200.0})
    make_scene("braid", {"bead_spacing_nm": 6.25, "length_nm": 200.0, "stretch": "constraints",
                         "mc_moves": 0})


def test_seeds_give_distinct_integrator_seeds():
    """Bug: seeds 0, 1 and 2^31 - 1 all gave integrator seed 1."""
    seeds = [0, 1, 2, 2**31 - 2]
    assert len({integrator_seed(s) for s in seeds}) == len(seeds)
    assert all(1 <= integrator_seed(s) <= 2**31 - 1 for s in seeds)
    with pytest.raises(ValueError):
        integrator_seed(2**31 - 1)


def test_knot_scene_has_no_brownian_model():
    """Bug: build(make_scene("knot")) silently returned a pulled tether."""
    with pytest.raises(SceneError, match="knot"):
        make_scene("knot").build()


@pytest.mark.parametrize("over, key", [({"bead_spacing_nm": 0}, "bead_spacing_nm"),
                                       ({"bead_spacing_nm": -0.5}, "bead_spacing_nm")])
def test_knot_bad_spacing_is_refused(over, key):
    """Bug: bead_spacing_nm=0 ended in ZeroDivisionError; a negative spacing was accepted."""
    with pytest.raises(SceneError, match=key):
        make_scene("knot", over)


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
    rc = cli.main(["run", "knot", "--set", "bead_spacing_nm=0", "--out", str(out), "--quiet"])
    assert rc == 2 and "bead_spacing_nm" in capsys.readouterr().err


def test_cli_does_not_hide_bugs(monkeypatch):
    """Bug: the CLI caught every ValueError and printed real bugs as user errors."""
    from dnabraid.scenes.braid import Braid

    def broken(self, *a, **k):
        raise ValueError("internal bug")

    monkeypatch.setattr(Braid, "run", broken)
    with pytest.raises(ValueError, match="internal bug"):
        cli.main(["run", "braid", "--quiet", "--no-pin"])


def test_scenes_lists_keys_with_units(capsys):
    assert cli.main(["scenes"]) == 0
    text = capsys.readouterr().out
    for key in ("force_pN", "turns", "salt_mM", "length_nm", "bead_spacing_nm",
                "tether_separation_nm", "persistence_nm", "temperature_K", "steps", "seed",
                "knot_n", "twist_persistence_nm"):
        assert key in text
    assert "[pN]" in text and "tether" in text
