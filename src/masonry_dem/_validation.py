"""Input checks that fail with a message naming the field and the offending value."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray


def as_finite_array(
    name: str, value: Any, shape: tuple[int | None, ...] | None = None
) -> NDArray[np.float64]:
    """Return ``value`` as a float array, rejecting NaN/inf and wrong shapes by name."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {plain(value)}") from exc
    if shape is not None:
        if arr.ndim != len(shape) or any(
            want is not None and got != want for got, want in zip(arr.shape, shape, strict=False)
        ):
            raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f" at index {', '.join(map(str, first))}" if first else ""
        raise ValueError(f"{name} contains a non-finite value {plain(arr[first])}{where}")
    return arr


def require_positive(name: str, arr: NDArray[np.float64], strict: bool = True) -> None:
    bad = arr <= 0 if strict else arr < 0
    if np.any(bad):
        first = tuple(int(i) for i in np.argwhere(np.atleast_1d(bad))[0])
        value = np.atleast_1d(arr)[first]
        sign = "positive" if strict else "non-negative"
        where = f" at index {', '.join(map(str, first))}" if np.ndim(arr) else ""
        raise ValueError(f"{name} must be {sign}, got {plain(value)}{where}")


def positive_scalar(name: str, value: Any, strict: bool = True) -> float:
    if isinstance(value, (bool, np.bool_)):  # True would be read as 1.0
        raise ValueError(f"{name} must be a number, got the boolean {plain(value)}")
    arr = as_finite_array(name, value)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a scalar, got shape {arr.shape}")
    require_positive(name, arr, strict)
    return float(arr)


def _number(value: Any) -> bool:
    """An int or a float (a boolean is no number here)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_positive_fields(owner: Any, names: Iterable[str]) -> None:
    """ValueError naming the first field of ``owner`` among ``names`` that is not a finite
    number > 0."""
    for name in names:
        value = getattr(owner, name)
        if not (_number(value) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value!r}")


def check_count_fields(owner: Any, least: Mapping[str, int]) -> None:
    """ValueError naming the first field of ``owner`` that is not an integer at least
    ``least[name]``."""
    for name, low in least.items():
        value = getattr(owner, name)
        if not isinstance(value, int) or isinstance(value, bool) or value < low:
            raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")


def check_load_path_fields(owner: Any) -> None:
    """The fields of the load path that the static and the dynamic-relaxation settings share,
    each refused by name: the step sizes and the bracket width (positive numbers),
    ``max_steps`` (an integer >= 1), ``growth`` (a finite number >= 1), ``max_load_factor``
    (a number > 0, inf: no cap) and ``displacement_limit`` (a number > 0, or None: the
    solver's own)."""
    check_positive_fields(owner, ("initial_step", "max_step", "bracket_tolerance"))
    check_count_fields(owner, {"max_steps": 1})
    growth = owner.growth
    if not (_number(growth) and math.isfinite(growth) and growth >= 1):
        raise ValueError(f"growth must be a number >= 1, got {growth!r}")
    cap = owner.max_load_factor
    if not (_number(cap) and cap > 0):  # NaN fails this too
        raise ValueError(f"max_load_factor must be a number > 0 (inf: no cap), got {cap!r}")
    limit = owner.displacement_limit
    if limit is not None and not (_number(limit) and limit > 0):
        raise ValueError(f"displacement_limit must be a number > 0 or None, got {limit!r}")


def plain(value: Any) -> str:
    """``value`` as a user wrote it: plain numbers (no numpy reprs), TOML's true/false."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        text = repr(float(value))
        if "e" in text:  # 1e+300 -> 1e300, 1e-05 -> 1e-5 (TOML reads both)
            mantissa, exponent = text.split("e")
            text = f"{mantissa.removesuffix('.0')}e{int(exponent)}"
        return text
    if isinstance(value, str):
        return '"' + value + '"' if len(value) <= 60 else '"' + value[:57] + '..."'
    if isinstance(value, dict):
        return (
            "a table {"
            + ", ".join(f"{k} = {plain(v)}" for k, v in list(value.items())[:4])
            + (", ...}" if len(value) > 4 else "}")
        )
    if isinstance(value, (list, tuple, np.ndarray)):
        items = list(value)
        text = ", ".join(plain(v) for v in items[:8])
        return "[" + text + (", ..." if len(items) > 8 else "") + "]"
    return repr(value)


def block_indices(name: str, value: Any, count: int | None = None) -> NDArray[np.int64]:
    """``value`` as an array of block indices, refusing what cannot be read plainly as one:
    a boolean mask (``np.asarray(mask, int64)`` would select blocks 0 and 1), fractional or
    non-finite numbers, text; with ``count``, indices outside 0..count-1 too."""
    arr = np.atleast_1d(np.asarray(value))
    if arr.dtype == bool:
        raise ValueError(
            f"{name}: got a boolean mask of {arr.size} values where block indices are expected; "
            "pass np.flatnonzero(mask)"
        )
    if arr.ndim != 1:
        raise ValueError(f"{name}: block indices must be a flat list, got shape {arr.shape}")
    if arr.dtype.kind in "iu":
        idx = arr.astype(np.int64)
    elif arr.dtype.kind == "f":
        whole = np.isfinite(arr) & (arr == np.round(arr))
        if not whole.all():
            bad = arr[np.argmin(whole)]
            raise ValueError(
                f"{name}: block indices must be whole numbers, got {plain(bad)} "
                f"(in {plain(arr.tolist())})"
            )
        idx = arr.astype(np.int64)
    else:
        raise ValueError(f"{name}: block indices must be integers, got {plain(arr.tolist())}")
    if count is not None and idx.size and (idx.min() < 0 or idx.max() >= count):
        bad = idx[(idx < 0) | (idx >= count)][0]
        raise ValueError(f"{name}: block index {int(bad)} is out of range 0..{count - 1}")
    return idx
