"""Where the seconds of one static pushover go, part by part.

    NUMBA_NUM_THREADS=1 python benchmarks/profile_pushover.py --scale 30 [--case S11]
        [--set name=value ...] [--repeat 3] [--bound]

Runs the default pushover (``StaticSolver(model, settings).run()``, after a small warm-up
wall so that no kernel is compiled inside the run) with the methods of each part wrapped by
a timer, and prints, per part, its calls (the outermost ones), its own seconds (the time
inside its methods less the time of the other parts they called), its share of the run and
its milliseconds per call:

* ``factorization``: the numeric factorizations of the backend (``Factorizer.factor``,
  ``factor_laid_out``);
* ``solve``: the solves with the factors;
* ``tangent assembly``: the fixed-pattern sum of H^T T H (``TangentAssembler.data``, and
  ``update``, which works out only the joints whose tangent changed);
* ``joint tangents``: the law's consistent tangent of each joint (``InterfaceLaw.tangent``);
* ``residual``: R(q, lambda) (the law's return of every joint, the assembly of the forces);
* ``certificate``: the checks of the collapse (``certify``);
* ``bound``: with ``--bound``, the associative limit-analysis bound the certificate checks
  lambda against, computed when the certificate asks for it (``LazyBound``, as ``masonry-dem
  run`` does);
* ``damped motion``: the instability rule's motions where Newton finds no equilibrium
  (their factorizations and residuals are counted in the parts above);
* ``recording``: a converged state made a step of the History (the plastic part, the
  utilisation of every joint);
* ``other``: the rest (the Python of the searches and the path followers).

The seconds depend on the machine's load; compare runs only as ratios within one run, and
read the calls, which do not. ``--repeat`` keeps the fastest run.
"""

from __future__ import annotations

import sys
import time
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

from _machine import arguments, print_machine

sys.path.insert(0, str(Path(__file__).resolve().parent))


def _parts() -> dict[str, list[tuple[object, str]]]:
    """(owner, method name) of each part; the owner is a class or a module."""
    from masonry_dem.constitutive.law import InterfaceLaw
    from masonry_dem.run_case import LazyBound
    from masonry_dem.solvers import factorization as fz
    from masonry_dem.solvers.static import solver as solver_module
    from masonry_dem.solvers.static.problem import DiscreteProblem, TangentAssembler

    factorizers = [fz._SuperLU, fz._Pardiso, fz._Umfpack, fz._Mumps, fz._CSCOrder]
    factors = [fz._HeldFactors, fz._SuperLUFactors, fz._UmfpackFactors, fz._Pardiso]
    return {
        "factorization": [(c, m) for c in factorizers for m in ("factor", "factor_laid_out")],
        "solve": [(c, "solve") for c in factors],
        "tangent assembly": [(TangentAssembler, "data"), (TangentAssembler, "update")],
        "joint tangents": [(InterfaceLaw, "tangent")],
        "residual": [(DiscreteProblem, "residual")],
        "certificate": [(solver_module, "certify")],
        "bound": [(LazyBound, "__call__")],
        "damped motion": [(solver_module.StaticSolver, "damped_motion")],
        "recording": [(solver_module.StaticSolver, "accept")],
    }


class Timer:
    """Own seconds and outermost calls per part, by wrapping the parts' methods."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._stack: list[list] = []  # [part, start, seconds of the parts it called]
        self._undo: list[tuple[object, str, object]] = []

    def wrap(self, parts: dict[str, list[tuple[object, str]]]) -> None:
        for part, methods in parts.items():
            for owner, name in methods:
                inner = owner.__dict__.get(name) if isinstance(owner, type) else None
                if isinstance(owner, type) and inner is None:
                    continue  # inherited: the owner that defines it is wrapped
                inner = getattr(owner, name)
                self._undo.append((owner, name, inner))
                setattr(owner, name, self._timed(part, inner))

    def unwrap(self) -> None:
        for owner, name, inner in reversed(self._undo):
            setattr(owner, name, inner)
        self._undo.clear()

    def _timed(self, part: str, inner):
        def call(*args, **kwargs):
            outer = not any(frame[0] == part for frame in self._stack)
            frame = [part, time.perf_counter(), 0.0]
            self._stack.append(frame)
            try:
                return inner(*args, **kwargs)
            finally:
                self._stack.pop()
                spent = time.perf_counter() - frame[1]
                self.seconds[part] += spent - frame[2]
                if self._stack:
                    self._stack[-1][2] += spent
                if outer:
                    self.calls[part] += 1

        return call


def profile(model, settings, monitor=None, bound: bool = False) -> dict:
    from masonry_dem.run_case import LazyBound
    from masonry_dem.solvers.static import StaticSolver

    timer = Timer()
    timer.wrap(_parts())
    try:
        solver = StaticSolver(model, settings, bound=LazyBound() if bound else None)
        t0, c0 = time.perf_counter(), time.process_time()
        hist = solver.run(monitor=monitor)
        seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    finally:
        timer.unwrap()
    parts = dict(timer.seconds)
    parts["other"] = seconds - sum(parts.values())
    return {
        "lambda": hist.collapse_multiplier
        if hist.collapse_multiplier is not None
        else hist.final_load_factor,
        "status": str(hist.status),
        "steps": len(hist.steps),
        "iterations": solver.iterations,
        "factorizations": solver.factorizations,
        "seconds": seconds,
        "cpu": cpu,
        "parts": parts,
        "calls": dict(timer.calls),
    }


def main() -> int:
    p = arguments(__doc__)
    p.add_argument("--scale", type=int, action="append", default=[], help="scale_wall(N)")
    p.add_argument("--case", action="append", default=[], help="a validation case")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--repeat", type=int, default=1, help="runs of each; the fastest is kept")
    p.add_argument("--bound", action="store_true", help="the certificate checks the LA bound")
    a = p.parse_args()
    print_machine()

    from bench_scale import scale_wall
    from bench_validation import parse_settings

    from masonry_dem.cases.paper import build_case
    from masonry_dem.solvers.static import StaticSettings, StaticSolver

    changes = parse_settings(a.set)
    walls = [(f"scale_wall({n})", scale_wall(n), StaticSettings(), None) for n in a.scale]
    for name in a.case:
        case = build_case(name)
        walls.append((name, case.model, case.settings, case.monitor))
    StaticSolver(scale_wall(6)).run()  # the kernels compiled or loaded before any run
    for label, model, settings, monitor in walls:
        settings = replace(settings, **changes) if changes else settings
        runs = [profile(model, settings, monitor, a.bound) for _ in range(a.repeat)]
        r = min(runs, key=lambda run: run["seconds"])
        print(
            f"{label}: {r['status']} lambda={r['lambda']:.7g} steps={r['steps']} "
            f"iterations={r['iterations']} factorizations={r['factorizations']} "
            f"{r['seconds']:.2f} s ({r['cpu']:.2f} s of CPU; fastest of {a.repeat})"
        )
        print(f"  {'part':18s} {'calls':>6s} {'seconds':>8s} {'share':>6s} {'ms a call':>9s}")
        for part, spent in sorted(r["parts"].items(), key=lambda kv: -kv[1]):
            calls = r["calls"].get(part, 0)
            each = f"{1e3 * spent / calls:9.3f}" if calls else f"{'':9s}"
            print(f"  {part:18s} {calls:6d} {spent:8.3f} {spent / r['seconds']:6.1%} {each}")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
