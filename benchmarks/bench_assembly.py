"""Benchmark: contact detection and assembly of running-bond walls, 10^2 to 10^5 blocks.

Run:  python benchmarks/bench_assembly.py [--sizes 100 1000 10000 100000] [--repeat 3]

For each size it builds a roughly square running-bond wall (half blocks at the ends) on a
fixed base slab and times, best of ``--repeat`` runs:

- ``detect``: contact detection (``detect_interfaces``),
- ``model``:  ``Model.build`` with the detected interfaces (supports, loads, mechanism check),
- ``H``:      the compatibility matrix and its free-DOF columns (``Assembly.of``),
- ``K``:      K = H_f^T Kbar H_f on the free DOFs (``Assembly.stiffness``),
- ``total``:  detect + model + H + K,

then, in a separate run under ``tracemalloc`` (so tracing does not slow the timed runs), the
peak memory allocated by the whole pipeline. It ends with the log-log slope of time against
the number of blocks (least squares over all sizes, and over the largest decade) and checks
the targets of issue 2: slope <= 1.15 and 10^5 blocks assembled in under 10 s.
``--check`` makes the exit status 1 when a target is missed.
"""

from __future__ import annotations

import gc
import platform
import sys
import time
import tracemalloc

import numpy as np
from _machine import arguments, print_machine

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support

A, B, S, GAMMA = 0.055, 0.25, 0.12, 18_000.0
MATERIAL = InterfaceMaterial(kn=1.0e10, kt=4.0e9, friction=0.6)
SLOPE_TARGET = 1.15
TIME_TARGET = 10.0  # seconds for 10^5 blocks
STAGES = ("detect", "model", "H", "K")


def wall_shape(n_blocks: int) -> tuple[int, int]:
    """Blocks per course and courses of a running-bond wall of about ``n_blocks`` blocks,
    about as high as long (courses alternate n and n + 1 blocks)."""
    per_course = max(1, round(np.sqrt(n_blocks * A / B)))
    courses = max(1, round(n_blocks / (per_course + 0.5)))
    return per_course, courses


def pipeline(n_blocks: int) -> tuple[dict[str, float], dict[str, int]]:
    """One run: stage times [s] and sizes."""
    per_course, courses = wall_shape(n_blocks)
    blocks, base = add_base(running_bond_wall(per_course, courses, A, B, S, GAMMA))
    t0 = time.perf_counter()
    its = detect_interfaces(blocks)
    t1 = time.perf_counter()
    model = Model.build(blocks, MATERIAL, [Support([base])], [SelfWeight()], interfaces=its)
    t2 = time.perf_counter()
    asm = Assembly.of(model)
    t3 = time.perf_counter()
    K = asm.stiffness()
    t4 = time.perf_counter()
    t = {"detect": t1 - t0, "model": t2 - t1, "H": t3 - t2, "K": t4 - t3}
    sizes = {
        "blocks": blocks.count,
        "interfaces": its.count,
        "dofs": asm.n_free,
        "nnz_K": int(K.nnz),
    }
    return t, sizes


def measure(n_blocks: int, repeat: int) -> dict:
    best: dict[str, float] = {}
    sizes: dict[str, int] = {}
    for _ in range(repeat):
        gc.collect()
        t, sizes = pipeline(n_blocks)
        best = t if not best else {k: min(best[k], t[k]) for k in t}
    gc.collect()
    tracemalloc.start()
    pipeline(n_blocks)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    total = sum(best.values())
    return {"requested": n_blocks, **sizes, **best, "total": total, "peak_mb": peak / 2**20}


def slope(x, y) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def main(argv: list[str] | None = None) -> int:
    parser = arguments(__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1_000, 10_000, 100_000])
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per size (best kept)")
    parser.add_argument("--check", action="store_true", help="exit 1 if a target is missed")
    args = parser.parse_args(argv)
    print_machine()

    pipeline(100)  # warm up imports and caches
    print(
        f"masonry_dem assembly benchmark: running-bond wall on a fixed base, "
        f"a x b x s = {A} x {B} x {S} m; Python {platform.python_version()}, "
        f"numpy {np.__version__}, best of {args.repeat}"
    )
    head = (
        f"{'blocks':>8} {'interf.':>8} {'free DOFs':>9} {'nnz(K)':>9} "
        f"{'detect s':>9} {'model s':>8} {'H s':>7} {'K s':>7} {'total s':>8} {'peak MB':>8}"
    )
    print(head)
    print("-" * len(head))
    rows = []
    for n in args.sizes:
        r = measure(n, args.repeat)
        rows.append(r)
        print(
            f"{r['blocks']:>8d} {r['interfaces']:>8d} {r['dofs']:>9d} {r['nnz_K']:>9d} "
            f"{r['detect']:>9.4f} {r['model']:>8.4f} {r['H']:>7.4f} {r['K']:>7.4f} "
            f"{r['total']:>8.4f} {r['peak_mb']:>8.1f}",
            flush=True,
        )

    ok = True
    if len(rows) >= 2:
        blocks = [r["blocks"] for r in rows]
        print("\nlog-log slope of time vs blocks (all sizes | largest decade):")
        for key in ("detect", "model", "H", "K", "total", "peak_mb"):
            ys = [max(r[key], 1e-9) for r in rows]
            print(f"  {key:>8}: {slope(blocks, ys):5.2f} | {slope(blocks[-2:], ys[-2:]):5.2f}")
        s_all = slope(blocks, [r["total"] for r in rows])
        s_top = slope(blocks[-2:], [r["total"] for r in rows][-2:])
        worst = max(s_all, s_top)
        ok &= worst <= SLOPE_TARGET
        print(
            f"target slope <= {SLOPE_TARGET}: total {s_all:.2f} (all), {s_top:.2f} "
            f"(largest decade) -> {'met' if worst <= SLOPE_TARGET else 'MISSED'}"
        )
    big = [r for r in rows if r["requested"] >= 100_000]
    if big:
        t_big = big[0]["total"]
        ok &= t_big < TIME_TARGET
        print(
            f"target 10^5 blocks < {TIME_TARGET:.0f} s: {t_big:.2f} s "
            f"({big[0]['blocks']} blocks) -> {'met' if t_big < TIME_TARGET else 'MISSED'}"
        )
    return 0 if ok or not args.check else 1


if __name__ == "__main__":
    sys.exit(main())
