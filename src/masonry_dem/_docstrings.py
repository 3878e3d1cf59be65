"""Docstring text that several public names share, written once and filled in where it
belongs (as scipy's ``doccer`` does): a docstring line that holds only ``%(key)s`` becomes the
text of ``key``, each of its lines indented as the placeholder was. The filled docstring is
the one ``help()``, the doctests and the docs build read.

Shared text lives in a dict beside the names that use it (the geometry's parameters in
:mod:`masonry_dem.geometry.builders`, the loads' in :mod:`masonry_dem.model`); the text the
whole package shares, such as the sliding block of the Examples, is :data:`SHARED`.
"""

from __future__ import annotations

import inspect
import re
import textwrap
from collections.abc import Callable, Mapping
from typing import TypeVar

T = TypeVar("T")

_PLACEHOLDER = re.compile(r"(?P<indent>[ \t]*)%\((?P<key>\w+)\)s")


def filled(doc: str | None, docs: Mapping[str, str]) -> str | None:
    """``doc`` with each line that holds only ``%(key)s`` replaced by ``docs[key]`` (its
    lines indented as the placeholder); a key ``docs`` lacks is a KeyError."""
    if doc is None:  # python -OO strips docstrings
        return None
    lines: list[str] = []
    for line in doc.split("\n"):
        m = _PLACEHOLDER.fullmatch(line)
        if m is None:
            lines.append(line)
            continue
        text = textwrap.dedent(docs[m["key"]]).strip("\n")
        lines += [m["indent"] + part if part else "" for part in text.split("\n")]
    return "\n".join(lines)


def fill(*docs: Mapping[str, str]) -> Callable[[T], T]:
    """A decorator that fills the placeholders of a function's or class's docstring from
    ``docs`` (the later mappings win); a class's methods are filled too."""
    merged: dict[str, str] = {}
    for d in docs:
        merged.update(d)

    def decorate(obj: T) -> T:
        obj.__doc__ = filled(obj.__doc__, merged)
        if isinstance(obj, type):
            for member in vars(obj).values():
                method = getattr(member, "__func__", member)  # a classmethod's function
                if inspect.isfunction(method):
                    method.__doc__ = filled(method.__doc__, merged)
        return obj

    return decorate


#: text shared across the package
SHARED: dict[str, str] = {
    # the Raises of the settings, which check every field by its range
    "field_errors": """
        Raises
        ------
        ValueError
            If a field is out of its range, named.
    """,
    # the model of the Examples: a block on a rigid base, pushed sideways by a load
    # proportional to its weight; it slides at lambda = mu = 0.6
    "sliding_block": """
        >>> import masonry_dem as md
        >>> blocks, base = md.add_base(md.single_block(0.2, 0.2, 0.1, 18e3))  # 72 N
        >>> model = md.Model.build(
        ...     blocks,
        ...     md.InterfaceMaterial(kn=1e9, kt=4e8, friction=0.6),
        ...     supports=[md.Support([base])],
        ...     loads=[md.SelfWeight(), md.WeightProportional((1, 0, 0))],
        ... )
    """,
}
