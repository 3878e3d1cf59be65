"""What a static pushover will need, known before it starts: memory and time from the size of
the wall alone, and the check that refuses a run the machine cannot hold.

The estimate is a sum of parts, each proportional to what it stores, with constants measured
by ``python benchmarks/bench_scale.py`` (walls of 10^2 to 10^5 blocks;
docs/history/solvers_record.md, "Scale"):

* ``runtime``: the interpreter with numpy, scipy, numba and the compiled kernels;
* ``model``: blocks, interfaces, the compatibility matrix H and the interface law's arrays;
* ``assembly``: the fixed-pattern tangent assembler (for each interface 144 terms: where
  they go, one (12 x 12) block of the tangent) and the tangent's entries;
* ``kept``: what the tangent's update keeps between factorizations (each joint's tangent
  and 12 x 12 block, the entries, and which entries each joint adds to);
* ``factors``: the sparse LU of the tangent. A running-bond wall is a planar graph of blocks,
  so with a nested-dissection ordering the factors of its n DOFs hold about
  ``FILL_PER_DOF x n x log2(n / 6)`` entries (George's bound: O(n log n) for planar graphs);
* ``history``: every converged step kept in memory (q, actions, states, utilisation, flags),
  or three of them where the run streams its steps to disk (``streamed_history``).

Time: the analysis is ``factorizations x`` (seconds per factorization, growing like
n^FACTOR_EXPONENT) ``+ iterations x`` (seconds per Newton iteration without the
factorization: a fixed part, the Python around the kernels, and a part linear in the
interfaces), with the iterations and factorizations of the pushovers of the measured walls,
growing like blocks^GROWTH. :func:`run_time` adds what a run does around the analysis: the
kernels compiled (an empty or stale numba cache, once per machine) or loaded from the disk
cache, and the pictures. The total is said as a range, from half to :data:`SPREAD` times it,
widened on a machine busier than its cores (:func:`busy_factor`): a message, not a promise;
memory is the figure that refuses a run.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace

#: bytes of the interpreter, numpy, scipy, numba and the compiled kernels (peak RSS of the
#: 10^2-block pushover)
RUNTIME_BYTES = 250e6
#: bytes per block and per interface of the model and the solver's set-up (H, the law's
#: arrays, the tangent assembler's 144 terms per interface and its construction's sort)
MODEL_BYTES_PER_BLOCK = 2_000.0
MODEL_BYTES_PER_INTERFACE = 12_000.0
#: bytes per interface of ``TangentAssembler.update``'s store: the joint's tangent (288)
#: and block (1 152), its share of the entries (82 of them, 656) and of their joint index
#: (141 terms, 564): 2 670 on the 909-block wall
KEPT_BYTES_PER_INTERFACE = 2_700.0
#: entries of the LU factors per DOF per log2(n / 6) (PARDISO, METIS ordering); 16 bytes
#: per entry with its index and the library's work space
FILL_PER_DOF = 22.0
BYTES_PER_FACTOR_ENTRY = 16.0
#: bytes per block and per interface of one converged step kept in the History
STEP_BYTES_PER_BLOCK = 48.0
STEP_BYTES_PER_INTERFACE = 66.0
#: converged steps of a pushover to collapse (the benchmark walls: 46-62 steps)
STEPS = 70
#: Newton iterations and factorizations of a pushover to collapse, and how they grow with
#: the blocks. On the benchmark walls (``bench_scale.py``, Eurocode-6 slenderness, mortar
#: joints) they do not grow: 645 / 300 at 909 blocks, 449 / 198 at 10 017, 465 / 208 at
#: 99 878 (docs/history/solvers_record.md, "Scale")
ITERATIONS = 500
FACTORIZATIONS = 230
GROWTH = 0.0
#: seconds per factorization of n DOFs: FACTOR_SECONDS x (n / 6e4)^FACTOR_EXPONENT
#: (PARDISO, 2 threads: 0.147 s at 60 050 DOFs, 1.76 s at 599 216)
FACTOR_SECONDS = 0.15
FACTOR_EXPONENT = 1.08
#: seconds per Newton iteration and interface without the factorization (law, residual,
#: tangent assembly, solves, line search: 0.069 s an iteration at 29 850 interfaces, 0.34 s
#: at about 3e5)
ITERATION_SECONDS_PER_INTERFACE = 1.5e-6
#: seconds per Newton iteration whatever the size (the Python around the kernels: the default
#: wall, 107 interfaces, ran 572 iterations and 305 factorizations in 0.52 s, idle)
ITERATION_SECONDS_FIXED = 7e-4
#: seconds to load the compiled kernels from numba's disk cache (a warm run's first analysis)
KERNEL_LOAD_SECONDS = 0.7
#: the pictures ``run`` writes: pyvista's import and OpenGL context once, then per picture a
#: fixed part and one per block (1.5 s and 2 x 0.3 s for the default wall; 0.6-1.3 s a
#: picture of 10^4 blocks, ``benchmarks/bench_render.py``)
PICTURES_SECONDS = 1.5
PICTURE_SECONDS = 0.3
PICTURE_SECONDS_PER_BLOCK = 1e-4
#: the range said: from the estimate / SPREAD to the estimate x SPREAD (x the busy factor)
SPREAD = 2.0
#: a sweep's run against its pushover's analysis alone: the case built and the associative
#: limit-analysis bound besides (the bundled wall: 0.85 s a run, 0.56 s estimated)
SWEEP_RUN_FACTOR = 1.5
#: seconds to start a sweep's LocalCluster and load the kernels in its workers
SWEEP_START_SECONDS = 3.0
#: bytes a limit analysis takes above the loaded model, by backend: a fixed part and a part
#: per interface at the associative grid of 2 x 2 points a side, growing with the points
#: ((grid / 2)^2). The process's peak address space less its size before the analysis, on
#: running-bond walls: Clarabel 0.33 GB at 1 170 interfaces, 0.45 GB at 10 710 (its threads
#: and workspace, then 13 kB an interface); HiGHS 24 MB at 285 interfaces, 0.17 GB at 1 170
#: (its interior-point factors fill faster than the interfaces grow: the larger figure)
LIMIT_BYTES = {"clarabel": (0.35e9, 14e3), "highs": (0.05e9, 150e3)}
#: bytes of address space Clarabel takes per entry of its constraint matrix: the 13 kB an
#: interface of :data:`LIMIT_BYTES` over the 67 entries an interface has in the kinematic
#: form at 2 x 2 points (1 998 042 for the 29 850 interfaces of a 100 x 100 wall)
CLARABEL_BYTES_PER_ENTRY = 200.0


@dataclass(frozen=True)
class Estimate:
    """Memory [bytes] and time [s] a pushover is expected to need, with the parts."""

    blocks: int
    interfaces: int
    dofs: int
    memory: float
    #: seconds of the analysis alone
    seconds: float
    parts: dict[str, float] = field(default_factory=dict)
    #: seconds of the whole run by part (:func:`run_time`; empty: the analysis alone)
    times: dict[str, float] = field(default_factory=dict)
    #: how much slower than idle the machine may run it (:func:`busy_factor`), and why
    busy: float = 1.0
    busy_reason: str = ""

    @property
    def total_seconds(self) -> float:
        """The whole run's seconds on an idle machine (the analysis alone without
        :attr:`times`)."""
        return float(sum(self.times.values())) if self.times else self.seconds

    def time_range(self) -> tuple[float, float]:
        """(shortest, longest) seconds said: the total / SPREAD to the total x SPREAD x busy."""
        total = self.total_seconds
        return total / SPREAD, total * SPREAD * self.busy

    def describe(self) -> str:
        parts = ", ".join(f"{k} {_gb(v)}" for k, v in self.parts.items())
        lo, hi = self.time_range()
        times = ", ".join(f"{k} {_duration(v)}" for k, v in self.times.items())
        busy = f"; {self.busy_reason}" if self.busy > 1.0 and self.busy_reason else ""
        return (
            f"{self.blocks} blocks, {self.interfaces} interfaces, {self.dofs} DOFs: about "
            f"{_gb(self.memory)} of memory ({parts}); about {_duration(self.total_seconds)} "
            f"on an idle machine, expect {_duration(lo, hi)} ({times or 'the analysis'}{busy})"
        )


def _gb(b: float) -> str:
    # two figures below 1 GB: "0.37 GB over 0.36 GB", not "0.4 GB over 0.4 GB"
    if b >= 1e9:
        return f"{b / 1e9:.1f} GB"
    return f"{b / 1e9:.2f} GB" if b >= 1e8 else f"{b / 1e6:.0f} MB"


def _unit(s: float) -> tuple[float, str, int]:
    """Scale, unit and decimals to write ``s`` seconds in."""
    if s < 10:
        return 1.0, "s", 1
    if s < 120:
        return 1.0, "s", 0
    if s < 7200:
        return 60.0, "min", 0
    return 3600.0, "h", 1


def _duration(s: float, upto: float | None = None) -> str:
    """``s`` in a readable unit; with ``upto`` the range "s-upto" in the unit of ``upto``."""
    scale, unit, digits = _unit(s if upto is None else upto)
    if upto is None:
        return f"{s / scale:.{digits}f} {unit}"
    return f"{s / scale:.{digits}f}-{upto / scale:.{digits}f} {unit}"


def estimate(blocks: int, interfaces: int | None = None, dofs: int | None = None) -> Estimate:
    """The estimate for a wall of ``blocks`` blocks (``interfaces``: default 3 per block, a
    running bond; ``dofs``: default 6 per block)."""
    if blocks < 0:
        raise ValueError(f"blocks must be >= 0, got {blocks}")
    m = 3 * blocks if interfaces is None else int(interfaces)
    n = 6 * blocks if dofs is None else int(dofs)
    fill = FILL_PER_DOF * n * max(math.log2(max(n, 6) / 6.0), 1.0)
    parts = {
        "runtime": RUNTIME_BYTES,
        "model": MODEL_BYTES_PER_BLOCK * blocks + MODEL_BYTES_PER_INTERFACE * m,
        "kept": KEPT_BYTES_PER_INTERFACE * m,
        "factors": BYTES_PER_FACTOR_ENTRY * fill,
        "history": STEPS * (STEP_BYTES_PER_BLOCK * blocks + STEP_BYTES_PER_INTERFACE * m),
    }
    if should_stream(blocks, m):  # the run keeps its steps on disk: 3 in memory
        parts["history"] *= 3 / STEPS
    more = (max(blocks, 1) / 1e3) ** GROWTH
    seconds = more * (
        FACTORIZATIONS * FACTOR_SECONDS * (n / 6e4) ** FACTOR_EXPONENT
        + ITERATIONS * (ITERATION_SECONDS_FIXED + ITERATION_SECONDS_PER_INTERFACE * m)
    )
    return Estimate(blocks, m, n, float(sum(parts.values())), float(seconds), parts)


def busy_factor(load: float | None = None, cores: int | None = None) -> tuple[float, str]:
    """How much slower than idle a run may go on a machine whose one-minute load average is
    ``load`` on ``cores`` cores (default: this machine's now): 1 while a core is free, else
    (load + 1) / cores, the share of a core the run can expect among the others. Returns the
    factor and a phrase saying why ("" when 1)."""
    if cores is None:
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
        cores = cores or os.cpu_count() or 1
    if load is None:
        try:
            load = os.getloadavg()[0]
        except OSError:  # no load average on this platform: say nothing of it
            return 1.0, ""
    factor = max(1.0, (float(load) + 1.0) / max(int(cores), 1))
    if factor <= 1.0:
        return 1.0, ""
    return factor, f"the machine is busy: load {load:.1f} on {cores} cores"


def run_time(
    est: Estimate,
    compile_seconds: float = 0.0,
    pictures: int = 0,
    load: float | None = None,
    cores: int | None = None,
) -> Estimate:
    """``est`` with the seconds of a whole run by part: compiling the kernels
    (``compile_seconds`` > 0: the cache is empty or stale) or loading them from the disk
    cache, the analysis, and ``pictures`` PNGs; and the :func:`busy_factor` of the machine
    (``load`` on ``cores``: default, this machine's now)."""
    times: dict[str, float] = {}
    if compile_seconds > 0:
        times["compiling the kernels (once per machine)"] = float(compile_seconds)
    else:
        times["loading the compiled kernels"] = KERNEL_LOAD_SECONDS
    times["analysis"] = est.seconds
    if pictures > 0:
        times["pictures"] = PICTURES_SECONDS + pictures * (
            PICTURE_SECONDS + PICTURE_SECONDS_PER_BLOCK * est.blocks
        )
    busy, reason = busy_factor(load, cores)
    return replace(est, times=times, busy=busy, busy_reason=reason)


@dataclass(frozen=True)
class LimitEstimate:
    """Memory [bytes] a limit analysis is expected to take above the loaded model."""

    blocks: int
    interfaces: int
    grid: int
    backend: str
    memory: float
    parts: dict[str, float] = field(default_factory=dict)

    def describe(self) -> str:
        parts = ", ".join(f"{k} {_gb(v)}" for k, v in self.parts.items())
        return (
            f"{self.blocks} blocks, {self.interfaces} interfaces, {self.grid} x {self.grid} "
            f"points a side, {self.backend}: about {_gb(self.memory)} of memory ({parts})"
        )


def limit_estimate(blocks: int, interfaces: int, grid: int, backend: str) -> LimitEstimate:
    """The memory of a limit analysis of ``interfaces`` interfaces by ``backend`` ("highs"
    or "clarabel") at ``grid`` x ``grid`` points a side (:data:`LIMIT_BYTES`)."""
    fixed, per_interface = LIMIT_BYTES[backend]
    parts = {"solver": fixed, "problem": per_interface * interfaces * (grid / 2.0) ** 2}
    return LimitEstimate(
        int(blocks), int(interfaces), int(grid), backend, float(sum(parts.values())), parts
    )


def sweep_time(
    runs: int,
    run_seconds: float,
    workers: int,
    load: float | None = None,
    cores: int | None = None,
) -> tuple[float, str]:
    """Seconds a sweep of ``runs`` runs of ``run_seconds`` each (:func:`estimate`'s analysis)
    takes on ``workers`` processes of an idle machine, and the sentence saying it as a range
    (widened by :func:`busy_factor`)."""
    one = run_seconds * SWEEP_RUN_FACTOR
    total = SWEEP_START_SECONDS + math.ceil(runs / max(int(workers), 1)) * one
    busy, reason = busy_factor(load, cores)
    lo, hi = total / SPREAD, total * SPREAD * busy
    why = f"; {reason}" if reason else ""
    return total, (
        f"about {_duration(one)} a run, {_duration(total)} on {workers} workers of an idle "
        f"machine, expect {_duration(lo, hi)}{why}"
    )


def machine_memory() -> float | None:
    """Bytes of memory this process may still take: the least of the machine's available
    memory (MemAvailable of /proc/meminfo, else the physical memory), what the process's
    address-space limit (RLIMIT_AS, ``ulimit -v``) leaves above its present size, and what
    its cgroup's memory limit leaves above the cgroup's use; None where none can be read."""
    limits = [m for m in (_available(), _address_space_left(), _cgroup_left()) if m is not None]
    return min(limits) if limits else None


def memory_limit_source() -> str:
    """Which limit :func:`machine_memory` comes from, for the message that names it."""
    named = {
        "the process's address-space limit (ulimit -v)": _address_space_left(),
        "the cgroup's memory limit": _cgroup_left(),
        "the machine's available memory": _available(),
    }
    known = {k: v for k, v in named.items() if v is not None}
    return min(known, key=lambda k: known[k]) if known else "the machine's available memory"


def _available() -> float | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def _address_space_left() -> float | None:
    """RLIMIT_AS less the process's virtual size (VmSize): a run's allocations count against
    the limit, whatever the machine has free."""
    try:
        import resource
    except ImportError:  # pragma: no cover - Windows
        return None
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    used = _status_bytes("VmSize:") or 0.0
    return max(float(soft) - used, 0.0)


def _status_bytes(key: str) -> float | None:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return None


def _cgroup_left() -> float | None:
    """memory.max less memory.current of the process's cgroup (v2), or the v1 equivalents."""
    for limit_file, usage_file in (
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
        (
            "/sys/fs/cgroup/memory/memory.limit_in_bytes",
            "/sys/fs/cgroup/memory/memory.usage_in_bytes",
        ),
    ):
        try:
            with open(limit_file) as f:
                text = f.read().strip()
            if text == "max" or int(text) >= 2**60:  # no limit (v1 writes a huge number)
                return None
            with open(usage_file) as f:
                return max(float(text) - float(f.read().strip()), 0.0)
        except (OSError, ValueError):
            continue
    return None


def require_memory(need: float, what: str) -> None:
    """Raise MemoryError when ``need`` bytes are more than the process may still take
    (:func:`machine_memory`: the machine's available memory, what ``ulimit -v`` leaves, what
    the cgroup's limit leaves), naming the limit met: for a library that aborts the process
    on a failed allocation (Clarabel, in Rust) instead of reporting it, and for a cgroup,
    whose OOM killer ends the process with a SIGKILL no process can report."""
    left = machine_memory()
    if left is not None and need > left:
        raise MemoryError(
            f"{what} would need about {_gb(need)}; {memory_limit_source()} leaves {_gb(left)}"
        )


class TooLarge(RuntimeError):
    """The estimated memory of a run is above what it may use."""


def check_fits(est: Estimate | LimitEstimate, max_memory: float | None = None) -> None:
    """Raise :class:`TooLarge` when ``est.memory`` is above ``max_memory`` bytes (None: the
    machine's available memory)."""
    limit = machine_memory() if max_memory is None else max_memory
    if limit is None:
        return
    if est.memory > limit:
        source = "--max-memory" if max_memory is not None else memory_limit_source()
        raise TooLarge(
            f"the run would need {est.describe()}; that is over {_gb(limit)} "
            f"({source}). Use a smaller wall, or raise --max-memory if the estimate is wrong."
        )


def parse_memory(text: str) -> float:
    """Bytes of a size such as ``16G``, ``500M``, ``2.5GB`` or ``1e9``."""
    units = {"": 1.0, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12}
    t = str(text).strip().upper().removesuffix("B").removesuffix("I")
    unit = t[-1:] if t[-1:] in units and t[-1:] != "" and not t[-1:].isdigit() else ""
    number = t[: len(t) - len(unit)] if unit else t
    try:
        value = float(number) * units[unit]
    except ValueError:
        raise ValueError(
            f"--max-memory must be a size such as 16G, 500M or 2.5e9 (bytes), got {text!r}"
        ) from None
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"--max-memory must be positive, got {text!r}")
    return value


#: the return (or cross) walls of the plans behind their facade (the box: its own count)
_RETURNS = {"l_wall": 1, "u_wall": 2, "t_wall": 1, "box_wall": 0}


def blocks_of_geometry(geometry: dict) -> int | None:
    """Blocks of a case file's ``[geometry]`` counted from the builder's parameters without
    building them (a wall of 10^6 blocks takes seconds to build), openings not subtracted;
    None for a builder or parameters it does not know (the caller then builds the model and
    estimates from it)."""
    builder = geometry.get("builder")
    # the base slab and the loading beam, each one block
    base = (1 if geometry.get("base", False) else 0) + (1 if geometry.get("top_beam") else 0)
    try:
        if builder == "running_bond_wall":
            n, courses = int(geometry["blocks_along_length"]), int(geometry["courses"])
            halves = (
                courses // 2 if not geometry.get("start_with_half", False) else -(-courses // 2)
            )
            return n * courses + halves + base
        if builder == "running_bond_wall_of_size":
            e = float(geometry.get("joint", 0.0))
            # a block size by its name or by the paper's letter (KeyError: neither given)
            b = float(geometry["block_length" if "block_length" in geometry else "b"])
            a = float(geometry["block_height" if "block_height" in geometry else "a"])
            n = max(1, round(float(geometry["length"]) / (b + e)))
            courses = max(1, round(float(geometry["height"]) / (a + e)))
            return n * courses + courses // 2 + base
        if builder == "stack_bond_column":
            return int(geometry["courses"]) + base
        if builder == "single_block":
            return 1 + base
        if builder == "boxes":
            return len(geometry["lower"]) + base
        if builder in _RETURNS:
            # an upper bound: whole blocks along each run and a few cut pieces at its ends
            n, courses = int(geometry["blocks_along_length"]), int(geometry["courses"])
            if builder == "box_wall":
                m = int(geometry.get("blocks_along_depth") or n)
                return courses * (2 * (n + m) + 8) + base
            m = int(geometry.get("return_blocks", 4))
            return courses * (n + 3 + _RETURNS[builder] * (m + 2)) + base
    except (KeyError, TypeError, ValueError):
        return None
    return None


def step_bytes(blocks: int, interfaces: int) -> float:
    """Bytes of one converged step in memory (q, actions, state, utilisation, flags)."""
    return STEP_BYTES_PER_BLOCK * blocks + STEP_BYTES_PER_INTERFACE * interfaces


def should_stream(blocks: int, interfaces: int, available: float | None = None) -> bool:
    """Stream the History when its expected steps (:data:`STEPS`) would take more than a
    quarter of the memory available (``available`` bytes; None: the machine's)."""
    if available is None:
        available = machine_memory()
    if available is None:
        return False
    return STEPS * step_bytes(blocks, interfaces) > 0.25 * available
