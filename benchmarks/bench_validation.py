"""Benchmark: each validation case's time, and lambda's sensitivity to the paper's assumptions.

Time of every validation case (no files written), and the sensitivity of lambda to the
assumptions of masonry_dem.cases.paper.Assumptions.

    python benchmarks/bench_validation.py                 # time per case and in total
    python benchmarks/bench_validation.py OL1 S11         # some cases
    python benchmarks/bench_validation.py --sensitivity   # lambda when each assumption moves
    python benchmarks/bench_validation.py --settings memory=slip   # other static settings
"""

from __future__ import annotations

import time
from dataclasses import fields, replace

from _machine import arguments, print_machine

from masonry_dem import set_thread_wait_policy
from masonry_dem.cases.paper import build_case, case_names
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.studies.runs import warm_up

# (case, assumption changes): a sensible move of each value the paper does not give
SENSITIVITY = [
    ("OL1", {"dry_kn": 2.4e8, "dry_kt": 1.0e8}),
    ("OL1", {"dry_kn": 2.4e10, "dry_kt": 1.0e10}),
    ("OL1", {"dry_kt": 0.4e9}),
    ("OL1", {"column_dofs_table1": ("u1", "u2", "u3")}),
    ("OL1", {"column_dofs_table1": ("u3",)}),
    ("OL1", {"column_dofs_table1": ("u1", "u3", "w1", "w2", "w3")}),
    ("OL2", {"column_dofs_table1": ("u1", "u2", "u3")}),
    ("S13", {"dry_kn": 2.4e8, "dry_kt": 1.0e8}),
    ("S13", {"column_dofs_table2": ("u1", "u3")}),
    ("S5", {"column_dofs_table2": ("u1", "u3")}),
    ("S32", {"s32_beams_hold": False}),
    ("S32", {"s32_beam_course": 16}),
    ("S32", {"s32_top_restrained": True}),
    # openings: +-1 block wide, +-1 course high, sill +-1 course
    ("S23", {"opening_width": 2}),
    ("S23", {"opening_width": 4}),
    ("S23", {"opening_height": 8}),
    ("S23", {"opening_height": 10}),
    ("S23", {"sill_courses": 5}),
    ("S23", {"sill_courses": 7}),
    ("S34", {"opening_width": 2}),
    ("S34", {"opening_width": 4}),
    ("S34", {"opening_height": 8}),
    ("S34", {"opening_height": 10}),
    ("S34", {"sill_courses": 5}),
    ("S34", {"sill_courses": 7}),
    ("9-13", {"brick_unit_weight": 16e3}),
    ("9-13", {"brick_unit_weight": 20e3}),
    ("9-13", {"simple_support": "dofs"}),
    ("2-3", {"simple_support": "dofs"}),
    ("2-3", {"support_strip_width": 0.02}),
    ("2-3", {"support_strip_width": 0.04}),
]


def run(
    name: str, settings: dict | None = None, **changes
) -> tuple[float | None, int, int, float, float, str]:
    """One case with ``changes`` to its Assumptions and ``settings`` to its StaticSettings."""
    case = build_case(name, **changes)
    t0, c0 = time.perf_counter(), time.process_time()
    h = pushover(case.model, replace(case.settings, **(settings or {})), monitor=case.monitor)
    return (
        h.collapse_multiplier,
        len(h.steps),
        h.iterations,
        time.perf_counter() - t0,
        time.process_time() - c0,
        h.status,
    )


def parse_settings(items: list[str]) -> dict:
    """``FIELD=VALUE`` pairs as StaticSettings changes, values typed like the field's default."""
    defaults = {f.name: getattr(StaticSettings(), f.name) for f in fields(StaticSettings)}
    out: dict = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or key not in defaults:
            raise SystemExit(f"--settings: {item!r} is not FIELD=VALUE with a StaticSettings field")
        default = defaults[key]
        if isinstance(default, bool):
            out[key] = text.lower() in ("1", "true", "yes")
        elif isinstance(default, (str, int)):
            out[key] = type(default)(text)
        else:  # floats, and None (a length)
            out[key] = float(text)
    try:
        StaticSettings(**out)
    except ValueError as err:  # the message names the field and the value
        raise SystemExit(f"--settings: {err}") from None
    return out


def main(argv: list[str] | None = None) -> None:
    set_thread_wait_policy()  # as the command line does, before any kernel runs
    p = arguments(__doc__)
    p.add_argument("cases", nargs="*")
    p.add_argument("--sensitivity", action="store_true")
    p.add_argument(
        "--settings",
        nargs="+",
        default=[],
        metavar="FIELD=VALUE",
        help="StaticSettings fields for every case (e.g. memory=slip tension=plastic)",
    )
    args = p.parse_args(argv)
    print_machine()
    settings = parse_settings(args.settings)
    if args.sensitivity:
        base: dict[str, float | None] = {}
        print(f"{'case':6s} {'change':45s} {'lambda':>10s} {'base':>10s} {'move':>7s}")
        for name, changes in SENSITIVITY:
            if name not in base:
                base[name] = run(name)[0]
            lam = run(name, **changes)[0]
            ref = base[name]
            move = "-" if lam is None or not ref else f"{100 * (lam / ref - 1):+.1f}%"
            print(f"{name:6s} {str(changes):45s} {lam!s:>10.8s} {ref!s:>10.8s} {move:>7s}")
        return
    warm_up()  # the compiled law is loaded before anything is timed
    total = 0.0
    print(f"{'case':6s} {'lambda':>10s} {'steps':>5s} {'iters':>5s} {'wall s':>7s} {'cpu s':>6s}")
    for name in args.cases or case_names():
        lam, steps, its, wall, cpu, status = run(name, settings)
        total += wall
        print(f"{name:6s} {lam!s:>10.8s} {steps:5d} {its:5d} {wall:7.2f} {cpu:6.2f} {status}")
    print(f"total wall time {total:.1f} s")


if __name__ == "__main__":
    main()
