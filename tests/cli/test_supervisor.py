"""A run that dies by a signal no process can handle (issue 39): the kernel's out-of-memory
killer (SIGKILL), Clarabel's abort on a failed allocation (SIGABRT), a segmentation fault in
VTK. The supervising parent of ``run``, ``limit`` and ``render`` (masonry_dem._supervisor)
says so in one line, ends with the documented exit code, and the results folder the dead
child left ``running`` says ``failed`` with the reason, every step written kept. On main
(a948e3a) the process itself died: no line, exit code -9/-6/-11, the folder ``running``.

The deaths are real: SIGKILL sent to the process named by ``summary.json``'s pid (the one
that claimed the folder), ``os.abort()`` and SIGSEGV raised inside it by a ``sitecustomize``
hook (:func:`_dying`) that acts only in the process doing the work."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cli.test_faults import _assert_whole, _pvd_files, _slow_case, _wait_for_steps
from helpers.case_files import SINGLE_BLOCK, write_case
from helpers.cli_process import child_env, run_cli
from masonry_dem.export import results_folder as rf

#: the hook: in the process that claimed the folder DIE_OUT (summary.json's pid) once
#: blocks.pvd lists DIE_STEPS steps (0: once claimed), or in the process that imported DIE_MODULE, send it DIE_SIGNAL
#: (SIGABRT: os.abort(), as a library's abort does)
HOOK = """
import os, signal, sys, threading, time

def _watch(name, out, steps, module):
    import json, re
    while True:
        time.sleep(0.02)
        if module:
            if module not in sys.modules:
                continue
        else:
            try:
                pid = json.loads(open(os.path.join(out, "summary.json")).read()).get("pid")
                listed = steps and len(
                    re.findall("<DataSet", open(os.path.join(out, "blocks.pvd")).read())
                )
            except (OSError, ValueError):
                continue
            if pid != os.getpid() or listed < steps:
                continue
        if name == "SIGABRT":
            os.abort()
        os.kill(os.getpid(), getattr(signal, name))

if os.environ.get("COUNT_SIGNALS"):  # each signal a handler of the package takes, a line
    _install = signal.signal

    def _counting(signum, handler):
        if not callable(handler):
            return _install(signum, handler)

        def counted(s, frame, _handler=handler):
            with open(os.environ["COUNT_SIGNALS"], "a") as f:
                f.write(f"{os.getpid()} {s}\\n")
            return _handler(s, frame)

        return _install(signum, counted)

    signal.signal = _counting

if os.environ.get("DIE_SIGNAL"):
    threading.Thread(
        target=_watch,
        args=(os.environ["DIE_SIGNAL"], os.environ.get("DIE_OUT", ""),
              int(os.environ.get("DIE_STEPS", "0")), os.environ.get("DIE_MODULE", "")),
        daemon=True,
    ).start()
"""


def _hooked(tmp_path: Path, **variables: str) -> dict[str, str]:
    """The environment of a CLI process with the hook (:data:`HOOK`) on its path."""
    hooks = tmp_path / "hooks"
    hooks.mkdir(exist_ok=True)
    (hooks / "sitecustomize.py").write_text(HOOK)
    env = child_env()
    env["PYTHONPATH"] = os.pathsep.join([str(hooks), env["PYTHONPATH"]])
    env.update(variables)
    return env


def _dying(tmp_path: Path, signame: str, **where: str) -> dict[str, str]:
    """:func:`_hooked`, the process at work to die by ``signame`` (DIE_OUT, DIE_STEPS,
    DIE_MODULE from ``where``)."""
    return _hooked(
        tmp_path, DIE_SIGNAL=signame, **{f"DIE_{k.upper()}": str(v) for k, v in where.items()}
    )


def _counting(tmp_path: Path) -> tuple[dict[str, str], Path]:
    """:func:`_hooked`, each signal a handler of the package takes written to a file."""
    counts = tmp_path / "signals.txt"
    return _hooked(tmp_path, COUNT_SIGNALS=str(counts)), counts


def _taken(counts: Path, out: Path) -> list[int]:
    """The signals the process at work (``summary.json``'s pid) took."""
    pid = json.loads((out / "summary.json").read_text())["pid"]
    lines = counts.read_text().split() if counts.exists() else []
    return [int(s) for p, s in zip(lines[::2], lines[1::2], strict=True) if int(p) == pid]


def _signals_heard() -> None:
    """In the child before it starts: the signals the tests send at their default action,
    whatever the runner left ignored (``nohup`` ignores SIGHUP, a shell's background job
    SIGINT and SIGQUIT, and an ignored signal stays ignored across exec, as it should)."""
    for sig in (signal.SIGHUP, signal.SIGINT, signal.SIGQUIT):
        signal.signal(sig, signal.SIG_DFL)


def _start(env: dict[str, str], *args: str | Path) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "masonry_dem.cli", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        preexec_fn=_signals_heard,
    )


def _assert_recorded(out: Path, err: str, words: str) -> dict:
    """The one line naming the death, and the folder that says ``failed`` with it, every
    step written kept (both PVDs whole, the curve at least as long)."""
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"masonry-dem: {words}"), err
    assert f"results folder {out.resolve()} says failed" in last, err
    assert "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed", summary
    assert words in summary["reason"], summary
    blocks = _assert_whole(out, killed=True)
    assert summary["steps_written"] == len(blocks) >= 5
    assert f"after {len(blocks)} steps written" in summary["reason"]
    rows = np.loadtxt(out / "pushover.csv", delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[0] >= len(blocks)
    assert rf.state(out).kind == "failed"
    assert not (out / rf.LOCK).exists()
    return summary


def test_a_run_killed_by_sigkill_says_so_and_its_folder_says_failed(tmp_path):
    out = tmp_path / "out"
    proc = _start(child_env(), "run", _slow_case(tmp_path), "--out", out, "--no-render", "--quiet")
    _wait_for_steps(proc, out)
    pid = json.loads((out / "summary.json").read_text())["pid"]
    os.kill(pid, signal.SIGKILL)  # as the out-of-memory killer does: the process at work
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, err
    _assert_recorded(out, err, "killed by SIGKILL: the system's out-of-memory killer or kill -9")
    # the next run is refused as for any finished run, not as one in use
    again = run_cli("run", _slow_case(tmp_path), "--out", out, "--no-render", "--quiet")
    assert again.returncode == 2 and "ended 'failed'" in again.stderr, again.stderr


def test_a_run_that_aborts_says_so_and_its_folder_says_failed(tmp_path):
    out = tmp_path / "out"
    env = _dying(tmp_path, "SIGABRT", out=str(out), steps="5")
    proc = _start(env, "run", _slow_case(tmp_path), "--out", out, "--no-render", "--quiet")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 2, err
    summary = _assert_recorded(out, err, "aborted (SIGABRT)")
    assert "out of memory" in summary["reason"]


def test_a_render_that_crashes_says_so(tmp_path):
    """A segmentation fault once VTK is loaded (as 1 in 92 interrupted ``render --animate``
    did): one line and 128 + 11; the folder read is left as it was."""
    out = tmp_path / "out"
    case = write_case(tmp_path, SINGLE_BLOCK)
    assert run_cli("run", case, "--out", out, "--no-render", "--quiet").returncode == 0
    before = (out / "summary.json").read_text()
    env = _dying(tmp_path, "SIGSEGV", module="pyvista")
    proc = _start(env, "render", out, "--animate")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 128 + signal.SIGSEGV, err
    assert err.strip().splitlines()[-1].startswith("masonry-dem: crashed (SIGSEGV)"), err
    assert (out / "summary.json").read_text() == before


def test_a_killed_limit_analysis_says_so(tmp_path):
    """``limit``: the folder it claimed says ``failed`` (no steps: 0 written)."""
    out = tmp_path / "out"
    env = _dying(tmp_path, "SIGKILL", out=str(out), steps="0")  # once the folder is claimed
    proc = _start(env, "limit", "--out", out, "--no-render")
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 2, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("masonry-dem: killed by SIGKILL"), err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "SIGKILL" in summary["reason"], summary
    assert rf.state(out).kind == "failed"


def test_the_opt_out_runs_in_one_process(tmp_path):
    """``MASONRY_DEM_NO_SUPERVISOR=1``: the command in one process, as before (the folder's
    pid is the process started)."""
    out = tmp_path / "out"
    env = {**child_env(), "MASONRY_DEM_NO_SUPERVISOR": "1"}
    proc = _start(env, "run", _slow_case(tmp_path), "--out", out, "--no-render", "--quiet")
    try:
        _wait_for_steps(proc, out, steps=1)
        assert json.loads((out / "summary.json").read_text())["pid"] == proc.pid
    finally:
        proc.kill()
        proc.wait()


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_to_the_parent_reaches_the_child_once(tmp_path, signum, code):
    """A signal sent to the process started (the parent) reaches the run once: it stops at
    its next Newton iteration, as the first signal does (a second would stop it at once)."""
    out = tmp_path / "out"
    env, counts = _counting(tmp_path)
    proc = _start(env, "run", _slow_case(tmp_path), "--out", out, "--no-render")
    _wait_for_steps(proc, out)
    started = time.monotonic()
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    assert "stopping at the next Newton iteration" in err, err
    assert err.count("stopping at the next Newton iteration") == 1, err
    assert time.monotonic() - started < 60
    assert rf.state(out).kind == "interrupted"
    assert len(_pvd_files(out / "blocks.pvd")) >= 5
    assert _taken(counts, out) == [signum]


def test_a_run_killed_by_a_signal_sent_on_purpose_says_interrupted_and_ends_by_it(tmp_path):
    """SIGHUP (a closed terminal's, sent here to the process at work): the folder says
    ``interrupted`` by it, and the program ends by the same signal, as the run did."""
    out = tmp_path / "out"
    proc = _start(child_env(), "run", _slow_case(tmp_path), "--out", out, "--no-render", "--quiet")
    _wait_for_steps(proc, out)
    pid = json.loads((out / "summary.json").read_text())["pid"]
    os.kill(pid, signal.SIGHUP)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == -signal.SIGHUP, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and "SIGHUP" in summary["reason"], summary
    assert summary["steps_written"] == len(_assert_whole(out, killed=True)) >= 5
    assert rf.state(out).kind == "interrupted"


def test_a_terminals_ctrl_c_reaches_the_run_once(tmp_path):
    """Ctrl-C typed at a terminal: the terminal sends SIGINT to its whole foreground process
    group, the parent and the child; the parent passes on no copy of it, so the run stops
    at its next Newton iteration (one "stopping" line), as a first Ctrl-C does."""
    import pty

    out = tmp_path / "out"
    args = ["run", str(_slow_case(tmp_path)), "--out", str(out), "--no-render", "--quiet"]
    env, counts = _counting(tmp_path)
    pid, master = pty.fork()
    if pid == 0:  # pragma: no cover - the child: the command on the terminal
        os.execve(sys.executable, [sys.executable, "-m", "masonry_dem.cli", *args], env)
    said = b""
    try:
        deadline = time.monotonic() + 300
        while len(_listed(out)) < 5:
            assert time.monotonic() < deadline, said
            said += _read(master, 0.05)
        os.write(master, b"\x03")  # Ctrl-C, as typed
        while chunk := _read(master, 120):
            said += chunk
    finally:
        _, status = os.waitpid(pid, 0)
        os.close(master)
    text = said.decode(errors="replace")
    assert os.waitstatus_to_exitcode(status) == 130, text
    assert text.count("stopping at the next Newton iteration") == 1, text
    assert "masonry-dem: interrupted by SIGINT" in text and "Traceback" not in text, text
    assert rf.state(out).kind == "interrupted"
    assert _taken(counts, out) == [signal.SIGINT]  # the terminal's, and no copy


def _listed(out: Path) -> list[str]:
    try:
        return _pvd_files(out / "blocks.pvd")
    except (OSError, Exception):  # not there yet, or half read
        return []


def _read(fd: int, timeout: float) -> bytes:
    """What the terminal shows within ``timeout`` (b"" when it is closed)."""
    import select

    ready, _, _ = select.select([fd], [], [], timeout)
    if not ready:
        return b""
    try:
        return os.read(fd, 4096) or b""
    except OSError:  # EIO: every process of the terminal has ended
        return b""
