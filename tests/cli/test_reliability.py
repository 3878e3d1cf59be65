"""Issue 39, through the command line: nothing outside a results folder is touched, counts
and inputs are refused before anything is allocated, an interrupted or killed run leaves a
folder the tools read."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from helpers.case_files import SINGLE_BLOCK, write_case

ROOT = Path(__file__).resolve().parents[2]


def _cli(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "NUMBA_NUM_THREADS": "1"}
    return subprocess.run(
        [sys.executable, "-m", "masonry_dem.cli", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
    )


def _vtus(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.glob("*.vtu"))}


def test_overwrite_never_reaches_through_a_linked_steps_folder(tmp_path):
    case = write_case(tmp_path, SINGLE_BLOCK)
    other = tmp_path / "other"
    assert _cli("run", str(case), "--out", str(other), "--no-render", "--quiet").returncode == 0
    kept = _vtus(other / "steps")
    assert kept
    out = tmp_path / "out"
    out.mkdir()
    (out / "steps").symlink_to(other / "steps")

    refused = _cli("run", str(case), "--out", str(out), "--no-render", "--quiet")
    assert refused.returncode == 2
    assert "is a symbolic link" in refused.stderr and "Traceback" not in refused.stderr
    assert _vtus(other / "steps") == kept

    done = _cli("run", str(case), "--out", str(out), "--no-render", "--quiet", "--overwrite")
    assert done.returncode == 0, done.stderr
    assert _vtus(other / "steps") == kept  # the other run's steps are whole
    assert not (out / "steps").is_symlink() and _vtus(out / "steps")
