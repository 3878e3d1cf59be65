"""The shared docstring text (masonry_dem._docstrings, issue 42): a placeholder line becomes
the text it names, indented as it stood, and no public docstring keeps a placeholder."""

from __future__ import annotations

import inspect

import pytest

import masonry_dem
from masonry_dem._docstrings import fill, filled


def test_a_placeholder_line_becomes_its_text_indented_as_it_stood() -> None:
    docs = {"x": "\n    x : int\n        The x.\n"}
    assert filled("Sum.\n\n    Parameters\n    ----------\n    %(x)s\n    ", docs) == (
        "Sum.\n\n    Parameters\n    ----------\n    x : int\n        The x.\n    "
    )
    # only a line that holds nothing else is a placeholder
    assert filled("a %(x)s b", docs) == "a %(x)s b"
    assert filled(None, docs) is None  # python -OO
    with pytest.raises(KeyError):
        filled("    %(y)s", docs)


def test_fill_fills_a_class_and_its_methods() -> None:
    @fill({"summary": "The answer."})
    class C:
        """%(summary)s"""

        def f(self) -> int:
            """%(summary)s"""
            return 42

        @classmethod
        def g(cls) -> int:
            """%(summary)s"""
            return 42

    assert C.__doc__ == C.f.__doc__ == C.g.__doc__ == "The answer."


def _docstrings() -> list[tuple[str, str]]:
    out = []
    for name in masonry_dem.__all__:
        obj = getattr(masonry_dem, name)
        out.append((name, inspect.getdoc(obj) or ""))
        if inspect.isclass(obj) or inspect.ismodule(obj):  # md.select is a module
            for key, member in vars(obj).items():
                target = getattr(member, "__func__", getattr(member, "fget", member))
                if callable(target) and target.__doc__:
                    out.append((f"{name}.{key}", target.__doc__))
    return out


def test_no_public_docstring_keeps_a_placeholder() -> None:
    kept = [name for name, doc in _docstrings() if "%(" in doc]
    assert kept == []
