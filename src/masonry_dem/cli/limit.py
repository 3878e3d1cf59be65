"""``masonry-dem limit [CASE] [--associative | --non-associative] [--start elastic|associative]
[--grid N] [--out DIR]``:
the collapse multiplier and mechanism of a case by limit analysis (one convex solve)."""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from masonry_dem.cli.options import (
    EventLine,
    add_case,
    add_max_memory,
    add_output,
    add_overwrite,
    positive_seconds,
    results_line,
)

if TYPE_CHECKING:
    from masonry_dem.solvers.limit_analysis import LimitProgress
    from masonry_dem.solvers.resources import LimitEstimate

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
    p.add_argument(
        "--start",
        choices=("elastic", "associative"),
        default=None,
        help="with --non-associative: the state the iteration freezes its first friction "
        "capacities from: 'elastic' (default), the joints' elastic actions under the dead "
        "load, or 'associative', the associative collapse (Gilbert et al. 2006) "
        "([analysis] start in a case file)",
    )
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
    p.add_argument("--quiet", action="store_true", help="no progress line")
    add_overwrite(p)
    add_max_memory(p, "an analysis")
    p.set_defaults(func=limit_command)


def limit_memory(case, options: dict, max_memory: float | None = None) -> LimitEstimate | None:
    """The memory estimate of the limit analysis of a loaded case with ``options`` (None for
    a backend it does not know: the analysis names it); raises
    :class:`~masonry_dem.solvers.resources.TooLarge` when it is above ``max_memory`` bytes
    (None: what the machine, the process's ``ulimit -v`` and its cgroup leave)."""
    from masonry_dem.solvers.limit_analysis.analysis import choose_backend
    from masonry_dem.solvers.limit_analysis.interface import (
        ASSOCIATIVE_GRID,
        NON_ASSOCIATIVE_GRID,
        lobatto_rule,
    )
    from masonry_dem.solvers.resources import LIMIT_BYTES, check_fits, limit_estimate

    model = case.model
    backend = options.get("backend") or choose_backend(model, options.get("cone"))
    grid = options.get("grid") or (
        ASSOCIATIVE_GRID if options.get("associative", True) else NON_ASSOCIATIVE_GRID
    )
    lobatto_rule(grid)  # a grid out of its range is named as such, not as too large
    if backend not in LIMIT_BYTES:
        return None
    est = limit_estimate(model.blocks.count, model.interfaces.count, int(grid), str(backend))
    check_fits(est, max_memory)
    return est


class LimitBar(EventLine):
    """The progress line of a limit analysis: the iterations of its stage and the two values
    that close on lambda (``LimitProgress``). A solve that reports none (HiGHS, Clarabel on
    small walls) shows nothing."""

    def __init__(self, name: str, quiet: bool) -> None:
        super().__init__(name[:40], "it", quiet)

    def __call__(self, event: LimitProgress) -> None:
        if event.lower == event.upper:
            self.tick(f"{event.stage} {event.iteration}: lambda {event.lower:.6g}")
        else:
            self.tick(
                f"{event.stage} {event.iteration}: lambda in [{event.lower:.6g}, "
                f"{event.upper:.6g}] (not yet certified)"
            )


def run_limit(
    case,
    out: Path,
    options: dict,
    render: bool = True,
    overwrite: bool = False,
    max_memory: float | None = None,
    quiet: bool = True,
) -> dict:
    """Run the limit analysis of a loaded case into ``out``, a folder this run claims as
    ``run`` does (refused if it holds another run, unless ``overwrite``); returns the
    summary. An analysis whose memory estimate is above what it may take is refused before
    the folder is claimed (TooLarge); an allocation that fails anyway is a MemoryError that
    quotes the estimate. Unless ``quiet``, the iterations show on a progress line."""
    from masonry_dem._signals import run_interruptible
    from masonry_dem.analysis import analyze
    from masonry_dem.export.limit_results import write_limit_results
    from masonry_dem.export.results_folder import claim, record_stopped, write_summary

    est = limit_memory(case, options, max_memory)
    folder = claim(out, overwrite, {"case": case.source, "analysis": "limit"})
    try:
        t0 = time.perf_counter()
        try:
            with LimitBar(case.model.name, quiet) as bar:
                result = run_interruptible(
                    lambda: analyze(case.model, "limit", options, progress=bar).details
                )
        except MemoryError as exc:  # an allocation failed: with what was expected
            expected = f"; estimated {est.describe()}" if est is not None else ""
            stopped = MemoryError(f"{exc or 'an allocation failed'}{expected}")
            record_stopped(out, stopped)
            raise stopped from exc
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
    from masonry_dem.solvers.resources import TooLarge, parse_memory

    case = load_case(args.case)
    if case.stages is not None:
        print(
            "masonry-dem limit: refused: the case has loading stages ([[stages]]); limit "
            "analysis takes one dead and one live load: run it with masonry-dem run, or give "
            "the stage to analyse as the case's own [[loads]] and [[supports]]",
            file=sys.stderr,
        )
        return 2
    options = dict(case.limit_options or {})
    if args.associative is not None:
        options["associative"] = args.associative
    if args.grid is not None:
        options["grid"] = args.grid
    if args.start is not None:
        if options.get("associative", True):  # the associative analysis has no start
            print(
                f"masonry-dem limit: refused: --start {args.start} is the starting state of "
                "the non-associative analysis; add --non-associative (or associative = false "
                "in [analysis])",
                file=sys.stderr,
            )
            return 2
        options["start"] = args.start
    elif options.get("associative", True):  # the case file's, for an overriding --associative
        options.pop("start", None)
    if args.backend is not None:
        options["backend"] = args.backend
    if args.time_limit is not None:
        options["time_limit"] = args.time_limit
    if args.dem_bound:
        from masonry_dem.solvers.limit_analysis import model_friction_scale

        options["friction_scale"] = model_friction_scale(case.model)
    out = Path(args.out)
    max_memory = None if args.max_memory is None else parse_memory(args.max_memory)
    try:
        summary = run_limit(
            case,
            out,
            options,
            not args.no_render,
            args.overwrite,
            max_memory=max_memory,
            quiet=args.quiet,
        )
    except TooLarge as exc:
        print(f"masonry-dem limit: refused: {exc}", file=sys.stderr)
        return 2
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
