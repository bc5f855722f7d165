"""What a scene declares: its keys (unit, default, help), validation, build and run.

A scene is a frozen dataclass whose fields are its keys, each declared with :func:`key`
(default, unit, help). Subclasses add keys or redeclare a key to change its default. A
scene validates itself when made (:meth:`Scene.from_values`), round-trips through TOML
(:meth:`Scene.to_toml`) and knows how to run itself into a run directory
(:meth:`Scene.run`), print its result (:meth:`Scene.report`) and give sweep rows
(:meth:`Scene.rows`). Nothing outside :mod:`dnabraid.scenes` asks a scene's name.
"""

from __future__ import annotations

import abc
import dataclasses
import math
from typing import Any, ClassVar

from .. import tomlio
from ..errors import UserError

__all__ = ["KeyInfo", "Scene", "SceneError", "key"]


class SceneError(UserError):
    """A scene could not be built: unknown key, bad value or impossible geometry."""


@dataclasses.dataclass(frozen=True)
class KeyInfo:
    """A scene key as the CLI, sweeps and docs see it."""

    name: str
    kind: str        # "float", "int", "bool", "str", "floats" (a list of numbers)
    unit: str
    default: Any
    help: str


def _kind_of(default) -> str:
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "int"
    if isinstance(default, float):
        return "float"
    if isinstance(default, str):
        return "str"
    if isinstance(default, tuple):
        return "floats"
    raise TypeError(f"unsupported key default {default!r}")


def key(default, unit: str = "", help: str = "", *, kind: str | None = None):
    """Declare a scene key (a dataclass field with its unit and help)."""
    meta = {"unit": unit, "help": help, "kind": kind or _kind_of(default)}
    return dataclasses.field(default=default, metadata=meta)


def _coerce(info: KeyInfo, value: Any):
    where = info.name + (f" (in {info.unit})" if info.unit else "")
    k = info.kind
    if k == "floats":
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            value = [value]
        if not isinstance(value, (list, tuple)) or not value:
            raise SceneError(f"{where}: expected a non-empty list of numbers, got {value!r}")
        if any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in value):
            raise SceneError(f"{where}: expected a list of numbers, got {value!r}")
        out = tuple(float(x) for x in value)
        if any(not math.isfinite(x) for x in out):
            raise SceneError(f"{where}: values must be finite, got {value!r}")
        if len(set(out)) != len(out):
            raise SceneError(f"{where}: values must be distinct, got {value!r}")
        return out
    if k == "bool":
        if isinstance(value, bool):
            return value
        raise SceneError(f"{where}: expected true or false, got {value!r}")
    if k == "int":
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not math.isfinite(value) or int(value) != value):
            raise SceneError(f"{where}: expected an integer, got {value!r}")
        return int(value)
    if k == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(f"{where}: expected a number, got {value!r}")
        if not math.isfinite(value):
            raise SceneError(f"{where}: expected a finite number, got {value!r}")
        return float(value)
    if k == "str":
        if not isinstance(value, str):
            raise SceneError(f"{where}: expected a string, got {value!r}")
        return value
    raise SceneError(f"{info.name}: unsupported kind {k!r}")  # pragma: no cover


@dataclasses.dataclass(frozen=True)
class Scene(abc.ABC):
    """Base of every scene. Subclasses set ``name`` and ``help``, declare keys and implement
    :meth:`run`, :meth:`report` and :meth:`rows` (abstract: a scene that lacks one cannot be
    made)."""

    name: ClassVar[str] = ""
    help: ClassVar[str] = ""

    # -- keys ------------------------------------------------------------------------
    @classmethod
    def keys(cls) -> dict[str, KeyInfo]:
        """The scene's keys in declaration order."""
        out = {}
        for f in dataclasses.fields(cls):
            m = f.metadata
            out[f.name] = KeyInfo(f.name, m["kind"], m["unit"], f.default, m["help"])
        return out

    @property
    def scene(self) -> str:
        """The scene's registered name (``scene = ...`` in its TOML)."""
        return self.name

    @classmethod
    def resolve(cls, values: dict) -> dict:
        """Hook: turn symbolic values into numbers before coercion (default: unchanged)."""
        return values

    @classmethod
    def from_values(cls, values: dict) -> Scene:
        """Coerce, construct and validate; raise :class:`SceneError` naming the key."""
        infos = cls.keys()
        unknown = sorted(set(values) - set(infos))
        if unknown:
            raise SceneError(f"unknown key(s) {', '.join(unknown)} for scene {cls.name!r}; "
                             f"allowed keys: {', '.join(sorted(infos))}")
        values = cls.resolve(dict(values))
        coerced = {k: _coerce(infos[k], v) for k, v in values.items()}
        s = cls(**coerced)
        s.validate()
        return s

    def need(self, cond: bool, key: str, msg: str) -> None:
        """Raise :class:`SceneError` for ``key`` with ``msg`` unless ``cond``."""
        if not cond:
            unit = self.keys()[key].unit
            raise SceneError(f"{key}={getattr(self, key)!r}{' ' + unit if unit else ''}: {msg}")

    def validate(self) -> None:  # noqa: B027 - optional hook
        """Check values and geometry (subclasses extend)."""

    # -- TOML ------------------------------------------------------------------------
    def to_dict(self) -> dict:
        d = {"scene": self.name}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            d[f.name] = list(v) if isinstance(v, tuple) else v
        return d

    def to_toml(self) -> str:
        return tomlio.dumps(self.to_dict())

    # -- running ---------------------------------------------------------------------
    def build(self):
        """The OpenMM model of a thermal scene (scenes without one raise SceneError)."""
        raise SceneError(f"scene {self.name!r} has no Brownian OpenMM model to build; run it "
                         "with `dnabraid run` (Scene.run)")

    @abc.abstractmethod
    def run(self, out: str, *, platform: str = "CPU", threads: int | None = None,
            progress_factory=None) -> dict:
        """Run the scene into the run directory ``out``; return the summary dict."""

    @abc.abstractmethod
    def report(self, summary: dict, out: str, file) -> None:
        """Print the run's result table for a person (the CLI calls this)."""

    @abc.abstractmethod
    def rows(self, summary: dict) -> list[dict]:
        """Sweep rows of one finished run: one dict per result line (column -> value)."""

    #: Columns :meth:`rows` fills (after the sweep's grid keys).
    row_columns: ClassVar[tuple] = ()

    #: Keys a sweep/extremes case may drop for this scene (e.g. a tether has no turns).
    def default_short_run(self) -> dict:
        """Overrides that make a short run of this scene (extremes matrix, smoke tests)."""
        return {}


class DNAQuantities:
    """Derived quantities of a scene with DNA keys (``temperature_K``, ``salt_mM``,
    ``diameter_nm``, ``bead_spacing_nm``, ``persistence_nm``, ``stretch_modulus_pN``): the
    tweezer scenes and the catenane share them."""

    @property
    def kT(self) -> float:
        """Thermal energy (pN nm)."""
        from ..units import kT

        return kT(self.temperature_K)

    @property
    def effective_diameter_nm(self) -> float:
        """``diameter_nm`` if set, else Stigter's effective diameter at ``salt_mM``."""
        from .. import forcefield

        if self.diameter_nm > 0:
            return float(self.diameter_nm)
        return forcefield.salt_parameters(self.salt_mM).diameter_nm

    def dna(self):
        """The bead model's :class:`~dnabraid.chains.DNAParameters` for these keys."""
        from ..chains import DNAParameters

        return DNAParameters.make(temperature_K=self.temperature_K,
                                  bead_spacing_nm=self.bead_spacing_nm,
                                  persistence_nm=self.persistence_nm,
                                  stretch_modulus_pN=self.stretch_modulus_pN,
                                  salt_mM=self.salt_mM, diameter_nm=self.diameter_nm)


def resolve_salt_alpha(values: dict, default_salt_mM: float) -> dict:
    """``alpha = 'salt'``: the chiral strength estimated at the scene's salt
    (``forcefields/chiral.toml``); any other text is refused."""
    if isinstance(values.get("alpha"), str):
        from .. import forcefield

        if values["alpha"].strip().lower() != "salt":
            raise SceneError(f"alpha (in pN): expected a number or 'salt', got "
                             f"{values['alpha']!r}")
        salt = values.get("salt_mM", default_salt_mM)
        if isinstance(salt, bool) or not isinstance(salt, (int, float)) or not salt > 0:
            raise SceneError(f"salt_mM={salt!r} mM: salt must be > 0 mM")
        values["alpha"] = forcefield.chiral_parameters(float(salt))["alpha_pN"]
    return values
