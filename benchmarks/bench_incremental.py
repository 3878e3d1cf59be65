"""Benchmark: the incremental kinematics of `masonry-dem assess` (the finite motion of a
mechanism integrated in steps, the blocks' twists projected onto the joints' contacts at
each step), its sparse factorizations as SuperLU's defaults make them against the symmetric
setting the package uses.

Run:  python benchmarks/bench_incremental.py [--steps 30] [--repeat 2] [--walls default u big]

For each wall (``default``: the bundled case; ``u``: the U wall of docs/walls_that_meet.md,
8 x 21 blocks with returns of 4, dry joints; ``big``: the same U wall of 14 x 30 blocks with
returns of 6, as bench_walls_that_meet.py builds it) it runs the associative limit analysis, takes
its mechanism (``Mechanism.of(..., kinematics="incremental")``) and integrates ``--steps``
steps of the path (each: two predictions, two projections, 1-4 factorizations each). In one
run, alternating the two settings ``--repeat`` times, best of each, it prints:

- ``default``: seconds a step with SuperLU's defaults (COLAMD, partial pivoting), what the
  package used before;
- ``symmetric``: seconds a step with ``spd_lu`` (the ordering of A^T + A, diagonal pivots,
  SuperLU's symmetric mode: the matrices are symmetric positive definite);
- ``ratio``: symmetric / default;
- ``twist diff``: the largest difference of the last node's twists between the two, over
  their largest entry (the same path to the projection's accuracy).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as sla
from _machine import arguments, print_machine
from bench_limit_analysis import U_WALL

import masonry_dem as md
import masonry_dem.assessment.incremental as incremental
from masonry_dem.assessment.kinematics import Mechanism
from masonry_dem.cases.casefile import load_case


def wall(name: str) -> md.Model:
    if name == "default":
        return load_case().model
    text = U_WALL
    if name == "big":  # bench_walls_that_meet.py's big U wall: 14 blocks x 30 courses, returns 6
        text = (
            U_WALL.replace("blocks_along_length = 8", "blocks_along_length = 14")
            .replace("courses = 21", "courses = 30")
            .replace("return_blocks = 4", "return_blocks = 6")
        )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "u_wall.toml"
        path.write_text(text)
        return load_case(path).model


def default_lu(matrix):
    return sla.splu(matrix.tocsc())


def run(model: md.Model, mode: np.ndarray, factor, steps: int) -> tuple[float, np.ndarray]:
    incremental.spd_lu = factor
    path = Mechanism.of(model, mode, kinematics="incremental").path
    assert path is not None
    t0 = time.perf_counter()
    path._reach(steps * path.ds)
    seconds = (time.perf_counter() - t0) / len(path.xi_mid)
    return seconds, path.xi[-1]


def main() -> None:
    parser = arguments(__doc__)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument(
        "--walls", nargs="+", choices=("default", "u", "big"), default=["default", "u"]
    )
    args = parser.parse_args()
    print_machine()
    symmetric = incremental.spd_lu
    print(
        f"{'wall':>8} {'blocks':>6} {'default s':>10} {'symmetric s':>12} {'ratio':>6} {'twist diff':>10}"
    )
    for name in args.walls:
        model = wall(name)
        result = md.analyze(model, "limit")
        mode = np.asarray(result.mechanism_of(), dtype=float).reshape(-1, 6)
        best = {"default": np.inf, "symmetric": np.inf}
        last = {}
        for _ in range(args.repeat):
            for label, factor in (("default", default_lu), ("symmetric", symmetric)):
                seconds, xi = run(model, mode, factor, args.steps)
                best[label] = min(best[label], seconds)
                last[label] = xi
        incremental.spd_lu = symmetric
        diff = np.abs(last["default"] - last["symmetric"]).max() / np.abs(last["default"]).max()
        print(
            f"{name:>8} {model.blocks.count:>6} {best['default']:>10.4f} "
            f"{best['symmetric']:>12.4f} {best['symmetric'] / best['default']:>6.2f} {diff:>10.2e}"
        )


if __name__ == "__main__":
    main()
