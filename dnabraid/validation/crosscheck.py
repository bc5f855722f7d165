"""Zero-temperature cross-checks of the bead model against the continuum module.

:func:`zero_temperature_braid` braids the bead model of a tweezer scene at T = 0: starting
from straight strands it turns the rotational trap to 2 pi n in small increments,
minimising the energy after each (a quasi-static path, so the braid forms as in the
experiment), and reads off the extension, the trap torque -K sin(phi - 2 pi n) and the
catenation. :func:`compare_tweezer` puts the same observables from
:func:`dnabraid.continuum.tweezer.solve_tweezer` beside it.

The continuum braid is in hard contact at a distance Delta. The bead model's contact is
the WCA wall at ~2^(1/6) d compressed by the contact pressure, so the comparison uses the
bead model's own contact distance, measured as the mean closest inter-strand bead distance
over the middle third of the braid at alpha = 0 (``contact_nm``), as Delta.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..geometry.curves import catenation_number
from ..scenes import make_scene
from ..scenes.braid import LONG_BRAID
from ..units import PN_NM_IN_KJ_MOL, TWO_PI

#: The braid the cross-checks run unless overridden: the long braid (2 x 200 nm at 2 pN),
#: a developed two-ply at n = 2, on which the tolerances of tests/test_handedness.py and
#: tests/test_crosscheck.py were set.
#: the long braid with the stiff trap of the cross-checks' measurements (K = 2e4 pN nm, the
#: braid's default until 2026-12-05): at T = 0 its lag Gamma / K keeps the bead's catenation
#: within 1e-3 turn of n
CROSSCHECK_BRAID = {**LONG_BRAID, "trap_stiffness_pN_nm": 2e4}


@dataclasses.dataclass(frozen=True)
class ZeroTBraid:
    """A zero-temperature bead braid: observables in nm, pN nm, turns."""

    turns: float
    alpha_pN: float
    extension_nm: float
    torque_pN_nm: float
    catenation: float
    contact_nm: float
    diameter_nm: float
    wall_time_s: float


def segment_gap(c0, c1) -> np.ndarray:
    """For each segment of polyline ``c0``, its closest distance to polyline ``c1`` (nm)."""
    from ..forces.segment_contact import segment_distance

    d, _, _ = segment_distance(c0[:-1, None], c0[1:, None], c1[None, :-1], c1[None, 1:])
    return d.min(axis=1)


def zero_temperature_braid(turns: float, overrides: dict | None = None, *, increments: int = 40,
                           tolerance_pN: float = 0.01, chiral_after: bool = False
                           ) -> ZeroTBraid:
    """Braid the bead model quasi-statically at T = 0 (see the module docstring).

    Parameters
    ----------
    turns : float
        Bead turns n.
    overrides : dict, optional
        Flat keys of the ``braid`` scene (``alpha``, ``force_pN``, ``length_nm``, ...) over
        :data:`CROSSCHECK_BRAID`. The surface is left out (the continuum braid has none).
    increments : int
        Trap-angle increments from 0 to 2 pi n, each followed by a minimisation.
    tolerance_pN : float
        Force tolerance of OpenMM's L-BFGS minimiser (a final pass uses 1/10 of it).
    chiral_after : bool
        Form the braid with the chiral term off (its parameter at 0) and switch it on at
        the end, then minimise: the braid in contact, the branch the continuum describes
        (formed with the term on, a disfavoured hand can stop short of contact where the
        chiral weight's decay balances the contact pressure; docs/chirality.md).
    """
    from ..run.engine import Engine

    t0 = time.perf_counter()
    over = {**CROSSCHECK_BRAID, "surface": False, **(overrides or {}), "turns": [float(turns)]}
    s = make_scene("braid", over)
    m = s.build()
    e = Engine.for_model(m, seed=s.seed, threads=1)
    chiral = chiral_after and s.alpha != 0.0
    if chiral:
        e.set_parameter("chiral_alpha", 0.0)
    e.minimise(tolerance_pN=tolerance_pN, max_iterations=20000)
    for k in range(1, increments + 1):
        e.set_parameter("trap_angle", TWO_PI * turns * k / increments)
        e.minimise(tolerance_pN=tolerance_pN, max_iterations=20000)
    if chiral:
        e.set_parameter("chiral_alpha", s.alpha * PN_NM_IN_KJ_MOL)
    for _ in range(3):
        e.minimise(tolerance_pN=0.1 * tolerance_pN, max_iterations=50000)
    pos = e.positions()
    a = m.attachments
    u = pos[a[1]] - pos[a[0]]
    lag = (math.atan2(u[1], u[0]) - TWO_PI * turns + math.pi) % TWO_PI - math.pi
    c0, c1 = pos[m.chains[0]], pos[m.chains[1]]
    if getattr(s, "contact", "beads") == "capsules":
        dmin = segment_gap(c0, c1)
    else:
        dmin = np.linalg.norm(c0[:, None] - c1[None], axis=2).min(axis=1)
    k = len(dmin)
    return ZeroTBraid(float(turns), s.alpha, float(pos[a, 2].mean()),
                      float(-s.trap_stiffness_pN_nm * math.sin(lag)),
                      float(catenation_number(c0, c1)), float(dmin[k // 3: 2 * k // 3].mean()),
                      m.params["diameter_nm"], time.perf_counter() - t0)


def compare_tweezer(turns: float, alpha_pN: float, overrides: dict | None = None,
                    contact_nm: float | None = None) -> dict:
    """Bead model at T = 0 against the continuum tweezer braid at +n and -n.

    ``contact_nm`` (the continuum's Delta) defaults to the bead model's contact at alpha = 0,
    or to D_c with ``contact = "capsules"``. Returns a dict with, for each sign, bead and
    continuum extension and torque, and the handedness asymmetries
    ``delta_z_nm = z(+n) - z(-n)`` and ``torque_sum_pN_nm = Gamma(+n) + Gamma(-n)`` of both
    (zero for both when alpha = 0).
    """
    from ..continuum.tweezer import solve_tweezer

    over = {**CROSSCHECK_BRAID, **(overrides or {})}
    s = make_scene("braid", {**over, "turns": [abs(turns)]})
    if contact_nm is None and s.contact == "capsules":
        contact_nm = s.effective_diameter_nm  # D_c: the one contact distance
    if contact_nm is None:
        contact_nm = zero_temperature_braid(abs(turns), {**over, "alpha": 0.0}).contact_nm
    out = {"turns": abs(turns), "alpha_pN": alpha_pN, "contact_nm": contact_nm}
    for sign, tag in ((1, "plus"), (-1, "minus")):
        n = sign * abs(turns)
        bead = zero_temperature_braid(n, {**over, "alpha": alpha_pN})
        cont = solve_tweezer(n, s.force_pN, s.length_nm, s.tether_separation_nm, contact_nm,
                             bending_pN_nm2=s.kT * s.persistence_nm, alpha_pN=alpha_pN)
        out[tag] = {"bead_extension_nm": bead.extension_nm, "bead_torque_pN_nm": bead.torque_pN_nm,
                    "bead_catenation": bead.catenation, "bead_contact_nm": bead.contact_nm,
                    "continuum_extension_nm": cont["extension_nm"] if cont.success else math.nan,
                    "continuum_torque_pN_nm": cont["torque_pN_nm"] if cont.success else math.nan,
                    "continuum_success": cont.success, "wall_time_s": bead.wall_time_s}
    for who in ("bead", "continuum"):
        out[f"{who}_delta_z_nm"] = (out["plus"][f"{who}_extension_nm"]
                                    - out["minus"][f"{who}_extension_nm"])
        out[f"{who}_torque_sum_pN_nm"] = (out["plus"][f"{who}_torque_pN_nm"]
                                          + out["minus"][f"{who}_torque_pN_nm"])
    return out
