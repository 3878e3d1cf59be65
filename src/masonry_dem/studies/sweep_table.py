"""The table of a sweep: ``sweep.csv``, appended one row per run as runs complete (so an
interrupted sweep keeps them and a resume reads them back), and ``sweep.parquet``, the same rows
typed."""

from __future__ import annotations

import csv
import json
import os
import uuid
from pathlib import Path
from typing import Any

from masonry_dem.studies.sweep_plan import Plan
from masonry_dem.studies.sweep_point import RESULT_COLUMNS

TABLE_CSV = "sweep.csv"
TABLE_PARQUET = "sweep.parquet"


def columns_of(plan: Plan) -> list[str]:
    return ["run", *plan.paths, *RESULT_COLUMNS]


def cell(value: Any) -> str:
    """A CSV cell that reads back as written: floats by repr, None empty, vectors as JSON."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple, dict)):
        return json.dumps(value)
    return str(value)


def _parse_cell(text: str, kind: type) -> Any:
    if text == "":
        return None
    return kind(text) if kind in (int, float) else text


def write_rows(path: Path, columns: list[str], rows: list[dict[str, Any]]) -> None:
    """``sweep.csv`` holding ``rows``, rewritten whole under a temporary name (no torn line)."""
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    with tmp.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        writer.writerows([cell(r.get(c)) for c in columns] for r in rows)
    os.replace(tmp, path)


class Journal:
    """``sweep.csv``, one line per completed run in the order the runs end, flushed at
    once: a killed sweep keeps every row it wrote. The sweep rewrites it in run order when
    it ends (:func:`write_rows`)."""

    def __init__(self, path: Path, columns: list[str], rows: list[dict[str, Any]]) -> None:
        self.columns = columns
        write_rows(path, columns, rows)
        self._file = path.open("a", newline="")
        self._writer = csv.writer(self._file)

    def append(self, row: dict[str, Any]) -> None:
        self._writer.writerow([cell(row.get(c)) for c in self.columns])
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def read_rows(folder: Path, plan: Plan) -> dict[int, dict[str, Any]]:
    """The rows of ``sweep.csv`` that belong to ``plan``; a torn last line is dropped."""
    path = folder / TABLE_CSV
    if not path.is_file():
        return {}
    points = plan.points()
    columns = columns_of(plan)
    rows: dict[int, dict[str, Any]] = {}
    with path.open(newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        # a table of an older version lacks some result columns: read by name, the missing
        # ones empty
        head = len(plan.paths) + 1
        known = (
            header is not None
            and header[:head] == columns[:head]
            and set(header[head:]) <= set(RESULT_COLUMNS)
            and {"status", "lambda"} <= set(header[head:])
        )
        if not known:
            raise ValueError(
                f"{path}: its columns are not those of this sweep; use another folder or overwrite"
            )
        assert header is not None
        names = header[head:]
        for cells in reader:
            if len(cells) != len(header) or not cells[0].isdigit():
                continue
            run = int(cells[0])
            if run >= len(points):
                continue
            point = points[run]
            if [cell(point[p]) for p in plan.paths] != cells[1 : 1 + len(plan.paths)]:
                raise ValueError(
                    f"{path}: run {run} was made with other values than this sweep's; use "
                    "another folder or overwrite"
                )
            given = dict(zip(names, cells[head:], strict=True))
            typed = {c: _parse_cell(given.get(c, ""), kind) for c, kind in RESULT_COLUMNS.items()}
            rows[run] = {"run": run, **point, **typed}
    return rows


def _arrow_type(values: list[Any]) -> Any:
    import pyarrow as pa

    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return pa.bool_()
    if present and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        return pa.int64()
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return pa.float64()
    return pa.string()


def to_table(rows: list[dict[str, Any]], columns: list[str]) -> Any:
    """The rows as a typed pyarrow Table (vectors and mixed values as JSON text)."""
    import pyarrow as pa

    kinds = {"run": int, **RESULT_COLUMNS}
    arrays, names = [], []
    for c in columns:
        values = [r.get(c) for r in rows]
        if c in kinds:
            kind = kinds[c]
            typ = pa.int64() if kind is int else pa.float64() if kind is float else pa.string()
        else:
            typ = _arrow_type(values)
        if typ == pa.string():
            values = [None if v is None else v if isinstance(v, str) else cell(v) for v in values]
        elif typ == pa.float64():
            values = [None if v is None else float(v) for v in values]
        arrays.append(pa.array(values, type=typ))
        names.append(c)
    return pa.Table.from_arrays(arrays, names=names)


def write_parquet(path: Path, rows: list[dict[str, Any]], columns: list[str]) -> None:
    import pyarrow.parquet as pq

    from masonry_dem.export.results_folder import write_atomic

    table = to_table(rows, columns)
    write_atomic(path, lambda tmp: pq.write_table(table, tmp))
