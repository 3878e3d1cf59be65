"""Compiling the kernels an analysis uses before it starts: announced, and on two cores at once.

On a machine whose numba cache is empty (a fresh install, a new numba or CPU) the first
analysis compiles the kernels of the interface law and the tangent assembly. :func:`prepare`
says so first ("compiling kernels, once per machine, about N s") and compiles them on a tiny
model of the same types, the law's forces in this process and its tangent in a second one
(the two groups share no code to compile, and numba compiles on one core), so the wait is the
longer group instead of the sum. The disk cache then serves every later process.
``masonry-dem warmup`` calls :func:`compile_kernels` for every variant ahead of time.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

# the modules of every kernel, so that jit's catalogue (the kernels pending, the estimates,
# the copy at installation) holds them all; jit, below them, cannot import them
import masonry_dem.constitutive.law_kernels  # noqa: F401
import masonry_dem.solvers.dynamic_relaxation.kinetic  # noqa: F401
import masonry_dem.solvers.static.problem  # noqa: F401
from masonry_dem import jit

__all__ = ["compile_kernels", "prepare"]

log = logging.getLogger(__name__)

#: the variants (parallel or not) this process found compiled or cached: not checked again
_READY: set[bool] = set()


def _tiny_problem():  # -> DiscreteProblem
    """One block on a base: every kernel of an analysis, on arrays of the analysis' types."""
    from masonry_dem.geometry.builders import add_base, single_block
    from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
    from masonry_dem.solvers.static.problem import DiscreteProblem

    blocks, base = add_base(single_block(0.1, 0.2, 0.1, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional(direction=(0, 0, 1))],
    )
    return DiscreteProblem(model)


def _forces_group(lazy: bool = False) -> None:
    """The residual's kernels: the law's forces, the strength check, and with ``lazy`` the
    forward difference and the relaxation's time steps (compiled on their first call
    otherwise: many analyses never call them)."""
    from masonry_dem.constitutive.law import fd_tangent
    from masonry_dem.solvers.dynamic_relaxation.integrator import Relaxation, RelaxationStart

    problem = _tiny_problem()
    m = problem.model.interfaces.count
    _, _, response = problem.residual(
        np.zeros(problem.model.n_dofs), 0.0, np.zeros((m, 6)), np.zeros(m, dtype=bool)
    )
    problem.law.utilisation(response)
    if not lazy:
        return
    law = problem.law
    fd_tangent(
        np.zeros((m, 6)),
        np.ones((m, 6)),
        np.zeros(m),
        np.arange(m, dtype=np.int64),
        law._domain,
        np.ones((m, 6)),
        law.projection,
        np.zeros(m, dtype=bool),
    )
    relaxation = Relaxation(problem.model)
    nf = relaxation.Hf.shape[1]
    at_rest = RelaxationStart(
        np.zeros(nf), np.zeros((m, 6)), np.zeros(m, dtype=bool), 0.0, np.ones((m, 6))
    )
    relaxation.relax_with_cuts(at_rest, 0.0)


def _tangent_group() -> None:
    """The tangent's kernels: the joints' tangents as Newton builds them (the law's consistent
    tangent, the zero-capacity reduction) and their assembly (whole, and updated)."""
    from masonry_dem.constitutive.law import LawResponse

    problem = _tiny_problem()
    m = problem.model.interfaces.count
    # what the forces kernel returns, without compiling it here too
    response = LawResponse(
        np.zeros((m, 6)), np.zeros(m), np.zeros((m, 6)), np.zeros(m, dtype=np.uint8), None
    )
    T = problem.joint_tangents(response, 1e-9)
    problem.tangent_assembler.data(T)
    problem.tangent_assembler.update(T)  # the assembly of the tangents Newton factorizes


def _run_group(group: str, parallel: bool, lazy: bool = False) -> None:
    before = jit.set_parallel_from(0 if parallel else jit.parallel_from())
    try:
        if group == "forces":
            _forces_group(lazy)
        else:
            _tangent_group()
    finally:
        jit.set_parallel_from(before)


def _start_child(group: str, parallel: bool) -> subprocess.Popen[bytes]:
    """A second interpreter compiling ``group`` (a plain process, not a fork or a
    multiprocessing spawn: no threads copied, no user ``__main__`` run again)."""
    package_root = str(Path(__file__).resolve().parents[2])
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (package_root, env.get("PYTHONPATH")) if p)
    code = (
        "from masonry_dem.solvers.warmup import _run_group; "
        f"_run_group({group!r}, {bool(parallel)!r})"
    )
    return subprocess.Popen(
        [sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )


def compile_kernels(parallel: bool = False, processes: int = 2, lazy: bool = False) -> float:
    """Compile (or load from the disk cache) the kernels of an analysis: the serial variants,
    or the parallel ones with ``parallel``; with ``lazy`` also those compiled on first call. With ``processes`` >= 2 and two cores the tangent's
    kernels compile in a second process beside this one's (their code reaches this process
    through the disk cache; if that process fails they compile here). Returns the seconds."""
    t0 = time.perf_counter()
    jit.mark_announced(parallel)  # said once for all by the caller
    child = None
    if processes >= 2 and (os.cpu_count() or 1) >= 2:
        try:
            child = _start_child("tangent", parallel)
        except OSError as exc:  # no second interpreter: everything here
            log.debug("no second process to compile in: %s", exc)
    _run_group("forces", parallel, lazy)
    if child is not None:
        _, err = child.communicate()
        if child.returncode != 0:
            log.warning(
                "compiling in a second process failed (exit code %s): %s",
                child.returncode,
                err.decode(errors="replace").strip().splitlines()[-1:],
            )
    _run_group("tangent", parallel)  # loads what the second process compiled
    return time.perf_counter() - t0


def prepare(interfaces: int, processes: int = 2) -> float:
    """Before an analysis of a model with ``interfaces`` interfaces: if it would compile
    kernels (empty or stale cache), announce it (a warning: "compiling kernels, once per
    machine, about N s") and compile them (:func:`compile_kernels`). Returns the seconds spent
    compiling, 0 when every kernel is cached."""
    parallel = interfaces >= jit.parallel_from()
    if parallel in _READY:
        return 0.0
    seconds = 0.0
    if jit.compile_pending(parallel):
        jit.announce_compilation(interfaces, processes=processes)
        seconds = compile_kernels(parallel, processes)
        log.info("kernels compiled in %.1f s", seconds)
    _READY.add(parallel)
    return seconds
