"""The command line in a child process, as a user's shell starts it: ``python -m
masonry_dem.cli`` with this tree's sources and one numba thread, its output captured."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def start_cli(*args: str | Path) -> subprocess.Popen:
    """Start ``masonry-dem ARGS`` (text pipes for stdout and stderr)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_NUM_THREADS": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "masonry_dem.cli", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
