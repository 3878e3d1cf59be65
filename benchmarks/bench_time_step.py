"""Where one time step of the dynamic relaxation goes: the interface law against the rest.

Run:  NUMBA_NUM_THREADS=1 python benchmarks/bench_time_step.py [--walls U S23]

Runs the pushover of the U wall of ``bench_walls_that_meet.py`` (S5, no side supports) and of
the validation case S23, whose corner checks relax the wall (``Relaxation._relax``), and
splits the seconds spent inside ``_relax`` into

- ``forces``: the calls of the interface law (``Relaxation._forces``, the numba kernel);
- ``probe``: the Newton probes at kinetic-energy peaks (not a cost of the time step);
- ``rest``: everything else of a time step (numpy vector operations and Python bookkeeping).

It prints the seconds per time step of each and the share of ``rest`` in a time step
(forces + rest). The timers add about a microsecond per call: the rest is an upper bound.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from masonry_dem.cases.paper import build_case
from masonry_dem.solvers.dynamic_relaxation import integrator
from masonry_dem.solvers.incremental import StaticSolver, pushover

sys.path.insert(0, str(Path(__file__).parent))
from bench_walls_that_meet import build, walls  # noqa: E402

Relaxation = integrator.Relaxation


class Timers:
    def __init__(self) -> None:
        self.relax = self.forces = self.probe = 0.0
        self.steps = self.calls = 0


def instrument(t: Timers):
    """Wrap Relaxation._relax, _forces and the probe with timers; returns the undo."""
    relax, forces = Relaxation._relax, Relaxation._forces

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

    def undo() -> None:
        Relaxation._relax, Relaxation._forces = relax, forces

    return undo


def run(name: str) -> tuple[Timers, float, float | None]:
    if name == "U":
        model, _ = build(walls("S5")[0], held=False)
        t = Timers()
        undo = instrument(t)
        t0 = time.perf_counter()
        h = StaticSolver(model).run()
    else:
        case = build_case(name)
        t = Timers()
        undo = instrument(t)
        t0 = time.perf_counter()
        h = pushover(case.model, case.settings, monitor=case.monitor)
    seconds = time.perf_counter() - t0
    undo()
    return t, seconds, h.collapse_multiplier


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--walls", nargs="+", default=["U", "S23"])
    args = parser.parse_args(argv)
    run("U")  # compile the kernels before timing
    print(
        f"{'wall':>5} {'pushover s':>10} {'lambda':>8} {'time steps':>10} {'in _relax s':>11} "
        f"{'forces us':>9} {'rest us':>8} {'probe s':>8} {'rest %':>7}"
    )
    for name in args.walls:
        t, seconds, lam = run(name)
        n = max(t.steps, 1)
        rest = t.relax - t.forces - t.probe
        share = rest / max(rest + t.forces, 1e-30)
        print(
            f"{name:>5} {seconds:10.2f} {lam or float('nan'):8.4f} {t.steps:10d} {t.relax:11.2f} "
            f"{1e6 * t.forces / n:9.1f} {1e6 * rest / n:8.1f} {t.probe:8.2f} {100 * share:6.1f}%"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
