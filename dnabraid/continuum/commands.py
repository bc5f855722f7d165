"""``dnabraid continuum ply|knot|overhand|tweezer|closed``: the continuum sub-commands.

Each problem lives in its own module (``ply``, ``knot_braid``, ``overhand``, ``tweezer``,
``closed_ply``) that provides ``cli_add_arguments(parser)`` and ``cli_run(args) -> dict``; this
module only dispatches. Modules are imported lazily so ``dnabraid --help`` stays fast.
"""

from __future__ import annotations

import argparse
import importlib

#: problem name -> (module, one-line help)
PROBLEMS = {
    "ply": ("ply", "two-ply in hard contact: uniform plies and the ply with ends "
                   "(van der Heijden, elastic braids, slides 15-19)"),
    "knot": ("knot_braid", "braid of an open elastic knot: the difference problem, w_c, sigma "
                     "(Audoly et al. 2007, Eqs. 5-9)"),
    "overhand": ("overhand", "long overhand knots: helical braid, loop elastica g, master "
                             "curve (Jawed et al. 2015)"),
    "tweezer": ("tweezer", "two molecules braided in magnetic tweezers: z(n), torque(n)"),
    "closed": ("closed_ply", "closed two-ply (torus links and knots): uniform, axis-curvature "
                         "correction, relaxed equilibrium (van der Heijden, elastic braids, slides 19-23)"),
}


def problem_module(name: str):
    """Import ``dnabraid.continuum.<module>`` of problem ``name``."""
    if name not in PROBLEMS:
        raise ValueError(f"unknown continuum problem {name!r}; choose one of: "
                         + ", ".join(PROBLEMS))
    return importlib.import_module(f"dnabraid.continuum.{PROBLEMS[name][0]}")


def add_subparsers(parser: argparse.ArgumentParser) -> None:
    """Add one sub-command per problem to ``parser`` (the ``continuum`` sub-command)."""
    sub = parser.add_subparsers(dest="problem", required=True, metavar="PROBLEM")
    for name, (_, help_) in PROBLEMS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        try:
            problem_module(name).cli_add_arguments(p)
        except ImportError as exc:  # pragma: no cover - a module missing from this install
            p.set_defaults(_import_error=str(exc))
        p.add_argument("--json", action="store_true", help="print the result as JSON")


def run(args) -> dict:
    """Run the problem named by ``args.problem``; a JSON-serialisable dict."""
    if getattr(args, "_import_error", None):
        raise ValueError(f"continuum problem {args.problem!r} is unavailable: "
                         f"{args._import_error}")
    return problem_module(args.problem).cli_run(args)
