"""Diagnosis: why Newton's first iterations from the dead-load state stall on the default
wall at 10^3-10^4 blocks (issues 18 and 23). Not a timing benchmark: it prints what the
corrector meets on its first live-load step.

Run:  python benchmarks/bench_first_step.py [--size 30] [--load 0.02 0.005]
                                            [--tensile 0 1e3 1e4]

For the ``bench_scale.default_wall(size)`` (size 30: the 1 007-block wall of issue 18, with
the wall's joints given each ``--tensile`` strength in Pa) it prints:

* the dead-load state: its iterations, the joints at zero compression (trial normal force
  within 1e-8 of the largest: the head joints of a dry wall, whose state flags are then set
  by round-off) and their flags by joint orientation;
* the displacement the live load ``--load`` gives the bonded elastic assembly and the
  dead-load tangent (against the solver's displacement limit);
* the first Newton direction from the dead-load state: the residual and the number of
  joints that change state at step lengths 1 .. 1/64 (the line search's trials, longer);
* ``Corrector.equilibrate`` at each load from the dead-load state: converged or why not,
  iterations and factorizations.
"""

from __future__ import annotations

import argparse
import collections
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_scale  # noqa: E402


def wall(size: int, tensile: float):
    import masonry_dem as md

    courses = 33 if size == 30 else min(size, bench_scale.MAX_COURSES)
    w = md.running_bond_wall(
        size, courses, bench_scale.A, bench_scale.B, bench_scale.S, bench_scale.GAMMA
    )
    blocks, base = md.add_base(w)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(
            kn=bench_scale.KN, kt=bench_scale.KT, friction=bench_scale.MU, tensile_strength=tensile
        ),
        supports=[md.Support([base]), md.Support(md.select.column(w, "left"), ["u1", "u3"])],
        loads=[md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))],
    )


def main() -> None:
    from masonry_dem.solvers.incremental import StaticSolver

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=30)
    ap.add_argument("--load", type=float, nargs="+", default=[0.02, 0.005])
    ap.add_argument("--tensile", type=float, nargs="+", default=[0.0, 1e3, 1e4])
    args = ap.parse_args()
    for tensile in args.tensile:
        model = wall(args.size, tensile)
        solver = StaticSolver(model)
        dead = solver.dead_load()
        solver.accept(dead, 0, 0.0)
        its = model.interfaces
        fn = dead.response.trial[:, 2]
        zero = fn > -1e-8 * np.abs(fn).max()
        print(
            f"\n== {model.blocks.count} blocks, {its.count} joints, tensile strength "
            f"{tensile:g} Pa; dead load: {'ok' if dead.ok else dead.reason} in "
            f"{dead.iterations} iterations; displacement limit {solver.limit:.3g} m"
        )
        print(f"joints at zero compression: {int(zero.sum())}")
        for axis in np.unique(its.axis):
            sel = its.axis == axis
            flags = collections.Counter(dead.response.flags[sel].tolist())
            print(f"  normal along e{axis + 1}: {int(sel.sum())} joints, flags {dict(flags)}")
        free = solver.problem.asm.free_index
        live = solver.problem.F_live
        compliance = solver.problem.factor(dead.response).solve(live)
        for lam in args.load:
            bonded = lam * solver.problem.elastic_displacement(live)
            tangent = lam * float(np.abs(compliance[solver.problem.translation]).max())
            print(
                f"lambda {lam:g}: bonded elastic displacement {bonded:.3g} m, along the "
                f"dead-load tangent {tangent:.3g} m"
            )
            residual, rnorm, response = solver.residual(solver.q, lam)
            dq = solver.problem.factor(response).solve(residual)
            trials = []
            for f in (1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 32, 1 / 64):
                q = solver.q.copy()
                q[free] += f * dq
                _, n_try, r_try = solver.residual(q, lam)
                changed = int((r_try.flags != response.flags).sum())
                trials.append(f"{f:.4g}: {n_try / rnorm:.3g} ({changed})")
            print(
                f"  first Newton direction, residual / start (joints changing state) at "
                f"step {', '.join(trials)}"
            )
            f0 = solver.factorizations
            out = solver.equilibrate(lam)
            print(
                f"  equilibrate: {'converged' if out.ok else out.reason}, "
                f"{out.iterations} iterations, {solver.factorizations - f0} factorizations"
            )


if __name__ == "__main__":
    main()
