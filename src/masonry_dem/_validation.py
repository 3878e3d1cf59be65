"""Input checks that fail with a message naming the field and the offending value."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import field, fields
from numbers import Integral
from typing import Any, TypeVar

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


def finite_scalar(name: str, value: Any) -> float:
    """``value`` as a finite float (-0.0 made 0.0, see :func:`frozen`); a boolean, text or
    an array is refused by name."""
    if isinstance(value, (bool, np.bool_)):  # True would be read as 1.0
        raise ValueError(f"{name} must be a number, got the boolean {plain(value)}")
    if isinstance(value, (str, bytes)):  # numpy reads "1e9" as 1e9, but the caller keeps text
        raise ValueError(f"{name} must be a number, got the text {plain(value)}")
    arr = as_finite_array(name, value)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a scalar, got shape {arr.shape}")
    return float(arr) + 0.0


def positive_scalar(name: str, value: Any, strict: bool = True) -> float:
    number = finite_scalar(name, value)
    require_positive(name, np.asarray(number), strict)
    return number


def boolean(name: str, value: Any) -> bool:
    """``value`` as a boolean; text ("no", "false": both true in Python) and numbers are
    refused as the case files refuse them."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(
            f"{name} must be true or false (a boolean, without quotes), got {plain(value)}"
        )
    return bool(value)


def whole_number(name: str, value: Any, allowed: tuple[int, ...]) -> int:
    """``value`` as one of the integers ``allowed`` (a float, a boolean or text is refused)."""
    if not is_count(value, min(allowed)) or int(value) not in allowed:
        raise ValueError(
            f"{name} must be one of {', '.join(map(str, allowed))} (a whole number), "
            f"got {plain(value)}"
        )
    return int(value)


def frozen(value: Any, dtype: Any = None) -> NDArray[Any]:
    """A read-only copy of ``value``, a float array's signed zeros made +0.0: a -0.0 reaches
    copysign, 1/x and the sign tests of the kernels (friction -0.0 ended a pushover failed
    where 0.0 collapses), and a model changed after it was built answers another question."""
    arr = np.array(value, dtype=dtype)
    if arr.dtype.kind == "f":
        arr += 0.0
    arr.flags.writeable = False
    return arr


def read_only(arr: NDArray[Any]) -> NDArray[Any]:
    """A read-only view of ``arr`` (the array itself stays writable for its owner)."""
    view = arr.view()
    view.flags.writeable = False
    return view


def is_number(value: Any) -> bool:
    """An int or a float (a boolean is no number here)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_choice(name: str, value: object, allowed: tuple[str, ...]) -> None:
    """ValueError naming ``name``, ``value`` and the ``allowed`` values unless it is one."""
    if value not in allowed:
        raise ValueError(f"{name} must be one of {allowed}, got {value!r}")


# A settings field states its own range where it is declared, ``tolerance: float =
# positive(1e-8)``: the specifier returns a dataclasses.Field that carries the test and its
# words, type checkers see the default's type, and ``check_fields`` runs every test.
T = TypeVar("T")


def checked(default: T, test: Callable[[Any], bool], what: str) -> T:
    """A dataclass field of ``default`` whose value must pass ``test``; ``what`` says what it
    must be, after "NAME must be" in the error."""
    return field(default=default, metadata={"test": test, "what": what})


def check_fields(owner: Any) -> None:
    """ValueError naming the first checked field of the dataclass ``owner`` whose value fails
    its test, with the value."""
    for f in fields(owner):
        value = getattr(owner, f.name)
        if "test" in f.metadata and not f.metadata["test"](value):
            raise ValueError(f"{f.name} must be {f.metadata['what']}, got {value!r}")


def _finite(value: Any) -> bool:
    return is_number(value) and math.isfinite(value)


def positive(default: float) -> float:
    """A field that takes a finite number > 0."""
    return checked(default, lambda v: _finite(v) and v > 0, "a positive number")


def positive_or_none(default: float | None = None, *, finite: bool = False) -> float | None:
    """A field that takes a number > 0 (finite if ``finite``; inf: no limit), or None (the
    solver's own value)."""
    test = _finite if finite else is_number
    return checked(default, lambda v: v is None or (test(v) and v > 0), "a number > 0 or None")


def at_least(default: float, least: float, note: str = "") -> float:
    """A field that takes a finite number >= ``least``; ``note`` explains a special value."""
    return checked(default, lambda v: _finite(v) and v >= least, f"a number >= {least:g}{note}")


def finite(default: float) -> float:
    """A field that takes any finite number."""
    return checked(default, _finite, "a finite number")


def is_count(value: Any, least: int) -> bool:
    """Whether ``value`` is an integer >= ``least`` (numpy's too; a boolean or a float is not)."""
    return isinstance(value, Integral) and not isinstance(value, bool) and int(value) >= least


#: the largest value of a count field (an iteration budget, a window, a number of steps):
#: 10^8 iterations of the smallest wall take days, and a window or a history of that many
#: entries would not fit in memory
MOST_COUNT = 10**8
#: the finest grid of contact points of the limit analysis (grid x grid points on each
#: interface, each a column per friction direction): 8 is the non-associative default, and
#: 100 000 asked for 74.5 GiB before anything named it
GRID_MOST = 32


def count(default: int, least: int, most: int = MOST_COUNT) -> int:
    """A field that takes an integer from ``least`` to ``most`` (a boolean or a float is
    refused)."""
    return field(
        default=default,
        metadata={
            "test": lambda v: is_count(v, least) and int(v) <= most,
            "what": f"an integer from {least} to {most:.0e}".replace("e+0", "e"),
            "least": least,
            "most": most,
        },
    )


def choice(default: T, allowed: tuple[str, ...]) -> T:
    """A field that takes one of ``allowed`` (the values of its ``Literal`` type)."""
    return checked(default, lambda v: v in allowed, f"one of {allowed}")


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
