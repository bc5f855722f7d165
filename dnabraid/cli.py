"""The ``dnabraid`` command.

    dnabraid run [SCENE | SCENE.toml] [--set KEY=VALUE]... [--out DIR] [--platform NAME] [--seed N]
    dnabraid scenes
    dnabraid sweep SPEC.toml [--workers N] [--scheduler ADDRESS] [--out DIR]
    dnabraid continuum ply|knot|overhand|tweezer|closed [options] [--json]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys

from . import scenes as scn
from .errors import UserError
from .progress import progress_bar
from .run.contract import ThermalContract
from .run.engine import SimulationBlowUp
from .run.workers import pin_to_core, usable_cores

#: Errors that are the user's input, printed without a traceback (anything else is a bug).
USER_ERRORS = (UserError, FileNotFoundError)


def _parse_sets(items) -> dict:
    out = {}
    for it in items or []:
        if "=" not in it:
            raise scn.SceneError(f"--set expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        out[k.strip()] = scn.parse_value(v)
    return out


def cmd_scenes(args) -> int:
    for name, cls in scn.SCENES.items():
        print(f"{name}: {cls.help}")
        for k, info in sorted(cls.keys().items()):
            val = info.default
            if isinstance(val, tuple):
                val = "[" + ",".join(f"{x:g}" for x in val) + "]"
            unit = f"[{info.unit}]" if info.unit else ""
            print(f"    {k:<24} = {val!s:<14} {unit:<14} {info.help}")
        print()
    return 0


def cmd_run(args) -> int:
    overrides = _parse_sets(args.set)
    if args.seed is not None:
        overrides["seed"] = args.seed
    s = scn.make_scene(args.scene, overrides)
    out = args.out or os.path.join("runs", s.name)
    threads = args.threads
    # Replicas run in processes that pin themselves to a core each; pin this process only
    # when everything runs in it (one worker), and then give OpenMM one thread.
    parallel = isinstance(s, ThermalContract) and min(
        s.workers or len(usable_cores()), s.replicas) > 1
    if args.platform == "CPU" and not args.no_pin and threads in (None, 1) and not parallel:
        pin_to_core(0)
        threads = 1

    def bar(total):
        return progress_bar(total, unit="step", desc=s.name, disable=args.quiet)

    print(f"dnabraid run: scene '{s.name}' -> {out}", file=sys.stderr)
    summary = s.run(out, platform=args.platform, threads=threads, progress_factory=bar)
    s.report(summary, out, sys.stdout)
    return 0


def run_sweep_verbose(spec, *, workers=None, scheduler=None, platform="CPU", quiet=False):
    """Run a validated sweep with a progress bar over points and print its table.

    Returns the :class:`dnabraid.sweep.SweepResult` (also used by workflows/*.py).
    """
    from . import sweep as swp

    print(f"dnabraid sweep: {len(spec.points)} points of scene '{spec.points[0].scene.name}' "
          f"-> {spec.out}" + (f" on Dask scheduler {scheduler}" if scheduler else ""),
          file=sys.stderr)
    bar = progress_bar(len(spec.points), unit="point", desc="sweep", disable=quiet)

    def progress(rec):
        bar.update(1)
        if rec["status"] == "failed":
            bar.write(f"point {rec['name']} failed: {rec['error']['type']}: "
                      f"{rec['error']['message']}", file=sys.stderr)

    try:
        res = swp.run_sweep(spec, workers=workers, scheduler=scheduler, platform=platform,
                            progress=progress)
    finally:
        bar.close()
    print(swp.format_table(res.rows, list(spec.grid)))
    print(f"wall time {res.wall_time_s:.1f} s; table {res.table}"
          + (f", figure {res.figure}" if res.figure else ""))
    if res.failed:
        print(f"{len(res.failed)} of {len(spec.points)} points failed (errors in "
              f"{os.path.join(res.out, swp.STATUS_FILE)}); rerun to retry them", file=sys.stderr)
    return res


def cmd_sweep(args) -> int:
    from . import sweep as swp

    spec = swp.load_spec(args.spec, out=args.out)  # validates every point before any run
    try:
        res = run_sweep_verbose(spec, workers=args.workers, scheduler=args.scheduler,
                                platform=args.platform, quiet=args.quiet)
    except ConnectionError as exc:
        print(f"dnabraid: error: {exc}", file=sys.stderr)
        return 2
    return 1 if res.failed else 0


def cmd_continuum(args) -> int:
    from .continuum import commands as ccli

    result = ccli.run(args)
    if args.json:
        print(json.dumps(result, indent=2, default=float))
    else:
        for k, v in result.items():
            print(f"{k:>28}: {v}")
    return 0 if result.get("success", True) else 1


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="dnabraid", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command")
    r = sub.add_parser("run", help="simulate a scene (default: braid)")
    r.add_argument("scene", nargs="?", default="braid", help="built-in scene name or SCENE.toml")
    r.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a scene key (see `dnabraid scenes`); repeatable")
    r.add_argument("--out", help="run directory (default runs/SCENE); rerun to resume")
    r.add_argument("--platform", default="CPU", help="OpenMM platform (CPU, Reference, CUDA...)")
    r.add_argument("--threads", type=int, default=None, help="CPU platform threads")
    r.add_argument("--no-pin", action="store_true", help="do not pin the process to one core")
    r.add_argument("--seed", type=int, default=None, help="random seed")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_run)
    w = sub.add_parser("sweep", help="run a scene over a grid of key values (SPEC.toml)",
                       description="Run every point of a sweep spec (TOML: scene, [fixed], "
                       "[grid]); finished points are skipped, interrupted ones resume.")
    w.add_argument("spec", help="sweep spec (TOML)")
    w.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: usable cores)")
    w.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on a Dask cluster (needs the 'distributed' extra)")
    w.add_argument("--out", default=None, help="sweep directory (default: the spec's out)")
    w.add_argument("--platform", default="CPU", help="OpenMM platform of every point")
    w.add_argument("--quiet", action="store_true", help="no progress bar")
    w.set_defaults(func=cmd_sweep)
    s = sub.add_parser("scenes", help="list built-in scenes and their keys")
    s.set_defaults(func=cmd_scenes)
    try:
        from .continuum import commands as ccli

        c = sub.add_parser("continuum", help="rod-theory equilibria (ply, knot, overhand, tweezer, closed)")
        ccli.add_subparsers(c)
        c.set_defaults(func=cmd_continuum)
    except ImportError:  # pragma: no cover - continuum CLI not available
        pass
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        args = parser.parse_args(["run"] + (argv or []))
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        return args.func(args)
    except USER_ERRORS as exc:
        print(f"dnabraid: error: {exc}", file=sys.stderr)
        return 2
    except SimulationBlowUp as exc:
        # a run that stopped on a blow-up or a broken invariant: the message names the step,
        # the term, the saved state and what to change; finished turn values stay on disk
        print(f"dnabraid: simulation stopped: {exc}\nTurn values finished before "
              "it are kept in the run directory.", file=sys.stderr)
        return 3
    except BrokenPipeError:  # output piped into `head` and the like: not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the interpreter's flush
        return 0
    except KeyboardInterrupt:
        print("dnabraid: interrupted; finished turn values are checkpointed, rerun the same "
              "command to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
