"""Benchmark: where one time step of the dynamic relaxation goes; compiled steps against Python.

Where one time step of the dynamic relaxation goes, and the compiled time steps against
the Python loop.

Run:  NUMBA_NUM_THREADS=1 python benchmarks/bench_time_step.py [--walls U S23] [--repeat 3]

Runs the pushover of the U wall of ``bench_walls_that_meet.py`` (S5, no side supports) and of
the validation case S23, whose corner checks relax the wall (``Relaxation._relax``), and
splits the seconds spent inside ``_relax`` into

- ``forces``: the calls of the interface law (``Relaxation._forces``, the numba kernel);
- ``probe``: the Newton probes at kinetic-energy peaks (not a cost of the time step);
- ``rest``: everything else of a time step (numpy vector operations and Python bookkeeping).

It prints the seconds per time step of each and the share of ``rest`` in a time step
(forces + rest) for the Python loop (``DRSettings.compiled_steps=False``; the timers add
about a microsecond per call: the rest is an upper bound), then the compiled time steps
(``compiled_steps=True``, the default: forces and rest in one call, not split) against it,
the two alternated ``--repeat`` times in one run (the best of each): seconds per time step in
``_relax`` (probes excluded) and of the whole pushover, and their ratios. Both must give the
same lambda and time steps (the same bits): it says so.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.dynamic_relaxation import integrator
from masonry_dem.solvers.incremental import StaticSolver, pushover

sys.path.insert(0, str(Path(__file__).parent))
from _machine import arguments, print_machine
from bench_walls_that_meet import build, walls  # noqa: E402

Relaxation = integrator.Relaxation


class Timers:
    def __init__(self) -> None:
        self.relax = self.forces = self.probe = 0.0
        self.steps = self.calls = 0


def instrument(t: Timers, compiled: bool):
    """Wrap Relaxation._relax, _forces and the probe with timers, and set
    ``compiled_steps``; returns the undo."""
    relax, forces, init = Relaxation._relax, Relaxation._forces, Relaxation.__init__

    def set_loop(self, model, settings=None):
        init(self, model, settings)
        self.settings = dataclasses.replace(self.settings, compiled_steps=compiled)

    def timed_forces(self, *args):
        t0 = time.perf_counter()
        out = forces(self, *args)
        t.forces += time.perf_counter() - t0
        t.calls += 1
        return out

    def timed_relax(self, *args, probe=None, **kw):
        def timed_probe(x):
            t0 = time.perf_counter()
            ok = probe(x)
            t.probe += time.perf_counter() - t0
            return ok

        steps0 = self.stats.time_steps
        t0 = time.perf_counter()
        out = relax(self, *args, probe=timed_probe if probe is not None else None, **kw)
        t.relax += time.perf_counter() - t0
        t.steps += self.stats.time_steps - steps0
        return out

    Relaxation._relax, Relaxation._forces = timed_relax, timed_forces
    Relaxation.__init__ = set_loop

    def undo() -> None:
        Relaxation._relax, Relaxation._forces, Relaxation.__init__ = relax, forces, init

    return undo


def run(name: str, compiled: bool) -> tuple[Timers, float, float | None]:
    if name == "U":
        model, _ = build(walls("S5")[0], held=False)
        t = Timers()
        undo = instrument(t, compiled)
        t0 = time.perf_counter()
        h = StaticSolver(model).run()
    else:
        case = build_case(name)
        t = Timers()
        undo = instrument(t, compiled)
        t0 = time.perf_counter()
        h = pushover(case.model, case.settings, monitor=case.monitor)
    seconds = time.perf_counter() - t0
    undo()
    return t, seconds, h.collapse_multiplier


def main(argv=None) -> int:
    parser = arguments(__doc__)
    parser.add_argument("--walls", nargs="+", default=["U", "S23"])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    print_machine()
    for name in args.walls:  # compile the kernels (both loops) before timing
        run(name, True)
        run(name, False)
    print("Python loop (compiled_steps=False), split:")
    print(
        f"{'wall':>5} {'pushover s':>10} {'lambda':>8} {'time steps':>10} {'in _relax s':>11} "
        f"{'forces us':>9} {'rest us':>8} {'probe s':>8} {'rest %':>7}"
    )
    best: dict[tuple[str, bool], list[float]] = {}
    answers: dict[tuple[str, bool], tuple[int, float | None]] = {}
    for name in args.walls:
        for r in range(args.repeat):
            for compiled in (False, True):  # alternated: both see the same load
                t, seconds, lam = run(name, compiled)
                n = max(t.steps, 1)
                step = (t.relax - t.probe) / n
                old = best.get((name, compiled), [float("inf")] * 2)
                best[name, compiled] = [min(old[0], step), min(old[1], seconds)]
                answers[name, compiled] = (t.steps, lam)
                if not compiled and r == 0:
                    rest = t.relax - t.forces - t.probe
                    share = rest / max(rest + t.forces, 1e-30)
                    print(
                        f"{name:>5} {seconds:10.2f} {lam or float('nan'):8.4f} {t.steps:10d} "
                        f"{t.relax:11.2f} {1e6 * t.forces / n:9.1f} {1e6 * rest / n:8.1f} "
                        f"{t.probe:8.2f} {100 * share:6.1f}%"
                    )
    print(f"compiled against Python loop, best of {args.repeat} alternated runs:")
    print(
        f"{'wall':>5} {'step us py':>10} {'step us nb':>10} {'ratio':>6} {'pushover py':>11} "
        f"{'pushover nb':>11} {'ratio':>6} {'same':>5}"
    )
    for name in args.walls:
        py, nb = best[name, False], best[name, True]
        same = answers[name, False] == answers[name, True]
        print(
            f"{name:>5} {1e6 * py[0]:10.1f} {1e6 * nb[0]:10.1f} {py[0] / nb[0]:6.2f} "
            f"{py[1]:11.2f} {nb[1]:11.2f} {py[1] / nb[1]:6.2f} {str(same):>5}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
