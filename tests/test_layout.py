"""The package's layout rules, checked from the source.

* no import circle inside ``dnabraid`` (module-level and function-level imports alike);
* no force module imports :mod:`dnabraid.analysis`; geometry imports nothing above it;
* the layers of the zero-temperature side, bottom up: geometry, forces and continuum;
  :mod:`dnabraid.statics` (bead solvers: uses geometry, forces, continuum and units only);
  scenes; :mod:`dnabraid.validation` (runs scenes; nothing else in the package imports it);
* no code outside ``dnabraid/scenes/`` compares a scene's name;
* no two modules share a file name (``__init__.py`` aside), so that a name says which module.
"""

import ast
import pathlib
import re

import dnabraid
from dnabraid.scenes import SCENES

ROOT = pathlib.Path(dnabraid.__file__).parent


def _module_name(path: pathlib.Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: pathlib.Path) -> set:
    mod = _module_name(path)
    pkg = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("dnabraid")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[:len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            if name.startswith("dnabraid"):
                out.add(name)
                for a in node.names:  # `from . import x` imports the submodule x
                    out.add(f"{name}.{a.name}")
    return out


def graph() -> dict:
    mods = {_module_name(p): p for p in ROOT.rglob("*.py")}
    g = {}
    for m, p in mods.items():
        g[m] = {i for i in _imports(p) if i in mods and i != m}
    return g


def _strip_packages(g):
    """Edges to a package's ``__init__`` stand for what it re-exports; drop the package
    nodes' own edges to their submodules (``__init__`` importing its children is not a
    circle of the code that uses them)."""
    out = {}
    for m, deps in g.items():
        out[m] = {d for d in deps if not d.startswith(m + ".")}
    return out


def test_no_import_cycles():
    g = _strip_packages(graph())
    seen, stack, cycles = set(), [], []

    def visit(m):
        if m in stack:
            cycles.append(stack[stack.index(m):] + [m])
            return
        if m in seen:
            return
        seen.add(m)
        stack.append(m)
        for d in sorted(g.get(m, ())):
            visit(d)
        stack.pop()

    for m in sorted(g):
        visit(m)
    assert not cycles, cycles[:3]


def test_forces_and_geometry_stay_below():
    g = graph()
    for m, deps in g.items():
        if m.startswith("dnabraid.forces"):
            assert not any(d.startswith(("dnabraid.analysis", "dnabraid.scenes")) for d in deps), m
        if m.startswith("dnabraid.geometry"):
            # geometry is the ground floor: only itself and the constants of units
            assert all(d.startswith("dnabraid.geometry") or d == "dnabraid.units"
                       for d in deps), (m, deps)
    assert not graph()["dnabraid.units"], "units imports nothing of dnabraid"


#: What the zero-temperature bead solvers may import (besides themselves).
STATICS_MAY_IMPORT = ("dnabraid.geometry", "dnabraid.forces", "dnabraid.continuum",
                      "dnabraid.units", "dnabraid.errors")


def test_statics_and_continuum_stay_below_scenes():
    g = graph()
    for m, deps in g.items():
        if m.startswith("dnabraid.statics"):
            bad = {d for d in deps if not d.startswith(("dnabraid.statics",) + STATICS_MAY_IMPORT)}
            assert not bad, (m, bad)
        if m.startswith("dnabraid.continuum"):
            bad = {d for d in deps if d.startswith(
                ("dnabraid.statics", "dnabraid.scenes", "dnabraid.validation", "dnabraid.run"))}
            assert not bad, (m, bad)


def test_validation_is_on_top():
    g = graph()
    for m, deps in g.items():
        if m.startswith("dnabraid.validation") or m == "dnabraid.cli":
            continue
        assert not any(d.startswith("dnabraid.validation") for d in deps), m


def test_module_file_names_are_unique():
    seen = {}
    for p in sorted(ROOT.rglob("*.py")):
        if p.name != "__init__.py":
            seen.setdefault(p.name, []).append(str(p.relative_to(ROOT)))
    dup = {k: v for k, v in seen.items() if len(v) > 1}
    assert not dup, dup


def test_no_scene_name_comparisons_outside_scenes():
    names = "|".join(SCENES)
    pat = re.compile(rf"""(==|!=|\bin\b)\s*\(?\s*["']({names})["']|["']({names})["']\s*(==|!=)""")
    bad = []
    for p in ROOT.rglob("*.py"):
        if "scenes" in p.relative_to(ROOT).parts:
            continue
        for i, line in enumerate(p.read_text().splitlines(), 1):
            if pat.search(line) and re.search(r"scene|kind", line):
                bad.append(f"{p.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not bad, bad
