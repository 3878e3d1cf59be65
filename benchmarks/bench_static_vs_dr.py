"""Benchmark: the static solver against dynamic relaxation at equal accuracy, one case after
the other in one process (no parallel jobs, so both methods see the same machine).

Run:  python benchmarks/bench_static_vs_dr.py [--cases S15 OL1 14-15] [--repeat 2]

For each case: the static default, then DR at tolerance 1e-3 (its fastest setting within 1 %
in earlier studies) and at its default; lambda, seconds, work (Newton iterations or time
steps), the error of each DR run against the static answer, and the time ratio DR / static
of the fastest DR run within 1 % of the static lambda (none: DR never got within 1 %).
``--repeat N`` runs the static default and each DR setting N times in turn (static, DR, DR,
static, DR, DR, ...) and keeps the fastest of each: on a machine whose speed drifts within
minutes both methods then get its fast phases.
"""

from __future__ import annotations

import argparse
import platform
import time

from masonry_dem.studies.runs import (
    Method,
    load_study_case,
    run_method,
    settings_for,
    warm_up,
    with_changes,
)

DR_RUNS = (
    ("DR tolerance 1e-3", {"tolerance": 1e-3, "bracket_tolerance": 0.01}),
    ("DR default", {}),
)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", nargs="+", default=["S15", "OL1", "14-15"])
    p.add_argument("--repeat", type=int, default=1, help="runs of each, in turn; fastest kept")
    args = p.parse_args()
    if args.repeat < 1:
        p.error(f"--repeat must be at least 1, got {args.repeat}")
    print(f"python {platform.python_version()} on {platform.machine()}, {time.ctime()}")
    warm_up()  # the compiled law is loaded before anything is timed
    print(f"{'case':6} {'run':18} {'lambda':>10} {'seconds':>8} {'work':>8} {'vs static':>9}")
    for name in args.cases:
        case = load_study_case(name)
        dr = settings_for(Method.DYNAMIC_RELAXATION, case.static)
        drs = [with_changes(dr, c) for _, c in DR_RUNS]
        best: dict[int, tuple] = {}  # run index (0: static) -> fastest (history, s, cost)
        for _ in range(args.repeat):
            for i, (method, settings) in enumerate(
                [(Method.STATIC, case.static)] + [(Method.DYNAMIC_RELAXATION, d) for d in drs]
            ):
                run = run_method(method, case.model, settings)
                if i not in best or run.seconds < best[i][1]:
                    best[i] = (run.history, run.seconds, run.cost)
        h, t_static, cost = best[0]
        lam = h.collapse_multiplier
        print(f"{name:6} {'static default':18} {lam:10.5g} {t_static:8.2f} {cost['iterations']:8d}")
        within = []
        for i, (label, _) in enumerate(DR_RUNS, start=1):
            hd, t_dr, cost_dr = best[i]
            lam_dr = hd.collapse_multiplier
            err = None if lam_dr is None or lam is None else lam_dr / lam - 1
            if err is not None and abs(err) <= 0.01:
                within.append(t_dr)
            shown = "-" if err is None else f"{100 * err:+.2f}%"
            print(
                f"{name:6} {label:18} {lam_dr or float('nan'):10.5g} {t_dr:8.2f} "
                f"{cost_dr['time_steps']:8d} {shown:>9}"
            )
        ratio = f"{min(within) / t_static:.1f}x" if within else "no DR run within 1 %"
        print(f"{name:6} DR / static at 1 %: {ratio}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
