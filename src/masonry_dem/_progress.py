"""The channel through which a running analysis reports its progress: a callback held in a
context variable (as the limit analysis's budget is), so that a solver reports from any
depth of the thread (or task) that set it, with no argument passed down to it.

What is reported is the reporter's own event (``LimitProgress`` of the limit analysis,
``NewtonProgress`` of the static solver); a listener keeps the kinds it shows.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

log = logging.getLogger(__name__)

Listener = Callable[[Any], None]

_listener: ContextVar[Listener | None] = ContextVar("progress_listener", default=None)


@contextmanager
def reporting(listener: Listener | None) -> Iterator[None]:
    """Events reported inside are handed to ``listener`` (None: to nobody)."""
    token = _listener.set(listener)
    try:
        yield
    finally:
        _listener.reset(token)


def listening() -> bool:
    """Whether anybody listens: a reporter builds its event only then."""
    return _listener.get() is not None


def report(event: Any) -> None:
    """Hand ``event`` to the listener, if there is one. A listener that raises is logged and
    dropped: what shows the progress never stops the analysis."""
    listener = _listener.get()
    if listener is None:
        return
    try:
        listener(event)
    except Exception:  # noqa: BLE001 (a display's error is not the analysis's)
        log.warning("the progress callback failed; no more progress is reported", exc_info=True)
        _listener.set(None)
