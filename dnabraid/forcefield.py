"""Force-field parameters of double-stranded DNA as functions of salt.

Reads ``forcefields/dna.toml`` (shipped inside the package). Every number there names
its literature source; this module only interpolates.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from importlib import resources

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def load_toml(name: str) -> dict:
    """Load ``dnabraid/forcefields/<name>`` as a dict."""
    with resources.files("dnabraid.forcefields").joinpath(name).open("rb") as fh:
        return tomllib.load(fh)


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
    pref = load_toml("dna.toml")["electrostatics"]["debye_prefactor_nm"]
    return pref / math.sqrt(salt_mM / 1000.0)


def salt_parameters(salt_mM: float) -> SaltParameters:
    """Effective diameter and Debye length at ``salt_mM`` (monovalent salt, mM)."""
    if not (isinstance(salt_mM, (int, float)) and math.isfinite(salt_mM) and salt_mM > 0):
        raise ValueError(f"salt_mM must be a positive number (mM), got {salt_mM!r}")
    table = load_toml("dna.toml")["effective_diameter"]
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
    return SaltParameters(float(salt_mM), lam, float(d), extrapolated, table["source"])


def mechanics() -> dict:
    """The ``[mechanics]`` table of dna.toml (persistence, stretch modulus, ...)."""
    return dict(load_toml("dna.toml")["mechanics"])


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
    nearest entry is used and ``extrapolated`` is True. The range of the interaction is the
    Debye length (:func:`debye_length_nm`), as in the table's ``range_nm``.

    Returns
    -------
    dict with ``alpha_pN``, ``alpha_min_pN``, ``alpha_max_pN``, ``range_nm``,
    ``extrapolated`` and ``source``.
    """
    if not (isinstance(salt_mM, (int, float)) and math.isfinite(salt_mM) and salt_mM > 0):
        raise ValueError(f"salt_mM must be a positive number (mM), got {salt_mM!r}")
    table = sorted(((float(k), v) for k, v in load_toml("chiral.toml")["salt"].items()),
                   key=lambda kv: kv[0])
    cs = [c for c, _ in table]
    out = {"range_nm": debye_length_nm(salt_mM), "extrapolated": not cs[0] <= salt_mM <= cs[-1]}
    keys = ("alpha_pN", "alpha_min_pN", "alpha_max_pN")
    if salt_mM <= cs[0] or salt_mM >= cs[-1]:
        entry = table[0][1] if salt_mM <= cs[0] else table[-1][1]
        out.update({k: float(entry[k]) for k in keys}, source=entry["source"])
        return out
    for (c0, e0), (c1, e1) in zip(table[:-1], table[1:]):
        if c0 <= salt_mM <= c1:
            t = (math.log(salt_mM) - math.log(c0)) / (math.log(c1) - math.log(c0))
            out.update({k: float(e0[k] + t * (e1[k] - e0[k])) for k in keys})
            out["source"] = e0["source"] if t < 0.5 else e1["source"]
            return out
    raise AssertionError("unreachable")  # pragma: no cover
