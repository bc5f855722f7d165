"""TOML reading and writing, and ``--set`` value parsing: the one place for both.

Reading uses :mod:`tomllib` (Python >= 3.11) or ``tomli``; writing covers what a resolved
scene or sweep spec holds: flat tables of numbers, strings, booleans and lists.
"""

from __future__ import annotations

import ast
import sys
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TOMLDecodeError = tomllib.TOMLDecodeError

__all__ = ["TOMLDecodeError", "dumps", "load", "load_file", "loads", "parse_value", "value"]


def load(path) -> dict:
    """Read the TOML file ``path`` into a dict."""
    with open(path, "rb") as fh:
        return tomllib.load(fh)


def load_file(path, what: str, error: type[Exception]) -> dict:
    """Read the TOML file ``path``: FileNotFoundError if missing, ``error`` if not TOML.

    ``what`` names the file in messages ("scene file", "sweep spec").
    """
    import os

    if not os.path.isfile(path):
        raise FileNotFoundError(f"{what} {os.fspath(path)!r} does not exist")
    try:
        return load(path)
    except TOMLDecodeError as exc:
        raise error(f"{what} {os.fspath(path)!r} is not valid TOML: {exc}") from exc


def loads(text: str) -> dict:
    """Parse TOML text into a dict."""
    return tomllib.loads(text)


def value(v) -> str:
    """One TOML literal: bool, int, float, str or a list of those."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def dumps(d: dict) -> str:
    """A flat table ``{key: literal}`` as TOML text (one ``key = value`` line each)."""
    return "".join(f"{k} = {value(v)}\n" for k, v in d.items())


def parse_value(text: str) -> Any:
    """Parse a ``--set`` value: numbers, lists, true/false; anything else stays a string."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    try:
        return ast.literal_eval(t)
    except (ValueError, SyntaxError):
        return t
