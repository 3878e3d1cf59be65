"""Pictures that never mislead: the sweep plot of a lambda that does not vary (a free wall,
friction 0.5-0.9: lambda 0.067278287 in every run, its limit-analysis bound 1e-10 above),
and a pushover plot whose case name is longer than the figure is wide.

Each is an image test (pytest-mpl, baseline in tests/export/baseline, RMS tolerance 2 of
255 as for the pushover plot of test_render.py) and, because an image test only says the
picture did not change, a test of what the picture must show: no tick offset, the level
drawn where it is, the method named, the title inside the figure.
"""

from __future__ import annotations

import json

import pytest

from masonry_dem.export.figure_text import fitted_title, level
from masonry_dem.export.plots import pushover_figure
from masonry_dem.studies.sweep_plan import Plan
from masonry_dem.studies.sweep_plots import lambda_figure

FRICTIONS = [0.5, 0.6, 0.7, 0.8, 0.9]
FREE_WALL = 0.067278287
#: the bound of a free wall equals its lambda but for the solvers' round-off
ABOVE = 1e-10
LONG_NAME = (
    "U-shaped rubble-stone wall with two return walls of four blocks each, a window and a "
    "lintel, tilted on a fixed base (test case of a very long name)"
)


def free_wall_sweep() -> tuple[list[dict], Plan]:
    rows = [
        {
            "run": k,
            "material.friction": mu,
            "status": "collapse",
            "lambda": FREE_WALL * (1 + 1e-13 * k),
            "limit_analysis_bound": FREE_WALL + ABOVE,
        }
        for k, mu in enumerate(FRICTIONS)
    ]
    plan = Plan(
        case={"name": "free wall"},
        source="free_wall.toml",
        vary={"material.friction": FRICTIONS},
    )
    return rows, plan


def drawn(fig):
    fig.canvas.draw()
    return fig.axes[0]


@pytest.mark.slow
@pytest.mark.mpl_image_compare(baseline_dir="baseline", tolerance=2, style="default")
def test_constant_lambda_sweep_image():
    rows, plan = free_wall_sweep()
    return lambda_figure(rows, plan, "material.friction")


def test_a_constant_lambda_is_a_level_line_on_a_plain_axis():
    rows, plan = free_wall_sweep()
    ax = drawn(lambda_figure(rows, plan, "material.friction"))
    assert ax.yaxis.get_offset_text().get_text() == ""
    lo, hi = ax.get_ylim()
    assert lo < FREE_WALL < hi
    assert hi - lo >= 0.1 * FREE_WALL  # not magnified to the runs' round-off
    ticks = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
    assert ticks and all(float(t.replace("\u2212", "-")) > 0 for t in ticks)
    labels = [line.get_label() for line in ax.get_lines()]
    assert f"collapse: {FREE_WALL:.6g} in every run" in labels
    assert f"limit-analysis bound: {FREE_WALL + ABOVE:.6g} in every run" in labels
    assert "static pushover" in ax.get_title()


def test_a_varying_lambda_is_not_a_level():
    assert level([0.1, 0.1 + 1e-9]) == pytest.approx(0.1)
    assert level([0.1, 0.11]) is None
    assert level([0.1]) is None


def long_named(results_copy):
    summary = json.loads((results_copy / "summary.json").read_text())
    summary["name"] = LONG_NAME
    (results_copy / "summary.json").write_text(json.dumps(summary))
    return pushover_figure(results_copy)


@pytest.mark.slow
@pytest.mark.mpl_image_compare(baseline_dir="baseline", tolerance=2, style="default")
def test_long_title_image(results_copy):
    return long_named(results_copy)


def test_a_long_title_is_wrapped_inside_the_figure(results_copy):
    fig = long_named(results_copy)
    ax = drawn(fig)
    title = ax.title
    box = title.get_window_extent()
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width
    assert box.y1 <= fig.bbox.height
    lines = title.get_text().split("\n")
    assert len(lines) == 3
    assert lines[-1].startswith("static pushover")  # the method is never shortened away
    assert LONG_NAME.startswith(" ".join(lines[:-1])[: -len("...")])


def test_a_title_past_its_lines_is_shortened_with_an_ellipsis():
    text = fitted_title("word " * 200 + "\nthe method", width_inches=6.4, fontsize=10)
    lines = text.split("\n")
    assert len(lines) == 3
    assert lines[1].endswith("...")
    assert lines[2] == "the method"
