"""The command line in a child process, as a user's shell starts it: ``python -m
masonry_dem.cli`` with this tree's sources and one numba thread, its output captured."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def child_env() -> dict[str, str]:
    """The environment of a child process: this tree's sources, one numba thread."""
    return {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_NUM_THREADS": "1"}


def start_python(*args: str | Path) -> subprocess.Popen:
    """Start ``python ARGS`` (text pipes for stdout and stderr)."""
    return subprocess.Popen(
        [sys.executable, *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(),
    )


def start_cli(*args: str | Path) -> subprocess.Popen:
    """Start ``masonry-dem ARGS`` (text pipes for stdout and stderr)."""
    return start_python("-m", "masonry_dem.cli", *args)


def run_cli(
    *args: str | Path, timeout: float = 300, preexec_fn: Callable[[], None] | None = None
) -> subprocess.CompletedProcess:
    """Run ``masonry-dem ARGS`` to its end (output captured as text)."""
    return subprocess.run(
        [sys.executable, "-m", "masonry_dem.cli", *map(str, args)],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=timeout,
        preexec_fn=preexec_fn,
    )
