"""``masonry-dem validate [CASE] [--json] [--out DIR] [--jobs N]``: run the paper's validation cases
(Tables 1-3, :mod:`masonry_dem.studies.validation`) and print ours against the paper's DEM and
the reference (test / FEM) values; each case's results (VTU/PVD, PNGs) go to ``DIR/<case>/``.
``masonry-dem validate shear-walls``: the shear walls of Raijmakers & Vermeltfoort
(:mod:`masonry_dem.studies.shear_walls`), each with its curve and crack pattern.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from masonry_dem.cli.options import add_output, whole_number


def add_parser(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "validate",
        help="run the paper's validation cases and print the comparison table",
        description="Run the validation cases of Tables 1-3 of the paper (all, or one) and "
        "print ours vs the paper's DEM and the test or FEM reference.",
    )
    p.add_argument(
        "case",
        nargs="?",
        help="one case (OL1, S11, 2-3, ...), or shear-walls (the Raijmakers & Vermeltfoort "
        "shear walls); default: every case of the paper",
    )
    p.add_argument("--json", action="store_true", help="print the rows as a JSON array")
    add_output(p, "results/validation", "the PNGs")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--jobs",
        type=whole_number("--jobs", 1),
        default=1,
        help="cases run side by side in this many processes (default: %(default)s; each "
        "case's own time is then measured under the load of the others)",
    )
    p.add_argument(
        "--restraint",
        choices=("columns", "return-walls"),
        default="columns",
        help="how the return walls of Table 2 are read: fixed DOFs of the end columns (the "
        "paper's, default) or walls of blocks, the specimens rebuilt as L and U walls "
        "(S11, S12, S13, S15, S6, S1-S3, S5; docs/walls_that_meet.md)",
    )
    p.add_argument(
        "--return-blocks",
        type=whole_number("--return-blocks", 2),
        nargs="+",
        default=[None],
        metavar="M",
        help="with --restraint return-walls: the return walls' length in blocks, one run "
        "per value (default: the fewest blocks at least half the wall's height, 4)",
    )
    p.set_defaults(func=validate_command)


def validate_command(args: argparse.Namespace) -> int:
    if args.case == "shear-walls":
        return _shear_walls(args)
    from tqdm import tqdm

    from masonry_dem.cases.paper import RETURN_WALL_CASES, case_names
    from masonry_dem.studies.validation import format_table, run_cases

    every = case_names() if args.restraint == "columns" else list(RETURN_WALL_CASES)
    names = [args.case] if args.case else every
    if args.case and args.case not in every:
        raise ValueError(
            f"unknown case {args.case!r} for --restraint {args.restraint}; "
            f"the cases are {', '.join(every)}"
        )
    lengths = args.return_blocks if args.restraint == "return-walls" else [None]
    out = Path(args.out)
    rows = []
    with tqdm(total=len(names) * len(lengths), unit="case", disable=args.quiet or args.json) as bar:

        def done(row: dict[str, Any]) -> None:
            bar.set_description(row["case"])
            bar.update()

        for m in lengths:
            variant = {"restraint": args.restraint, "return_blocks": m}
            rows += run_cases(names, out, not args.no_render, args.jobs, done, **variant)
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        print(format_table(rows))
        print(
            f"results in {out}/<case>/"
            + (
                ""
                if args.restraint == "columns"
                else " (<case>_return<M>/ for the return-wall reading)"
            )
        )
    return 0 if all(r["status"] == "collapse" for r in rows) else 1


def _shear_walls(args: argparse.Namespace) -> int:
    """The shear-wall validation: one row per wall, its curve and crack pattern."""
    from masonry_dem.studies.shear_walls import format_shear_walls, run_shear_walls

    out = Path(args.out)
    rows = run_shear_walls(out=out, render=not args.no_render)
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        print(format_shear_walls(rows))
        print(f"results in {out}/<wall>/ (curve.csv, cracks.png)")
    return 0 if all(r["status"] in ("completed", "collapse") for r in rows) else 1
