"""The studies' text for people: fixed-width tables (:func:`text_table`), the progress line of
one run, and numbers that may be missing (:func:`fmt`)."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

Row = Mapping[str, Any]


def fmt(value: Any, spec: str, missing: str = "-") -> str:
    """``value`` formatted by ``spec``; ``missing`` for None."""
    return missing if value is None else format(value, spec)


def progress_line(what: str, row: Row) -> str:
    """One line per finished run: what ran, how it ended, lambda and its seconds."""
    return f"  {what}: {row['status']} lambda={fmt(row['lambda'], '.5g')} in {row['seconds']:.2f} s"


@dataclass(frozen=True)
class Column:
    """A column of :func:`text_table`: its title, the format of its values (``"<8"``,
    ``"11.5g"``, ``"9.2%"``: a width in every one) and how a row gives its value: a function
    of the row, or the row's key (default: the title). A missing value (None) is shown as
    ``-``; ``gap`` goes before the column."""

    title: str
    spec: str
    value: Callable[[Row], Any] | str | None = None
    gap: str = " "

    def _fit(self) -> str:
        """The alignment and width of ``spec``: right unless it says otherwise."""
        m = re.match(r"([<>^]?)(\d*)", self.spec)
        align, width = (m.group(1), m.group(2)) if m else ("", "")
        return f"{align or '>'}{width}"

    def title_text(self) -> str:
        return format(self.title, self._fit())

    def cell(self, row: Row) -> str:
        get = self.value
        value = get(row) if callable(get) else row[self.title if get is None else get]
        return format("-", self._fit()) if value is None else format(value, self.spec)


def text_table(columns: Sequence[Column], rows: Iterable[Row]) -> list[str]:
    """The lines of a fixed-width table: the titles, a rule as long, a line per row."""

    def line(texts: Iterable[str]) -> str:
        return "".join(c.gap + t for c, t in zip(columns, texts, strict=True))[
            len(columns[0].gap) :
        ]

    head = line(c.title_text() for c in columns)
    return [head, "-" * len(head), *(line(c.cell(r) for c in columns) for r in rows)]
