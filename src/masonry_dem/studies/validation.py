"""The paper's validation cases (Tables 1-3): each run as a pushover, its row against the
paper's DEM and the test or FEM reference, the cases side by side in worker processes, and
the comparison table.

Each case run with a results folder writes its VTU/PVD series, pushover.csv, summary.json,
the pushover plot, the collapse mechanism (``mechanism.png``: the collapse mode, joints
coloured by the relative motion across them) and the damage map (``damage.png``: interface
states) to ``<out>/<case>/``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from masonry_dem.studies import text

log = logging.getLogger(__name__)

#: the face each table's walls are seen from
_VIEWS = {"1": "front", "2": "front", "3": "front"}
RESTRAINTS = ("columns", "return-walls")

Row = dict[str, Any]


def run_case(
    name: str,
    out: Path | None = None,
    render: bool = True,
    restraint: str = "columns",
    return_blocks: int | None = None,
) -> Row:
    """Run one case; return its row. ``restraint="return-walls"``: the specimen with its
    return walls as blocks, ``return_blocks`` long (None: the default of
    ``cases.paper.Assumptions``)."""
    from masonry_dem.analysis import analyze
    from masonry_dem.cases.paper import build_case

    if restraint not in RESTRAINTS:
        raise ValueError(f"restraint must be one of {RESTRAINTS}, got {restraint!r}")
    if restraint == "columns":
        case = build_case(name)
    else:
        case = build_case(name, restraint=restraint, return_blocks=return_blocks)
    label = name
    if restraint != "columns":
        label = f"{name}_return{case.extra['return_blocks']}"
    folder = None if out is None else Path(out) / label
    t0 = time.perf_counter()
    hist = analyze(case.model, "pushover", case.settings, out=folder, monitor=case.monitor).details
    seconds = time.perf_counter() - t0
    ours = hist.collapse_multiplier
    row: Row = {
        "case": name,
        "table": case.table,
        "unit": case.unit,
        "ours": ours,
        "paper_dem": case.paper_dem,
        "reference": case.reference,
        "error_vs_reference": None if ours is None else case.error(ours),
        "error_vs_paper": None if ours is None else case.error(ours, "paper"),
        "bracket": list(hist.collapse_bracket) if hist.collapse_bracket else None,
        "steps": len(hist.steps),
        "iterations": hist.iterations,
        "seconds": round(seconds, 3),
        "status": hist.status,
        "reason": hist.reason,
        "mechanism": case.mechanism,
        "restraint": restraint,
    }
    if restraint != "columns":
        row["return_blocks"] = case.extra["return_blocks"]
    row.update({k: v for k, v in case.extra.items() if k in ("lambda_limit_analysis",)})
    if folder is not None and render:
        row["png"] = render_case(folder, _VIEWS[case.table])
    return row


def run_cases(
    names: Sequence[str],
    out: Path | None,
    render: bool,
    jobs: int = 1,
    done: Callable[[Row], None] | None = None,
    **variant: Any,
) -> list[Row]:
    """Run cases, side by side in ``jobs`` processes when more than one; the rows in the
    order of ``names``; ``done(row)`` after each case; ``variant``: the restraint reading
    (``restraint``, ``return_blocks`` of :func:`run_case`).

    Fresh (spawned) processes: a forked copy of a process that has started VTK or BLAS
    threads may hang."""
    if jobs <= 1 or len(names) <= 1:
        rows = []
        for name in names:
            rows.append(run_case(name, out, render, **variant))
            if done is not None:
                done(rows[-1])
        return rows
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from masonry_dem.cases.paper import build_case

    # the largest models first (the time of a case grows with its joints), so that no
    # worker is left with a long case while the others wait
    restraint = variant.get("restraint", "columns")
    largest_first = sorted(
        names, key=lambda name: -build_case(name, restraint=restraint).model.interfaces.count
    )
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        max_workers=min(jobs, len(names)), mp_context=context, initializer=one_kernel_thread
    ) as pool:
        futures = {
            pool.submit(run_case, name, out, render, **variant): name for name in largest_first
        }
        by_name = {}
        for future in as_completed(futures):
            by_name[futures[future]] = future.result()
            if done is not None:
                done(by_name[futures[future]])
    return [by_name[name] for name in names]


def one_kernel_thread() -> None:
    """In a worker process of a pool: the compiled kernels (interface law, factorization) on
    one thread, since the workers already share the cores."""
    import numba

    numba.set_num_threads(1)


def render_case(folder: Path, view: str) -> str | None:
    """The pushover plot, damage maps and (after a collapse) mechanism PNGs of a case's
    folder; the path of the oblique one, None where rendering is unavailable or fails."""
    try:
        from masonry_dem.export.render import plot_pushover, render_mechanism, render_step
    except ImportError as exc:
        log.warning("no PNG for %s: the render module is unavailable (%s)", folder, exc)
        return None
    try:
        plot_pushover(folder)
        png = render_step(folder, step="last", view="oblique", out=folder / "damage.png")
        render_step(folder, step="last", view=view, out=folder / f"damage_{view}.png")
        from masonry_dem.export.results_folder import MECHANISM_FILES

        if (folder / MECHANISM_FILES[0]).is_file():  # the run ended in collapse
            png = render_mechanism(folder, view="oblique", out=folder / "mechanism.png")
            render_mechanism(folder, view=view, out=folder / f"mechanism_{view}.png")
    except Exception as exc:  # rendering must never lose the analysis
        log.warning("no PNG for %s: %s", folder, exc)
        return None
    return str(png)


def _number(value: float | None, unit: str) -> str | None:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return None
    return f"{value:9.0f}" if unit == "Pa" else f"{value:9.4f}"


def _pct(value: float | None) -> str | None:
    return None if value is None else f"{100 * value:+6.1f}%"


def _label(row: text.Row) -> str:
    """The case, and the return walls' length in blocks of the return-wall reading."""
    m = row.get("return_blocks")
    return str(row["case"]) if m is None else f"{row['case']}/r{m}"


#: the columns of :func:`format_table`
TABLE_COLUMNS = (
    text.Column("case", "<7", _label),
    text.Column("table", "<5"),
    text.Column("ours", ">9", lambda r: _number(r["ours"], r["unit"])),
    text.Column("paper", ">9", lambda r: _number(r["paper_dem"], r["unit"])),
    text.Column("ref", ">9", lambda r: _number(r["reference"], r["unit"])),
    text.Column("err ref", ">8", lambda r: _pct(r["error_vs_reference"])),
    text.Column("err pap", ">8", lambda r: _pct(r["error_vs_paper"])),
    text.Column("steps", "5d"),
    text.Column("s", "6.2f", "seconds"),
    text.Column("status", "", gap="  "),
)


def format_table(rows: list[Row]) -> str:
    """The rows against the paper and the reference, and the mean error of each table."""
    lines = text.text_table(TABLE_COLUMNS, rows)
    readings = sorted(
        {(r.get("restraint", "columns"), r.get("return_blocks")) for r in rows}, key=str
    )
    for restraint, m in readings:
        same = [
            r
            for r in rows
            if (r.get("restraint", "columns"), r.get("return_blocks")) == (restraint, m)
        ]
        what = "" if restraint == "columns" else f", return walls of {m} blocks"
        for table in ("1", "2", "3"):
            errs = [abs(r["error_vs_reference"]) for r in same if r["table"] == table and r["ours"]]
            n_all = sum(r["table"] == table for r in same)
            if errs:
                lines.append(
                    f"Table {table}{what}: mean |error| vs reference "
                    f"{100 * sum(errs) / len(errs):.1f}% over {len(errs)} of {n_all} cases"
                )
    return "\n".join(lines)
