"""The budget of one limit analysis: a wall-clock time limit for the whole analysis and an
iteration limit for every solver call, so that no solve runs without an end.

:func:`limit_analysis` opens a :func:`budget`. Every solver call is handed what is left of
it (:func:`solver_seconds`) as the solver's own time limit (HiGHS's ``time_limit``, the column
generation's master's too; Clarabel's ``time_limit``) and an iteration limit (the constants
below); the package's own loops check :func:`spent` between their steps (the
normal-equation interior point method, the non-associative iteration). A solve stopped by
its budget returns the solution word ``"budget"``, which the analysis reports as ``failed``
with the solver's own words.

The budget is held in a context variable: the analysis's solvers all run in the thread (or
task) that called :func:`limit_analysis`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import TYPE_CHECKING

from masonry_dem._signals import check_stop

if TYPE_CHECKING:
    from scipy import sparse

#: the default time limit of one analysis [s]: generous (a 10^4-block wall takes seconds to
#: tens of seconds), so that it stops only a solve that would not end
DEFAULT_TIME_LIMIT = 600.0
#: interior point iterations of one HiGHS solve (HiGHS's IPX takes tens on these LPs; its own
#: default has no limit)
HIGHS_IPM_ITERATIONS = 2_000
#: simplex iterations of one HiGHS master solve of the column generation (its own default
#: has no limit)
HIGHS_SIMPLEX_ITERATIONS = 5_000_000
#: interior point iterations of one Clarabel solve (Clarabel's own default; it takes 20-60
#: on these problems)
CLARABEL_ITERATIONS = 200

_deadline: ContextVar[float] = ContextVar("limit_analysis_deadline", default=math.inf)


@contextmanager
def budget(seconds: float) -> Iterator[None]:
    """Solvers called inside stop ``seconds`` from now at the latest."""
    token = _deadline.set(time.monotonic() + seconds)
    try:
        yield
    finally:
        _deadline.reset(token)


def seconds_left() -> float:
    """Seconds left of the current budget (inf outside one, 0 once spent)."""
    deadline = _deadline.get()
    return max(deadline - time.monotonic(), 0.0) if math.isfinite(deadline) else math.inf


def spent() -> bool:
    """Has the current budget's time run out? A stop a signal asked for (``_signals``)
    raises here: every loop that asks (the non-associative iteration, the normal-equation
    IPM) is one the signal stops."""
    check_stop()
    return seconds_left() <= 0.0


def solver_seconds() -> float:
    """The time limit to hand a solver: the seconds left, a millisecond at least (a limit of
    zero may read as "none" to a solver), and a large finite number outside a budget."""
    left = seconds_left()
    return 1e7 if math.isinf(left) else max(left, 1e-3)


def clarabel_room(A: sparse.csc_matrix) -> None:
    """MemoryError before Clarabel starts on ``A`` where the memory the process may still take
    (the machine's available memory, ``ulimit -v``, the cgroup's limit) is too little:
    Clarabel, in Rust, aborts the process on a failed allocation."""
    from masonry_dem.solvers.resources import (
        CLARABEL_BYTES_PER_ENTRY,
        LIMIT_BYTES,
        require_memory,
    )

    need = LIMIT_BYTES["clarabel"][0] + CLARABEL_BYTES_PER_ENTRY * A.nnz
    require_memory(need, f"Clarabel on {A.shape[0]} x {A.shape[1]} ({A.nnz} entries)")
