"""Is a certified collapse a peak or a fold? (issue 18, item 2; docs/history/solvers_record.md,
"Peaks and folds: the audit").

    python benchmarks/fold_audit.py [--cases S13 OL1 ...] [--rows S15 ...] [--return-blocks 4]
        [--walls 6] [--seed 18] [--budget 50000] [--rise 0.01]

Three groups of walls, each run by the static pushover (``StaticSolver``, the case's own
settings and monitor) with the associative bound ``dem_upper_bound`` given to its certificate:

- ``--cases``: the 18 validation cases of ``masonry_dem.cases.paper`` (default: all), their
  standard restraint;
- ``--rows``: the Restrepo Velez walls held by return walls of ``--return-blocks`` blocks
  (default: all seven rows, 4 blocks); ``--rows`` with no name skips them;
- ``--walls N``: N generated walls of ``benchmarks/certificate_sweep.py`` (its generator,
  ``--seed``).

Where the path ends ``collapse`` at lambda_c, a dynamic relaxation from its last converged
state (plastic part and cracks held; on a falling curve below lambda_c) to lambda_c x
(1 + ``rise``) with ``budget`` time steps (it also gives up when its residual has not halved
over a quarter of them: ``dynamic_rescue``'s stall window), then
Newton at that lambda (``StaticSolver.dynamic_rescue``). A polished state there (residual in
the static norm under its tolerance) is an equilibrium of the same step problem above the
certified collapse: that stop was a fold of the path, not its peak. "no rest" within the
budget is evidence the stop is a peak, not a proof. One row a wall: status, lambda, bound,
the check above (residual, largest translation, time steps), and seconds of the static run and
of the check.
"""

from __future__ import annotations

import argparse
import logging
import platform
import sys
import time
from dataclasses import dataclass

import numpy as np
from certificate_sweep import describe, random_spec, wall

from masonry_dem.cases.paper import RETURN_WALL_CASES, build_case, case_names
from masonry_dem.model import Model
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSettings, StaticSolver


@dataclass
class Above:
    """The search for an equilibrium above a stop: ``found`` with its residual, largest
    translation (m), or not within ``time_steps``."""

    target: float
    found: bool
    residual: float
    moved: float
    time_steps: int
    seconds: float
    why: str = ""  # why the relaxation did not come to rest (blow-up, stall, budget)
    start: float = 0.0  # largest translation of the stop state (m), from the unloaded wall
    limit: float = 0.0  # the relaxation's displacement limit (m), from the unloaded wall

    @property
    def verdict(self) -> str:
        """FOLD: an equilibrium above; n/c: the stop state already lies past the
        relaxation's limit, so it stops at once and says nothing; peak?: no rest."""
        if self.found:
            return "FOLD"
        return "n/c" if self.time_steps <= 1 else "peak?"

    def __str__(self) -> str:
        if not self.found:
            return f"no rest at {self.target:.4f} after {self.time_steps} time steps: {self.why}"
        return (
            f"equilibrium at {self.target:.4f}: residual {self.residual:.1e}, largest "
            f"translation {1e3 * self.moved:.2f} mm, {self.time_steps} time steps"
        )


class _Reasons(logging.Handler):
    """The corrector logs why a dynamic rescue failed at debug level: kept here."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def rest_above(solver: StaticSolver, peak: float, rise: float, budget: int) -> Above:
    """From the solver's last converged state, dynamic relaxation to peak x (1 + rise)
    within ``budget`` time steps, then Newton there. ``peak``: the multiplier the path
    reports (a state past the peak of a falling curve lies below it)."""
    target = peak * (1.0 + rise)
    stop = solver.load_factor
    start = float(np.abs(solver.q.reshape(-1, 6)[:, :3]).max())
    before = solver.time_steps
    reasons = _Reasons()
    logger = logging.getLogger("masonry_dem.solvers.static.relaxations")
    level = logger.level
    logger.addHandler(reasons)
    logger.setLevel(logging.DEBUG)
    t0 = time.perf_counter()
    try:
        polished = solver.dynamic_rescue(target, stop, budget=budget)
    finally:
        logger.removeHandler(reasons)
        logger.setLevel(level)
    seconds = time.perf_counter() - t0
    steps = solver.time_steps - before
    if polished is None:
        why = reasons.messages[-1].partition(": ")[2] if reasons.messages else "Newton failed"
        return Above(
            target, False, float("nan"), float("nan"), steps, seconds, why, start, solver.limit
        )
    residual = solver.residual(polished.q, target)[1]
    moved = float(np.abs(polished.q.reshape(-1, 6)[:, :3]).max())
    return Above(target, True, residual, moved, steps, seconds, "", start, solver.limit)


def audit(
    name: str,
    model: Model,
    settings: StaticSettings | None,
    monitor,
    rise: float,
    budget: int,
) -> str:
    """One wall: its static run, the bound, and (after a collapse) the search above."""
    la = dem_upper_bound(model)
    bound = la.load_factor if la.load_factor is not None and np.isfinite(la.load_factor) else None
    t0 = time.perf_counter()
    solver = StaticSolver(model, settings, bound=bound)
    history = solver.run(monitor=monitor)
    seconds = time.perf_counter() - t0
    lam = history.collapse_multiplier
    shown = f"{lam:.4f}" if lam is not None else f"({solver.load_factor:.4f})"
    bound_shown = f"{bound:.4f}" if bound is not None else f"({la.status})"
    line = f"{name:40s} {history.status!s:9s} {shown:>8s} {bound_shown:>7s} {seconds:6.1f} s"
    if history.status == "collapse":
        assert lam is not None
        above = rest_above(solver, lam, rise, budget)
        line += (
            f"  {above.verdict:5s} last state {solver.load_factor:.4g}, "
            f"{1e3 * above.start:.1f} mm (limit "
            f"{1e3 * above.limit:.1f}); {above} ({above.seconds:.1f} s)"
        )
    else:
        line += f"  ({history.stop})"
    return line


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", nargs="*", default=None, help="default: all 18")
    parser.add_argument("--rows", nargs="*", default=None, help="default: all seven")
    parser.add_argument("--return-blocks", type=int, default=4)
    parser.add_argument("--walls", type=int, default=6)
    parser.add_argument("--seed", type=int, default=18)
    parser.add_argument("--budget", type=int, default=50_000)
    parser.add_argument("--rise", type=float, default=0.01)
    args = parser.parse_args(argv)
    cases = case_names() if args.cases is None else args.cases
    rows = RETURN_WALL_CASES if args.rows is None else args.rows
    print(
        f"# {platform.processor() or platform.machine()}, python {sys.version.split()[0]}; "
        f"budget {args.budget} time steps to {1 + args.rise:g} x the stop"
    )
    print(f"{'wall':40s} {'status':9s} {'lambda':>8s} {'bound':>7s} {'static':>8s}  above")
    t_all = time.perf_counter()
    for name in cases:
        case = build_case(name)
        print(
            audit(name, case.model, case.settings, case.monitor, args.rise, args.budget), flush=True
        )
    for name in rows:
        case = build_case(name, restraint="return-walls", return_blocks=args.return_blocks)
        label = f"{name}/{args.return_blocks} (return walls)"
        print(
            audit(label, case.model, case.settings, case.monitor, args.rise, args.budget),
            flush=True,
        )
    rng = np.random.default_rng(args.seed)
    for _ in range(args.walls):
        spec = random_spec(rng)
        print(audit(describe(spec), wall(spec), None, None, args.rise, args.budget), flush=True)
    print(f"# total {time.perf_counter() - t_all:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
