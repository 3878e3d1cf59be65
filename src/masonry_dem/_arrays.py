"""The array types of the package's annotations (float64, index and boolean arrays of any
shape; the docstring that uses one gives its shape), and :class:`Rows`, the base of the
dataclasses whose fields are arrays with one row per item."""

from __future__ import annotations

from dataclasses import Field, fields, replace
from typing import Any, ClassVar, TypeAlias, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray: TypeAlias = NDArray[np.float64]
IndexArray: TypeAlias = NDArray[np.intp]
BoolArray: TypeAlias = NDArray[np.bool_]

R = TypeVar("R", bound="Rows")


class Rows:
    """A dataclass whose every field is an array with one row per item (a block, an
    interface): the number of items, and the items at an index, field by field."""

    __dataclass_fields__: ClassVar[dict[str, Field[Any]]]

    @property
    def count(self) -> int:
        first = next(iter(self.__dataclass_fields__))
        return int(getattr(self, first).shape[0])

    def __len__(self) -> int:
        return self.count

    def subset(self: R, index: ArrayLike | slice) -> R:
        """The items at ``index`` (indices, a boolean mask or a slice), checked as new ones."""
        idx = index if isinstance(index, slice) else np.asarray(index)
        return replace(self, **{f.name: getattr(self, f.name)[idx] for f in fields(self)})
