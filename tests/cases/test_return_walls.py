"""The Restrepo Velez specimens with their return walls as blocks (``restraint="return-walls"``
of ``cases.paper``): what is built, the default length, bad readings named, the JSON row."""

from __future__ import annotations

import math

import numpy as np
import pytest

from masonry_dem.cases.paper import (
    RETURN_WALL_CASES,
    build_case,
    default_return_blocks,
    reference_data,
)
from masonry_dem.geometry import selectors as sel


def test_default_return_length_is_half_the_wall_height_in_whole_blocks():
    data = reference_data()["restrepo_velez"]
    height = data["courses"] * data["block_height_a"]
    m = default_return_blocks(data)
    assert m == math.ceil(height / (2 * data["block_width_b"])) == 4
    assert (m - 1) * data["block_width_b"] < height / 2 <= m * data["block_width_b"]


@pytest.mark.parametrize("name", RETURN_WALL_CASES)
def test_specimens_are_rebuilt_as_l_and_u_walls(name):
    case = build_case(name, restraint="return-walls", return_blocks=2)
    flat = build_case(name)
    blocks = case.model.blocks
    wall = blocks.subset(case.wall)
    both = (
        "both edges"
        in dict((s["name"], s["setup"]) for s in reference_data()["restrepo_velez"]["specimen"])[
            name
        ]
    )
    returns = ["return:left", "return:right"] if both else ["return:left"]
    for part in returns:
        ret = sel.part(wall, part)
        depth = wall.upper[:, 2].max() - wall.lower[ret, 2].min()
        assert depth == pytest.approx(2 * reference_data()["restrepo_velez"]["block_width_b"])
    # the facade measures what the flat specimen measures, only the base is held, every
    # block is tilted with the table
    facade = sel.part(wall, "facade")
    flat_wall = flat.model.blocks.subset(flat.wall)
    assert np.ptp(wall.lower[facade, 0].tolist() + wall.upper[facade, 0].tolist()) == (
        pytest.approx(np.ptp(flat_wall.lower[:, 0].tolist() + flat_wall.upper[:, 0].tolist()))
    )
    assert case.model.fixed[case.wall].sum() == 0 and case.model.fixed[-1].all()
    np.testing.assert_allclose(case.model.live[case.wall, 2], wall.weights)
    assert case.monitor[0] in facade
    assert case.extra["restraint"] == "return-walls" and case.extra["return_blocks"] == 2


def test_readings_that_do_not_exist_are_named():
    with pytest.raises(ValueError, match="restraint must be one of"):
        build_case("S11", restraint="return_walls")
    with pytest.raises(ValueError, match="S32 .* has no such reading"):
        build_case("S32", restraint="return-walls")
    with pytest.raises(ValueError, match="OL1 \\(Table 1\\) has no such reading"):
        build_case("OL1", restraint="return-walls")
    with pytest.raises(ValueError, match="return_blocks must be a whole number >= 2"):
        build_case("S11", restraint="return-walls", return_blocks=1)
