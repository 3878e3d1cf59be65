"""Two settings on walls that meet of other sizes than the benchmark's (session 19).

    NUMBA_NUM_THREADS=1 python benchmarks/endgame_walls.py [--set NAME=VALUE ...] [--against NAME=VALUE ...]

Six U walls (facade blocks x courses, returns of m blocks), an L and a T wall, in
Restrepo Velez's stones, tilted with the base fixed as ``bench_walls_that_meet`` pushes its
U wall; each pushed over twice, with the defaults changed by ``--set`` and by ``--against``
(StaticSettings fields; at least one of them): status, collapse multiplier,
factorizations, implicit steps, time steps, and whether the two answers are the same
(``--set corner_check_steps=500 --against corner_check_steps=200``: docs/history/solvers_record.md,
"A motion that creeps").
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_validation import parse_settings  # noqa: E402
from bench_walls_that_meet import GAMMA, A, B, S, build  # noqa: E402

from masonry_dem.geometry import plans  # noqa: E402
from masonry_dem.solvers.static import StaticSettings, StaticSolver  # noqa: E402

U_SIZES = [(6, 12, 3), (10, 15, 2), (8, 21, 3), (8, 21, 5), (12, 18, 4), (6, 24, 4)]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--against", action="append", default=[], metavar="NAME=VALUE")
    a = p.parse_args(argv)
    if not (a.set or a.against):
        p.error("give --set or --against (or both)")
    runs = {" ".join(a.set) or "default": parse_settings(a.set)}
    runs[" ".join(a.against) or "default"] = parse_settings(a.against)
    walls = {
        f"U {n}x{c} r{m}": plans.u_wall(n, c, A, B, S, GAMMA, return_blocks=m)
        for n, c, m in U_SIZES
    }
    walls["L 8x15 r4"] = plans.l_wall(8, 15, A, B, S, GAMMA, return_blocks=4)
    walls["T 8x15 r4"] = plans.t_wall(8, 15, A, B, S, GAMMA, return_blocks=4)
    for label, wall in walls.items():
        model, _ = build(wall, held=False)
        out = []
        for changes in runs.values():
            solver = StaticSolver(model, StaticSettings(**changes))
            h = solver.run()
            out.append(
                (
                    h.status,
                    h.collapse_multiplier,
                    h.factorizations,
                    solver.implicit_steps,
                    solver.time_steps,
                )
            )
        same = out[0][:2] == out[1][:2]
        print(
            f"{label} ({wall.count} blocks): "
            + "; ".join(
                f"{r}: {st} lambda={lam:.7g} factorizations={f} implicit={i} time_steps={ts}"
                for r, (st, lam, f, i, ts) in zip(runs, out, strict=True)
            )
            + ("; the same" if same else "; DIFFERENT"),
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
