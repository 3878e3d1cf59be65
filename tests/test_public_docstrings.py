"""Every public name (``masonry_dem.__all__``) has a numpydoc docstring: a one-line summary,
a Parameters section naming exactly the parameters of its signature, Returns where a function
returns something, and an Examples section whose doctest runs and holds (issue 42). The public
methods and properties of the public classes have a summary, and their Parameters and Returns.

The sections are read by a plain parser (a title underlined with dashes), so the check needs
nothing outside the test extra; the docs build (docs/api, numpydoc) renders the same text.
"""

from __future__ import annotations

import doctest
import enum
import inspect
import re
import types
from typing import Any

import pytest

import masonry_dem

SECTION = re.compile(r"^(?P<title>[A-Z][A-Za-z ]+)\n-+$", re.MULTILINE)
#: a parameter line of a Parameters section: ``name : type`` or ``name`` (several: ``a, b``)
PARAMETER = re.compile(r"^(?P<names>\*{0,2}[A-Za-z_]\w*(?:, \*{0,2}[A-Za-z_]\w*)*)(?: : .*)?$")


def sections(doc: str) -> dict[str, str]:
    """The docstring's sections by title (the text before the first one under ``""``)."""
    found = list(SECTION.finditer(doc))
    out = {"": doc[: found[0].start()] if found else doc}
    for k, m in enumerate(found):
        end = found[k + 1].start() if k + 1 < len(found) else len(doc)
        out[m["title"]] = doc[m.end() : end]
    return out


def documented_parameters(section: str) -> list[str]:
    """The names a Parameters section documents (its lines at the section's own indent)."""
    names = []
    for line in section.splitlines():
        if line and not line[0].isspace():
            m = PARAMETER.match(line)
            assert m, f"not a parameter line: {line!r}"
            names += [n.lstrip("*") for n in m["names"].split(", ")]
    return names


def signature_parameters(obj: Any) -> list[str] | None:
    """The parameters a caller passes (None: not a callable with a signature to document)."""
    if isinstance(obj, types.ModuleType) or (inspect.isclass(obj) and issubclass(obj, enum.Enum)):
        return None
    if getattr(obj, "_is_protocol", False):  # a Protocol is implemented, not constructed
        return None
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    return [n for n in sig.parameters if n not in ("self", "cls")]


def returns_something(obj: Any) -> bool:
    if inspect.isclass(obj) or isinstance(obj, types.ModuleType):
        return False
    annotation = inspect.signature(obj).return_annotation
    return annotation not in (None, "None", inspect.Signature.empty)


def check(name: str, obj: Any, *, examples: bool, sections_needed: bool = True) -> list[str]:
    """What the docstring of ``obj`` lacks (empty: nothing)."""
    doc = inspect.getdoc(obj)
    if not doc:
        return [f"{name}: no docstring"]
    problems = []
    parts = sections(doc)
    if not sections_needed:  # a property: its one-line summary says what it is
        summary = parts[""].strip().split("\n\n")[0]
        return [] if summary and "\n" not in summary else [f"{name}: the summary is not one line"]
    summary = parts[""].strip().split("\n\n")[0]
    if "\n" in summary or not summary:
        problems.append(f"{name}: the summary is not one line")
    unknown = set(parts) - {
        "",
        "Parameters",
        "Returns",
        "Yields",
        "Raises",
        "Warns",
        "See Also",
        "Notes",
        "References",
        "Examples",
        "Attributes",
        "Methods",
        "Other Parameters",
    }
    if unknown:
        problems.append(f"{name}: sections numpydoc does not know: {sorted(unknown)}")
    params = signature_parameters(obj)
    if params:
        if "Parameters" not in parts:
            problems.append(f"{name}: no Parameters section")
        else:
            documented = documented_parameters(parts["Parameters"])
            if documented != params:
                problems.append(
                    f"{name}: Parameters documents {documented}, the signature has {params}"
                )
    if returns_something(obj) and "Returns" not in parts:
        problems.append(f"{name}: no Returns section")
    if examples and ">>>" not in parts.get("Examples", ""):
        problems.append(f"{name}: no Examples section with a doctest")
    return problems


def public_members(cls: type) -> list[tuple[str, Any]]:
    """The public methods and properties a class defines itself (not those of its bases)."""
    members = []
    for key, value in vars(cls).items():
        if key.startswith("_"):
            continue
        if isinstance(value, (staticmethod, classmethod)):
            members.append((key, getattr(cls, key)))
        elif inspect.isfunction(value) or isinstance(value, property):
            members.append((key, value))
    return members


PUBLIC = sorted(masonry_dem.__all__)


@pytest.mark.parametrize("name", PUBLIC)
def test_public_name_has_numpydoc_docstring(name: str) -> None:
    obj = getattr(masonry_dem, name)
    problems = check(name, obj, examples=True)
    if inspect.isclass(obj) and not issubclass(obj, enum.Enum):
        for key, member in public_members(obj):
            target = member.fget if isinstance(member, property) else member
            if isinstance(member, property):
                problems += check(f"{name}.{key}", target, examples=False, sections_needed=False)
            else:
                problems += check(f"{name}.{key}", target, examples=False)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name", PUBLIC)
def test_public_examples_hold(name: str) -> None:
    """The Examples of each public name run as doctests (``# doctest: +SKIP`` marks the few
    that take more than a second)."""
    obj = getattr(masonry_dem, name)
    finder = doctest.DocTestFinder(recurse=False)
    tests = [t for t in finder.find(obj, name, globs={}) if t.examples]
    assert tests, f"{name}: no doctest"
    runner = doctest.DocTestRunner(
        optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE | doctest.FAIL_FAST
    )
    for test in tests:
        runner.run(test)
    assert not runner.failures, f"{name}: {runner.failures} example(s) failed (see above)"


def test_the_parser_finds_what_is_missing() -> None:
    """The check fails on a Google-style docstring (the style it replaced)."""

    def google(a: int, b: int = 0) -> int:
        """Add.

        Args:
            a: one.
            b: the other.
        """
        return a + b

    assert check("google", google, examples=True) == [
        "google: no Parameters section",
        "google: no Returns section",
        "google: no Examples section with a doctest",
    ]


def test_the_api_page_lists_every_public_name() -> None:
    """docs/api/reference.rst (the API page of the docs build) documents every public name."""
    from pathlib import Path

    page = (Path(__file__).parents[1] / "docs" / "api" / "reference.rst").read_text()
    listed = set(re.findall(r"^\.\. auto(?:function|class):: (\w+)$", page, re.MULTILINE))
    if "automodule:: masonry_dem.geometry.selectors" in page:
        listed.add("select")
    assert sorted(set(PUBLIC) - listed) == []
