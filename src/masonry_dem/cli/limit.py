"""``masonry-dem limit [CASE] [--associative | --non-associative] [--grid N] [--out DIR]``:
the collapse multiplier and mechanism of a case by limit analysis (one convex solve)."""

from __future__ import annotations

import argparse
import json
import logging
import time
from pathlib import Path

from masonry_dem.cli.options import (
    add_case,
    add_output,
    add_overwrite,
    positive_seconds,
    results_line,
)

log = logging.getLogger(__name__)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "limit",
        help="limit analysis of a case file: collapse multiplier, mechanism VTU/PNG, summary.json",
        description=(
            "Rigid-block limit analysis of a case file (default: the bundled wall). The "
            "associative multiplier with --dem-bound is an upper bound of the pushover's "
            "(the friction enlarged by kappa(alpha) so that the DEM's joints fit); the "
            "classical one is that bound for alpha = 1; the non-associative one (zero "
            "dilatancy) an estimate."
        ),
    )
    add_case(p)
    kind = p.add_mutually_exclusive_group()
    kind.add_argument(
        "--associative", dest="associative", action="store_true", default=None, help="(default)"
    )
    kind.add_argument("--non-associative", dest="associative", action="store_false")
    p.add_argument("--grid", type=int, default=None, help="contact points per interface side")
    p.add_argument("--backend", choices=("highs", "clarabel"), default=None)
    p.add_argument(
        "--dem-bound",
        action="store_true",
        help="enlarge the friction by kappa(alpha) (1.0655 for alpha 1.5): a theorem-backed "
        "upper bound of the pushover's multiplier (docs/limit_analysis.md)",
    )
    p.add_argument(
        "--time-limit",
        type=positive_seconds("--time-limit"),
        default=None,
        metavar="SECONDS",
        help="the analysis's wall-clock budget: every solver stops there, the run ends "
        "'failed' with no lambda (default 600; [analysis] time_limit in a case file)",
    )
    add_output(p, "results/limit", "the PNG of the mechanism")
    add_overwrite(p)
    p.set_defaults(func=limit_command)


def run_limit(case, out: Path, options: dict, render: bool = True, overwrite: bool = False) -> dict:
    """Run the limit analysis of a loaded case into ``out``, a folder this run claims as
    ``run`` does (refused if it holds another run, unless ``overwrite``); returns the
    summary."""
    from masonry_dem._signals import run_interruptible
    from masonry_dem.export.limit_results import write_limit_results
    from masonry_dem.export.results_folder import claim, record_stopped, write_summary
    from masonry_dem.solvers.limit_analysis import limit_analysis

    folder = claim(out, overwrite, {"case": case.source, "analysis": "limit"})
    try:
        t0 = time.perf_counter()
        try:
            result = run_interruptible(lambda: limit_analysis(case.model, **options))
        except BaseException as exc:  # a signal or an error: summary.json says so
            record_stopped(out, exc)
            raise
        summary = write_limit_results(
            out,
            case.model,
            result,
            case=case.source,
            wall_seconds=round(time.perf_counter() - t0, 4),
        )
        if render and result.status == "collapse":
            try:
                from masonry_dem.export.render import render_mechanism
            except ImportError as exc:  # rendering is optional for the analysis itself
                log.warning("no PNG: the render module is unavailable (%s)", exc)
            else:
                summary = write_summary(out, summary, {"mechanism_png": render_mechanism(out).name})
    finally:
        folder.release()
    return summary


def limit_command(args: argparse.Namespace) -> int:
    from masonry_dem.cases.casefile import load_case

    case = load_case(args.case)
    options = dict(case.limit_options or {})
    if args.associative is not None:
        options["associative"] = args.associative
    if args.grid is not None:
        options["grid"] = args.grid
    if args.backend is not None:
        options["backend"] = args.backend
    if args.time_limit is not None:
        options["time_limit"] = args.time_limit
    if args.dem_bound:
        from masonry_dem.solvers.limit_analysis import model_friction_scale

        options["friction_scale"] = model_friction_scale(case.model)
    out = Path(args.out)
    summary = run_limit(case, out, options, render=not args.no_render, overwrite=args.overwrite)
    print(
        json.dumps(
            {k: summary[k] for k in ("status", "lambda", "method", "bound", "seconds", "blocks")}
        )
    )
    print(f"{summary['status']}: {summary['reason']}")
    print(summary["bound_reason"])
    print(results_line(out))
    return exit_code(summary["status"])


def exit_code(status: str) -> int:
    """0 for an answer (a collapse, or none possible: the pushover's ``completed``), 1 for a
    limit analysis that failed."""
    return 0 if status in ("collapse", "no collapse") else 1
