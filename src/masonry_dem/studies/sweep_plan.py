"""The plan of a parameter sweep: which case-file values vary, over which values.

A value is named by its path in the case file (``material.friction``, ``geometry.courses``,
``loads[1].direction``) and takes the values of a grid (``0.5:0.9:9``, both ends included), of a
list (``0.5,0.6,0.8``), or of a distribution drawn with a seed (``lognormal(1e9,0.3)``: median
and standard deviation of the logarithm; ``normal(mean,sd)``; ``uniform(lo,hi)``). Grids of
several paths are crossed; samples are drawn once and crossed with the grid (every grid point
sees the same draws). :func:`make_plan` checks every value by the case schema before anything
runs, so a bad path or a value out of range is one error naming the path, the value and the
allowed range.
"""

from __future__ import annotations

import copy
import functools
import itertools
import json
import logging
import math
import re
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem._validation import is_count, plain

log = logging.getLogger(__name__)

#: seconds between two progress lines of a long plan
PROGRESS_SECONDS = 2.0

#: the distributions of ``sample``: name -> the meaning of its two numbers
DISTRIBUTIONS = {
    "lognormal": ("median", "sigma_log"),
    "normal": ("mean", "sd"),
    "uniform": ("lo", "hi"),
}


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
            # 15 digits: 0.85, not linspace's 0.8500000000000001, in the table and the case
            return [float(f"{x:.15g}") for x in np.linspace(lo, hi, n)] if n > 1 else [lo]
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
    from masonry_dem._toml import tomllib

    try:
        return tomllib.loads(f"v = {token}")["v"]
    except tomllib.TOMLDecodeError:
        return token  # text without quotes: a selector, a builder, a method


_KEY = re.compile(r"([A-Za-z_]\w*)?((?:\[\d+\])*)")


def path_keys(path: str) -> list[str | int]:
    """``loads[1].direction`` or ``loads.1.direction`` -> ['loads', 1, 'direction']."""
    return list(_keys(path))


@functools.lru_cache(maxsize=256)
def _keys(path: str) -> tuple[str | int, ...]:
    # parsed once per path: a plan of 10^6 values asks for the same few paths each time
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
    return tuple(keys)


def set_path(data: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """A deep copy of the case ``data`` with ``value`` at ``path`` (a missing table is made)."""
    return _put(copy.deepcopy(data), path, value, copy_path=False)


def _with_value(data: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """``data`` with ``value`` at ``path``, copying only the tables and lists on the path:
    the rest is shared with ``data``, to be read (checked), never changed."""
    return _put(data, path, value, copy_path=True)


def _put(data: dict[str, Any], path: str, value: Any, copy_path: bool) -> dict[str, Any]:
    keys = _keys(path)
    out: Any = dict(data) if copy_path else data
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
            elif copy_path and isinstance(node[key], (dict, list)):
                node[key] = type(node[key])(node[key])
            node = node[key]
    result: dict[str, Any] = out
    return result


def get_path(data: dict[str, Any], path: str) -> Any:
    node: Any = data
    for key in _keys(path):
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
    key = _keys(path)[-1]
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

    case: dict[str, Any]
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

    def _grid(self) -> Iterator[tuple[Any, ...]]:
        return itertools.product(*self.vary.values())

    def draws(self) -> dict[str, list[Any]]:
        rng = np.random.default_rng(self.seed)
        return {
            p: [_typed(p, x, get_path(self.case, p)) for x in d.draw(rng, self.samples)]
            for p, d in self.sample.items()
        }

    def case_of(self, point: Mapping[str, Any]) -> dict[str, Any]:
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
    from masonry_dem.cases.casefile import check_case_data, read_case_data
    from masonry_dem.cases.schema import CaseError

    if isinstance(case, Mapping):
        data, source = copy.deepcopy(dict(case)), "<dict>"
    else:
        data, source = read_case_data(case)
    check_case_data(data, source)
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
    if seed is not None and not (is_count(seed, 0) and int(seed) < 2**63):
        raise ValueError(
            f"seed (--seed) must be a whole number from 0 to 2^63 - 1, got {plain(seed)}"
        )
    if dists and seed is None:  # recorded in sweep.json: a resumed sweep draws the same values
        seed = int(np.random.SeedSequence().entropy % 2**63)  # type: ignore[operator]
    plan = Plan(data, source, grid, dists, samples if dists else 0, seed)
    every = {path: _distinct(vals) for path, vals in {**grid, **plan.draws()}.items()}
    total = sum(len(vals) for vals in every.values())
    progress = _Progress(total)
    for path, vals in every.items():
        for value in vals:
            try:
                check_case_data(_with_value(data, path, value), source)
            except CaseError as exc:
                raise CaseError(f"sweep parameter {path} = {plain(value)}: {exc}") from None
            progress.step()
    return plan


class _Progress:
    """Logs how far the checks of a long plan are and how long they will still take, every
    :data:`PROGRESS_SECONDS`."""

    def __init__(self, total: int) -> None:
        self.total, self.done = total, 0
        self.start = self.last = time.monotonic()

    def step(self) -> None:
        self.done += 1
        now = time.monotonic()
        if now - self.last < PROGRESS_SECONDS:
            return
        self.last = now
        left = (now - self.start) / self.done * (self.total - self.done)
        log.info(
            "planning the sweep: checked %d of %d values, about %.0f s left",
            self.done,
            self.total,
            left,
        )


def _distinct(values: list[Any]) -> list[Any]:
    seen: dict[str, Any] = {}
    for v in values:
        seen.setdefault(json.dumps(v), v)
    return list(seen.values())
