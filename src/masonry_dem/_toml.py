"""The TOML reader: the standard library's ``tomllib`` from Python 3.11, its backport
``tomli`` on 3.10 (a dependency there, see pyproject.toml). Every module that parses TOML
imports it from here."""

from __future__ import annotations

import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["tomllib"]
