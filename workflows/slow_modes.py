"""Slow modes of the tweezer scenes: integrated autocorrelation times, measured and predicted.

For tether, braid and plectoneme, at several sizes and forces, one long trajectory per case
(one replica, run serially in this process) gives the integrated autocorrelation time of

* the extension (every sample),
* the trap torque (every sample) and its slow part (the torque averaged over blocks longer
  than the trap's fast libration),
* the bead position x, y (the bead centre C for the braid, the attachment for tether and
  plectoneme; from the trajectory frames),
* the bead tilt (braid: the bead centre's offset from the attachment chord's midpoint,
  perpendicular to the chord, over the height h of C above the chord; plectoneme: the
  orientation arm's z-difference over its length),
* the catenation crossings (braid, n != 0: the mean height of the apparent crossings of the
  two strands seen along y, per frame),
* the writhe (plectoneme, per frame).

Every measured time is set beside the prediction of a linearised bead-spring model of the
same scene (the discrete chain under tension with bending, the exact bead frictions, the
bead's centre on its tilt spring F/h and the trap; dnabraid.analysis.slow_modes.linear_model,
which also holds the closed forms and the estimators used here), whose slowest
mode has the closed form tau_1 = zeta_l L^2 / (f q^2), q tan q = zeta_l L / zeta_end
(docs/slow_modes.md). The predictions for the default scenes, too slow to measure here, come
from the same model.

Conventions: tau = g Delta / 2, with g = 1 + 2 sum rho (the statistical inefficiency of
dnabraid.analysis.stats.integrated_autocorrelation_time, Sokal's window) and Delta the
sampling interval; tau equals the relaxation time of a single exponential and the integral
of the autocorrelation function. A run of length T holds T / (2 tau) independent samples.
The relative error of tau from one run is about sqrt(2 (2 M + 1) / N) (Sokal 1996, M the
window, N the samples): a run needs T >~ 50 tau for a usable estimate.

Beside tau, the first lag at which the autocorrelation falls below 1/e is given, measured
(error from four segments of the run) and predicted: it is far less noisy than tau in runs
of a few tens of tau, and tests the model's time scale directly.

The runs use timestep_safety = 0.9 (dt ~ 71 ps instead of the default 23.6 ps): relaxation
times in ns do not depend on the time step to first order in rate x dt (< 1e-3 for the slow
modes, 0.04 for the trap's libration), and the steps are reported at the default time step
(tau_ns / dt_default).

Usage: taskset -c 0 python workflows/slow_modes.py [--quick] [--cases id1,id2] [--scale s]
       [--keep DIR] [--reanalyse DIR] [--predict-only]
Writes workflows/results/slow_modes.md and .json after every case (about 16 min on one
free core for all cases). Results and formulas: docs/slow_modes.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import pathlib
import tempfile
import time
import warnings

import numpy as np

from dnabraid.analysis.slow_modes import (
    TORQUE_BLOCK,
    block_means,
    e_time_err,
    e_time_spectrum,
    linear_model,
    tau_of,
)
from dnabraid.scenes.braid import TOY_BRAID

HERE = pathlib.Path(__file__).resolve().parent
RESULTS = HERE / "results"
#: Time-step safety of the runs (the scenes' default is 0.3).
RUN_SAFETY = 0.9
#: pinned: the braid's default trap is K = 2000 since 2026-12-06; the braid cases and
#: predictions were set up and measured in the stiff trap of the time
STIFF_TRAP = {"trap_stiffness_pN_nm": 20000.0}


# ----------------------------------------------------------------------------- cases
@dataclasses.dataclass
class Case:
    id: str
    scene: str
    keys: dict
    steps: int               # sampling steps (at RUN_SAFETY)
    equilibration: int       # equilibration steps (at RUN_SAFETY)
    note: str = ""


CASES = [
    Case("tether-25nm-5pN", "tether", {"length_nm": 25.0, "force_pN": 5.0}, 1_000_000, 20_000),
    Case("tether-50nm-5pN", "tether", {"length_nm": 50.0, "force_pN": 5.0}, 1_000_000, 20_000),
    Case("tether-50nm-20pN", "tether", {"length_nm": 50.0, "force_pN": 20.0}, 400_000, 10_000),
    Case("braid-2x60nm-10pN-n0", "braid", {"length_nm": 60.0, "force_pN": 10.0,
                                           "turns": [0.0], **STIFF_TRAP}, 800_000, 100_000),
    Case("braid-2x60nm-10pN-n1", "braid", {"length_nm": 60.0, "force_pN": 10.0,
                                           "turns": [1.0], **STIFF_TRAP}, 800_000, 100_000),
    Case("plectoneme-50nm-5pN-n0", "plectoneme", {"length_nm": 50.0, "force_pN": 5.0,
                                                  "turns": [0.0]}, 400_000, 50_000),
    Case("plectoneme-100nm-1pN-n2", "plectoneme", {"length_nm": 100.0, "force_pN": 1.0,
                                                   "turns": [2.0]}, 400_000, 60_000,
         "the brief's size: its pivot mode (~40 us) is longer than this run (26 us)"),
    Case("tether-100nm-10pN", "tether", {"length_nm": 100.0, "force_pN": 10.0}, 800_000,
         20_000),
    Case("braid-2x60nm-20pN-n0", "braid", {"length_nm": 60.0, "force_pN": 20.0,
                                           "turns": [0.0], **STIFF_TRAP}, 800_000, 100_000),
]

#: Default scenes (and the brief's larger sizes), predicted only.
PREDICT_ONLY = [
    ("tether default (300 nm, 1 pN)", "tether", {}),
    ("tether 100 nm, 1 pN", "tether", {"length_nm": 100.0, "force_pN": 1.0}),
    ("tether 100 nm, 5 pN", "tether", {"length_nm": 100.0, "force_pN": 5.0}),
    ("tether 50 nm, 1 pN", "tether", {"length_nm": 50.0, "force_pN": 1.0}),
    ("braid old default (2 x 200 nm, 2 pN), n = 0", "braid",
     {"length_nm": 200.0, "force_pN": 2.0, "timestep_safety": 0.3, "turns": [0.0],
      **STIFF_TRAP}),
    ("braid 2 x 100 nm, 2 pN, n = 0", "braid", {"length_nm": 100.0, "force_pN": 2.0,
                                                "timestep_safety": 0.3, "turns": [0.0],
                                                **STIFF_TRAP}),
    ("braid 2 x 60 nm, 2 pN, n = 0", "braid", {"length_nm": 60.0, "force_pN": 2.0,
                                               "timestep_safety": 0.3, "turns": [0.0],
                                               **STIFF_TRAP}),
    # pinned: the row is the default of 2026-12-01 to 2026-12-05 (TOY_BRAID), not today's
    ("braid toy default (2 x 60 nm, 20 pN), n = 0", "braid", {**TOY_BRAID, "turns": [0.0]}),
    ("plectoneme default (300 nm, 1 pN), n = 0", "plectoneme", {"turns": [0.0]}),
    ("plectoneme 100 nm, 1 pN, n = 0", "plectoneme", {"length_nm": 100.0, "turns": [0.0]}),
]


# --------------------------------------------------------------------------- measuring
def crossing_heights(pa: np.ndarray, pb: np.ndarray) -> tuple[float, int]:
    """Apparent crossings of two strands seen along y: heights where x_A - x_B changes sign
    (strands sampled at common heights). Returns (mean height of the crossings, count)."""
    z = np.linspace(max(pa[1, 2], pb[1, 2]), min(pa[-2, 2], pb[-2, 2]), 200)
    ia, ib = np.argsort(pa[:, 2]), np.argsort(pb[:, 2])
    dx = np.interp(z, pa[ia, 2], pa[ia, 0]) - np.interp(z, pb[ib, 2], pb[ib, 0])
    k = np.nonzero(np.sign(dx[:-1]) * np.sign(dx[1:]) < 0)[0]
    if k.size == 0:
        return math.nan, 0
    zc = z[k] - dx[k] * (z[k + 1] - z[k]) / (dx[k + 1] - dx[k])
    return float(np.mean(zc)), int(k.size)


def read_frames(out: str, model) -> dict:
    """Per-frame series from the trajectory: bead x, y; tilt; crossing heights."""
    import MDAnalysis as mda

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        u = mda.Universe(str(pathlib.Path(out) / "topology.pdb"),
                         str(pathlib.Path(out) / "trajectory.dcd"))
        att = model.attachments
        center = model.bead_center
        m = getattr(model, "bead_orientation", None)
        ser: dict = {k: [] for k in ("bead_x", "bead_y", "tilt", "crossing_z", "n_crossings")}
        for ts in u.trajectory:
            p = ts.positions.astype(float) / 10.0
            if center is not None:  # braid: the bead centre; tilt about the chord
                mid = p[att].mean(axis=0)
                chord = p[att[1]] - p[att[0]]
                perp = np.array([-chord[1], chord[0], 0.0])
                perp /= np.linalg.norm(perp)
                h = p[center, 2] - mid[2]
                ser["bead_x"].append(p[center, 0])
                ser["bead_y"].append(p[center, 1])
                ser["tilt"].append(float(np.dot(p[center] - mid, perp) / h))
                zc, nc = crossing_heights(p[model.chains[0]], p[model.chains[1]])
                ser["crossing_z"].append(zc)
                ser["n_crossings"].append(nc)
            else:
                ser["bead_x"].append(p[att[0], 0])
                ser["bead_y"].append(p[att[0], 1])
                if m is not None:
                    arm = p[m] - p[att[0]]
                    ser["tilt"].append(float(arm[2] / np.linalg.norm(arm)))
    return {k: np.asarray(v, float) for k, v in ser.items() if len(v)}


def read_csv(path) -> dict:
    from dnabraid.run.reporters import read_csv as _read

    return _read(path)


def case_scene(case: Case, quick: bool, scale: float):
    """The scene of a case (run keys) and its sampling settings."""
    from dnabraid.scenes import make_scene

    steps = case.steps if not quick else max(20_000, case.steps // 25)
    steps = int(round(steps * scale / 1000)) * 1000 if not quick else steps
    eq = case.equilibration if not quick else case.equilibration // 10
    fi = max(100, int(round(steps / 4000 / 100)) * 100)
    # mc_moves pinned: the scenes' defaults have moves (tether, plectoneme since 2026-12-02,
    # braid since 2026-12-06); these are Brownian dynamics' (physical) relaxation times
    keys = dict(case.keys, steps=steps, equilibration_steps=eq, report_interval=100,
                frame_interval=fi, replicas=1, workers=1, protocol="ramp",
                timestep_safety=RUN_SAFETY, seed=3, mc_moves=0)
    return make_scene(case.scene, keys)


def run_case(case: Case, quick: bool, scale: float, keep: str = "") -> dict:
    from tqdm import tqdm

    scene = case_scene(case, quick, scale)
    model = scene.build()
    dt = model.timestep.time_step_ns
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()

        def bar(total):
            return tqdm(total=total, unit="step", unit_scale=True, desc=case.id,
                        mininterval=15.0)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene.run(tmp, threads=1, progress_factory=bar)
        wall = time.perf_counter() - t0
        obs = read_csv(pathlib.Path(tmp) / "observables.csv")
        frames = read_frames(tmp, model)
        fr = read_csv(pathlib.Path(tmp) / "frames.csv")
    if keep:  # the raw series, for re-analysis without rerunning
        pathlib.Path(keep).mkdir(parents=True, exist_ok=True)
        np.savez_compressed(pathlib.Path(keep) / f"{case.id}.npz", wall_s=wall,
                            sample_dt_ns=100 * dt, frame_dt_ns=scene.frame_interval * dt,
                            **{f"obs_{k}": v for k, v in obs.items()},
                            **{f"frame_{k}": v for k, v in frames.items()},
                            **{f"fr_{k}": v for k, v in fr.items()})
    return analyse(case, scene, dt, obs, frames, fr, wall)


def reanalyse(case: Case, path, quick: bool, scale: float) -> dict:
    """The row of a case from its saved series (``--keep``)."""
    z = np.load(path)
    pick = {p: {k[len(p):]: z[k] for k in z.files if k.startswith(p)}
            for p in ("obs_", "frame_", "fr_")}
    scene = case_scene(case, quick, scale)
    dt = float(z["sample_dt_ns"]) / 100
    return analyse(case, scene, dt, pick["obs_"], pick["frame_"], pick["fr_"],
                   float(z["wall_s"]) if "wall_s" in z.files else float("nan"))


def analyse(case: Case, scene, dt, obs, frames, fr, wall) -> dict:
    from dnabraid.scenes import make_scene

    default_dt_ns = make_scene(case.scene, dict(case.keys)).build().timestep.time_step_ns
    steps, fi = scene.steps, scene.frame_interval
    sdt = 100 * dt
    fdt = fi * dt
    pred = linear_model(scene, sdt, fdt)
    # a tether starts from an exact equilibrium draw: nothing to cut; the others are cut
    # where Chodera's rule says
    cut = scene.name != "tether"
    meas: dict = {"extension": tau_of(obs["extension_nm"], sdt, cut=cut)}
    if "torque_pN_nm" in obs:
        meas["torque"] = tau_of(obs["torque_pN_nm"], sdt, cut=cut)
        tb = block_means(obs["torque_pN_nm"], TORQUE_BLOCK)
        r = tau_of(tb, TORQUE_BLOCK * sdt, cut=False)
        if r["tau_ns"] is not None:
            r["slow_fraction"] = float(np.var(tb) / np.var(obs["torque_pN_nm"]))
        meas["torque_slow"] = r
    if "twist_torque_pN_nm" in obs:
        meas["twist_torque"] = tau_of(obs["twist_torque_pN_nm"], sdt, cut=cut)
    for k in ("bead_x", "bead_y", "tilt", "crossing_z"):
        if k in frames and np.isfinite(frames[k]).mean() > 0.9:
            meas[k] = tau_of(frames[k], fdt, cut=cut)
    if "writhe" in fr:
        meas["writhe"] = tau_of(fr["writhe"], fdt, cut=cut)
    spectra = pred.pop("_spectra", {})
    columns = {"extension": obs.get("extension_nm"), "torque": obs.get("torque_pN_nm"),
               "twist_torque": obs.get("twist_torque_pN_nm"), "writhe": fr.get("writhe")}
    columns.update({k: frames[k] for k in ("bead_x", "bead_y", "tilt", "crossing_z")
                    if k in frames})
    for k, m in meas.items():
        src = columns.get(k)
        if m.get("tau_ns") is None or src is None:
            continue
        src = np.asarray(src, float)
        src = src[np.isfinite(src)]
        step = sdt if k in ("extension", "torque", "twist_torque") else fdt
        m["e_time_ns"], m["e_time_err_ns"] = e_time_err(src[m["cut"]:], step)
        if k in spectra:
            m["e_time_pred_ns"] = e_time_spectrum(spectra[k])
    row = {"id": case.id, "scene": case.scene, "keys": case.keys, "steps": steps,
           "equilibration_steps": scene.equilibration_steps, "frame_interval": fi,
           "dt_ns": dt, "default_dt_ns": default_dt_ns, "wall_s": wall,
           "run_ns": steps * dt, "predicted": pred, "measured": meas, "note": case.note}
    if "n_crossings" in frames:
        row["mean_crossings"] = float(np.mean(frames["n_crossings"]))
    return row


# ----------------------------------------------------------------------------- output
OBS = [("extension", "extension", "extension"), ("torque", "trap torque", "torque"),
       ("torque_slow", "torque, 71 ns blocks", "torque_slow"),
       ("twist_torque", "twist torque", None),  # Tw = Lk - Wr: follows the writhe
       ("bead_x", "bead x", "bead_x"), ("bead_y", "bead y", "bead_y"),
       ("tilt", "bead tilt", "tilt"), ("crossing_z", "crossing height", None),
       ("writhe", "writhe", None)]


def _pred_for(row, key):
    p = row["predicted"]
    if key is None:
        return None
    if key in ("bead_x", "bead_y") and key not in p:
        return p.get("bead_xy")
    return p.get(key)


def fmt(x, nd=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{nd}g}"


def _pm(v, e):
    if v is None:
        return "-"
    return f"{v:.3g} +- {e:.2g}" if e is not None else f"{v:.3g}"


def table(rows) -> str:
    out = ["| case | observable | tau (ns) | +- | tau (steps at default dt) | run / tau | "
           "predicted tau (ns) | run / predicted tau | measured / predicted | "
           "1/e time (ns) | predicted 1/e time (ns) |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        for key, label, pkey in OBS:
            m = row["measured"].get(key)
            if not m or m.get("tau_ns") is None:
                continue
            tp = _pred_for(row, pkey)
            tau = m["tau_ns"]
            ratio = tau / tp if tp else None
            run_pred = f"{m['run_over_tau'] * tau / tp:.0f}" if tp else "-"
            extra = ""
            if key == "torque_slow" and "slow_fraction" in m:
                extra = (f" (var. kept {m['slow_fraction']:.2g}, predicted "
                         f"{fmt(row['predicted'].get('torque_slow_fraction'), 2)})")
            out.append(f"| {row['id']} | {label}{extra} | {fmt(tau)} | {m['rel_err'] * tau:.2g} | "
                       f"{tau / row['default_dt_ns']:.3g} | {m['run_over_tau']:.0f} | {fmt(tp)} | "
                       f"{run_pred} | "
                       f"{fmt(ratio, 2)} | {_pm(m.get('e_time_ns'), m.get('e_time_err_ns'))} | "
                       f"{fmt(m.get('e_time_pred_ns'))} |")
    return "\n".join(out)


def case_lines(rows) -> str:
    out = ["| case | steps (dt) | run (us) | wall (s) | tau_1 model (ns) | tau_1 formula (ns) "
           "| notes |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        p = r["predicted"]
        note = r.get("note", "")
        if "mean_crossings" in r:
            note = (note + "; " if note else "") + f"{r['mean_crossings']:.2f} crossings/frame"
        out.append(f"| {r['id']} | {r['steps']:,} ({r['dt_ns'] * 1e3:.1f} ps) | "
                   f"{r['run_ns'] / 1e3:.1f} | {r['wall_s']:.0f} | {fmt(p['tau1_ns'])} | "
                   f"{fmt(p['tau1_formula_ns'])} | {note} |")
    return "\n".join(out)


def predictions() -> list[dict]:
    from dnabraid.scenes import make_scene

    rows = []
    for label, name, keys in PREDICT_ONLY:
        s = make_scene(name, keys)
        dt = s.build().timestep.time_step_ns
        p = linear_model(s, 100 * dt, s.frame_interval * dt)
        p.pop("_spectra", None)
        worst = max(p["extension"], p.get("bead_xy", 0.0))
        rows.append({"label": label, "dt_ns": dt, "steps_default": s.steps,
                     "equilibration_default": s.equilibration_steps, "predicted": p,
                     "tau_worst_ns": worst,
                     "steps_needed": int(50 * p["extension"] / dt + 5 * p["tau1_ns"] / dt)})
    return rows


def prediction_table(prow) -> str:
    out = ["| scene | dt (ps) | tau_1 model (formula) (ns) | tau extension model (formula) (ns) | "
           "tau bead x,y model (formula) (ns) | tau tilt (ns) | steps/replica needed "
           "(50 tau_ext + 5 tau_1) | default steps (+ eq.) |", "|---|---|---|---|---|---|---|---|"]
    for r in prow:
        p = r["predicted"]
        out.append(f"| {r['label']} | {r['dt_ns'] * 1e3:.1f} | {fmt(p['tau1_ns'])} "
                   f"({fmt(p['tau1_formula_ns'])}) | {fmt(p['extension'])} "
                   f"({fmt(p['extension_formula_ns'])}) | {fmt(p.get('bead_xy'))} "
                   f"({fmt(p['bead_xy_formula_ns'])}) | {fmt(p.get('tilt'))} | "
                   f"{r['steps_needed']:.3g} | {r['steps_default']:,} (+{r['equilibration_default']:,}) |")
    return "\n".join(out)


def write(rows, prow, total_wall, quick):
    RESULTS.mkdir(exist_ok=True)
    stem = "slow_modes_quick" if quick else "slow_modes"
    md = [f"# slow modes, {time.strftime('%Y-%m-%d %H:%M')}"
          + (" (QUICK: runs too short to trust)" if quick else ""), "",
          "tau = g Delta / 2 (g = 1 + 2 sum rho, Sokal window; Delta the sampling interval); "
          "+- = Sokal's error sqrt(2 (2M+1)/N) tau; run / tau = sampled time over tau (>= 50 "
          "for a usable estimate); steps at the scene's default time step (safety 0.3); runs "
          f"at timestep_safety {RUN_SAFETY}. Predicted: the linearised bead-spring model "
          "(dnabraid.analysis.slow_modes.linear_model), about the straight n = 0 state.", "",
          "## measured", "", table(rows), "", "## cases", "", case_lines(rows), "",
          "## predicted for the default scenes", "", prediction_table(prow), "",
          f"total wall time {total_wall:.0f} s (one core, serial)", ""]
    (RESULTS / f"{stem}.md").write_text("\n".join(md))

    def clean(o):
        if isinstance(o, dict):
            return {k: clean(v) for k, v in o.items()}
        if isinstance(o, (list, tuple)):
            return [clean(v) for v in o]
        if isinstance(o, (np.floating, np.integer)):
            return o.item()
        if isinstance(o, np.ndarray):
            return None
        if isinstance(o, float) and not math.isfinite(o):
            return None
        return o

    (RESULTS / f"{stem}.json").write_text(json.dumps(
        {"cases": clean(rows), "predictions": clean(prow), "total_wall_s": total_wall,
         "run_safety": RUN_SAFETY}, indent=1))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short runs (a smoke test)")
    ap.add_argument("--cases", default="", help="comma-separated case ids (default: all)")
    ap.add_argument("--scale", type=float, default=1.0, help="multiply every run's steps")
    ap.add_argument("--keep", default="", help="directory to save each case's raw series "
                    "(npz)")
    ap.add_argument("--reanalyse", default="", help="rebuild the rows of the cases saved "
                    "in this directory (--keep) without running them; other rows are kept")
    ap.add_argument("--predict-only", action="store_true",
                    help="only print the model predictions for the default scenes")
    ap.add_argument("--append", action="store_true",
                    help="keep the cases already in the results JSON (rerun the named ones)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    prow = predictions()
    print(prediction_table(prow), flush=True)
    stem = "slow_modes_quick" if args.quick else "slow_modes"
    rows: list = []
    prev_wall = 0.0
    if (args.append or args.reanalyse) and (RESULTS / f"{stem}.json").exists():
        old = json.loads((RESULTS / f"{stem}.json").read_text())
        rows = old["cases"]
        prev_wall = old.get("total_wall_s", 0.0)
    if args.predict_only:  # printed above; the results files are left as they are
        return
    if args.reanalyse:
        for case in CASES:
            f = pathlib.Path(args.reanalyse) / f"{case.id}.npz"
            if f.exists():
                row = reanalyse(case, f, args.quick, args.scale)
                old = [r for r in rows if r["id"] == case.id]
                if old and not math.isfinite(row["wall_s"]):
                    row["wall_s"] = old[0]["wall_s"]
                rows = [r for r in rows if r["id"] != case.id] + [row]
        rows.sort(key=lambda r: [c.id for c in CASES].index(r["id"]))
        write(rows, prow, prev_wall, args.quick)
        print(table(rows))
        return
    want = [c for c in args.cases.split(",") if c]
    todo = [c for c in CASES if not want or c.id in want]
    for case in todo:
        row = run_case(case, args.quick, args.scale, args.keep)
        rows = [r for r in rows if r["id"] != case.id] + [row]
        rows.sort(key=lambda r: [c.id for c in CASES].index(r["id"]))
        write(rows, prow, prev_wall + time.perf_counter() - t0, args.quick)
        print(f"\n{case.id}: {row['wall_s']:.0f} s", flush=True)
        print(table([row]), flush=True)
    print(f"total wall {prev_wall + time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
