"""``masonry-dem report RESULTS``: one self-contained HTML page of a results folder
(``report.html``: the verdict, lambda in words, the certificate and the bound, the mechanism,
the wall, the pushover curve and the assessment when there is one; pictures embedded)."""

from __future__ import annotations

import argparse

from masonry_dem.cli.options import add_results


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "report",
        help="write report.html: one self-contained page of a results folder",
        description=(
            "One HTML page, every picture embedded (it loads nothing else): the verdict of "
            "the assessment (assessment.json, from masonry-dem assess) or the run's status, "
            "lambda in words (for a weight-proportional load the horizontal acceleration in "
            "g and the tilt angle), the certificate and the limit analysis's bound with their "
            "gap, the mechanism, the wall and its supports, the pushover curve and the "
            "assessment. Written as RESULTS/report.html, nothing else anywhere."
        ),
    )
    add_results(p)
    p.add_argument(
        "--no-render",
        action="store_true",
        help="draw no picture the folder lacks (the wall; the mechanism when the run drew none)",
    )
    p.set_defaults(func=report_command)


def report_command(args: argparse.Namespace) -> int:
    from masonry_dem.export.report import write_report

    path = write_report(args.results, render=not args.no_render)
    print(path)
    return 0
