"""A run that dies by a signal it cannot handle says so: the supervising process.

``masonry-dem run``, ``limit`` and ``render`` (the program itself: the console script or
``python -m masonry_dem.cli``) start a small parent that runs the same command line as its
child (:data:`ENV` set, so the child does not supervise again) and waits for it. The parent
imports none of numpy, scipy, numba or VTK. It forwards SIGINT, SIGTERM, SIGHUP, SIGQUIT and
SIGUSR2 to the child, except those the terminal sends (Ctrl-C reaches the whole foreground
process group: the child has it already), and holds back those that come before the child's
handlers are in place (the child says so with SIGUSR1).

The child hands the lock of each results folder it claims to the parent (the open file
description, over a socket: :func:`hand_over_lock`), so the lock outlives a child killed
outright and dies with the parent, whatever kills it. A child that ends with an exit code
ends the parent with the same code, nothing added. A child that dies by a signal:

* SIGKILL (the kernel's out-of-memory killer, ``kill -9``), SIGABRT (Clarabel's failed
  allocation, a library's abort), SIGSEGV and the other faults (a crash in a compiled
  library, e.g. VTK): one line naming it, and each results folder the child left
  ``running`` says ``failed`` with that reason and the number of steps it keeps (every step
  written stays); exit code 2 for SIGKILL and SIGABRT (out of memory, most likely, as a
  MemoryError is), 128 + the signal's number for a crash (139 for SIGSEGV);
* any other signal (SIGINT or SIGTERM before the child's handlers, SIGHUP, ...): a folder
  left ``running`` says ``interrupted``, and the parent ends by the same signal, as the
  child did.

``MASONRY_DEM_NO_SUPERVISOR=1`` runs the command in one process, as before (for a debugger).
On a system without ``posix_spawn``, ``sigwaitinfo`` and descriptor passing, likewise.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

__all__ = ["ENV", "OPT_OUT", "hand_over_lock", "supervised"]

#: set by the parent for its child: "<parent pid>,<socket descriptor>"
ENV = "MASONRY_DEM_SUPERVISED"
#: set to 1 to run without the supervising process
OPT_OUT = "MASONRY_DEM_NO_SUPERVISOR"
#: the commands run under a supervising process
COMMANDS = ("run", "limit", "render")
#: exit code of a child killed by SIGKILL or aborted (out of memory, most likely)
RESOURCE_DEATH = 2

#: the signals the parent passes on to the child (the child handles SIGINT and SIGTERM)
_FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGUSR2)
#: the child's "my handlers are in place"
_READY = signal.SIGUSR1
#: si_code of a signal the kernel sent (a terminal's Ctrl-C, Ctrl-\, hang-up): to the group
_SI_KERNEL = 0x80
#: signals a process dies by when it is stopped from outside on purpose: the parent does too
_STOPS = (*_FORWARDED, _READY, signal.SIGALRM, signal.SIGPIPE, signal.SIGVTALRM, signal.SIGPROF)

#: the child's end of the socket to its parent (None: not supervised)
_channel: int | None = None


def death(signum: int) -> tuple[int, str]:
    """The exit code and the words for a child that died by ``signum``."""
    name = signal.Signals(signum).name
    if signum == signal.SIGKILL:
        return RESOURCE_DEATH, "killed by SIGKILL: the system's out-of-memory killer or kill -9"
    if signum == signal.SIGABRT:
        return RESOURCE_DEATH, (
            "aborted (SIGABRT): a library stopped the process, as Clarabel does when an "
            "allocation fails (out of memory)"
        )
    return 128 + signum, (
        f"crashed ({name}): a fault inside a compiled library (numpy, a solver, VTK); "
        "run again, and report it if it repeats"
    )


def supervised(args: list[str]) -> int | None:
    """In the program's process (``main()`` with no argv): the exit code of the command run
    under a supervising parent, or None when this process is to run it itself (the child,
    a command not supervised, the opt-out, a system without what it takes)."""
    if ENV in os.environ:
        _child_started()
        return None
    if not _wanted(args):
        return None
    return _supervise()


def _wanted(args: list[str]) -> bool:
    if os.environ.get(OPT_OUT, "") not in ("", "0"):
        return False
    if not all(
        hasattr(m, n)
        for m, n in (
            (os, "posix_spawn"),
            (os, "waitstatus_to_exitcode"),
            (signal, "sigwaitinfo"),
            (signal, "pthread_sigmask"),
            (sys, "orig_argv"),
        )
    ):
        return False
    if not _is_the_program():
        return False
    command = next((a for a in args if not a.startswith("-")), None)
    return command in COMMANDS


def _is_the_program() -> bool:
    """Whether this process is the command line itself (``masonry-dem``, ``python -m
    masonry_dem.cli``), which can be run again as it was started, not a program of the
    user's calling ``main()``."""
    orig = list(sys.orig_argv)
    if "-m" in orig[1:-1]:
        return orig[orig.index("-m", 1) + 1] == "masonry_dem.cli"
    return Path(sys.argv[0]).name.startswith("masonry-dem")


def _supervise() -> int | None:
    import socket

    try:
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
    except OSError:
        return None
    os.set_inheritable(theirs.fileno(), True)
    env = {**os.environ, ENV: f"{os.getpid()},{theirs.fileno()}"}
    watched = {*_FORWARDED, _READY, signal.SIGCHLD}
    # from here the signals wait in the queue (the child starts with the mask as it was)
    before = signal.pthread_sigmask(signal.SIG_BLOCK, watched)
    try:
        pid = os.posix_spawn(
            sys.executable, [sys.executable, *sys.orig_argv[1:]], env, setsigmask=before
        )
    except OSError:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)
        ours.close()
        theirs.close()
        return None
    theirs.close()
    status = _wait(pid, watched)
    code = os.waitstatus_to_exitcode(status)
    locks = _received(ours)
    if code >= 0:
        for _, fd in locks:
            os.close(fd)
        return _end(code)
    signum = -code
    if signum in _STOPS:
        _record(locks, pid, "interrupted", f"interrupted by {signal.Signals(signum).name}")
        _end_by(signum)
    code, what = death(signum)
    said = _record(locks, pid, "failed", what)
    print(f"masonry-dem: {'; '.join([what, *said])}", file=sys.stderr)
    return _end(code)


def _wait(pid: int, watched: set[signal.Signals]) -> int:
    """Wait for the child ``pid``, passing the signals on; its wait status."""
    ready, held = False, list[int]()
    while True:
        info = signal.sigwaitinfo(watched)
        signum = info.si_signo
        if signum == signal.SIGCHLD:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done == pid:
                return status
            continue
        if signum == _READY and info.si_pid == pid:
            ready = True
            for s in held:
                _kill(pid, s)
            held.clear()
            continue
        if info.si_code == _SI_KERNEL:  # the terminal's: the child's group has it too
            continue
        if ready:
            _kill(pid, signum)
        else:  # before its handlers: it would die of it, as no signal after them does
            held.append(signum)


def _kill(pid: int, signum: int) -> None:
    try:
        os.kill(pid, signum)
    except ProcessLookupError:  # it has just ended: its SIGCHLD is on the way
        pass


def _received(ours) -> list[tuple[Path, int]]:
    """The results folders the child claimed, each with its lock's descriptor."""
    import socket

    locks = []
    ours.setblocking(False)  # (recv_fds of Python 3.11 drops its flags)
    while True:
        try:
            data, fds, _, _ = socket.recv_fds(ours, 4096, 1)
        except (BlockingIOError, InterruptedError, OSError):
            break
        if not data and not fds:
            break
        for fd in fds:
            locks.append((Path(os.fsdecode(data)), fd))
    ours.close()
    return locks


def _record(locks: list[tuple[Path, int]], pid: int, status: str, what: str) -> list[str]:
    """Each folder the child ``pid`` claimed and left ``running``: ``status`` with ``what``;
    every lock let go. What was said of each folder."""
    said = []
    if locks:
        from masonry_dem.export.results_folder import record_death

        for folder, fd in locks:
            try:
                line = record_death(folder, fd, pid, status, what)
            except Exception as exc:  # noqa: BLE001 - the death is the news, not this
                line = f"{folder}: its summary is not updated ({exc})"
            if line:
                said.append(line)
    return said


def _end(code: int) -> int:
    """End the parent with ``code`` at once: the child ran the program's exit (atexit hooks
    and all); the parent has nothing of its own to finish."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


def _end_by(signum: int) -> None:
    """End the parent by ``signum``, as the child ended."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signum})
    os._exit(128 + signum)  # pragma: no cover - a signal that does not end a process


# ------------------------------------------------------------------------------ the child
def _child_started() -> None:
    """In the child: take the channel to the parent, die with the parent (SIGKILL, as the
    parent was killed outright), and tell it the handlers are in place."""
    global _channel
    marker = os.environ.pop(ENV, "")
    try:
        parent, fd = (int(x) for x in marker.split(","))
    except ValueError:
        return
    try:
        os.set_inheritable(fd, False)  # not for this process's own children
    except OSError:
        return
    _channel = fd
    from masonry_dem.export import results_folder

    results_folder.lock_keeper = hand_over_lock
    _die_with_parent(parent)
    try:
        os.kill(parent, _READY)
    except OSError:
        pass


def _die_with_parent(parent: int) -> None:
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # it died before the line above: as if after it
        os.kill(os.getpid(), signal.SIGKILL)


def hand_over_lock(folder: Path, fd: int) -> bool:
    """In a supervised child: give the parent (a copy of) the lock ``fd`` of ``folder``,
    which then holds the lock as long as it lives, through the child's death; True when
    handed over (the caller closes its own copy), False when not supervised."""
    if _channel is None:
        return False
    import socket

    sock = socket.socket(fileno=os.dup(_channel))
    try:
        socket.send_fds(sock, [os.fsencode(str(Path(folder).resolve()))], [fd], socket.MSG_DONTWAIT)
    except OSError:
        return False
    finally:
        sock.close()
    return True
