"""How the package compiles its numba kernels: one decorator, its disk cache, and the first run.

Every compiled kernel is built by :func:`kernel`. What it adds to ``numba.njit``:

* **A serial and a parallel variant.** A kernel with ``numba.prange`` loops is compiled without
  ``parallel`` for walls of fewer than :data:`masonry_dem._threads.SERIAL_BELOW` interfaces
  (which run on one thread anyway) and with it for larger ones, each variant on its first use.
  Numba's parallel pass doubles the compile time, so a small wall never pays for it. Each row
  of a loop is worked out alone, so both variants give the same bits.
* **A disk cache keyed on every kernel file.** Numba renews a function's cache when the
  function's own file changes, not when a callee's file does; the kernels of the interface law
  call the strength check's row functions in another file, so the key of every kernel here also
  holds a hash of :data:`KERNEL_SOURCES`. The stamp that tells a cache file is fresh is that
  hash and the kernel's own file's (numba's is that file's time, which an installation or a
  checkout changes).
* **Kernels compiled at installation.** Building the package (``pip install .``: setup.py)
  compiles the serial variants of the eager kernels on the machine that installs it and copies
  their cache files into the package (:data:`INSTALLED`, :func:`copy_compiled`); a kernel
  found in neither numba's cache nor there (a parallel or lazy one, another numba or CPU, an
  editable install) is compiled on first use.
* **Word before the wait.** :func:`compile_pending` says which kernels a run will compile (their
  cache is empty or stale) and :func:`announce_compilation` logs "compiling kernels, once per
  machine, about N s" before it happens; ``masonry-dem warmup`` compiles them ahead.
"""

from __future__ import annotations

import hashlib
import inspect
import logging
import os
import shutil
import types
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numba
from numba.core.caching import FunctionCache, IndexDataCacheFile

from masonry_dem._threads import SERIAL_BELOW

__all__ = [
    "COMPILE_SECONDS",
    "INSTALLED",
    "KERNEL_SOURCES",
    "Kernel",
    "announce_compilation",
    "compile_estimate",
    "compile_pending",
    "compile_seconds",
    "copy_compiled",
    "kernel",
    "kernels",
    "mark_announced",
]

logger = logging.getLogger(__name__)

_PACKAGE = Path(__file__).resolve().parent

#: the files whose kernels call each other: a change in any renews the cache of all
KERNEL_SOURCES: Final[tuple[Path, ...]] = (
    _PACKAGE / "jit.py",
    _PACKAGE / "constitutive" / "check_kernels.py",
    _PACKAGE / "constitutive" / "energy_return.py",
    _PACKAGE / "constitutive" / "law_kernels.py",
)

#: seconds to compile the kernels of one analysis on an idle core (2-core AMD EPYC, see
#: docs/history/first_run_record.md): serial variants (every wall) and the parallel ones
#: (walls of SERIAL_BELOW interfaces or more) on top
COMPILE_SECONDS: Final[dict[str, float]] = {"serial": 15.0, "parallel": 12.0}


#: wall time of the compilation on two cores side by side, as a share of one core's
SIDE_BY_SIDE: Final[float] = 0.6


def _sources_hash() -> str:
    digest = hashlib.sha256()
    for path in KERNEL_SOURCES:
        digest.update(path.read_bytes())
    return digest.hexdigest()


_SOURCES_HASH: Final[str] = _sources_hash()


#: the kernels compiled when the package was built (numba's cache files, read only)
INSTALLED: Final[Path] = _PACKAGE / "_compiled"


class _KernelCache(FunctionCache):  # type: ignore[misc]
    """numba's function cache with the hash of every kernel file in its key, and in its stamp
    with the hash of the kernel's own file (its callees there); it reads what it lacks from
    :data:`INSTALLED`."""

    def __init__(self, py_func: Callable[..., Any]) -> None:
        super().__init__(py_func)
        own = hashlib.sha256(Path(inspect.getfile(py_func)).read_bytes()).hexdigest()
        self._stamp = (_SOURCES_HASH, own)
        self._cache_file = IndexDataCacheFile(
            self._cache_path, self._impl.filename_base, self._stamp
        )

    def installed(self) -> IndexDataCacheFile:
        """The kernel's cache files in :data:`INSTALLED`."""
        return IndexDataCacheFile(str(INSTALLED), self._impl.filename_base, self._stamp)

    def _index_key(self, sig: Any, codegen: Any) -> tuple[Any, ...]:
        return (*super()._index_key(sig, codegen), _SOURCES_HASH)

    def _load_overload(self, sig: Any, target_context: Any) -> Any:
        data = super()._load_overload(sig, target_context)
        if data is None and self._enabled:
            payload = self.installed().load(self._index_key(sig, target_context.codegen()))
            if payload is not None:
                data = self._impl.rebuild(target_context, payload)
        return data


def _twin(py_func: Callable[..., Any], suffix: str) -> Callable[..., Any]:
    """A copy of ``py_func`` under another qualified name: its own cache files on disk."""
    twin = types.FunctionType(
        py_func.__code__,
        py_func.__globals__,
        py_func.__name__,
        py_func.__defaults__,
        py_func.__closure__,
    )
    twin.__qualname__ = py_func.__qualname__ + suffix
    twin.__doc__ = py_func.__doc__
    return twin


def _dispatcher(py_func: Callable[..., Any], options: dict[str, Any]) -> Any:
    disp = numba.njit(**options)(py_func)
    disp._cache = _KernelCache(py_func)  # numba's own enable_caching(), with our key
    return disp


@dataclass(frozen=True)
class Kernel:
    """A compiled kernel: its serial variant, and its parallel one when it has ``prange``
    loops. Call :meth:`for_rows` with the number of rows (interfaces) to pick. ``eager``
    kernels are compiled before an analysis (:mod:`masonry_dem.solvers.warmup`); the others,
    which most analyses never call, on their first call, announced then."""

    name: str
    serial: Any  # numba dispatcher
    parallel: Any | None
    eager: bool = True
    _announced: set[str] = field(default_factory=set, compare=False, repr=False)

    def for_rows(self, rows: int) -> Any:
        """The variant for a loop over ``rows`` rows: parallel from ``SERIAL_BELOW`` rows."""
        variant = "serial"
        disp = self.serial
        if self.parallel is not None and rows >= parallel_from():
            variant = "parallel"
            disp = self.parallel
        if variant not in self._announced:  # once per process and variant
            self._announced.add(variant)
            if not _cached(disp):
                seconds = COMPILE_SECONDS[variant] / max(len(_KERNELS), 1)
                logger.warning(
                    "compiling kernel %s (%s), once per machine, about %.0f s",
                    self.name,
                    variant,
                    max(seconds, 1.0),
                )
        return disp

    def __call__(self, *args: Any) -> Any:
        """The kernel without a parallel variant called on ``args``."""
        if self.parallel is not None:
            raise TypeError(f"kernel {self.name} has two variants: pick one with for_rows")
        return self.for_rows(0)(*args)

    @property
    def variants(self) -> tuple[tuple[str, Any], ...]:
        out: tuple[tuple[str, Any], ...] = (("serial", self.serial),)
        if self.parallel is not None:
            out += (("parallel", self.parallel),)
        return out


_KERNELS: list[Kernel] = []
_PARALLEL_FROM: list[int] = [SERIAL_BELOW]


def parallel_from() -> int:
    """Rows from which the parallel variants run (``SERIAL_BELOW``; the warm-up lowers it)."""
    return _PARALLEL_FROM[0]


def set_parallel_from(rows: int) -> int:
    """Set :func:`parallel_from`; returns the previous value (for the warm-up)."""
    before = _PARALLEL_FROM[0]
    _PARALLEL_FROM[0] = int(rows)
    return before


def kernel(
    *, parallel: bool = False, eager: bool = True, **options: Any
) -> Callable[[Callable[..., Any]], Kernel]:
    """Decorator: a :class:`Kernel` of ``py_func`` compiled with ``numba.njit(**options)`` on
    first use and cached on disk; ``parallel=True`` adds the parallel variant; ``eager=False``
    leaves it out of the compilation before an analysis."""

    def wrap(py_func: Callable[..., Any]) -> Kernel:
        serial = _dispatcher(py_func, options)
        par = None
        if parallel:
            par = _dispatcher(_twin(py_func, "_parallel"), {**options, "parallel": True})
        k = Kernel(py_func.__name__, serial, par, eager)
        _KERNELS.append(k)
        return k

    return wrap


def calling_kernel(
    name: str, py_func: Callable[..., Any], callee_global: str, callee: Kernel, **options: Any
) -> Kernel:
    """A lazy :class:`Kernel` named ``name`` of ``py_func``, which calls another kernel
    through its global ``callee_global``: the serial variant calls ``callee``'s serial
    variant, the parallel one its parallel variant (so :meth:`Kernel.for_rows` picks both
    alike), each compiled with ``numba.njit(**options)`` into its own cache files."""

    def variant(dispatcher: Any, suffix: str) -> Any:
        scope = dict(py_func.__globals__)
        scope[callee_global] = dispatcher
        twin = types.FunctionType(
            py_func.__code__, scope, name + suffix, py_func.__defaults__, py_func.__closure__
        )
        twin.__qualname__ = name + suffix
        twin.__doc__ = py_func.__doc__
        return _dispatcher(twin, options)

    parallel = None if callee.parallel is None else variant(callee.parallel, "_parallel")
    k = Kernel(name, variant(callee.serial, ""), parallel, eager=False)
    _KERNELS.append(k)
    return k


def mark_announced(parallel: bool) -> None:
    """The kernels' compilation is announced already (by the warm-up): their first calls
    stay quiet (the serial variants, and the parallel ones with ``parallel``)."""
    for k in kernels():
        k._announced.add("parallel" if parallel else "serial")


def kernels() -> tuple[Kernel, ...]:
    """Every kernel of the modules imported so far (:mod:`masonry_dem.solvers.warmup`
    imports them all: the estimates and announcements run through it)."""
    return tuple(_KERNELS)


def _cached(disp: Any) -> bool:
    """Whether ``disp`` has compiled code in this process, or on disk an entry for this
    machine (numba's target) and these kernel sources (any signature: a run uses one per
    kernel)."""
    if disp.signatures:
        return True
    try:
        magic = disp.targetctx.codegen().magic_tuple()
        for cache_file in (disp._cache._cache_file, disp._cache.installed()):
            index = cache_file._load_index()  # {} when stale
            if any(key[1] == magic and key[-1] == _SOURCES_HASH for key in index):
                return True
        return False
    except Exception:  # pragma: no cover - numba's cache layout changed: assume compiled
        logger.debug("cannot read the numba cache index of %s", disp, exc_info=True)
        return True


def _pending(parallel: bool, lazy: bool = False) -> dict[str, list[str]]:
    """Names of the eager kernels (and the ``lazy`` ones) not in the cache, by variant."""
    out: dict[str, list[str]] = {"serial": [], "parallel": []}
    for k in kernels():
        if not (k.eager or lazy):
            continue
        for variant, disp in k.variants:
            if (parallel or variant == "serial") and not _cached(disp):
                out[variant].append(k.name)
    return out


def compile_pending(parallel: bool, lazy: bool = False) -> list[str]:
    """Names of the kernels an analysis would compile first: serial variants, and the
    parallel ones when ``parallel`` (a wall of ``SERIAL_BELOW`` interfaces or more); with
    ``lazy`` also those compiled on their first call."""
    pending = _pending(parallel, lazy)
    return [f"{name} ({variant})" for variant, names in pending.items() for name in names]


def compile_estimate(parallel: bool, lazy: bool = False) -> float:
    """Seconds the pending kernels take to compile: :data:`COMPILE_SECONDS` (the eager
    kernels' all together) pro rata of the kernels pending."""
    eager = [k for k in kernels() if k.eager]
    total = {"serial": len(eager), "parallel": sum(k.parallel is not None for k in eager)}
    pending = _pending(parallel, lazy)
    return sum(COMPILE_SECONDS[v] * len(names) / max(total[v], 1) for v, names in pending.items())


def compile_seconds(interfaces: int, processes: int = 1) -> float:
    """Seconds an analysis of a model with ``interfaces`` interfaces will spend compiling
    kernels first (with ``processes`` >= 2 on a machine of two cores or more, the two groups
    of :mod:`masonry_dem.solvers.warmup` side by side); 0 when every kernel it uses is
    cached."""
    parallel = interfaces >= parallel_from()
    if not compile_pending(parallel):
        return 0.0
    seconds = compile_estimate(parallel)
    side_by_side = processes >= 2 and (os.cpu_count() or 1) >= 2
    return seconds * SIDE_BY_SIDE if side_by_side else seconds


def announce_compilation(interfaces: int, processes: int = 1) -> float:
    """Log "compiling kernels, once per machine, about N s" if an analysis of a model with
    ``interfaces`` interfaces will compile kernels (on ``processes`` cores: the two groups of
    :mod:`masonry_dem.solvers.warmup` side by side); returns N (0 when all are cached)."""
    parallel = interfaces >= parallel_from()
    pending = compile_pending(parallel)
    if not pending:
        return 0.0
    seconds = compile_seconds(interfaces, processes)
    logger.warning(
        "compiling kernels, once per machine, about %.0f s (%s)", seconds, ", ".join(pending)
    )
    return seconds


def copy_compiled(target: Path) -> int:
    """Copy the cache files numba's cache holds for the kernels (index and compiled code of
    each variant compiled) into ``target``, where :data:`INSTALLED` of an installed package
    finds them; returns the number of files."""
    target.mkdir(parents=True, exist_ok=True)
    copied = 0
    for k in kernels():
        for _, disp in k.variants:
            base = disp._cache._impl.filename_base
            for path in Path(disp._cache._cache_path).glob(f"{base}.*"):
                if path.suffix in (".nbi", ".nbc"):
                    shutil.copy2(path, target / path.name)
                    copied += 1
    return copied
