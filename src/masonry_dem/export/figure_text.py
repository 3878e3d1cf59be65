"""What every matplotlib picture of the package shares, so that none misleads: axes that print
their values as they are (no offset moved into a corner label, where "1e-10+6.7278287e-2" read
as a bound below lambda), a quantity that does not vary drawn as a level line on such an axis,
titles wrapped to the figure's width instead of running off its edges, and the method that
made the numbers named on the picture."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Iterable, Mapping
from typing import Any

#: values whose spread is below this share of their size are one level, to any digit shown
LEVEL_SPREAD = 1e-6
#: half-height of the axis around a level, as a share of the level
LEVEL_MARGIN = 0.1
#: width of an average character of the default sans-serif font, in font sizes (DejaVu Sans
#: runs 0.55-0.6; the larger keeps a wrapped line inside the figure)
_CHAR_WIDTH = 0.62
#: lines a title may take before it is shortened
TITLE_LINES = 3
ELLIPSIS = "..."

#: how a pushover's ``method`` in summary.json is named on a picture (a run without one is a
#: static pushover: the only method that writes none)
METHOD_NAMES = {
    "static": "static pushover (Newton, load/displacement control)",
    "dynamic_relaxation": "pushover by dynamic relaxation",
}


def method_name(method: object) -> str:
    """The picture's name of a pushover's ``method`` (None: the static pushover)."""
    key = "static" if method in (None, "") else str(method)
    return METHOD_NAMES.get(key, key.replace("_", " "))


def method_of(summary: Mapping[str, Any]) -> str:
    """The method that made a results folder, from its summary.json: a limit analysis
    (``analysis = "limit"``, its ``method`` associative or not) or a pushover."""
    if summary.get("analysis") == "limit":
        kind = summary.get("method")
        return f"limit analysis ({kind}, rigid blocks)" if kind else "limit analysis (rigid blocks)"
    return method_name(summary.get("method"))


def plain_axes(ax: Any) -> None:
    """Linear axes print every tick as its value: no offset (log axes have none)."""
    from matplotlib.ticker import ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        formatter = axis.get_major_formatter()
        if isinstance(formatter, ScalarFormatter):
            formatter.set_useOffset(False)


def level(values: Iterable[float | None]) -> float | None:
    """The one value the finite ``values`` hold (their mean) when they spread less than
    :data:`LEVEL_SPREAD` of it; None when they vary or there are fewer than two."""
    finite = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    if len(finite) < 2:
        return None
    lo, hi = min(finite), max(finite)
    centre = 0.5 * (lo + hi)
    return centre if hi - lo <= LEVEL_SPREAD * max(abs(centre), 1e-300) else None


def frame_level(ax: Any, value: float) -> None:
    """y-limits reaching at least :data:`LEVEL_MARGIN` of ``value`` either side of it (1 for a
    level of 0), and every point already drawn: a constant is drawn as a level line with
    readable ticks, never magnified to its round-off. Call it after plotting."""
    half = LEVEL_MARGIN * abs(value) or 1.0
    lo, hi = ax.get_ylim()
    ax.set_ylim(min(lo, value - half), max(hi, value + half))


def fitted_title(text: str, width_inches: float, fontsize: float) -> str:
    """``text`` wrapped to lines that fit ``width_inches`` at ``fontsize`` points, each of its
    own lines kept. Past :data:`TITLE_LINES` lines its first line (the case's name) is
    shortened with an ellipsis, so the lines after it (what is drawn, the method) stay."""
    chars = max(12, int(width_inches * 72.0 / (_CHAR_WIDTH * fontsize)))
    wrapped = [
        textwrap.wrap(paragraph, chars, break_on_hyphens=False) or [""]
        for paragraph in text.split("\n")
    ]
    first, rest = wrapped[0], [line for lines in wrapped[1:] for line in lines]
    room = max(1, TITLE_LINES - len(rest))
    if len(first) > room:
        last = first[room - 1][: chars - len(ELLIPSIS)].rstrip()
        first = first[: room - 1] + [last + ELLIPSIS]
    return "\n".join(first + rest)


def set_title(ax: Any, text: str, fontsize: float = 10.0) -> None:
    """The axes' title, wrapped to the figure's width (:func:`fitted_title`)."""
    width = ax.figure.get_figwidth()
    ax.set_title(fitted_title(text, width, fontsize), fontsize=fontsize)
