"""Issue 39, through the command line: nothing outside a results folder is touched, counts
and inputs are refused before anything is allocated, an interrupted or killed run leaves a
folder the tools read."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from helpers.case_files import SINGLE_BLOCK, write_case
from helpers.cli_process import ROOT, run_cli, start_cli, start_python


def _cli(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return run_cli(*args, timeout=timeout)


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


U_WALL = {
    "name": "u",
    "geometry": {
        "builder": "u_wall",
        "blocks_along_length": 6,
        "courses": 3,
        "return_blocks": 4,
        "block_height": 0.1,
        "block_length": 0.25,
        "thickness": 0.12,
        "unit_weight": 18e3,
        "base": True,
    },
    "material": {"kn": 2.4e9, "kt": 1e9, "friction": 0.7},
    "supports": [{"select": "base"}],
    "loads": [{"type": "self_weight"}, {"type": "weight_proportional", "direction": [0, 0, 1]}],
}


def _u_wall(tmp_path: Path, analysis: dict | None = None, **geometry: object) -> Path:
    data = {**U_WALL, "geometry": {**U_WALL["geometry"], **geometry}}
    if analysis:
        data["analysis"] = analysis
    return write_case(tmp_path, data)


def _running_bond(tmp_path: Path, length: int, courses: int) -> Path:
    """A running-bond wall of ``length`` x ``courses`` blocks on a base, pushed out of plane."""
    geometry = {
        **U_WALL["geometry"],
        "builder": "running_bond_wall",
        "blocks_along_length": length,
        "courses": courses,
    }
    del geometry["return_blocks"]
    return write_case(tmp_path, {**U_WALL, "geometry": geometry})


def _one_line(done: subprocess.CompletedProcess, *named: str) -> None:
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and "unable to allocate" not in done.stderr
    for word in named:
        assert word in done.stderr, done.stderr


def test_a_count_without_its_range_is_refused_before_anything_is_allocated(tmp_path):
    case = _u_wall(tmp_path, return_blocks=100_000_000)
    done = _cli("run", str(case), "--out", str(tmp_path / "out"), "--quiet", "--no-render")
    _one_line(done, "return_blocks", "10000", "100000000")
    assert not (tmp_path / "out").exists()


def test_a_plan_too_large_for_the_memory_is_refused_by_the_estimate(tmp_path):
    case = _u_wall(tmp_path, blocks_along_length=10_000, courses=10_000, return_blocks=10_000)
    done = _cli("run", str(case), "--out", str(tmp_path / "out"), "--quiet", "--no-render")
    _one_line(done, "refused", "would need")


def test_a_picture_size_has_a_range(tmp_path):
    done = _cli("render", str(tmp_path / "anywhere"), "--size", "100000x100000")
    _one_line(done, "--size", "8192", "100000x100000")


def test_a_limit_analysis_grid_has_a_range(tmp_path):
    case = _u_wall(tmp_path)
    done = _cli("limit", str(case), "--grid", "100000", "--out", str(tmp_path / "a"))
    _one_line(done, "grid", "100000", "32")
    in_file = _u_wall(tmp_path, analysis={"method": "limit", "grid": 100_000})
    done = _cli("run", str(in_file), "--out", str(tmp_path / "b"), "--quiet", "--no-render")
    _one_line(done, "grid", "100000")


def test_limit_with_no_live_load_is_an_answer_as_the_pushover_says(tmp_path):
    data = {**SINGLE_BLOCK, "loads": [{"type": "self_weight"}]}
    case = write_case(tmp_path, data)
    limit = _cli("limit", str(case), "--out", str(tmp_path / "la"), "--no-render")
    pushover = _cli("run", str(case), "--out", str(tmp_path / "po"), "--no-render", "--quiet")
    assert limit.returncode == pushover.returncode == 0, limit.stdout + limit.stderr
    assert "no live load" in limit.stdout and "no live load" in pushover.stdout
    assert "-0" not in limit.stdout


def test_a_caption_never_says_minus_zero():
    from masonry_dem.export.render import caption

    assert "lambda = 0 " in caption("wall", "step 3", -0.0, "completed", "x1", "static pushover")


def test_a_killed_run_keeps_its_pushover_curve_row_by_row(tmp_path):
    import numpy as np

    from cli.test_faults import _pvd_files, _slow_case, _start, _wait_for_steps

    out = tmp_path / "out"
    proc = _start(_slow_case(tmp_path), out)
    _wait_for_steps(proc, out, steps=8)
    proc.kill()
    proc.wait(timeout=60)
    rows = np.loadtxt(out / "pushover.csv", delimiter=",", skiprows=1, ndmin=2)
    written = len(_pvd_files(out / "blocks.pvd"))
    assert rows.shape[0] >= written >= 8
    np.testing.assert_array_equal(rows[:, 0], np.arange(rows.shape[0]))
    assert np.isfinite(rows).all()
    done = _cli("render", str(out), "--pushover", "--step", "last", "--size", "320x240")
    assert done.returncode == 0, done.stderr
    assert (out / "pushover.png").is_file()


def test_a_row_cut_short_by_a_kill_is_left_out_of_the_curve(tmp_path):
    from masonry_dem.export.results_series import read_pushover

    (tmp_path / "pushover.csv").write_text("step,lambda,control_displacement\n0,0,0\n1,0.1,0.0")
    assert read_pushover(tmp_path)["step"].tolist() == [0.0]


def test_sigterm_just_after_the_folder_is_claimed_is_recorded(tmp_path):
    import json
    import signal
    import time

    from cli.test_faults import _slow_case, _start

    out = tmp_path / "out"
    proc = _start(_slow_case(tmp_path), out)
    deadline = time.monotonic() + 300
    while not (out / "summary.json").exists():
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.001)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and "SIGTERM" in summary["reason"]


def test_a_signal_held_back_while_the_folder_is_claimed_is_recorded(tmp_path, monkeypatch):
    import json
    import signal

    import pytest

    from masonry_dem._signals import raise_on_signals
    from masonry_dem.export import results_folder as rf

    written = rf.write_summary

    def then_a_signal(folder, summary, extra=None):
        data = written(folder, summary, extra)
        if data["status"] == rf.RUNNING:
            os.kill(os.getpid(), signal.SIGTERM)  # held back until the claim is done
        return data

    monkeypatch.setattr(rf, "write_summary", then_a_signal)
    with raise_on_signals(), pytest.raises(KeyboardInterrupt):
        rf.claim(tmp_path / "out", False, {"name": "wall"})
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["name"] == "wall"
    assert rf.state(tmp_path / "out").kind == "interrupted"


def test_unreadable_case_files_are_named_with_their_cause(tmp_path):
    text = write_case(tmp_path, SINGLE_BLOCK).read_text()
    bom = tmp_path / "bom.toml"
    bom.write_text("\ufeff" + text, encoding="utf-8")
    deep = tmp_path / "deep.toml"
    deep.write_text(text + "\nx = " + "[" * 5000 + "]" * 5000 + "\n")
    long_key = tmp_path / "key.toml"
    long_key.write_text(text.replace("[material]", "[material]\n" + "k" * 100_000 + " = 1"))

    read = _cli("run", str(bom), "--out", str(tmp_path / "bom"), "--quiet", "--no-render")
    assert read.returncode == 0, read.stderr  # a byte-order mark is no fault of the case
    nested = _cli("run", str(deep), "--out", str(tmp_path / "deep"), "--quiet", "--no-render")
    _one_line(nested, str(deep), "too deeply")
    assert "recursion" not in nested.stderr
    unknown = _cli("run", str(long_key), "--out", str(tmp_path / "k"), "--quiet", "--no-render")
    _one_line(unknown, "unknown key", "100000 characters")
    assert len(unknown.stderr) < 2000


def test_a_negative_seed_names_its_flag(tmp_path):
    case = write_case(tmp_path, SINGLE_BLOCK)
    done = _cli(
        "sweep",
        str(case),
        "--sample",
        "material.friction=uniform(0.5,0.9)",
        "--samples",
        "2",
        "--seed",
        "-1",
        "--out",
        str(tmp_path / "sweep"),
    )
    _one_line(done, "--seed", "-1")


def test_a_full_disk_under_render_names_the_picture(tmp_path, capsys, monkeypatch):
    import errno

    from masonry_dem.cli import main
    from masonry_dem.export.scene import Scene

    out = tmp_path / "out"
    case = write_case(tmp_path, SINGLE_BLOCK)
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0

    def full(self, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Scene, "save", full)
    capsys.readouterr()
    assert main(["render", str(out), "--step", "last", "--size", "320x240"]) == 2
    err = capsys.readouterr().err
    assert "no space left on the device" in err and str(out / "render_") in err
    assert not list(out.glob(".*.tmp*"))


def test_the_memory_estimate_respects_the_process_limit(tmp_path):
    case = _running_bond(tmp_path, 300, 100)
    limit = 2_500_000_000
    args = ("run", str(case), "--out", str(tmp_path / "o"), "--quiet", "--no-render")
    done = _limited(limit, *args, timeout=300)
    _one_line(done, "refused", "ulimit -v")
    assert not (tmp_path / "o").exists()


def _limited(limit: int, *args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """The command line under an address-space limit of ``limit`` bytes (``ulimit -v``)."""
    import resource

    def address_space_limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    return run_cli(*args, timeout=timeout, preexec_fn=address_space_limit)


def test_a_limit_analysis_out_of_memory_is_named_with_its_estimate(tmp_path):
    """Under ``ulimit -v``: the estimate refuses the analysis before the folder is claimed;
    past the estimate (``--max-memory``), HiGHS's arrays fail with numpy's MemoryError and
    Clarabel, which aborted the process (SIGABRT) on a failed allocation, is stopped before
    it starts: both are "out of memory", exit 2, with the estimate beside it."""
    import json

    case = str(_running_bond(tmp_path, 100, 100))
    limit = 1_200_000_000
    refused = _limited(limit, "limit", case, "--backend", "clarabel", "--out", str(tmp_path / "a"))
    _one_line(refused, "refused", "ulimit -v", "clarabel", "29850 interfaces")
    assert not (tmp_path / "a").exists()
    for backend in ("clarabel", "highs"):
        out = tmp_path / backend
        args = ["limit", case, "--backend", backend, "--out", str(out), "--max-memory", "100G"]
        done = _limited(limit, *args)
        _one_line(done, "out of memory", "estimated", f"{backend}: about")
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "failed" and "estimated" in summary["reason"]


def test_highs_out_of_memory_is_no_property_of_the_wall():
    from types import SimpleNamespace

    import pytest

    from masonry_dem.cli import one_line
    from masonry_dem.solvers.limit_analysis.backends import _highs_error

    res = SimpleNamespace(status=4, message="Memory allocation failed")
    with pytest.raises(MemoryError) as err:
        _highs_error(res)
    assert one_line(err.value).startswith("out of memory")
    assert _highs_error(SimpleNamespace(status=4, message="Numerical issues")).status == "error"


def test_clarabel_is_stopped_before_it_starts_by_every_memory_limit(monkeypatch):
    """Clarabel aborts the process on a failed allocation, so it is refused before it
    starts where its matrix needs more than the machine's available memory or the cgroup's
    limit leaves, as where ``ulimit -v`` does (on 26a12f1 only the last was checked, and a
    cgroup's OOM killer or the machine's lack of memory ended the process unreported)."""
    import pytest
    from scipy import sparse

    from masonry_dem.cli import one_line
    from masonry_dem.solvers import resources
    from masonry_dem.solvers.limit_analysis.backends import clarabel_room

    A = sparse.random(1000, 2000, density=0.01, format="csc", random_state=0)
    need = resources.LIMIT_BYTES["clarabel"][0] + resources.CLARABEL_BYTES_PER_ENTRY * A.nnz
    plenty = 1e15
    for source, getter in (
        ("the machine's available memory", "_available"),
        ("the cgroup's memory limit", "_cgroup_left"),
        ("the process's address-space limit (ulimit -v)", "_address_space_left"),
    ):
        for name in ("_available", "_cgroup_left", "_address_space_left"):
            monkeypatch.setattr(resources, name, lambda: plenty)
        monkeypatch.setattr(resources, getter, lambda: 0.5 * need)
        with pytest.raises(MemoryError) as err:
            clarabel_room(A)
        line = one_line(err.value)
        assert line.startswith("out of memory") and source in line, line
        monkeypatch.setattr(resources, getter, lambda: 2.0 * need)
        clarabel_room(A)  # room enough: no error


def test_pardiso_out_of_memory_is_no_property_of_the_wall():
    import numpy as np
    import pytest

    from masonry_dem.cli import one_line
    from masonry_dem.solvers import factorization

    pytest.importorskip("pypardiso")
    handle = factorization.PardisoHandle(np.array([0, 1, 2]), np.array([0, 1]), 2, 11, {})

    def out_of_memory(*args):
        handle._error.value = factorization.PARDISO_OUT_OF_MEMORY

    handle.solver._mkl_pardiso = out_of_memory
    with pytest.raises(MemoryError) as err:
        handle.call(12)
    assert one_line(err.value).startswith("out of memory")


def test_a_live_load_that_cannot_drive_a_collapse_is_named_and_stops_early(tmp_path):
    import json

    loads = {
        "down": {"type": "pressure", "value": 1000.0, "axis": 1, "sign": -1},
        "tilted": {"type": "weight_proportional", "direction": [1e-12, -1.0, 0.0]},
    }
    for name, live in loads.items():
        data = {**SINGLE_BLOCK, "loads": [{"type": "self_weight"}, live]}
        folder = tmp_path / name
        folder.mkdir()
        out = folder / "out"
        done = _cli("run", str(write_case(folder, data)), "--out", str(out), "--no-render")
        assert done.returncode == 0, done.stderr
        assert "cannot drive a collapse" in done.stderr
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "completed" and summary["lambda"] is None
        assert "cannot drive a collapse" in summary["reason"]
        assert len(list((out / "steps").glob("*.vtu"))) == 2  # the dead-load state


def test_sigterm_stops_a_limit_analysis_inside_its_solver(tmp_path):
    import json
    import signal
    import time

    case, out = _running_bond(tmp_path, 40, 40), tmp_path / "out"
    # --quiet: stderr holds the signal's line alone (the progress line is test_limit_outputs')
    proc = start_cli("limit", case, "--out", out, "--non-associative", "--no-render", "--quiet")
    try:
        while not (out / "summary.json").exists():
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.01)
        time.sleep(2)  # inside the solver's first solves (minutes in all)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)  # it ignored the signal for minutes
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    assert err.strip() == "masonry-dem: interrupted by SIGTERM"
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"


def test_a_signal_that_breaks_an_import_is_an_interruption(monkeypatch, capsys):
    import signal

    import masonry_dem.cli.render as render_cli
    from masonry_dem._signals import Interrupted
    from masonry_dem.cli import main

    def vtk_loading(args):
        try:
            raise Interrupted(signal.SIGINT)
        except Interrupted as exc:  # what VTK's loader makes of a Ctrl-C
            raise ImportError("Failed to load vtkCommonMath") from exc

    monkeypatch.setattr(render_cli, "run", vtk_loading)
    assert main(["render", "anywhere"]) == 130
    assert capsys.readouterr().err.strip() == "masonry-dem: interrupted by SIGINT"


def test_a_signal_an_extension_loader_keeps_only_the_message_of_is_an_interruption(
    monkeypatch, capsys
):
    """numpy's loader, stopped by Ctrl-C while it imports datetime, raises an ImportError
    that keeps the message and not the KeyboardInterrupt (seen at 0.1 s of a `render`)."""
    import signal

    import masonry_dem.cli.render as render_cli
    from masonry_dem.cli import main

    def numpy_loading(args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
        except KeyboardInterrupt:
            pass
        raise ImportError('Original error was: PyCapsule_Import could not import module "datetime"')

    monkeypatch.setattr(render_cli, "run", numpy_loading)
    assert main(["render", "anywhere"]) == 130
    assert capsys.readouterr().err.strip() == "masonry-dem: interrupted by SIGINT"


def test_a_signal_at_any_moment_leaves_a_folder_that_says_how_the_run_ended(tmp_path):
    """Hypothesis picks the signal and the moment (from the interpreter's start to the run's
    steps); whatever the moment, the process ends by the signal or with 0, one line at most,
    and a folder it claimed never says ``running``."""
    import itertools
    import json
    import signal
    import time

    from hypothesis import given, settings
    from hypothesis import strategies as st

    from cli.test_faults import _slow_case, _start

    case = _slow_case(tmp_path)
    runs = itertools.count()

    @settings(max_examples=8, derandomize=True, deadline=None)
    @given(st.sampled_from([signal.SIGINT, signal.SIGTERM]), st.floats(0.0, 3.0))
    def check(signum, delay):
        out = tmp_path / f"out{next(runs)}"
        proc = _start(case, out)
        time.sleep(delay)
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode in (0, -signum, 128 + signum), err
        if proc.returncode != -signum:  # before the handlers, the signal's default action
            assert "Traceback" not in err and len(err.strip().splitlines()) <= 2, err
        if (out / "summary.json").exists():
            status = json.loads((out / "summary.json").read_text())["status"]
            assert status != "running"

    check()


def _stderr_lines(proc: subprocess.Popen):
    """The child's stderr lines as they come (a queue filled by a thread; None at the end)."""
    import queue
    import threading

    lines: queue.Queue[str | None] = queue.Queue()

    def read() -> None:
        for line in proc.stderr:  # type: ignore[union-attr]
            lines.put(line)
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()
    return lines


def _interrupted_says(proc: subprocess.Popen, lines, timeout: float) -> list[str]:
    """SIGINT to ``proc``, then what it says on stderr after it (``-X importtime``'s lines
    left out) once it has ended within ``timeout``."""
    import signal

    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=timeout)
    rest = []
    while (line := lines.get(timeout=10)) is not None:
        rest.append(line)
    return [line.strip() for line in rest if not line.startswith("import time:")]


def _wait_for_line(lines, words, timeout: float) -> tuple[str, list[str]]:
    """The first line holding ``words`` (a text, or a test of the line) and the lines before
    it (AssertionError: none came)."""
    import time

    found = words if callable(words) else lambda line: words in line
    seen: list[str] = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            line = lines.get(timeout=1.0)
        except Exception:  # queue.Empty: nothing yet
            continue
        assert line is not None, "".join(seen)
        if found(line):
            return line, seen
        seen.append(line)
    raise AssertionError(f"no line with {words!r} in {timeout} s: {''.join(seen)}")


def test_a_sweep_of_a_million_points_shows_its_planning_and_stops_on_sigterm(tmp_path):
    import signal

    out = tmp_path / "sweep"
    proc = start_cli("sweep", "--vary", "material.friction=0.5:0.9:1000000", "--out", out)
    try:
        line, _ = _wait_for_line(_stderr_lines(proc), "planning the sweep", timeout=240)
        assert "of 1000000 values" in line and "s left" in line
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 143
    assert not out.exists()  # stopped while planning: nothing claimed


def test_a_crossed_grid_says_its_runs_and_time_before_it_starts(tmp_path):
    import signal

    out = tmp_path / "sweep"
    vary = ["--vary", "material.friction=0.5:0.9:1000", "--vary", "material.kt=1e8:2e9:1000"]
    proc = start_cli("sweep", *vary, "--out", out, "--quiet")
    try:
        line, before = _wait_for_line(_stderr_lines(proc), "WARNING", timeout=240)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
    finally:
        proc.kill()
    assert "sweep of 1000000 runs (1000 x 1000 crossed)" in line, line
    assert " h on " in line and "expect" in line  # hours, on how many workers
    assert not any("to run" in b for b in before)  # before the sweep claims its folder


def test_ctrl_c_while_python_imports_numpy_is_one_line_and_130(tmp_path):
    """The signal lands while the interpreter imports the heavy modules (right after numpy,
    told by ``-X importtime``): before, the package's own import did so before the command
    line's first line, and Ctrl-C gave a KeyboardInterrupt traceback and -2."""

    case = write_case(tmp_path, SINGLE_BLOCK)
    for command in (["run", str(case), "--out", str(tmp_path / "out")], ["render", "folder"]):
        proc = start_python("-X", "importtime", "-m", "masonry_dem.cli", *command)
        try:
            lines = _stderr_lines(proc)
            _wait_for_line(lines, lambda line: line.split("|")[-1].strip() == "numpy", 120)
            said = _interrupted_says(proc, lines, 60)
        finally:
            proc.kill()
        assert proc.returncode == 130, said
        assert said == ["masonry-dem: interrupted by SIGINT"]


def _signal_at_call(monkeypatch, owner, name: str, call: int, calls: list[int]) -> None:
    """SIGTERM to this process from inside the ``call``-th call of ``owner.name``; ``calls``
    counts the calls (a real signal, at a moment inside a step)."""
    import signal

    original = getattr(owner, name)

    def counted(*args, **kwargs):
        calls.append(1)
        if len(calls) == call:
            os.kill(os.getpid(), signal.SIGTERM)
        return original(*args, **kwargs)

    monkeypatch.setattr(owner, name, counted)


def test_a_signal_stops_the_static_solver_at_its_next_newton_iteration(monkeypatch):
    """The first signal stops a step under way (a 316 x 316 wall's step is a minute): no
    factorization after it, at most the step it lands in handed on; before, the solver went
    on to the end and only the run command's check between steps stopped it."""
    import pytest

    from masonry_dem._signals import Interrupted, stop_on_signals
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.solvers.incremental import StaticSolver
    from masonry_dem.solvers.static.problem import DiscreteProblem

    case = load_case(ROOT / "src" / "masonry_dem" / "cases" / "data" / "default_wall.toml")
    factored: list[int] = []
    _signal_at_call(monkeypatch, DiscreteProblem, "factor", 12, factored)
    steps: list[int] = []
    solver = StaticSolver(case.model, case.settings)
    with stop_on_signals(), pytest.raises(Interrupted) as stopped:
        solver.run(control=case.control, callback=lambda s: steps.append(len(factored)))
    assert stopped.value.signum == 15
    assert len(factored) == 12  # none after the signal
    assert len([n for n in steps if n >= 12]) <= 1  # the step the signal landed in, at most


def test_a_signal_stops_the_non_associative_limit_analysis_between_its_solves(monkeypatch):
    """The bound a run computes at a collapse runs in the run's worker thread, where only
    the checks stop it: the signal ends the iteration before its next solve."""
    import pytest

    from masonry_dem._signals import Interrupted, stop_on_signals
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.solvers.limit_analysis import limit_analysis, non_associative

    case = load_case(ROOT / "src" / "masonry_dem" / "cases" / "data" / "default_wall.toml")
    started: list[int] = []
    _signal_at_call(monkeypatch, non_associative, "solve_associative", 1, started)
    solves: list[int] = []
    _signal_at_call(monkeypatch, non_associative, "solve_frozen_columns", 0, solves)
    with stop_on_signals(), pytest.raises(Interrupted):
        limit_analysis(case.model, associative=False)
    assert started == [1] and solves == []


def test_a_signal_stops_dynamic_relaxation_inside_a_relaxation(monkeypatch):
    import pytest

    from masonry_dem._signals import Interrupted, stop_on_signals
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.solvers.dynamic_relaxation import DRSettings, relax
    from masonry_dem.solvers.dynamic_relaxation.solver import DynamicRelaxation

    case = load_case(ROOT / "src" / "masonry_dem" / "cases" / "data" / "default_wall.toml")
    relaxed: list[int] = []
    _signal_at_call(monkeypatch, DynamicRelaxation, "relax_with_cuts", 3, relaxed)
    with stop_on_signals(), pytest.raises(Interrupted):
        relax(case.model, DRSettings())
    assert len(relaxed) == 3  # stopped inside the relaxation the signal landed in


def test_an_interrupted_render_ends_without_the_interpreters_teardown(tmp_path):
    """Ctrl-C in a render, VTK loaded: one line, 130, and no teardown after it (an atexit
    hook of the program says if there is one). The teardown finalized what the signal left
    half made (llvmlite's "Exception ignored in OutputString.__del__") and took most of the
    time to stop (a median of 1.8 s and up to 7.7 s after Ctrl-C, 30 renders, load 7 on 2
    cores; 0.05 s and 0.44 s without it)."""
    import time

    out = tmp_path / "out"
    case = write_case(tmp_path, SINGLE_BLOCK)
    assert _cli("run", str(case), "--out", str(out), "--no-render", "--quiet").returncode == 0
    program = (
        "import atexit, sys\n"
        "atexit.register(lambda: print('teardown', file=sys.stderr))\n"
        "from masonry_dem.cli import main\n"
        f"sys.argv = ['masonry-dem', 'render', {str(out)!r}, '--animate']\n"
        "sys.exit(main())\n"
    )
    proc = start_python("-X", "importtime", "-c", program)
    try:
        lines = _stderr_lines(proc)
        _wait_for_line(lines, lambda line: line.split("|")[-1].strip() == "pyvista", 240)
        time.sleep(0.5)
        assert proc.poll() is None
        said = _interrupted_says(proc, lines, 120)
    finally:
        proc.kill()
    assert proc.returncode == 130 and said == ["masonry-dem: interrupted by SIGINT"], said
