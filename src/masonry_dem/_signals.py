"""Stopping a run cleanly on SIGINT (Ctrl-C) and SIGTERM.

:func:`stop_on_signals` records the first signal and :func:`check_stop` raises it as
:class:`Interrupted` (a KeyboardInterrupt); the run command calls it after each step, the
static solver at each Newton iteration (so before each factorization) and dynamic relaxation
at each time step and each return of its kernel, so a long step stops within an iteration, and
the results writer, on its way out, records the run as ``interrupted`` with every step written
so far (the step under way is dropped). An exception raised from the handler itself
would land inside a compiled kernel's call and come out as a SystemError (seen with SIGTERM
in the residual), so only a second signal stops at once. :func:`deferred_signals` holds a
signal back while files that must agree are being finished, and raises it afterwards.
"""

from __future__ import annotations

import logging
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

T = TypeVar("T")

__all__ = [
    "Interrupted",
    "check_stop",
    "deferred_signals",
    "exit_code",
    "interruption",
    "raise_on_signals",
    "run_interruptible",
    "stop_on_signals",
]

log = logging.getLogger(__name__)

_SIGNALS = tuple(s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None)) if s is not None)


class Interrupted(KeyboardInterrupt):
    """The run was stopped by a signal (``signum``) or by Ctrl-C."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum


def interruption(exc: BaseException | None) -> KeyboardInterrupt | None:
    """The Ctrl-C or signal behind ``exc``: itself, or the cause of the SystemErrors a compiled
    kernel's call wraps an exception raised inside it in (several, one per nested call), or
    of the ImportError an extension's loader makes of it (VTK: "Failed to load ...")."""
    seen, first = 0, exc
    while exc is not None and seen < 100:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        if not isinstance(exc, (SystemError, ImportError)):
            return None
        exc, seen = exc.__cause__ or exc.__context__, seen + 1
    if isinstance(first, ImportError) and _raised:
        # a loader in C that keeps only the message of what stopped it (numpy: "Original
        # error was: PyCapsule_Import could not import module datetime"): the signal that
        # was raised, not the import, is what went wrong
        return Interrupted(_raised[-1])
    return None


def exit_code(exc: BaseException) -> int:
    """The shell's exit code of a process ended by a signal: 128 + its number (130 Ctrl-C)."""
    return 128 + int(getattr(exc, "signum", signal.SIGINT))


_received: list[int] = []
#: the signals :func:`raise_on_signals` raised in this process
_raised: list[int] = []


def _raise(signum: int, frame) -> None:
    _raised.append(signum)
    raise Interrupted(signum)


@contextmanager
def raise_on_signals() -> Iterator[None]:
    """SIGINT and SIGTERM raise :class:`Interrupted` at once while inside (commands with no
    steps to finish: render, validate, study)."""
    _raised.clear()
    yield from _handled(_raise)


def _handled(handler) -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, handler) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, old in previous.items():
            signal.signal(s, old if old is not None else signal.SIG_DFL)


def _request_stop(signum: int, frame) -> None:
    if _received:  # the second signal: at once
        raise Interrupted(signum)
    _received.append(signum)
    log.warning(
        "%s: stopping at the next Newton iteration (again to stop at once)",
        signal.Signals(signum).name,
    )


def check_stop() -> None:
    """Raise :class:`Interrupted` if a signal came since :func:`stop_on_signals` began."""
    if _received:
        raise Interrupted(_received[0])


@contextmanager
def stop_on_signals() -> Iterator[None]:
    """SIGINT and SIGTERM request a stop (:func:`check_stop`) while inside; a second one
    raises at once."""
    _received.clear()
    try:
        yield from _handled(_request_stop)
    finally:
        _received.clear()


@contextmanager
def deferred_signals() -> Iterator[None]:
    """SIGINT and SIGTERM wait until the block is done, then raise :class:`Interrupted`."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler if handler is not None else signal.SIG_DFL)
    if caught:
        raise Interrupted(caught[0])


def run_interruptible(work: Callable[[], T]) -> T:
    """``work()`` in a worker thread while this (the main) thread waits for it: a signal's
    handler runs only between the main thread's bytecodes, and a solver's long call into
    a C library (a HiGHS or Clarabel solve of minutes) held it back until the call
    returned. Here the main thread raises the signal's :class:`Interrupted` at once; the
    worker is left to the process's end (a daemon thread)."""
    if threading.current_thread() is not threading.main_thread():
        return work()
    box: dict[str, Any] = {}

    def target() -> None:
        try:
            box["value"] = work()
        except BaseException as exc:  # handed to the main thread
            box["error"] = exc

    worker = threading.Thread(target=target, name="interruptible-work", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(0.1)
    if "error" in box:
        raise box["error"]
    value: T = box["value"]
    return value
