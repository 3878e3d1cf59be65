"""``masonry-dem sweep [CASE] --vary PATH=VALUES --sample PATH=DIST``: a parameter sweep on
Dask (the library is :mod:`masonry_dem.studies.sweep`)."""

from __future__ import annotations

import argparse
import json
import logging
import sys


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep",
        help="run a case over varied values on Dask: one row per run (Parquet, CSV) and plots",
        description="Run a case file (default: the bundled wall) over grids, lists or random "
        "samples of its values, each named by its path in the case file, on a Dask "
        "LocalCluster (one process per core) or a running scheduler. Rows go to "
        "OUT/sweep.csv as runs complete and to OUT/sweep.parquet; PNGs plot lambda.",
    )
    p.add_argument("case", nargs="?", help="TOML case file (see README, 'Case files')")
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="PATH=VALUES",
        help="a grid lo:hi:n (both ends included) or a list v1,v2,...; e.g. "
        "material.friction=0.5:0.9:9; repeat to cross several",
    )
    p.add_argument(
        "--sample",
        action="append",
        default=[],
        metavar="PATH=DIST",
        help="lognormal(median,sigma_log), normal(mean,sd) or uniform(lo,hi); e.g. "
        '"material.kn=lognormal(1e9,0.3)" (quoted: a shell reads the brackets); repeat for several',
    )
    p.add_argument("--samples", type=int, default=0, help="number of random samples")
    p.add_argument("--seed", type=int, default=None, help="seed of the samples (default: drawn)")
    p.add_argument("--out", default="results/sweep", help="sweep folder (default: %(default)s)")
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="a running Dask scheduler, e.g. tcp://host:8786 (default: a LocalCluster)",
    )
    p.add_argument(
        "--workers", type=int, default=None, help="LocalCluster processes (default: the cores)"
    )
    p.add_argument(
        "--keep",
        choices=("none", "summary", "all"),
        default="none",
        help="files of each run under OUT/runs/: none, summary.json and pushover.csv, or the "
        "whole results folder (default: %(default)s)",
    )
    group = p.add_mutually_exclusive_group()
    group.add_argument("--resume", action="store_true", help="run only the rows OUT lacks")
    group.add_argument("--overwrite", action="store_true", help="replace the sweep in OUT")
    p.add_argument("--no-plots", action="store_true", help="no PNGs")
    p.add_argument(
        "--quiet", action="store_true", help="no progress lines (the planning's, the runs')"
    )
    p.set_defaults(func=sweep_command)


def _pairs(items: list[str], option: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        path, sep, value = item.partition("=")
        if not sep or not path.strip() or not value.strip():
            raise ValueError(f"{option} {item!r}: must be PATH=VALUES, e.g. material.friction=0.5")
        if path.strip() in out:
            raise ValueError(f"{option} {path.strip()} is given twice")
        out[path.strip()] = value.strip()
    return out


def sweep_command(args: argparse.Namespace) -> int:
    try:
        import distributed  # noqa: F401

        from masonry_dem.studies.sweep import sweep
    except ImportError as exc:  # pragma: no cover - the optional extra is missing
        print(f'masonry-dem sweep: error: {exc}; pip install "masonry_dem[sweep]"', file=sys.stderr)
        return 2
    if not args.verbose:  # Dask logs its cluster's life at INFO (set on its import, above)
        logging.getLogger("distributed").setLevel(logging.WARNING)
    logging.getLogger("masonry_dem.studies.sweep").setLevel(logging.INFO)  # the dashboard
    if not args.quiet:  # how far the checks of a long plan are
        logging.getLogger("masonry_dem.studies.sweep_plan").setLevel(logging.INFO)
    try:
        result = sweep(
            args.case,
            vary=_pairs(args.vary, "--vary"),
            sample=_pairs(args.sample, "--sample"),
            samples=args.samples,
            seed=args.seed,
            out=args.out,
            scheduler=args.scheduler,
            workers=args.workers,
            keep=args.keep,
            resume=args.resume,
            overwrite=args.overwrite,
            plots=not args.no_plots,
            progress=not args.quiet,
        )
    except ModuleNotFoundError as exc:  # dask or pyarrow not installed
        print(f"masonry-dem sweep: error: {exc}", file=sys.stderr)
        return 2
    rows = result.rows
    statuses: dict[str, int] = {}
    for row in rows:
        statuses[row["status"]] = statuses.get(row["status"], 0) + 1
    lam = [r["lambda"] for r in rows if r["status"] == "collapse"]
    print(
        json.dumps(
            {
                "runs": len(rows),
                "ran": result.ran,
                "resumed": result.resumed,
                "status": statuses,
                "lambda_min": min(lam, default=None),
                "lambda_max": max(lam, default=None),
            }
        )
    )
    print(f"results in {result.folder}/ ({result.csv.name}, {result.parquet.name}, PNGs)")
    return 0
