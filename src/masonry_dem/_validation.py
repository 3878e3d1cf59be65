"""Input checks that fail with a message naming the field and the offending value."""

from __future__ import annotations

import numpy as np


def as_finite_array(name: str, value, shape: tuple[int | None, ...] | None = None) -> np.ndarray:
    """Return ``value`` as a float array, rejecting NaN/inf and wrong shapes by name."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {value!r}") from exc
    if shape is not None:
        if arr.ndim != len(shape) or any(
            want is not None and got != want for got, want in zip(arr.shape, shape, strict=False)
        ):
            raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = np.argwhere(bad)[0]
        raise ValueError(
            f"{name} contains a non-finite value {arr[tuple(first)]!r} at {tuple(first)}"
        )
    return arr


def require_positive(name: str, arr: np.ndarray, strict: bool = True) -> None:
    bad = arr <= 0 if strict else arr < 0
    if np.any(bad):
        first = np.argwhere(np.atleast_1d(bad))[0]
        value = np.atleast_1d(arr)[tuple(first)]
        sign = "positive" if strict else "non-negative"
        raise ValueError(f"{name} must be {sign}, got {value!r} at {tuple(first)}")


def positive_scalar(name: str, value, strict: bool = True) -> float:
    arr = as_finite_array(name, value)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a scalar, got shape {arr.shape}")
    require_positive(name, arr, strict)
    return float(arr)
