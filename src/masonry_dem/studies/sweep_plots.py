"""The plots of a sweep: lambda against each varied value and, for samples, the histogram
and the empirical CDF of lambda (PNG files in the sweep's folder)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.studies.sweep_plan import Plan, path_keys
from masonry_dem.studies.sweep_table import cell

LAMBDA_LABEL = "collapse multiplier $\\lambda$ [-] (live load / its nominal value)"


def axis_label(path: str) -> str:
    """``material.kn`` -> ``material.kn [N/m^3]``: the unit from the case schema."""
    from masonry_dem.cases.schema import RANGES

    key = path_keys(path)[-1]
    rng = RANGES.get(key) if isinstance(key, str) else None
    return f"{path} [{rng.unit if rng is not None and rng.unit else '-'}]"


def write_plots(folder: Path, rows: list[dict[str, Any]], plan: Plan) -> list[Path]:
    """lambda against each varied path (``lambda_vs_<path>.png``) and, for samples, the
    histogram and the empirical CDF of lambda; failed runs are marked along the axis."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from masonry_dem.export.results_folder import write_atomic

    out: list[Path] = []
    ok = [r for r in rows if r["status"] == "collapse" and r["lambda"] is not None]
    done = [r for r in rows if r["status"] == "completed" and r["lambda"] is not None]
    bad = [r for r in rows if r["status"] not in ("collapse", "completed")]
    name = str(plan.case.get("name", Path(plan.source).stem))

    def save(fig: Any, filename: str) -> None:
        path = folder / filename
        write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=120, format="png"))
        plt.close(fig)
        out.append(path)

    for path in plan.paths:
        fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
        numeric = all(
            isinstance(r[path], (int, float)) and not isinstance(r[path], bool) for r in rows
        )
        labels = None if numeric else sorted({cell(r[path]) for r in rows})

        def x(
            rs: list[dict[str, Any]], path: str = path, labels: list[str] | None = labels
        ) -> list[Any]:
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
        for drawn, column, marker, style in series:
            if drawn:
                ax.plot(x(drawn), [r[column] for r in drawn], marker, **style)
        if bad:
            for xv in x(bad):
                ax.axvline(xv, color="C3", lw=0.8, ls=":")
            ax.plot([], [], ":", color="C3", label=f"failed ({len(bad)})")
        if labels is not None:
            ax.set_xticks(range(len(labels)), labels)
        if path.split(".")[-1] in ("kn", "kt"):
            ax.set_xscale("log")
        ax.set_xlabel(axis_label(path))
        ax.set_ylabel(LAMBDA_LABEL)
        ax.set_title(f"{name}: {len(rows)} runs")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        save(fig, f"lambda_vs_{path}.png")
    if plan.sample and ok:
        lam = np.sort([r["lambda"] for r in ok])
        excluded = (
            f"; {len(rows) - lam.size} runs without collapse left out"
            if len(rows) > lam.size
            else ""
        )
        what = ", ".join(f"{p} ~ {d.label()}" for p, d in plan.sample.items())
        for kind in ("histogram", "cdf"):
            fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
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
            ax.set_xlabel(LAMBDA_LABEL)
            ax.set_title(f"{name}: {subject}{excluded}\n{what}", fontsize=9)
            save(fig, f"lambda_{kind}.png")
    return out
