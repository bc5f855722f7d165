"""Zero-temperature chirality cross-check on the long braid with the capsule contact.

The bead braid (2 x 200 nm, 2 pN, tethers 40 nm apart, ``contact = "capsules"``) is formed
quasi-statically at n = +-N (:func:`dnabraid.validation.crosscheck.zero_temperature_braid`)
for each alpha and compared with the continuum braid
(:func:`dnabraid.continuum.tweezer.solve_tweezer`) at the same contact distance D_c, the
capsule contact's unloaded distance (= the effective diameter), which is also where the
chiral weight is normalised (docs/chirality.md). Three checks (issue "Chirality that agrees
with its theory", item 3):

(a) the contact distance at +-N equals the alpha = 0 value within ``CONTACT_TOL_NM`` for
    alpha <= 1 pN (the chiral weight is flat at contact, so it neither pulls the strands
    together nor pushes them apart);
(b) z(+N) - z(-N) has the continuum's sign and lies within ``DZ_RTOL`` x |continuum| +
    ``DZ_ATOL_NM`` of it;
(c) the torque sums Gamma(+N) + Gamma(-N) agree within ``TORQUE_RTOL``.
"""

from __future__ import annotations

import math
import time

from ..scenes import make_scene
from .crosscheck import CROSSCHECK_BRAID, zero_temperature_braid

CONTACT_TOL_NM = 0.02
DZ_RTOL = 0.30
DZ_ATOL_NM = 0.05
TORQUE_RTOL = 0.15
#: the scene keys of the check: the long braid with the capsule contact
CAPSULE_BRAID = {**CROSSCHECK_BRAID, "contact": "capsules"}


def continuum_pair(turns: float, alpha_pN: float, overrides: dict | None = None) -> dict:
    """The continuum braid at +-|turns| at the capsule contact distance D_c."""
    from ..continuum.tweezer import solve_tweezer

    over = {**CAPSULE_BRAID, **(overrides or {})}
    s = make_scene("braid", {**over, "turns": [abs(turns)]})
    D = s.effective_diameter_nm
    out = {"contact_nm": D}
    for sign, tag in ((1, "plus"), (-1, "minus")):
        c = solve_tweezer(sign * abs(turns), s.force_pN, s.length_nm, s.tether_separation_nm,
                          D, bending_pN_nm2=s.kT * s.persistence_nm, alpha_pN=alpha_pN)
        out[tag] = (c["extension_nm"] if c.success else math.nan,
                    c["torque_pN_nm"] if c.success else math.nan, bool(c.success))
    out["delta_z_nm"] = out["plus"][0] - out["minus"][0]
    out["torque_sum_pN_nm"] = out["plus"][1] + out["minus"][1]
    return out


def check_alpha(turns: float, alpha_pN: float, contact0_nm: float, *, increments: int = 40,
                overrides: dict | None = None, chiral_after: bool = False) -> dict:
    """One row of the table: bead braids at +-turns and the continuum at alpha_pN."""
    over = {**CAPSULE_BRAID, **(overrides or {}), "alpha": float(alpha_pN)}
    t0 = time.perf_counter()
    p = zero_temperature_braid(abs(turns), over, increments=increments,
                               chiral_after=chiral_after)
    m = zero_temperature_braid(-abs(turns), over, increments=increments,
                               chiral_after=chiral_after)
    c = continuum_pair(turns, alpha_pN, overrides)
    row = {"turns": abs(turns), "alpha_pN": float(alpha_pN), "D_c_nm": c["contact_nm"],
           "contact0_nm": contact0_nm, "contact_plus_nm": p.contact_nm,
           "contact_minus_nm": m.contact_nm,
           "bead_dz_nm": p.extension_nm - m.extension_nm, "cont_dz_nm": c["delta_z_nm"],
           "bead_torque_sum_pN_nm": p.torque_pN_nm + m.torque_pN_nm,
           "cont_torque_sum_pN_nm": c["torque_sum_pN_nm"],
           "bead_torque_plus_pN_nm": p.torque_pN_nm, "bead_torque_minus_pN_nm": m.torque_pN_nm,
           "cont_torque_plus_pN_nm": c["plus"][1], "cont_torque_minus_pN_nm": c["minus"][1],
           "catenation": (p.catenation, m.catenation),
           "continuum_success": c["plus"][2] and c["minus"][2],
           "wall_time_s": time.perf_counter() - t0}
    row.update(verdict(row))
    return row


def verdict(row: dict) -> dict:
    """The three checks of the module docstring on one row (None where not applicable)."""
    dc = max(abs(row["contact_plus_nm"] - row["contact0_nm"]),
             abs(row["contact_minus_nm"] - row["contact0_nm"]))
    a_ok = dc <= CONTACT_TOL_NM if row["alpha_pN"] <= 1.0 else None
    b, c = row["bead_dz_nm"], row["cont_dz_nm"]
    b_ok = (math.copysign(1.0, b) == math.copysign(1.0, c)
            and abs(b - c) <= DZ_RTOL * abs(c) + DZ_ATOL_NM)
    tb, tc = row["bead_torque_sum_pN_nm"], row["cont_torque_sum_pN_nm"]
    c_ok = abs(tb - tc) <= TORQUE_RTOL * abs(tc)
    return {"contact_shift_nm": dc, "a_ok": a_ok, "b_ok": bool(b_ok), "c_ok": bool(c_ok)}


def baseline(turns: float, *, increments: int = 40, overrides: dict | None = None):
    """The alpha = 0 bead braid at +turns (its mirror image at -turns is identical)."""
    return zero_temperature_braid(abs(turns), {**CAPSULE_BRAID, **(overrides or {}),
                                               "alpha": 0.0}, increments=increments)


def table(turns: float = 2.0, alphas=(0.5, 1.0, 2.0), *, increments: int = 40,
          overrides: dict | None = None, chiral_after: bool = False) -> list[dict]:
    """Every row for ``alphas`` (the alpha = 0 baseline run once)."""
    b0 = baseline(turns, increments=increments, overrides=overrides)
    return [check_alpha(turns, a, b0.contact_nm, increments=increments, overrides=overrides,
                        chiral_after=chiral_after) | {"chiral_after": chiral_after}
            for a in alphas]
