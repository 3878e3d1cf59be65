"""What every benchmark prints first: the machine and its load, and the one-line ``--help``.

Seconds measured on a shared machine scale with its load, so each script of ``benchmarks/``
starts its output with :func:`print_machine` (CPU model, cores, load average, Python, numpy
and numba versions, the thread variables) and builds its command line with :func:`arguments`,
whose ``--help`` prints the script's one-line purpose (its docstring's first line) first.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from importlib import metadata

#: the environment variables that set how many threads the kernels and libraries use
THREAD_VARIABLES = (
    "NUMBA_NUM_THREADS",
    "OMP_NUM_THREADS",
    "OMP_WAIT_POLICY",
    "MKL_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MASONRY_DEM_FACTORIZER",
)


def purpose(doc: str | None) -> str:
    """The one-line purpose: the first line of a script's docstring."""
    return (doc or "").strip().splitlines()[0].strip() if (doc or "").strip() else ""


class _Parser(argparse.ArgumentParser):
    def format_help(self) -> str:
        return f"{self.purpose}\n\n{super().format_help()}"


def arguments(doc: str | None, **kwargs) -> argparse.ArgumentParser:
    """An argument parser whose ``--help`` prints ``doc``'s first line, then the usage, then
    the rest of ``doc`` as written."""
    first = purpose(doc)
    rest = (doc or "").strip()[len(first) :].strip("\n")
    kwargs.setdefault("description", rest or None)
    kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
    p = _Parser(**kwargs)
    p.purpose = first  # type: ignore[attr-defined]
    return p


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def _version(distribution: str) -> str:
    """The installed version, read without importing (a script may set up numba first)."""
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "-"


def machine_lines() -> list[str]:
    """The machine and its load, as lines to print."""
    cores = os.cpu_count() or 0
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else cores
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    threads = ", ".join(f"{v}={os.environ[v]}" for v in THREAD_VARIABLES if v in os.environ)
    autogroup = ""
    try:
        with open("/proc/sys/kernel/sched_autogroup_enabled") as f:
            autogroup = f", autogroup {f.read().strip()}"
    except OSError:
        pass
    return [
        f"machine: {_cpu_model()}, {cores} cores ({usable} usable){autogroup}, "
        f"{platform.system()} {platform.release()}",
        f"load average (1, 5, 15 min): {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}",
        f"python {platform.python_version()}, numpy {_version('numpy')}, "
        f"numba {_version('numba')}, scipy {_version('scipy')}",
        f"threads: {threads or 'no thread variable set'}",
    ]


def print_machine(file=None) -> None:
    """Print the machine and its load (stdout unless ``file``), then a blank line."""
    out = sys.stdout if file is None else file
    for line in machine_lines():
        print(line, file=out)
    print(file=out, flush=True)


if __name__ == "__main__":
    print_machine()
