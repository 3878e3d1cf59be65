"""How the compiled kernels' threads run: how many one analysis uses
(:func:`kernel_threads_for`) and how they wait between parallel loops
(:func:`set_thread_wait_policy`, called by the entry points, never at import).

The kernels (interface law, tangent assembly) share their loops among the cores, and so does
PARDISO (solvers/factorization.py gives MKL numba's thread count). On a small wall a parallel
loop does too little to pay for waking the threads, so below ``SERIAL_BELOW`` interfaces an
analysis runs them on one thread (the measurements: docs/history/solvers_record.md, "Compiled
kernels and threads"). The answers are the same bits on any number of threads.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Literal

import numba

log = logging.getLogger(__name__)

#: below this many interfaces an analysis runs its compiled kernels on one thread
SERIAL_BELOW = 300

WaitPolicy = Literal["PASSIVE", "ACTIVE"]


def set_thread_wait_policy(policy: WaitPolicy = "PASSIVE") -> str:
    """Ask the OpenMP threads of the compiled kernels to wait ``policy`` between parallel loops.

    Threads that spin while they wait (``ACTIVE``) take a core from the serial work between
    the loops and from any other process: passive waiting is the safe default for long runs
    and busy machines (docs/history/solvers_record.md, "Compiled kernels and threads").
    OpenMP reads ``OMP_WAIT_POLICY`` once, when it starts, so call this before the first
    analysis of the process; the command line calls it first thing. A value already set in
    the environment is kept; set after the kernels' threads started, it applies to the next
    process only (a warning says so).

    Parameters
    ----------
    policy : {"PASSIVE", "ACTIVE"}, default "PASSIVE"
        How the threads wait.

    Returns
    -------
    str
        The policy in force (``OMP_WAIT_POLICY``).

    Raises
    ------
    ValueError
        If ``policy`` is neither value.

    Examples
    --------
    >>> import os
    >>> import masonry_dem as md
    >>> saved = os.environ.get("OMP_WAIT_POLICY")
    >>> os.environ["OMP_WAIT_POLICY"] = "ACTIVE"  # set in the environment: kept
    >>> md.set_thread_wait_policy("PASSIVE")
    'ACTIVE'
    >>> if saved is None:
    ...     del os.environ["OMP_WAIT_POLICY"]
    ... else:
    ...     os.environ["OMP_WAIT_POLICY"] = saved
    """
    if policy not in ("PASSIVE", "ACTIVE"):
        raise ValueError(f"policy must be 'PASSIVE' or 'ACTIVE', got {policy!r}")
    unset = "OMP_WAIT_POLICY" not in os.environ
    value = os.environ.setdefault("OMP_WAIT_POLICY", policy)
    from numba.np.ufunc import parallel

    if unset and parallel._is_initialized:
        log.warning(
            "OMP_WAIT_POLICY=%s set after the kernels' threads started: it applies to the "
            "next process only; call set_thread_wait_policy() before the first analysis",
            value,
        )
    return value


@contextmanager
def kernel_threads_for(interfaces: int) -> Iterator[None]:
    """One kernel thread for a model of fewer than ``SERIAL_BELOW`` interfaces, else as set
    (``NUMBA_NUM_THREADS``). Per calling thread, restored on exit."""
    if interfaces >= SERIAL_BELOW:
        yield
        return
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)
