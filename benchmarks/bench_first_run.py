"""Benchmark: the first `masonry-dem run` on a machine (empty numba cache) against a warm one.

Run:  python benchmarks/bench_first_run.py [--ref 5133bd5] [--python /tmp/fresh/bin/python ...]
                                           [--repeat 2] [--case CASE]

Each tree runs the bundled default wall (or CASE) in fresh processes: first with
NUMBA_CACHE_DIR on an empty folder (cold: every kernel compiles), then again on that folder
(warm), ``--repeat`` times each in turn, keeping the fastest. It prints per tree the wall
seconds of the whole command (interpreter start, imports, compilation, analysis, files,
renders), the compilation's share and the ratio cold / warm, and with ``--ref`` the same for
that commit (checked out into a temporary git worktree), in one run, so the machine's load is
the same for both. ``--python`` (repeatable) also runs the package installed for another
interpreter (a fresh venv: ``python3 -m venv /tmp/fresh && /tmp/fresh/bin/pip install .``),
whose kernels were compiled when it was built (setup.py): its cold run is the first run on a
fresh install; this tree's ``src`` on PYTHONPATH has no kernels compiled at build and compiles
them. Give the venv of an older commit too to compare installations in the same run.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import arguments, print_machine

ROOT = Path(__file__).resolve().parents[1]


def _run(python: str, src: Path | None, cache: Path, out: Path, case: str | None) -> float:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env.pop("PYTHONPATH", None)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    cmd = [python, "-m", "masonry_dem.cli", "run", *([case] if case else [])]
    cmd += ["--out", str(out), "--overwrite", "--quiet"]
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return time.perf_counter() - t0


def main() -> int:
    p = arguments(__doc__)
    p.add_argument("--ref", default=None, help="a commit to compare with (hash, tag, branch)")
    p.add_argument(
        "--python", action="append", default=[], help="interpreter with the package installed"
    )
    p.add_argument("--repeat", type=int, default=1, help="cold and warm runs per tree")
    p.add_argument("--case", default=None, help="case file (default: the bundled wall)")
    args = p.parse_args()
    print_machine()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        trees: dict[str, tuple[str, Path | None]] = {}
        if args.ref:
            worktree = base / "ref"
            subprocess.run(
                [
                    "git",
                    "-C",
                    str(ROOT),
                    "worktree",
                    "add",
                    "--detach",
                    "-q",
                    str(worktree),
                    args.ref,
                ],
                check=True,
            )
            trees[args.ref[:10]] = (sys.executable, worktree / "src")
        trees["this tree (src)"] = (sys.executable, ROOT / "src")
        for python in args.python:
            trees[f"installed: {python}"] = (python, None)
        try:
            best: dict[str, dict[str, float]] = {name: {} for name in trees}
            for r in range(args.repeat):
                for k, (name, (python, src)) in enumerate(trees.items()):
                    cache = base / f"cache-{k}-{r}"  # empty: the cold run compiles
                    cache.mkdir()
                    out = base / f"out-{k}"
                    cold = _run(python, src, cache, out, args.case)
                    warm = _run(python, src, cache, out, args.case)
                    row = best[name]
                    row["cold"] = min(row.get("cold", cold), cold)
                    row["warm"] = min(row.get("warm", warm), warm)
            width = max(len(name) for name in trees)
            print(
                f"{'tree':{width}s} {'cold s':>8s} {'warm s':>8s} {'compile s':>10s} "
                f"{'cold/warm':>10s}"
            )
            for name, row in best.items():
                cold, warm = row["cold"], row["warm"]
                print(
                    f"{name:{width}s} {cold:8.1f} {warm:8.1f} {cold - warm:10.1f} {cold / warm:9.2f}x"
                )
        finally:
            if args.ref:
                subprocess.run(
                    ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base / "ref")],
                    check=False,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
