"""The plectoneme scene: keys, the terms it builds, linking-number conservation over a run,
the two torque estimators, the plectoneme finder, MDAnalysis classes, and (slow) the hat
curve against Moroz-Nelson and the buckling torque.
"""

import math
import os

import numpy as np
import pytest

from dnabraid.geometry import ribbon as atw
from dnabraid.scenes import SceneError, make_scene

Z_TOL = 4.0
#: Linking number: Tw + Wr must equal the imposed turns to 1 % (the bead lags the trap by
#: torque / K ~ 1e-4 turns; Tw + Wr equals the bead angle to round-off).
LK_RTOL = 0.01
#: The sampling these runs were written and measured with before the plectoneme's defaults
#: became move-dominant (2026-12-04: 20 000 moves per 50 steps); 500 moves per 100 steps
#: keep them short.
OLD_SAMPLING = {"mc_moves": 500, "report_interval": 100}


def test_scene_keys_and_validation():
    s = make_scene("plectoneme")
    assert s.twist_persistence_nm == 100.0
    assert "twist_persistence_nm" in s.to_dict()
    assert "twist_persistence_nm" not in make_scene("braid").to_dict()
    with pytest.raises(SceneError, match="twist_persistence_nm"):
        make_scene("braid", {"twist_persistence_nm": 90.0})
    with pytest.raises(SceneError, match="tether_separation_nm"):
        make_scene("plectoneme", {"tether_separation_nm": 20.0})
    with pytest.raises(SceneError, match="twist_persistence_nm"):
        make_scene("plectoneme", {"twist_persistence_nm": 2.0})
    # a plectoneme's branches must not pass through each other, whatever its length
    with pytest.raises(SceneError, match="bead_spacing_nm"):
        make_scene("plectoneme", {"length_nm": 60.0, "bead_spacing_nm": 10.0, "persistence_nm": 50.0})


def test_chiral_term_built_for_plectoneme():
    # the moves' local energies have no chiral term: mc_moves = 0 with alpha
    m = make_scene("plectoneme", {"length_nm": 100.0, "alpha": 0.5, "mc_moves": 0}).build()
    assert "chiral" in m.forces
    assert "chiral" in m.params["rates_per_ns"]
    m0 = make_scene("plectoneme", {"length_nm": 100.0}).build()
    assert "chiral" not in m0.forces


def synthetic_plectoneme(tail1=60.0, arms=80.0, tail2=60.0, b=2.5, radius=4.0, pitch=20.0,
                         x0=0.0):
    """Tail up the z axis, a two-branch plectoneme along +x, tail on up.

    Branch 1 runs out along a right-handed helix of radius ``radius`` about the plectoneme
    axis, a half-circle end loop turns it back, branch 2 returns interwound (half a
    period out of phase)."""
    pts = [np.array([x0, 0, z]) for z in np.arange(0, tail1, b)]
    base = np.array([x0, 0, tail1])
    s = np.arange(0, arms, b)
    ph = 2 * np.pi * s / pitch
    out = base + np.c_[s, radius * np.cos(ph), radius * np.sin(ph)] - [0, radius, 0]
    back = base + np.c_[s[::-1], radius * np.cos(ph[::-1] + np.pi),
                        radius * np.sin(ph[::-1] + np.pi)] - [0, radius, 0]
    pts += list(out) + list(back)
    top = np.array([x0, 0, tail1 + 2 * radius])
    pts += [top + [0, 0, z] for z in np.arange(b, tail2, b)]
    return np.array(pts)


def test_plectoneme_finder_on_synthetic_chains():
    b = 2.5
    straight = np.c_[np.zeros(80), np.zeros(80), b * np.arange(80)]
    assert atw.find_plectonemes(straight) == []
    p = synthetic_plectoneme()
    found = atw.find_plectonemes(p)
    assert len(found) == 1
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    # the plectoneme is the DNA between the two tails: 2 x 80 nm of branches (+ loop); its
    # ends are found to about the contact distance on each side (tail beads near the base
    # touch the far branch)
    n_tail = len(np.arange(0, 60.0, b))
    start, end = s[n_tail], s[n_tail + 2 * len(np.arange(0, 80.0, b)) - 1]
    assert found[0].length_nm == pytest.approx(end - start, abs=2 * 12.0 + 6.0)
    assert found[0].tip_nm == pytest.approx(0.5 * (start + end), abs=10.0)
    # two plectonemes along one chain
    p2 = synthetic_plectoneme()
    q = p2[-1] + (synthetic_plectoneme() - synthetic_plectoneme()[0]) + [0, 0, b]
    two = np.vstack([p2, q])
    assert len(atw.find_plectonemes(two)) == 2
    summ = atw.plectoneme_summary(two)
    assert summ["count"] == 2 and summ["length_nm"] > 2 * 100


@pytest.fixture(scope="module")
def twisted_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("plect") / "run"
    s = make_scene("plectoneme", {"length_nm": 60.0, "force_pN": 2.0, "turns": [0.0, 1.5],
                                  "steps": 16_000, "equilibration_steps": 4000,
                                  "turn_rate": 2e-4, "frame_interval": 1000, "seed": 3,
                                  "replicas": 1, **OLD_SAMPLING})
    return s, str(out), s.run(str(out))


def test_linking_number_conserved(twisted_run):
    """Tw + Wr equals the bead turns in every frame (no passage), and the imposed turns to 1 %."""
    s, out, summ = twisted_run
    from dnabraid.run.reporters import read_point

    pdir = os.path.join(out, "replicas", "r00", "points")
    for f in sorted(os.listdir(pdir)):
        samples, frames = read_point(os.path.join(pdir, f))
        turns = float(frames["turns"][0])
        lk = frames["twist"] + frames["writhe"]
        assert np.all(np.abs(lk - turns) <= LK_RTOL * max(abs(turns), 1.0)), (turns, lk)
        # frames are taken at observable samples: Lk = bead angle to round-off
        idx = np.searchsorted(samples["step"], frames["step"])
        np.testing.assert_allclose(lk, samples["bead_angle_turns"][idx], atol=1e-6)
        if turns != 0:
            assert np.std(frames["writhe"]) > 0.005  # twist and writhe really exchange


def test_torque_estimators_agree(twisted_run):
    """The trap torque -K sin(lag) and the twist torque 2 pi Tw C kT / L measure the same
    mean torque; at n = 1.5 (below buckling for 60 nm at 2 pN) it is positive."""
    s, out, summ = twisted_run
    pts = {p["turns"]: p for p in summ["points"]}
    for n, p in pts.items():
        tt, tr = p["twist_torque_pN_nm"], p["torque_pN_nm"]
        assert abs(tt["mean"] - tr["mean"]) < Z_TOL * math.hypot(tt["sem"], tr["sem"]) + 2.0
    t15 = pts[1.5]["twist_torque_pN_nm"]
    assert t15["mean"] > 10 * t15["sem"]
    assert abs(pts[0.0]["twist_torque_pN_nm"]["mean"]) < Z_TOL * pts[0.0]["twist_torque_pN_nm"]["sem"] + 1.0
    # summary carries the twist observables with units
    assert {"twist", "writhe", "linking", "plectonemes"} <= set(summ["points"][0])
    assert "twist_torque_pN_nm" in summ["units"]


def test_ramps_run_the_moves(twisted_run):
    """The ramp to n = 1.5 gets the moves too: the point's move count is the number of report
    intervals of ramp, equilibration and sampling times the moves per interval (until
    2026-12-03 a ramp ran by Brownian dynamics alone; docs/validation.md 2.3i)."""
    import json

    s, out, summ = twisted_run
    ri = s.report_interval
    ramp = math.ceil(math.ceil(1.5 / s.turn_rate) / ri) * ri
    pdir = os.path.join(out, "replicas", "r00", "points")
    point = [f for f in sorted(os.listdir(pdir)) if "+001.5" in f][0]
    with open(os.path.join(pdir, point, "moves.json")) as fh:
        moves = json.load(fh)
    attempted = sum(v["attempted"] for v in moves.values() if isinstance(v, dict))
    intervals = (ramp + s.equilibration_steps + s.steps) // ri
    assert attempted == intervals * s.mc_moves


def test_ramp_checks_the_linking_number_and_names_the_turn_rate(tmp_path, monkeypatch):
    """A passage during a ramp stops the run within the ramp, and the message names the
    ramp's turn rate. The passage is simulated: the writhe jumps by one turn once the trap
    is past 0.6 turns. Until 2026-12-03 the check ran only on sampled frames, after the
    ramp and the equilibration, and blamed the time step (a 1-um plectoneme turned at 1e-3
    turns/step)."""
    from dnabraid import observables as ob
    from dnabraid.run.engine import SimulationBlowUp

    call = ob.TwistWrithe.__call__

    def passed(self, pos, ctx, values):
        v = call(self, pos, ctx, values)
        return dict(v, writhe=v["writhe"] + (1.0 if ctx.trap_turns > 0.6 else 0.0))

    monkeypatch.setattr(ob.TwistWrithe, "__call__", passed)
    s = make_scene("plectoneme", {"length_nm": 60.0, "force_pN": 2.0, "turns": [1.5],
                                  "steps": 2000, "equilibration_steps": 500,
                                  "turn_rate": 1e-3, "frame_interval": 500, "seed": 3,
                                  "replicas": 1, "workers": 1, **OLD_SAMPLING})
    with pytest.raises(SimulationBlowUp) as exc:
        s.run(str(tmp_path / "run"), platform="CPU", threads=1)
    ramp_end = math.ceil(math.ceil(1.5 / 1e-3) / s.report_interval) * s.report_interval
    assert exc.value.step <= ramp_end
    msg = str(exc.value)
    assert "changed its linking number" in msg
    assert "while the trap turned from 0 to 1.5 turns at 0.001 turns/step" in msg
    assert "try a smaller turn_rate" in msg


def test_mdanalysis_twist_writhe_and_plectonemes(twisted_run):
    import MDAnalysis as mda

    from dnabraid.analysis.mda import Plectonemes, TwistWrithe, select_twisted_tether

    s, out, summ = twisted_run
    u = mda.Universe(os.path.join(out, "topology.pdb"), os.path.join(out, "trajectory.dcd"))
    dna, sides, bead = select_twisted_tether(u)
    assert len(dna) == s.n_beads and len(sides) == s.n_beads - 1
    tw = TwistWrithe(dna, sides, bead, twist_persistence_nm=s.twist_persistence_nm,
                     kT_pN_nm=s.kT, contour_nm=s.length_nm).run()
    n_frames = u.trajectory.n_frames
    assert tw.results.linking.shape == (n_frames,)
    # the last frames belong to turns = 1.5 (points are written sorted by turns); DCD
    # positions are single precision
    assert tw.results.linking[-1] == pytest.approx(1.5, abs=LK_RTOL * 1.5)
    pl = Plectonemes(dna, contact_nm=12.0).run()
    assert pl.results.count.shape == (n_frames,)


@pytest.mark.slow
def test_hat_curve_against_theory(tmp_path):
    """100 nm at 1 pN, seed 5, turns 0 ... 2 in halves (the buckling of a short chain).

    Against theory: below buckling C_eff from the torque slope vs Moroz & Nelson (PNAS 94,
    14418 (1997), Eq. 12; model tolerance 15 %: a 100-nm chain of 5-nm bonds lacks part of
    the long rod's writhe fluctuations); the largest torque of the straight phase below
    Greenhill's linear instability of a twisted rod under tension, 2 sqrt(kT A F) = 28.7 pN nm
    (no stretched rod carries more), so buckling comes at the latest at the first turn past
    Greenhill's n = 2 sqrt(kT A F) L / (2 pi kT C_eff); at buckling the torque drops (the
    hat's finite-size overshoot, Marko, PRE 76, 021926 (2007); Daniels et al., PRE 80,
    040901 (2009)). The lower bound n_buckle >= 1 is a characterisation: the point before it
    has a stretched-phase torque (11.3 pN nm measured) below this model's long-chain
    coexistence torque, 12.5-12.7 pN nm measured at 0.5 and 1 um (docs/validation.md 2.3h).

    Measured 2026-12-06 (turns 0 ... 3, 883 s on one core): C_eff 87.5 +- 0.4 nm (85.7),
    torque 11.32, 19.98, 14.71, 16.29, 19.39, 22.63 pN nm at n = 0.5 ... 3 (SE 0.06-0.16),
    buckled from 1.5 (plectoneme in 91 % of frames). A 100-nm chain has no torque plateau:
    once the plectoneme has taken up the chain (z 39 -> 14 nm from n = 1.5 to 3) the torque
    rises again, so the old check "plateau between 1.0 and 1.6 x sqrt(2 kT A F)" (from a
    26.5 pN nm read before the replica errors) tested a mean over points of another regime;
    the long chains' plateau is 0.62 x sqrt(2 kT A F) (2.3h).
    """
    from dnabraid.analysis.hat_curve import hat_curve

    s = make_scene("plectoneme", {"force_pN": 1.0, "length_nm": 100.0,
                                  "turns": [0, 0.5, 1, 1.5, 2], "steps": 150000,
                                  "equilibration_steps": 50000, "frame_interval": 2000,
                                  "seed": 5, "turn_rate": 5e-5, **OLD_SAMPLING})
    summ = s.run(str(tmp_path / "run"))
    _, res = hat_curve(summ)
    pts = sorted(summ["points"], key=lambda p: p["turns"])
    n = np.array([p["turns"] for p in pts])
    tq = np.array([p["twist_torque_pN_nm"]["mean"] for p in pts])
    se = np.array([p["twist_torque_pN_nm"]["sem"] for p in pts])
    table = ", ".join(f"n {a:g}: {b:.2f} +- {c:.2f}" for a, b, c in zip(n, tq, se))
    tol = Z_TOL * res["ceff_sim_err"] + 0.15 * res["ceff_theory"]
    assert res["ceff_sim"] == pytest.approx(res["ceff_theory"], abs=tol)
    assert res["ceff_sim"] < res["C"]  # writhe fluctuations soften the twist
    sc = summ["scene"]
    kT, A, F, L = res["kT"], sc["persistence_nm"], sc["force_pN"], sc["length_nm"]
    greenhill = 2.0 * math.sqrt(kT * A * F)
    n_greenhill = greenhill * L / (2 * math.pi * kT * res["ceff_sim"])
    nb = res["n_buckle"]
    assert 1.0 <= nb <= n[n >= n_greenhill][0], (nb, n_greenhill, table)
    k = int(np.nonzero(n == nb)[0][0])
    assert tq[:k].max() < greenhill, table
    assert tq[k] < tq[k - 1] - Z_TOL * math.hypot(se[k], se[k - 1]), table


def test_hat_curve_theory_values():
    """Moroz & Nelson's C_eff and the buckling torque at F = 1 pN, A = 50 nm, C = 100 nm,
    kT = 4.11 pN nm (independent arithmetic)."""
    from dnabraid.analysis.hat_curve import buckling_torque, moroz_nelson_ceff

    kT = 4.11
    assert moroz_nelson_ceff(100.0, 50.0, 1.0, kT) == pytest.approx(
        100.0 * (1.0 - 0.5 * math.sqrt(kT / 50.0)), rel=1e-12)
    assert moroz_nelson_ceff(100.0, 50.0, 1.0, kT) == pytest.approx(85.66, abs=0.01)
    assert buckling_torque(50.0, 1.0, kT) == pytest.approx(20.27, abs=0.01)


def test_two_phase_theory_values():
    """Marko's (2007) two-phase coexistence at F = 1 pN, A = 50 nm, C = 100 nm, kT = 4.11
    pN nm, P = 24 nm, by independent arithmetic: g = F - sqrt(kT F / A), c_s from
    Moroz-Nelson, tau^2 = 2 g p c_s / (c_s - p) (p = kT P, c_s = kT C_s); the slope from the
    two twist rates -2 pi x / (w_p - w_s) equals the parameter-free -pi x tau / g, and the
    stiffness implied by the torque returns P."""
    from dnabraid.analysis.hat_curve import (coexistence_slope, implied_plectoneme_stiffness,
                                             marko_two_phase)

    kT, F, A, C, P = 4.11, 1.0, 50.0, 100.0, 24.0
    g = F - math.sqrt(kT * F / A)
    cs = kT * 100.0 * (1.0 - 0.5 * math.sqrt(kT / 50.0))
    p = kT * P
    tau = math.sqrt(2.0 * g * p * cs / (cs - p))
    r = marko_two_phase(C, A, F, kT, P)
    assert r["torque"] == pytest.approx(tau, rel=1e-12)
    assert r["torque"] == pytest.approx(13.98, abs=0.01)
    x = 1.0 - 0.5 * math.sqrt(kT / (A * F))
    assert r["slope_nm_per_turn"] == pytest.approx(-2 * math.pi * x / (tau / p - tau / cs),
                                                   rel=1e-12)
    assert coexistence_slope(r["torque"], A, F, kT) == pytest.approx(r["slope_nm_per_turn"],
                                                                     rel=1e-12)
    assert implied_plectoneme_stiffness(r["torque"], C, A, F, kT) == pytest.approx(P, rel=1e-12)
    with pytest.raises(ValueError, match="P = "):
        marko_two_phase(C, A, F, kT, 90.0)
    with pytest.raises(ValueError, match="below kT / A"):
        coexistence_slope(10.0, A, 0.05, kT)


def test_hat_curve_recovers_two_phase_curve():
    """hat_curve on a synthetic summary drawn from the two-phase model (P = 22 nm, 1 um, 1 pN):
    twist torque 2 pi kT C_s n / L up to the coexistence torque, then flat; extension
    falling at Marko's slope after the onset. The analysis must return that slope, that
    plateau, P and the onset (exact data: tolerances are round-off); at a force below kT / A
    it leaves the two-phase quantities out instead of failing."""
    from dnabraid.analysis.hat_curve import hat_curve, marko_two_phase
    from dnabraid.units import KB_PN_NM

    kT = KB_PN_NM * 298.15
    C, A, F, L, P = 100.0, 50.0, 1.0, 1000.0, 22.0
    r = marko_two_phase(C, A, F, kT, P)
    ns = r["torque"] * L / (2 * math.pi * kT * r["C_s"])
    pts = []
    for n in [0, 2, 4, 8, 10, 12, 14]:
        buck = n > ns
        tq = r["torque"] if buck else 2 * math.pi * kT * r["C_s"] * n / L
        z = 850.0 + (r["slope_nm_per_turn"] * (n - ns) if buck else 0.0)
        pts.append({"turns": n, "twist_torque_pN_nm": {"mean": tq, "sem": 0.1},
                    "extension_nm": {"mean": z, "sem": 1.0},
                    "plectoneme_fraction": 1.0 if buck else 0.0})
    scene = {"length_nm": L, "twist_persistence_nm": C, "persistence_nm": A, "force_pN": F,
             "temperature_K": 298.15}
    _, res = hat_curve({"scene": scene, "points": pts})
    assert res["plateau_torque"] == pytest.approx(r["torque"], rel=1e-12)
    assert res["slope_sim"] == pytest.approx(r["slope_nm_per_turn"], rel=1e-9)
    assert res["slope_two_phase"] == pytest.approx(r["slope_nm_per_turn"], rel=1e-12)
    assert res["P_implied"] == pytest.approx(P, rel=1e-12)
    assert res["n_onset_two_phase"] == pytest.approx(ns, rel=1e-12)
    assert res["ceff_sim"] == pytest.approx(r["C_s"], rel=1e-9)
    _, low = hat_curve({"scene": dict(scene, force_pN=0.05), "points": pts})
    assert "slope_two_phase" not in low and "plateau_torque" in low
