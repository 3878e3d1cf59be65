"""The Restrepo Velez rows with short return walls: where the static path stops, and whether
the wall has an equilibrium above that stop (docs/walls_that_meet.md).

Run:  python benchmarks/return_wall_rows.py [--rows S13 S15 ...] [--return-blocks 2]
      [--rise 0.01] [--budget 200000] [--dr]

For each row it builds ``build_case(name, restraint="return-walls", return_blocks=m)`` and
prints:

- ``static``: the static solver's lambda and how its path stopped;
- ``bound``: the associative limit-analysis multiplier with the friction enlarged to cover
  the DEM's domain (``dem_upper_bound``), above every equilibrium of the wall;
- ``above``: from the static path's last converged state (its plastic part and cracks
  held), a dynamic relaxation to lambda = stop x (1 + ``rise``) at tolerance 1e-6 with
  ``budget`` time steps, then Newton at that lambda (``StaticSolver.dynamic_rescue``): the
  residual of the polished state in the static solver's norm (tolerance 1e-8), its largest
  translation and the time steps it took. A polished state there is an equilibrium of the
  same holonomic step problem the path solves, above the stop: the stop was a fold of the
  path, not its peak;
- with ``--dr``: dynamic relaxation from the dead load (tolerance 1e-3) and its stop.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time

from fold_audit import rest_above

from masonry_dem.cases.paper import RETURN_WALL_CASES, build_case
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation
from masonry_dem.solvers.limit_analysis.analysis import dem_upper_bound
from masonry_dem.solvers.static import StaticSolver


def row(name: str, m: int, rise: float, budget: int, dr: bool) -> None:
    case = build_case(name, restraint="return-walls", return_blocks=m)
    t0 = time.perf_counter()
    solver = StaticSolver(case.model)
    history = solver.run()
    seconds = time.perf_counter() - t0
    stop = solver.load_factor
    print(
        f"{name}/{m}: {case.model.blocks.count} blocks; static {history.status} "
        f"{history.collapse_multiplier} in {seconds:.1f} s ({history.reason})",
        flush=True,
    )
    bound = dem_upper_bound(case.model)
    print(f"  bound {bound.load_factor:.4f} ({bound.status})", flush=True)
    above = rest_above(solver, stop, rise, budget)
    print(f"  above: {above} ({above.seconds:.1f} s)", flush=True)
    if dr:
        t0 = time.perf_counter()
        relaxation = DynamicRelaxation(case.model, DRSettings(tolerance=1e-3))
        h = relaxation.run()
        print(
            f"  DR (1e-3): {h.status} {h.collapse_multiplier} in "
            f"{time.perf_counter() - t0:.1f} s, {relaxation.stats.time_steps} time steps "
            f"({h.reason})",
            flush=True,
        )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", nargs="+", choices=RETURN_WALL_CASES, default=RETURN_WALL_CASES)
    parser.add_argument("--return-blocks", type=int, default=2)
    parser.add_argument("--rise", type=float, default=0.01)
    parser.add_argument("--budget", type=int, default=200_000)
    parser.add_argument("--dr", action="store_true")
    args = parser.parse_args(argv)
    print(f"# {platform.processor() or platform.machine()}, python {sys.version.split()[0]}")
    for name in args.rows:
        row(name, args.return_blocks, args.rise, args.budget, args.dr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
