"""Names a package imports on first use (PEP 562): the package's public names that would pull
in heavy dependencies, or its own modules too early, at import time."""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any


def lazy_names(package: str, modules: Mapping[str, str]) -> Callable[[str], Any]:
    """The module ``__getattr__`` of ``package`` that imports each name of ``modules`` (name ->
    the module that defines it, absolute or relative to ``package``) when it is first asked
    for, and keeps it in the package's namespace so the import happens once."""

    def __getattr__(name: str) -> Any:
        if name not in modules:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(modules[name], package), name)
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__
