"""Benchmark: the parts of one Newton iteration on the validation walls, in CPU microseconds.

Run:  python benchmarks/bench_iteration.py [--cases OL1 S15 ...] [--repeat 400]

For each case, at the state where its pushover stopped (its last converged state, yielded
joints and all), it times with ``time.process_time`` (so that the load of a shared machine
does not enter; run with ``NUMBA_NUM_THREADS=1`` for one core) the median of ``--repeat``
calls of:

* ``residual``: ``DiscreteProblem.residual`` (the compiled law and products, the norms);
* ``tangents``: ``DiscreteProblem.joint_tangents`` (the law's tangent, the zero-capacity
  joints);
* ``assembly``: the entries of the tangent in the backend's order (``TangentAssembler.data``);
* ``factor`` and ``solve``: the backend's numeric factorization and one solve;
* ``iteration``: the CPU of the whole pushover divided by its Newton iterations.

Compare two trees by running it with ``PYTHONPATH`` on each, back to back: only ratios
measured close together mean anything on a shared machine.
"""

from __future__ import annotations

import statistics
import time

from _machine import arguments, print_machine


def _median_us(repeat: int, call, *args) -> float:
    times = []
    for _ in range(repeat):
        t = time.process_time()
        call(*args)
        times.append(time.process_time() - t)
    return 1e6 * statistics.median(times)


def main() -> int:
    p = arguments(__doc__)
    p.add_argument("--cases", nargs="+", default=None, help="default: every validation case")
    p.add_argument("--repeat", type=int, default=400, help="calls timed per part (median)")
    args = p.parse_args()
    print_machine()
    if args.repeat < 1:
        p.error(f"--repeat must be at least 1, got {args.repeat}")
    from masonry_dem.cases.paper import build_case, case_names
    from masonry_dem.solvers.static.solver import StaticSolver
    from masonry_dem.studies.runs import warm_up

    warm_up()
    print(
        f"{'case':6} {'DOFs':>5} {'joints':>6} | {'residual':>8} {'tangents':>8} "
        f"{'assembly':>8} {'factor':>8} {'solve':>8} | {'iteration':>9}  (CPU us)"
    )
    for name in args.cases or case_names():
        case = build_case(name)
        solver = StaticSolver(case.model, case.settings)
        t = time.process_time()
        history = solver.run(monitor=case.monitor)
        per_iteration = 1e6 * (time.process_time() - t) / max(history.iterations, 1)
        problem = solver.problem
        q, lam = solver.q, history.collapse_multiplier or 0.0
        residual, _, response = solver.residual(q, lam)
        fronts = problem._factorizer()
        T = problem.joint_tangents(response)
        values = problem.tangent_assembler.data(T, fronts.layout)
        n = args.repeat
        parts = [
            _median_us(n, solver.residual, q, lam),
            _median_us(n, problem.joint_tangents, response),
            _median_us(n, problem.tangent_assembler.data, T, fronts.layout),
            _median_us(n, fronts.factor_laid_out, values),
        ]
        factors = fronts.factor_laid_out(values)  # the newest factors solve
        parts.append(_median_us(n, factors.solve, residual))
        print(
            f"{name:6} {problem.free.size:5d} {case.model.interfaces.count:6d} | "
            + " ".join(f"{x:8.1f}" for x in parts)
            + f" | {per_iteration:9.1f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
