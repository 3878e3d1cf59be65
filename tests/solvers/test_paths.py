"""The steps of the path followers (solvers/static/paths.py): where each search starts, how
a failed step is re-tried."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.geometry.builders import add_base, running_bond_wall, single_block
from masonry_dem.geometry.selectors import column
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.solvers.static.outcome import Failure, Outcome
from masonry_dem.solvers.static.solver import StaticSolver
from masonry_dem.solvers.static.steps import (
    SecantPredictor,
    elastic_range,
)

DRY = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7)
TOL = 0.005  # the default bracket tolerance


def _tilt(blocks, base, extra=()) -> Model:
    return Model.build(
        blocks,
        DRY,
        supports=[Support([base]), *extra],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )


def _panel() -> Model:
    """3 x 13 running bond held on its left column, tilted out of plane (as in
    test_incremental): its path meets folds where joints start to rock."""
    wall = running_bond_wall(3, 13, 0.081, 0.21, 0.07, 20e3)
    blocks, base = add_base(wall)
    return _tilt(blocks, base, extra=[Support(column(wall, "left"), ["u1", "u3"])])


def test_secant_predictor_extends_the_line_through_the_last_two_states():
    """Exact: the start at t is q1 + (t - t1) / (t1 - t0) (q1 - q0), and lambda alike; one
    state (a path that jumped) gives no start."""
    q0, q1 = np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 2.0])
    line = SecantPredictor()
    line.add(0.5, q0, 0.1)
    assert line.start(2.0) == (None, None)
    line.add(1.5, q1, 0.3)
    q, lam = line.start(2.5)  # one more step of the same length
    assert q == pytest.approx([2.0, 5.0, 2.0], abs=1e-15)
    assert lam == pytest.approx(0.5, abs=1e-15)
    q, lam = line.start(1.75)  # a quarter step
    assert q == pytest.approx([1.25, 3.5, 2.0], abs=1e-15)
    line.add(2.0, q, lam)  # the oldest state drops out
    assert line.states[0][0] == 1.5
    line.restart(3.0, q1, 0.4)
    assert line.start(4.0) == (None, None)


def test_load_control_retries_a_failure_from_the_first_easy_step_inside_its_bracket(
    monkeypatch,
):
    """A load step that failed because it was long (here every step longer than 0.03 fails,
    on an elastic block far from its rocking limit s / a = 0.5) is re-tried from the first
    easy step inside the bracket, which passes it: 0.1 and 0.05 fail, 0.025 passes, then
    0.05 at once. Halving the gap instead crept up on 0.05 in 7 ever shorter steps (0.0375,
    0.04375, ... 0.0498) before the re-try."""
    original = StaticSolver.equilibrate

    def long_steps_fail(self, load_factor, *args, **kwargs):
        if kwargs.get("control") is None and load_factor - self.load_factor > 0.03 + 1e-12:
            response = self.residual(self.q, self.load_factor)[2]
            return Outcome(
                False, self.q, load_factor, response, 0, "too long", failure=Failure.STALL
            )
        return original(self, load_factor, *args, **kwargs)

    monkeypatch.setattr(StaticSolver, "equilibrate", long_steps_fail)
    blocks, base = add_base(single_block(0.2, 0.25, 0.1, 20e3))
    h = pushover(
        _tilt(blocks, base),
        StaticSettings(initial_step=0.1, max_load_factor=0.2, continuation="bracket"),
    )
    assert h.status == "completed", h.reason
    lams = h.load_factors
    assert lams[1:3] == pytest.approx([0.025, 0.05], rel=1e-12)
    assert lams[-1] == pytest.approx(0.2, rel=1e-12)


def _standing(solver: StaticSolver) -> StaticSolver:
    """The solver at its dead-load state, as load control finds it."""
    dead = solver.dead_load()
    assert dead.ok, dead.reason
    solver.accept(dead, 0, 0.0)
    return solver


@pytest.mark.parametrize(
    "a, s, friction, closed_form",
    [(0.2, 0.1, 0.7, 0.5), (0.3, 0.06, 0.7, 0.2), (0.05, 0.2, 0.45, 0.45)],
    ids=["tilts at s/a", "tilts at s/a, slender", "slides at mu"],
)
def test_the_elastic_range_of_a_block_on_its_base_ends_at_its_collapse_load(
    a, s, friction, closed_form
):
    """Closed form: a rigid block on a rigid base under its weight W and a horizontal lambda W
    loads its one joint with N = W, V = lambda W, M = lambda W a / 2 at once and in proportion,
    so the joint reaches its strength domain (|M| <= N s / 2: lambda = s / a; V <= mu N:
    lambda = mu) at the lower of the two, which is also the block's collapse load. The
    bisection stops just inside (to 1e-6 of lambda)."""
    blocks, base = add_base(single_block(a, 0.25, s, 20e3))
    material = InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=friction)
    model = Model.build(
        blocks,
        material,
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )
    elastic = elastic_range(_standing(StaticSolver(model)), cap=10.0)
    assert elastic is not None
    assert elastic.load_factor == pytest.approx(closed_form, rel=1e-5)
    assert elastic.load_factor <= closed_form


def test_the_first_live_step_is_the_elastic_range_and_takes_no_newton_iteration():
    """A free-standing running-bond wall stays elastic until its base joints rock, at
    lambda = s / H (the whole wall tilting as one block): the first live step goes to a
    bracket tolerance short of it at once (at the very end of the range the base joints sit
    on the edge of their domain), started from the elastic predictor q_D + lambda K_t^-1 F_L,
    which is the equilibrium (no Newton iteration), with every joint inside its domain. With
    the setting off the first step is ``initial_step`` load scales, as before."""
    a, s, courses = 0.081, 0.07, 9
    blocks, base = add_base(running_bond_wall(4, courses, a, 0.21, s, 20e3))
    model = _tilt(blocks, base)
    h = pushover(model)
    first = h.steps[1]
    assert first.iterations == 0
    assert first.load_factor == pytest.approx((1 - TOL) * s / (courses * a), rel=1e-5)
    assert first.utilisation.max() <= 1.0
    assert h.collapse_multiplier == pytest.approx(s / (courses * a), rel=TOL)
    solver = StaticSolver(model, StaticSettings(elastic_first_step=False))
    off = solver.run()
    assert off.steps[1].load_factor == pytest.approx(0.02 * solver.problem.load_scale, rel=1e-12)


def test_an_elastic_range_shorter_than_the_initial_step_leaves_the_first_step_alone():
    """Where the first joint yields before ``initial_step`` (a block tilting at s/a = 0.5
    asked to start with 0.8), the first step is ``initial_step``, as with the setting off:
    a short elastic range says nothing of how far Newton goes beyond it."""
    blocks, base = add_base(single_block(0.2, 0.25, 0.1, 20e3))
    model = _tilt(blocks, base)
    on = pushover(model, StaticSettings(initial_step=0.8, max_step=0.8))
    off = pushover(model, StaticSettings(initial_step=0.8, max_step=0.8, elastic_first_step=False))
    assert on.load_factors == pytest.approx(off.load_factors, rel=1e-12)
    assert on.collapse_multiplier == pytest.approx(0.5, rel=TOL)
