"""Benchmark: a U wall (return walls as blocks) against a flat wall of the same block count.

Run:  python benchmarks/bench_walls_that_meet.py [--sizes S5 big] [--repeat 3] [--set k=v ...]
      [--stiffness F]

``--set FIELD=VALUE`` (repeatable) overrides a ``StaticSettings`` field for both walls'
pushovers. ``--stiffness F`` makes the joints of both
walls F times stiffer (kt / kn kept): with the dry joints of the default (F = 1) the big flat
wall leaves the small-displacement range (half a block) on a still rising curve, and so does
every flat wall of its block count held as it is (docs/history/solvers_record.md, "The cost of
passing a fold"); with F = 10 it peaks, so ``--sizes big --stiffness 10`` compares two collapses.

For each size it builds a U wall of Restrepo Velez's stones on a fixed base (``S5``: the
8-block specimen with returns of 4 blocks, 326 blocks; ``big``: 14 blocks x 30 courses with
returns of 6 blocks) and a flat running-bond wall with the nearest block count, held on both
end columns as the paper holds its return walls (all DOFs but u2), both tilted out of plane.
In one run, alternating U and flat ``--repeat`` times, best of each, it prints:

- ``detect+assemble``: contact detection, ``Model.build`` and K on the free DOFs;
- ``linear solve``: one elastic solve (``solve_linear``: assembly of K, SuperLU with its
  default ordering, back substitution), best of 5, and ``K fill``, the entries of its
  factors; ``K parts``: the connected parts of K's graph of DOFs (a flat wall's elastic
  stiffness falls apart into its in-plane and its out-of-plane DOFs, which no joint of
  a plane wall couples; the corners of a U wall couple them, so its K is one part and
  fills in about twice as much: a property of the plan, not of an ordering);
- ``tangent fill``: the entries of SuperLU's factors (COLAMD) of the static solver's
  tangent pattern, 6 x 6 per pair of blocks in contact whatever the plan: the fill every
  factorization of the pushover pays; ``tangent LU``: one factorization of the static
  solver's tangent at the dead-load state, as every Newton step after the first does it
  (the multifrontal LU with the ordering the solver keeps), best of 5;
- ``pushover``: the static solver to collapse, its recorded steps, Newton iterations,
  factorizations, the time steps of its dynamic-relaxation checks and the steps of its
  implicit corner checks (each one factorization);
- ``per iteration``, ``per factorization``: pushover seconds per Newton iteration and per
  factorization of the tangent, the cost of the solver's work on that wall whatever the
  length of its path;

and the ratio U / flat of each. The paths differ (a U wall's mechanism drags its returns; a
flat wall with held columns cracks on its own), so the total time is printed for reference
and the claim rests on the assembly, linear-solve, per-iteration and per-factorization
ratios.
"""

from __future__ import annotations

import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.geometry.plans import u_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import StaticSettings, StaticSolver
from masonry_dem.solvers.linear import solve_linear

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import arguments, print_machine
from bench_validation import parse_settings  # noqa: E402

A, B, S, GAMMA = 0.02824, 0.07978, 0.03968, 26.8e3  # Restrepo Velez's stones
DRY = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)
SIZES = {"S5": (8, 21, 4), "big": (14, 30, 6)}  # facade blocks, courses, return blocks
HELD = ["u1", "u3", "w1", "w2", "w3"]


def walls(size: str):
    n, courses, m = SIZES[size]
    u = u_wall(n, courses, A, B, S, GAMMA, return_blocks=m)
    per_course = max(1, round(u.count / courses - 0.5))
    flat = running_bond_wall(per_course, courses, A, B, S, GAMMA)
    return u, flat


def build(wall, held: bool, stiffness: float = 1.0) -> tuple[Model, float]:
    t0 = time.perf_counter()
    blocks, base = add_base(wall)
    its = detect_interfaces(blocks)
    supports = [Support([base])]
    if held:
        supports += [Support(sel.column(wall, side), HELD) for side in ("left", "right")]
    loads = [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))]
    joints = replace(DRY, kn=stiffness * DRY.kn, kt=stiffness * DRY.kt)
    model = Model.build(blocks, joints, supports, loads, interfaces=its)
    Assembly.of(model).stiffness()
    return model, time.perf_counter() - t0


def measure(
    wall, held: bool, settings: StaticSettings | None = None, stiffness: float = 1.0
) -> dict:
    model, assemble = build(wall, held, stiffness)
    linear = []
    for _ in range(5):
        t0 = time.perf_counter()
        solve_linear(model, 0.0)
        linear.append(time.perf_counter() - t0)
    K = Assembly.of(model).stiffness().tocsc()
    lu = splu(K)
    parts = connected_components(K, directed=False)[0]
    t0 = time.perf_counter()
    pushed = StaticSolver(model, settings)
    h = pushed.run()
    seconds = time.perf_counter() - t0
    solver = StaticSolver(model)
    pattern = solver.problem.tangent_assembler
    n = pattern.n
    ones = np.ones(pattern.nnz)
    T = sparse.csc_matrix((ones, pattern.indices, pattern.indptr), shape=(n, n))
    T = T + sparse.identity(n, format="csc") * n  # the pattern, numerically regular
    tangent_lu = splu(T.tocsc(), permc_spec="COLAMD")
    # at the dead-load state (at rest, unloaded dry joints have no tangent stiffness)
    response = solver.residual(h.steps[0].q.reshape(-1), 0.0)[2]
    solver.problem.factor(response)  # the first factorization fixes the ordering and the fronts
    tangent = []
    for _ in range(5):
        t0 = time.perf_counter()
        solver.problem.factor(response)
        tangent.append(time.perf_counter() - t0)
    return {
        "blocks": wall.count,
        "interfaces": model.interfaces.count,
        "assemble": assemble,
        "linear": min(linear),
        "fill": lu.L.nnz + lu.U.nnz,
        "parts": parts,
        "tangent_fill": tangent_lu.L.nnz + tangent_lu.U.nnz,
        "tangent": min(tangent),
        "pushover": seconds,
        "steps": len(h.steps),
        "iterations": h.iterations,
        "factorizations": h.factorizations,
        "time_steps": pushed.time_steps,
        "per_iteration": seconds / max(h.iterations, 1),
        "per_factorization": seconds / max(h.factorizations, 1),
        "lambda": h.collapse_multiplier,
        "status": h.status,
    }


def main(argv=None) -> int:
    parser = arguments(__doc__)
    parser.add_argument("--sizes", nargs="+", choices=sorted(SIZES), default=["S5", "big"])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE")
    parser.add_argument("--stiffness", type=float, default=1.0, metavar="F")
    args = parser.parse_args(argv)
    print_machine()
    settings = StaticSettings(**parse_settings(args.set))
    if args.set:
        print(f"# settings: {' '.join(args.set)}")
    if args.stiffness != 1.0:
        print(f"# joints {args.stiffness:g} x stiffer: kn={args.stiffness * DRY.kn:.3g}")
    print(f"# {platform.processor() or platform.machine()}, python {sys.version.split()[0]}")
    measure(*walls("S5")[:1], held=False)  # compile the kernels before timing
    for size in args.sizes:
        u, flat = walls(size)
        runs: dict[str, list[dict]] = {"U": [], "flat": []}
        for _ in range(args.repeat):  # alternate, so both see the same load of the machine
            runs["U"].append(measure(u, held=False, settings=settings, stiffness=args.stiffness))
            runs["flat"].append(
                measure(flat, held=True, settings=settings, stiffness=args.stiffness)
            )
        best = {}
        for kind, rs in runs.items():
            best[kind] = {
                k: min(r[k] for r in rs)
                if k
                in (
                    "assemble",
                    "linear",
                    "tangent",
                    "pushover",
                    "per_iteration",
                    "per_factorization",
                )
                else rs[0][k]
                for k in rs[0]
            }
        print(
            f"\n{size}: U wall {u.count} blocks, flat wall {flat.count} blocks (best of {args.repeat})"
        )
        head = f"{'':16s} {'U':>12s} {'flat':>12s} {'U / flat':>9s}"
        print(head)
        print("-" * len(head))
        for key, unit in (
            ("interfaces", ""),
            ("assemble", "s"),
            ("linear", "ms"),
            ("fill", ""),
            ("parts", ""),
            ("tangent_fill", ""),
            ("tangent", "ms"),
            ("pushover", "s"),
            ("steps", ""),
            ("iterations", ""),
            ("factorizations", ""),
            ("time_steps", ""),
            ("per_iteration", "ms"),
            ("per_factorization", "ms"),
            ("lambda", ""),
        ):
            # a run that stops without a certified collapse has no lambda (None): nan
            uu, ff = (float("nan") if v is None else v for v in (best["U"][key], best["flat"][key]))
            scale = 1e3 if unit == "ms" else 1.0
            ratio = uu / ff if ff else float("nan")
            names = {
                "assemble": "detect+assemble",
                "linear": "linear solve",
                "fill": "K fill",
                "parts": "K parts",
                "tangent": "tangent LU",
            }
            name = names.get(key, key.replace("_", " "))
            print(
                f"{name + (' [' + unit + ']' if unit else ''):16s} {uu * scale:12.4g} {ff * scale:12.4g} {ratio:9.2f}"
            )
        print(f"status: U {best['U']['status']}, flat {best['flat']['status']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
