"""The plots of a sweep: lambda against each varied value and, for samples, the histogram
and the empirical CDF of lambda (PNG files in the sweep's folder)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.export.figure_text import frame_level, level, method_name, plain_axes, set_title
from masonry_dem.studies.sweep_plan import Plan, path_keys
from masonry_dem.studies.sweep_table import cell

LAMBDA_LABEL = "collapse multiplier $\\lambda$ [-] (live load / its nominal value)"


def axis_label(path: str) -> str:
    """``material.kn`` -> ``material.kn [N/m^3]``: the unit from the case schema."""
    from masonry_dem.cases.schema import RANGES

    key = path_keys(path)[-1]
    rng = RANGES.get(key) if isinstance(key, str) else None
    return f"{path} [{rng.unit if rng is not None and rng.unit else '-'}]"


def _method(plan: Plan) -> str:
    """The method that made the sweep's lambda, as its pictures name it."""
    analysis = plan.case.get("analysis")
    method = analysis.get("method") if isinstance(analysis, dict) else None
    return method_name(method)


def _figure() -> tuple[Any, Any]:
    """A figure of the sweep's size on the Agg canvas (no pyplot: nothing global to close)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def lambda_figure(rows: list[dict[str, Any]], plan: Plan, path: str) -> Any:
    """lambda (and the limit-analysis bound) against the varied ``path``, failed runs marked
    along the axis: a matplotlib Figure. A lambda or bound equal in every run is drawn as a
    level line on a plain axis, so no digit of it moves into an offset."""
    ok = [r for r in rows if r["status"] == "collapse" and r["lambda"] is not None]
    done = [r for r in rows if r["status"] == "completed" and r["lambda"] is not None]
    bad = [r for r in rows if r["status"] not in ("collapse", "completed")]
    name = str(plan.case.get("name", Path(plan.source).stem))
    fig, ax = _figure()
    numeric = all(isinstance(r[path], (int, float)) and not isinstance(r[path], bool) for r in rows)
    labels = None if numeric else sorted({cell(r[path]) for r in rows})

    def x(rs: list[dict[str, Any]]) -> list[Any]:
        return [r[path] if labels is None else labels.index(cell(r[path])) for r in rs]

    bounds = [r for r in rows if r["limit_analysis_bound"] is not None]
    series: tuple[tuple[list[dict[str, Any]], str, str, dict[str, Any]], ...] = (
        (ok, "lambda", "o", {"color": "C0", "label": "collapse"}),
        (
            bounds,
            "limit_analysis_bound",
            "_",
            {"color": "C2", "ms": 12, "label": "limit-analysis bound"},
        ),
        (
            done,
            "lambda",
            "^",
            {"mfc": "none", "color": "C1", "label": "completed (no collapse up to)"},
        ),
    )
    levels = []
    for drawn, column, marker, style in series:
        if not drawn:
            continue
        values = [r[column] for r in drawn]
        flat = level(values)
        if flat is not None:  # one legend entry: the level line, with its value
            label = f"{style['label']}: {flat:.6g} in every run"
            ax.axhline(flat, color=style["color"], lw=1, ls="--", label=label)
            style = {**style, "label": "_nolegend_"}
            levels.append(flat)
        ax.plot(x(drawn), values, marker, **style)
    if bad:
        for xv in x(bad):
            ax.axvline(xv, color="C3", lw=0.8, ls=":")
        ax.plot([], [], ":", color="C3", label=f"failed ({len(bad)})")
    if labels is not None:
        ax.set_xticks(range(len(labels)), labels)
    if path.split(".")[-1] in ("kn", "kt"):
        ax.set_xscale("log")
    plain_axes(ax)
    for flat in levels:
        frame_level(ax, flat)
    ax.set_xlabel(axis_label(path))
    ax.set_ylabel(LAMBDA_LABEL)
    set_title(ax, f"{name}: {len(rows)} runs\n{_method(plan)}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def sample_figure(rows: list[dict[str, Any]], plan: Plan, kind: str) -> Any:
    """The histogram (``kind`` "histogram") or the empirical CDF ("cdf") of the sampled
    runs' lambda, runs without collapse left out and counted in the title."""
    lam = np.sort(
        [r["lambda"] for r in rows if r["status"] == "collapse" and r["lambda"] is not None]
    )
    name = str(plan.case.get("name", Path(plan.source).stem))
    excluded = (
        f"; {len(rows) - lam.size} runs without collapse left out" if len(rows) > lam.size else ""
    )
    what = ", ".join(f"{p} ~ {d.label()}" for p, d in plan.sample.items())
    fig, ax = _figure()
    if kind == "histogram":
        ax.hist(lam, bins="auto", color="C0", edgecolor="white")
        ax.set_ylabel("runs [-]")
        subject = f"{lam.size} collapses"
    else:
        ax.step(lam, np.arange(1, lam.size + 1) / lam.size, where="post", color="C0")
        ax.set_ylabel("P(collapse at or below $\\lambda$) [-]")
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        subject = f"empirical CDF of {lam.size} collapses"
    plain_axes(ax)
    ax.set_xlabel(LAMBDA_LABEL)
    set_title(ax, f"{name}: {subject}{excluded}\n{what}\n{_method(plan)}", fontsize=9)
    return fig


def write_plots(folder: Path, rows: list[dict[str, Any]], plan: Plan) -> list[Path]:
    """lambda against each varied path (``lambda_vs_<path>.png``, :func:`lambda_figure`)
    and, for samples, the histogram and the empirical CDF of lambda
    (:func:`sample_figure`)."""
    from masonry_dem.export.results_folder import write_atomic

    out: list[Path] = []

    def save(fig: Any, filename: str) -> None:
        path = folder / filename
        write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=120, format="png"))
        out.append(path)

    for path in plan.paths:
        save(lambda_figure(rows, plan, path), f"lambda_vs_{path}.png")
    if plan.sample and any(r["status"] == "collapse" and r["lambda"] is not None for r in rows):
        for kind in ("histogram", "cdf"):
            save(sample_figure(rows, plan, kind), f"lambda_{kind}.png")
    return out
