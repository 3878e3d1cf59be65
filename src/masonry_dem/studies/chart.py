"""The speed-accuracy chart: run time against error in lambda, one column per case, a marker
per method, the Pareto front of each panel joined and ringed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from masonry_dem.studies.runs import Method
from masonry_dem.studies.speed_accuracy import ACCURACY, pareto_front

STYLE: dict[Method, dict[str, str]] = {
    Method.STATIC: dict(marker="o", color="tab:blue", label="static (paper's method)"),
    Method.DYNAMIC_RELAXATION: dict(marker="^", color="tab:orange", label="dynamic relaxation"),
    Method.LIMIT_ANALYSIS: dict(
        marker="s", color="tab:green", label="limit analysis (rigid blocks)"
    ),
}


def chart(rows: list[dict[str, Any]], path: Path, floor: float = 1e-5) -> Path:
    """Run time against error in lambda, one column per case; top row against the converged
    lambda of the case, bottom row against each method's own converged lambda."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    cases = list(dict.fromkeys(r["case"] for r in rows))
    ncol = max(len(cases), 1)
    fig, axes = plt.subplots(2, ncol, figsize=(5.0 * ncol, 8.2), squeeze=False)
    panels = (
        ("error_vs_converged", "error vs converged lambda of the case"),
        ("error_vs_own", "error vs the method's own converged lambda"),
    )
    for row, (error, ylabel) in enumerate(panels):
        for col, name in enumerate(cases):
            ax = axes[row, col]
            rs = [r for r in rows if r["case"] == name]
            for method, st in STYLE.items():
                mine = [r for r in rs if r["method"] == method]
                if not mine:
                    continue
                ok = [r for r in mine if r.get(error) is not None]
                bad = [r for r in mine if r.get(error) is None]
                ax.scatter(
                    [r["seconds"] for r in ok], [max(r[error], floor) for r in ok], s=36, **st
                )
                if bad:
                    ax.scatter(
                        [r["seconds"] for r in bad],
                        [1.0] * len(bad),
                        marker="x",
                        color=st["color"],
                        label=f"{method.value.replace('_', ' ')}: no lambda",
                    )
                for r in ok:
                    ax.annotate(
                        r["label"],
                        (r["seconds"], max(r[error], floor)),
                        fontsize=6,
                        xytext=(3, 2),
                        textcoords="offset points",
                    )
            front = pareto_front(rs, error)
            if front:
                xs = [r["seconds"] for r in front]
                ys = [max(r[error], floor) for r in front]
                ax.step(xs, ys, where="post", color="k", lw=1, label="Pareto front")
                ax.scatter(xs, ys, s=110, facecolors="none", edgecolors="k")
            ax.axhline(ACCURACY, color="grey", ls=":", lw=1)
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())  # no crowded labels
            ax.set_yscale("log")
            errors = [r[error] for r in rs if r.get(error) is not None]
            ax.set_ylim(floor / 2, max([2.0] + [1.5 * e for e in errors]))
            ax.set_xlabel("run time [s]")
            ax.set_title(name if row == 0 else f"{name} (own answer)")
            ax.grid(True, which="both", alpha=0.2)
        axes[row, 0].set_ylabel(f"{ylabel}\n(floor {floor:g}; dotted: 1 %)")
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Speed against accuracy of every solver setting")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
