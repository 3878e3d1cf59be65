"""Benchmark: does the collapse multiplier move with the step size (issue 18, item 3)?

Run:  python benchmarks/step_sizes.py [CASES ...] [--divisors 1 2 4 8]
                                      [--settings FIELD=VALUE ...] [--against FIELD=VALUE ...]
                                      [--walls] [--check] [--check-time-steps N]

For each case (validation case names; ``--walls`` adds a few generated tilted walls of
``tests/helpers/certificate_checks.tilted_wall``, named ``W<along>x<courses><i|o><h|f>``) and
each divisor d, the pushover runs with ``initial_step`` and ``max_step`` divided by d, once
with ``--settings`` and, when given, once more with ``--against`` on top. It prints lambda,
status, steps, Newton iterations and factorizations of each run. ``--check`` also checks the
peak state of each run on its own: dynamic relaxation from it (its law state as the path
left it) to lambda x 0.99 and to lambda x 1.01, ``--check-time-steps`` at most; ``rest``
there says an equilibrium near that state stands at that load (at 1.01: the path stopped
below a load the wall carries), ``none`` that the relaxation ran off or did not settle.
Counts are exact; nothing is timed.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from bench_validation import parse_settings  # noqa: E402

from masonry_dem import set_thread_wait_policy  # noqa: E402
from masonry_dem.cases.paper import build_case  # noqa: E402
from masonry_dem.solvers.static.settings import StaticSettings  # noqa: E402
from masonry_dem.solvers.static.solver import StaticSolver  # noqa: E402
from masonry_dem.studies.runs import warm_up  # noqa: E402

#: generated walls: (blocks along, courses, in plane, held, friction)
WALLS = {
    "W3x5if": (3, 5, True, False, 0.7),
    "W6x8oh": (6, 8, False, True, 0.7),
    "W5x10ih": (5, 10, True, True, 0.4),
    "W8x6of": (8, 6, False, False, 1.0),
}


def _model(name: str):
    if name in WALLS:
        from helpers.certificate_checks import tilted_wall
        from masonry_dem.model import InterfaceMaterial

        along, courses, in_plane, held, friction = WALLS[name]
        material = InterfaceMaterial(kn=1e9, kt=0.4e9, friction=friction)
        direction = (1.0, 0.0, 0.0) if in_plane else (0.0, 0.0, 1.0)
        return tilted_wall(along, courses, material, direction, held), StaticSettings(), None
    case = build_case(name)
    return case.model, case.settings, case.monitor


def _run(name: str, divisor: float, changes: dict, check: int) -> str:
    model, settings, monitor = _model(name)
    settings = replace(
        settings,
        initial_step=settings.initial_step / divisor,
        max_step=settings.max_step / divisor,
        **changes,
    )
    solver = StaticSolver(model, settings)
    peak: list = [None, -float("inf")]

    def keep_peak(step) -> None:
        if step.load_factor > peak[1]:
            peak[:] = [solver.snapshot(), float(step.load_factor)]

    hist = solver.run(monitor=monitor, callback=keep_peak)
    lam = hist.collapse_multiplier
    text = (
        f"{float('nan') if lam is None else float(lam):10.6g} {str(hist.status):9s} "
        f"{len(hist.steps):5d} {hist.iterations:5d} {hist.factorizations:5d}"
    )
    if check and lam is not None and peak[0] is not None:
        verdicts = []
        for factor in (0.99, 1.01):
            solver.resume(peak[0])
            out = solver.dynamic_rescue(peak[1] * factor, peak[1], check, polish=False)
            verdicts.append("rest" if out is not None and out.ok else "none")
        text += f"  {verdicts[0]:4s} {verdicts[1]:4s}"
    return text


def main(argv: list[str] | None = None) -> int:
    set_thread_wait_policy()
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("cases", nargs="*", help="validation cases or walls (default: S23)")
    p.add_argument("--divisors", nargs="+", type=float, default=[1, 2, 4, 8])
    p.add_argument("--settings", nargs="+", default=[], metavar="FIELD=VALUE")
    p.add_argument("--against", nargs="+", default=[], metavar="FIELD=VALUE")
    p.add_argument("--walls", action="store_true", help="add the generated walls")
    p.add_argument("--check", action="store_true", help="relax the peak state at 0.99, 1.01")
    p.add_argument("--check-time-steps", type=int, default=20000)
    args = p.parse_args(argv)
    base = parse_settings(args.settings)
    columns = [base] + ([{**base, **parse_settings(args.against)}] if args.against else [])
    warm_up()
    names = list(args.cases) + (list(WALLS) if args.walls else [])
    names = names or ["S23"]
    check = args.check_time_steps if args.check else 0
    head = f"{'lambda':>10s} {'status':9s} {'steps':>5s} {'iters':>5s} {'facs':>5s}"
    if check:
        head += "  0.99 1.01"
    print(f"{'case':8s} {'step/':>5s}  " + " | ".join(head for _ in columns), flush=True)
    for name in names:
        for d in args.divisors:
            cells = " | ".join(_run(name, d, changes, check) for changes in columns)
            print(f"{name:8s} {d:5g}  {cells}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
