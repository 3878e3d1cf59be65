"""The motion of each implicit corner check on U walls that creep (session 19, `creep`).

    NUMBA_NUM_THREADS=1 python benchmarks/creep_trace.py [--wall 6x24r4] [--wall 14x30r6]
        [--budget 1000] [--every 25]

Each U wall (facade blocks x courses, returns of m blocks; ``14x30r6`` is the big U wall of
``bench_walls_that_meet``) is tilted as ``endgame_walls`` tilts it and pushed over with
``corner_check_steps`` = ``--budget``. For every implicit check the path makes it prints the
verdict and, every ``--every`` steps taken, the factorizations so far, the largest
translation from the check's start (against the displacement limit), the pace of the motion
over the last ``--every`` steps taken and the residual: what a verdict read from the
motion's speed and its trend would see (docs/history/solvers_record.md, "A motion that creeps").
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_walls_that_meet import GAMMA, A, B, S, build  # noqa: E402

from masonry_dem.geometry import plans  # noqa: E402
from masonry_dem.solvers.static import StaticSettings, StaticSolver  # noqa: E402
from masonry_dem.solvers.static.outcome import Outcome  # noqa: E402


class Traced(StaticSolver):
    """A static solver that prints each implicit check's motion."""

    every = 25

    def implicit_relaxation(self, target: float, budget: int | None = None) -> Outcome:
        out = super().implicit_relaxation(target, budget)
        verdict = "rest" if out.ok else ("past the limit" if out.past_limit else "no verdict")
        print(
            f"  check to lambda={target:.7g}: {verdict}, {out.iterations} factorizations, "
            f"{len(self.check_motion)} steps taken, limit {self.limit * 1e3:.2f} mm"
        )
        last = 0.0
        for k, (factorizations, moved, residual) in enumerate(self.check_motion, start=1):
            if k % self.every == 0 or k == len(self.check_motion):
                print(
                    f"    step {k}: {factorizations} factorizations, moved {moved * 1e3:.3f} mm, "
                    f"pace {(moved - last) * 1e6 / self.every:.2f} um a step, "
                    f"residual {residual:.2e}"
                )
                last = moved
        return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--wall", action="append", default=[], metavar="NxCrM")
    p.add_argument("--budget", type=int, default=1000)
    p.add_argument("--every", type=int, default=25)
    a = p.parse_args(argv)
    Traced.every = a.every
    for label in a.wall or ["6x24r4", "14x30r6"]:
        match = re.fullmatch(r"(\d+)x(\d+)r(\d+)", label)
        if match is None:
            raise SystemExit(f"--wall: {label!r} is not NxCrM (facade blocks x courses, returns)")
        n, c, m = (int(g) for g in match.groups())
        model, _ = build(plans.u_wall(n, c, A, B, S, GAMMA, return_blocks=m), held=False)
        print(f"U {label}, corner_check_steps={a.budget}:", flush=True)
        solver = Traced(model, StaticSettings(corner_check_steps=a.budget))
        h = solver.run()
        print(
            f"  {h.status} lambda={h.collapse_multiplier:.7g} factorizations={h.factorizations} "
            f"implicit={solver.implicit_steps} time_steps={solver.time_steps}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
