"""The build backend: setuptools', with numba, numpy and scipy in the build environment of a
wheel, where setup.py compiles the kernels into the package, and not in that of an editable
install (``pip install -e .``), which compiles nothing at build."""

from __future__ import annotations

from typing import Any

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F403

#: what the kernels' compilation at build needs (the package's own requirements of them)
KERNEL_BUILD_REQUIRES = ["numpy>=1.24", "numba>=0.59", "scipy>=1.10"]


def get_requires_for_build_wheel(config_settings: dict[str, Any] | None = None) -> list[str]:
    return [*_setuptools.get_requires_for_build_wheel(config_settings), *KERNEL_BUILD_REQUIRES]
