"""Parameter sweeps of a case file on Dask: the spread of the collapse multiplier.

A sweep varies values of a case file by their path in it (``material.friction``,
``geometry.courses``, ``loads[1].direction``): on a grid (``0.5:0.9:9``, both ends included),
as a list (``0.5,0.6,0.8``), or drawn at random from a distribution with a seed
(``lognormal(1e9,0.3)``: median and standard deviation of the logarithm; ``normal(mean,sd)``;
``uniform(lo,hi)``). Grids of several paths are crossed; samples are drawn once and crossed
with the grid (every grid point sees the same draws). Every value is checked by the case
schema before anything runs, so a bad path or a value out of range is one error naming the
path, the value and the allowed range.

Each run is one task of a ``dask.distributed`` client: a ``LocalCluster`` of one process per
core by default, or any running scheduler by address, so the same sweep runs on a laptop or a
cluster (whose workers need the package and, with ``keep``, the output folder). The rows are
appended to ``sweep.csv`` as the runs complete, so an interrupted sweep keeps them and
``resume`` runs only the missing ones; ``sweep.parquet`` (pyarrow) holds the same table, and
PNGs plot lambda against each varied value and, for samples, its histogram and empirical CDF.
A run that fails is a row with its status and reason; it never stops the sweep.

Folder layout::

    sweep.json          the plan: case, varied paths and values, distributions, seed
    sweep.csv           one row per run, appended as runs complete
    sweep.parquet       the same rows, typed (written at the end, also after an interrupt)
    lambda_vs_<path>.png, lambda_histogram.png, lambda_cdf.png
    runs/run_NNNN/      a run's files (keep="summary": summary.json and pushover.csv;
                        keep="all": the whole results folder of ``masonry-dem run``)
"""

from __future__ import annotations

import copy
import csv
import itertools
import json
import logging
import math
import os
import re
import shutil
import socket
import threading
import time
import uuid
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from masonry_dem._validation import plain

if TYPE_CHECKING:
    from masonry_dem.model import Model
    from masonry_dem.results import History

log = logging.getLogger(__name__)

PLAN = "sweep.json"
TABLE_CSV = "sweep.csv"
TABLE_PARQUET = "sweep.parquet"
RUNS = "runs"
KEEP = ("none", "summary", "all")
#: the distributions of ``sample``: name -> the meaning of its two numbers
DISTRIBUTIONS = {
    "lognormal": ("median", "sigma_log"),
    "normal": ("mean", "sd"),
    "uniform": ("lo", "hi"),
}
#: the result columns of a row (after ``run`` and the varied paths), with their type
RESULT_COLUMNS: dict[str, type] = {
    "status": str,  # collapse | completed | failed (the analysis) | error (an exception)
    "reason": str,
    "lambda": float,  # collapse multiplier, or the final lambda of a completed run
    "lambda_upper": float,  # upper end of the collapse bracket
    "limit_analysis_bound": float,
    "limit_analysis_status": str,
    "steps": int,
    "mechanism_blocks": int,  # blocks moving >= 5 % of the largest translation of the mode
    "mechanism_cracks": int,  # joints moving >= 50 % of the largest: the cracks
    "mechanism_sliding_share": float,  # sliding / (sliding + opening) over the cracks
    "seconds": float,  # wall-clock time of the run on its worker
    "cpu_seconds": float,  # CPU time of the worker process meanwhile: seconds / cpu_seconds
    # above 1 is time spent waiting for a core (a loaded machine), not computing
    "worker": str,
    "folder": str,
}
#: a block "moves" in the collapse mode above this share of the largest translation, the
#: threshold below which the mechanism picture draws a joint as shut
MOVING = 0.05


# ---------------------------------------------------------------------------- the plan
@dataclass(frozen=True)
class Distribution:
    """A distribution of ``sample``: ``kind`` one of :data:`DISTRIBUTIONS`, two numbers."""

    kind: str
    a: float
    b: float

    @classmethod
    def parse(cls, text: str, path: str = "") -> Distribution:
        """``lognormal(1e9,0.3)``, ``normal(0.7,0.05)``, ``uniform(0.5,0.9)``."""
        m = re.fullmatch(r"\s*(\w+)\s*\(\s*([^,()]+)\s*,\s*([^,()]+)\s*\)\s*", text)
        where = f"sample {path}={text}" if path else f"sample {text!r}"
        forms = ", ".join(f"{k}({', '.join(v)})" for k, v in DISTRIBUTIONS.items())
        if not m or m.group(1) not in DISTRIBUTIONS:
            raise ValueError(f"{where}: must be one of {forms}")
        try:
            a, b = float(m.group(2)), float(m.group(3))
        except ValueError:
            raise ValueError(f"{where}: the two parameters must be numbers") from None
        return cls(m.group(1), a, b).checked(where)

    def checked(self, where: str) -> Distribution:
        names = DISTRIBUTIONS.get(self.kind)
        if names is None:
            raise ValueError(f"{where}: must be one of {', '.join(DISTRIBUTIONS)}")
        if not (math.isfinite(self.a) and math.isfinite(self.b)):
            raise ValueError(f"{where}: {names[0]} and {names[1]} must be finite")
        if self.kind == "lognormal" and not (self.a > 0 and self.b >= 0):
            raise ValueError(f"{where}: the median must be above 0 and sigma_log at least 0")
        if self.kind == "normal" and self.b < 0:
            raise ValueError(f"{where}: sd must be at least 0")
        if self.kind == "uniform" and self.b < self.a:
            raise ValueError(f"{where}: hi must be at least lo")
        return self

    def draw(self, rng: np.random.Generator, n: int) -> np.ndarray:
        if self.kind == "lognormal":
            return np.exp(rng.normal(math.log(self.a), self.b, n))
        if self.kind == "normal":
            return rng.normal(self.a, self.b, n)
        return rng.uniform(self.a, self.b, n)

    def text(self) -> str:
        return f"{self.kind}({plain(self.a)},{plain(self.b)})"

    def label(self) -> str:
        """For people: ``lognormal(median 1e+09, sigma_log 0.3)``."""
        a, b = DISTRIBUTIONS[self.kind]
        return f"{self.kind}({a} {self.a:.6g}, {b} {self.b:.6g})"


def parse_values(text: str, path: str = "") -> list[Any]:
    """The values of a grid ``lo:hi:n`` (n evenly spaced, both ends included) or of a list
    ``v1,v2,...`` (each a TOML value: a number, true/false, a [vector]; else text)."""
    where = f"vary {path}={text}" if path else f"vary {text!r}"
    if ":" in text and "," not in text and "[" not in text:
        parts = text.split(":")
        if len(parts) in (2, 3) and all(_is_number(p) for p in parts[:2]):
            lo, hi = float(parts[0]), float(parts[1])
            n = int(parts[2]) if len(parts) == 3 and parts[2].strip().isdigit() else 0
            if not (math.isfinite(lo) and math.isfinite(hi) and 1 <= n <= 10**6):
                raise ValueError(
                    f"{where}: a grid is lo:hi:n with finite numbers lo, hi and a whole "
                    "number n from 1 to 10^6"
                )
            return [float(x) for x in np.linspace(lo, hi, n)] if n > 1 else [lo]
    values = [_toml_value(token.strip()) for token in _split_top(text)]
    if not values or any(v == "" for v in values):
        raise ValueError(f"{where}: give a grid lo:hi:n or a list v1,v2,... with no empty item")
    return values


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _split_top(text: str) -> list[str]:
    """Split at the commas outside brackets: ``[0,0,1],[1,0,0]`` is two items."""
    items, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        depth += {"[": 1, "]": -1}.get(ch, 0)
        if ch == "," and depth == 0:
            items.append(text[start:k])
            start = k + 1
    items.append(text[start:])
    return items


def _toml_value(token: str) -> Any:
    from masonry_dem.cases.casefile import tomllib

    try:
        return tomllib.loads(f"v = {token}")["v"]
    except tomllib.TOMLDecodeError:
        return token  # text without quotes: a selector, a builder, a method


_KEY = re.compile(r"([A-Za-z_]\w*)?((?:\[\d+\])*)")


def path_keys(path: str) -> list[str | int]:
    """``loads[1].direction`` or ``loads.1.direction`` -> ['loads', 1, 'direction']."""
    keys: list[str | int] = []
    for part in path.strip().split("."):
        m = _KEY.fullmatch(part)
        if part.isdigit():
            keys.append(int(part))
        elif m and (m.group(1) or m.group(2)):
            if m.group(1):
                keys.append(m.group(1))
            keys.extend(int(i) for i in re.findall(r"\d+", m.group(2)))
        else:
            raise ValueError(
                f"parameter path {path!r}: must be table keys joined by dots, with list "
                "indices in brackets, e.g. material.friction or loads[1].direction"
            )
    return keys


def set_path(data: dict, path: str, value: Any) -> dict:
    """A deep copy of the case ``data`` with ``value`` at ``path`` (a missing table is made)."""
    out = copy.deepcopy(data)
    keys = path_keys(path)
    node: Any = out
    for depth, key in enumerate(keys):
        last = depth == len(keys) - 1
        where = ".".join(str(k) for k in keys[: depth + 1])
        if isinstance(key, int):
            if not isinstance(node, list) or key >= len(node):
                size = len(node) if isinstance(node, list) else 0
                raise ValueError(
                    f"parameter path {path!r}: {where} names no entry (the case has {size})"
                )
        elif not isinstance(node, dict):
            raise ValueError(f"parameter path {path!r}: {where} is inside a value, not a table")
        if last:
            node[key] = value
        else:
            if isinstance(node, dict) and key not in node:
                node[key] = [] if isinstance(keys[depth + 1], int) else {}
            node = node[key]
    return out


def get_path(data: dict, path: str) -> Any:
    node: Any = data
    for key in path_keys(path):
        try:
            node = node[key]
        except (KeyError, IndexError, TypeError):
            return None
    return node


def _typed(path: str, value: Any, current: Any) -> Any:
    """A plain Python value; a whole float where the case wants a whole number (a grid of
    courses) becomes an int, since the schema takes no 3.0 for 3."""
    from masonry_dem.cases.schema import RANGES

    if isinstance(value, np.generic):
        value = value.item()
    key = path_keys(path)[-1]
    rng = RANGES.get(key) if isinstance(key, str) else None
    wants_int = (rng is not None and rng.integer) or (
        isinstance(current, int) and not isinstance(current, bool)
    )
    if isinstance(value, float) and wants_int and value.is_integer():
        return int(value)
    return value


@dataclass(frozen=True)
class Plan:
    """What a sweep runs: the case, the varied paths and their values, the distributions of
    the sampled paths with their seed; :meth:`points` lists the runs in order."""

    case: dict
    source: str
    vary: dict[str, list[Any]] = field(default_factory=dict)
    sample: dict[str, Distribution] = field(default_factory=dict)
    samples: int = 0
    seed: int | None = None

    @property
    def paths(self) -> list[str]:
        return [*self.vary, *self.sample]

    def points(self) -> list[dict[str, Any]]:
        grid = [dict(zip(self.vary, combo, strict=True)) for combo in self._grid()]
        if not self.sample:
            return grid
        draws = self.draws()
        return [
            {**g, **{p: draws[p][k] for p in self.sample}}
            for g in grid
            for k in range(self.samples)
        ]

    def _grid(self) -> Iterator[tuple]:
        return itertools.product(*self.vary.values())

    def draws(self) -> dict[str, list[Any]]:
        rng = np.random.default_rng(self.seed)
        return {
            p: [_typed(p, x, get_path(self.case, p)) for x in d.draw(rng, self.samples)]
            for p, d in self.sample.items()
        }

    def case_of(self, point: Mapping[str, Any]) -> dict:
        data = self.case
        for path, value in point.items():
            data = set_path(data, path, value)
        return data

    def manifest(self) -> dict[str, Any]:
        return {
            "case": self.case,
            "source": self.source,
            "vary": self.vary,
            "sample": {p: d.text() for p, d in self.sample.items()},
            "samples": self.samples,
            "seed": self.seed,
        }


def make_plan(
    case: str | Path | Mapping[str, Any] | None,
    vary: Mapping[str, str | Sequence[Any]] | None = None,
    sample: Mapping[str, str | Distribution] | None = None,
    samples: int = 0,
    seed: int | None = None,
) -> Plan:
    """The plan of a sweep, every value checked by the case schema (CaseError, a ValueError,
    naming the path, the value and the allowed range)."""
    from masonry_dem.cases.casefile import _BUILDERS, read_case_data
    from masonry_dem.cases.schema import CaseError, check_case
    from masonry_dem.solvers.incremental import StaticSettings

    if isinstance(case, Mapping):
        data, source = copy.deepcopy(dict(case)), "<dict>"
    else:
        data, source = read_case_data(case)
    check_case(data, source, _BUILDERS, StaticSettings)
    grid: dict[str, list[Any]] = {}
    for path, spec in (vary or {}).items():
        path_keys(path)
        values = parse_values(spec, path) if isinstance(spec, str) else list(spec)
        if not values:
            raise ValueError(f"vary {path}: no values")
        grid[path] = [_typed(path, v, get_path(data, path)) for v in values]
    dists = {
        p: d if isinstance(d, Distribution) else Distribution.parse(str(d), p)
        for p, d in (sample or {}).items()
    }
    for path in dists:
        path_keys(path)
        if path in grid:
            raise ValueError(f"{path} is both varied and sampled; give it once")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 0:
        raise ValueError(f"samples = {plain(samples)}: must be a whole number >= 0")
    if samples and not dists:
        raise ValueError(f"samples = {samples} but no sampled parameter: give --sample PATH=DIST")
    if dists and samples < 1:
        raise ValueError("sample given but samples = 0: give the number of samples (--samples N)")
    if not grid and not dists:
        raise ValueError("nothing to sweep: give a parameter to vary or to sample")
    if dists and seed is None:  # recorded in sweep.json: a resumed sweep draws the same values
        seed = int(np.random.SeedSequence().entropy % 2**63)  # type: ignore[operator]
    plan = Plan(data, source, grid, dists, samples if dists else 0, seed)
    every: dict[str, list[Any]] = {**grid, **plan.draws()}
    for path, vals in every.items():
        for value in _distinct(vals):
            try:
                check_case(set_path(data, path, value), source, _BUILDERS, StaticSettings)
            except CaseError as exc:
                raise CaseError(f"sweep parameter {path} = {plain(value)}: {exc}") from None
    return plan


def _distinct(values: list[Any]) -> list[Any]:
    seen: dict[str, Any] = {}
    for v in values:
        seen.setdefault(json.dumps(v), v)
    return list(seen.values())


# ------------------------------------------------------------------------------- one run
def run_point(data: dict, source: str, keep: str = "none", folder: str | None = None) -> dict:
    """Run one case (a parsed case file) as ``masonry-dem run`` does: the associative
    limit-analysis bound, then the pushover (or the limit analysis alone for ``[analysis]
    method = "limit"``). Returns the result columns of its row (:data:`RESULT_COLUMNS`);
    anything the run raises is the row's status ``error`` with the reason, never raised."""
    t0, c0 = time.perf_counter(), time.process_time()
    row: dict[str, Any] = dict.fromkeys(RESULT_COLUMNS)
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    try:
        row.update(_run(data, source, keep, None if keep == "none" else folder))
    except Exception as exc:  # a failed run is a row: the sweep goes on
        text = " ".join(str(exc).split()) or type(exc).__name__
        row.update(status="error", reason=f"{type(exc).__name__}: {text}")
        log.info("run of %s raised %s", source, row["reason"])
    row["seconds"] = time.perf_counter() - t0
    row["cpu_seconds"] = time.process_time() - c0
    return row


def _run(data: dict, source: str, keep: str, folder: str | None) -> dict[str, Any]:
    from masonry_dem.cases.casefile import case_from_dict
    from masonry_dem.solvers.incremental import StaticSolver
    from masonry_dem.solvers.limit_analysis import limit_analysis

    case = case_from_dict(data, source)
    if case.method == "limit":
        la = limit_analysis(case.model, **(case.limit_options or {}))
        lam = la.load_factor if la.status == "collapse" else None
        if folder is not None:
            from masonry_dem.export import results_folder as rf

            Path(folder).mkdir(parents=True, exist_ok=True)
            rf.write_summary(folder, {"case": source, **la.summary()})
        return {
            "status": la.status,
            "reason": la.reason,
            "lambda": lam,
            "limit_analysis_bound": lam if la.bound == "upper" else None,
            "limit_analysis_status": la.status,
            "folder": folder,
        }
    la = limit_analysis(case.model, backend="clarabel")
    bound = la.load_factor if la.status == "collapse" else None
    extra: dict[str, Any] = {"limit_analysis_bound": bound, "limit_analysis_status": la.status}
    writer = None
    if keep == "all" and folder is not None:
        from masonry_dem.export.writer import ResultsWriter

        writer = ResultsWriter(folder, case.model, overwrite=True, start={"case": source})
    solver = StaticSolver(case.model, case.settings, bound=bound)
    with writer or nullcontext():
        history = solver.run(control=case.control, callback=writer, monitor=case.monitor)
    if writer is not None:
        writer.finish(history, case=source, **extra)
    elif folder is not None:  # keep = "summary"
        from masonry_dem.export import results_folder as rf

        Path(folder).mkdir(parents=True, exist_ok=True)
        rf.write_pushover(
            folder,
            np.arange(len(history.steps)),
            history.load_factors,
            history.control_displacements,
        )
        summary = history.summary(
            blocks=case.model.blocks.count, interfaces=case.model.interfaces.count
        )
        rf.write_summary(folder, {"name": case.model.name, "case": source, **summary}, extra)
    status = str(history.status)
    ended = status in ("collapse", "completed")
    bracket = history.collapse_bracket
    row: dict[str, Any] = {
        "status": status,
        "reason": history.reason,
        "lambda": history.summary()["lambda"] if ended else None,
        "lambda_upper": bracket[1] if bracket else None,
        "steps": len(history.steps),
        "folder": folder,
        **extra,
    }
    if status == "collapse":
        row.update(mechanism_summary(case.model, history))
    return row


def mechanism_summary(model: Model, history: History) -> dict[str, Any]:
    """The collapse mode in three numbers: the blocks that move (>= 5 % of the largest
    translation), the cracks (joints whose relative motion is >= 50 % of the largest, the
    red joints of the mechanism picture) and the share of sliding in the cracks' motion
    (1: they slide, 0: they open and turn)."""
    from masonry_dem.export.render import MECHANISM_BINS
    from masonry_dem.export.vtu import joint_relative_motion
    from masonry_dem.mechanism import collapse_mode, joint_motion

    try:
        mode = collapse_mode(model, history.last)
    except (ValueError, RuntimeError, ArithmeticError) as exc:
        log.info("%s: no collapse mode (%s)", model.name, exc)
        return {}
    moved = np.linalg.norm(mode[:, :3], axis=1)
    motion = joint_relative_motion(model, mode)
    peak = float(motion.max(initial=0.0))
    cracks = motion >= MECHANISM_BINS[-1] * peak if peak > 0 else np.zeros(motion.size, bool)
    jm = joint_motion(model, mode)
    slide = float(jm.sliding[cracks].sum())
    opening = float(np.maximum(jm.opening[cracks], 0.0).sum())
    return {
        "mechanism_blocks": int((moved >= MOVING * moved.max(initial=0.0)).sum())
        if moved.max(initial=0.0) > 0
        else 0,
        "mechanism_cracks": int(cracks.sum()),
        "mechanism_sliding_share": slide / (slide + opening) if slide + opening > 0 else None,
    }


# ------------------------------------------------------------------------------ the table
def columns_of(plan: Plan) -> list[str]:
    return ["run", *plan.paths, *RESULT_COLUMNS]


def _cell(value: Any) -> str:
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


class _Journal:
    """``sweep.csv``, one line per completed run, flushed at once: a killed sweep keeps
    every row it wrote."""

    def __init__(self, path: Path, columns: list[str], rows: list[dict]) -> None:
        self.columns = columns
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
        with tmp.open("w", newline="") as f:  # the rows kept, rewritten whole (no torn line)
            writer = csv.writer(f)
            writer.writerow(columns)
            writer.writerows([_cell(r.get(c)) for c in columns] for r in rows)
        os.replace(tmp, path)
        self._file = path.open("a", newline="")
        self._writer = csv.writer(self._file)

    def append(self, row: dict) -> None:
        self._writer.writerow([_cell(row.get(c)) for c in self.columns])
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def _read_rows(folder: Path, plan: Plan) -> dict[int, dict]:
    """The rows of ``sweep.csv`` that belong to ``plan``; a torn last line is dropped."""
    path = folder / TABLE_CSV
    if not path.is_file():
        return {}
    points = plan.points()
    columns = columns_of(plan)
    rows: dict[int, dict] = {}
    with path.open(newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header != columns:
            raise ValueError(
                f"{path}: its columns are not those of this sweep; use another folder or overwrite"
            )
        for cells in reader:
            if len(cells) != len(columns) or not cells[0].isdigit():
                continue
            run = int(cells[0])
            if run >= len(points):
                continue
            point = points[run]
            if [_cell(point[p]) for p in plan.paths] != cells[1 : 1 + len(plan.paths)]:
                raise ValueError(
                    f"{path}: run {run} was made with other values than this sweep's; use "
                    "another folder or overwrite"
                )
            results = cells[1 + len(plan.paths) :]
            typed = {
                c: _parse_cell(t, kind)
                for (c, kind), t in zip(RESULT_COLUMNS.items(), results, strict=True)
            }
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


def to_table(rows: list[dict], columns: list[str]) -> Any:
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
            values = [None if v is None else v if isinstance(v, str) else _cell(v) for v in values]
        elif typ == pa.float64():
            values = [None if v is None else float(v) for v in values]
        arrays.append(pa.array(values, type=typ))
        names.append(c)
    return pa.Table.from_arrays(arrays, names=names)


# ------------------------------------------------------------------------------ the sweep
@dataclass
class SweepResult:
    """What a sweep left in ``folder``: the rows (one per run, by run number), the table
    files, the plots, how many runs ran now and how many a resume found done."""

    folder: Path
    rows: list[dict]
    csv: Path
    parquet: Path
    plots: list[Path]
    ran: int
    resumed: int

    @property
    def lambdas(self) -> np.ndarray:
        """lambda of every run (nan where a run did not end in collapse or completion)."""
        return np.array([np.nan if r["lambda"] is None else r["lambda"] for r in self.rows])

    def table(self) -> Any:
        """The rows as a pyarrow Table (``.to_pandas()`` where pandas is installed)."""
        import pyarrow.parquet as pq

        return pq.read_table(self.parquet)


def sweep(
    case: str | Path | Mapping[str, Any] | None = None,
    vary: Mapping[str, str | Sequence[Any]] | None = None,
    sample: Mapping[str, str | Distribution] | None = None,
    samples: int = 0,
    seed: int | None = None,
    out: str | Path = "results/sweep",
    scheduler: Any = None,
    workers: int | None = None,
    keep: str = "none",
    resume: bool = False,
    overwrite: bool = False,
    plots: bool = True,
    progress: bool = False,
) -> SweepResult:
    """Run a case (a TOML path, a parsed case dict, or None: the bundled default wall) over
    varied values on Dask, writing one row per run to ``out``.

    vary: path -> values, or their text (``"0.5:0.9:9"`` a grid, ``"0.5,0.6,0.8"`` a list);
        several paths are crossed.
    sample, samples, seed: path -> distribution (``"lognormal(1e9,0.3)"``, ``normal(mean,sd)``,
        ``uniform(lo,hi)``), drawn ``samples`` times with ``seed`` (one is drawn and recorded
        in ``sweep.json`` when not given).
    scheduler: None for a LocalCluster of ``workers`` processes (default: the cores) with one
        thread each, an address (``"tcp://host:8786"``), or a ``distributed.Client``.
    keep: "none" (rows only), "summary" (each run's summary.json and pushover.csv) or "all"
        (each run's whole results folder, VTU/PVD) under ``out/runs/run_NNNN``.
    resume: run only the rows ``out`` does not hold yet (same plan, else refused);
        overwrite: replace a sweep in ``out`` (its own files only); without either, a folder
        that holds a sweep is refused.
    progress: show Dask's progress bar on stdout.
    """
    if keep not in KEEP:
        raise ValueError(f"keep = {plain(keep)}: must be one of {', '.join(KEEP)}")
    if workers is not None and (isinstance(workers, bool) or not 1 <= int(workers) <= 4096):
        raise ValueError(f"workers = {plain(workers)}: must be a whole number from 1 to 4096")
    folder = Path(out)
    if resume and sample and seed is None:  # the seed the sweep drew and recorded
        seed = _recorded(folder).get("seed")
    plan = make_plan(case, vary, sample, samples, seed)
    done = _prepare(folder, plan, resume, overwrite)
    points = plan.points()
    columns = columns_of(plan)
    rows: dict[int, dict] = dict(done)
    todo = [i for i in range(len(points)) if i not in done]
    log.info(
        "sweep of %d runs in %s: %d to run, %d done", len(points), folder, len(todo), len(done)
    )
    journal = _Journal(folder / TABLE_CSV, columns, [rows[i] for i in sorted(rows)])
    interrupted = True
    try:
        if todo:
            _compute(plan, points, todo, folder, keep, scheduler, workers, progress, rows, journal)
        interrupted = False
    finally:
        journal.close()
        ordered = [rows[i] for i in sorted(rows)]
        _write_parquet(folder / TABLE_PARQUET, ordered, columns)
        pngs = write_plots(folder, ordered, plan) if plots else []
        if interrupted:
            log.warning(
                "sweep in %s stopped after %d of %d runs; resume continues it",
                folder,
                len(rows),
                len(points),
            )
    return SweepResult(
        folder,
        ordered,
        folder / TABLE_CSV,
        folder / TABLE_PARQUET,
        pngs,
        ran=len(rows) - len(done),
        resumed=len(done),
    )


def _compute(
    plan: Plan,
    points: list[dict],
    todo: list[int],
    folder: Path,
    keep: str,
    scheduler: Any,
    workers: int | None,
    progress: bool,
    rows: dict[int, dict],
    journal: _Journal,
) -> None:
    from distributed import as_completed

    runs = (folder / RUNS).resolve()
    with _client(scheduler, workers) as client:
        log.info("dask scheduler %s, dashboard %s", client.scheduler.address, client.dashboard_link)
        tag = uuid.uuid4().hex[:8]
        futures = {
            client.submit(
                run_point,
                plan.case_of(points[i]),
                plan.source,
                keep,
                str(runs / f"run_{i:04d}"),
                key=f"masonry-run-{i}-{tag}",
            ): i
            for i in todo
        }
        if progress:
            _show_progress(list(futures))
        for future in as_completed(futures):
            i = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # the worker died, or the task could not run
                text = " ".join(str(exc).split()) or type(exc).__name__
                result = dict.fromkeys(RESULT_COLUMNS)
                result.update(status="error", reason=f"{type(exc).__name__}: {text}")
            rows[i] = {"run": i, **points[i], **result}
            journal.append(rows[i])
            future.release()


def _show_progress(futures: list) -> None:
    """Dask's own text progress bar, drawn by a thread while the rows are written."""
    from distributed import progress

    threading.Thread(
        target=progress, args=(futures,), kwargs={"notebook": False}, daemon=True
    ).start()


@contextmanager
def _client(scheduler: Any, workers: int | None) -> Iterator[Any]:
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - the optional extra is missing
        raise ModuleNotFoundError(
            'a sweep needs dask.distributed and pyarrow: pip install "masonry_dem[sweep]"'
        ) from exc
    if scheduler is not None and not isinstance(scheduler, str):
        yield scheduler  # a Client of the caller's: theirs to close
        return
    if isinstance(scheduler, str):
        with Client(scheduler) as client:
            yield client
        return
    n = int(workers or os.cpu_count() or 1)
    # one run per core: the kernels' own threads would only compete with the other workers
    env = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    with (
        LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            env=env,
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


def _prepare(folder: Path, plan: Plan, resume: bool, overwrite: bool) -> dict[int, dict]:
    """Claim ``folder`` for the sweep; returns the rows a resume keeps."""
    if resume and overwrite:
        raise ValueError("resume and overwrite exclude each other")
    manifest = plan.manifest()
    plan_file = folder / PLAN
    if plan_file.is_file() or (folder / TABLE_CSV).is_file():
        if resume:
            same = json.loads(json.dumps(manifest))
            before = _recorded(folder)
            if {k: before.get(k) for k in same if k != "source"} != {
                k: v for k, v in same.items() if k != "source"
            }:
                raise ValueError(
                    f"{folder} holds a sweep of another plan (case, values, distributions or "
                    "seed differ): resume needs the same; use another folder or overwrite"
                )
            return _read_rows(folder, plan)
        if not overwrite:
            raise ValueError(
                f"{folder} holds a sweep already: resume continues it, overwrite replaces it"
            )
        remove_own_files(folder)
    folder.mkdir(parents=True, exist_ok=True)
    tmp = plan_file.with_name(f".{PLAN}.{uuid.uuid4().hex}.tmp")
    tmp.write_text(json.dumps(manifest, indent=2))
    os.replace(tmp, plan_file)
    return {}


def _recorded(folder: Path) -> dict[str, Any]:
    """The plan a sweep in ``folder`` recorded ({} when there is none)."""
    try:
        data = json.loads((folder / PLAN).read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def remove_own_files(folder: Path) -> None:
    """Remove what a sweep writes in ``folder`` and nothing else."""
    for name in (PLAN, TABLE_CSV, TABLE_PARQUET):
        (folder / name).unlink(missing_ok=True)
    for png in folder.glob("lambda_*.png"):
        png.unlink()
    runs = folder / RUNS
    if runs.is_dir():
        for run in runs.iterdir():
            if run.is_dir() and re.fullmatch(r"run_\d+", run.name):
                shutil.rmtree(run)
        if not any(runs.iterdir()):
            runs.rmdir()


def _write_parquet(path: Path, rows: list[dict], columns: list[str]) -> None:
    import pyarrow.parquet as pq

    from masonry_dem.export.results_folder import write_atomic

    table = to_table(rows, columns)
    write_atomic(path, lambda tmp: pq.write_table(table, tmp))


# ----------------------------------------------------------------------------- the plots
LAMBDA_LABEL = "collapse multiplier $\\lambda$ [-] (live load / its nominal value)"


def axis_label(path: str) -> str:
    """``material.kn`` -> ``material.kn [N/m^3]``: the unit from the case schema."""
    from masonry_dem.cases.schema import RANGES

    key = path_keys(path)[-1]
    rng = RANGES.get(key) if isinstance(key, str) else None
    return f"{path} [{rng.unit if rng is not None and rng.unit else '-'}]"


def write_plots(folder: Path, rows: list[dict], plan: Plan) -> list[Path]:
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
        labels = None if numeric else sorted({_cell(r[path]) for r in rows})

        def x(rs: list[dict], path: str = path, labels: list | None = labels) -> list:
            return [r[path] if labels is None else labels.index(_cell(r[path])) for r in rs]

        if ok:
            ax.plot(x(ok), [r["lambda"] for r in ok], "o", color="C0", label="collapse")
        bounds = [r for r in rows if r["limit_analysis_bound"] is not None]
        if bounds:
            ax.plot(
                x(bounds),
                [r["limit_analysis_bound"] for r in bounds],
                "_",
                color="C2",
                ms=12,
                label="limit-analysis bound",
            )
        if done:
            ax.plot(
                x(done),
                [r["lambda"] for r in done],
                "^",
                mfc="none",
                color="C1",
                label="completed (no collapse up to)",
            )
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
        fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
        ax.hist(lam, bins="auto", color="C0", edgecolor="white")
        ax.set_xlabel(LAMBDA_LABEL)
        ax.set_ylabel("runs [-]")
        ax.set_title(f"{name}: {lam.size} collapses{excluded}\n{what}", fontsize=9)
        save(fig, "lambda_histogram.png")
        fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
        ax.step(lam, np.arange(1, lam.size + 1) / lam.size, where="post", color="C0")
        ax.set_xlabel(LAMBDA_LABEL)
        ax.set_ylabel("P(collapse at or below $\\lambda$) [-]")
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        ax.set_title(f"{name}: empirical CDF of {lam.size} collapses{excluded}\n{what}", fontsize=9)
        save(fig, "lambda_cdf.png")
    return out
