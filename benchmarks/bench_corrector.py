"""Benchmark: what the equilibrium corrector spends, and one setting against another.

Run:  python benchmarks/bench_corrector.py [CASES ...] [--settings FIELD=VALUE ...]
                                          [--against FIELD=VALUE ...] [--scale 30 100]
                                          [--scale-only] [--breakdown]

For each case (default: every validation case; ``--scale N`` adds the benchmark wall
``bench_scale.scale_wall(N)``: 30 gives 909 blocks, 100 gives 10 017) it runs the pushover
with ``--settings`` (default: none, the defaults) and, when given, with ``--settings`` plus
``--against``, one after the other in this process, and prints side by side: lambda and its
move, steps, Newton iterations, factorizations and CPU seconds (``time.process_time``: run
with ``NUMBA_NUM_THREADS=1`` for one core), and the totals over the validation cases.
Counts are exact; seconds carry the noise of a shared machine (compare the CPU of the two
columns, measured minutes apart at most).

``--breakdown`` also prints where the iterations and factorizations go: the corrector's
searches by kind (``L``: load control and the dead load, ``W``: a controlled displacement,
``transient``: the pseudo-transient step) and outcome (the ``Failure`` of those that fail),
summed over the cases, for each column.
"""

from __future__ import annotations

import collections
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import arguments, print_machine
from bench_validation import parse_settings  # noqa: E402

from masonry_dem import set_thread_wait_policy  # noqa: E402
from masonry_dem.cases.paper import build_case, case_names  # noqa: E402
from masonry_dem.solvers.static.settings import StaticSettings  # noqa: E402
from masonry_dem.solvers.static.solver import StaticSolver  # noqa: E402
from masonry_dem.studies.runs import warm_up  # noqa: E402

#: (kind, outcome) -> [searches, iterations, factorizations] of the column running now
_SEARCHES: dict[tuple[str, str], list[int]] = collections.defaultdict(lambda: [0, 0, 0])


def _counted(name: str) -> None:
    """Count the searches of ``StaticSolver.<name>`` into ``_SEARCHES``."""
    original = getattr(StaticSolver, name)

    def counted(self, *args, **kwargs):
        f0, i0 = self.factorizations, self.iterations
        out = original(self, *args, **kwargs)
        if name == "equilibrate":
            kind = "W" if kwargs.get("control") is not None else "L"
        else:
            kind = "motion"
        outcome = "ok" if out.ok else (out.failure.name.lower() if out.failure else "failed")
        row = _SEARCHES[(kind, outcome)]
        row[0] += 1
        row[1] += self.iterations - i0
        row[2] += self.factorizations - f0
        return out

    setattr(StaticSolver, name, counted)


def _run(name: str, changes: dict) -> tuple[float, int, int, int, float]:
    if name.startswith("scale"):
        import bench_scale

        model, settings, monitor = bench_scale.scale_wall(int(name[5:])), StaticSettings(), None
    else:
        case = build_case(name)
        model, settings, monitor = case.model, case.settings, case.monitor
    c0 = time.process_time()
    solver = StaticSolver(model, replace(settings, **changes))
    hist = solver.run(monitor=monitor)
    lam = hist.collapse_multiplier
    return (
        float("nan") if lam is None else float(lam),
        len(hist.steps),
        hist.iterations,
        hist.factorizations,
        time.process_time() - c0,
    )


def main(argv: list[str] | None = None) -> int:
    set_thread_wait_policy()
    p = arguments(__doc__)
    p.add_argument("cases", nargs="*", help="validation cases (default: all)")
    p.add_argument("--settings", nargs="+", default=[], metavar="FIELD=VALUE")
    p.add_argument("--against", nargs="+", default=[], metavar="FIELD=VALUE")
    p.add_argument("--scale", nargs="+", type=int, default=[], help="bench_scale.scale_wall(N)")
    p.add_argument("--scale-only", action="store_true", help="no validation case")
    p.add_argument("--breakdown", action="store_true")
    args = p.parse_args(argv)
    print_machine()
    base = parse_settings(args.settings)
    columns = [base] + ([{**base, **parse_settings(args.against)}] if args.against else [])
    if args.breakdown:
        _counted("equilibrate")
        _counted("damped_motion")
    warm_up()
    cases = [] if args.scale_only else args.cases or list(case_names())
    names = cases + [f"scale{n}" for n in args.scale]
    breakdown: list[dict] = [collections.defaultdict(lambda: [0, 0, 0]) for _ in columns]
    totals = [[0.0] * 4 for _ in columns]
    head = f"{'lambda':>9s} {'steps':>5s} {'iters':>5s} {'facs':>5s} {'cpu s':>6s}"
    print(f"{'case':8s} " + " | ".join(head for _ in columns) + "   move")
    for name in names:
        rows = []
        for k, changes in enumerate(columns):
            _SEARCHES.clear()
            rows.append(_run(name, changes))
            for key, value in _SEARCHES.items():
                breakdown[k][key] = [a + b for a, b in zip(breakdown[k][key], value, strict=True)]
            if not name.startswith("scale"):
                totals[k] = [t + v for t, v in zip(totals[k], rows[-1][1:], strict=True)]
        cells = " | ".join(f"{r[0]:9.6g} {r[1]:5d} {r[2]:5d} {r[3]:5d} {r[4]:6.2f}" for r in rows)
        move = f"{100 * (rows[1][0] / rows[0][0] - 1):+7.3f}%" if len(rows) > 1 else ""
        print(f"{name:8s} {cells}   {move}", flush=True)
    cells = " | ".join(f"{'':9s} {t[0]:5.0f} {t[1]:5.0f} {t[2]:5.0f} {t[3]:6.2f}" for t in totals)
    print(f"{'total':8s} {cells}   (validation cases)")
    if len(columns) > 1 and totals[0][3] > 0:
        ratios = [b / a if a else float("nan") for a, b in zip(totals[0], totals[1], strict=True)]
        print(
            f"ratios: steps {ratios[0]:.3f}, iterations {ratios[1]:.3f}, "
            f"factorizations {ratios[2]:.3f}, cpu {ratios[3]:.3f}"
        )
    if args.breakdown:
        for k, table in enumerate(breakdown):
            print(f"\nsearches, column {k + 1} ({columns[k] or 'defaults'}):")
            print(f"{'kind':10s} {'outcome':16s} {'searches':>8s} {'iters':>7s} {'facs':>7s}")
            for (kind, outcome), (n, its, facs) in sorted(table.items(), key=lambda x: -x[1][2]):
                print(f"{kind:10s} {outcome:16s} {n:8d} {its:7d} {facs:7d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
