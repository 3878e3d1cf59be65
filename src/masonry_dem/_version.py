"""The package's version: the one of its source tree, and the installed one."""

from __future__ import annotations

__version__ = "0.1.0"


def version() -> str:
    """The installed package's version (its metadata: what pip installed)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as installed

    try:
        return installed("masonry_dem")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return f"{__version__} (not installed)"
