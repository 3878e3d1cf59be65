"""The reach of a work step (solvers/static/steps.py; docs/solvers.md, "The reach of a work
step"): the step rules of work control (``StaticSettings.step_rule``), the predictor of
order 1 or 2 (``predictor_order``), the first work step, and the closed-form collapses
each keeps.

Proves:

- the arithmetic of each rule: after a step of I Newton iterations the iteration rule
  multiplies the step by (I_d / I) ** p, clamped to [step_shrink, growth] and to the cap;
  the easy rule grows by ``growth`` after at most ``easy_iterations`` and keeps the step
  otherwise;
- the parabola through three states reproduces a path quadratic in w exactly (its error is
  third order), where the line misses by the second-order term; past a turn of the path
  (the states on two straight pieces of opposite slope) its second-order term is larger
  than its first and it falls back to the line, past a milder kink it is kept;
- work control's first step is the last load step's increment of w;
- each rule and predictor finds the closed-form collapses: a block on its
  base tilts at s/a and slides at mu, a free-standing wall tilts at t/H (the weight's moment
  about the toe, W t / 2, against the live load's, lambda W H / 2), within 1e-6 with a
  bracket tolerance of 1e-7;
- bad values are refused with the field, the value and the allowed range.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from helpers.walls import CLOSED_FORMS, on_base
from masonry_dem.geometry.builders import running_bond_wall
from masonry_dem.solvers.incremental import pushover
from masonry_dem.solvers.static import StaticSettings
from masonry_dem.solvers.static.steps import SecantPredictor, StepController


def _controller(rule: str, **kw) -> StepController:
    return StepController(1.0, 1.5, rule=rule, target_iterations=6, exponent=0.5, **kw)


@pytest.mark.parametrize(
    "iterations, expected",
    [(6, 1.0), (24, 0.5), (12, math.sqrt(0.5)), (4, math.sqrt(1.5)), (2, 1.5), (100, 0.5)],
    ids=["on target", "4x the target", "2x", "2/3", "clamped to growth", "clamped to shrink"],
)
def test_the_iteration_rule_scales_the_step_by_the_ratio_of_iterations(iterations, expected):
    """Exact: (6 / I) ** 0.5, clamped to [0.5, 1.5]: 24 iterations halve the step, 6 keep it,
    2 would give sqrt(3) = 1.73 and are held to 1.5, 100 would give 0.245 and are held to
    0.5."""
    step = _controller("iterations", shrink=0.5)
    step.grow(iterations)
    assert step.size == pytest.approx(expected, rel=1e-14)


def test_the_easy_rule_grows_after_easy_steps_only_and_every_rule_keeps_the_cap():
    """The easy rule grows by 1.5 after at most 6 and keeps the step after 7."""
    step = StepController(1.0, 1.5, easy_iterations=6, rule="easy")
    step.grow(6)
    assert step.size == 1.5
    step.grow(7)
    assert step.size == 1.5
    capped = _controller("iterations", cap=1.2)
    capped.grow(1)
    assert capped.size == 1.2
    step.cut()
    assert (step.size, step.cuts) == (0.75, 1)


def _path(t: float) -> tuple[np.ndarray, float]:
    """A path quadratic in t: q = a + b t + c t^2, lambda = 0.1 + 0.3 t - 0.2 t^2."""
    a, b, c = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.1, -1.0]), np.array([0.2, -0.4, 0.05])
    return a + b * t + c * t * t, 0.1 + 0.3 * t - 0.2 * t * t


def test_the_parabola_through_three_states_is_exact_on_a_quadratic_path():
    """Exact to round-off on unequal steps (t = 0, 0.3, 0.7, predicted at 1.1): the
    interpolating parabola of a quadratic is the quadratic. The line through the last two
    misses by the second-order term c (t - t0)(t - t1) = c x 0.4 x 0.8."""
    ts = (0.0, 0.3, 0.7)
    parabola = SecantPredictor(True, [], order=2)
    line = SecantPredictor(True, [])
    for t in ts:
        parabola.add(t, *_path(t))
        line.add(t, *_path(t))
    assert len(parabola.states) == 3 and len(line.states) == 2
    q, lam = parabola.start(1.1)
    exact_q, exact_lam = _path(1.1)
    assert q == pytest.approx(exact_q, abs=1e-14)
    assert lam == pytest.approx(exact_lam, abs=1e-14)
    q1, lam1 = line.start(1.1)
    c = np.array([0.2, -0.4, 0.05])
    assert exact_q - q1 == pytest.approx(c * 0.4 * 0.8, abs=1e-14)
    assert exact_lam - lam1 == pytest.approx(-0.2 * 0.4 * 0.8, abs=1e-14)


def test_the_parabola_falls_back_to_the_line_past_a_turn_of_the_path():
    """States on two straight pieces that turn back (slope +1, then -1: a kink at t = 1):
    over the next half step the parabola's second-order term, (0.5 x 1.5 / 2) x (-2) =
    -0.75, is larger than the line's increment -0.5, so the start is the line through the
    last two states (0.5). A milder kink, a slope of 0 then 1, gives a term of 0.375 against
    0.5: the parabola is kept (1.875, the line 1.5)."""
    for states, t_next, expected, kept in (
        (((0.0, 0.0), (1.0, 1.0), (2.0, 0.0)), 2.5, -0.5, False),
        (((0.0, 0.0), (1.0, 0.0), (2.0, 1.0)), 2.5, 1.875, True),
    ):
        parabola = SecantPredictor(True, [], order=2)
        line = SecantPredictor(True, [])
        for t, q in states:
            parabola.add(t, np.array([q]), q)
            line.add(t, np.array([q]), q)
        q, lam = parabola.start(t_next)
        assert q == pytest.approx([expected], abs=1e-15)
        assert lam == pytest.approx(expected, abs=1e-15)
        assert (q != line.start(t_next)[0]).all() == kept


RULES = [
    {"step_rule": "iterations"},
    {"predictor_order": 2},
    {"step_rule": "iterations", "predictor_order": 2},
]
RULE_IDS = ["iterations", "parabola", "iterations+parabola"]


@pytest.mark.parametrize("rule", RULES, ids=RULE_IDS)
@pytest.mark.parametrize("model, closed_form", CLOSED_FORMS.values(), ids=CLOSED_FORMS.keys())
def test_each_rule_finds_the_closed_form_collapses(rule, model, closed_form):
    hist = pushover(model(), StaticSettings(bracket_tolerance=1e-7, **rule))
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(closed_form, rel=1e-6)


@pytest.mark.parametrize(
    "name, value, words",
    [
        ("predictor_order", 3, "1 or 2"),
        ("predictor_order", 1.0, "1 or 2"),
        ("step_rule", "crisfield", "one of ('easy', 'iterations')"),
        ("target_iterations", 0, "an integer >= 1"),
        ("step_exponent", 0.0, "a positive number"),
        ("step_shrink", 1.5, "in (0, 1]"),
        ("step_shrink", 0, "in (0, 1]"),
    ],
)
def test_bad_step_settings_are_named(name, value, words):
    with pytest.raises(ValueError, match=re.escape(f"{name} must be {words}, got {value!r}")):
        StaticSettings(**{name: value})


def _first_work_step(settings: StaticSettings) -> tuple[float, float]:
    """(the first step of w work control asks for, the last load step's increment of w) on a
    free-standing 4 x 9 wall, recorded from the searches the path followers ask for."""
    from masonry_dem.solvers.static.solver import StaticSolver

    solver = StaticSolver(
        on_base(running_bond_wall(4, 9, 0.081, 0.21, 0.07, 20e3), kn=2.4e9), settings
    )
    calls: list[tuple[float, object, bool, int]] = []
    accepted: list[tuple[float, np.ndarray]] = []  # (lambda, q) of each recorded state
    plain, accept = solver.equilibrate, solver.accept

    def recording(load_factor, *args, **kwargs):
        out = plain(load_factor, *args, **kwargs)
        calls.append((float(load_factor), kwargs.get("control"), bool(out.ok), len(accepted)))
        return out

    def keeping(out, step, value):
        accepted.append((float(out.load_factor), out.q.reshape(-1).copy()))
        return accept(out, step, value)

    solver.equilibrate = recording  # type: ignore[method-assign]
    solver.accept = keeping  # type: ignore[method-assign]
    hist = solver.run()
    assert hist.status == "collapse", hist.reason
    first = next(i for i, call in enumerate(calls) if call[1] is not None)
    failed = calls[first - 1]
    assert failed[1] is None and not failed[2]  # the load step that failed hands over
    free = solver.problem.asm.free_index
    c = solver.problem.F_live / np.linalg.norm(solver.problem.F_live)
    # the last two states load control recorded before it handed over
    (_, q0), (_, q1) = accepted[calls[first][3] - 2 : calls[first][3]]
    last = float(c @ (q1[free] - q0[free]))
    return calls[first][1][2], last


def test_the_first_work_step_is_the_last_load_step():
    """Exact: work control's first step is the last load step's increment of w."""
    asked, last = _first_work_step(StaticSettings())
    assert asked == pytest.approx(last, rel=1e-9)
