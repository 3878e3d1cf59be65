"""Where the solvers break, and what the package then does (docs/solvers.md).

Load control past the limit point, near-singular stiffness before collapse, a DR time step
above the stability limit, very stiff dry joints, zero or tiny friction, loads that reverse,
and random small walls on which the static solver and dynamic relaxation must agree (or fail
the same way). Every run ends with a status and a reason and never puts NaN in the results.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers.walls import A, B, S, on_base
from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.constitutive.law import InterfaceLaw
from masonry_dem.geometry import builders
from masonry_dem.model import Model
from masonry_dem.results import History
from masonry_dem.solvers.dynamic_relaxation import DRSettings, DynamicRelaxation
from masonry_dem.solvers.incremental import StaticSettings, StaticSolver
from masonry_dem.solvers.static.corrector import STALL_WINDOW
from masonry_dem.solvers.static.outcome import StopReason

DR_FAST = DRSettings(bracket_tolerance=0.01)


def assert_clean(hist: History) -> None:
    """A status, a reason, finite numbers everywhere, and a lambda only after a collapse."""
    assert hist.status in ("collapse", "completed", "failed")
    assert hist.reason
    assert hist.steps, "every run keeps at least the state it started from"
    for step in hist.steps:
        assert math.isfinite(step.load_factor)
        for arr in (step.q, step.actions, step.utilisation):
            assert np.all(np.isfinite(arr))
    if hist.status == "collapse":
        lo, hi = hist.collapse_bracket
        assert math.isfinite(lo) and math.isfinite(hi) and lo <= hi
    else:
        assert hist.collapse_multiplier is None
    summary = hist.summary()
    assert all(not (isinstance(v, float) and math.isnan(v)) for v in summary.values())


def both(model: Model, static: StaticSettings | None = None, dr: DRSettings = DR_FAST):
    hs = StaticSolver(model, static).run()
    hd = DynamicRelaxation(model, dr).run()
    assert_clean(hs)
    assert_clean(hd)
    return hs, hd


@pytest.fixture(scope="module")
def block() -> Model:
    return on_base(builders.single_block(A, B, S, 20e3))


# ---------------------------------------------------------------------------- limit point
def test_load_control_past_the_limit_point(block):
    """A first step far beyond collapse fails; the bracket is refined back to s/a."""
    hs, hd = both(
        block,
        StaticSettings(initial_step=3.0, max_step=3.0),
        DRSettings(initial_step=3.0, max_step=3.0, bracket_tolerance=0.01),
    )
    for hist in (hs, hd):
        assert hist.status == "collapse"
        assert hist.collapse_multiplier == pytest.approx(S / A, rel=0.01)
        # a converged state, not beyond (to the residual tolerance, 1e-8 of the load)
        assert hist.collapse_multiplier <= S / A * (1 + 1e-8)


def test_unrefined_bracket_says_so(block):
    """Without refinement a first step beyond collapse stops the run at [0, 3]. That is no
    collapse: the state it stops in is the dead load's, with its whole elastic stiffness
    along the load (also across the bracket's tolerance), so the run ends failed (no
    lambda), and the reason says the bracket was not refined and why it is no collapse."""
    hist = StaticSolver(block, StaticSettings(initial_step=3.0, max_step=3.0, refine=False)).run()
    assert_clean(hist)
    assert hist.status == "failed"
    assert hist.stop == StopReason.LOAD_BRACKET
    assert hist.certificate is not None and not hist.certificate.mode_found
    assert "refine=False" in hist.reason and "not a certified collapse" in hist.reason


def test_bracket_refined_when_work_control_finds_nothing_higher(block, monkeypatch):
    """Work control takes over at the first failure of load control; where it finds no
    equilibrium above the last load step, the load-control bracket is refined after all,
    from the state it was handed (the block still tilts over at s/a, bracket <= 0.5 %)."""
    calls = []

    from masonry_dem.solvers.static import paths
    from masonry_dem.solvers.static.outcome import StopReason

    def nothing_higher(solver, hist, record, first_failure):
        calls.append(hist.steps[-1].load_factor)
        return "forced", StopReason.PATH_STUCK

    monkeypatch.setattr(paths, "work_control", nothing_higher)
    # steps of 0.1 (the elastic first step would reach s/a at once, before any hand-over)
    hist = StaticSolver(block, StaticSettings(initial_step=0.1, elastic_first_step=False)).run()
    assert_clean(hist)
    assert len(calls) == 1 and calls[0] < S / A  # handed over once, below the collapse
    lo, hi = hist.collapse_bracket
    assert lo <= S / A * (1 + 1e-9) <= hi
    assert hi - lo <= 0.005 * lo * (1 + 1e-9)
    assert "work control found no higher equilibrium (forced)" in hist.reason


def test_a_controlled_step_that_converges_slowly_is_not_a_stall(monkeypatch):
    """A controlled step starts at an equilibrium (residual ~0) a whole step from its goal:
    the merit it starts from is the control's error. With a tangent too stiff (a twentieth of
    its diagonal added) Newton converges linearly and must still reach the equilibrium the
    exact tangent finds, not be stopped as a stall because its residual is above the
    start's (the error that made 20 work steps of a Table 3 wall fail at 8 iterations with
    every residual falling)."""
    from masonry_dem.solvers.static import paths, problem

    wall = on_base(builders.running_bond_wall(3, 3, A, B, S, 20e3), left=["u1", "u2", "u3"])
    solver = StaticSolver(wall)
    dead = solver.equilibrate(0.0, radius=solver.limit, damped=True)
    assert dead.ok
    solver.restore(dead.q)
    F_live = solver.problem.F_live
    c = F_live / np.linalg.norm(F_live)
    dw = 1e-6  # elastic
    control = (c, float(c @ dead.q[solver.problem.free]) + dw, dw)
    radius = paths.control_radius(solver, c, dw)
    exact = solver.equilibrate(0.0, control=control, radius=radius)
    assert exact.ok and exact.iterations <= 3

    entries = problem.TangentAssembler.data

    def too_stiff(self, T, layout=None):
        data = entries(self, T).copy()
        column = np.repeat(np.arange(self.n), np.diff(self.indptr))
        data[self.indices == column] *= 1.05  # the diagonal is stored
        return data if layout is None else data[layout]  # in the backend's order

    monkeypatch.setattr(problem.TangentAssembler, "data", too_stiff)
    monkeypatch.setattr(problem.TangentAssembler, "update", too_stiff)  # what Newton factors
    slow = solver.equilibrate(0.0, control=control, radius=radius)
    assert slow.ok, slow.reason
    assert slow.iterations > STALL_WINDOW  # linear, as intended
    # both within the residual tolerance (1e-8 of the dead load, about 1e-8 load scales)
    assert slow.load_factor == pytest.approx(exact.load_factor, abs=1e-7)
    assert exact.load_factor > 1e-5


def test_dead_load_settles_by_relaxation_where_newton_stalls(block, monkeypatch):
    """Where the damped Newton search of the dead load stalls, the instability rule's damped
    motion brings the wall to rest, and the analysis goes on from there (the block still
    tilts over at s/a)."""
    from dataclasses import replace as _replace

    newton = StaticSolver.equilibrate

    def stalls_under_dead_load(self, load_factor, dead_factor=1.0, **kw):
        out = newton(self, load_factor, dead_factor, **kw)
        if kw.get("damped"):
            return _replace(out, ok=False, reason="no equilibrium found: forced stall")
        return out

    monkeypatch.setattr(StaticSolver, "equilibrate", stalls_under_dead_load)
    hist = StaticSolver(block).run()
    assert_clean(hist)
    assert hist.status == "collapse"
    assert hist.collapse_multiplier == pytest.approx(S / A, rel=0.01)


def test_near_singular_stiffness_before_collapse():
    """Just before collapse the paper's damaged stiffness (Eqs. 13-14 factors of the last
    converged state) is singular: yielded joints leave a mechanism that is not yet driven.
    The static solver still converges there (residual stiffness floor, elastic fall-back) and
    both solvers give the same finite lambda."""
    model = on_base(builders.running_bond_wall(3, 4, 0.081, 0.21, 0.07, 20e3), left=["u1", "u3"])
    hs, hd = both(model, StaticSettings(bracket_tolerance=1e-3))
    asm = Assembly.of(model)
    law = InterfaceLaw.of(model, asm.kbar)
    last = hs.last
    response = law.respond(
        asm.relative_displacements(last.q.reshape(-1)),
        np.zeros_like(last.actions),
        np.zeros(model.interfaces.count, dtype=bool),
    )
    damaged = np.linalg.eigvalsh(asm.stiffness(np.maximum(response.tangent, 0.0)).toarray())
    elastic = np.linalg.eigvalsh(asm.stiffness().toarray())
    assert abs(damaged.min()) < 1e-6 * elastic.min()  # singular to round-off
    assert hd.collapse_multiplier == pytest.approx(hs.collapse_multiplier, rel=0.01)


# ---------------------------------------------------------------------------- DR time step
@pytest.mark.parametrize("dt", [None, 10.0], ids=["1.5x-limit", "dt=10"])
def test_dr_step_above_the_limit_is_cut(block, dt):
    s = DRSettings(dt_rule="power", dt_fraction=1.5, dt=dt, bracket_tolerance=0.01)
    dr = DynamicRelaxation(block, s)
    hist = dr.run()
    assert_clean(hist)
    assert dr.stats.cuts >= 1 and dr.dt < dr.dt_limit
    assert any("blow-up" in e for e in dr.stats.events)
    assert hist.collapse_multiplier == pytest.approx(S / A, rel=0.01)


def test_dr_step_above_the_limit_is_refused(block):
    s = DRSettings(dt_rule="power", dt_fraction=1.5, on_blowup="refuse")
    hist = DynamicRelaxation(block, s).run()
    assert_clean(hist)
    assert hist.status == "failed"
    assert hist.collapse_multiplier is None
    assert "blow-up" in hist.reason and "limit" in hist.reason


def test_dr_blow_up_during_the_load_steps_is_not_a_collapse():
    """A step above the limit met only under the live load (the dead load was relaxed with a
    stable step) must not end as a collapse multiplier."""
    model = on_base(builders.running_bond_wall(2, 2, 0.1, 0.2, 0.08, 20e3))
    dr = DynamicRelaxation(model, DRSettings(stability="current", dt_fraction=1.0))
    dr._step_for = lambda state: dr.dt if state.load_factor == 0.0 and not state.x.any() else 3.0
    hist = dr.run()
    assert_clean(hist)
    if hist.status == "collapse":  # the cuts brought the step back below the limit
        assert dr.stats.cuts >= 1
        static = StaticSolver(model).run()
        assert hist.collapse_multiplier == pytest.approx(static.collapse_multiplier, rel=0.01)


# ---------------------------------------------------------------------------- kn
def test_lambda_stable_as_dry_kn_grows_by_1e4():
    lams = []
    for kn in (1e8, 1e10, 1e12):
        model = on_base(
            builders.running_bond_wall(3, 4, 0.081, 0.21, 0.07, 20e3), kn=kn, left=["u1", "u3"]
        )
        hist = StaticSolver(model).run()
        assert_clean(hist)
        lams.append(hist.collapse_multiplier)
    lams = np.array(lams)
    assert np.ptp(lams) / lams[0] <= 0.01, lams


def test_dr_lambda_stable_as_dry_kn_grows():
    """DR's masses follow the stiffness, so its step count and answer barely move either."""
    lams = []
    for kn in (1e8, 1e10, 1e12):
        model = on_base(builders.single_block(A, B, S, 20e3), kn=kn)
        hist = DynamicRelaxation(model, DR_FAST).run()
        assert_clean(hist)
        lams.append(hist.collapse_multiplier)
    assert np.ptp(lams) / lams[0] <= 0.01, lams


# ---------------------------------------------------------------------------- friction
def test_zero_friction_slides_at_once():
    model = on_base(builders.single_block(A, B, 0.3, 20e3), friction=0.0, direction=(1, 0, 0))
    hs, hd = both(model)
    for hist, tol in ((hs, StaticSettings().tolerance), (hd, DR_FAST.tolerance)):
        assert hist.status == "collapse"
        # zero capacity: lambda is zero up to the residual tolerance (relative to |F| ~ W)
        assert 0.0 <= hist.collapse_multiplier <= 2 * tol


def test_tiny_friction():
    mu = 0.01
    model = on_base(builders.single_block(A, B, 0.3, 20e3), friction=mu, direction=(1, 0, 0))
    hs, hd = both(model)
    assert hs.collapse_multiplier == pytest.approx(mu, rel=0.01)
    assert hd.collapse_multiplier == pytest.approx(mu, rel=0.02)


# ---------------------------------------------------------------------------- reversal
def test_live_load_reversing_the_weight_lifts_the_block_at_one(block):
    """A live load pulling up: the net vertical force reverses at lambda = 1."""
    model = on_base(builders.single_block(A, B, S, 20e3), direction=(0.0, 1.0, 0.0))
    hs, hd = both(model)
    assert hs.collapse_multiplier == pytest.approx(1.0, rel=0.01)
    assert hd.collapse_multiplier == pytest.approx(1.0, rel=0.01)


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["push", "pull"])
def test_reversed_lateral_load_gives_the_mirror_answer(sign):
    model = on_base(builders.single_block(A, B, S, 20e3), direction=(0.0, 0.0, sign))
    hs, hd = both(model)
    assert hs.collapse_multiplier == pytest.approx(S / A, rel=0.005)
    assert hd.collapse_multiplier == pytest.approx(S / A, rel=0.01)
    assert np.sign(hs.last.q[0, 2]) == sign


# ---------------------------------------------------------------------------- random walls
@settings(
    max_examples=3,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    nx=st.integers(1, 3),
    nc=st.integers(1, 3),
    friction=st.sampled_from([0.3, 0.5, 0.7, 1.0]),
    left=st.sampled_from([None, ("u1", "u3")]),
    direction=st.sampled_from([(1.0, 0.0, 0.0), (0.0, 0.0, 1.0)]),
)
def test_random_small_walls_both_solvers_agree(nx, nc, friction, left, direction):
    blocks = builders.running_bond_wall(nx, nc, 0.081, 0.21, 0.07, 20e3)
    model = on_base(blocks, friction=friction, direction=direction, left=left and list(left))
    cap = 3.0  # a wall pushed against its support may never collapse
    hs, hd = both(
        model,
        StaticSettings(max_load_factor=cap),
        DRSettings(bracket_tolerance=0.01, max_load_factor=cap),
    )
    assert hs.status == hd.status, (hs.reason, hd.reason)
    if hs.status == "collapse":
        assert hd.collapse_multiplier == pytest.approx(hs.collapse_multiplier, rel=0.02, abs=1e-3)
