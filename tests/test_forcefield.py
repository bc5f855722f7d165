"""dnabraid.forcefield: every table loads, is read once, and extrapolation is announced."""

import dataclasses
import math
import warnings
from importlib import resources

import pytest

from dnabraid import forcefield
from dnabraid.forcefield import SaltExtrapolationWarning


@pytest.fixture
def fresh_warnings(monkeypatch):
    """Forget which salts have already warned, so each test sees its own warnings."""
    monkeypatch.setattr(forcefield, "_WARNED", set())


def table_names():
    return sorted(p.name for p in resources.files("dnabraid.forcefields").iterdir()
                  if p.name.endswith(".toml"))


def test_every_table_loads():
    assert table_names() == ["chiral.toml", "dna.toml"]
    for name in table_names():
        assert forcefield.load_toml(name)
    dna = forcefield.load_toml("dna.toml")
    assert {"mechanics", "electrostatics", "effective_diameter"} <= set(dna)
    eff = dna["effective_diameter"]
    assert len(eff["salt_mM"]) == len(eff["diameter_nm"]) and eff["source"]
    assert eff["salt_mM"] == sorted(eff["salt_mM"])
    chiral = forcefield.load_toml("chiral.toml")
    for key, entry in chiral["salt"].items():
        assert float(key) > 0 and entry["source"]
        assert entry["alpha_min_pN"] <= entry["alpha_pN"] <= entry["alpha_max_pN"]


def test_every_accessor_reads_its_table():
    eff = forcefield.load_toml("dna.toml")["effective_diameter"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing is extrapolated at the table points
        for c, d in zip(eff["salt_mM"], eff["diameter_nm"]):
            sp = forcefield.salt_parameters(c)
            assert sp.diameter_nm == pytest.approx(d) and not sp.extrapolated
            assert sp.debye_nm == pytest.approx(0.304 / math.sqrt(c / 1000.0))
        for key, entry in forcefield.load_toml("chiral.toml")["salt"].items():
            out = forcefield.chiral_parameters(float(key))
            assert out["alpha_pN"] == pytest.approx(entry["alpha_pN"])
            assert not out["extrapolated"] and out["source"]
    assert forcefield.debye_length_nm(100.0) == pytest.approx(0.304 / math.sqrt(0.1))


def test_tables_are_read_once_and_cannot_be_changed_by_callers():
    forcefield.load_toml("dna.toml")
    before = forcefield._table.cache_info()
    a = forcefield.load_toml("dna.toml")
    forcefield.salt_parameters(150.0)
    forcefield.mechanics()
    after = forcefield._table.cache_info()
    assert after.misses == before.misses and after.hits > before.hits  # no second parse
    a["mechanics"]["persistence_nm"] = -1.0
    a["effective_diameter"]["diameter_nm"].append(99.0)
    m = forcefield.mechanics()
    m["persistence_nm"] = -2.0
    assert forcefield.load_toml("dna.toml")["mechanics"]["persistence_nm"] == 50.0
    assert forcefield.mechanics()["persistence_nm"] == 50.0
    assert 99.0 not in forcefield.load_toml("dna.toml")["effective_diameter"]["diameter_nm"]
    assert forcefield.salt_parameters(150.0).diameter_nm == pytest.approx(4.9)


def test_mechanics_parameters_typed_and_frozen():
    m = forcefield.mechanics_parameters()
    assert isinstance(m, forcefield.Mechanics)
    assert (m.persistence_nm, m.stretch_modulus_pN, m.twist_persistence_nm) == (50.0, 1100.0,
                                                                               100.0)
    assert m.rise_nm_per_bp == 0.34 and m.hydrodynamic_radius_fraction == 0.5
    raw = forcefield.mechanics()
    for f in dataclasses.fields(m):
        assert getattr(m, f.name) == raw[f.name]
        if f.name.endswith("_source"):
            assert isinstance(getattr(m, f.name), str) and getattr(m, f.name)
        else:
            assert isinstance(getattr(m, f.name), float)
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.persistence_nm = 1.0
    assert forcefield.mechanics_parameters() == m


def test_continuum_defaults_come_from_the_table():
    from dnabraid.continuum import ply, tweezer
    from dnabraid.units import kT

    lp = forcefield.mechanics_parameters().persistence_nm
    assert ply.DEFAULT_PERSISTENCE_NM == lp
    assert ply.DEFAULT_BENDING_PN_NM2 == pytest.approx(kT(298.15) * lp)
    assert tweezer.DEFAULT_BENDING_PN_NM2 == ply.DEFAULT_BENDING_PN_NM2


@pytest.mark.parametrize("salt", [5.0, 2500.0])
def test_salt_extrapolation_warns_with_salt_range_and_source(fresh_warnings, salt):
    source = forcefield.load_toml("dna.toml")["effective_diameter"]["source"]
    with pytest.warns(SaltExtrapolationWarning) as rec:
        sp = forcefield.salt_parameters(salt)
    assert sp.extrapolated
    assert len(rec) == 1 and issubclass(rec[0].category, UserWarning)
    msg = str(rec[0].message)
    assert f"{salt:g} mM" in msg and "10-1000 mM" in msg and "dna.toml" in msg
    assert source in msg
    assert rec[0].filename == __file__  # points at the caller, not at forcefield.py


def test_salt_extrapolation_values_follow_the_toml_promise(fresh_warnings):
    eff = forcefield.load_toml("dna.toml")["effective_diameter"]
    with pytest.warns(SaltExtrapolationWarning):
        lo = [forcefield.salt_parameters(c).diameter_nm for c in (1.0, 2.0, 5.0)]
    with pytest.warns(SaltExtrapolationWarning):
        hi = forcefield.salt_parameters(1e6).diameter_nm
    assert lo[0] > lo[1] > lo[2] > eff["diameter_nm"][0]  # grows like the Debye length
    assert (lo[0] - 2.0) / (lo[2] - 2.0) == pytest.approx(math.sqrt(5.0))
    assert eff["bare_diameter_nm"] < hi < eff["bare_diameter_nm"] + 0.1  # tends to bare DNA


def test_salt_extrapolation_warns_once_per_salt(fresh_warnings):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        for _ in range(3):
            forcefield.salt_parameters(3.0)
        forcefield.salt_parameters(4.0)
    salts = [str(w.message).split(" mM")[0] for w in rec
             if issubclass(w.category, SaltExtrapolationWarning)]
    assert salts == ["salt 3", "salt 4"]
    assert forcefield.salt_parameters(3.0).extrapolated  # the flag stays on every call


@pytest.mark.parametrize("salt", [10.0, 10, 37.5, 150.0, 999.9, 1000.0])
def test_inside_the_table_no_warning(fresh_warnings, salt):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not forcefield.salt_parameters(salt).extrapolated
        assert not forcefield.chiral_parameters(salt)["extrapolated"]


def test_chiral_extrapolation_warns(fresh_warnings):
    with pytest.warns(SaltExtrapolationWarning, match=r"salt 2000 mM .*10-1000 mM.*chiral"):
        out = forcefield.chiral_parameters(2000.0)
    assert out["extrapolated"] and out["alpha_pN"] == pytest.approx(0.4)


@pytest.mark.parametrize("bad", [0.0, -5.0, math.nan, math.inf, True, "150", None])
def test_bad_salt_raises(bad):
    with pytest.raises(ValueError, match="salt_mM"):
        forcefield.salt_parameters(bad)
    with pytest.raises(ValueError, match="salt_mM"):
        forcefield.chiral_parameters(bad)
