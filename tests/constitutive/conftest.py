"""Shared fixtures of the constitutive tests: the paper's reference numbers, read from TOML."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from masonry_dem._toml import tomllib

_NAME = "baraldi_cecchi_2016.toml"


def _reference_path() -> Path:
    env = os.environ.get("MASONRY_DEM_REFERENCE")
    if env:
        return Path(env)
    for parent in Path(__file__).resolve().parents:
        candidate = parent / "shared" / "reference" / _NAME
        if candidate.is_file():
            return candidate
    # a checkout without ../shared: the package's copy, which tests/cases/test_paper.py
    # checks is identical to the shared file wherever both exist
    bundled = Path(__file__).resolve().parents[2] / "src" / "masonry_dem" / "cases" / "data" / _NAME
    if bundled.is_file():
        return bundled
    raise FileNotFoundError(
        f"{_NAME} not found in any shared/reference/ above the tests nor in the package; "
        "set MASONRY_DEM_REFERENCE to its path"
    )


@pytest.fixture(scope="session")
def reference() -> dict:
    """The whole reference TOML."""
    with _reference_path().open("rb") as fh:
        return tomllib.load(fh)


@pytest.fixture(scope="session")
def ref_interface(reference: dict) -> dict:
    """Section 2.1 reference interface (l1 = b, l2 = s)."""
    return reference["interface_spring_model"]


@pytest.fixture(scope="session")
def table_a1(reference: dict) -> dict:
    return reference["table_A1"]


@pytest.fixture(scope="session")
def alpha_columns(table_a1: dict) -> dict[str, list[float]]:
    """Table A1 columns keyed by the package's shear-direction names."""
    keys = {"f1": "alpha_shear_f1", "f2": "alpha_shear_f2", "f1=f2": "alpha_shear_f1_eq_f2"}
    return {direction: table_a1[key] for direction, key in keys.items()}
