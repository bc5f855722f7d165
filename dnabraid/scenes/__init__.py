"""Scenes: one module per scene, and the registry everything else reads.

``SCENES`` maps a scene's name to its class; :func:`make_scene` builds one from a name or
a TOML file plus flat ``KEY=VALUE`` overrides, validated at this entry point. The CLI
(``dnabraid scenes``, ``dnabraid run``), sweeps and the extremes matrix read the keys,
defaults, units and help from here; nothing outside this package asks a scene's name.

Adding a thermal scene = one new module here with a
:class:`~dnabraid.scenes.thermal.ThermalScene` subclass (``name``, ``help``, keys declared
with :func:`~dnabraid.scenes.base.key`, ``validate``, ``build`` into a typed
:class:`~dnabraid.chains.Model`, ``observables``, ``states`` and ``state_of``) and one line
in ``SCENES``; the run driver (:mod:`dnabraid.run.driver`) does the rest. A zero-temperature
scene subclasses :class:`~dnabraid.scenes.base.Scene` and implements ``run``, ``report`` and
``rows`` itself.
"""

from __future__ import annotations

import os

from .. import tomlio
from .base import KeyInfo, Scene, SceneError, key
from .braid import Braid
from .catenane import Catenane
from .closed import Closed
from .knot import Knot
from .plectoneme import Plectoneme
from .tether import Tether

__all__ = ["SCENES", "KeyInfo", "Scene", "SceneError", "key", "make_scene", "parse_value",
           "scene_class"]

#: The registry: scene name -> scene class (in the order `dnabraid scenes` lists them).
SCENES: dict[str, type[Scene]] = {c.name: c for c in (Braid, Tether, Plectoneme, Knot, Catenane,
                                                         Closed)}

parse_value = tomlio.parse_value


def scene_class(name: str) -> type[Scene]:
    """The scene class registered as ``name``."""
    try:
        return SCENES[name]
    except (KeyError, TypeError):
        raise SceneError(f"unknown scene {name!r}; built-in scenes are: "
                         + ", ".join(SCENES)) from None


def make_scene(base: str | os.PathLike = "braid", overrides: dict | None = None) -> Scene:
    """Build and validate a scene.

    Parameters
    ----------
    base : str or path
        A registered scene name (see ``SCENES``) or a path to a TOML file (its ``scene``
        key names the kind; default ``braid``).
    overrides : dict, optional
        Flat keys overriding the base (see ``dnabraid scenes``).

    Raises
    ------
    SceneError
        For an unknown scene, key, a bad value or an impossible geometry.
    FileNotFoundError
        For a missing TOML file.
    """
    base_s = os.fspath(base)
    values: dict = {}
    if base_s in SCENES:
        cls = SCENES[base_s]
    elif base_s.endswith(".toml") or os.path.sep in base_s:
        data = tomlio.load_file(base_s, "scene file", SceneError)
        name = data.pop("scene", "braid")
        if name not in SCENES:
            raise SceneError(f"{base_s}: unknown scene {name!r}; built-in scenes are: "
                             + ", ".join(SCENES))
        cls = SCENES[name]
        values.update(data)
    else:
        raise SceneError(f"unknown scene {base_s!r}: give one of the built-in scenes ("
                         + ", ".join(SCENES) + ") or a path to a .toml file")
    if overrides:
        values.update(overrides)
    return cls.from_values(values)
