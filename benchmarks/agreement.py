"""Agreement: the default static solver against the reference quasi-static analysis, wall by wall.

The agreement benchmark: the default static solver (``md.pushover``) against the reference
quasi-static analysis (``md.quasi_static``) on the corpus of
:mod:`masonry_dem.studies.corpus`, one row per wall: both multipliers, their ratio, both
statuses and seconds. A row is ``ok`` when the default agrees with the reference within
``--within`` (2 %), or ends ``failed``; ``LOW`` when the default certifies a collapse more
than that below a load at which the reference rests; ``HIGH`` when it reports a collapse
above the reference's. With ``--refined`` the reference runs again with its increments and
motion tolerance halved, to show its own discretisation error on each wall.

Where the reference's last rest lies past the small-displacement range, it runs again with
joints ten times stiffer in the same kt/kn (:mod:`masonry_dem.studies.judge`; the row's
``reference_stiffer``).

    NUMBA_NUM_THREADS=1 python benchmarks/agreement.py                  # everything
    python benchmarks/agreement.py --memory slip                        # the incremental law
    python benchmarks/agreement.py --groups issue                       # issue 36's walls
    python benchmarks/agreement.py --groups generated --count 30 --out rows.jsonl

Rows are appended to ``--out`` (JSON lines) as they finish, so a long run keeps them.
"""

from __future__ import annotations

import json
import logging
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

from _machine import arguments, print_machine

import masonry_dem as md
from masonry_dem.studies.corpus import CorpusWall, corpus
from masonry_dem.studies.judge import reference_within_range


def verdict(default: md.History, reference: md.History, within: float) -> str:
    """How the default answer stands against the reference."""
    ours = default.collapse_multiplier
    theirs = reference.collapse_multiplier
    if default.status == "failed":
        return "ok (failed)"
    if reference.status != "collapse" or theirs is None:
        # the reference found no collapse (completed) or no verdict: a collapse of the
        # default is unjudged, a completed default agrees with a completed reference
        if reference.status == default.status:
            return "ok"
        return f"unjudged (reference {reference.status})"
    if ours is None:
        return f"MISSED (default {default.status})"
    ratio = ours / theirs
    if ratio < 1.0 - within:
        return "LOW"
    if ratio > 1.0 + within:
        return "HIGH"
    return "ok"


def run_wall(wall: CorpusWall, within: float, refined: bool, memory: str | None = None) -> dict:
    model = wall.build()
    if memory is not None:  # the interface law of every wall: holonomic or incremental
        model = replace(model, memory=memory)
    t0 = time.perf_counter()
    default = md.pushover(model)
    t_default = time.perf_counter() - t0
    t0 = time.perf_counter()
    reference, stiffer = reference_within_range(model)
    t_reference = time.perf_counter() - t0
    row = {
        "wall": wall.name,
        "group": wall.group,
        "blocks": model.blocks.count - 1,
        "default": default.collapse_multiplier,
        "default_status": str(default.status),
        "default_reason": default.reason,
        "default_seconds": round(t_default, 2),
        "default_factorizations": default.factorizations,
        "reference": reference.collapse_multiplier,
        "reference_status": str(reference.status),
        "reference_reason": reference.reason,
        "reference_seconds": round(t_reference, 2),
        "reference_factorizations": reference.factorizations,
        "reference_stiffer": stiffer,
        **wall.describe,
    }
    ours, theirs = default.collapse_multiplier, reference.collapse_multiplier
    row["ratio"] = ours / theirs if ours is not None and theirs else None
    row["verdict"] = verdict(default, reference, within)
    if refined:
        base = md.QuasiStaticSettings()
        finer = replace(
            base,
            first_increment=base.first_increment / 2,
            load_increment=base.load_increment / 2,
            motion_tolerance=base.motion_tolerance / 2,
        )
        again = md.quasi_static(model, finer)
        row["refined"] = again.collapse_multiplier
        row["refined_status"] = str(again.status)
    return row


def summarise(rows: list[dict]) -> str:
    """The totals of a run: verdicts, the worst ratios, seconds and factorizations of each
    solver, and how far the refined reference moved."""
    lines = [f"{len(rows)} walls"]
    verdicts: dict[str, int] = {}
    for r in rows:
        name = r["verdict"].split(" ")[0] + (" (failed)" if "(failed)" in r["verdict"] else "")
        verdicts[name] = verdicts.get(name, 0) + 1
    ratios = [
        r["default"] / r["reference"]
        for r in rows
        if r.get("default") is not None
        and r.get("reference")
        and r["reference_status"] == "collapse"
    ]
    worst = (min(ratios), max(ratios)) if ratios else (math.nan, math.nan)
    lines.append(
        f"default: {', '.join(f'{k} {v}' for k, v in sorted(verdicts.items()))}; ratio to the "
        f"reference {worst[0]:.4f} .. {worst[1]:.4f}; "
        f"{sum(r['default_seconds'] for r in rows):.0f} s, "
        f"{sum(r['default_factorizations'] for r in rows)} factorizations"
    )
    statuses: dict[str, int] = {}
    for r in rows:
        statuses[r["reference_status"]] = statuses.get(r["reference_status"], 0) + 1
    lines.append(
        f"reference: {', '.join(f'{k} {v}' for k, v in sorted(statuses.items()))}; "
        f"{sum(r['reference_seconds'] for r in rows):.0f} s, "
        f"{sum(r['reference_factorizations'] for r in rows)} factorizations; run with "
        f"stiffer joints on {sum(r.get('reference_stiffer', 1.0) > 1.0 for r in rows)} walls"
    )
    moved = [
        abs(r["refined"] / r["reference"] - 1)
        for r in rows
        if r.get("refined") is not None and r.get("reference")
    ]
    if any("refined" in r for r in rows):
        unsettled = sum(
            1 for r in rows if "refined" in r and r["refined_status"] != r["reference_status"]
        )
        lines.append(
            f"refined reference: moved more than 0.5 % on {sum(m > 0.005 for m in moved)} "
            f"walls, more than 2 % on {sum(m > 0.02 for m in moved)} (largest "
            f"{max(moved, default=0.0):.2%}); another status on {unsettled}"
        )
    return "\n".join(lines)


def number(value: float | None, digits: int = 5) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def main(argv: list[str] | None = None) -> int:
    parser = arguments(__doc__)
    parser.add_argument(
        "--groups", nargs="+", default=["validation", "issue", "generated"], help="corpus groups"
    )
    parser.add_argument("--count", type=int, default=200, help="generated walls")
    parser.add_argument("--first", type=int, default=0, help="first wall of the list to run")
    parser.add_argument("--within", type=float, default=0.02, help="agreement tolerance")
    parser.add_argument("--refined", action="store_true", help="the reference refined too")
    parser.add_argument(
        "--memory",
        choices=["none", "slip"],
        help="the interface law of every wall: none (holonomic), slip (incremental)",
    )
    parser.add_argument("--out", type=Path, help="append rows as JSON lines")
    parser.add_argument(
        "--summarise", type=Path, metavar="ROWS", help="print the totals of a run's JSON lines"
    )
    args = parser.parse_args(argv)
    print_machine()
    if args.summarise is not None:
        rows = [json.loads(line) for line in args.summarise.read_text().splitlines() if line]
        print(summarise(rows))
        return 0
    logging.basicConfig(level=logging.ERROR)
    md.set_thread_wait_policy()
    walls = list(corpus(tuple(args.groups), args.count))[args.first :]
    header = (
        f"{'wall':42s} {'blocks':>6s} {'default':>9s} {'status':>9s} {'reference':>9s} "
        f"{'status':>9s} {'ratio':>7s} {'s def':>6s} {'s ref':>6s}  verdict"
    )
    print(header, flush=True)
    rows = []
    for wall in walls:
        row = run_wall(wall, args.within, args.refined, args.memory)
        rows.append(row)
        line = (
            f"{wall.name[:42]:42s} {row['blocks']:6d} {number(row['default']):>9s} "
            f"{row['default_status']:>9s} {number(row['reference']):>9s} "
            f"{row['reference_status']:>9s} {number(row['ratio'], 4):>7s} "
            f"{row['default_seconds']:6.1f} {row['reference_seconds']:6.1f}  {row['verdict']}"
        )
        if args.refined:
            line += f"  refined {number(row['refined'])}"
        print(line, flush=True)
        if args.out is not None:
            with args.out.open("a") as fh:
                fh.write(json.dumps(row) + "\n")
    print(summarise(rows), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
