"""Benchmark: the time `masonry-dem run` says before it starts against the time it takes.

Run:  python benchmarks/bench_estimate.py [CASE]

Runs the bundled default wall (or CASE) from this tree's ``src`` in a fresh process, first
with NUMBA_CACHE_DIR on an empty folder (cold: every kernel compiles), then again on that
folder (warm), and prints for each the estimate line and the wall seconds from that line to
the end of the command (what the estimate covers), with the load average.
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


def timed(case: str | None, cache: Path, out: Path) -> tuple[str, float]:
    """The estimate line of one run and the seconds from it to the end of the command."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT / "src"))
    cmd = [sys.executable, "-m", "masonry_dem.cli", "run", *([case] if case else [])]
    cmd += ["--out", str(out), "--overwrite"]
    proc = subprocess.Popen(
        cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    assert proc.stderr is not None
    line, seen = "", time.perf_counter()
    for text in proc.stderr:
        if text.startswith("estimate:"):
            line, seen = text.strip(), time.perf_counter()
    if proc.wait() != 0:
        raise SystemExit(f"{' '.join(cmd)} failed (exit code {proc.returncode})")
    return line, time.perf_counter() - seen


def main() -> None:
    p = arguments(__doc__)
    p.add_argument("case", nargs="?")
    args = p.parse_args()
    print_machine()
    with tempfile.TemporaryDirectory() as tmp:
        cache = Path(tmp) / "numba_cache"
        cache.mkdir()
        for name in ("cold", "warm"):
            line, seconds = timed(args.case, cache, Path(tmp) / name)
            load = os.getloadavg()[0]
            print(f"{name}: {line}\n  took {seconds:.1f} s after that line (load {load:.1f})")


if __name__ == "__main__":
    main()
