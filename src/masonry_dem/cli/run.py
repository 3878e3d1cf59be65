"""``masonry-dem run [CASE] [--out DIR]``: run a case file (or the bundled default wall)."""

from __future__ import annotations

import argparse
import json
import logging
import threading
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
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace the run already in --out (removes the package's own files there, and "
        "only those); without it such a folder is refused",
    )
    p.add_argument(
        "--max-memory",
        default=None,
        help="refuse a run whose estimated memory is above this (e.g. 16G, 500M; default: "
        "the machine's available memory)",
    )
    p.add_argument(
        "--no-bound",
        action="store_true",
        help="do not compute the limit-analysis bound of a collapse (its certificate then "
        "says the bound was not checked); by default it is computed once the pushover has "
        "stopped at a collapse to certify, and only then",
    )
    p.set_defaults(func=run_command)


class LazyBound:
    """The associative limit-analysis bound, computed the first time the certificate of a
    collapse asks for it and never otherwise: a run that ends ``completed`` or ``failed``
    before a collapse is checked costs no limit analysis (at 10^4 blocks it took longer
    than the pushover). :meth:`summary` gives the ``limit_analysis_*`` fields."""

    def __init__(self, enabled: bool = True) -> None:
        self.enabled = enabled
        self.result: dict | None = None

    def __call__(self, model) -> float | None:
        if not self.enabled:
            return None
        if self.result is None:
            self.result = limit_analysis_bound(model)
        return self.result["limit_analysis_bound"]

    def summary(self) -> dict:
        if self.result is not None:
            return self.result
        why = (
            "not computed (--no-bound)"
            if not self.enabled
            else "not computed (no collapse to certify)"
        )
        return {
            "limit_analysis_bound": None,
            "limit_analysis_status": why,
            "limit_analysis_seconds": 0.0,
        }


def limit_analysis_bound(model) -> dict:
    """The associative limit-analysis multiplier of the model, an upper bound of the
    pushover's (``limit_analysis_bound``: None unless the LA finds a collapse), and its
    status and time: the exact cone (Clarabel) with the friction enlarged by kappa(alpha),
    whose domain contains the DEM's (``solvers.limit_analysis.dem_upper_bound``)."""
    from masonry_dem.solvers.limit_analysis import dem_upper_bound

    la = dem_upper_bound(model)
    return {
        "limit_analysis_bound": la.load_factor if la.status == "collapse" else None,
        "limit_analysis_status": la.status,
        "limit_analysis_seconds": round(la.seconds, 4),
    }


def _refuse_if_too_large(args: argparse.Namespace, model=None) -> int | None:
    """Exit code 2 with the estimate when the run would not fit (before the model is built
    when the case's geometry can be counted, else after); None when it fits."""
    import sys

    from masonry_dem.solvers import resources

    if model is None:
        geometry = _geometry_of(args.case)
        try:
            blocks = None if geometry is None else resources.blocks_of_geometry(geometry)
        except (TypeError, ValueError, OverflowError):
            blocks = None  # not a geometry the schema accepts: load_case names the fault
        if blocks is None:
            return None
        est = resources.estimate(blocks)
    else:
        est = resources.estimate(model.blocks.count, model.interfaces.count, model.n_dofs)
    limit = None if args.max_memory is None else resources.parse_memory(args.max_memory)
    try:
        resources.check_fits(est, limit)
    except resources.TooLarge as exc:
        print(f"masonry-dem run: refused: {exc}", file=sys.stderr)
        return 2
    if model is not None and not args.quiet:
        print(f"estimate: {est.describe()}", file=sys.stderr)
    return None


def _geometry_of(case: str | None) -> dict | None:
    """The ``[geometry]`` table of a case file, read without building anything (None for the
    bundled wall or a file that does not parse: load_case then reports it)."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python < 3.11
        import tomli as tomllib  # type: ignore[no-redef,import-not-found]

    if case is None:
        return None
    try:
        geometry = tomllib.loads(Path(case).read_text()).get("geometry")
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return None
    return geometry if isinstance(geometry, dict) else None


def run_command(args: argparse.Namespace) -> int:
    refused = _refuse_if_too_large(args)  # before anything is built
    if refused is not None:
        return refused
    from tqdm import tqdm

    from masonry_dem._signals import check_stop, deferred_signals, stop_on_signals
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.export.results_folder import MECHANISM_FILES
    from masonry_dem.export.writer import ResultsWriter
    from masonry_dem.solvers.incremental import StaticSolver

    case = load_case(args.case)
    refused = _refuse_if_too_large(args, case.model)
    if refused is not None:
        return refused
    out = Path(args.out)
    if case.method == "limit":  # [analysis] method = "limit"
        from masonry_dem.cli.limit import run_limit

        summary = run_limit(
            case, out, dict(case.limit_options or {}), not args.no_render, args.overwrite
        )
        print(json.dumps({k: summary[k] for k in ("status", "lambda", "method", "bound")}))
        print(f"{summary['status']}: {summary['reason']}")
        return 0 if summary["status"] == "collapse" else 1
    from masonry_dem.solvers.warmup import prepare

    prepare(case.model.interfaces.count)  # says "compiling kernels ..." first, if it must
    t0 = time.perf_counter()
    # claims the folder: refused if it holds another run (without --overwrite) or is in use
    writer = ResultsWriter(
        out, case.model, background=True, overwrite=args.overwrite, start={"case": case.source}
    )
    try:
        bar = tqdm(desc=case.model.name[:40], unit="step", disable=args.quiet)

        def on_step(step) -> None:
            writer(step)
            bar.set_postfix(lam=f"{step.load_factor:.4g}")
            bar.update(1)
            check_stop()  # Ctrl-C or SIGTERM: stop here, between steps, all of them written

        # the associative bound, which the certificate of a collapse checks lambda against,
        # is computed when a collapse is to be certified (LazyBound)
        bound = LazyBound(enabled=not args.no_bound)
        solver = StaticSolver(case.model, case.settings, bound=bound)
        # the steps handed to the writer reach the disk; an exception (Ctrl-C, SIGTERM, a
        # full disk) leaves the folder marked interrupted or failed with every step written
        done = threading.Event()

        def tick() -> None:  # progress within long steps: Newton iterations, factorizations
            while not done.wait(2.0):
                bar.set_postfix(its=solver.iterations, fac=solver.factorizations, refresh=True)

        ticker = threading.Thread(target=tick, daemon=True)
        with writer, bar, stop_on_signals():
            ticker.start()
            try:
                history = solver.run(control=case.control, callback=on_step, monitor=case.monitor)
            finally:
                done.set()
                ticker.join()
        with deferred_signals():  # pushover.csv, the mechanism and summary.json agree
            summary = writer.finish(
                history,
                release=False,
                case=case.source,
                wall_seconds=round(time.perf_counter() - t0, 4),
                **bound.summary(),
            )
        if not args.no_render:
            summary = _render(out, summary, writer, MECHANISM_FILES[0])
    finally:
        writer.release()
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


def _render(out: Path, summary: dict, writer, mechanism_file: str) -> dict:
    """PNGs of the last step and, after a collapse, of the mechanism, named in summary.json."""
    try:
        from masonry_dem.export.render import render_mechanism, render_step
    except ImportError as exc:  # rendering is optional for the analysis itself
        log.warning("no PNG: the render module is unavailable (%s)", exc)
        return summary
    pngs = {"png": Path(render_step(out, step="last")).name}
    if (out / mechanism_file).is_file():  # the run ended in collapse
        pngs["mechanism_png"] = render_mechanism(out).name
    return writer.write_summary(summary, pngs)
