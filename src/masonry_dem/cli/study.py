"""``masonry-dem study ...``: the solver studies of :mod:`masonry_dem.studies`, printed.

* ``study speed-accuracy [--cases ...] [--methods ...] [--quick | --full] [--json] [--out DIR]``:
  every setting of each method (static, dynamic relaxation, limit analysis) on each case;
  a table, ``speed_accuracy.json`` and a PNG chart of time against error with the Pareto
  front; the DR / static time ratio at equal (1 %) accuracy and the limit analysis against
  the static answer, per case;
* ``study ladder [--sizes ...] [--methods ...]``: the methods on walls of 10^2 to 10^4 blocks;
* ``study reduction [--json]``: the 3-DOF in-plane model against the 6-DOF model;
* ``study kn-sweep [--case NAME] [--factors ...] [--json]``: lambda as the dry kn grows.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from masonry_dem.studies.runs import Method

METHODS = [m.value for m in Method]
HELP = f"{', '.join(METHODS)} (default: %(default)s)"


def add_parser(subparsers: Any) -> None:
    from masonry_dem.studies.size_ladder import DEFAULT_SIZES, DEFAULT_UP_TO
    from masonry_dem.studies.speed_accuracy import DEFAULT_CASES

    p = subparsers.add_parser(
        "study",
        help="speed against accuracy of the solvers, a size ladder, the in-plane reduction, "
        "the kn sweep",
        description="The solvers: docs/solvers.md; their measurements: docs/history/solvers_record.md.",
    )
    sub = p.add_subparsers(dest="study", metavar="STUDY")
    sa = sub.add_parser("speed-accuracy", help="every setting of each method; time vs error")
    sa.add_argument(
        "--cases", nargs="+", default=list(DEFAULT_CASES), help="validation cases or 'default'"
    )
    sa.add_argument(
        "--methods", nargs="+", choices=METHODS, default=METHODS, metavar="METHOD", help=HELP
    )
    sa.add_argument("--quick", action="store_true", help="a few settings per method only")
    sa.add_argument("--full", action="store_true", help="also the DR settings that cost time")
    sa.add_argument("--budget", type=int, help="time-step budget of each DR run")
    sa.add_argument("--json", action="store_true", help="print the runs as a JSON array")
    sa.add_argument("--from-json", metavar="FILE", help="no runs: redo the table and chart")
    sa.add_argument("--out", default="results/study", help="PNG, JSON, table (%(default)s)")
    sa.set_defaults(func=speed_accuracy_command)
    la = sub.add_parser("ladder", help="the methods on walls of 10^2 to 10^4 blocks")
    la.add_argument("--sizes", type=int, nargs="+", default=list(DEFAULT_SIZES), help="blocks")
    la.add_argument(
        "--methods", nargs="+", choices=METHODS, default=METHODS[::2], metavar="METHOD", help=HELP
    )
    for method, blocks in DEFAULT_UP_TO.items():
        la.add_argument(
            f"--{method.value.replace('_', '-')}-up-to",
            type=int,
            default=blocks,
            metavar="BLOCKS",
            help=f"largest wall of {method.value} (%(default)s)",
        )
    la.add_argument("--json", action="store_true")
    la.set_defaults(func=ladder_command)
    rd = sub.add_parser("reduction", help="3-DOF in-plane model against the 6-DOF model")
    rd.add_argument("--repeats", type=int, default=3, help="best of N timings (%(default)s)")
    rd.add_argument("--json", action="store_true")
    rd.set_defaults(func=reduction_command)
    kn = sub.add_parser("kn-sweep", help="lambda as the dry-joint normal stiffness grows")
    kn.add_argument("--case", default="S15", help="a dry-joint case (default: %(default)s)")
    kn.add_argument("--factors", type=float, nargs="+", default=[0.1, 1.0, 10.0, 100.0, 1000.0])
    kn.add_argument("--method", choices=METHODS[:2], default="static")
    kn.add_argument("--budget", type=int, help="DR time-step budget")
    kn.add_argument("--scale-kt", action="store_true", help="scale kt with kn (law invariant)")
    kn.add_argument("--json", action="store_true")
    kn.set_defaults(func=kn_sweep_command)
    p.set_defaults(func=lambda args: _help(p))


def _help(p: argparse.ArgumentParser) -> int:
    p.print_help()
    return 2


def speed_accuracy_command(args: argparse.Namespace) -> int:
    from masonry_dem.studies import speed_accuracy as sa
    from masonry_dem.studies.chart import chart

    out = Path(args.out)

    def progress(row: dict[str, Any]) -> None:
        if not args.json:
            print(sa.progress_line(row), flush=True)

    if args.from_json:
        res = sa.from_saved(Path(args.from_json))
    else:
        res = sa.speed_accuracy(
            args.cases,
            quick=args.quick,
            budget=args.budget,
            progress=progress,
            full=args.full,
            methods=[Method(m) for m in args.methods],
        )
    out.mkdir(parents=True, exist_ok=True)
    (out / "speed_accuracy.json").write_text(json.dumps(res, indent=2))
    text = sa.table(res["rows"]) + "\n\n" + sa.summary_lines(res["summary"], res["accuracy"])
    (out / "speed_accuracy.txt").write_text(text + "\n")
    png = chart(res["rows"], out / "speed_accuracy.png")
    if args.json:
        print(json.dumps(res["rows"], indent=1))
    else:
        print(text)
        print(f"chart: {png}; data: {out / 'speed_accuracy.json'}")
    return 0 if res["rows"] else 1


def ladder_command(args: argparse.Namespace) -> int:
    from masonry_dem.studies.size_ladder import ladder_text, progress_line, size_ladder

    up_to = {m: getattr(args, f"{m.value}_up_to") for m in Method}
    shown = None if args.json else (lambda row: print(progress_line(row), flush=True))
    rows = size_ladder(args.sizes, [Method(m) for m in args.methods], up_to, progress=shown)
    print(json.dumps(rows, indent=1) if args.json else ladder_text(rows))
    return 0 if rows else 1


def reduction_command(args: argparse.Namespace) -> int:
    from masonry_dem.studies.reduction import reduction_study, reduction_text

    res = reduction_study(repeats=args.repeats)
    print(json.dumps(res, indent=1) if args.json else reduction_text(res))
    return 0


def kn_sweep_command(args: argparse.Namespace) -> int:
    from masonry_dem.studies.kn_sweep import kn_sweep, kn_sweep_text

    res = kn_sweep(args.case, args.factors, args.method, args.budget, args.scale_kt)
    if args.json:
        print(json.dumps(res, indent=1))
    else:
        print(kn_sweep_text(res, args.case, args.method, args.scale_kt))
    return 0
