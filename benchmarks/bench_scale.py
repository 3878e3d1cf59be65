"""Benchmark: the static pushover from 10^2 to 10^5 blocks, and the sparse LU backends.

Run:  python benchmarks/bench_scale.py [--sizes 10 30 100 316] [--pushover-up-to 10000]
                                       [--wall eurocode|issue]
                                       [--threads 1 2] [--backends ...] [--repeat 5]
                                       [--pushover-budget S] [--multifrontal-from REF]
                                       [--no-pushover] [--json FILE]
       python benchmarks/bench_scale.py --small [--repeat 200]   # the backends, 6-2 400 DOFs
       python benchmarks/bench_scale.py --pardiso-options --sizes 12 16 30 100 [--repeat 40]

The walls (``scale_wall``) are a family a structural engineer would analyse, chosen by two
stated rules, not tuned to the solver: the bundled default block (Orduna's a = 0.081,
b = 0.210, s = 0.070 m, 20 kN/m^3) in running bond on a base slab, its left column held by
a return wall, tilted out of plane, its mortar joints taken with no tensile strength or
cohesion (the no-tension assumption of an assessment), with

* the slenderness within the Eurocode 6 limit h_ef / t_ef <= 27 (EN 1996-1-1, 5.5.1.4),
  h_ef the wall's height: 23 courses (1.86 m, h / t = 26.6) whatever the size, the walls
  growing in length (about N^2 / 23 blocks per course for ``--sizes`` N: 10, 30, 100, 316
  give about 10^2, 10^3, 10^4, 10^5 blocks);
* the joint stiffness of a brick-mortar bed joint: kn = E_u E_m / (h_m (E_u - E_m)) and
  the same with the shear moduli for kt (Lourenco & Rots 1997, "Multisurface interface model
  for analysis of masonry structures", J. Eng. Mech. 123(7); their solid clay units
  E_u = 16.7 GPa, nu 0.15, with 10 mm of mortar E_m = 0.78 GPa, nu 0.125: kn = 82 N/mm^3,
  kt = 36 N/mm^3), friction 0.7 (the bundled default).

``--wall issue`` takes the walls of issue 23 instead (N blocks per course, N courses, 33
for N = 30: the 1 007-block wall; kn 1e9 N/m^3), whose slenderness 38 is beyond any code and
which at kn 1e9 moves 9 cm while still elastic. For each wall it prints:

* blocks, interfaces, free DOFs; ``build`` (blocks, contacts, Model.build) and ``assembly``
  (the solver's set-up: H, the fixed-pattern tangent assembler, one tangent's entries) seconds;
* seconds per factorization (median of ``--repeat``, after the analysis and a first
  factorization) and per solve, of the tangent at the dead-load state, for every installed
  backend (``factorization.installed()``) and each ``--threads`` count, each thread count in a
  fresh process with NUMBA/OMP/MKL/OPENBLAS threads set; with ``--multifrontal-from REF``
  also the hand-written multifrontal LU of commit REF (retired in issue 23) on the same
  matrices, in the ordering it was used with;
* for walls of at most ``--pushover-up-to`` blocks, the default pushover (backend chosen by
  ``factorization.choose``, or ``MASONRY_DEM_FACTORIZER``), each in a fresh process: status,
  lambda, seconds, steps, Newton iterations, factorizations, seconds per iteration and peak
  resident memory (ru_maxrss); a run still going after ``--pushover-budget`` seconds stops
  after its step and reports what it reached (status ``stopped@...``);

``--threads``: the thread counts of the child processes (NUMBA_NUM_THREADS, OMP_NUM_THREADS,
MKL_NUM_THREADS and OPENBLAS_NUM_THREADS all set to it): the factorizations are timed once
per count, the pushover runs on the first count only (default 1: on a machine shared with
other runs a second PARDISO or numba thread waits for a busy core, and a 5 400-DOF solve
took 0.096 s instead of a few ms); ``--threads 2 1`` runs the pushover on two;

and the log-log slope of each quantity against blocks (least squares over the walls measured,
and from about 10^3 blocks up). Timings are wall clock on a shared machine: compare ratios
measured in one run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _machine import arguments, print_machine

ROOT = Path(__file__).resolve().parents[1]
A, B, S, GAMMA = 0.081, 0.210, 0.070, 20.0e3  # the bundled default wall
KN, KT, MU = 1.0e9, 0.4e9, 0.7  # the walls of issue 23 (``--wall issue``)
#: slenderness limit h_ef / t_ef of EN 1996-1-1, 5.5.1.4
SLENDERNESS = 27.0
#: Lourenco & Rots (1997): kn = E_u E_m / (h_m (E_u - E_m)), kt from G = E / (2 (1 + nu))
E_UNIT, NU_UNIT, E_MORTAR, NU_MORTAR, JOINT = 16.7e9, 0.15, 0.78e9, 0.125, 0.010


def joint_stiffness() -> tuple[float, float]:
    """(kn, kt) [N/m^3] of a 10 mm mortar bed joint between clay units (Lourenco & Rots)."""
    g_unit, g_mortar = E_UNIT / (2 * (1 + NU_UNIT)), E_MORTAR / (2 * (1 + NU_MORTAR))
    kn = E_UNIT * E_MORTAR / (JOINT * (E_UNIT - E_MORTAR))
    kt = g_unit * g_mortar / (JOINT * (g_unit - g_mortar))
    return kn, kt


def scale_wall(n: int):
    """A wall of about n^2 blocks of the family in the module's docstring: as many courses
    as the slenderness limit allows, n^2 / courses blocks per course."""
    import masonry_dem as md

    courses = int(SLENDERNESS * S / A)
    per_course = max(2, round(n * n / courses))
    wall = md.running_bond_wall(per_course, courses, A, B, S, GAMMA)
    blocks, base = md.add_base(wall)
    kn, kt = joint_stiffness()
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=kn, kt=kt, friction=MU),
        supports=[md.Support([base]), md.Support(md.select.column(wall, "left"), ["u1", "u3"])],
        loads=[md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))],
    )


WALLS = {"eurocode": scale_wall}


#: at most this many courses (8.1 m): a dry wall much taller settles under its own weight by
#: more than the solver's displacement limit (half a block: 316 courses of kn = 1e9 N/m^3
#: shorten by about 8 cm) and fails under the dead load, a wall no one would build dry
MAX_COURSES = 100


def default_wall(n: int):
    """The wall of issue 23 with about n^2 blocks: n blocks per course and n courses (33
    for n = 30), or ``MAX_COURSES`` courses of n^2 / MAX_COURSES blocks when n is larger."""
    import masonry_dem as md

    courses = 33 if n == 30 else min(n, MAX_COURSES)
    per_course = n if n <= MAX_COURSES else round(n * n / MAX_COURSES)
    wall = md.running_bond_wall(per_course, courses, A, B, S, GAMMA)
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=KN, kt=KT, friction=MU),
        supports=[md.Support([base]), md.Support(md.select.column(wall, "left"), ["u1", "u3"])],
        loads=[md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))],
    )


WALLS["issue"] = default_wall


def _dead_load_tangent(model):
    """The solver, the tangent entries (CSC of its fixed pattern) at the dead-load state."""
    from masonry_dem.solvers.incremental import StaticSolver

    solver = StaticSolver(model)
    out = solver.equilibrate(0.0, radius=solver.limit, damped=True)
    T = solver.law.tangent(out.response, solver.settings.residual_stiffness)
    return solver, solver.problem.tangent_assembler.data(T)


def sizes_child(n: int, wall: str) -> dict:
    t0 = time.perf_counter()
    model = WALLS[wall](n)
    t1 = time.perf_counter()
    from masonry_dem.solvers.incremental import StaticSolver

    solver = StaticSolver(model)
    tangents = solver.problem.tangent_assembler
    tangents.data(np.tile(np.eye(6), (model.interfaces.count, 1, 1)))
    t2 = time.perf_counter()
    return {
        "blocks": model.blocks.count,
        "interfaces": model.interfaces.count,
        "dofs": tangents.n,
        "nnz": int(tangents.nnz),
        "build_s": t1 - t0,
        "assembly_s": t2 - t1,
    }


def _multifrontal(source: str):
    """The retired multifrontal module, loaded from its file."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("retired_multifrontal", source)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # numba's cache finds its functions by module name
    spec.loader.exec_module(module)
    return module


def factor_child(
    n: int, wall: str, backends: list[str], repeat: int, multifrontal: str | None
) -> dict:
    from scipy import sparse
    from scipy.sparse.linalg import splu

    from masonry_dem.solvers import factorization as fz

    model = WALLS[wall](n)
    solver, data = _dead_load_tangent(model)
    tangents = solver.problem.tangent_assembler
    b = np.random.default_rng(0).normal(size=tangents.n)
    out = {}
    makers = {
        name: (lambda name=name: fz.analyse(tangents.indptr, tangents.indices, tangents.n, name))
        for name in backends
    }
    if multifrontal:
        mf = _multifrontal(multifrontal)

        class Retired:  # as the solver used it: SuperLU's minimum degree, then the fronts
            def __init__(self) -> None:
                K = tangents.matrix(None, data)
                lu = splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, relax=1,
                          options={"SymmetricMode": True})  # fmt: skip
                p = np.argsort(lu.perm_c)
                ids = sparse.csc_matrix(
                    (np.arange(1, data.size + 1, dtype=float), tangents.indices, tangents.indptr),
                    shape=K.shape,
                )[p][:, p]
                ids = sparse.csc_matrix(ids)
                ids.sort_indices()
                self.gather = ids.data.astype(np.int64) - 1
                self.p = p
                self.sym = mf.Symbolic(
                    sparse.csc_matrix((np.ones(data.size), ids.indices, ids.indptr), shape=K.shape)
                )

            def factor(self, values):
                lu = self.sym.factorize_entries(values[self.gather])
                p = self.p

                class F:
                    def solve(self, rhs):
                        x = np.empty_like(rhs)
                        x[p] = lu.solve(rhs[p])
                        return x

                return F()

        makers["multifrontal"] = Retired
    K = tangents.matrix(None, data)
    for name, make in makers.items():
        t0 = time.perf_counter()
        f = make()
        F = f.factor(data)
        first = time.perf_counter() - t0
        times, solves = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            F = f.factor(data)
            times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            x = F.solve(b)
            solves.append(time.perf_counter() - t0)
        residual = float(np.linalg.norm(K @ x - b) / np.linalg.norm(b))
        out[name] = {
            "analyse_s": first,
            "factor_s": float(np.median(times)),
            "solve_s": float(np.median(solves)),
            "residual": residual,
        }
        del f, F
    return out


def small_walls(repeat: int) -> None:
    """The backends on the tangents of small walls (6 to 2 400 DOFs, the validation set's
    range), in one process on the threads set, each factorization followed by a solve,
    the backends in turn ``repeat`` times: medians in ms and the ratio to SuperLU. The
    rule ``factorization.SMALL`` comes from this table."""
    import masonry_dem as md
    from masonry_dem.solvers import factorization as fz

    def wall(n: int, courses: int):
        w = md.running_bond_wall(n, courses, A, B, S, GAMMA)
        blocks, base = md.add_base(w)
        return md.Model.build(
            blocks,
            md.InterfaceMaterial(kn=KN, kt=KT, friction=MU),
            [md.Support([base])],
            [md.SelfWeight(), md.WeightProportional((0.0, 0.0, 1.0))],
        )

    names = fz.installed()
    print(
        f"{'blocks':>6} {'DOFs':>5} " + " ".join(f"{b + ' ms':>11} {'/superlu':>8}" for b in names)
    )
    for n, courses in (
        (1, 1),
        (1, 3),
        (2, 4),
        (3, 5),
        (4, 8),
        (6, 8),
        (10, 10),
        (14, 14),
        (20, 20),
    ):
        solver, data = _dead_load_tangent(wall(n, courses))
        t = solver.problem.tangent_assembler
        made = {b: fz.analyse(t.indptr, t.indices, t.n, b) for b in names}
        for f in made.values():
            f.factor(data)
        times: dict[str, list[float]] = {b: [] for b in names}
        for _ in range(repeat):
            for b, f in made.items():
                t0 = time.perf_counter()
                f.factor(data).solve(data[: t.n])
                times[b].append(time.perf_counter() - t0)
        ref = float(np.median(times["superlu"]))
        cells = " ".join(
            f"{np.median(v) * 1e3:>11.3f} {np.median(v) / ref:>8.2f}" for v in times.values()
        )
        print(f"{solver.model.blocks.count:>6} {t.n:>5} {cells}", flush=True)


#: PARDISO's options against the package's (``factorization._Pardiso``): iparm number (as
#: MKL's manual numbers them from 1, and as ``pypardiso.set_iparm`` takes it) -> value
PARDISO_VARIANTS = {
    "package": {},
    "metis": {2: 2},  # the nested-dissection ordering
    "matching": {11: 1, 13: 1},  # scaling and weighted matching (MC64)
    "metis+matching": {2: 2, 11: 1, 13: 1},  # the options before session 15
}


def pardiso_options(sizes: list[int], repeat: int) -> None:
    """PARDISO with other orderings and with the weighted matching and scaling, and KLU
    (kvxopt, symbolic once, numeric per matrix) when installed, on the dead-load tangents of
    ``scale_wall(N)``: the median of ``repeat`` factorizations each followed by a solve, the
    variants in turn in this process, as a ratio to the package's PARDISO (one thread: run
    with NUMBA_NUM_THREADS=1 MKL_NUM_THREADS=1), and the entries of the LU factors of each
    PARDISO variant and the operations of its factorization (PARDISO's own counts,
    iparm(18) and iparm(19): they do not depend on the load of the machine)."""
    import importlib.util
    import warnings

    from masonry_dem.solvers import factorization as fz

    warnings.filterwarnings("ignore", module="pypardiso")  # "0 is no input iparm"
    klu = importlib.util.find_spec("kvxopt") is not None
    names = list(PARDISO_VARIANTS) + (["klu"] if klu else [])
    print(
        f"{'blocks':>6} {'DOFs':>6} {'package ms':>10} " + " ".join(f"{b:>15}" for b in names[1:])
    )
    for n in sizes:
        solver, data = _dead_load_tangent(scale_wall(n))
        t = solver.problem.tangent_assembler
        b = np.random.default_rng(0).standard_normal(t.n)
        runs: dict = {}
        fill = {}
        for name, iparm in PARDISO_VARIANTS.items():
            f = fz._Pardiso(t.indptr, t.indices, t.n)
            # iparm(18) = iparm(19) = -1: report the fill and the factorization's operations
            for i, value in {18: -1, 19: -1, **iparm}.items():
                f.solver.set_iparm(i, value)
            f.factor(data)
            fill[name] = (int(f.solver.iparm[17]), int(f.solver.iparm[18]))  # LU entries, MFLOP
            runs[name] = lambda f=f, data=data, b=b: f.factor(data).solve(b)
        if klu:
            runs["klu"] = _klu_run(t, data, b)
        times: dict[str, list[float]] = {k: [] for k in runs}
        for _ in range(repeat):
            for k, run in runs.items():
                t0 = time.perf_counter()
                run()
                times[k].append(time.perf_counter() - t0)
        ref = float(np.median(times["package"]))
        cells = " ".join(f"{np.median(times[k]) / ref:>15.2f}" for k in names[1:])
        print(f"{solver.model.blocks.count:>6} {t.n:>6} {ref * 1e3:>10.3f} {cells}", flush=True)
        print(f"{'':>6} {'':>6} {'LU entries':>10} " + " ".join(f"{fill[k][0]:>15,d}" for k in PARDISO_VARIANTS), flush=True)  # fmt: skip
        print(f"{'':>6} {'':>6} {'MFLOP':>10} " + " ".join(f"{fill[k][1]:>15,d}" for k in PARDISO_VARIANTS), flush=True)  # fmt: skip


def _klu_run(t, data: np.ndarray, b: np.ndarray):
    """A factorization and solve by KLU (kvxopt.klu), its symbolic analysis done once."""
    import importlib

    kvxopt = importlib.import_module("kvxopt")
    klu = importlib.import_module("kvxopt.klu")
    cols = np.repeat(np.arange(t.n, dtype=np.int64), np.diff(t.indptr))
    A = kvxopt.spmatrix(
        kvxopt.matrix(data.copy()),
        kvxopt.matrix(t.indices.astype(np.int64)),
        kvxopt.matrix(cols),
        (t.n, t.n),
    )
    symbolic = klu.symbolic(A)

    def run() -> None:
        A.V = kvxopt.matrix(data)
        numeric = klu.numeric(A, symbolic)
        x = kvxopt.matrix(b)
        klu.solve(A, symbolic, numeric, x)

    return run


class _OverBudget(Exception):
    pass


def pushover_child(n: int, wall: str, budget: float) -> dict:
    import resource

    from masonry_dem.solvers import factorization as fz
    from masonry_dem.solvers import resources
    from masonry_dem.solvers.incremental import StaticSolver

    model = WALLS[wall](n)
    t0 = time.perf_counter()
    solver = StaticSolver(model)
    steps: list = []

    def on_step(step) -> None:
        steps.append(step.load_factor)
        if time.perf_counter() - t0 > budget:
            raise _OverBudget

    stop, reason = "budget", ""
    try:
        h = solver.run(callback=on_step)
        status, stop, reason = str(h.status), str(h.stop), h.reason
        lam = h.collapse_multiplier if h.collapse_multiplier is not None else h.final_load_factor
    except _OverBudget:  # stopped by --pushover-budget: what it reached
        status, lam = f"stopped@{budget:.0f}s", max(steps)
    seconds = time.perf_counter() - t0
    return {
        "status": status,
        "stop": stop,
        "reason": reason[:300],
        "lambda": lam,
        "seconds": seconds,
        "steps": len(steps),
        "iterations": solver.iterations,
        "factorizations": solver.factorizations,
        "s_per_iteration": seconds / max(solver.iterations, 1),
        "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "estimated_mb": resources.estimate(
            model.blocks.count, model.interfaces.count, model.n_dofs
        ).memory
        / 1e6,
        "backend": fz.choose(6 * model.blocks.count),
    }


def _child(kind: str, payload: dict, threads: int | None = None, timeout: float | None = None):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    if threads is not None:
        for var in (
            "NUMBA_NUM_THREADS",
            "OMP_NUM_THREADS",
            "MKL_NUM_THREADS",
            "OPENBLAS_NUM_THREADS",
        ):
            env[var] = str(threads)
    proc = subprocess.run(
        [sys.executable, __file__, "--child", kind, json.dumps(payload)],
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    if proc.returncode != 0:
        return {"error": (proc.stderr.strip().splitlines() or ["?"])[-1][:200]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def slope(x, y) -> float:
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(y) & (y > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        kind, payload = sys.argv[2], json.loads(sys.argv[3])
        func = {"sizes": sizes_child, "factor": factor_child, "pushover": pushover_child}[kind]
        from masonry_dem.studies.runs import warm_up

        warm_up()
        print(json.dumps(func(**payload)))
        return 0
    p = arguments(__doc__)
    p.add_argument("--sizes", type=int, nargs="+", default=[10, 30, 100, 316],
                   help="blocks per course N of the N x N walls (default: %(default)s)")  # fmt: skip
    p.add_argument("--pushover-up-to", type=int, default=11_000,
                   help="run the pushover on walls of at most this many blocks (default: %(default)s)")  # fmt: skip
    p.add_argument("--wall", choices=sorted(WALLS), default="eurocode",
                   help="the family of walls (default: %(default)s; see the docstring)")  # fmt: skip
    p.add_argument("--no-pushover", action="store_true", help="sizes and factorizations only")
    p.add_argument("--pushover-budget", type=float, default=3600.0,
                   help="stop a pushover after the step that passes this many seconds and "
                   "report what it reached (default: %(default)s)")  # fmt: skip
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2],
                   help="thread counts of the factor children; the pushover runs on the first "
                   "(default: %(default)s)")  # fmt: skip
    p.add_argument("--backends", nargs="+", default=None, help="default: every installed one")
    p.add_argument("--repeat", type=int, default=5, help="factorizations timed per backend")
    p.add_argument("--factor-up-to", type=int, default=200_000,
                   help="time the factorizations on walls of at most this many blocks")  # fmt: skip
    p.add_argument("--multifrontal-from", metavar="REF", default=None,
                   help="also time the multifrontal LU of commit REF (e.g. 7022155)")  # fmt: skip
    p.add_argument("--timeout", type=float, default=3600.0, help="seconds per child process")
    p.add_argument("--json", default=None, help="also write the results to this file")
    p.add_argument("--small", action="store_true",
                   help="only the backends on small walls (6-2 400 DOFs), in this process")  # fmt: skip
    p.add_argument("--pardiso-options", action="store_true",
                   help="only PARDISO's ordering and matching variants and KLU on --sizes, in this process")  # fmt: skip
    args = p.parse_args()
    print_machine()
    if args.pardiso_options:
        from masonry_dem.studies.runs import warm_up

        warm_up()
        pardiso_options(args.sizes, args.repeat)
        return 0
    if any(t < 1 for t in args.threads):
        p.error(f"--threads must be positive counts, got {args.threads}")
    if args.small:
        from masonry_dem.cli.study import warm_up

        warm_up()
        small_walls(max(args.repeat, 50))
        return 0
    from masonry_dem.solvers import factorization as fz

    backends = args.backends or fz.installed()
    multifrontal = None
    tmp = tempfile.TemporaryDirectory()
    if args.multifrontal_from:
        text = subprocess.run(
            ["git", "-C", str(ROOT), "show", f"{args.multifrontal_from}:src/masonry_dem/solvers/multifrontal.py"],
            capture_output=True, text=True, check=True,
        ).stdout  # fmt: skip
        multifrontal = str(Path(tmp.name) / "multifrontal.py")
        Path(multifrontal).write_text(text)
    rows = []
    for n in args.sizes:
        row: dict = {"n": n, **_child("sizes", {"n": n, "wall": args.wall}, timeout=args.timeout)}
        print(f"N={n}: {row.get('blocks')} blocks, {row.get('dofs')} DOFs, build "
              f"{row.get('build_s', float('nan')):.2f} s, assembly {row.get('assembly_s', float('nan')):.2f} s", flush=True)  # fmt: skip
        if row.get("blocks", 0) <= args.factor_up_to:
            for t in args.threads:
                res = _child("factor", {"n": n, "wall": args.wall, "backends": backends, "repeat": args.repeat, "multifrontal": multifrontal}, t, args.timeout)  # fmt: skip
                row[f"factor_{t}"] = res
                for name, r in res.items():
                    if isinstance(r, dict):
                        print(f"  {t} thread(s) {name:12} factor {r['factor_s']:.4f} s  solve {r['solve_s']:.4f} s  "
                              f"analyse+first {r['analyse_s']:.3f} s  residual {r['residual']:.1e}", flush=True)  # fmt: skip
                    else:
                        print(f"  {t} thread(s): {res}", flush=True)
                        break
        if not args.no_pushover and row.get("blocks", 0) <= args.pushover_up_to:
            row["pushover"] = _child(
                "pushover",
                {"n": n, "wall": args.wall, "budget": args.pushover_budget},
                args.threads[0],
                timeout=args.timeout,
            )
            row["pushover_threads"] = args.threads[0]
            print(f"  pushover ({args.threads[0]} thread(s)) {row['pushover']}", flush=True)
        rows.append(row)
    tmp.cleanup()
    _report(rows, backends + (["multifrontal"] if multifrontal else []), args.threads)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2))
    return 0


def _report(rows: list[dict], backends: list[str], threads: list[int]) -> None:
    from masonry_dem.solvers import resources

    print()
    head = f"{'blocks':>7} {'DOFs':>7} {'build s':>8} {'asm s':>7}"
    series: dict[str, list[float]] = {"build": [], "assembly": []}
    for t in threads:
        for b in backends:
            head += f" {b[:8] + '/' + str(t):>11}"
            series[f"{b}/{t}"] = []
    push = ("seconds", "iterations", "factorizations", "s_per_iteration", "peak_mb")
    head += "  pushover: status      lambda  seconds  its  facs  s/it   MB"
    for k in push:
        series[k] = []
    print(head)
    blocks = []
    for r in rows:
        if "blocks" not in r:
            continue
        blocks.append(r["blocks"])
        line = f"{r['blocks']:>7} {r['dofs']:>7} {r['build_s']:>8.3f} {r['assembly_s']:>7.3f}"
        series["build"].append(r["build_s"])
        series["assembly"].append(r["assembly_s"])
        for t in threads:
            res = r.get(f"factor_{t}", {})
            for b in backends:
                v = (
                    res.get(b, {}).get("factor_s", float("nan"))
                    if isinstance(res.get(b), dict)
                    else float("nan")
                )
                series[f"{b}/{t}"].append(v)
                line += f" {v:>11.4f}"
        po = r.get("pushover", {})
        est = resources.estimate(r["blocks"], r["interfaces"], r["dofs"])
        if "status" in po:
            line += (f"  {po['status']:>16} {po['lambda']:>11.5g} {po['seconds']:>8.2f} {po['iterations']:>4} "
                     f"{po['factorizations']:>5} {po['s_per_iteration']:.3f} {po['peak_mb']:>4.0f} ({po['backend']})"
                     f" estimated {est.memory / 1e6:.0f} MB, {est.seconds:.0f} s")  # fmt: skip
        elif po:
            line += f"  pushover: {po}"
        for k in push:
            series[k].append(po.get(k, float("nan")) if "status" in po else float("nan"))
        print(line)
    print("\nlog-log slope against blocks: all walls | from ~10^3 blocks up")
    x = np.array(blocks, float)
    big = x >= 900
    for k, v in series.items():
        print(f"  {k:22} {slope(x, v):6.2f} | {slope(x[big], np.asarray(v)[big]):6.2f}")


if __name__ == "__main__":
    sys.exit(main())
