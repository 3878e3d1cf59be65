"""Benchmark: which numba kernels a `masonry-dem run` compiles on an empty cache, and how long.

Run:  python benchmarks/bench_compile.py [CASE]       (PYTHONPATH=OTHER/src for another tree)

Points NUMBA_CACHE_DIR at an empty temporary folder, then runs the command in this process
with a listener on numba's compile events, and prints each top-level compilation (its
callees included) with its seconds, the run's total and the compilation's share. With this
tree the compilation happens before the analysis, in this process and a second one
(``solvers/warmup.py``): the second one's kernels are loaded from the cache here and do not
appear; the line "prepare" gives the whole warm-up's wall time.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from collections import defaultdict

from _machine import arguments, print_machine


def main() -> int:
    p = arguments(__doc__)
    p.add_argument(
        "case", nargs="?", help="a bundled case or case file (default: the default wall)"
    )
    p.parse_known_args()  # anything else goes on to `masonry-dem run`
    with tempfile.TemporaryDirectory() as cache:
        os.environ["NUMBA_CACHE_DIR"] = cache  # before numba is imported
        print_machine()  # reads versions without importing numba
        from numba.core import event

        seconds: dict[str, float] = defaultdict(float)

        class Listener(event.Listener):  # type: ignore[misc]
            def __init__(self) -> None:
                self.stack: list[tuple[float, str]] = []

            def on_start(self, ev: event.Event) -> None:
                name = ev.data["dispatcher"].py_func.__qualname__
                self.stack.append((time.perf_counter(), name))

            def on_end(self, ev: event.Event) -> None:
                t0, name = self.stack.pop()
                if not self.stack:  # top level: callees included
                    seconds[name] += time.perf_counter() - t0

        event.register("numba:compile", Listener())
        t0 = time.perf_counter()
        from masonry_dem.cli import main as cli

        try:
            from masonry_dem.solvers import warmup

            prepare = warmup.prepare

            def timed(interfaces: int, processes: int = 2) -> float:
                t = time.perf_counter()
                out = prepare(interfaces, processes)
                seconds["prepare (whole warm-up)"] = time.perf_counter() - t
                return out

            warmup.prepare = timed  # type: ignore[assignment]
        except ImportError:  # a tree without the warm-up
            pass
        out = os.path.join(cache, "out")
        cli(["run", *sys.argv[1:], "--out", out, "--quiet"])
        total = time.perf_counter() - t0
    compiled = sum(v for k, v in seconds.items() if not k.startswith("prepare"))
    for name, s in sorted(seconds.items(), key=lambda kv: -kv[1]):
        print(f"{s:7.2f} s  {name}")
    print(f"{compiled:7.2f} s  compiled in this process, of {total:.2f} s in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
