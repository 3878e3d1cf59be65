"""Issue 39: the Python API is as strict as the case files. A built model cannot be changed
behind its back, signed zeros are one zero, and what the schema refuses the API refuses
with the field, the value and the allowed range."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.results import StepResult

MAT = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)


@pytest.fixture(scope="module")
def wall():
    return add_base(running_bond_wall(3, 2, 0.1, 0.25, 0.12, 18_000.0))[0]


def _build(blocks, material=MAT, **kwargs):
    kwargs.setdefault("supports", [Support([blocks.count - 1])])
    kwargs.setdefault("loads", [SelfWeight(), WeightProportional()])
    return Model.build(blocks, material, **kwargs)


def test_signed_zeros_are_one_zero_in_the_api_and_the_case_files(wall):
    material = InterfaceMaterial(kn=2.4e9, kt=1e9, friction=-0.0, tensile_strength=-0.0)
    assert not np.signbit(material.friction) and not np.signbit(material.tensile_strength)
    model = _build(wall, material, loads=[SelfWeight(), WeightProportional((-0.0, 0.0, 1.0))])
    for name in ("friction", "tensile_strength", "live", "dead"):
        values = getattr(model, name)
        assert not np.signbit(values[values == 0]).any(), name
    data = {**SINGLE_BLOCK, "material": {**SINGLE_BLOCK["material"], "friction": -0.0}}
    assert not np.signbit(case_from_dict(data).model.friction).any()


def test_a_built_model_and_its_steps_are_read_only(wall):
    model = _build(wall)
    for name in ("kn", "kt", "friction", "tensile_strength", "alpha", "fixed", "dead", "live"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(model, name)[...] = 0
    for name in ("block_i", "centre", "l1"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(model.interfaces, name)[0] = 0
    with pytest.raises(ValueError, match="read-only"):
        model.blocks.centres[0, 0] = 1.0
    q = np.zeros((wall.count, 6))
    step = StepResult(0, 0.0, q, q[:0], np.zeros(0, np.int32), np.zeros(0))
    with pytest.raises(ValueError, match="read-only"):
        step.q[0, 0] = 1.0
    q[0, 0] = 1.0  # the solver's own array stays its own


@pytest.mark.parametrize("tiny", [1e-170, 1e-300, 5e-324])
def test_a_direction_whose_norm_underflows_is_still_a_direction(wall, tiny):
    model = _build(wall, loads=[SelfWeight(), WeightProportional((tiny, 0.0, tiny))])
    pushed = model.live[:, :3][model.live[:, :3].any(axis=1)]
    np.testing.assert_allclose(pushed[:, 0], pushed[:, 2])
    weights = wall.weights[model.live[:, :3].any(axis=1)]
    np.testing.assert_allclose(np.linalg.norm(pushed, axis=1), weights, rtol=1e-12)
    huge = _build(wall, loads=[SelfWeight(), WeightProportional((1e300, 0.0, 1e300))])
    np.testing.assert_allclose(huge.live, model.live, rtol=1e-12)


def test_a_case_file_direction_whose_norm_underflows_is_accepted():
    data = {
        **SINGLE_BLOCK,
        "loads": [
            {"type": "self_weight"},
            {"type": "weight_proportional", "direction": [1e-170, 0.0, 1e-170]},
        ],
    }
    live = case_from_dict(data).model.live
    np.testing.assert_allclose(live[0, 0], live[0, 2])
    assert live[0, 0] > 0


def test_every_whole_number_of_the_case_files_has_a_range():
    from typing import get_args

    from masonry_dem.cases import schema
    from masonry_dem.cases.casefile import _BUILDERS
    from masonry_dem.solvers.incremental import StaticSettings

    tables = [schema._analysis_table(StaticSettings)]
    tables += [schema._geometry_table(name, func) for name, func in _BUILDERS.items()]
    unbounded = []
    for table in tables:
        for key, info in table.model_fields.items():
            kinds = [info.annotation, *get_args(info.annotation)]
            if int not in kinds and not any(int in get_args(k) for k in kinds):
                continue
            checks = [m for m in info.metadata if hasattr(m, "func")]
            checks += [m for k in kinds for m in getattr(k, "__metadata__", ())]
            ranged = key in schema.RANGES or any(
                "Range.check" in getattr(getattr(c, "func", None), "__qualname__", "")
                for c in checks
            )
            if not ranged:
                unbounded.append(f"{table.__name__}.{key}")
    assert not unbounded


def test_api_counts_have_the_case_files_ranges():
    from masonry_dem import StaticSettings, u_wall

    with pytest.raises(ValueError, match=r"return_blocks must be a whole number from 1 to 10000"):
        u_wall(6, 3, 0.1, 0.25, 0.12, 18e3, return_blocks=100_000_000)
    with pytest.raises(ValueError, match=r"max_cuts must be an integer from 0 to 1e8"):
        StaticSettings(max_cuts=10**9)
    from masonry_dem.solvers.limit_analysis.interface import lobatto_rule

    with pytest.raises(ValueError, match=r"grid must be a whole number from 2 to 32"):
        lobatto_rule(100_000)
