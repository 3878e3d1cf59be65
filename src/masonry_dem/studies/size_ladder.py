"""The methods on a ladder of wall sizes (10^2 to 10^4 blocks): lambda, time and, against the
static solver's answer on the same wall, the ratio of the multipliers and of the times.

The walls: square running-bond walls of 0.4 x 0.2 x 0.2 m blocks (mu 0.6, dry joints) on a
rigid slab, pushed in their plane by lambda x their weight, as in
``benchmarks/bench_limit_analysis.py --ladder``. A method runs on the walls up to its own
size limit (a static pushover of 10^4 blocks takes tens of minutes; dynamic relaxation is
slower still), and limit analysis on all of them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from masonry_dem.model import Model
from masonry_dem.studies import text
from masonry_dem.studies.runs import Method, run_method, with_changes

DEFAULT_SIZES = (100, 1000, 10_000)
#: the largest wall (blocks) each method runs on by default
DEFAULT_UP_TO: dict[Method, int] = {
    Method.STATIC: 1000,
    Method.DYNAMIC_RELAXATION: 150,
    Method.LIMIT_ANALYSIS: 20_000,
}
#: limit analysis on the ladder: the exact cone (the LP of the entry point's default backend
#: is 7-77 times slower on the validation walls, docs/limit_analysis.md)
LADDER_LIMIT_SETTINGS: dict[str, Any] = {"backend": "clarabel"}


def ladder_wall(blocks: int) -> Model:
    """A square running-bond wall of about ``blocks`` blocks on a slab, tilted in plane."""
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import InterfaceMaterial, SelfWeight, Support, WeightProportional

    if isinstance(blocks, bool) or int(blocks) != blocks or blocks < 4:
        raise ValueError(f"blocks must be a whole number >= 4, got {blocks!r}")
    side = max(2, round(math.sqrt(blocks)))
    wall = running_bond_wall(side, side, a=0.2, b=0.4, s=0.2, unit_weight=2000 * 9.81)
    slab_and_wall, base = add_base(wall)
    return Model.build(
        slab_and_wall,
        InterfaceMaterial(kn=1e9, kt=4e8, friction=0.6),
        [Support([base])],
        [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
        name=f"ladder {side}x{side}",
    )


def size_ladder(
    sizes: Iterable[int] = DEFAULT_SIZES,
    methods: Iterable[Method | str] = (Method.STATIC, Method.LIMIT_ANALYSIS),
    up_to: Mapping[Method, int] | None = None,
    limit_settings: Mapping[str, Any] | None = None,
    progress: Callable[[dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """One row per wall and method: lambda, status, seconds; ``ratio_to_static`` and
    ``time_ratio_to_static`` against the static run of the same wall (None without one).
    ``up_to``: the largest size (blocks asked for) each method runs on (``DEFAULT_UP_TO``)."""
    from masonry_dem.solvers.dynamic_relaxation import DRSettings
    from masonry_dem.solvers.incremental import StaticSettings

    chosen = [Method.parse(str(m)) for m in methods]
    limits = {**DEFAULT_UP_TO, **(up_to or {})}
    base: dict[Method, Any] = {
        Method.STATIC: StaticSettings(),
        Method.DYNAMIC_RELAXATION: DRSettings(),
        Method.LIMIT_ANALYSIS: with_changes(LADDER_LIMIT_SETTINGS, dict(limit_settings or {})),
    }
    rows: list[dict[str, Any]] = []
    for size in sizes:
        model = ladder_wall(size)
        n = model.blocks.count
        static: dict[str, Any] | None = None
        wall_rows = []
        for method in chosen:
            if size > limits[method]:  # the size asked for: a wall of 1 000 has 1 041 blocks
                continue
            run = run_method(method, model, base[method])
            row = {
                "blocks": n,
                "interfaces": model.interfaces.count,
                "method": method.value,
                "status": run.status,
                "reason": run.reason,
                "lambda": run.load_factor,
                "seconds": round(run.seconds, 4),
                **({"bound": run.bound} if run.bound else {}),
                **run.cost,
            }
            if method is Method.STATIC:
                static = row
            wall_rows.append(row)
            if progress is not None:
                progress(row)
        for row in wall_rows:
            lam_s = None if static is None else static["lambda"]
            row["ratio_to_static"] = (
                None if row["lambda"] is None or not lam_s else row["lambda"] / lam_s
            )
            row["time_ratio_to_static"] = (
                None
                if static is None or not static["seconds"]
                else row["seconds"] / static["seconds"]
            )
        rows += wall_rows
    return rows


def progress_line(row: dict[str, Any]) -> str:
    return text.progress_line(f"{row['blocks']} blocks, {row['method']}", row)


#: the columns of :func:`ladder_text`
LADDER_COLUMNS = (
    text.Column("blocks", "7d"),
    text.Column("interf", "7d", "interfaces"),
    text.Column("method", "<7", lambda r: Method(r["method"]).short),
    text.Column("status", "<11"),
    text.Column("lambda", ">10.5g"),
    text.Column("seconds", "8.2f"),
    text.Column("x static lambda", ">15.3f", "ratio_to_static"),
    text.Column("x static time", ">13.3f", "time_ratio_to_static"),
)


def ladder_text(rows: list[dict[str, Any]]) -> str:
    lines = text.text_table(LADDER_COLUMNS, rows)
    lines.append(
        "x static: over the static pushover of the same wall (- where the wall is above the "
        "static solver's size limit)"
    )
    for r in rows:
        if r["status"] != "collapse":
            lines.append(f"{r['blocks']} blocks, {r['method']}: {r['reason']}")
    return "\n".join(lines)
