"""How many threads the compiled kernels use for one analysis.

The kernels (interface law, tangent assembly) share their loops among the cores, and so does
PARDISO (solvers/factorization.py gives MKL numba's thread count). On a small wall a parallel
loop does too little to pay for waking the threads (they wait passively, see
``masonry_dem/__init__.py``): one thread is faster below about 300 interfaces (measured on 2
cores, session 9: a dynamic-relaxation time step of OL1, 107 interfaces, 85 -> 48 us, of S15,
237 interfaces, 103 -> 78 us; the static OL1 0.17 -> 0.12 s; with 466 interfaces two threads
win: 205 -> 169 us). The answers are the same bits on any number of threads.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numba

#: below this many interfaces an analysis runs its compiled kernels on one thread
SERIAL_BELOW = 300


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
