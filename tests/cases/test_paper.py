"""The validation cases of Tables 1-3: built from the published data, not retyped.

Proves: the package's copy of the reference TOML equals the shared one; every case of the
three tables builds, with the paper's block counts, supports and load units; the first case
of Table 1 runs to a collapse with a refined bracket (the value it reaches is recorded, not
tuned: docs/validation.md explains why it is above the paper's FEM reference).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from masonry_dem.cases.paper import Assumptions, build_case, case_names, reference_data
from masonry_dem.solvers.incremental import pushover

SHARED = Path(__file__).resolve().parents[3] / "shared" / "reference" / "baraldi_cecchi_2016.toml"


def test_package_copy_equals_the_shared_reference():
    if not SHARED.is_file():
        pytest.skip("no ../shared/reference beside the repository")
    copy = resources.files("masonry_dem.cases").joinpath("data", "baraldi_cecchi_2016.toml")
    assert copy.read_text() == SHARED.read_text()


def test_every_case_of_the_three_tables_is_there():
    data = reference_data()
    expected = (
        [c["name"] for c in data["orduna_lourenco"]["case"]]
        + [c["name"] for c in data["restrepo_velez"]["specimen"]]
        + [c["name"] for c in data["chee_liang"]["wall"]]
    )
    assert case_names() == expected
    assert len(case_names("1")) == 2 and len(case_names("2")) == 10 and len(case_names("3")) == 6


@pytest.mark.parametrize("name", case_names())
def test_case_builds_from_the_published_data(name):
    case = build_case(name)
    model = case.model
    assert model.blocks.count > 10
    assert np.any(model.live) and np.any(model.dead)
    if case.table == "3":
        assert case.unit == "Pa"
        tests = reference_data()["chee_liang"]["wall"][case_names("3").index(name)]
        assert case.reference == pytest.approx(np.mean(tests["pressure_tests"]))
    else:
        assert case.unit == "lambda"


def test_restrepo_velez_walls_have_21_courses_of_n_blocks():
    for spec in reference_data()["restrepo_velez"]["specimen"][:7]:
        case = build_case(spec["name"])
        wall = case.model.blocks.subset(case.wall)
        length = wall.upper[:, 0].max() - wall.lower[:, 0].min()
        height = wall.upper[:, 1].max() - wall.lower[:, 1].min()
        data = reference_data()["restrepo_velez"]
        assert length == pytest.approx(spec["blocks_along_length"] * data["block_width_b"])
        assert height == pytest.approx(21 * data["block_height_a"])


def test_assumptions_are_overridable_in_one_place():
    base = build_case("2-3")
    heavier = build_case("2-3", brick_unit_weight=20e3)
    assert heavier.model.dead.sum() == pytest.approx(base.model.dead.sum() * 20 / 18)
    assert Assumptions().dry_kn == reference_data()["interface_spring_model"]["kn"]


def test_orduna_lourenco_panel_collapses_with_a_refined_bracket():
    case = build_case("OL1")
    h = pushover(case.model, case.settings, monitor=case.monitor)
    assert h.status == "collapse", h.reason
    lo, hi = h.collapse_bracket
    assert hi - lo <= 0.005 * lo * 1.0001
    # measured 0.2519; the paper's DEM gives 0.175, FEM 0.210, limit analysis 0.127
    assert 0.24 < lo < 0.26
