"""Benchmark: speed against accuracy of the static solver, dynamic relaxation and limit analysis.

Benchmark: speed against accuracy of the static solver, dynamic relaxation and limit
analysis (issues 6 and 19).

Run:  python benchmarks/bench_speed_accuracy.py [--cases S15 OL1 14-15] [--quick]
                                                [--out results/study] [--skip-sweeps]

One command for every figure of docs/history/solvers_record.md:

1. the speed-accuracy study (``masonry-dem study speed-accuracy``): every setting of each
   method (``--methods``) on each case, the table, ``speed_accuracy.json`` and the chart with
   the Pareto front, the time ratio DR / static at equal (1 %) accuracy and the limit
   analysis against the static answer, measured in this run;
2. the in-plane reduction (``masonry-dem study reduction``): lambda and time of the 3-DOF
   model against the 6-DOF model, and what the never-assembled fixed DOFs and the closed-form
   interface domain save;
3. the dry-joint stiffness sweeps (``masonry-dem study kn-sweep [--scale-kt]``): lambda as kn
   grows by 10^4, with kt (a pure conditioning test: the law is invariant) and alone (kt/kn
   changes the frictional prestate, a physical change).

``--check`` makes the exit status 1 when a target of issue 6 is missed (DR / static >= 10 at
1 % on every case; 3-DOF lambda within 0.1 %; kn-and-kt sweep within 1 %).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from _machine import arguments, print_machine

from masonry_dem.studies import speed_accuracy as study
from masonry_dem.studies.chart import chart
from masonry_dem.studies.kn_sweep import kn_sweep
from masonry_dem.studies.reduction import reduction_study, reduction_text
from masonry_dem.studies.runs import Method
from masonry_dem.studies.validation import one_kernel_thread


def _progress(r: dict) -> None:
    print(study.progress_line(r), flush=True)


def _one_case(case: str, options: dict) -> dict:
    return study.speed_accuracy([case], progress=_progress, **options)


def main(argv: list[str] | None = None) -> int:
    p = arguments(__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--cases", nargs="+", default=list(study.DEFAULT_CASES))
    p.add_argument(
        "--methods", nargs="+", choices=[m.value for m in Method], default=[m.value for m in Method]
    )
    p.add_argument("--quick", action="store_true", help="a few settings per method")
    p.add_argument("--full", action="store_true", help="also the DR settings that only cost time")
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="cases run in parallel processes (each case's runs stay sequential, so the "
        "time ratios within a case share the same load)",
    )
    p.add_argument(
        "--budget", type=int, default=None, help="DR time-step budget per run (default: DR's own)"
    )
    p.add_argument("--out", default="results/study")
    p.add_argument("--skip-sweeps", action="store_true", help="speed-accuracy study only")
    p.add_argument("--kn-case", default="S15")
    p.add_argument("--kn-dr", action="store_true", help="the kn sweeps with DR too (slow)")
    p.add_argument("--check", action="store_true")
    args = p.parse_args(argv)
    print_machine()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"python {platform.python_version()} on {platform.machine()}, {time.ctime()}")
    failures: list[str] = []

    t0 = time.perf_counter()
    options = {
        "quick": args.quick,
        "full": args.full,
        "budget": args.budget,
        "methods": args.methods,
    }
    if args.jobs > 1 and len(args.cases) > 1:
        with ProcessPoolExecutor(
            max_workers=args.jobs,
            mp_context=multiprocessing.get_context("spawn"),  # no fork of a threaded process
            initializer=one_kernel_thread,
        ) as pool:
            parts = list(pool.map(_one_case, args.cases, [options] * len(args.cases)))
        rows = [r for part in parts for r in part["rows"]]
        refs = {k: v for part in parts for k, v in part["summary"].items()}
        res = study.summarise(rows, refs)
    else:
        res = study.speed_accuracy(args.cases, progress=_progress, **options)
    (out / "speed_accuracy.json").write_text(json.dumps(res, indent=2))
    text = study.table(res["rows"]) + "\n\n" + study.summary_lines(res["summary"], res["accuracy"])
    (out / "speed_accuracy.txt").write_text(text + "\n")
    png = chart(res["rows"], out / "speed_accuracy.png")
    print(text)
    print(f"chart: {png} ({time.perf_counter() - t0:.0f} s)")
    for name, s in res["summary"].items():
        for key, what in (("", "converged lambda"), ("own_", "own answers")):
            ratio = s[f"{key}time_ratio_dr_over_static"]
            if ratio is None or ratio < 10:
                failures.append(f"{name}: DR / static at 1 % of the {what} = {ratio}")

    if not args.skip_sweeps:
        red = reduction_study(repeats=3)
        (out / "reduction.json").write_text(json.dumps(red, indent=2))
        print()
        print(reduction_text(red))
        for r in red["in_plane"]:
            d = r["lambda_relative_difference"]
            if d is None or d > 1e-3:
                failures.append(f"{r['scene']}: 3-DOF lambda differs by {d}")
        factors = [1.0, 10.0, 100.0, 1000.0, 10000.0]
        sweeps = {}
        methods = ["static"] + (["dynamic_relaxation"] if args.kn_dr else [])
        for method in methods:
            for scale_kt in (True, False):
                key = f"{method}, {'kn and kt' if scale_kt else 'kn alone'}"
                sweep = kn_sweep(args.kn_case, factors, method, args.budget, scale_kt)
                sweeps[key] = sweep
                print()
                print(f"{args.kn_case}: lambda as the dry-joint stiffness grows ({key})")
                for r in sweep["rows"]:
                    print(
                        f"  kn = {r['kn']:9.3g}  kt = {r['kt']:9.3g}  "
                        f"lambda = {study.fmt(r['lambda'], '.5g'):>9}  "
                        f"drift {study.fmt(r['drift'], '.2%'):>7}  {r['seconds']:6.2f} s  "
                        f"{r['status']}"
                    )
                print(f"  spread: {study.fmt(sweep['spread'], '.2%')}")
                if scale_kt and (sweep["spread"] is None or sweep["spread"] > 0.01):
                    failures.append(f"kn sweep ({key}) spread {sweep['spread']}")
        (out / "kn_sweep.json").write_text(json.dumps(sweeps, indent=2))

    if failures:
        print("\ntargets missed:\n  " + "\n  ".join(failures))
    else:
        print("\nall targets met")
    return 1 if (failures and args.check) else 0


if __name__ == "__main__":
    sys.exit(main())
