"""The ``dnabraid`` command.

    dnabraid run [SCENE | SCENE.toml] [--set KEY=VALUE]... [--out DIR] [--platform NAME] [--seed N]
    dnabraid scenes
    dnabraid sweep SPEC.toml [--workers N] [--scheduler ADDRESS] [--out DIR]
    dnabraid continuum ply|knot|overhand|tweezer [options] [--json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import os
import sys

from . import scene as scn


def _parse_sets(items) -> dict:
    out = {}
    for it in items or []:
        if "=" not in it:
            raise scn.SceneError(f"--set expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        out[k.strip()] = scn.parse_value(v)
    return out


def cmd_scenes(args) -> int:
    defaults = scn.Scene()
    for name in scn.BUILTIN:
        print(f"{name}: {scn.SCENE_HELP[name]}")
        base = dataclasses.replace(defaults, scene=name, **{
            k: (tuple(v) if isinstance(v, list) else v) for k, v in scn.BUILTIN[name].items()})
        for key in sorted(scn.allowed_keys(name)):
            unit, help_ = scn.KEY_DOCS[key]
            val = getattr(base, key)
            if isinstance(val, tuple):
                val = "[" + ",".join(f"{x:g}" for x in val) + "]"
            print(f"    {key:<24} = {val!s:<14} {('[' + unit + ']') if unit else '':<14} {help_}")
        print()
    return 0


def _pin_to_one_core() -> None:
    """Pin the process to one core: OpenMM's CPU platform hands forces to a worker
    thread, and for small systems the hand-off costs more than the force (measured up to
    3-4x faster pinned; workflows/benchmark_engine.py)."""
    try:
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[0]})
    except (AttributeError, OSError):  # pragma: no cover - not on Linux
        pass


def cmd_run(args) -> int:
    from .runner import run_scene

    overrides = _parse_sets(args.set)
    if args.seed is not None:
        overrides["seed"] = args.seed
    s = scn.make_scene(args.scene, overrides)
    out = args.out or os.path.join("runs", s.scene)
    threads = args.threads
    if args.platform == "CPU" and not args.no_pin and (threads in (None, 1)):
        _pin_to_one_core()
        threads = 1

    def bar(total):
        from tqdm import tqdm

        return tqdm(total=total, unit="step", unit_scale=True, desc=f"{s.scene}",
                    disable=args.quiet, dynamic_ncols=True)

    print(f"dnabraid run: scene '{s.scene}' -> {out}", file=sys.stderr)
    summary = run_scene(s, out, platform=args.platform, threads=threads, progress_factory=bar)
    if s.scene == "knot":
        m, t = summary["measured"], summary["theory"]
        print(f"knot n = {summary['knot_n']}, eps = {summary['eps']:.3f}, {summary['beads']} beads, "
              f"{summary['newton_iterations']} Newton iterations, largest OpenMM force left "
              f"{summary['openmm_max_force_pN']:.2g} pN")
        print(f"{'':<24} {'bead model':>12} {'theory':>12}")
        print(f"{'loop radius (apex) nm':<24} {m['radius_apex_nm']:>12.2f} {t['radius_nm']:>12.2f}")
        print(f"{'shortening / 2 pi nm':<24} {m['radius_dL_nm']:>12.2f} {t['radius_nm']:>12.2f}")
        print(f"{'braid length nm':<24} {m['braid_length_nm']:>12.2f} {t['braid_length_nm']:>12.2f}")
        print(f"{'wave number 1/nm':<24} {m['wave_number_per_nm']:>12.4f} "
              f"{t['wave_number_per_nm']:>12.4f}")
        print(f"{'winding turns':<24} {m['winding_turns']:>12.3f} {t['winding_turns']:>12d}")
        for n in summary["notes"]:
            print(f"note: {n}")
        print(f"wall time {summary['wall_time_s']:.1f} s; results in {out}/")
        return 0
    print(f"time step {summary['time_step_ps']:.4g} ps: {summary['time_step_reason']}")
    for n in summary["notes"]:
        print(f"note: {n}")
    print(f"{'turns':>7} {'extension_nm':>20} {'torque_pN_nm':>20} {'catenation':>18}")

    def fmt(d, p=2):
        if d["mean"] is None:
            return "-"
        return f"{d['mean']:.{p}f} +- {d['sem']:.{p}f}"

    for pt in summary["points"]:
        print(f"{pt['turns']:>7g} {fmt(pt['extension_nm'], 1):>20} "
              f"{fmt(pt['torque_pN_nm'], 1):>20} {fmt(pt['catenation'], 3):>18}")
    print(f"wall time {summary['wall_time_s']:.1f} s on {summary['platform']}; results in {out}/")
    return 0


def run_sweep_verbose(spec, *, workers=None, scheduler=None, platform="CPU", quiet=False):
    """Run a validated sweep with a progress bar over points and print its table.

    Returns the :class:`dnabraid.sweep.SweepResult` (also used by workflows/*.py).
    """
    from tqdm import tqdm

    from . import sweep as swp

    print(f"dnabraid sweep: {len(spec.points)} points of scene '{spec.points[0].scene.scene}' "
          f"-> {spec.out}" + (f" on Dask scheduler {scheduler}" if scheduler else ""),
          file=sys.stderr)
    bar = tqdm(total=len(spec.points), unit="point", desc="sweep", disable=quiet,
               dynamic_ncols=True)

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
    from .continuum import cli as ccli

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
        from .continuum import cli as ccli

        c = sub.add_parser("continuum", help="rod-theory equilibria (ply, knot, overhand, tweezer)")
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
    except (scn.SceneError, FileNotFoundError, ValueError, ImportError) as exc:
        print(f"dnabraid: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into `head` and the like: not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the interpreter's flush
        return 0
    except KeyboardInterrupt:
        print("dnabraid: interrupted; finished turn values are checkpointed, rerun the same "
              "command to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
