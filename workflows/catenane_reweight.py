"""Catenane handedness from alpha = 0 runs reweighted to every alpha, with hybrid BD/MC.

The chiral energy is linear in alpha, U_chiral = alpha W(x) (W the contact integral of
tan(eta/2), the numpy twin with alpha = 1), so one ensemble at alpha_0 gives every other
alpha exactly by reweighting (Zwanzig 1954; Shirts & Chodera 2008 for the multistate form):

    <A>_alpha = <A exp(-(alpha - alpha_0) W / kT)>_alpha_0 / <exp(-(alpha - alpha_0) W / kT)>_alpha_0

as long as the weights do not collapse (their effective sample size is reported per alpha).
Runs (scene ``catenane`` with its Metropolis rigid-body and crankshaft moves,
dnabraid.moves; 8 replicas, half started apart, half in contact):

1. ``a0_dlk-1``: alpha = 0, Delta Lk_i = -1, Lk_12 = +1;
2. ``a0_dlk+1``: its mirror image, alpha = 0, Delta Lk_i = +1, Lk_12 = -1;
3. ``a+6_dlk-1``: alpha = +6 pN, Delta Lk_i = -1, run directly (checks the reweighting);
4. ``ring``: one 144-nm ring at the same time step, <dTw_half^2> against L / (4 pi^2 C)
   (exact for the model: the moves and the step leave it unbiased).

From the frames (``frame_interval`` steps apart) it computes W, the contact length, the
contact-averaged folded braid angle eta and both writhes, reweights them to a grid of alpha,
and reports per alpha: <eta>_contact, the contact fraction, <Wr_i>, the weights' ESS; the
handedness switch alpha* where <eta>_contact(alpha) = 0 (errors from the scatter of the
replicas' own reweighted curves, each replica an independent run); the exact symmetry
<Wr>(alpha, -1) = -<Wr>(-alpha, +1) from the two independent ensembles; and the direct run
against the reweighted prediction. Writes workflows/results/catenane_reweight.md/.json/.png.

Usage: python workflows/catenane_reweight.py [--steps 400000] [--replicas 8]
       [--out runs/catenane_rw] [--runs-only]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from catenane import run_point  # noqa: E402

from dnabraid.scenes import make_scene  # noqa: E402

POINTS = {
    "a0_dlk-1": {"alpha": 0.0, "delta_lk": -1, "link": 1},
    "a0_dlk+1": {"alpha": 0.0, "delta_lk": 1, "link": -1},
    "a+6_dlk-1": {"alpha": 6.0, "delta_lk": -1, "link": 1},
}


def common_keys(args) -> dict:
    return {"steps": args.steps, "equilibration_steps": args.equilibration,
            "replicas": args.replicas, "integrator": "lm", "start": "mixed",
            "timestep_safety": args.safety, "frame_interval": args.frame_interval,
            "report_interval": 100}


def run_all(args, log) -> dict:
    out = {}
    c = common_keys(args)
    for tag, k in POINTS.items():
        keys = {**c, **k}
        if tag.startswith("a+6"):
            keys["steps"] = args.direct_steps
        out[tag] = run_point(tag, keys, args.out, log)
        print(f"{tag}: done ({out[tag]['wall_time_s']:.0f} s)", flush=True)
    ring = {**c, "rings": 1, "steps": args.ring_steps, "replicas": 4, "start": "apart"}
    out["ring"] = run_point("ring", ring, args.out, log)
    print(f"ring: done ({out['ring']['wall_time_s']:.0f} s)", flush=True)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=400_000)
    ap.add_argument("--direct-steps", type=int, default=250_000)
    ap.add_argument("--ring-steps", type=int, default=100_000)
    ap.add_argument("--equilibration", type=int, default=40_000)
    ap.add_argument("--replicas", type=int, default=8)
    ap.add_argument("--safety", type=float, default=0.6)
    ap.add_argument("--frame-interval", type=int, default=1000)
    ap.add_argument("--out", default="runs/catenane_rw")
    ap.add_argument("--runs-only", action="store_true")
    ap.add_argument("--table", default=str(HERE / "results" / "catenane_reweight.md"))
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    with open(os.path.join(args.out, "reports.md"), "a") as log:
        runs = run_all(args, log)
    if args.runs_only:
        return 0
    from analysis_catenane_reweight import write_report  # noqa: E402

    write_report(runs, args, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
