"""Benchmark: each sparse LU backend on the validation set's tangents, on 1 and on 2 threads.

Benchmark: seconds per factorization of the tangents the validation set really factorizes,
with each installed backend on 1 and on 2 threads, in one process.

    python benchmarks/bench_factorization.py [--cases OL1 S11 ...] [--repeat 30] [--walls 20 30]

Each validation case runs once; its 10th and 40th tangents are kept (the entries of the fixed
pattern, as :meth:`DiscreteProblem.factor` hands them to the backend). ``--walls N`` adds the
dead-load tangent of ``benchmarks/bench_scale.py``'s default wall with about N^2 blocks (20:
2 460 DOFs, 30: 5 970). Every backend then factorizes each tangent ``--repeat`` times on one
thread and on two, the four measurements interleaved (one round of each, then the next), so
that the load of a shared machine falls on all of them alike; the medians are printed per
tangent, with the ratio of two threads to one, and the total per backend. This is the
measurement behind :data:`masonry_dem.solvers.factorization.PARALLEL_FROM`, the size from
which PARDISO takes more than one thread.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numba
import numpy as np
from _machine import arguments, print_machine

from masonry_dem import set_thread_wait_policy
from masonry_dem.cases.paper import build_case, case_names
from masonry_dem.solvers import factorization
from masonry_dem.solvers.incremental import pushover
from masonry_dem.solvers.static.problem import DiscreteProblem

KEEP = (10, 40)  # which factorizations of each case are kept


def validation_tangents(cases: list[str]) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """(label, entries, indptr, indices) of the tangents number KEEP of each case."""
    kept: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]] = []
    original = DiscreteProblem.factor
    current = [""]

    def factor(self: DiscreteProblem, response, floor=None):
        number = self.factorizations
        if number in KEEP:
            assembler = self.tangent_assembler
            data = assembler.data(self.joint_tangents(response, floor))
            kept.append((f"{current[0]}#{number}", data, assembler.indptr, assembler.indices))
        return original(self, response, floor)

    DiscreteProblem.factor = factor  # type: ignore[method-assign]
    try:
        for name in cases:
            current[0] = name
            case = build_case(name)
            pushover(case.model, case.settings, monitor=case.monitor)
    finally:
        DiscreteProblem.factor = original  # type: ignore[method-assign]
    return kept


def wall_tangent(n: int) -> tuple[str, np.ndarray, np.ndarray, np.ndarray]:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_scale import _dead_load_tangent, default_wall

    solver, data = _dead_load_tangent(default_wall(n))
    assembler = solver.problem.tangent_assembler
    return f"wall {n}", data, assembler.indptr, assembler.indices


def main() -> int:
    set_thread_wait_policy()
    p = arguments(__doc__)
    p.add_argument("--cases", nargs="*", default=None, help="default: every validation case")
    p.add_argument("--walls", nargs="*", type=int, default=[], help="default walls of ~N^2 blocks")
    p.add_argument("--repeat", type=int, default=30)
    p.add_argument("--backends", nargs="+", default=None, help="default: pardiso and superlu")
    args = p.parse_args()
    print_machine()
    # SuperLU runs on one thread whatever the setting: the reference of the single-thread cost
    backends = args.backends or [
        b for b in ("pardiso", "superlu") if b in factorization.installed()
    ]
    tangents = validation_tangents(case_names() if args.cases is None else args.cases)
    tangents += [wall_tangent(n) for n in args.walls]
    threads = (1, 2)
    totals = {(b, t): 0.0 for b in backends for t in threads}
    head = " ".join(f"{b + ' 1/2 thr ms':>24s}" for b in backends)
    print(f"{'tangent':10s} {'DOFs':>5s} {head}  (ratio 2 threads / 1)")
    for label, data, indptr, indices in tangents:
        n = indptr.size - 1
        handles = {}
        for b in backends:
            for t in threads:
                numba.set_num_threads(t)  # a handle keeps the thread count of its analysis
                handles[b, t] = factorization.analyse(indptr, indices, n, b)
                handles[b, t].factor(data)  # the analysis, with the first matrix
        times: dict[tuple[str, int], list[float]] = {key: [] for key in handles}
        for _ in range(args.repeat):
            for (b, t), handle in handles.items():
                numba.set_num_threads(t)
                start = time.perf_counter()
                handle.factor(data)
                times[b, t].append(time.perf_counter() - start)
        numba.set_num_threads(max(threads))
        cells = []
        for b in backends:
            one, two = (float(np.median(times[b, t])) for t in threads)
            totals[b, 1] += one
            totals[b, 2] += two
            cells.append(f"{1e3 * one:7.2f} / {1e3 * two:7.2f} {two / one:5.2f}x")
        print(f"{label:10s} {n:5d} " + " ".join(f"{c:>24s}" for c in cells))
    print("total ms (sum of the medians), 1 / 2 threads:")
    for b in backends:
        one, two = totals[b, 1], totals[b, 2]
        print(f"  {b:8s} {1e3 * one:8.1f} / {1e3 * two:8.1f}  ratio {two / one:.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
