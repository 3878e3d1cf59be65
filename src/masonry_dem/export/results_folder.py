"""The results folder of one run: its layout, and every write and read of its index files.

Layout::

    summary.json            how the run stands: "running" from its start, then how it ended
    blocks.pvd              the step series of the blocks   } always listing the same steps
    interfaces.pvd          the step series of the joints   }
    steps/blocks_NNNN.vtu, steps/interfaces_NNNN.vtu
    pushover.csv            step, lambda, control displacement
    mechanism_blocks.vtu, mechanism_interfaces.vtu   the collapse mode (runs ending in collapse)
    *.png, *.gif, *.pvsm    renders and ParaView states made from the folder
    assessment.json, capacity_curve.csv, adrs.png   the seismic assessment (masonry-dem assess)
    .masonry-dem.lock       held (flock) by the process writing the folder

A folder belongs to one run: :func:`claim` refuses a folder that holds another run's files
unless asked to overwrite them (and then removes the package's own files, :data:`OWN_FILES`,
and nothing else), and a lock keeps a second process out. Every file is written under a unique
temporary name and renamed into place (:func:`write_atomic`), so a reader, an interrupted run
or a full disk never leaves a half-written file under a real name. A run killed outright
(SIGKILL, power cut) leaves ``summary.json`` at ``running`` with nobody holding the lock:
:func:`state` names such a folder ``unfinished``.
"""

from __future__ import annotations

import errno
import json
import logging
import os
import socket
import time
import uuid
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from masonry_dem._signals import deferred_signals

if TYPE_CHECKING:
    import numpy as np
else:

    class _Numpy:
        """numpy on first use: the supervising process (:mod:`masonry_dem._supervisor`)
        records a run's end here without loading it."""

        def __getattr__(self, name: str) -> Any:
            import numpy

            return getattr(numpy, name)

    np = _Numpy()

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: the pid in summary.json is the only sign
    fcntl = None  # type: ignore[assignment]

log = logging.getLogger(__name__)

SUMMARY = "summary.json"
BLOCKS_PVD = "blocks.pvd"
INTERFACES_PVD = "interfaces.pvd"
STEPS = "steps"
PUSHOVER = "pushover.csv"
MECHANISM_FILES = ("mechanism_blocks.vtu", "mechanism_interfaces.vtu")
LOCK = ".masonry-dem.lock"

#: the files the package writes in a results folder (glob patterns): what ``--overwrite``
#: removes, and what marks a folder as holding a run
RUN_FILES = (
    SUMMARY,
    BLOCKS_PVD,
    INTERFACES_PVD,
    PUSHOVER,
    f"{STEPS}/blocks_*.vtu",
    f"{STEPS}/interfaces_*.vtu",
    *MECHANISM_FILES,
)
OWN_FILES = (
    *RUN_FILES,
    "render_*.png",
    "animation_*.gif",
    "animation_*.mp4",
    "mechanism_*.png",
    "mechanism.png",
    "damage*.png",
    "pushover.png",
    "pushover.svg",
    "pushover.pdf",
    "damage_map.pvsm",
    "deformed_shape.pvsm",
    "force_view.pvsm",
    "mechanism.pvsm",
    "assessment.json",
    "capacity_curve.csv",
    "adrs.png",
    ".*.tmp*",
    f"{STEPS}/.*.tmp*",
)

#: statuses of summary.json: while the run goes, and how it can end
RUNNING, INTERRUPTED = "running", "interrupted"
#: folder states whose files may stop short of a whole run (see :func:`state`)
UNFINISHED = ("running", "unfinished", INTERRUPTED, "failed")


class ResultsFolderError(OSError):
    """A results folder that cannot be used or written: the message names the path and why."""


def folder_path(folder: object) -> Path:
    """``folder`` as the path of a results folder: an empty or blank name (which would be
    the current directory) or something that is no path is refused."""
    if not isinstance(folder, (str, os.PathLike)) or not str(folder).strip():
        raise ResultsFolderError(
            errno.EINVAL,
            f"a results folder must be named by a path (e.g. results/wall), got {folder!r}",
        )
    return Path(folder)


# ------------------------------------------------------------------------------ writing
def _tmp_name(path: Path) -> Path:
    """A name beside ``path`` that no other process or thread uses (hidden, .tmp)."""
    return path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")


def write_atomic(path: Path | str, write: Callable[[Path], Any]) -> Path:
    """``write(tmp)`` under a unique temporary name beside ``path``, then rename it onto
    ``path``: readers see the old file or the new one, never half of one. An OS error
    (full disk, read-only folder) removes the temporary file and is raised as
    :class:`ResultsFolderError` naming ``path``."""
    path = Path(path)
    tmp = _tmp_name(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        raise write_error(path, exc) from exc
    finally:
        with _quiet():
            tmp.unlink(missing_ok=True)
    return path


def replace_together(targets: Mapping[Path, Callable[[Path], Any]]) -> None:
    """Write every target to its temporary name first, then rename them one after the other:
    files that must agree (the two PVD indexes) change together, and if any write fails
    none of them changes."""
    tmps = {path: _tmp_name(path) for path in targets}
    try:
        for path, write in targets.items():
            try:
                write(tmps[path])
            except OSError as exc:
                raise write_error(path, exc) from exc
        for path, tmp in tmps.items():
            try:
                os.replace(tmp, path)
            except OSError as exc:
                raise write_error(path, exc) from exc
    finally:
        for tmp in tmps.values():
            with _quiet():
                tmp.unlink(missing_ok=True)


@contextmanager
def _quiet() -> Iterator[None]:
    try:
        yield
    except OSError:
        pass


def write_error(path: Path, exc: OSError) -> ResultsFolderError:
    """``exc`` (a failed write of ``path``) as one line naming the path and why."""
    if isinstance(exc, ResultsFolderError):
        return exc
    return ResultsFolderError(exc.errno or 0, f"cannot write {path}: {_why(exc)}")


def _why(exc: OSError) -> str:
    return {
        errno.ENOSPC: "no space left on the device",
        errno.EDQUOT: "disk quota exceeded",
        errno.EROFS: "the file system is read-only",
        errno.EACCES: "permission denied",
        errno.EPERM: "permission denied",
    }.get(exc.errno or 0, (exc.strerror or str(exc)).lower())


def write_summary(
    folder: Path | str, summary: Mapping[str, Any], extra: Mapping | None = None
) -> dict:
    """The one writer of ``summary.json``: ``summary`` updated with ``extra`` (the keys other
    parts of the package add), written atomically; returns what was written."""
    data = dict(summary)
    data.update(extra or {})
    text = json.dumps(data, indent=2, default=_plain_json)
    write_atomic(Path(folder) / SUMMARY, lambda tmp: tmp.write_text(text))
    return data


def _plain_json(value: Any) -> Any:
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"summary.json: {type(value).__name__} is not JSON")


def read_summary(folder: Path | str) -> dict:
    """``summary.json`` of a folder ({} when absent or unreadable: logged)."""
    path = Path(folder) / SUMMARY
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        log.warning("%s unreadable (%s): ignored", path, exc)
        return {}
    return data if isinstance(data, dict) else {}


@dataclass(frozen=True)
class FolderState:
    """What a folder holds: ``empty`` (no run's files), ``running`` (a live process holds
    its lock), ``unfinished`` (a run that stopped without saying how: killed), or the
    status the run ended with (``collapse``, ``completed``, ``failed``, ``interrupted``)."""

    kind: str
    summary: dict

    def describe(self, folder: Path) -> str:
        s = self.summary
        started = f" started {s['started']}" if s.get("started") else ""
        pid = f" by process {s['pid']}" if s.get("pid") else ""
        if self.kind == "running":
            return f"results folder {folder} is being written{pid}{started}"
        if self.kind == "unfinished":
            return (
                f"results folder {folder} is unfinished: its run{started}{pid} stopped without "
                "finishing (killed?) and its files stop at the last step written"
            )
        if self.kind == "empty":
            return f"results folder {folder} holds no run"
        return f"results folder {folder} holds a run that ended '{self.kind}'"


def _lock_is_held(folder: Path) -> bool:
    """Whether a live process holds the folder's lock (a lock nobody holds is free)."""
    path = folder / LOCK
    if fcntl is None or not path.is_file():
        return False
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)
    return False


def _own_paths(folder: Path, pattern: str) -> Iterator[Path]:
    """The paths of ``folder`` matching ``pattern``, never through a symbolic link: a
    ``steps`` that links elsewhere holds another folder's files, not this run's."""
    parent = folder / pattern.rpartition("/")[0]
    if parent.is_symlink() or not parent.is_dir():
        return iter(())
    return folder.glob(pattern)


def _holds_run(folder: Path) -> bool:
    return any(any(_own_paths(folder, pattern)) for pattern in RUN_FILES)


def state(folder: Path | str, _locked_here: bool = False) -> FolderState:
    """How the run of ``folder`` stands (see :class:`FolderState`)."""
    folder = Path(folder)
    if not folder.is_dir() or not _holds_run(folder):
        return FolderState("empty", {})
    summary = read_summary(folder)
    status = str(summary.get("status", ""))
    if not _locked_here and _lock_is_held(folder):
        return FolderState("running", summary)
    if status in ("", RUNNING):
        return FolderState("unfinished", summary)
    return FolderState(status, summary)


def warn_if_unfinished(folder: Path | str) -> FolderState:
    """For the readers of a folder (render, paraview-state): log a warning naming a folder
    whose run is still going or never finished; the steps it holds are whole and usable."""
    st = state(folder)
    if st.kind in ("running", "unfinished", INTERRUPTED):
        what = (
            st.describe(Path(folder))
            if st.kind != INTERRUPTED
            else (
                f"results folder {folder} holds an interrupted run "
                f"({st.summary.get('reason', 'stopped')})"
            )
        )
        log.warning("%s; using the steps it holds", what)
    return st


# ------------------------------------------------------------------------ one run, one folder
class RunFolder:
    """The folder of one run, claimed by :func:`claim`: locked for this process until
    :meth:`release`."""

    def __init__(self, folder: Path, lock_fd: int | None, locked: bool | None = None) -> None:
        self.folder = folder
        self._lock_fd = lock_fd
        #: whether this run locked the folder (its lock's descriptor may be the supervising
        #: process's alone: :func:`claim`)
        self._locked = lock_fd is not None if locked is None else locked

    def release(self) -> None:
        """Remove the lock file, then drop the lock: a finished folder keeps no empty lock
        file (a process waiting on the removed file finds it gone, :func:`_lock`). A lock
        handed to the supervising process is dropped when that process ends, moments after
        this one; its file is gone now."""
        if self._locked:
            with _quiet():
                (self.folder / LOCK).unlink(missing_ok=True)
            self._locked = False
        if self._lock_fd is not None:
            with _quiet():
                os.close(self._lock_fd)  # closing the descriptor drops the flock
            self._lock_fd = None

    def __del__(self) -> None:  # pragma: no cover - a writer dropped without finish
        self.release()


def _refuse_path(folder: Path) -> None:
    if folder.exists() and not folder.is_dir():
        raise ResultsFolderError(errno.ENOTDIR, f"results folder {folder} is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ResultsFolderError(
            exc.errno or 0,
            f"cannot create results folder {folder}: {_why(exc)}",
        ) from exc
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ResultsFolderError(
            errno.EACCES, f"cannot write results folder {folder}: permission denied"
        )


def _lock(folder: Path) -> int | None:
    if fcntl is None:  # pragma: no cover
        return None
    path = folder / LOCK
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise write_error(path, exc) from exc
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        holder = read_summary(folder).get("pid", "another process")
        raise ResultsFolderError(
            errno.EBUSY,
            f"results folder {folder} is in use by another run (process {holder}); "
            "choose another --out or wait for it to end",
        ) from None
    if not _same_file(fd, path):  # the run holding it removed it on release: lock anew
        os.close(fd)
        return _lock(folder)
    return fd


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` is still the file open as ``fd``."""
    try:
        here = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (here.st_dev, here.st_ino) == (held.st_dev, held.st_ino)


def remove_own_files(folder: Path) -> int:
    """Remove the package's files from ``folder`` (:data:`OWN_FILES`), nothing else; the
    ``steps`` folder too when that leaves it empty. Returns how many were removed."""
    removed = 0
    for pattern in OWN_FILES:
        for path in _own_paths(folder, pattern):
            if path.is_symlink() or path.is_file():  # a link goes, never what it names
                try:
                    path.unlink()
                except OSError as exc:
                    raise write_error(path, exc) from exc
                removed += 1
    steps = folder / STEPS
    if steps.is_dir() and not steps.is_symlink() and not any(steps.iterdir()):
        steps.rmdir()
    return removed


def _refuse_foreign_steps(folder: Path, overwrite: bool) -> None:
    """A ``steps`` that is a symbolic link would take this run's VTUs (and ``--overwrite``'s
    removals) into the folder it names: it is refused, or with ``overwrite`` removed as a
    link. A ``steps`` that is a file is refused: it is not the package's."""
    steps = folder / STEPS
    if steps.is_symlink():
        if not overwrite:
            raise ResultsFolderError(
                errno.EEXIST,
                f"results folder {folder}: {steps} is a symbolic link to {os.readlink(steps)}; "
                "a run writes only inside its folder: pass --overwrite (overwrite=True) to "
                "remove the link (not what it names), or choose another --out",
            )
        try:
            steps.unlink()
        except OSError as exc:
            raise write_error(steps, exc) from exc
        log.info("removed the symbolic link %s", steps)
    elif steps.exists() and not steps.is_dir():
        raise ResultsFolderError(
            errno.ENOTDIR,
            f"results folder {folder}: {steps} is a file, not the package's steps folder; "
            "move it or choose another --out",
        )


def claim(folder: Path | str, overwrite: bool, start: Mapping[str, Any]) -> RunFolder:
    """Make ``folder`` the folder of this run: create it, lock it, refuse it if it holds
    another run (unless ``overwrite``: then remove the package's own files, and only them),
    and write ``summary.json`` with status ``running`` and ``start`` (name, sizes).

    Raises :class:`ResultsFolderError` (an OSError) naming the folder: a file, not
    writable, in use by a live run, or holding another run without ``overwrite``."""
    folder = folder_path(folder)
    _refuse_path(folder)
    fd = _lock(folder)
    locked = fd is not None
    if fd is not None and _hand_over_lock(folder, fd):
        # the supervising process holds the lock from now on, so it outlives this process
        # killed outright (then that process records how it died) and ends with it
        os.close(fd)
        fd = None
    claimed = False
    try:
        previous = state(folder, _locked_here=True)
        # a Ctrl-C while the old run is removed would leave part of it and no summary:
        # it waits until the folder is this run's (summary.json running), then stops it
        with deferred_signals():
            _refuse_foreign_steps(folder, overwrite)
            if previous.kind != "empty":
                if not overwrite:
                    raise ResultsFolderError(
                        errno.EEXIST,
                        f"{previous.describe(folder)}; pass --overwrite (overwrite=True) to replace "
                        "it, or choose another --out",
                    )
                count = remove_own_files(folder)
                log.info("removed %d files of the previous run from %s", count, folder)
            write_summary(
                folder,
                {
                    "status": RUNNING,
                    "reason": "the analysis is running",
                    "pid": os.getpid(),
                    "host": socket.gethostname(),
                    "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                },
                start,
            )
            claimed = True
    except BaseException as exc:
        if claimed:  # a signal held back while the folder was claimed: the run never started
            record_stopped(folder, exc)
        if fd is not None:
            os.close(fd)
        raise
    return RunFolder(folder, fd, locked)


#: in a supervised child, how to hand the lock of a folder to the supervising process
#: (:func:`masonry_dem._supervisor.hand_over_lock`, set as the child starts); None: no one
lock_keeper: Callable[[Path, int], bool] | None = None


def _hand_over_lock(folder: Path, fd: int) -> bool:
    return lock_keeper is not None and lock_keeper(folder, fd)


def steps_listed(folder: Path | str) -> int:
    """How many steps ``blocks.pvd`` of ``folder`` lists (0 without one)."""
    import xml.etree.ElementTree as ET

    try:
        return sum(1 for _ in ET.parse(Path(folder) / BLOCKS_PVD).getroot().iter("DataSet"))
    except (OSError, ET.ParseError):
        return 0


def record_death(folder: Path, fd: int, pid: int, status: str, what: str) -> str | None:
    """For the supervising process (:mod:`masonry_dem._supervisor`), which holds ``fd``, the
    lock of ``folder`` handed over by its child ``pid``, now dead by a signal (``what``):
    if the child left ``summary.json`` ``running``, it says ``status`` (``failed``,
    ``interrupted``) with ``what`` and the steps the folder keeps (every one written stays).
    The lock is let go either way. Returns what the folder says now, or None if the child
    had recorded its end itself."""
    path = folder / LOCK
    try:
        if not _same_file(fd, path):  # released by the child: its end is recorded
            return None
        summary = read_summary(folder)
        if summary.get("status") != RUNNING or summary.get("pid") != pid:
            return None
        steps = steps_listed(folder)
        write_summary(
            folder,
            {
                **summary,
                "status": status,
                "reason": f"{what}; after {steps} steps written",
                "steps_written": steps,
            },
        )
        with _quiet():
            path.unlink()
        return f"results folder {folder} says {status}, with the {steps} steps written"
    finally:
        os.close(fd)


def record_stopped(folder: Path, exc: BaseException, done: int = 0, **extra: Any) -> dict:
    """``summary.json`` of a run stopped by ``exc`` after ``done`` steps: ``interrupted``
    (a signal, Ctrl-C) or ``failed``, over what it says already; ``extra``: more keys. A
    failing disk is logged: the exception that stopped the run is the one to report."""
    from masonry_dem._signals import interruption

    signal = interruption(exc)
    cause = signal or exc
    why = (
        (cause.strerror if isinstance(cause, OSError) else None)
        or str(cause)
        or type(cause).__name__
    )
    reason = (
        f"{why} after {done} steps"
        if signal is not None
        else f"stopped by an error after {done} steps: {why}"
    )
    end = {"status": INTERRUPTED if signal is not None else "failed", "reason": reason, **extra}
    try:
        return write_summary(folder, {**read_summary(folder), **end})
    except OSError as err:
        log.warning("%s: the run's end is not recorded (%s)", folder, err)
        return end
