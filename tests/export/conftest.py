"""Fixtures: results folders with a known damage pattern (see damage_pattern.py)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from helpers.damage_pattern import build_model, write_results
from masonry_dem.model import Model


@pytest.fixture(scope="session")
def model() -> Model:
    return build_model()


@pytest.fixture(scope="session")
def results(tmp_path_factory, model) -> Path:
    """A complete results folder, 5 steps; do not write into it (use results_copy)."""
    folder = tmp_path_factory.mktemp("results") / "wall"
    write_results(folder, model)
    return folder


@pytest.fixture
def results_copy(tmp_path, results) -> Path:
    dst = tmp_path / "wall"
    shutil.copytree(results, dst)
    return dst
