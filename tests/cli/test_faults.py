"""Faults around a results folder (issue 24): SIGINT and SIGTERM stop a run as
``interrupted`` with both PVDs listing the same whole steps; a folder left by SIGKILL is
named unfinished by the next command; a second run into a folder is refused; a full disk and
a read-only folder end in one line naming the path, with only whole files kept. On 7022155
each of these either left no summary, collided, or raised a traceback."""

from __future__ import annotations

import errno
import json
import logging
import os
import signal
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from helpers.case_files import write_case as _write_case
from helpers.cli_process import run_cli, start_cli
from masonry_dem.cli import main
from masonry_dem.export import results_folder as rf

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "src" / "masonry_dem" / "cases" / "data" / "default_wall.toml"


def _slow_case(tmp_path: Path) -> Path:
    """The default wall with lambda steps of 0.0005: several hundred steps, a few seconds.
    (Work control's steps still grow: at a growth of 1 its first, short step creeps up the
    plateau past max_steps.)"""
    text = DEFAULT.read_text().replace(
        "bracket_tolerance = 0.005",
        "bracket_tolerance = 0.005\ninitial_step = 0.0005\nmax_step = 0.0005\ngrowth = 1.2",
    )
    case = tmp_path / "slow.toml"
    case.write_text(text)
    return case


def _pvd_files(path: Path) -> list[str]:
    return [d.get("file") for d in ET.parse(path).getroot().iter("DataSet")]


def _start(case: Path, out: Path) -> subprocess.Popen:
    return start_cli("run", case, "--out", out, "--no-render", "--quiet")


def _wait_for_steps(proc: subprocess.Popen, out: Path, steps: int = 5) -> None:
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            pytest.fail(f"the run ended before the signal: {proc.communicate()}")
        try:
            if len(_pvd_files(out / "blocks.pvd")) >= steps:
                return
        except (FileNotFoundError, ET.ParseError):
            pass
        time.sleep(0.05)
    proc.kill()
    pytest.fail("the run wrote no steps in 300 s")


def _assert_whole(out: Path, killed: bool = False) -> list[str]:
    """Both PVDs list the same steps (after SIGKILL between their two renames, interfaces.pvd
    may be one step ahead, never behind), every listed VTU is a whole file; no temporary."""
    blocks, interfaces = _pvd_files(out / "blocks.pvd"), _pvd_files(out / "interfaces.pvd")
    assert len(blocks) > 0
    assert len(interfaces) - len(blocks) in ((0, 1) if killed else (0,))
    for name in blocks + interfaces:
        mesh = meshio.read(out / name)
        assert np.isfinite(mesh.points).all()
    temporary = list(out.glob(".*.tmp")) + list((out / "steps").glob(".*.tmp"))
    assert killed or not temporary  # SIGKILL may leave a hidden temporary, never a real name
    return blocks


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_mid_run_ends_interrupted_with_every_step(tmp_path, signum, code):
    out = tmp_path / "out"
    proc = _start(_slow_case(tmp_path), out)
    _wait_for_steps(proc, out)
    assert json.loads((out / "summary.json").read_text())["status"] == "running"
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    assert "interrupted" in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert signal.Signals(signum).name in summary["reason"]
    blocks = _assert_whole(out)
    assert summary["steps_written"] == len(blocks)
    rows = np.loadtxt(out / "pushover.csv", delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[0] == summary["steps"] >= len(blocks)
    assert rf.state(out).kind == "interrupted"


@pytest.mark.slow
def test_sigkill_leaves_a_folder_the_next_commands_name_unfinished(tmp_path, caplog, capsys):
    out = tmp_path / "out"
    case = _slow_case(tmp_path)
    proc = _start(case, out)
    _wait_for_steps(proc, out)
    proc.kill()
    proc.wait(timeout=60)
    assert json.loads((out / "summary.json").read_text())["status"] == "running"
    assert rf.state(out).kind == "unfinished"
    blocks = _assert_whole(out, killed=True)
    from masonry_dem.export.render import open_results

    series = open_results(out)  # the steps both PVDs list
    assert len(series.block_files) == len(series.interface_files) == len(blocks)
    # a new run is refused, naming the folder unfinished
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"results folder {out} is unfinished" in err and "--overwrite" in err
    # render and paraview-state name it, and still use the whole steps it holds
    with caplog.at_level(logging.WARNING):
        assert main(["render", str(out), "--step", "last", "--size", "320x240"]) == 0
        assert main(["paraview-state", "damage_map", str(out)]) == 0
    named = [r.getMessage() for r in caplog.records if "is unfinished" in r.getMessage()]
    assert len(named) == 2, named
    # --overwrite replaces it, leaving a file that is not the package's own
    (out / "notes.txt").write_text("mine")
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet", "--overwrite"]) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "collapse"
    assert (out / "notes.txt").read_text() == "mine"
    assert not list(out.glob("render_*.png")) and not (out / "damage_map.pvsm").exists()
    assert not list((out / "steps").glob(".*.tmp"))  # the killed run's temporaries too


def _small(tmp_path: Path) -> Path:
    return _write_case(tmp_path, SINGLE_BLOCK)


def test_second_run_into_a_folder_is_refused(tmp_path, capsys):
    case, out = _small(tmp_path), tmp_path / "out"
    args = ["run", str(case), "--out", str(out), "--no-render", "--quiet"]
    assert main(args) == 0
    first = (out / "summary.json").read_text()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "holds a run that ended 'collapse'" in err and "--overwrite" in err
    assert (out / "summary.json").read_text() == first  # untouched


def test_a_folder_in_use_is_refused(tmp_path, capsys):
    """A live run holds the folder's lock: a second process is kept out, whatever it asks."""
    case, out = _small(tmp_path), tmp_path / "out"
    held = rf.claim(out, overwrite=False, start={"name": "other"})
    try:
        rc = main(["run", str(case), "--out", str(out), "--no-render", "--quiet", "--overwrite"])
        assert rc == 2
        assert "is in use by another run" in capsys.readouterr().err
        assert rf.state(out).kind == "running"
    finally:
        held.release()
    assert rf.state(out).kind == "unfinished"  # summary 'running', nobody holds the lock
    assert not (out / rf.LOCK).exists()  # released: no empty lock file left behind
    again = rf.claim(out, overwrite=True, start={"name": "third"})
    try:
        assert rf.state(out).kind == "running"
    finally:
        again.release()


def test_out_naming_a_file_is_one_line(tmp_path, capsys):
    target = tmp_path / "file.txt"
    target.write_text("x")
    assert main(["run", str(_small(tmp_path)), "--out", str(target), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"masonry-dem: error: results folder {target} is a file, not a folder"


def test_full_disk_stops_the_run_with_one_line_and_whole_files(tmp_path, capsys, monkeypatch):
    """ENOSPC simulated on the 4th VTU file (a half-written file, then the error): the run
    stops at the next step, names the path, and keeps only whole files under real names."""
    import masonry_dem.export.vtu as vtu

    real = vtu.meshio.write
    calls = {"n": 0}

    def write(path, mesh, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] >= 4:
            Path(path).write_bytes(b"<VTKFile")  # what a full disk leaves
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, mesh, *args, **kwargs)

    monkeypatch.setattr(vtu.meshio, "write", write)
    case, out = _small(tmp_path), tmp_path / "out"
    rc = main(["run", str(case), "--out", str(out), "--no-render", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "no space left on the device" in err and str(out / "steps") in err
    blocks = _assert_whole(out)
    assert len(blocks) == 1  # step 0 (2 files) whole; step 1's interfaces file failed
    assert sorted(p.name for p in (out / "steps").iterdir()) == [
        "blocks_0000.vtu",
        "blocks_0001.vtu",
        "interfaces_0000.vtu",
    ]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "no space left" in summary["reason"]


def test_read_only_folder_is_one_line(tmp_path, capsys, monkeypatch):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o555)
    try:
        if os.access(out, os.W_OK):  # root writes anyway: the file system's answer, simulated
            real_open = os.open

            def refuse(path, *args, **kwargs):
                if Path(path).parent == out:
                    raise PermissionError(errno.EACCES, "Permission denied", str(path))
                return real_open(path, *args, **kwargs)

            monkeypatch.setattr(rf.os, "open", refuse)
        rc = main(["run", str(_small(tmp_path)), "--out", str(out), "--quiet"])
    finally:
        out.chmod(0o755)
    err = capsys.readouterr().err
    assert rc == 2 and len(err.strip().splitlines()) == 1
    assert str(out) in err and "permission denied" in err


def test_python_api_rerun_replaces_the_previous_run_whole(tmp_path):
    """``pushover(out=...)`` twice into one folder (a script re-run): the second run's folder
    holds its own steps only; 7022155 left the first run's later steps and mechanism beside."""
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.export.analyses import pushover

    out = tmp_path / "api"
    wall = load_case(None)
    first = pushover(wall.model, wall.settings, out=out)
    block = load_case(_small(tmp_path))
    second = pushover(block.model, block.settings, out=out)
    assert len(second.steps) < len(first.steps)
    assert len(_pvd_files(out / "blocks.pvd")) == len(second.steps)
    assert len(list((out / "steps").glob("blocks_*.vtu"))) == len(second.steps)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["name"] == block.model.name and summary["blocks"] == 2
    assert rf.state(out).kind == second.status


def test_concurrent_pvd_writes_use_unique_temporary_names(tmp_path):
    """Two writers of one index never share a temporary file (7022155: a fixed ``.pvd.tmp``
    that the second writer renamed from under the first)."""
    from concurrent.futures import ThreadPoolExecutor

    from masonry_dem.export.pvd import read_pvd, write_pvd

    target = tmp_path / "blocks.pvd"

    def write(k: int) -> None:
        for i in range(50):
            write_pvd(target, [f"steps/b_{k}_{j}.vtu" for j in range(i + 1)], range(i + 1))

    with ThreadPoolExecutor(2) as pool:
        list(pool.map(write, [0, 1]))  # raises if a rename lost its temporary file
    assert len(read_pvd(target)) == 50
    assert not list(tmp_path.glob(".*.tmp"))


def test_ctrl_c_in_another_command_stops_at_once(tmp_path):
    """Commands with no steps to finish (validate here) stop at the first Ctrl-C: one line,
    exit code 130, no traceback (7022155 printed a 60-line numba traceback)."""
    proc = start_cli("validate", "--out", tmp_path / "v", "--no-render", "--quiet")
    deadline = time.monotonic() + 300
    while not list((tmp_path / "v").glob("*/steps/*.vtu")) and time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "masonry-dem: interrupted by SIGINT"
    assert "Traceback" not in err
    kinds = [rf.state(f).kind for f in (tmp_path / "v").iterdir()]
    # the case it was running says so (unless the signal fell between two cases)
    assert kinds and all(k in ("interrupted", "collapse", "completed", "failed") for k in kinds)


@pytest.mark.parametrize("background", [False, True])
def test_a_write_failing_after_the_last_step_marks_the_run_failed(tmp_path, background):
    """The last step's write fails after the solver has returned (the background writer
    still busy): leaving the writer's block records 'failed' and raises, naming the path."""
    import masonry_dem.export.vtu as vtu
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.export.writer import ResultsWriter

    case = load_case(_small(tmp_path))
    writer = ResultsWriter(tmp_path / "w", case.model, background=background)
    from masonry_dem.solvers.incremental import StaticSolver

    history_steps: list = []
    history = StaticSolver(case.model, case.settings).run(callback=history_steps.append)
    real = vtu.meshio.write
    try:
        with pytest.raises(rf.ResultsFolderError, match="no space left on the device"):
            with writer:
                for step in history_steps[:-1]:
                    writer(step)
                writer.flush()
                vtu.meshio.write = _full_disk  # type: ignore[assignment]
                writer(history_steps[-1])
    finally:
        vtu.meshio.write = real  # type: ignore[assignment]
    summary = json.loads((tmp_path / "w" / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["steps"] == len(history.steps)
    assert len(_pvd_files(tmp_path / "w" / "blocks.pvd")) == len(history.steps) - 1
    assert rf.state(tmp_path / "w").kind == "failed"


def _full_disk(path, *args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device", str(path))


def test_a_real_full_disk(tmp_path):
    """On a 64 KiB tmpfs (where the machine lets the tests mount one; the simulated ENOSPC
    above runs everywhere) the run stops with one line naming the file, exit code 2, and
    the folder holds whole files only, its summary saying why."""
    mount = tmp_path / "small"
    mount.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mount)], capture_output=True
    )
    if done.returncode != 0:
        pytest.skip(f"no tmpfs here: {done.stderr.decode().strip()}")
    try:
        out = mount / "out"
        run = run_cli("run", DEFAULT, "--out", out, "--no-render", "--quiet", timeout=600)
        assert run.returncode == 2, run.stderr
        assert run.stderr.strip().splitlines() == [
            line for line in run.stderr.strip().splitlines() if line.startswith("masonry-dem")
        ]
        assert "no space left on the device" in run.stderr and str(out) in run.stderr
        _assert_whole(out)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "failed" and "no space left" in summary["reason"]
    finally:
        subprocess.run(["umount", str(mount)], check=False)


def test_out_inside_a_file_is_one_line(tmp_path, capsys):
    target = tmp_path / "file.txt"
    target.write_text("x")
    assert main(["run", str(_small(tmp_path)), "--out", str(target / "sub"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (
        f"masonry-dem: error: cannot create results folder {target / 'sub'}: not a directory"
    )


def test_an_interrupt_wrapped_by_compiled_calls_is_found():
    """numba wraps an exception raised inside its dispatcher in SystemErrors, one per nested
    call: the interrupt under them is what the command line reports (exit 128 + signal)."""
    from masonry_dem._signals import Interrupted, exit_code, interruption

    inner = Interrupted(signal.SIGTERM)
    wrapped: BaseException = inner
    for _ in range(3):
        outer = SystemError("returned a result with an exception set")
        outer.__cause__ = wrapped
        wrapped = outer
    assert interruption(wrapped) is inner and exit_code(inner) == 143
    plain_error = SystemError("x")
    plain_error.__cause__ = ValueError("y")
    assert interruption(plain_error) is None and interruption(None) is None
