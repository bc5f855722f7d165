"""Packaging: the force-field tables of the top-level ``forcefields/`` directory install as
the package ``dnabraid.forcefields``, from the wheel and from the (editable) install."""

import importlib.metadata
import os
import shutil
import subprocess
import sys
import zipfile
from importlib import resources
from pathlib import Path

import pytest

from dnabraid import tomlio

ROOT = Path(__file__).resolve().parent.parent
TABLES = ("chiral.toml", "dna.toml")


def pyproject():
    return tomlio.load(ROOT / "pyproject.toml")


def test_tables_live_in_the_top_level_directory():
    top = ROOT / "forcefields"
    assert top.is_dir() and not top.is_symlink()
    assert all((top / t).is_file() for t in TABLES)
    assert not (ROOT / "dnabraid" / "forcefields").exists()  # one copy only
    st = pyproject()["tool"]["setuptools"]
    assert st["package-dir"] == {"dnabraid.forcefields": "forcefields"}
    assert st["package-data"]["dnabraid.forcefields"] == ["*.toml"]


def test_every_subpackage_is_listed_in_pyproject():
    """``packages`` is an explicit list (a package mapped elsewhere cannot be found by
    ``packages.find``): every directory of dnabraid/ holding Python files must be in it."""
    listed = set(pyproject()["tool"]["setuptools"]["packages"])
    on_disk = {".".join(d.relative_to(ROOT).parts) for d in [ROOT / "dnabraid",
                                                             *(ROOT / "dnabraid").rglob("*")]
               if d.is_dir() and d.name != "__pycache__" and any(d.glob("*.py"))}
    assert on_disk - listed == set(), "add these to [tool.setuptools] packages in pyproject.toml"
    assert listed - on_disk == {"dnabraid.forcefields"}


def test_installed_package_finds_the_tables():
    found = {p.name for p in resources.files("dnabraid.forcefields").iterdir()}
    assert set(TABLES) <= found
    for t in TABLES:
        assert resources.files("dnabraid.forcefields").joinpath(t).read_bytes() == \
            (ROOT / "forcefields" / t).read_bytes()


def _ignore(directory, names):
    skip = {".git", ".venv", ".venv-ci", "venv", "build", "dist", "runs", "results", "out",
            "__pycache__", ".pytest_cache"}
    return [n for n in names if n in skip or n.endswith(".egg-info")]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """A wheel built from a copy of the source tree (a build in place would leave build/
    behind, whose stale files can end up in later wheels)."""
    try:
        version = importlib.metadata.version("setuptools")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("setuptools is not installed (pip install -e '.[test]')")
    if int(version.split(".")[0]) < 77:
        pytest.skip(f"setuptools {version} < 77 (pip install -e '.[test]')")
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    shutil.copytree(ROOT, src, ignore=_ignore, symlinks=True)
    out = tmp / "dist"
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                           "--no-build-isolation", "--no-index", "-q", "-w", str(out), str(src)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (whl,) = out.glob("dnabraid-*.whl")
    return whl


@pytest.mark.integration
def test_wheel_holds_the_tables(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for t in TABLES:
        assert f"dnabraid/forcefields/{t}" in names
    assert "dnabraid/forcefields/__init__.py" in names
    assert not any(n.startswith("forcefields/") for n in names)  # no stray top-level package
    for pkg in pyproject()["tool"]["setuptools"]["packages"]:
        assert any(n.startswith(pkg.replace(".", "/") + "/") for n in names), pkg


@pytest.mark.integration
@pytest.mark.parametrize("layout", ["zip", "unpacked"])
def test_wheel_reads_the_tables(wheel, tmp_path, layout):
    """The wheel alone (first on sys.path, outside the checkout) serves the tables."""
    if layout == "zip":
        path = wheel
    else:
        path = tmp_path / "site"
        zipfile.ZipFile(wheel).extractall(path)
    code = ("import dnabraid.forcefield as f; from importlib import resources; "
            "print(f.__file__); print(resources.files('dnabraid.forcefields')); "
            "print(f.salt_parameters(150).diameter_nm, f.mechanics_parameters().persistence_nm, "
            "f.chiral_parameters(150)['alpha_pN'])")
    env = {**os.environ, "PYTHONPATH": str(path)}
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    where, tables, values = proc.stdout.splitlines()
    assert where.startswith(str(path)) and tables.startswith(str(path))
    assert values.split() == ["4.9", "50.0", "0.15"]


def test_source_checkout_without_install_reads_the_tables(tmp_path):
    """No install at all (``python -S``, the checkout on PYTHONPATH): forcefield.py falls back
    to the top-level forcefields/ directory."""
    code = ("import importlib.util, dnabraid.forcefield as f; "
            "assert importlib.util.find_spec('dnabraid.forcefields') is None; "
            "print(f.salt_parameters(150).diameter_nm, f.load_toml('chiral.toml')['salt']"
            "['150']['alpha_pN'])")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-S", "-c", code], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["4.9", "0.15"]
