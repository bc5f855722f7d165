"""Force-field parameters of double-stranded DNA as functions of salt.

Reads the tables of the top-level ``forcefields/`` directory (``dna.toml``, ``chiral.toml``),
installed as the resource package ``dnabraid.forcefields``. Every number there names its
literature source; this module only reads, interpolates and extrapolates.

Each table is parsed once per process (:func:`load_toml` hands out deep copies, so callers
cannot change what the next caller reads). Outside the tabulated salt range
:func:`salt_parameters` and :func:`chiral_parameters` extrapolate, set ``extrapolated`` and
emit a :class:`SaltExtrapolationWarning`, once per table and salt value.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import warnings
from importlib import resources
from pathlib import Path

from dnabraid import tomlio

__all__ = ["Mechanics", "SaltExtrapolationWarning", "SaltParameters", "bending_stiffness_kT",
           "chiral_parameters", "debye_length_nm", "load_toml", "mechanics",
           "mechanics_parameters", "salt_parameters"]

#: Where the tables live in a source checkout (used only when the package
#: ``dnabraid.forcefields`` is not importable, i.e. the project is not installed).
_SOURCE_DIR = Path(__file__).resolve().parent.parent / "forcefields"


class SaltExtrapolationWarning(UserWarning):
    """A salt concentration outside a force-field table: the value is extrapolated."""


@functools.cache
def _table(name: str) -> dict:
    """Parsed ``forcefields/<name>``, read once per process. Never hand this out: it is shared."""
    try:
        path = resources.files("dnabraid.forcefields").joinpath(name)
    except ModuleNotFoundError:  # a source checkout on sys.path, not installed
        path = _SOURCE_DIR / name
    return tomlio.loads(path.read_text(encoding="utf-8"))


def load_toml(name: str) -> dict:
    """The table ``forcefields/<name>`` (e.g. ``"dna.toml"``) as a dict.

    The file is parsed once per process; each call returns a deep copy, so changing the
    result changes nothing for other callers.
    """
    return copy.deepcopy(_table(name))


_WARNED: set[tuple[str, float]] = set()


def _warn_extrapolated(table: str, salt_mM: float, lo: float, hi: float, how: str,
                       source: str) -> None:
    """Emit one :class:`SaltExtrapolationWarning` per ``(table, salt_mM)``."""
    key = (table, float(salt_mM))
    if key in _WARNED:
        return
    _WARNED.add(key)
    warnings.warn(f"salt {salt_mM:g} mM is outside the range {lo:g}-{hi:g} mM tabulated in "
                  f"forcefields/{table}; {how} (source: {source})",
                  SaltExtrapolationWarning, stacklevel=3)


@dataclasses.dataclass(frozen=True)
class SaltParameters:
    """What DNA looks like at one monovalent salt concentration.

    Attributes
    ----------
    salt_mM : float
    debye_nm : float
        Debye screening length.
    diameter_nm : float
        Effective hard-core diameter (Stigter 1977).
    extrapolated : bool
        True when ``salt_mM`` lies outside the tabulated range.
    source : str
    """

    salt_mM: float
    debye_nm: float
    diameter_nm: float
    extrapolated: bool
    source: str


def debye_length_nm(salt_mM: float) -> float:
    """Debye length lambda_D = 0.304 nm / sqrt(I/M) of a 1:1 salt at 25 C."""
    if not salt_mM > 0:
        raise ValueError(f"salt_mM must be > 0, got {salt_mM!r}")
    pref = _table("dna.toml")["electrostatics"]["debye_prefactor_nm"]
    return pref / math.sqrt(salt_mM / 1000.0)


def salt_parameters(salt_mM: float) -> SaltParameters:
    """Effective diameter and Debye length at ``salt_mM`` (monovalent salt, mM).

    Between the points of ``[effective_diameter]`` in ``dna.toml`` the diameter is
    interpolated linearly in log(salt). Outside them, ``d - d_bare`` scales with the Debye
    length from the nearest end point (growing like lambda_D at low salt, tending to the bare
    duplex at high salt), ``extrapolated`` is True and a :class:`SaltExtrapolationWarning`
    names the salt, the table range and the source (once per salt value).
    """
    if isinstance(salt_mM, bool) or not (isinstance(salt_mM, (int, float))
                                         and math.isfinite(salt_mM) and salt_mM > 0):
        raise ValueError(f"salt_mM must be a positive number (mM), got {salt_mM!r}")
    table = _table("dna.toml")["effective_diameter"]
    cs = table["salt_mM"]
    ds = table["diameter_nm"]
    lam = debye_length_nm(salt_mM)
    extrapolated = not (cs[0] <= salt_mM <= cs[-1])
    if salt_mM < cs[0]:
        # d - d_bare scales like the Debye length at low salt (Stigter's asymptotics).
        lam0 = debye_length_nm(cs[0])
        d = table["bare_diameter_nm"] + (ds[0] - table["bare_diameter_nm"]) * lam / lam0
    elif salt_mM > cs[-1]:
        lam1 = debye_length_nm(cs[-1])
        d = table["bare_diameter_nm"] + (ds[-1] - table["bare_diameter_nm"]) * lam / lam1
    else:
        x = math.log(salt_mM)
        xs = [math.log(c) for c in cs]
        for i in range(len(xs) - 1):
            if xs[i] <= x <= xs[i + 1]:
                t = (x - xs[i]) / (xs[i + 1] - xs[i])
                d = ds[i] + t * (ds[i + 1] - ds[i])
                break
    if extrapolated:
        _warn_extrapolated("dna.toml", salt_mM, cs[0], cs[-1],
                           f"effective diameter extrapolated with the Debye length to "
                           f"{d:.3g} nm", table["source"])
    return SaltParameters(float(salt_mM), lam, float(d), extrapolated, table["source"])


@dataclasses.dataclass(frozen=True)
class Mechanics:
    """The ``[mechanics]`` table of ``dna.toml``: elastic constants of the double helix.

    Attributes
    ----------
    persistence_nm : float
        Bending persistence length A (at >= ~100 mM monovalent salt).
    stretch_modulus_pN : float
        Stretch modulus S.
    twist_persistence_nm : float
        Twist persistence length C.
    rise_nm_per_bp : float
        Helical rise per base pair.
    hydrodynamic_radius_fraction : float
        Bead Stokes radius as a fraction of the bead spacing.
    persistence_source, stretch_modulus_source, twist_persistence_source,
    hydrodynamic_source : str
        Literature source of each number.
    """

    persistence_nm: float
    stretch_modulus_pN: float
    twist_persistence_nm: float
    rise_nm_per_bp: float
    hydrodynamic_radius_fraction: float
    persistence_source: str
    stretch_modulus_source: str
    twist_persistence_source: str
    hydrodynamic_source: str


@functools.cache
def mechanics_parameters() -> Mechanics:
    """The ``[mechanics]`` table of ``dna.toml`` as a (frozen) :class:`Mechanics`."""
    m = _table("dna.toml")["mechanics"]
    return Mechanics(**{f.name: str(m[f.name]) if f.name.endswith("_source") else
                        float(m[f.name]) for f in dataclasses.fields(Mechanics)})


def mechanics() -> dict:
    """The ``[mechanics]`` table of dna.toml as a new dict (persistence, stretch modulus, ...).

    See :func:`mechanics_parameters` for the typed form.
    """
    return dict(_table("dna.toml")["mechanics"])


def bending_stiffness_kT(bead_spacing_nm: float, persistence_nm: float) -> float:
    """Hinge stiffness kappa/kT of the discrete worm-like chain U = kappa (1 - cos theta).

    Exact mapping: for a freely rotating hinge with Boltzmann weight exp(kappa cos theta / kT)
    the mean cosine is the Langevin function L(x) = coth(x) - 1/x with x = kappa/kT, and the
    persistence length of the discrete chain is defined by <cos theta> = exp(-b / lp).
    Solve L(x) = exp(-b/lp) for x (Newton with bisection safeguard).

    Parameters
    ----------
    bead_spacing_nm, persistence_nm : float

    Returns
    -------
    float
        kappa / kT (dimensionless).
    """
    if bead_spacing_nm <= 0 or persistence_nm <= 0:
        raise ValueError("bead spacing and persistence length must be positive")
    target = math.exp(-bead_spacing_nm / persistence_nm)

    def langevin(x):
        if x < 1e-4:
            return x / 3.0
        return 1.0 / math.tanh(x) - 1.0 / x

    lo, hi = 1e-8, 1e8
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        if langevin(mid) < target:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1 + 1e-14:
            break
    return math.sqrt(lo * hi)


def chiral_parameters(salt_mM: float) -> dict:
    """Chiral strength alpha (pN) and its bracket at ``salt_mM``, from ``chiral.toml``.

    Log-linear interpolation in salt between the tabulated values; outside the table the
    nearest entry is used, ``extrapolated`` is True and a :class:`SaltExtrapolationWarning`
    is emitted (once per salt value). ``range_nm`` is the decay length of the chiral weight,
    the range of the first helical harmonic of the DNA charge (Kornyshev & Leikin, J. Chem.
    Phys. 107, 3656 (1997)): 1/sqrt(lambda_D^-2 + (2 pi / H)^2) with lambda_D from
    :func:`debye_length_nm` and H the table's ``[helix] pitch_nm``
    (:func:`dnabraid.forces.reference_chiral.chiral_range_nm`), computed at ``salt_mM``
    whether or not it is tabulated (the table's ``range_nm`` entries are this formula,
    rounded, for reading).

    Returns
    -------
    dict with ``alpha_pN``, ``alpha_min_pN``, ``alpha_max_pN``, ``range_nm``,
    ``extrapolated`` and ``source``.
    """
    from dnabraid.forces.reference_chiral import chiral_range_nm

    if isinstance(salt_mM, bool) or not (isinstance(salt_mM, (int, float))
                                         and math.isfinite(salt_mM) and salt_mM > 0):
        raise ValueError(f"salt_mM must be a positive number (mM), got {salt_mM!r}")
    table = sorted(((float(k), v) for k, v in _table("chiral.toml")["salt"].items()),
                   key=lambda kv: kv[0])
    cs = [c for c, _ in table]
    rho = chiral_range_nm(debye_length_nm(salt_mM), _table("chiral.toml")["helix"]["pitch_nm"])
    out = {"range_nm": rho, "extrapolated": not cs[0] <= salt_mM <= cs[-1]}
    keys = ("alpha_pN", "alpha_min_pN", "alpha_max_pN")
    if salt_mM <= cs[0] or salt_mM >= cs[-1]:
        end, entry = table[0] if salt_mM <= cs[0] else table[-1]
        out.update({k: float(entry[k]) for k in keys}, source=entry["source"])
        if out["extrapolated"]:
            _warn_extrapolated("chiral.toml", salt_mM, cs[0], cs[-1],
                               f"alpha held at its {end:g} mM value {out['alpha_pN']:g} pN",
                               entry["source"])
        return out
    for (c0, e0), (c1, e1) in zip(table[:-1], table[1:]):
        if c0 <= salt_mM <= c1:
            t = (math.log(salt_mM) - math.log(c0)) / (math.log(c1) - math.log(c0))
            out.update({k: float(e0[k] + t * (e1[k] - e0[k])) for k in keys})
            out["source"] = e0["source"] if t < 0.5 else e1["source"]
            return out
    raise AssertionError("unreachable")  # pragma: no cover
