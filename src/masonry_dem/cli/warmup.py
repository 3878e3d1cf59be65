"""``masonry-dem warmup``: compile the numba kernels once, ahead of the first analysis."""

from __future__ import annotations

import argparse


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "warmup",
        help="compile the compiled kernels now (once per machine) instead of in the first run",
        description="Compile the kernels of the interface law and the tangent assembly into "
        "numba's disk cache (NUMBA_CACHE_DIR, or __pycache__ beside the package), so that the "
        "first analysis starts at once. Both variants by default: the serial one (walls below "
        "300 interfaces) and the parallel one (larger walls).",
    )
    p.add_argument(
        "--variant",
        choices=("all", "serial", "parallel"),
        default="all",
        help="which variants to compile (default: all)",
    )
    p.add_argument(
        "--processes", type=int, default=2, help="compile on this many cores (1 or 2; default 2)"
    )
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from masonry_dem import jit
    from masonry_dem.solvers.warmup import compile_kernels

    variants = ("serial", "parallel") if args.variant == "all" else (args.variant,)
    for variant in variants:
        parallel = variant == "parallel"
        pending = jit.compile_pending(parallel, lazy=True)
        if not pending:
            print(f"{variant} kernels: cached")
            continue
        estimate = jit.compile_estimate(parallel, lazy=True)
        estimate *= jit.SIDE_BY_SIDE if args.processes > 1 else 1
        print(f"{variant} kernels: compiling {len(pending)}, about {estimate:.0f} s", flush=True)
        seconds = compile_kernels(parallel, processes=args.processes, lazy=True)
        print(f"{variant} kernels: compiled in {seconds:.1f} s")
    return 0
