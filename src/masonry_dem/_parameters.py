"""Functions declared by their parameters: a frozen dataclass of the parameters, called to
compute the result. Parameters that several functions share (a builder's unit, a strength
run's interface) are then declared once, in a base class, and :func:`function_of` makes the
public function, with the class's signature (for help(), type checkers and the case-file
schema) and docstring.

Dataclass fields come base by base from the last base named: ``C(Unit, Courses)`` takes the
fields of ``Courses``, then those of ``Unit``, then its own (keyword-only ones last).
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable
from typing import ParamSpec, Protocol, TypeVar

P = ParamSpec("P")
T = TypeVar("T")
T_co = TypeVar("T_co", covariant=True)


class Computation(Protocol[T_co]):
    def __call__(self) -> T_co: ...


def function_of(parameters: Callable[P, Computation[T]]) -> Callable[P, T]:
    """The function of a parameter class: its signature (returning what its call returns)
    and docstring, named as the class in snake case (``_RunningBondWall``:
    ``running_bond_wall``)."""

    # the class's own __call__ (what an instance returns), not the class's constructor
    returns = inspect.signature(inspect.getattr_static(parameters, "__call__")).return_annotation
    signature = inspect.signature(parameters).replace(return_annotation=returns)
    name = re.sub(r"(?<=.)(?=[A-Z])", "_", parameters.__name__.lstrip("_")).lower()

    def function(*args: P.args, **kwargs: P.kwargs) -> T:
        try:  # a wrong call named as the function, not as the private class
            signature.bind(*args, **kwargs)
        except TypeError as exc:
            raise TypeError(f"{name}(): {exc}") from None
        return parameters(*args, **kwargs)()

    for attribute, value in (
        ("parameter_class", parameters),  # what the class declares of its result (SLABS)
        ("__signature__", signature),
        ("__name__", name),
        ("__qualname__", name),
        ("__doc__", parameters.__doc__),
        ("__module__", parameters.__module__),
    ):
        setattr(function, attribute, value)
    return function
