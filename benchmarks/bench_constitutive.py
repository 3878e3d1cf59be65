"""Benchmark: the interface strength check and the spring model against one sparse factorization.

Run:  python benchmarks/bench_constitutive.py [--interfaces 1000000] [--steps 1000] [--n 32]
                                              [--wall-blocks 10000] [--repeat 3]

Prints one table, best of ``--repeat`` runs:

- ``check_strength``: the closed-form domain (Eqs. 9-14, A5, torsion-bending interaction) on
  ``--interfaces`` random trial actions (a mix of elastic, sliding, rocking, detached), and on as
  many interfaces as the wall below has;
- ``spring path``: one ``--n`` x ``--n`` spring interface (1024 springs by default) driven along
  a ``--steps`` load path of cyclic shear, bending and torsion, with the normal force held at
  -240 N (dn solved each step) and with dn imposed;
- ``Table A1 fits``: the 21 alpha fits of ``masonry-dem interface`` (32 x 32 springs);
- ``splu``: one ``scipy.sparse.linalg.splu`` factorization of the stiffness K = H^T Kbar H of a
  running-bond wall of about ``--wall-blocks`` blocks on a fixed base, built with the package's
  own pipeline (``running_bond_wall`` + ``detect_interfaces`` + ``Model`` + ``Assembly``): the
  matrix a panel solver factorizes at every stiffness update.

With ``--law`` it times instead the batched interface law of the solvers,
``InterfaceLaw.respond`` and ``InterfaceLaw.tangent``, on the paper's cases (``--cases``,
default S15 OL2 2-3) at the last step of their pushover (many joints sliding, rocking or
detached), against the law of git revision ``--baseline`` (default: the commit before the law
was optimised). Both run in fresh subprocesses on the same saved inputs, alternately,
``--rounds`` times; the fastest call is kept and the outputs are compared::

    python benchmarks/bench_constitutive.py --law [--cases S15 OL2 2-3] [--baseline REV]

With ``--forces`` it times ``InterfaceLaw.forces`` (one time step of a dynamic relaxation,
one Newton residual: ``H x``, the law, ``H^T actions``) on the S5 U wall of
bench_walls_that_meet.py (326 blocks, 921 interfaces) at the dead-load state and at the
last state of its pushover, against git revision ``--baseline`` (give faf4f27, the commit
before the early-out), the same way: fresh subprocesses on the same saved inputs, alternating
``--rounds`` times, fastest call kept, outputs compared bit for bit. It prints the rows the
strength check settles (elastic, detached) and runs (sliding, rocking), the seconds per call
of both trees and their ratio, and scipy's ``H @ x`` then ``H_T @ y`` for scale::

    NUMBA_NUM_THREADS=1 python benchmarks/bench_constitutive.py --forces --baseline faf4f27

With ``--parts`` instead it prints where a call of ``forces`` goes on this tree, on the same
two states and on S23's last: the strength check of each kind of row (elastic, detached,
sliding, rocking only, and zero trials: what any row costs) one at a time with the
interface's constants stored and computed in the row (as before they were stored), and two
by two as ``forces`` checks them (``nb_project_rows``); the Newton steps of a sliding row's
radial factor and energy return; the early-out's test of a row; the latency of pow, exp,
log, sqrt and a division in a chain of dependent operations; and the loop of ``H x``
through signed (scipy's) and unsigned index arrays::

    NUMBA_NUM_THREADS=1 python benchmarks/bench_constitutive.py --forces --parts

With ``--pushover`` as well it then runs the U wall's pushover (``StaticSolver``, after one
run to warm up) on both trees, alternating ``--rounds`` times, and prints the mean
wall-clock and CPU seconds of each, the seconds spent in ``InterfaceLaw.forces`` (timed by
wrapping it) and the ratios, with the calls, factorizations and lambda (which must agree).
"""

from __future__ import annotations

import argparse
import io
import os
import platform
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Callable

import numpy as np
from _machine import arguments, print_machine
from scipy.sparse.linalg import splu

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive import (
    ALPHA_TABLE_A1,
    REFERENCE_INTERFACE,
    SpringInterface,
    check_strength,
    fit_alpha,
)
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.interfaces import detect_interfaces
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support

A, B, S, GAMMA = 0.081, 0.21, 0.07, 20_000.0  # Orduna & Lourenco bricks
#: the last commit with the unoptimised InterfaceLaw / check_strength
LAW_BASELINE = "635b871988f6fcc5453a5b2d14ea5170c6ff4a12"
LAW_FIELDS = ("kbar", "l1", "l2", "friction", "tensile_force", "alpha")
LAW_OUTPUTS = ("actions", "state", "flags", "tangent", "utilisation")
MATERIAL = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)


def best_of(repeat: int, fn: Callable[[], object]) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def random_actions(m: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    act = rng.normal(size=(m, 6)) * [100.0, 100.0, 200.0, 10.0, 10.0, 10.0]
    act[:, 2] -= 200.0
    return act


def load_path(steps: int) -> np.ndarray:
    t = np.linspace(0.0, 1.0, steps)
    path = np.zeros((steps, 6))
    path[:, 0] = 1e-4 * np.sin(6 * np.pi * t)
    path[:, 1] = 5e-5 * np.sin(4 * np.pi * t)
    path[:, 3] = 2e-3 * np.sin(2 * np.pi * t)
    path[:, 4] = 1e-3 * np.sin(3 * np.pi * t)
    path[:, 5] = 1e-3 * np.sin(5 * np.pi * t)
    return path


def wall_stiffness(n_blocks: int):
    per_course = max(1, round(np.sqrt(n_blocks * A / B)))
    courses = max(1, round(n_blocks / (per_course + 0.5)))
    blocks, base = add_base(running_bond_wall(per_course, courses, A, B, S, GAMMA))
    its = detect_interfaces(blocks)
    model = Model.build(blocks, MATERIAL, [Support([base])], [SelfWeight()], interfaces=its)
    asm = Assembly.of(model)
    return asm.stiffness(), blocks.count, its.count


# --------------------------------------------------------------------------------------------
# the interface law of the solvers: respond() and tangent() per call, against a git revision


def law_inputs(name: str, folder: str) -> str:
    """Save the law of case ``name`` and its state at the last pushover step to an .npz."""
    from masonry_dem.assembly.stiffness import Assembly
    from masonry_dem.cases.paper import build_case
    from masonry_dem.constitutive.law import InterfaceLaw
    from masonry_dem.solvers.incremental import pushover

    case = build_case(name)
    settings = case.settings
    history = pushover(case.model, settings)
    asm = Assembly.of(case.model)
    law = InterfaceLaw.of(case.model, asm.kbar, settings.tension, settings.memory)
    rel = asm.relative_displacements(np.asarray(history.steps[-1].q).reshape(-1))
    m = rel.shape[0]
    first = law.respond(rel, np.zeros((m, 6)), np.zeros(m, dtype=bool))
    plastic = law.plastic_part(rel, first.actions)
    cracked = law.cracked_after(np.zeros(m, dtype=bool), first)  # opened joints lose ft
    path = os.path.join(folder, f"law_{name}.npz")
    np.savez(
        path,
        **{
            f: np.broadcast_to(getattr(law, f), (m,) if f != "kbar" else (m, 6)) for f in LAW_FIELDS
        },
        tension=law.tension,
        memory=law.memory,
        relative=rel,
        plastic=plastic,
        cracked=cracked,
        history_steps=len(history.steps),
    )
    return path


def per_call(fn: Callable[[], object], seconds: float = 1.0) -> float:
    """Fastest single call of ``fn`` in about ``seconds`` of calls (robust to a busy machine:
    some calls run uninterrupted)."""
    fn()
    best = np.inf
    end = time.perf_counter() + seconds
    while True:
        t0 = time.perf_counter()
        fn()
        t1 = time.perf_counter()
        best = min(best, t1 - t0)
        if t1 > end:
            return best


def law_timings(path: str) -> dict[str, np.ndarray]:
    """Time per call of respond() and tangent() on one saved input, with their outputs."""
    from masonry_dem.constitutive.law import InterfaceLaw

    d = np.load(path)
    law = InterfaceLaw(*(np.array(d[f]) for f in LAW_FIELDS), str(d["tension"]), str(d["memory"]))
    rel, plastic, cracked = d["relative"], d["plastic"], d["cracked"]
    r = law.respond(rel, plastic, cracked)
    out = {f: getattr(r, f) for f in LAW_OUTPUTS if f != "tangent"}
    out["tangent"] = law.tangent(r)
    out["yielded"] = np.array(float(np.mean(r.flags > 0)))
    out["respond"] = np.array(per_call(lambda: law.respond(rel, plastic, cracked)))
    out["tangent_time"] = np.array(per_call(lambda: law.tangent(r)))
    return out


def law_worker(inputs: list[str], out: str) -> None:
    """Time the law of the imported masonry_dem on each input; write times and outputs."""
    result = {}
    for path in inputs:
        tag = os.path.basename(path)
        result.update({f"{tag}:{k}": v for k, v in law_timings(path).items()})
    np.savez(out, **result)


def baseline_source(rev: str, folder: str) -> str:
    """Extract ``src/`` of git revision ``rev`` of this repository into ``folder``."""
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    tar = subprocess.run(
        ["git", "-C", repo, "archive", rev, "src"], check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=io.BytesIO(tar)) as tf:
        if hasattr(tarfile, "data_filter"):  # Python >= 3.11.4
            tf.extractall(folder, filter="data")
        else:  # pragma: no cover
            tf.extractall(folder)
    return os.path.join(folder, "src")


def run_worker(
    src: str, inputs: list[str], out: str, flag: str = "--law-worker"
) -> dict[str, np.ndarray]:
    env = dict(os.environ, PYTHONPATH=src)
    env.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # the same for both trees
    cmd = [sys.executable, os.path.abspath(__file__), flag, out, *inputs]
    subprocess.run(cmd, check=True, env=env)
    with np.load(out) as d:
        return {k: d[k] for k in d.files}


def max_rel_diff(x: np.ndarray, y: np.ndarray) -> float:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    same = (x == y) | (np.isnan(x) & np.isnan(y))
    if same.all():
        return 0.0
    return float(np.max(np.abs(x - y)[~same] / np.maximum(np.abs(y)[~same], 1e-300)))


def law_main(cases: list[str], baseline: str, rounds: int) -> int:
    import masonry_dem

    current = os.path.dirname(os.path.dirname(os.path.abspath(masonry_dem.__file__)))
    with tempfile.TemporaryDirectory() as tmp:
        old = baseline_source(baseline, os.path.join(tmp, "baseline"))
        inputs = [law_inputs(name, tmp) for name in cases]
        runs: dict[str, list[dict]] = {"before": [], "after": []}
        for k in range(rounds):  # alternate, so both see the same machine load
            for label, src in (("before", old), ("after", current)):
                runs[label].append(run_worker(src, inputs, os.path.join(tmp, f"{label}{k}.npz")))

    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    print(f"baseline {baseline[:12]}; fastest call over {rounds} alternating rounds")
    header = f"{'case':6s} {'m':>5s} {'yielded':>7s}  {'call':8s} {'before [us]':>11s} "
    print(header + f"{'after [us]':>10s} {'ratio':>6s}  max rel. diff of outputs")
    for name, path in zip(cases, inputs, strict=True):
        tag = os.path.basename(path)
        before, after = runs["before"][0], runs["after"][0]
        m = before[f"{tag}:actions"].shape[0]
        diff = max(max_rel_diff(after[f"{tag}:{f}"], before[f"{tag}:{f}"]) for f in LAW_OUTPUTS)
        for call, key in (("respond", "respond"), ("tangent", "tangent_time")):
            tb = min(float(r[f"{tag}:{key}"]) for r in runs["before"])
            ta = min(float(r[f"{tag}:{key}"]) for r in runs["after"])
            print(
                f"{name:6s} {m:5d} {float(after[f'{tag}:yielded']):7.2f}  {call:8s} "
                f"{tb * 1e6:11.1f} {ta * 1e6:10.1f} {tb / ta:6.2f}  {diff:.1e}"
            )
    return 0


# --------------------------------------------------------------------------------------------
# InterfaceLaw.forces on the U wall, against a git revision

FORCES_OUTPUTS = ("rel", "trial", "actions", "flags", "internal")


def forces_inputs(folder: str) -> str:
    """Save the S5 U wall's law, H on the free DOFs and its dead-load and last states."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from bench_walls_that_meet import build, walls

    from masonry_dem.solvers.incremental import StaticSolver

    model, _ = build(walls("S5")[0], False)
    solver = StaticSolver(model)
    history = solver.run()
    law, asm = solver.problem.law, solver.problem.asm
    H, H_T = asm.H_free.tocsr(), asm.H_free_T.tocsr()
    m = law.kbar.shape[0]
    free = asm.free_index
    path = os.path.join(folder, "forces_u_wall.npz")
    np.savez(
        path,
        **{
            f: np.broadcast_to(getattr(law, f), (m,) if f != "kbar" else (m, 6)) for f in LAW_FIELDS
        },
        tension=law.tension,
        memory=law.memory,
        projection=law.projection,
        **{
            f"H_{k}": v for k, v in (("data", H.data), ("indices", H.indices), ("indptr", H.indptr))
        },
        **{
            f"T_{k}": v
            for k, v in (("data", H_T.data), ("indices", H_T.indices), ("indptr", H_T.indptr))
        },
        H_shape=H.shape,
        T_shape=H_T.shape,
        dead=np.asarray(history.steps[0].q).reshape(-1)[free],
        last=np.asarray(history.steps[-1].q).reshape(-1)[free],
    )
    return path


def forces_worker(path: str, out: str) -> None:
    """Time ``forces`` of the imported masonry_dem per call on each state; write times and
    outputs."""
    from scipy import sparse

    from masonry_dem.constitutive.law import InterfaceLaw

    d = np.load(path)
    fields = (np.array(d[f]) for f in LAW_FIELDS)
    law = InterfaceLaw(*fields, str(d["tension"]), str(d["memory"]), str(d["projection"]))
    H = sparse.csr_matrix((d["H_data"], d["H_indices"], d["H_indptr"]), shape=tuple(d["H_shape"]))
    H_T = sparse.csr_matrix((d["T_data"], d["T_indices"], d["T_indptr"]), shape=tuple(d["T_shape"]))
    m = law.kbar.shape[0]
    plastic, cracked = np.zeros((m, 6)), np.zeros(m, dtype=bool)
    result = {}
    for state in ("dead", "last"):
        x = np.array(d[state])
        rel, r, internal = law.forces(H, x, plastic, cracked, H_T)
        outputs = {"rel": rel, "trial": r.trial, "actions": r.actions, "flags": r.flags}
        outputs["internal"] = internal
        result.update({f"{state}:{k}": v for k, v in outputs.items()})
        result[f"{state}:time"] = np.array(
            per_call(lambda x=x: law.forces(H, x, plastic, cracked, H_T))
        )
        result[f"{state}:spmv"] = np.array(per_call(lambda x=x: H_T @ (H @ x)))
    np.savez(out, **result)


def forces_parts(path: str, s23: str | None = None) -> None:
    """Print the cost of the parts of one ``forces`` call on the saved U wall states (and the
    rows of S23's last state, saved by :func:`law_inputs`, if given)."""
    import math

    import numba
    from scipy import sparse

    from masonry_dem.constitutive.check_kernels import (
        NEWTON_MAX_ITER,
        _nb_demands,
        _nb_radial_closed,
        _nb_radial_step,
        nb_check_row,
        nb_project_rows,
    )
    from masonry_dem.constitutive.energy_return import (
        PROJECTION_MAX_ITER,
        _nb_bracket_start,
        _nb_bracket_step,
        _nb_closest_setup,
    )
    from masonry_dem.constitutive.law import InterfaceLaw
    from masonry_dem.constitutive.law_kernels import nb_plain_row

    @numba.njit(error_model="numpy")
    def check_rows(trial, ft, l1, l2, friction, alpha, snap1, snap2, constants, actions, flags):
        # as the forces kernel calls the check: the interface's constants stored, or (an
        # empty ``constants``) computed in the row
        on = trial.shape[0] >= 0
        stored = constants.shape[0] > 0
        c1 = c2 = c3 = c4 = 0.0
        for i in range(trial.shape[0]):
            t = trial[i]
            if stored:
                c1, c2, c3, c4 = constants[i, 1], constants[i, 2], constants[i, 3], constants[i, 4]
            p = nb_check_row(t[0], t[1], t[2], t[3], t[4], t[5], ft[i], 0.0, l1[i], l2[i], friction[i], alpha[i], snap1[i], snap2[i], on, on, on, stored, c1, c2, c3, c4)  # fmt: skip
            actions[i, 0], actions[i, 1], actions[i, 2] = p[0], p[1], p[2]
            actions[i, 3], actions[i, 4], actions[i, 5] = p[3], p[4], p[5]
            flags[i] = p[6]

    @numba.njit(error_model="numpy")
    def pair_rows(trial, ft, l1, l2, friction, alpha, snap1, snap2, constants, actions, flags):
        # as the forces kernel checks them: consecutive rows two by two (an odd last row
        # with itself)
        n = trial.shape[0]
        for k in range((n + 1) // 2):
            i = 2 * k
            j = i + 1 if i + 1 < n else i
            t, c = trial[i], constants[i]
            first = (t[0], t[1], t[2], t[3], t[4], t[5], ft[i], 0.0, l1[i], l2[i], friction[i], alpha[i], snap1[i], snap2[i], c[1], c[2], c[3], c[4])  # fmt: skip
            t, c = trial[j], constants[j]
            second = (t[0], t[1], t[2], t[3], t[4], t[5], ft[j], 0.0, l1[j], l2[j], friction[j], alpha[j], snap1[j], snap2[j], c[1], c[2], c[3], c[4])  # fmt: skip
            p, flag, q, flag_b = nb_project_rows(first, second, True)
            for c in range(6):
                actions[i, c] = p[c]
                actions[j, c] = q[c]
            flags[i] = flag
            flags[j] = flag_b

    @numba.njit(error_model="numpy")
    def iterations(trial, ft, l1, l2, friction, alpha, snap1, snap2, constants, out):
        # per row, through the check's own parts: the radial factor's Newton steps, the
        # energy return's bracketed Newton steps, and whether it ran on the shear half
        for i in range(trial.shape[0]):
            t, c = trial[i], constants[i]
            _, _, _, _, _, _, _, _, _, fsu, abs_m3, m3u, shear, a, cc = _nb_demands(t[0], t[1], t[2], t[3], t[4], t[5], ft[i], 0.0, l1[i], l2[i], friction[i], snap1[i], snap2[i], True)  # fmt: skip
            s, newton, m, big_a, big_c = _nb_radial_closed(a, cc, alpha[i])
            steps = 0
            if newton:
                ln_a, ln_c, tau, done = math.log(big_a), math.log(big_c), 0.0, False
                while not done and steps < NEWTON_MAX_ITER:
                    tau, done = _nb_radial_step(tau, ln_a, ln_c, alpha[i])
                    steps += 1
                s = math.exp(tau) / m
            out[i, 0] = steps
            rho = c[4]
            run, torsion, power, hi, start, _ = _nb_closest_setup(
                shear, abs_m3 / rho, fsu, m3u / rho, alpha[i], s, c[1], c[2], c[3]
            )
            steps = 0
            if run:
                lo, x, stop = 0.0, _nb_bracket_start(hi, start), False
                while not stop and steps < PROJECTION_MAX_ITER:
                    lo, hi, x, stop = _nb_bracket_step(torsion, fsu, m3u / rho, shear, abs_m3 / rho, alpha[i], power, lo, hi, x)  # fmt: skip
                    steps += 1
            out[i, 1] = steps
            out[i, 2] = 1.0 if run and not torsion else 0.0

    @numba.njit(error_model="numpy")
    def chain(kind, x0, n):
        # n dependent operations: their latency (the Newton steps wait on each result)
        x = x0
        for _ in range(n):
            if kind == 0:
                x = (x + 0.5) ** 1.5 * 0.5
            elif kind == 1:
                x = math.exp(0.1 * x)
            elif kind == 2:
                x = math.log(x + 2.0)
            elif kind == 3:
                x = math.sqrt(x + 0.5)
            elif kind == 4:
                x = 0.75 / (x + 0.5)
            else:
                x = (x + 0.5) * 0.75
        return x

    @numba.njit(error_model="numpy")
    def plain_rows(trial, ft, l1, l2, friction, snap1, snap2, torsion):
        n = 0
        for i in range(trial.shape[0]):
            t = trial[i]
            n += nb_plain_row(t[0], t[1], t[2], t[3], t[4], t[5], ft[i], 0.0, l1[i], l2[i], friction[i], snap1[i], snap2[i], torsion[i])  # fmt: skip
        return n

    @numba.njit(error_model="numpy")
    def product(x, ptr, idx, val, out):
        start = ptr[0]
        for r in range(out.shape[0]):
            end = ptr[r + 1]
            total = 0.0
            t = start
            while t < end:
                total += val[t] * x[idx[t]]
                t += 1
            start = end
            out[r] = total

    d = np.load(path)
    fields = (np.array(d[f]) for f in LAW_FIELDS)
    law = InterfaceLaw(*fields, str(d["tension"]), str(d["memory"]), str(d["projection"]))
    H = sparse.csr_matrix((d["H_data"], d["H_indices"], d["H_indptr"]), shape=tuple(d["H_shape"]))
    H_T = H.T.tocsr()
    m = law.kbar.shape[0]
    unsigned = np.uint32 if H.indices.dtype.itemsize == 4 else np.uint64
    print(
        f"{'state':5s} {'rows':18s} {'n':>4s} {'check [ns/row]':>14s} {'early-out [ns/row]':>18s}"
        f" {'constants computed [ns/row]':>27s} {'two by two [ns/row]':>19s}"
    )
    states = []
    for state in ("dead", "last"):
        x = np.array(d[state])
        _, r, _ = law.forces(H, x, np.zeros((m, 6)), np.zeros(m, dtype=bool), H_T)
        states.append((state, r, law._domain))
    if s23 is not None:  # S23's last pushover state (law_inputs), through its own law
        e = np.load(s23)
        s23_law = InterfaceLaw(*(np.array(e[f]) for f in LAW_FIELDS), str(e["tension"]), str(e["memory"]))  # fmt: skip
        r = s23_law.respond(e["relative"], e["plastic"], e["cracked"])
        states.append(("S23", r, s23_law._domain))
    for state, r, dom in states:
        kinds = {
            "elastic": r.flags == 0,
            "detached": r.flags == 8,
            "sliding": r.flags & 1 > 0,
            "rocking only": (r.flags > 0) & (r.flags < 8) & (r.flags & 1 == 0),
            "zero trial": r.flags == 0,
        }
        for kind, rows in kinds.items():
            n = int(rows.sum())
            if n == 0:
                continue
            trial = (
                np.zeros((n, 6)) if kind == "zero trial" else np.ascontiguousarray(r.trial[rows])
            )
            ft = np.ascontiguousarray(r.tensile_force[rows])
            arrays = [np.ascontiguousarray(a[rows]) for a in dom.kernel_arrays]
            torsion = np.ascontiguousarray(dom.torsion_constant[rows])
            constants = np.ascontiguousarray(dom.row_constants[rows])
            act, flags = np.empty((n, 6)), np.empty(n, dtype=np.uint8)
            l1, l2, mu, _, s1, s2 = arrays
            checked = (trial, ft, *arrays, constants, act, flags)
            t_check = per_call(lambda a=checked: check_rows(*a))
            computed = (trial, ft, *arrays, np.empty((0, 5)), act, flags)
            t_computed = per_call(lambda a=computed: check_rows(*a))
            t_pairs = per_call(lambda a=checked: pair_rows(*a))
            tested = (trial, ft, l1, l2, mu, s1, s2, torsion)
            t_plain = per_call(lambda a=tested: plain_rows(*a))
            print(
                f"{state:5s} {kind:18s} {n:4d} {t_check / n * 1e9:14.0f} {t_plain / n * 1e9:18.0f}"
                f" {t_computed / n * 1e9:27.0f} {t_pairs / n * 1e9:19.0f}"
            )
            if kind == "sliding":
                count = np.zeros((n, 3))
                iterations(trial, ft, *arrays, constants, count)
                ran = count[:, 1] > 0
                shear = count[ran, 2].mean()
                print(
                    f"      {n} sliding rows: radial factor {count[:, 0].mean():.2f} Newton steps a "
                    f"row (at most {count[:, 0].max():.0f}); energy return {count[ran, 1].mean():.2f} "
                    f"(at most {count[:, 1].max():.0f}) on {ran.sum()} rows, {shear:.0%} of them "
                    "on the shear half"
                )
    steps = 100_000
    base = per_call(lambda: chain(5, 0.3, steps))
    latency = {
        name: (per_call(lambda k=k: chain(k, 0.3, steps)) - base) / steps * 1e9
        for k, name in enumerate(("pow", "exp", "log", "sqrt", "division"))
    }
    print(
        "latency in a chain of dependent operations [ns]: "
        + ", ".join(f"{k} {v:.1f}" for k, v in latency.items())
    )
    x = np.array(d["last"])
    out = np.empty(H.shape[0])
    signed = per_call(lambda: product(x, H.indptr, H.indices, H.data, out))
    ptr, idx = H.indptr.view(unsigned), H.indices.view(unsigned)
    plain = per_call(lambda: product(x, ptr, idx, H.data, out))
    print(
        f"H x ({H.nnz} entries): signed indices {signed * 1e6:.1f} us, unsigned "
        f"{plain * 1e6:.1f} us, scipy {per_call(lambda: H @ x) * 1e6:.1f} us"
    )
    assert math.isfinite(signed)


def pushover_worker(out: str) -> None:
    """The U wall's pushover on the imported masonry_dem, after one run to warm up: seconds
    (wall-clock, CPU, inside ``InterfaceLaw.forces``), calls, factorizations, lambda."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from bench_walls_that_meet import build, walls

    from masonry_dem.constitutive.law import InterfaceLaw
    from masonry_dem.solvers.incremental import StaticSolver

    model, _ = build(walls("S5")[0], False)
    StaticSolver(model).run()
    spent = [0.0, 0.0]
    plain = InterfaceLaw.forces

    def timed(self, *args, **kwargs):
        t0 = time.perf_counter()
        result = plain(self, *args, **kwargs)
        spent[0] += time.perf_counter() - t0
        spent[1] += 1
        return result

    InterfaceLaw.forces = timed
    t0, c0 = time.perf_counter(), time.process_time()
    history = StaticSolver(model).run()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    np.savez(
        out,
        wall=wall,
        cpu=cpu,
        forces=spent[0],
        calls=spent[1],
        factorizations=history.factorizations,
        lam=history.collapse_multiplier,
    )


def pushover_runs(old: str, current: str, rounds: int, tmp: str) -> dict[str, dict]:
    """Mean outputs of :func:`pushover_worker` on both trees, alternating ``rounds`` times."""
    runs: dict[str, list[dict]] = {"before": [], "after": []}
    for k in range(rounds):
        for label, src in (("before", old), ("after", current)):
            out = os.path.join(tmp, f"pushover_{label}{k}.npz")
            runs[label].append(run_worker(src, [], out, "--pushover-worker"))
    return {
        label: {key: float(np.mean([r[key] for r in rs])) for key in rs[0]}
        for label, rs in runs.items()
    }


def print_pushover(mean: dict[str, dict], rounds: int) -> None:
    b, a = mean["before"], mean["after"]
    print(f"U wall pushover, mean of {rounds} alternating rounds:")
    print(f"{'':22s} {'before':>9s} {'after':>9s} {'ratio':>6s}")
    for key, name in (("wall", "wall-clock [s]"), ("cpu", "CPU [s]"), ("forces", "in forces [s]")):
        print(f"{name:22s} {b[key]:9.2f} {a[key]:9.2f} {b[key] / a[key]:6.2f}")
    for key in ("calls", "factorizations", "lam"):
        print(f"{key:22s} {b[key]:9.6g} {a[key]:9.6g}")


def forces_main(baseline: str, rounds: int, pushover: bool = False) -> int:
    import masonry_dem
    from masonry_dem.constitutive.states import FLAG_DETACHED, FLAG_SHEAR_TORSION

    current = os.path.dirname(os.path.dirname(os.path.abspath(masonry_dem.__file__)))
    with tempfile.TemporaryDirectory() as tmp:
        old = baseline_source(baseline, os.path.join(tmp, "baseline"))
        path = forces_inputs(tmp)
        runs: dict[str, list[dict]] = {"before": [], "after": []}
        for k in range(rounds):  # alternate, so both see the same machine load
            for label, src in (("before", old), ("after", current)):
                out = os.path.join(tmp, f"forces_{label}{k}.npz")
                runs[label].append(run_worker(src, [path], out, "--forces-worker"))
        pushed = pushover_runs(old, current, rounds, tmp) if pushover else None

    threads = os.environ.get("NUMBA_NUM_THREADS", "all")
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    print(f"S5 U wall; baseline {baseline[:12]}; NUMBA_NUM_THREADS={threads}; fastest call")
    print(f"over {rounds} alternating rounds; rows: elastic/detached/sliding/rocking only")
    head = f"{'state':5s} {'rows':>19s} {'before [us]':>11s} {'after [us]':>10s} {'ratio':>6s}"
    print(head + f" {'scipy H, H_T [us]':>17s}  outputs")
    for state in ("dead", "last"):
        before, after = runs["before"][0], runs["after"][0]
        flags = after[f"{state}:flags"]
        rows = (
            int(np.sum(flags == 0)),
            int(np.sum(flags == FLAG_DETACHED)),
            int(np.sum(flags & FLAG_SHEAR_TORSION > 0)),
            int(np.sum((flags > 0) & (flags < FLAG_DETACHED) & (flags & FLAG_SHEAR_TORSION == 0))),
        )
        same = all(
            after[f"{state}:{f}"].tobytes() == before[f"{state}:{f}"].tobytes()
            for f in FORCES_OUTPUTS
        )
        tb = min(float(r[f"{state}:time"]) for r in runs["before"])
        ta = min(float(r[f"{state}:time"]) for r in runs["after"])
        spmv = min(float(r[f"{state}:spmv"]) for r in runs["after"])
        print(
            f"{state:5s} {'/'.join(map(str, rows)):>19s} {tb * 1e6:11.1f} {ta * 1e6:10.1f} "
            f"{tb / ta:6.2f} {spmv * 1e6:17.1f}  {'same bits' if same else 'DIFFERENT'}"
        )
    if pushed is not None:
        print_pushover(pushed, rounds)
    return 0


def main(argv: list[str] | None = None) -> int:
    p = arguments(__doc__)
    p.add_argument("--interfaces", type=int, default=1_000_000)
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--n", type=int, default=32, help="springs per side")
    p.add_argument("--wall-blocks", type=int, default=10_000)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--law", action="store_true", help="time InterfaceLaw only (see above)")
    p.add_argument("--cases", nargs="+", default=["S15", "OL2", "2-3"])
    p.add_argument("--baseline", default=LAW_BASELINE, help="git revision to compare with")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--forces", action="store_true", help="time InterfaceLaw.forces (see above)")
    p.add_argument("--law-worker", nargs="+", help=argparse.SUPPRESS)  # OUT INPUT...
    p.add_argument("--pushover", action="store_true", help="with --forces: the U wall's pushover")
    p.add_argument("--parts", action="store_true", help="with --forces: where a call goes")
    p.add_argument("--forces-worker", nargs=2, help=argparse.SUPPRESS)  # OUT INPUT
    p.add_argument("--pushover-worker", nargs=1, help=argparse.SUPPRESS)  # OUT
    args = p.parse_args(argv)
    if args.law_worker:
        law_worker(args.law_worker[1:], args.law_worker[0])
        return 0
    if args.forces_worker:
        forces_worker(args.forces_worker[1], args.forces_worker[0])
        return 0
    if args.pushover_worker:
        pushover_worker(args.pushover_worker[0])
        return 0
    print_machine()
    if args.law:
        return law_main(args.cases, args.baseline, args.rounds)
    if args.forces and args.parts:
        with tempfile.TemporaryDirectory() as tmp:
            forces_parts(forces_inputs(tmp), law_inputs("S23", tmp))
        return 0
    if args.forces:
        return forces_main(args.baseline, args.rounds, args.pushover)

    rows: list[tuple[str, str, float, str]] = []

    act = random_actions(args.interfaces)
    t = best_of(args.repeat, lambda: check_strength(act, 0.3, 0.2, 0.7, 0.0))
    states = np.bincount(check_strength(act, 0.3, 0.2, 0.7, 0.0).state, minlength=5)
    rows.append(
        (
            "check_strength",
            f"{args.interfaces:,} interfaces",
            t,
            f"{t / args.interfaces * 1e9:.0f} ns/interface; states {states.tolist()}",
        )
    )

    ref = REFERENCE_INTERFACE
    iface = SpringInterface(ref.l1, ref.l2, args.n, ref.kn, ref.ks, ref.friction)
    path = load_path(args.steps)
    springs = args.n**2
    t = best_of(args.repeat, lambda: iface.run(path, normal_force=ref.normal_force))
    rows.append(
        (
            "spring path, fn held",
            f"{springs} springs x {args.steps} steps",
            t,
            f"{t / (springs * args.steps) * 1e9:.0f} ns/spring-step",
        )
    )
    imposed = path.copy()
    imposed[:, 2] = ref.normal_force / (ref.kn * ref.l1 * ref.l2)
    t = best_of(args.repeat, lambda: iface.run(imposed))
    rows.append(
        (
            "spring path, dn imposed",
            f"{springs} springs x {args.steps} steps",
            t,
            f"{t / (springs * args.steps) * 1e9:.0f} ns/spring-step",
        )
    )

    def fits() -> None:
        for direction in ("f1", "f2", "f1=f2"):
            for aspect in ALPHA_TABLE_A1["aspect"]:
                fit_alpha(aspect, direction, n=32)

    t = best_of(1, fits)
    rows.append(("Table A1 fits", "21 fits, 32 x 32 springs", t, "masonry-dem interface"))

    t0 = time.perf_counter()
    K, n_blocks, n_its = wall_stiffness(args.wall_blocks)
    t_build = time.perf_counter() - t0
    t_lu = best_of(args.repeat, lambda: splu(K))
    lu = splu(K)
    rows.append(
        (
            "splu(K) of a wall",
            f"{n_blocks:,} blocks, {n_its:,} interfaces, {K.shape[0]:,} DOFs",
            t_lu,
            f"nnz(K) {K.nnz:,}, nnz(L+U) {lu.L.nnz + lu.U.nnz:,}; build {t_build:.2f} s",
        )
    )
    act_wall = random_actions(n_its, seed=1)
    t_wall = best_of(args.repeat, lambda: check_strength(act_wall, 0.105, 0.07, 0.7, 0.0))
    rows.append(
        (
            "check_strength, wall size",
            f"{n_its:,} interfaces",
            t_wall,
            f"{t_lu / t_wall:.0f}x faster than splu(K)",
        )
    )

    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    w = max(len(r[0]) for r in rows), max(len(r[1]) for r in rows)
    print(f"{'case':{w[0]}s}  {'size':{w[1]}s}  {'time [s]':>9s}  notes")
    for name, size, t, note in rows:
        print(f"{name:{w[0]}s}  {size:{w[1]}s}  {t:9.4f}  {note}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
