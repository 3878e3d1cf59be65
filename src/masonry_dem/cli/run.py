"""``masonry-dem run [CASE] [--out DIR]``: run a case file (or the bundled default wall); the run
itself is :func:`masonry_dem.run_case.run_case`."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from masonry_dem.cli.options import (
    add_case,
    add_max_memory,
    add_output,
    add_overwrite,
    results_line,
)
from masonry_dem.run_case import Progress, estimate_run, run_case

if TYPE_CHECKING:
    from masonry_dem.model import Model
    from masonry_dem.results import StepResult


def add_parser(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = subparsers.add_parser(
        "run",
        help="run a case file (default: the bundled wall) and write VTU/PVD, summary.json and a PNG",
        description="Run the pushover analysis of a case file. With no CASE, the bundled default wall.",
    )
    add_case(p)
    add_output(p, "results/default", "the PNGs of the last step and of the collapse mechanism")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_overwrite(p)
    add_max_memory(p, "a run")
    p.add_argument(
        "--no-bound",
        action="store_true",
        help="do not compute the limit-analysis bound of a collapse (its certificate then "
        "says the bound was not checked); by default it is computed once the pushover has "
        "stopped at a collapse to certify, and only then",
    )
    p.set_defaults(func=run_command)


class _Bar(Progress):
    """The progress bar of a run (tqdm on stderr): steps, lambda, and within long steps the
    Newton iterations and factorizations."""

    def __init__(self, name: str, quiet: bool) -> None:
        self.name, self.quiet = name, quiet

    def __enter__(self) -> _Bar:
        from tqdm import tqdm

        self.bar = tqdm(desc=self.name[:40], unit="step", disable=self.quiet)
        return self

    def __exit__(self, *exc: object) -> None:
        self.bar.close()

    def step(self, step: StepResult) -> None:
        self.bar.set_postfix(lam=f"{step.load_factor:.4g}")
        self.bar.update(1)

    def tick(self, iterations: int, factorizations: int) -> None:
        self.bar.set_postfix(its=iterations, fac=factorizations, refresh=True)


def _refused(args: argparse.Namespace, model: Model | None = None) -> bool:
    """Print why the run would not fit (before the model is built when the case's geometry
    can be counted, else after) and say so; print the estimate of a built model and keep
    it (``args.estimate``) for an out-of-memory error to quote."""
    from masonry_dem.solvers.resources import TooLarge

    try:
        est = estimate_run(
            args.case if model is None else model, args.max_memory, render=not args.no_render
        )
    except TooLarge as exc:
        print(f"masonry-dem run: refused: {exc}", file=sys.stderr)
        return True
    args.estimate = est
    if model is not None and est is not None and not args.quiet:
        print(f"estimate: {est.describe()}", file=sys.stderr)
    return False


def run_command(args: argparse.Namespace) -> int:
    if _refused(args):  # before anything is built
        return 2
    from masonry_dem.cases.casefile import load_case

    case = load_case(args.case)
    if _refused(args, case.model):
        return 2
    out = Path(args.out)
    if case.method == "limit":  # [analysis] method = "limit"
        from masonry_dem.cli.limit import exit_code, run_limit
        from masonry_dem.solvers.resources import TooLarge, parse_memory

        try:
            summary = run_limit(
                case,
                out,
                dict(case.limit_options or {}),
                not args.no_render,
                args.overwrite,
                max_memory=None if args.max_memory is None else parse_memory(args.max_memory),
                quiet=args.quiet,
            )
        except TooLarge as exc:
            print(f"masonry-dem run: refused: {exc}", file=sys.stderr)
            return 2
        print(json.dumps({k: summary[k] for k in ("status", "lambda", "method", "bound")}))
        print(f"{summary['status']}: {summary['reason']}")
        print(summary["bound_reason"])
        print(results_line(out))
        return exit_code(summary["status"])
    try:
        summary = run_case(
            case,
            out,
            overwrite=args.overwrite,
            bound=not args.no_bound,
            render=not args.no_render,
            progress=_Bar(case.model.name, args.quiet),
        )
    except MemoryError as exc:  # an allocation failed, wherever: with what was expected
        est = getattr(args, "estimate", None)
        expected = f"; estimated {est.describe()}" if est is not None else ""
        raise MemoryError(f"{exc}{expected}") from exc
    keys = ("status", "lambda", "steps", "seconds", "blocks", "interfaces")
    print(json.dumps({k: summary[k] for k in keys}))
    print(f"{summary['status']}: {summary['reason']}")
    print(results_line(out))
    return 0 if summary["status"] in ("collapse", "completed") else 1
