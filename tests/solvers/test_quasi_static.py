"""The reference quasi-static analysis (solvers/quasi_static.py, ``md.quasi_static``): the
judge of the path follower, a wall with dashpots beside its joints moved to rest after every
small increment of load.

Proves:

- the closed-form collapses of the tilt table (a block tilts at s/a, a squat block slides at
  mu, a free-standing 4 x 9 wall tilts at t/H) lie in the judge's bracket [lo, hi], within
  1e-9 relative, and the bracket is as narrow as ``bracket_tolerance`` (1e-3) asks;
- the answer does not move when kn and kt are scaled together (x 0.1 and x 100), within 1e-3:
  the model is geometrically linear and the judge's units are the wall's elastic ones;
- every rest of the History is an equilibrium of the static problem: its residual, worked out
  again by ``DiscreteProblem``, is within 10 x the judge's ``tolerance`` (1e-8); the
  collapse multiplier is the load of the last rest;
- a wall with a block that hangs on dry head joints over an opening finds no rest under its
  dead load: ``failed``, stop ``DEAD_LOAD``, and the block that falls is the hanging one;
- the judge's lambda is at most the associative limit-analysis multiplier (x (1 + 1e-3));
- without a live load the analysis ends ``completed`` (``NO_LIVE_LOAD``); with
  ``max_load_factor`` below the collapse it ends ``completed`` at exactly that load;
- with ``newton_steps`` the closed forms are bracketed as well;
- bad settings are refused by name, and settings of another type by a TypeError.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import masonry_dem as md
from helpers.walls import CLOSED_FORMS, on_base
from masonry_dem.geometry import builders
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support
from masonry_dem.solvers.quasi_static import QuasiStatic
from masonry_dem.solvers.static.problem import DiscreteProblem

DEFAULT = md.QuasiStaticSettings()
SLACK = 1e-9  # relative: round-off of the loads the judge adds up in increments

A, B, S, GAMMA = 0.081, 0.21, 0.07, 20e3  # the 4 x 9 wall's blocks [m] and unit weight


def free_wall(kn: float = 2.4e9) -> Model:
    """The free-standing 4 x 9 running-bond wall of CLOSED_FORMS (tilts at t/H = 0.0960)."""
    return on_base(builders.running_bond_wall(4, 9, A, B, S, GAMMA), kn=kn)


def block(kn: float = 2.4e9) -> Model:
    """The block of CLOSED_FORMS 0.2 high and 0.1 thick (tilts at s/a = 0.5)."""
    return on_base(builders.single_block(0.2, 0.25, 0.1, 20e3), friction=0.7, kn=kn)


SCENES = pytest.mark.parametrize("build", [free_wall, block], ids=["wall t/H", "block s/a"])


@pytest.mark.parametrize("build, exact", CLOSED_FORMS.values(), ids=CLOSED_FORMS.keys())
def test_the_bracket_holds_the_closed_form_collapse(build, exact):
    """Measured: the bracket is (0.5, 0.500313) for s/a, (0.45, 0.450313) for mu and
    (0.0960156, 0.0960938) around t/H = 0.0960219; hi / lo - 1 is 6.2e-4, 6.9e-4, 8.1e-4."""
    hist = md.quasi_static(build())
    assert hist.status == "collapse", hist.reason
    assert hist.stop is md.StopReason.NO_REST
    lo, hi = hist.collapse_bracket
    assert hist.collapse_multiplier == lo
    assert lo <= exact * (1 + SLACK)
    assert exact <= hi * (1 + SLACK)
    assert hi / lo - 1 <= DEFAULT.bracket_tolerance + SLACK


@pytest.mark.parametrize("build, exact", CLOSED_FORMS.values(), ids=CLOSED_FORMS.keys())
def test_newton_steps_keep_the_closed_form_collapse(build, exact):
    """With ``newton_steps`` (Newton at each load step, the damped motion only where it
    fails) the bracket still holds the closed form, within the same tolerances."""
    settings = md.QuasiStaticSettings(newton_steps=True)
    hist = md.quasi_static(build(), settings)
    assert hist.status == "collapse", hist.reason
    lo, hi = hist.collapse_bracket
    assert lo <= exact * (1 + SLACK)
    assert exact <= hi * (1 + SLACK)
    assert hi / lo - 1 <= settings.bracket_tolerance + SLACK


@SCENES
@pytest.mark.parametrize("factor", [0.1, 100.0])
def test_the_collapse_does_not_move_with_the_joint_stiffness(build, factor):
    """kn (and kt = 0.4 kn with it) x 0.1 and x 100: the same multiplier within 1e-3 relative
    (measured: the same brackets to the last bit)."""
    reference = md.quasi_static(build())
    scaled = md.quasi_static(build(kn=2.4e9 * factor))
    assert reference.status == scaled.status == "collapse", (reference.reason, scaled.reason)
    assert scaled.collapse_multiplier == pytest.approx(reference.collapse_multiplier, rel=1e-3)


@pytest.mark.parametrize(
    "build", [build for build, _ in CLOSED_FORMS.values()], ids=CLOSED_FORMS.keys()
)
def test_every_rest_is_an_equilibrium(build):
    """Each step's q, at its load factor, is an equilibrium of the static problem: the
    weighted relative residual within 10 x ``tolerance`` (measured, the largest of the
    steps: 7.9e-10 for s/a, 4.1e-10 for mu, 4.7e-9 for t/H). The law's state along the path is not
    stored, but neither matters here: the plastic slip of a rest is its own (its relative
    displacements less its actions over the stiffness, in the slip components: zero under the
    holonomic law), and the joints are dry (tensile strength 0), so a cracked joint has the
    tensile force 0 it had uncracked: the residual is the same whatever joints the judge took
    as cracked (checked, bit for bit, with none and with all). The load factors rise from the
    dead load's 0, and the collapse multiplier is the last."""
    model = build()
    hist = md.quasi_static(model)
    assert hist.status == "collapse", hist.reason
    problem = DiscreteProblem(model)
    assert np.all(problem.law.tensile_force == 0.0)
    m = model.interfaces.count
    none, every = np.zeros(m, dtype=bool), np.ones(m, dtype=bool)
    lams = hist.load_factors
    assert lams[0] == 0.0 and np.all(np.diff(lams) > 0)
    assert lams[-1] == hist.collapse_multiplier
    worst = 0.0
    for step in hist.steps:
        q = step.q.reshape(-1)
        relative = problem.asm.relative_displacements(q)
        plastic = problem.law.plastic_part(relative, step.actions)
        residual, norm, _ = problem.residual(q, step.load_factor, plastic, none)
        residual_all, norm_all, _ = problem.residual(q, step.load_factor, plastic, every)
        assert np.array_equal(residual, residual_all) and norm == norm_all
        assert norm <= 10 * DEFAULT.tolerance, (step.step, step.load_factor, norm)
        worst = max(worst, norm)
    assert worst > 0.0  # the rests are numerical ones: the check is not vacuous


def test_a_block_that_hangs_over_an_opening_falls_under_the_dead_load():
    """A 4 x 5 running-bond wall with an opening two blocks wide over courses 1 and 2, cut
    in whole blocks without lintels: the block of course 3 over its middle has nothing under
    it and hangs on dry head joints, which carry no normal force and so no friction. It
    falls: the judge finds no rest under the dead load, and the damped motion that ran past
    the displacement limit (s / 2 = 0.035 m; measured: 0.095 m) is the hanging block's,
    straight down, every other block within 1e-2 of that limit of where it stood (their
    elastic settling under the weight; measured: 4.0e-5 m)."""
    wall = builders.running_bond_wall(4, 5, A, B, S, GAMMA)
    cut = md.cut_openings(wall, [(B, A, 3 * B, 3 * A)], lintels=False)
    hanging = builders.unsupported_blocks(cut)
    assert hanging.size == 1
    model = on_base(cut, kn=2.4e9)  # the base is added after the wall's blocks
    hist = md.quasi_static(model)
    assert hist.status == "failed", hist.reason
    assert hist.stop is md.StopReason.DEAD_LOAD
    assert hist.collapse_bracket is None
    # the motion itself (not the History's record of it): where it ran past the limit
    judge = QuasiStatic(model)
    motion = judge.move_to_rest(0.0)
    assert not motion.rest and motion.past_limit, motion.reason
    q = judge.q.reshape(-1, 6)
    k = int(hanging[0])
    assert q[k, 1] < -S / 2  # down, past the displacement limit
    others = np.delete(np.arange(cut.count), k)
    assert np.abs(q[others, :3]).max() < 1e-2 * S / 2  # their elastic settling


@SCENES
def test_the_judge_lies_at_or_below_the_associative_multiplier(build):
    """Associative limit analysis (HiGHS, circumscribed pyramid) bounds the collapse of an
    associative material from above, and the non-associative joint's collapse lies at or
    below it: judge lambda <= bound x (1 + 1e-3). Measured: 0.0960156 against 0.0960219
    (wall) and 0.5 against 0.5 (block). (The proved bound of the DEM is ``dem_upper_bound``,
    the friction enlarged for torsion; these mechanisms tilt without torsion.)"""
    model = build()
    bound = md.limit_analysis(model)
    assert bound.status == "collapse", bound.reason
    hist = md.quasi_static(model)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier <= bound.load_factor * (1 + 1e-3)


def test_without_a_live_load_the_analysis_ends_at_the_dead_load():
    blocks, base = builders.add_base(builders.single_block(0.2, 0.25, 0.1, 20e3))
    model = Model.build(
        blocks, InterfaceMaterial(2.4e9, 1e9, 0.7), [Support([base])], [SelfWeight()]
    )
    hist = md.quasi_static(model)
    assert hist.status == "completed", hist.reason
    assert hist.stop is md.StopReason.NO_LIVE_LOAD
    assert len(hist.steps) == 1 and hist.last.load_factor == 0.0
    assert hist.collapse_bracket is None


def test_max_load_factor_ends_the_analysis_below_the_collapse():
    """The s/a block (collapse 0.5) capped at 0.2: completed, its last rest at 0.2 exactly."""
    hist = md.quasi_static(block(), md.QuasiStaticSettings(max_load_factor=0.2))
    assert hist.status == "completed", hist.reason
    assert hist.stop is md.StopReason.MAX_LOAD_FACTOR
    assert hist.last.load_factor == 0.2
    assert hist.collapse_bracket is None


@pytest.mark.parametrize(
    "name, value",
    [
        ("load_increment", -1),
        ("first_increment", 0.0),
        ("bracket_tolerance", math.nan),
        ("growth", 0.5),
        ("max_time_steps", 0),
        ("max_load_factor", -1.0),
        ("displacement_limit", -0.01),
    ],
)
def test_bad_settings_are_refused_by_name(name, value):
    with pytest.raises(ValueError, match=name):
        md.QuasiStaticSettings(**{name: value})


def test_settings_of_another_type_are_refused():
    with pytest.raises(TypeError, match="QuasiStaticSettings"):
        md.quasi_static(block(), settings=object())
