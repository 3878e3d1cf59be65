"""``masonry-dem run [CASE] [--out DIR]``: run a case file (or the bundled default wall)."""

from __future__ import annotations

import argparse
import json
import logging
import time
from pathlib import Path

log = logging.getLogger(__name__)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "run",
        help="run a case file (default: the bundled wall) and write VTU/PVD, summary.json and a PNG",
        description="Run the pushover analysis of a case file. With no CASE, the bundled default wall.",
    )
    p.add_argument("case", nargs="?", help="TOML case file (see README, 'Case files')")
    p.add_argument("--out", default="results/default", help="results folder (default: %(default)s)")
    p.add_argument(
        "--no-render",
        action="store_true",
        help="skip the PNGs of the last step and of the collapse mechanism",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run_command)


def limit_analysis_bound(model) -> dict:
    """The associative limit-analysis multiplier of the model, an upper bound of the
    pushover's (``limit_analysis_bound``: None unless the LA finds a collapse), and its
    status and time. With the exact cone (Clarabel): the tightest bound, and on the
    validation walls 7-77 times faster than the LP (docs/limit_analysis.md)."""
    from masonry_dem.solvers.limit_analysis import limit_analysis

    la = limit_analysis(model, backend="clarabel")
    return {
        "limit_analysis_bound": la.load_factor if la.status == "collapse" else None,
        "limit_analysis_status": la.status,
        "limit_analysis_seconds": round(la.seconds, 4),
    }


def run_command(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from masonry_dem.cases.casefile import load_case
    from masonry_dem.export.writer import ResultsWriter
    from masonry_dem.solvers.incremental import StaticSolver

    case = load_case(args.case)
    out = Path(args.out)
    if case.method == "limit":  # [analysis] method = "limit"
        from masonry_dem.cli.limit import run_limit

        summary = run_limit(case, out, dict(case.limit_options or {}), not args.no_render)
        print(json.dumps({k: summary[k] for k in ("status", "lambda", "method", "bound")}))
        print(f"{summary['status']}: {summary['reason']}")
        return 0 if summary["status"] == "collapse" else 1
    writer = ResultsWriter(out, case.model, background=True)
    bar = tqdm(desc=case.model.name[:40], unit="step", disable=args.quiet)

    def on_step(step) -> None:
        writer(step)
        bar.set_postfix(lam=f"{step.load_factor:.4g}")
        bar.update(1)

    t0 = time.perf_counter()
    solver = StaticSolver(case.model, case.settings)
    with writer, bar:  # the steps handed to the writer reach the disk
        history = solver.run(control=case.control, callback=on_step, monitor=case.monitor)
    wall_seconds = round(time.perf_counter() - t0, 4)
    summary = writer.finish(
        history, case=case.source, wall_seconds=wall_seconds, **limit_analysis_bound(case.model)
    )
    if not args.no_render:
        try:
            from masonry_dem.export.render import render_mechanism, render_step
        except ImportError as exc:  # rendering is optional for the analysis itself
            log.warning("no PNG: the render module is unavailable (%s)", exc)
        else:
            png = render_step(out, step="last")
            summary["png"] = str(Path(png).name)
            if (out / "mechanism_blocks.vtu").is_file():  # the run ended in collapse
                summary["mechanism_png"] = render_mechanism(out).name
            (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(
        json.dumps(
            {
                k: summary[k]
                for k in ("status", "lambda", "steps", "seconds", "blocks", "interfaces")
            }
        )
    )
    print(f"{summary['status']}: {summary['reason']}")
    print(f"results in {out}/ (blocks.pvd, interfaces.pvd, summary.json, pushover.csv)")
    return 0 if summary["status"] in ("collapse", "completed") else 1
