"""Issue 39: the Python API is as strict as the case files. A built model cannot be changed
behind its back, signed zeros are one zero, and what the schema refuses the API refuses
with the field, the value and the allowed range."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    Pressure,
    SelfWeight,
    Support,
    WeightProportional,
)
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
    with pytest.raises(ValueError, match=r"easy_iterations must be an integer from 0 to 1e8"):
        StaticSettings(easy_iterations=10**9)
    from masonry_dem.solvers.limit_analysis.interface import lobatto_rule

    with pytest.raises(ValueError, match=r"grid must be a whole number from 2 to 32"):
        lobatto_rule(100_000)


@pytest.mark.parametrize(
    "load, field",
    [
        (lambda: SelfWeight(live="no"), "SelfWeight.live"),
        (lambda: WeightProportional(live="false"), "WeightProportional.live"),
        (lambda: Pressure("1000"), "pressure"),
        (lambda: Pressure(1000.0, axis=2.0), "pressure axis"),
        (lambda: Pressure(1000.0, sign=True), "pressure sign"),
        (lambda: PointLoad([0], (1.0, 0.0, 0.0), live=1), "PointLoad.live"),
    ],
)
def test_loads_refuse_what_the_case_files_refuse(load, field):
    with pytest.raises(ValueError, match=rf"^{field} must be"):
        load()


def test_build_names_what_it_was_given_wrong(wall):
    base = [Support([wall.count - 1])]
    probes = {
        "blocks must be a Blocks": lambda: Model.build(None, MAT, base),
        "material must be an InterfaceMaterial": lambda: Model.build(
            wall, {"kn": 1e9, "kt": 1e9, "friction": 0.6}, base
        ),
        r"supports\[0\] must be a Support": lambda: Model.build(wall, MAT, ["base"]),
        r"loads\[1\] must be a": lambda: Model.build(wall, MAT, base, [SelfWeight(), "wind"]),
        r"material_overrides\[0\] blocks: block index 999 is out of range": lambda: _build(
            wall, material_overrides=[([999], MAT)]
        ),
        r"material_overrides\[0\] blocks: block index -1 is out of range": lambda: _build(
            wall, material_overrides=[([-1], MAT)]
        ),
        r"material_overrides\[0\] must be a pair": lambda: _build(
            wall, material_overrides=[[0, 1]]
        ),
    }
    for message, probe in probes.items():
        with pytest.raises(ValueError, match=message):
            probe()


def test_the_solvers_name_a_model_that_is_none_and_a_bound_that_is_no_number(wall, tmp_path):
    import masonry_dem as md

    with pytest.raises(ValueError, match="pushover: model must be a Model"):
        md.pushover(wall)
    with pytest.raises(ValueError, match="relax: model must be a Model"):
        md.relax(wall)
    with pytest.raises(ValueError, match="limit_analysis: model must be a Model"):
        md.limit_analysis(wall)
    model = _build(wall)
    with pytest.raises(ValueError, match='bound must be a number.*"maybe"'):
        md.pushover(model, bound="maybe")
    for every in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="write_every must be a whole number >= 1"):
            md.pushover(model, out=tmp_path / "a", write_every=every)


@pytest.mark.parametrize("out", ["", "   "])
def test_an_empty_out_is_refused_and_nothing_is_written(wall, tmp_path, monkeypatch, out):
    import masonry_dem as md

    monkeypatch.chdir(tmp_path)
    with pytest.raises(OSError, match="a results folder must be named by a path"):
        md.pushover(_build(wall), out=out)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("courses", [800, 3000])
def test_the_free_body_check_is_exact_whatever_the_size(courses):
    from masonry_dem import stack_bond_column

    blocks, base = add_base(stack_bond_column(courses, 0.2, 0.2, 0.2, 20e3))
    model = Model.build(blocks, MAT, [Support([base])])
    assert model.fixed[base].all()
    with pytest.raises(ValueError, match=r"leave 3 rigid-body motion.*mechanism"):
        Model.build(blocks, MAT, [Support([base], "translations")])
    with pytest.raises(ValueError, match=r"leave 1 rigid-body motion.*mechanism"):
        Model.build(blocks, MAT, [Support(np.arange(courses), "translations")])


# ------------------------------------------------------------------ fuzzing of the API calls
def _anything():
    from hypothesis import strategies as st

    return st.one_of(
        st.none(),
        st.booleans(),
        st.integers(-(10**12), 10**12),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=8),
        st.lists(st.floats(-10, 10), max_size=4),
        st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
    )


def test_api_calls_given_anything_build_or_name_what_is_wrong(wall):
    """Hypothesis gives the loads, the material and Model.build values of any type; each call
    builds, or raises a ValueError (never an AttributeError, IndexError or TypeError from
    inside the package)."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    calls = st.one_of(
        st.builds(lambda v: lambda: SelfWeight(live=v), _anything()),
        st.builds(lambda v: lambda: WeightProportional(live=v), _anything()),
        st.builds(lambda v: lambda: WeightProportional(v).vector(wall), _anything()),
        st.builds(lambda v, a: lambda: Pressure(v, axis=a).vector(wall), _anything(), _anything()),
        st.builds(lambda v: lambda: Pressure(1.0, sign=v), _anything()),
        st.builds(
            lambda kn, mu: lambda: InterfaceMaterial(kn=kn, kt=1e9, friction=mu),
            _anything(),
            _anything(),
        ),
        st.builds(lambda b: lambda: Model.build(b, MAT, [Support([0])]), _anything()),
        st.builds(lambda m: lambda: Model.build(wall, m, [Support([0])]), _anything()),
        st.builds(lambda s: lambda: Model.build(wall, MAT, s), _anything()),
        st.builds(lambda o: lambda: _build(wall, material_overrides=[(o, MAT)]), _anything()),
    )

    @settings(
        max_examples=300,
        derandomize=True,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )
    @given(calls)
    def check(call):
        try:
            call()
        except ValueError:
            pass

    check()


def test_the_schema_tables_are_made_once_not_per_checked_case():
    """A sweep checks a case per point; making the pydantic tables each time cost 1.6 ms a
    point (a sweep of 10^6 points planned for minutes)."""
    from masonry_dem.cases import schema
    from masonry_dem.cases.casefile import check_case_data

    data = {**SINGLE_BLOCK, "analysis": {"max_steps": 40}}
    check_case_data(data, "<dict>")
    made = schema._geometry_table.cache_info().misses, schema._analysis_table.cache_info().misses
    for friction in (0.5, 0.6, 0.7):
        check_case_data({**data, "material": {**data["material"], "friction": friction}}, "x")
    again = schema._geometry_table.cache_info().misses, schema._analysis_table.cache_info().misses
    assert again == made
