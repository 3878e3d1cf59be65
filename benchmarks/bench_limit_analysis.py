"""Limit analysis: the grid study, the validation cases beside the pushover, a size ladder.

    python benchmarks/bench_limit_analysis.py --grid-study      # default grid of the frozen
                                                               # capacities (cT within 1 %)
    python benchmarks/bench_limit_analysis.py --cases [NAMES]   # 18 cases: LA (assoc., HiGHS
                                                               # and Clarabel), non-assoc., pushover
    python benchmarks/bench_limit_analysis.py --cone-cases [NAMES]   # exact cone: Clarabel
                                                               # alone against the package's
                                                               # choice (normal equations)
    python benchmarks/bench_limit_analysis.py --ladder 100 1000 10000   # blocks: LA vs pushover
    python benchmarks/bench_limit_analysis.py --speed 100 1000 10000    # build vs solve, the
                                                               # formulations and solvers
                                                               # (Clarabel against the
                                                               # normal equations)
    python benchmarks/bench_limit_analysis.py --profile 300 1000 3000   # the exact cone: size
                                                               # per block, Clarabel's setup,
                                                               # iterations and settings

    python benchmarks/bench_limit_analysis.py --corpus          # non-associative against the
                                                               # pushover on 31 generated
                                                               # walls, both starts
    python benchmarks/bench_limit_analysis.py                   # issue 37's table: 10^3 and
    python benchmarks/bench_limit_analysis.py --scale 1000 10000 100000   # 10^4 blocks in
                                                               # and out of plane (s, memory,
                                                               # bracket, backend), and the
                                                               # bound's share of
                                                               # ``masonry-dem run``
    python benchmarks/bench_limit_analysis.py --scale 1000 10000 --against main --no-share
                                                               # each wall on main's src too,
                                                               # in turn: before and after in
                                                               # one run (CPU ratio); a wall
                                                               # above --max-memory GB (8) is
                                                               # stopped, or not started when
                                                               # its estimate is above it

Times are wall-clock seconds of one run on this machine; compare the ratios printed in one
run, not figures from different runs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _machine import arguments, print_machine

from masonry_dem.constitutive import torsion_constant
from masonry_dem.solvers.limit_analysis import limit_analysis, torsion_quadrature
from masonry_dem.studies.size_ladder import ladder_wall

ASPECTS = (1.0, 1.5, 2.0, 3.0, 4.0)


def grid_study(max_n: int = 12) -> int:
    """Error of the uniform-pressure torsion of the n x n Lobatto grid against cT, and the
    smallest even n within 1 % on every aspect (odd n put a point on the cusp of |y|)."""
    print(f"{'n':>3s} " + " ".join(f"{f'{a:g}:1':>8s}" for a in ASPECTS))
    chosen = None
    for n in range(2, max_n + 1):
        errs = [
            torsion_quadrature(0.2 * a, 0.2, n) / float(torsion_constant(0.2 * a, 0.2)) - 1
            for a in ASPECTS
        ]
        print(f"{n:3d} " + " ".join(f"{100 * e:+7.2f}%" for e in errs))
        if chosen is None and n % 2 == 0 and max(abs(e) for e in errs) <= 0.01:
            chosen = n
    print(f"smallest even n within 1 % of cT on aspects {ASPECTS}: {chosen}")
    return chosen or -1


def _timed(fn, *args, **kwargs):
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


def _fmt(x: float | None) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.4f}"


def cases(names: list[str], nonassoc_grid: int | None = None) -> None:
    from masonry_dem.cases.paper import build_case, case_names
    from masonry_dem.solvers.incremental import pushover
    from masonry_dem.studies.runs import warm_up

    warm_up()
    names = names or case_names()
    print(
        f"{'case':6s} {'LA assoc':>9s} {'s':>6s} {'LA cone':>9s} {'s':>6s} {'non-a Cl':>9s} "
        f"{'s':>6s} {'it':>3s} {'pushover':>9s} {'s':>6s} {'status':>9s} {'paper LA':>8s}"
    )
    for name in names:
        case = build_case(name)
        model = case.model
        assoc, t_a = _timed(limit_analysis, model)
        cone, t_c = _timed(limit_analysis, model, backend="clarabel")
        nonassoc, t_n = _timed(
            limit_analysis, model, associative=False, backend="clarabel", grid=nonassoc_grid
        )
        hist, t_p = _timed(pushover, model, case.settings, monitor=case.monitor)
        lam_p = hist.collapse_multiplier if hist.status == "collapse" else hist.final_load_factor
        la_ref = case.extra.get("lambda_limit_analysis")

        def show(r) -> str:
            return _fmt(r.load_factor) if r.status == "collapse" else r.status[:9]

        print(
            f"{name:6s} {show(assoc):>9s} {t_a:6.2f} {show(cone):>9s} {t_c:6.2f} "
            f"{show(nonassoc):>9s} {t_n:6.2f} {nonassoc.iterations:3d} {_fmt(lam_p):>9s} "
            f"{t_p:6.2f} {hist.status:>9s} {_fmt(la_ref):>8s}",
            flush=True,
        )
        for r in (assoc, cone, nonassoc):
            if r.status != "collapse":
                print(f"       {r.method} {r.backend}: {r.reason}")


def cone_cases(names: list[str]) -> None:
    """The exact cone on the validation cases: Clarabel alone (the normal equations switched
    off) against the package's choice (the normal equations from ``NORMAL_EQUATIONS_FROM``
    velocities), lambda and CPU seconds of the whole ``limit_analysis`` call, one run."""
    from masonry_dem.cases.paper import build_case, case_names
    from masonry_dem.solvers.limit_analysis import backends, normal_ipm

    limit_analysis(build_case("S11").model, backend="clarabel")  # numba's kernels loaded
    print(
        f"{'case':7s} {'veloc.':>6s} {'Clarabel':>13s} {'cpu s':>6s} {'package':>13s} "
        f"{'cpu s':>6s} {'ratio':>6s}  solver"
    )
    for name in names or case_names():
        model = build_case(name).model
        try:
            backends.NORMAL_EQUATIONS_FROM = 10**12
            alone, t_a, _ = _cpu(limit_analysis, model, backend="clarabel")
        finally:
            backends.NORMAL_EQUATIONS_FROM = normal_ipm.NORMAL_EQUATIONS_FROM
        chosen, t_b, _ = _cpu(limit_analysis, model, backend="clarabel")

        def show(r) -> str:
            return f"{r.load_factor:.6f}" if r.status == "collapse" else r.status

        print(
            f"{name:7s} {int(model.free.sum()):6d} {show(alone):>13s} {t_a:6.2f} "
            f"{show(chosen):>13s} {t_b:6.2f} {t_b / t_a:6.2f}  "
            f"{'normal eq.' if chosen.bracket else 'Clarabel'}",
            flush=True,
        )


def ladder(sizes: list[int], pushover_up_to: int, highs: bool = True) -> None:
    """Square-ish running-bond walls on a base tilted in plane (mu 0.6): LA against pushover."""
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
    from masonry_dem.solvers.incremental import pushover
    from masonry_dem.studies.runs import warm_up

    warm_up()
    print(
        f"{'blocks':>7s} {'interf':>7s} {'LA HiGHS':>9s} {'s':>7s} {'LA Clar.':>9s} {'s':>7s} "
        f"{'pushover':>9s} {'s':>7s} {'push/LA':>8s}"
    )
    for target in sizes:
        side = max(2, round(math.sqrt(target / 1.0)))
        wall = running_bond_wall(side, side, a=0.2, b=0.4, s=0.2, unit_weight=2000 * 9.81)
        blocks, base = add_base(wall)
        model = Model.build(
            blocks,
            InterfaceMaterial(kn=1e9, kt=4e8, friction=0.6),
            [Support([base])],
            [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
        )
        r_h, t_h = _timed(limit_analysis, model) if highs else (None, float("nan"))
        r_c, t_c = _timed(limit_analysis, model, backend="clarabel")
        lam_p, t_p = None, float("nan")
        if model.blocks.count <= pushover_up_to:
            h, t_p = _timed(pushover, model)
            lam_p = h.collapse_multiplier
        print(
            f"{model.blocks.count:7d} {model.interfaces.count:7d} "
            f"{_fmt(r_h.load_factor if r_h else None):>9s} "
            f"{t_h:7.2f} {_fmt(r_c.load_factor):>9s} {t_c:7.2f} {_fmt(lam_p):>9s} {t_p:7.2f} "
            f"{t_p / np.nanmin([t_h, t_c]):8.2f}",
            flush=True,
        )


def _cpu(fn, *args, **kwargs):
    """(result, process CPU seconds, wall seconds): on a shared machine the CPU time is the
    figure that does not depend on the other jobs."""
    c0, t0 = time.process_time(), time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.process_time() - c0, time.perf_counter() - t0


def _kinematic_problem(model):
    """The limit-analysis problem of ``model`` and its corner velocity rows (grid 2): what
    a kinematic solve builds before Clarabel starts."""
    from masonry_dem.solvers.limit_analysis import formulation, kinematic

    problem = formulation.Problem.of(model)
    return problem, kinematic.corner_velocity_rows(problem, 2)


def speed(sizes: list[int], static_up_to: int, highs_up_to: int, clarabel_up_to: int) -> None:
    """The ladder's walls: the time to build the problem (compatibility matrix and the cone
    rows, vectorised) against the solve, for the kinematic SOCP by Clarabel and by the
    interior point method on the normal equations (``normal_ipm``: on every DOF, and on the
    mirror-symmetric ones, the package's choice for these in-plane walls), the static SOCP
    it replaced (Clarabel, objective in force units) and the LP (HiGHS IPM, 4-face pyramid,
    exact in plane); then the whole ``limit_analysis`` call (build, solve, mechanism check).
    CPU seconds of this process, and the ratios of one run."""
    from masonry_dem.solvers.limit_analysis import formulation, kinematic, normal_ipm
    from masonry_dem.solvers.limit_analysis.backends import solve_clarabel, solve_highs
    from masonry_dem.solvers.limit_analysis.mirror import mirror_dofs

    print(
        f"{'blocks':>7s} {'interf':>7s} {'build':>6s} {'Clarabel':>9s} {'cpu s':>7s} "
        f"{'normal eq.':>10s} {'cpu s':>7s} {'it':>3s} {'mirror':>10s} {'cpu s':>7s} {'it':>3s} "
        f"{'bracket width':>13s} {'Cl./mir.':>8s} {'whole':>7s} {'wall s':>7s} "
        f"{'stat.SOCP':>9s} {'cpu s':>7s} {'LP HiGHS':>9s} {'cpu s':>7s}"
    )
    for target in sizes:
        model = ladder_wall(target)
        # numba's kernels loaded (compiled on a first run) before anything is timed
        normal_ipm.solve_kinematic_normal(formulation.Problem.of(ladder_wall(30)), 2)

        (problem, _), t_build, _ = _cpu(_kinematic_problem, model)
        lam_c, t_c = None, float("nan")
        if model.blocks.count <= clarabel_up_to:
            (sol, _, _), t_c, _ = _cpu(kinematic.solve_kinematic_clarabel, problem, 2)
            lam_c = sol.lam
        full, t_f, _ = _cpu(normal_ipm.solve_kinematic_normal, problem, 2)
        drop = mirror_dofs(model)
        half, t_m, _ = _cpu(normal_ipm.solve_kinematic_normal, problem, 2, drop=drop)
        whole, t_w, w_w = _cpu(limit_analysis, model, backend="clarabel")
        lam_s, t_s = None, float("nan")
        if model.blocks.count <= static_up_to:
            R, K = formulation.associative_columns(model, 2, None)
            E = (problem.H_T @ R).tocsc()
            mu = np.repeat(model.friction, K)
            st, t_s, _ = _cpu(
                solve_clarabel, E, problem.live, problem.rhs, E.shape[1] // 3, mu, None
            )
            lam_s = st.lam
        lam_h, t_h = None, float("nan")
        if model.blocks.count <= highs_up_to:
            dirs = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
            R, _ = formulation.associative_columns(model, 2, dirs)
            E = (problem.H_T @ R).tocsc()
            k = E.shape[1]
            lp, t_h, _ = _cpu(
                solve_highs, E, problem.live, problem.rhs, np.zeros(k), np.full(k, np.inf)
            )
            lam_h = lp.lam

        def ipm(out) -> tuple[str, int, str]:
            if out is None:
                return "-", 0, "-"
            sol, _, _, bracket = out
            return f"{sol.lam:.6f}", sol.iterations, f"{bracket.width:.1e}"

        lam_f, it_f, _ = ipm(full)
        lam_m, it_m, width = ipm(half if drop is not None else None)
        print(
            f"{model.blocks.count:7d} {model.interfaces.count:7d} {t_build:6.2f} "
            f"{_fmt(lam_c):>9s} {t_c:7.2f} {lam_f:>10s} {t_f:7.2f} {it_f:3d} "
            f"{lam_m:>10s} {t_m:7.2f} {it_m:3d} {width:>13s} {t_c / t_m:8.2f} "
            f"{t_w:7.2f} {w_w:7.2f} {_fmt(lam_s):>9s} {t_s:7.2f} {_fmt(lam_h):>9s} {t_h:7.2f}",
            flush=True,
        )
        print(
            f"        whole limit_analysis: {whole.status} {whole.load_factor:.6f}, "
            f"bracket {whole.bracket}; {whole.reason}",
            flush=True,
        )


#: Clarabel's settings compared by ``--profile``: the package's (``clarabel_options``), the
#: iterative refinement back on, and each factorization on one and two threads
PROFILE_VARIANTS: dict[str, dict[str, object]] = {
    "package": {},
    "refine": {"iterative_refinement_enable": True},
    "qdldl": {"direct_solve_method": "qdldl"},
    "faer 1": {"direct_solve_method": "faer", "max_threads": 1},
    "faer 2": {"direct_solve_method": "faer", "max_threads": 2},
}


def _normal_matrix_factor_seconds(G) -> float:
    """CPU seconds of one numeric Cholesky (PARDISO, one thread, METIS) of G^T W G with a
    positive definite 3 x 3 block W per cone: what one iteration of an interior point method
    on the normal equations (6 rows per block) would factorize; nan without pypardiso."""
    try:
        from pypardiso import PyPardisoSolver
    except ImportError:
        return float("nan")
    from scipy import sparse

    p = G.shape[0] // 3
    B = np.random.default_rng(0).standard_normal((p, 3, 3))
    W = B @ B.transpose(0, 2, 1) + np.eye(3)
    rows = np.repeat(np.arange(3 * p).reshape(-1, 3), 3, axis=1).ravel()
    cols = np.tile(np.arange(3 * p).reshape(-1, 3), 3).ravel()
    Wm = sparse.csr_matrix((W.ravel(), (rows, cols)), shape=(3 * p, 3 * p))
    N = sparse.triu((G.T @ Wm @ G).tocsr(), format="csr")
    N.sort_indices()
    solver = PyPardisoSolver(mtype=2)
    solver.libmkl.MKL_Set_Num_Threads(1)
    solver.set_phase(11)
    solver._call_pardiso(N, np.zeros(N.shape[0]))
    solver.set_phase(22)
    c0 = time.process_time()
    solver._call_pardiso(N, np.zeros(N.shape[0]))
    return time.process_time() - c0


def profile(sizes: list[int]) -> None:
    """Where the time of the exact cone goes, on the ladder's walls: the problem's size per
    block, the build, Clarabel's setup and its iterations (CPU seconds, each variant of
    ``PROFILE_VARIANTS``, with lambda), and one PARDISO factorization of the normal matrix."""
    from masonry_dem.solvers.limit_analysis import kinematic

    print(
        f"{'blocks':>7s} {'u':>6s} {'cones':>7s} {'nnz A':>8s} {'build':>6s} {'variant':>8s} "
        f"{'lambda':>9s} {'it':>3s} {'setup':>6s} {'solve':>7s} {'per it':>7s} {'x pkg':>6s}"
    )
    for target in sizes:
        model = ladder_wall(target)

        (problem, G), t_build, _ = _cpu(_kinematic_problem, model)
        n_u, cones = G.shape[1], G.shape[0] // 3
        n = model.blocks.count
        base = float("nan")
        for name, options in PROFILE_VARIANTS.items():
            (sol, _, _), t_solve, _ = _cpu(kinematic.solve_kinematic_clarabel, problem, 2, options)
            if name == "package":
                base = t_solve
            per_it = t_solve / max(sol.iterations, 1)
            print(
                f"{n:7d} {n_u:6d} {cones:7d} {G.nnz + n_u:8d} {t_build:6.2f} {name:>8s} "
                f"{sol.lam:9.6f} {sol.iterations:3d} {sol.setup_seconds:6.2f} "
                f"{t_solve:7.2f} {per_it:7.3f} {t_solve / base:6.2f}",
                flush=True,
            )
        t_n = _normal_matrix_factor_seconds(G.tocsr())
        print(
            f"{n:7d} per block: {n_u / n:.1f} velocities, {cones / n:.1f} cones, "
            f"{(G.nnz + n_u) / n:.0f} nonzeros of A; PARDISO on the normal matrix "
            f"({n_u} rows): {t_n:.3f} s per factorization",
            flush=True,
        )


def scale_wall(blocks: int, plane: str):
    """A running-bond wall of about ``blocks`` blocks on a rigid base: ``"in"``, the size
    ladder's wall tilted in its plane; ``"out"``, issue 37's (0.081 x 0.210 x 0.070 m
    blocks, dry, mu 0.7, the left column held in u1 and u3) tilted out of its plane;
    ``"sym"``, the same wall standing free on its base (symmetric about the vertical plane
    across its middle: ``mirror.mirror_pairs``; lambda = s / H)."""
    if plane == "in":
        return ladder_wall(blocks)
    from masonry_dem.geometry import selectors as select
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional

    side = max(2, round(math.sqrt(blocks)))
    wall = running_bond_wall(side, side, a=0.081, b=0.210, s=0.070, unit_weight=20e3)
    placed, base = add_base(wall)
    held = select.column(placed, "left", among=list(range(wall.count)))
    supports = [Support([base])] + ([Support(held, ["u1", "u3"])] if plane == "out" else [])
    return Model.build(
        placed,
        InterfaceMaterial(kn=1e9, kt=4e8, friction=0.7),
        supports,
        [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name=f"out of plane {side}x{side}{'' if plane == 'out' else ', free'}",
    )


def _scale_child(blocks: int, plane: str, queue) -> None:
    """One wall in a fresh process, so that its peak memory is its own: the build and the
    package's ``limit_analysis`` (associative, backend chosen by size), one thread."""
    from masonry_dem.solvers.limit_analysis import formulation, normal_ipm

    # numba's kernels loaded before anything is timed
    normal_ipm.solve_kinematic_normal(formulation.Problem.of(ladder_wall(30)), 2)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    c0, t0 = time.process_time(), time.perf_counter()
    model = scale_wall(blocks, plane)
    out = limit_analysis(model)
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    queue.put(
        {
            "blocks": model.blocks.count - 1,
            "plane": plane,
            "status": out.status,
            "lambda": out.load_factor,
            "bracket": out.bracket,
            "backend": out.backend,
            "solver": out.reason.split("(")[-1].rstrip(")")[:60],
            "cpu": cpu,
            "wall": wall,
            "peak_mb": rss / 1024,
            "start_mb": rss0 / 1024,
        }
    )


#: a U wall as ``docs/walls_that_meet.md`` writes it, for the bound's share of a run
U_WALL = """
[geometry]
builder = "u_wall"
blocks_along_length = 8
courses = 21
a = 0.02824
b = 0.07978
s = 0.03968
unit_weight = 26.8e3
return_blocks = 4
base = true

[material]
kn = 1e9
kt = 0.4e9
friction = 0.7

[[supports]]
select = "base"

[[loads]]
type = "self_weight"
[[loads]]
type = "weight_proportional"
direction = [0, 0, 1]
"""


def bound_share() -> None:
    """``masonry-dem run --no-render`` on the bundled wall and the U walls of
    ``docs/walls_that_meet.md``, one process each (one thread): the run's wall seconds and
    the limit-analysis bound's (``summary.json``)."""
    print(
        f"\n{'masonry-dem run':34s} {'blocks':>6s} {'lambda':>8s} {'run s':>7s} {'bound s':>8s} "
        f"{'share':>6s}  bound"
    )
    window = "facade_openings = [[0.23934, 0.19768, 0.39890, 0.39536]]\nlintels = true\n"
    with tempfile.TemporaryDirectory() as tmp:
        cases: dict[str, str | None] = {"default wall (bundled)": None}
        for label, text in (
            ("U wall 8 x 21, returns 4", U_WALL),
            (
                "U wall, window and lintels",
                U_WALL.replace("base = true\n", window + "base = true\n"),
            ),
        ):
            path = Path(tmp) / f"{len(cases)}.toml"
            path.write_text(text)
            cases[label] = str(path)
        for label, case in cases.items():
            out = Path(tmp) / f"out{len(label)}"
            cmd = [sys.executable, "-m", "masonry_dem.cli", "run"] + ([case] if case else [])
            cmd += ["--out", str(out), "--no-render"]
            env = dict(os.environ, NUMBA_NUM_THREADS="1")
            done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
            if not (out / "summary.json").exists():
                print(f"{label:34s} no summary: {done.stderr.strip()[-200:]}")
                continue
            summary = json.loads((out / "summary.json").read_text())
            run_s = float(summary.get("wall_seconds") or summary["seconds"])
            la_s = float(summary.get("limit_analysis_seconds") or 0.0)
            lam = summary.get("lambda")
            print(
                f"{label:34s} {summary['blocks']:6d} {_fmt(lam):>8s} {run_s:7.2f} {la_s:8.3f} "
                f"{la_s / run_s:6.1%}  {summary.get('limit_analysis_status')}",
                flush=True,
            )


#: the largest resident memory a ``--scale`` wall may take before it is stopped (the issue's
#: 8 GB at 10^5 blocks); a wall whose estimate (``resources.limit_estimate``, three
#: interfaces a block) is above it is not started
SCALE_MAX_BYTES = 8e9


def _scale_row(blocks: int, plane: str, src: str | None, max_bytes: float) -> dict:
    """One wall in a fresh process on the tree ``src`` (None: this one), its resident memory
    watched every 0.2 s and the process stopped above ``max_bytes``."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    if src is not None:
        env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    cmd = [sys.executable, __file__, "--scale-child", str(blocks), plane]
    with tempfile.TemporaryFile("w+") as out:
        child = subprocess.Popen(cmd, env=env, stdout=out, stderr=subprocess.DEVNULL, text=True)
        peak = 0.0
        while child.poll() is None:
            try:
                with open(f"/proc/{child.pid}/status") as f:
                    rss = next(int(x.split()[1]) * 1024 for x in f if x.startswith("VmRSS"))
            except (OSError, StopIteration):
                rss = 0
            peak = max(peak, rss)
            if rss > max_bytes:
                child.kill()
                child.wait()
                return {
                    "stopped": f"stopped at {rss / 1e9:.1f} GB resident (cap {max_bytes / 1e9:g})"
                }
            time.sleep(0.2)
        out.seek(0)
        lines = [x for x in out.read().splitlines() if x.startswith("{")]
    if child.returncode != 0 or not lines:
        return {"stopped": f"exit {child.returncode}"}
    return json.loads(lines[-1])


def _print_scale_row(row: dict, label: str) -> None:
    if "stopped" in row:
        print(f"{label}  {row['stopped']}", flush=True)
        return
    bracket = "-" if row["bracket"] is None else "[{:.7g}, {:.7g}]".format(*row["bracket"])
    lam = row["lambda"] if row["status"] == "collapse" else None
    print(
        f"{label} {row['blocks']:7d} {row['cpu']:7.2f} {row['wall']:7.2f} "
        f"{row['peak_mb']:8.0f} {row['start_mb']:8.0f} {_fmt(lam):>10s} {bracket:>27s} "
        f"{row['backend']:>8s}  {row['status']}: {row['solver']}",
        flush=True,
    )


def scale(
    sizes: list[int],
    against: str | None = None,
    max_bytes: float = SCALE_MAX_BYTES,
    share: bool = True,
    planes: tuple[str, ...] = ("in", "out"),
) -> None:
    """Issue 37's table: the package's associative ``limit_analysis`` on walls of ``sizes``
    blocks in and out of plane, one process a wall (one thread): CPU and wall seconds, peak
    memory (the process's, and what it held before the build), status, lambda, the certified
    bracket, the backend; then the bound's share of ``masonry-dem run``. ``against``: a
    commit whose ``src`` (``git archive``) runs each wall too, alternately with this tree's,
    and the CPU ratio (this tree / that one) of each wall is printed: before and after in
    one run."""
    from masonry_dem.solvers.resources import limit_estimate

    here = str(Path(__file__).resolve().parents[1] / "src")  # this tree's, first on the path
    trees: dict[str, str | None] = {"this": here}
    tmp = tempfile.TemporaryDirectory() if against else None
    if against and tmp is not None:
        root = Path(__file__).resolve().parents[1]
        archive = subprocess.run(
            ["git", "-C", str(root), "archive", against, "src"], capture_output=True, check=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", tmp.name], input=archive, check=True)
        trees = {against[:8]: str(Path(tmp.name) / "src"), "this": here}
    print(
        f"{'tree':>8s} {'plane':>5s} {'blocks':>7s} {'cpu s':>7s} {'wall s':>7s} "
        f"{'peak MB':>8s} {'start MB':>8s} {'lambda':>10s} {'bracket':>27s} {'backend':>8s}  solver"
    )
    try:
        for blocks in sizes:
            est = limit_estimate(blocks, 3 * blocks, 2, "clarabel")
            if est.memory > max_bytes:
                print(
                    f"{blocks} blocks: estimated {est.memory / 1e9:.1f} GB, above the cap "
                    f"{max_bytes / 1e9:g} GB: not run"
                )
                continue
            for plane in planes:
                cpu = {}
                for name, src in trees.items():
                    row = _scale_row(blocks, plane, src, max_bytes)
                    _print_scale_row(row, f"{name:>8s} {plane:>5s}")
                    cpu[name] = row.get("cpu")
                if len(trees) > 1 and None not in cpu.values():
                    before = cpu[next(iter(trees))]
                    print(
                        f"{'':>8s} {plane:>5s} cpu ratio this / {against}: "
                        f"{cpu['this'] / before:.2f}",
                        flush=True,
                    )
    finally:
        if tmp is not None:
            tmp.cleanup()
    if share:
        bound_share()


def _scale_child_main(blocks: int, plane: str) -> None:
    """``--scale-child``: one wall in this process, its row as one JSON line."""
    import queue as q

    out: q.Queue = q.Queue()
    _scale_child(blocks, plane, out)
    row = out.get()
    row["bracket"] = None if row["bracket"] is None else [float(x) for x in row["bracket"]]
    row["lambda"] = float(row["lambda"])
    print(json.dumps(row))


#: the generated walls of ``tests/solvers/test_limit_non_associative.py``: the corpus's walls of
#: at most 29 blocks with a reference collapse (seeds of ``studies.corpus.random_wall``)
CORPUS_SEEDS = (
    5, 8, 10, 12, 17, 22, 30, 34, 36, 37, 44, 49, 50, 51, 60, 65, 70, 85, 100, 113, 114,
    118, 126, 136, 141, 142, 143, 150, 151, 154, 161,
)  # fmt: skip


def corpus_walls(seeds: list[int], within: float = 0.10) -> None:
    """The non-associative analysis from both starts against the pushover on generated
    walls: per wall the pushover, each start's lambda (or status), its ratio and seconds;
    then how many lie within ``within`` of the pushover, per start."""
    import masonry_dem as md
    from masonry_dem.studies.corpus import random_wall

    starts = ("elastic", "associative")
    print(
        f"{'wall':40s} {'blocks':>6s} {'pushover':>9s}"
        + "".join(f" {name:>11s} {'ratio':>6s} {'s':>6s}" for name in starts)
    )
    tally: dict[str, dict[str, int]] = {name: {} for name in starts}
    for seed in seeds:
        wall = random_wall(seed)
        model = wall.build()
        push = md.pushover(model).collapse_multiplier
        line = f"{wall.name[:40]:40s} {model.blocks.count - 1:6d} {_fmt(push):>9s}"
        for name in starts:
            r, t = _timed(limit_analysis, model, associative=False, start=name)
            lam = r.load_factor if r.status == "collapse" else None
            ratio = lam / push if lam is not None and push else None
            kind = r.status if lam is None else ("within" if abs(ratio - 1) <= within else "off")
            tally[name][kind] = tally[name].get(kind, 0) + 1
            shown = _fmt(lam) if lam is not None else r.status
            line += f" {shown:>11s} {_fmt(ratio):>6s} {t:6.1f}"
        print(line, flush=True)
    for name in starts:
        counts = ", ".join(f"{k} {v}" for k, v in sorted(tally[name].items()))
        print(f"start={name!r}: {counts} (within {within:.0%} of the pushover)")


def main(argv: list[str] | None = None) -> None:
    p = arguments(__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--grid-study", action="store_true")
    p.add_argument("--cases", nargs="*", default=None, metavar="NAME")
    p.add_argument("--cone-cases", nargs="*", default=None, metavar="NAME")
    p.add_argument("--ladder", nargs="*", type=int, default=None, metavar="BLOCKS")
    p.add_argument(
        "--nonassoc-grid", type=int, default=None, help="grid of the non-associative runs"
    )
    p.add_argument("--no-highs", action="store_true", help="ladder: Clarabel only")
    p.add_argument("--speed", nargs="*", type=int, default=None, metavar="BLOCKS")
    p.add_argument("--profile", nargs="*", type=int, default=None, metavar="BLOCKS")
    p.add_argument("--static-up-to", type=int, default=1100, help="largest static SOCP (speed)")
    p.add_argument("--highs-up-to", type=int, default=320, help="largest LP (speed)")
    p.add_argument(
        "--clarabel-up-to", type=int, default=20_000, help="largest Clarabel SOCP (speed)"
    )
    p.add_argument("--pushover-up-to", type=int, default=2000, help="largest ladder pushover")
    p.add_argument("--scale", nargs="*", type=int, default=None, metavar="BLOCKS")
    p.add_argument(
        "--against",
        default=None,
        metavar="REF",
        help="--scale: run each wall on REF's src too (git archive), alternately: before and after",
    )
    p.add_argument(
        "--max-memory",
        type=float,
        default=SCALE_MAX_BYTES / 1e9,
        metavar="GB",
        help="--scale: stop a wall above this resident memory; skip one estimated above it",
    )
    p.add_argument("--no-share", action="store_true", help="--scale: without the run shares")
    p.add_argument(
        "--planes",
        nargs="+",
        choices=("in", "out", "sym"),
        default=["in", "out"],
        help="--scale: the walls (sym: out of plane, free on its base, symmetric)",
    )
    p.add_argument("--scale-child", nargs=2, default=None, metavar=("BLOCKS", "PLANE"))
    p.add_argument("--corpus", nargs="*", type=int, default=None, metavar="SEED")
    args = p.parse_args(argv)
    if args.scale_child is not None:
        _scale_child_main(int(args.scale_child[0]), args.scale_child[1])
        return
    print_machine()
    if args.corpus is not None:
        corpus_walls(args.corpus or list(CORPUS_SEEDS))
    if args.scale is not None:
        scale(
            args.scale or [1000, 10000],
            args.against,
            args.max_memory * 1e9,
            not args.no_share,
            tuple(args.planes),
        )
    if args.grid_study:
        grid_study()
    if args.cases is not None:
        cases(args.cases, args.nonassoc_grid)
    if args.cone_cases is not None:
        cone_cases(args.cone_cases)
    if args.ladder is not None:
        ladder(args.ladder or [100, 1000, 10000], args.pushover_up_to, not args.no_highs)
    if args.speed is not None:
        speed(
            args.speed or [100, 1000, 10000],
            args.static_up_to,
            args.highs_up_to,
            args.clarabel_up_to,
        )
    if args.profile is not None:
        profile(args.profile or [300, 1000, 3000])
    if not (
        args.profile is not None
        or args.grid_study
        or args.cases is not None
        or args.cone_cases is not None
        or args.ladder is not None
        or args.speed is not None
        or args.scale is not None
        or args.corpus is not None
    ):
        scale([1000, 10000])


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    main()
