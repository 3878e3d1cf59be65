"""Properties of the static solver over walls generated here (hypothesis, fixed seed, few
examples, small walls, so that the suite stays fast): in or out of plane, 1-6 blocks by 1-10
courses (the issue's 1-15 by 1-20 in ``benchmarks/certificate_sweep.py``),
with or without a held column, friction 0.3-100, kn 1e8-1e13.

Proves: every run ends collapse, completed or failed; every ``collapse`` carries a
certificate that :func:`certificate_checks.recheck` re-checks on its own (residual,
strength, the tangent's Rayleigh quotient along the load from a dense solve, the live load's
work), and lambda does not exceed the associative limit-analysis multiplier (1 %);
no collapse is reported at a lambda near zero for a wall whose friction exceeds its
aspect (lambda can only be ~0 when a joint slides at once); and lambda does not move by
more than 1 % when kn and kt are scaled together by 1e-2..1e3, nor with the step size.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, example, given, seed, settings
from hypothesis import strategies as st

from helpers.certificate_checks import recheck, tilted_wall
from masonry_dem.model import InterfaceMaterial
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.solvers.limit_analysis import limit_analysis

walls = st.fixed_dictionaries(
    {
        # the class is 1-15 x 1-20; the suite draws from its small end (time), the
        # whole range is run by benchmarks/certificate_sweep.py
        "blocks_along": st.integers(1, 6),
        "courses": st.integers(1, 10),
        "in_plane": st.booleans(),
        "held": st.booleans(),
        "friction": st.floats(0.3, 100.0),
        "kn": st.floats(1e8, 1e13),
    }
)


def _model(w: dict):
    material = InterfaceMaterial(kn=w["kn"], kt=0.4 * w["kn"], friction=w["friction"])
    direction = (1.0, 0.0, 0.0) if w["in_plane"] else (0.0, 0.0, 1.0)
    return tilted_wall(w["blocks_along"], w["courses"], material, direction, w["held"])


@seed(18)
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(walls)
# a head joint at round-off at the peak: its raw tangent is set by the sign of round-off
@example(
    {
        "blocks_along": 1,
        "courses": 2,
        "in_plane": True,
        "held": False,
        "friction": 2.0,
        "kn": 1e8,
    }
)
def test_every_collapse_carries_a_certificate_that_rechecks(w):
    model = _model(w)
    solver_settings = StaticSettings()
    hist = pushover(model, solver_settings)
    assert hist.status in ("collapse", "completed", "failed"), hist.status
    if hist.status == "collapse":
        recheck(model, hist, solver_settings)
        # Radenkovic: the associative limit-analysis multiplier bounds the non-associative
        la = limit_analysis(model)
        if la.status == "collapse":
            assert hist.collapse_multiplier <= la.load_factor * (1 + 0.01), la.load_factor
        # a free-standing or held dry wall tilted by its weight: with friction above 0.3 no
        # joint slides at once, so a collapse at lambda ~ 0 would be the solver's failure
        assert hist.collapse_multiplier > 1e-3
    else:
        assert hist.collapse_multiplier is None or hist.status == "completed"


def _lambda(model, **changes) -> float:
    hist = pushover(model, StaticSettings(**changes))
    assert hist.status == "collapse", hist.reason
    return hist.collapse_multiplier


def _same_or_too_soft(model, reference: float) -> None:
    """lambda within 1 % of ``reference``, or the run failed for the one physical reason a
    stiffness may change the answer of a geometrically linear model: the wall left the
    small-displacement range (half a block from its dead-load state) while its curve still
    rose, which the reason states with the numbers."""
    hist = pushover(model, StaticSettings())
    if hist.status == "collapse":
        assert hist.collapse_multiplier == pytest.approx(reference, rel=0.01)
        return
    assert hist.status == "failed" and hist.stop == "displacement limit", hist.reason
    assert "left the small-displacement range" in hist.reason
    first, last = hist.steps[0].q[:, :3], hist.steps[-1].q[:, :3]
    assert abs(last - first).max() >= 0.5 * model.smallest_moving_size


@pytest.mark.parametrize("in_plane", [False, True], ids=["out of plane", "in plane"])
@pytest.mark.parametrize("factor", [1e-2, 1e3])
def test_lambda_does_not_move_with_joint_stiffness(in_plane, factor):
    """kn and kt scaled together by 1e-2 and 1e3 (same ratio): lambda within 1 %, or (soft
    joints only) failed because the wall leaves the small-displacement range before its
    peak: the 3 x 5 panel out of plane with kn 1e7 moves 0.043 m (half a block: 0.035 m) by
    lambda 0.298, below its peak 0.3187."""
    direction = (1.0, 0.0, 0.0) if in_plane else (0.0, 0.0, 1.0)
    base = InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7)
    scaled = InterfaceMaterial(kn=1e9 * factor, kt=0.4e9 * factor, friction=0.7)
    reference = _lambda(tilted_wall(3, 5, base, direction))
    if factor >= 1:  # stiffer joints: the same answer, no excuse
        assert _lambda(tilted_wall(3, 5, scaled, direction)) == pytest.approx(reference, rel=0.01)
    else:
        _same_or_too_soft(tilted_wall(3, 5, scaled, direction), reference)


@seed(21)
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(walls, st.sampled_from([1e-1, 1e2]))
def test_kn_invariance_on_generated_walls(w, factor):
    """Generated walls of the issue's class (small end): a certified collapse keeps its
    lambda within 1 % with kn and kt x 1e-1 or x 1e2 (the range the solver issue asks for);
    with softer joints the run may instead fail because the wall leaves the
    small-displacement range before its peak."""
    # joints stiffer than 1e12 N/m^3 after scaling are left out: docs/solvers.md, "Where
    # each method breaks", very stiff joints and the rule
    w = dict(w, kn=min(w["kn"], 1e12 / factor))
    hist = pushover(_model(w), StaticSettings())
    if hist.status != "collapse":
        return
    scaled = dict(w, kn=w["kn"] * factor)
    if factor >= 1:
        assert _lambda(_model(scaled)) == pytest.approx(hist.collapse_multiplier, rel=0.01)
    else:
        _same_or_too_soft(_model(scaled), hist.collapse_multiplier)


@pytest.mark.parametrize(
    "steps", [{"initial_step": 0.005, "max_step": 0.01}, {"initial_step": 0.1}]
)
def test_lambda_does_not_move_with_step_size(steps):
    """The in-plane 3 x 5 wall: lambda within 1 % for steps 4x shorter or 5x longer."""
    model = tilted_wall(3, 5, direction=(1.0, 0.0, 0.0))
    assert _lambda(model, **steps) == pytest.approx(_lambda(model), rel=0.01)
