"""What a running limit analysis reports (``progress``): the interior point iterations close on
the certified bracket, the non-associative solves are the result's load factors, and a
failing display never stops the analysis."""

from __future__ import annotations

import pytest

from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.limit_analysis import LimitProgress, limit_analysis, normal_ipm


def _ladder_wall(side: int) -> Model:
    """side x side courses of 0.4 x 0.2 x 0.2 m running bond on a slab, mu 0.6, tilted in
    plane (the size ladder's wall)."""
    wall, base = add_base(running_bond_wall(side, side, a=0.2, b=0.4, s=0.2, unit_weight=19620))
    return Model.build(
        wall,
        InterfaceMaterial(kn=1e9, kt=1e9, friction=0.6),
        [Support([base])],
        [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
    )


def test_interior_point_iterations_close_on_the_certified_bracket():
    """Each iteration of the normal equations is reported once, numbered from 1; the last one
    is the iterate whose bracket was certified: its two values are the bracket's ends (to the
    live-work row's rounding)."""
    pytest.importorskip("pypardiso")
    model = _ladder_wall(17)
    assert 6 * (model.blocks.count - 1) >= normal_ipm.NORMAL_EQUATIONS_FROM
    seen: list[LimitProgress] = []
    result = limit_analysis(model, backend="clarabel", progress=seen.append)
    assert result.bracket is not None
    assert {e.stage for e in seen} == {"interior point"}
    assert [e.iteration for e in seen] == list(range(1, len(seen) + 1))
    last = seen[-1]
    low, up = result.bracket
    assert last.lower == pytest.approx(low, rel=1e-12)
    assert last.upper == pytest.approx(up, rel=1e-9)
    assert last.lower <= result.load_factor <= last.upper * (1 + 1e-9)


def test_non_associative_solves_are_the_load_factors_and_a_failing_display_is_dropped():
    """The non-associative iteration reports each frozen-friction solve's lambda: the same
    numbers as the result's ``load_factors``. A callback that raises is dropped at its first
    call and the analysis gives the same answer."""
    model = _ladder_wall(4)
    seen: list[LimitProgress] = []
    result = limit_analysis(model, associative=False, progress=seen.append)
    solves = [e for e in seen if e.stage == "non-associative"]
    assert len(solves) >= 2
    assert [e.lower for e in solves] == list(result.load_factors)
    assert all(e.lower == e.upper for e in solves)
    calls = []

    def broken(event: LimitProgress) -> None:
        calls.append(event)
        raise RuntimeError("the display is gone")

    again = limit_analysis(model, associative=False, progress=broken)
    assert len(calls) == 1
    assert again.status == result.status and again.load_factor == result.load_factor
