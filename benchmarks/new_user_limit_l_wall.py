"""The non-associative limit analysis of a small L wall against the pushover: time and lambda.

The non-associative limit analysis on a small L wall: a minute where the pushover takes
a fraction of a second (session 17; a few seconds since its LPs are solved by column
generation, session 18), and a multiplier 15-26 % above the pushover's certified one.

Found by the new-user sweep (session 17, docs/new_user_sweep.md): ``masonry-dem limit
--non-associative`` on an L wall of 4 x b facade, a 3-block return, 4 or 6 courses (29 or
43 blocks, dry, mu 0.7, tilted along e3) took 74 s and 151 s (load about 3 on 2 cores) for
lambda 0.3349 and 0.2822, where the pushover, certified against the associative bound,
gives 0.2790 and 0.2242 in 0.1-0.4 s. The non-associative multiplier is documented as an
estimate, not a bound (docs/limit_analysis.md, "Cost on small walls" has the diagnosis,
"The frozen-capacity LP by column generation" the remedy).

    PYTHONPATH=src python benchmarks/new_user_limit_l_wall.py [--courses 4 6]
        # the pushover against the non-associative limit analysis, in one run
    PYTHONPATH=src python benchmarks/new_user_limit_l_wall.py --grids
        # where the time goes (solves, seconds per solve) and where the +20 % comes from:
        # HiGHS and Clarabel on grids 4 and 8, and the DEM's own collapse actions frozen
    PYTHONPATH=src python benchmarks/new_user_limit_l_wall.py --lp
        # one frozen-capacity LP with and without the lambda = 0 LP first (ratio, one run)
    PYTHONPATH=src python benchmarks/new_user_limit_l_wall.py --colgen [--case S15] [--whole]
        # the frozen-capacity LPs by column generation against the full LP, in one run: the
        # iteration by columns (lambda, iterations, pricing rounds, patterns), then its first
        # LPs solved both ways (lambda, seconds, ratio); --whole: the iteration on the full
        # LP too (about a minute on the L wall)
    PYTHONPATH=src python benchmarks/new_user_limit_l_wall.py --order [--whole] [--nearest on]
        # the iteration's answer when the pyramid's edges are listed from another edge (the
        # same LPs, their columns in another order): how far the degenerate LPs' choice of
        # optimum moves the fixed point, without and with the nearest-optimum selection
"""

from __future__ import annotations

import time

import numpy as np
from _machine import arguments, print_machine

import masonry_dem as md
from masonry_dem.solvers.limit_analysis import analysis, backends, columns, non_associative
from masonry_dem.solvers.limit_analysis.formulation import Solution


def l_wall_model(courses: int) -> md.Model:
    wall = md.l_wall(4, courses, 0.081, 0.21, 0.07, 20e3, return_blocks=3)
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        [md.Support([base])],
        [md.SelfWeight(), md.WeightProportional((0, 0, 1))],
        name=f"L wall, {courses} courses",
    )


def compare(courses: int) -> None:
    model = l_wall_model(courses)
    t0 = time.perf_counter()
    history = md.pushover(model)
    t1 = time.perf_counter()
    la = md.limit_analysis(model, associative=False)
    t2 = time.perf_counter()
    print(
        f"{model.name} ({model.blocks.count} blocks): pushover {history.status} "
        f"{history.final_load_factor:.5f} in {t1 - t0:.2f} s; non-associative limit "
        f"analysis {la.status} {la.load_factor:.5f} in {t2 - t1:.1f} s, {la.iterations} "
        f"iterations ({la.load_factor / history.final_load_factor - 1:+.1%}, "
        f"{(t2 - t1) / (t1 - t0):.0f}x the time)"
    )


def grids(courses: int) -> None:
    model = l_wall_model(courses)
    history = md.pushover(model)
    lam_p = history.final_load_factor
    print(f"{model.name}: pushover {lam_p:.4f}, {model.interfaces.count} interfaces")

    def show(label: str, r, seconds: float) -> None:
        lams = r.load_factors
        print(
            f"  {label}: {r.status} {lams[-1]:.4f} ({lams[-1] / lam_p - 1:+.1%}), first "
            f"{lams[0]:.4f}, {len(lams)} solves in {seconds:.1f} s "
            f"({seconds / len(lams):.2f} s a solve)",
            flush=True,
        )

    for backend in ("highs", "clarabel"):
        t = time.perf_counter()
        r = md.limit_analysis(model, backend=backend)
        show(f"associative, {backend}", r, time.perf_counter() - t)
        for grid in (4, 8):
            t = time.perf_counter()
            r = md.limit_analysis(model, associative=False, backend=backend, grid=grid)
            show(f"non-associative, {backend}, grid {grid}", r, time.perf_counter() - t)
    # the frozen capacities of the DEM's own actions at its collapse (its last step)
    actions = np.asarray(history.steps[-1].actions, float)
    real_start = non_associative.solve_associative

    def dem_start(problem, grid, dirs):
        sol = Solution("optimal", lam_p, None, None, "the DEM's actions")
        sol.info_actions = actions  # type: ignore[attr-defined]
        return sol, (0, 0)

    non_associative.solve_associative = dem_start
    try:
        for backend, grid, iterations in (("highs", 8, 1), ("clarabel", 8, 1), ("clarabel", 8, 50)):
            t = time.perf_counter()
            r = md.limit_analysis(
                model, associative=False, backend=backend, grid=grid, max_iterations=iterations
            )
            label = "one solve" if iterations == 1 else "iterated"
            show(
                f"DEM's actions frozen, {backend}, grid {grid}, {label}", r, time.perf_counter() - t
            )
    finally:
        non_associative.solve_associative = real_start


def lp_ratio(courses: int, repeat: int = 2) -> None:
    model = l_wall_model(courses)
    captured = []
    real = non_associative.solve_highs

    def capture(*args, **kwargs):
        captured.append(args[:6])
        raise StopIteration

    non_associative.solve_highs = capture
    try:
        md.limit_analysis(model, associative=False)
    except StopIteration:
        pass
    finally:
        non_associative.solve_highs = real
    args = captured[0]
    seconds = {True: 0.0, False: 0.0}
    lams = {}
    for _ in range(repeat):
        for first in (True, False):
            t = time.perf_counter()
            lams[first] = backends.solve_highs(*args, dead_load_first=first).lam
            seconds[first] += time.perf_counter() - t
    print(
        f"{model.name}, first frozen LP ({args[0].shape[1]} columns): with the lambda = 0 LP "
        f"{seconds[True] / repeat:.2f} s, without {seconds[False] / repeat:.2f} s "
        f"({seconds[True] / seconds[False]:.2f}x); lambda {lams[True]:.6f} and {lams[False]:.6f}"
    )


def case_model(name: str) -> md.Model:
    if name == "L":
        return l_wall_model(4)
    from masonry_dem.cases.paper import build_case

    return build_case(name).model


def colgen(name: str, lps: int, whole: bool) -> None:
    """The iteration by columns, timed, with its frozen LPs captured; then the first ``lps``
    of them solved by columns (the run's start and duals) and in full, alternately."""
    model = case_model(name)
    captured = []
    real = non_associative.solve_frozen_columns

    def capture(*args, **kwargs):
        captured.append(args)
        return real(*args, **kwargs)

    non_associative.solve_frozen_columns = capture
    try:
        t = time.perf_counter()
        r = md.limit_analysis(model, associative=False)
        seconds = time.perf_counter() - t
    finally:
        non_associative.solve_frozen_columns = real
    E_n, friction = captured[0][:2]
    print(
        f"{model.name or name} ({model.blocks.count} blocks, {friction.m} interfaces): full LP "
        f"{E_n.shape[0]} equilibrium + {friction.m * friction.K} capacity rows, "
        f"{E_n.shape[1] + friction.E_s.shape[1] + 1} columns; master {E_n.shape[0]} + "
        f"{friction.m} rows, {E_n.shape[1] + 1} columns + the patterns"
    )
    print(
        f"  by columns: {r.status} {r.load_factor:.6f} in {seconds:.1f} s, {r.iterations} "
        f"iterations, {r.info['pricing_rounds']} pricing rounds in all, "
        f"{r.info['patterns']} patterns at the end, {r.info['full_lps']} full LPs",
        flush=True,
    )
    if whole:
        t = time.perf_counter()
        f = md.limit_analysis(model, associative=False, column_generation=False)
        full_seconds = time.perf_counter() - t
        print(
            f"  full LP:    {f.status} {f.load_factor:.6f} in {full_seconds:.1f} s, "
            f"{f.iterations} iterations ({full_seconds / seconds:.1f}x the time)"
        )
    total = {"columns": 0.0, "full": 0.0}
    for i, args in enumerate(captured[:lps]):
        t = time.perf_counter()
        sol, _, stats = columns.solve_frozen_columns(*args)
        t1 = time.perf_counter()
        full = columns.solve_frozen_full(*args[:4])
        t2 = time.perf_counter()
        total["columns"] += t1 - t
        total["full"] += t2 - t1
        print(
            f"  LP {i + 1}: by columns {sol.lam:.9f} in {t1 - t:.2f} s ({stats.rounds} rounds, "
            f"{stats.columns} patterns{', full LP' if stats.full else ''}); full "
            f"{full.lam:.9f} in {t2 - t1:.2f} s; {full.lam / sol.lam - 1:+.1e}, "
            f"{(t2 - t1) / (t1 - t):.1f}x",
            flush=True,
        )
    print(f"  first {min(lps, len(captured))} LPs: {total['full'] / total['columns']:.1f}x")


def order(name: str, whole: bool, nearest: tuple[bool, ...]) -> None:
    """The same iteration with the pyramid's edges listed from edge 0, 1, 2 and 3, without
    and with the nearest-optimum selection (``nearest``), alternately in one run."""
    model = case_model(name)
    real = analysis.pyramid_edges
    ways = (True, False) if whole else (True,)
    try:
        for shift in range(4):
            analysis.pyramid_edges = lambda *a, s=shift: np.roll(real(*a), s, axis=0)
            for by_columns in ways:
                for select in nearest:
                    t = time.perf_counter()
                    r = md.limit_analysis(
                        model,
                        associative=False,
                        column_generation=by_columns,
                        nearest_optimum=select,
                    )
                    print(
                        f"{model.name or name}, edges from {shift}, "
                        f"{'by columns' if by_columns else 'full LP'}, "
                        f"{'nearest optimum' if select else 'solver optimum'}: {r.status} "
                        f"{r.load_factor:.5f}, {r.iterations} iterations, "
                        f"{time.perf_counter() - t:.1f} s",
                        flush=True,
                    )
    finally:
        analysis.pyramid_edges = real


def main(argv: list[str] | None = None) -> None:
    parser = arguments(__doc__)
    parser.add_argument("--courses", type=int, nargs="+", default=[4])
    parser.add_argument("--grids", action="store_true")
    parser.add_argument("--lp", action="store_true")
    parser.add_argument("--colgen", action="store_true")
    parser.add_argument("--order", action="store_true")
    parser.add_argument("--case", nargs="+", default=["L"], help="L (the L wall) or a paper case")
    parser.add_argument("--lps", type=int, default=3, help="LPs solved both ways (--colgen)")
    parser.add_argument("--whole", action="store_true")
    parser.add_argument(
        "--nearest",
        choices=["both", "on", "off"],
        default="both",
        help="--order: without and with the nearest-optimum selection (both), or one",
    )
    args = parser.parse_args(argv)
    print_machine()
    if args.colgen or args.order:
        for name in args.case:
            nearest = {"both": (False, True), "on": (True,), "off": (False,)}[args.nearest]
            colgen(name, args.lps, args.whole) if args.colgen else order(name, args.whole, nearest)
        return
    for courses in args.courses:
        if args.grids:
            grids(courses)
        elif args.lp:
            lp_ratio(courses)
        else:
            compare(courses)


if __name__ == "__main__":
    main()
