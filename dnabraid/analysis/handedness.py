"""Handedness of thermal braids from gathered sweep rows (tweezer scenes).

Mirror symmetry makes an achiral braid's extension and trap torque even in the bead turns
n; a chiral term (``alpha``) breaks it. Two statistics of the rows that
:func:`dnabraid.sweep.gather` returns (one per point and turn value, with ``turns``,
``extension_nm`` and ``torque_pN_nm`` and their standard errors):

* :func:`asymmetry`: z(+n) - z(-n) per grid point, at the largest n with both signs;
* :func:`handedness_across_seeds`: the torque sum Gamma(+n) + Gamma(-n) and z(+n) - z(-n)
  per value of a grid key, with their standard errors across independent seeds.

Pure Python on lists of dicts; rows without ``turns`` and ``extension_nm`` (the knot
scene's) are ignored.
"""

from __future__ import annotations

import math

__all__ = ["asymmetry", "handedness_across_seeds"]


def _tweezer_rows(rows: list[dict]) -> list[dict]:
    """The finished rows that hold a turn value and an extension."""
    return [r for r in rows if r.get("status") == "done"
            and r.get("turns") is not None and r.get("extension_nm") is not None]


def asymmetry(rows: list[dict], keys: list[str]) -> list[dict]:
    """Handedness asymmetry z(+n) - z(-n) per grid point, for the largest n with both signs.

    Parameters
    ----------
    rows : list of dict
        Gathered sweep rows (:func:`dnabraid.sweep.gather`); only ``done`` rows with
        ``turns`` and ``extension_nm`` (nm) count.
    keys : list of str
        The grid keys, copied into each result.

    Returns
    -------
    list of dict
        One per point (in the order the rows first name it) with the grid values,
        ``point``, ``n`` (turns), ``asymmetry_nm`` (z(+n) - z(-n), nm) and
        ``asymmetry_sem_nm`` (the two standard errors in quadrature, nm). Points without a
        +n/-n pair (or rows without ``turns`` and ``extension_nm``, e.g. of the knot
        scene) are left out.
    """
    by_point: dict = {}
    for r in _tweezer_rows(rows):
        by_point.setdefault(r["point"], []).append(r)
    out = []
    for name, rs in by_point.items():
        z = {r["turns"]: (r["extension_nm"], r.get("extension_sem_nm")) for r in rs}
        pairs = [n for n in z if n > 0 and -n in z]
        if not pairs:
            continue
        n = max(pairs)
        (zp, sp), (zm, sm) = z[n], z[-n]
        out.append({**{k: rs[0][k] for k in keys}, "point": name, "n": n,
                    "asymmetry_nm": zp - zm, "asymmetry_sem_nm": math.hypot(sp or 0, sm or 0)})
    return out


def handedness_across_seeds(rows: list[dict], turns: float, *, group: str = "alpha",
                            seed: str = "seed") -> list[dict]:
    """Handedness of thermal braids with its error from independent seeds.

    Within one run the autocorrelation-corrected SEM of the trap torque is ~1.6x too small
    (a slow component escapes the window), so the error of the handedness comes from a
    sweep over ``seed``: per seed the torque sum Gamma(+n) + Gamma(-n) and the extension
    difference z(+n) - z(-n), then their mean and standard error across seeds. Without a
    chiral term both vanish by mirror symmetry; alpha > 0 favours right-handed braids
    (n > 0), so less torque holds +n (zero-temperature continuum: Gamma(+n) + Gamma(-n)
    ~ -2 r alpha, :func:`dnabraid.validation.crosscheck.compare_tweezer`).

    Parameters
    ----------
    rows : list of dict
        Gathered sweep rows (:func:`dnabraid.sweep.gather`) of a tweezer scene whose grid holds ``seed``.
    turns : float
        n (> 0); each seed must have run both +n and -n.
    group : str
        The grid key to group by (default ``alpha``).
    seed : str
        The grid key of the seeds.

    Returns
    -------
    list of dict
        One per value of ``group`` (ascending): ``group``, ``seeds`` (count),
        ``torque_sum_pN_nm``, ``torque_sum_se_pN_nm``, ``t`` (mean / SE),
        ``delta_z_nm``, ``delta_z_se_nm``, ``torque_sums`` (per seed). Means and errors are
        None with fewer than two seeds.
    """
    n = abs(float(turns))
    by: dict = {}
    for r in _tweezer_rows(rows):
        if r.get("torque_pN_nm") is None:
            continue
        key = (float(r[group]), r[seed])
        by.setdefault(key, {})[float(r["turns"])] = (float(r["torque_pN_nm"]),
                                                     float(r["extension_nm"]))
    out = []
    for g in sorted({k[0] for k in by}):
        sums, dz = [], []
        for (gg, _s), pts in sorted(by.items(), key=lambda kv: (kv[0][0], str(kv[0][1]))):
            if gg == g and n in pts and -n in pts:
                sums.append(pts[n][0] + pts[-n][0])
                dz.append(pts[n][1] - pts[-n][1])
        rec = {"group": g, "seeds": len(sums), "torque_sums": sums, "torque_sum_pN_nm": None,
               "torque_sum_se_pN_nm": None, "t": None, "delta_z_nm": None,
               "delta_z_se_nm": None}
        if len(sums) >= 2:
            m, sd = _mean_se(sums)
            mz, sdz = _mean_se(dz)
            rec.update(torque_sum_pN_nm=m, torque_sum_se_pN_nm=sd,
                       t=m / sd if sd > 0 else math.copysign(math.inf, m) if m else 0.0,
                       delta_z_nm=mz, delta_z_se_nm=sdz)
        out.append(rec)
    return out


def _mean_se(x: list[float]) -> tuple[float, float]:
    """Mean and standard error of the mean (sample standard deviation / sqrt(n))."""
    m = sum(x) / len(x)
    var = sum((v - m) ** 2 for v in x) / (len(x) - 1)
    return m, math.sqrt(var / len(x))

