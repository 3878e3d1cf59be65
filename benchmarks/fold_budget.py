"""The corner check's budget against its cost and the folds it passes (issue 18, task
`verdict`; docs/history/solvers_record.md, "Above a peak and above a fold").

    python benchmarks/fold_budget.py [--walls U S23 S6/2 S13/2]
        [--variants fold_creep_cos=0 "" fold_check_time_steps=20000 ...]

Each wall (a validation case, ``NAME/m`` with return walls of m blocks, or ``U``:
bench_walls_that_meet's S5 U wall) is pushed over once per variant (StaticSettings fields as
``name=value`` separated by commas; "" is the default), one after the other in this process,
and one row printed each: lambda, status, steps, factorizations, relaxation time steps and
CPU seconds (process time; compare them only within a run).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from masonry_dem.solvers.static import StaticSettings, StaticSolver

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_validation import parse_settings  # noqa: E402
from relaxation_trace import wall  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--walls", nargs="*", default=["U", "S23", "S6/2", "S13/2"])
    p.add_argument("--variants", nargs="*", default=["fold_creep_cos=0", ""])
    args = p.parse_args(argv)
    print(
        f"{'wall':7s} {'variant':40s} {'lambda':>10s} {'status':>10s} {'steps':>5s} "
        f"{'fact':>5s} {'t-steps':>8s} {'CPU s':>7s}"
    )
    for name in args.walls:
        model, settings, monitor = wall(name)
        for variant in args.variants:
            chosen = replace(
                settings or StaticSettings(),
                **parse_settings(variant.split(",") if variant else []),
            )
            t0 = time.process_time()
            solver = StaticSolver(model, chosen)
            h = solver.run(monitor=monitor)
            cpu = time.process_time() - t0
            lam = h.collapse_multiplier
            print(
                f"{name:7s} {variant or '(default)':40s} "
                f"{lam if lam is not None else float('nan'):10.6f} {h.status:>10s} "
                f"{len(h.steps):5d} {h.factorizations:5d} {solver.time_steps:8d} {cpu:7.2f}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
