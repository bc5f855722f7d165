"""The trap torque against the strands' torque on the top and their combinations.

Two estimators of the torque at a point have the same mean exactly: the trap's,
-K sin(2 pi (bead - trap)) (``torque_pN_nm``), and the torque that every other term exerts
on the top, dU_rest/d theta for a rigid turn of the bead centre and attachments about the
vertical (``torque_strands_pN_nm``, :class:`dnabraid.observables.StrandTorque`): a turn of a
subset of particles is volume preserving, so <dU/d theta> = 0 for the total energy.
Their difference is a control variate of mean zero; w X + (1 - w) Y is unbiased for any w.
This script runs a braid (or reads a finished run with ``--run DIR``) and prints, per
point, mean +- SEM (replica scatter, Student t, as the summary) of the trap torque, the
strands' torque and the combination with the w on a grid of 0.05 that gives the smallest
SEM (chosen on the same data: a slight optimism, stated in the table's header), and the
SEM ratio to the plain trap torque.

Usage: python workflows/torque_estimators.py [--run DIR] [--set key=value ...]
       [--out workflows/results/torque_estimators.md]
"""

from __future__ import annotations

import argparse
import datetime
import glob
import os
import pathlib
import tempfile

import numpy as np

from dnabraid.run.summary import summarise
from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent
RULE = {}


def _series(run_dir: str) -> dict:
    """point label -> list over replicas of (trap, strands) sample arrays."""
    out: dict = {}
    for f in sorted(glob.glob(os.path.join(run_dir, "replicas", "r*", "points", "*",
                                           "samples.csv"))):
        d = np.genfromtxt(f, delimiter=",", names=True)
        if "torque_strands_pN_nm" not in d.dtype.names:
            raise SystemExit(f"{f}: no torque_strands_pN_nm column (a run with alpha = 0 and "
                             "bead contact has it)")
        out.setdefault(os.path.basename(os.path.dirname(f)), []).append(
            (np.asarray(d["torque_pN_nm"]), np.asarray(d["torque_strands_pN_nm"])))
    return out


def table(run_dir: str) -> list[str]:
    lines = [f"{'point':>20} {'trap pN nm':>16} {'strands pN nm':>16} {'best w':>6} "
             f"{'combined pN nm':>16} {'SEM ratio':>9} {'corr':>5}"]
    for label, reps in _series(run_dir).items():
        x = summarise([a for a, _ in reps], RULE)
        y = summarise([b for _, b in reps], RULE)
        best = None
        for w in np.round(np.arange(0.0, 1.0001, 0.05), 2):
            z = summarise([w * a + (1 - w) * b for a, b in reps], RULE)
            if best is None or z["sem"] < best[1]["sem"]:
                best = (w, z)
        corr = float(np.corrcoef(np.concatenate([a for a, _ in reps]),
                                 np.concatenate([b for _, b in reps]))[0, 1])
        w, z = best
        lines.append(f"{label:>20} {x['mean']:8.1f} +- {x['sem']:5.1f} {y['mean']:8.1f} +- "
                     f"{y['sem']:5.1f} {w:6.2f} {z['mean']:8.1f} +- {z['sem']:5.1f} "
                     f"{z['sem'] / x['sem']:9.2f} {corr:5.2f}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", help="a finished braid run directory (else one is run)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="braid keys of the run (TOML values), e.g. turns=[0,1]")
    ap.add_argument("--out", default=str(HERE / "results" / "torque_estimators.md"))
    args = ap.parse_args(argv)
    run_dir = args.run
    head = f"# torque estimators, {datetime.datetime.now():%Y-%m-%d %H:%M}; "
    if run_dir is None:
        import tomllib

        keys = {}
        for kv in args.set:
            k, v = kv.split("=", 1)
            keys[k] = tomllib.loads(f"v = {v}")["v"]
        run_dir = tempfile.mkdtemp(prefix="torque_est_")
        summ = make_scene("braid", keys).run(run_dir)
        head += f"braid {keys or '(defaults)'}, wall {summ['wall_time_s']:.0f} s"
    else:
        head += f"run {run_dir}"
    lines = [head, "# SEM: replica scatter (Student t) as in summary.json; best w chosen on "
             "the same data (slightly optimistic)", *table(run_dir)]
    print("\n".join(lines))
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "a") as fh:
        fh.write("\n".join(lines) + "\n\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
