"""Newton's tangent at a kink of the law (``StaticSettings.kink_rounds``; docs/solvers.md,
"Newton's basin on walls that meet (session 19)").

Proves:

* the tangent :meth:`Corrector.kink_tangents` gives a joint on a kink is the derivative of
  the law on the side the step takes it to: on a single block on its base, with the bed
  joint's bending about y2 at its rocking capacity |m2| = |fn| l1 / 2 (1 + 1e-7), a step that
  turns it back (by a tenth of the rotation at capacity) gets the elastic bending stiffness, which a finite difference of the
  actions over that step reproduces to 1e-6 (the rocking tangent, zero, misses it by the
  whole of it); a step further into rocking changes no flag, so no tangent is replaced, and
  there the law's own tangent matches the finite difference; an elastic joint just inside
  the kink (1 - 1e-7), pushed over it, gets the rocking tangent (no bending stiffness);
* with the option on, a converged state is still an exact equilibrium of the law, so the
  closed forms hold within 1e-6 (a block tilts at s / a, a squat block slides at mu, a free
  wall tilts at t / H);
* a bad value is named;
* on a 3 x 13 panel with a free edge, the work searches that find no descent stop next to a
  kink of the law along their Newton direction (the merit falls up to it and not beyond).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest

from helpers.walls import tilted, tilted_panel
from masonry_dem.constitutive.law import LawResponse
from masonry_dem.constitutive.states import FLAG_ROCKING_2
from masonry_dem.geometry.builders import add_base, running_bond_wall, single_block
from masonry_dem.model import InterfaceMaterial, Model
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.solvers.static.corrector import Corrector
from masonry_dem.solvers.static.outcome import Failure
from masonry_dem.solvers.static.solver import StaticSolver

M2 = 4  # bending about y2 among the local actions [f1, f2, fn, m1, m2, m3]


def _block_at(over: float) -> tuple[Corrector, np.ndarray, float]:
    """A corrector of one block on its base, the block's DOFs q that put the bed joint's
    bending about y2 at ``over`` times its rocking capacity under a compression of the
    block's weight, and that joint's rotation at the capacity."""
    blocks, base = add_base(single_block(0.2, 0.25, 0.1, 20e3))
    corrector = Corrector(tilted(blocks, base))
    p = corrector.problem
    kbar = p.law.kbar[0]
    weight = 20e3 * 0.2 * 0.25 * 0.1
    rel = np.zeros(6)
    rel[2] = -weight / kbar[2]  # fn = -W
    capacity = weight * p.model.interfaces.l1[0] / 2.0  # |m2| <= (ft - fn) l1 / 2
    rel[M2] = over * capacity / kbar[M2]
    Hf = p.asm.H_free.toarray()  # 6 x 6: one joint, one free block
    q = np.zeros(p.model.n_dofs)
    q[p.asm.free_index] = np.linalg.solve(Hf, rel)
    return corrector, q, capacity / kbar[M2]


def _step(corrector: Corrector, rotation: float) -> np.ndarray:
    """The free DOFs' increment that turns the joint by ``rotation`` about y2 alone."""
    du = np.zeros(6)
    du[M2] = rotation
    return np.linalg.solve(corrector.problem.asm.H_free.toarray(), du)


def _difference(corrector: Corrector, q: np.ndarray, step: np.ndarray) -> np.ndarray:
    """(6,) the change of the joint's actions over ``step`` from q."""
    free = corrector.problem.asm.free_index
    moved = q.copy()
    moved[free] += step
    before = corrector.residual(q, 0.0)[2].actions[0]
    after = corrector.residual(moved, 0.0)[2].actions[0]
    return after - before


class _Across(NamedTuple):
    """The bed joint at ``over`` x its rocking capacity and a step that turns it by
    ``turn`` x its rotation at the capacity: the response there, the tangent
    :meth:`Corrector.kink_tangents` gives (None: no kink within the step), the joint's
    relative displacement over the step, the change of its actions (the law's own), its
    elastic stiffnesses and the corrector with its floor."""

    response: LawResponse
    sided: np.ndarray | None
    du: np.ndarray
    change: np.ndarray
    kbar: np.ndarray
    floor: float
    corrector: Corrector


def _across(over: float, turn: float) -> _Across:
    corrector, q, at_capacity = _block_at(over)
    response = corrector.residual(q, 0.0)[2]
    step = _step(corrector, turn * at_capacity)
    floor = corrector.settings.residual_stiffness
    return _Across(
        response,
        corrector.kink_tangents(q, 0.0, 1.0, step, response, floor, None),
        corrector.problem.relative(step)[0],
        _difference(corrector, q, step),
        corrector.problem.law.kbar[0],
        floor,
        corrector,
    )


def test_a_joint_turned_back_from_rocking_gets_its_elastic_tangent():
    x = _across(1.0 + 1e-7, -0.1)  # back into the elastic range
    assert x.response.flags[0] == FLAG_ROCKING_2
    assert x.sided is not None
    assert x.sided[0] == pytest.approx(np.diag(x.kbar * (1.0 + x.floor)), rel=1e-12)
    # the first 1e-6 of the step is on the rocking side
    assert (x.sided[0] @ x.du)[M2] == pytest.approx(x.change[M2], rel=2e-6)
    rocking = x.corrector.problem.joint_tangents(x.response, x.floor)[0]
    assert abs((rocking @ x.du)[M2] - x.change[M2]) > 0.99 * abs(x.change[M2])


def test_a_joint_pushed_further_into_rocking_keeps_the_law_tangent():
    x = _across(1.0 + 1e-7, 0.1)  # further into rocking: no kink on the way
    assert x.sided is None
    rocking = x.corrector.problem.joint_tangents(x.response, x.floor)[0]
    scale = x.kbar[M2] * abs(x.du[M2])
    # no moment change but the floor's: the rocking tangent is the derivative on this side
    assert x.change[M2] == pytest.approx(0.0, abs=1e-9 * scale)
    assert (rocking @ x.du)[M2] == pytest.approx(x.change[M2], abs=2e-9 * scale)


def test_an_elastic_joint_pushed_over_its_kink_gets_the_rocking_tangent():
    x = _across(1.0 - 1e-7, 0.1)
    assert x.response.flags[0] == 0
    assert x.sided is not None
    scale = x.kbar[M2] * abs(x.du[M2])
    # the moment rises over the first 1e-6 of the step, then stays at capacity
    assert abs(x.change[M2]) < 2e-6 * scale
    assert (x.sided[0] @ x.du)[M2] == pytest.approx(x.change[M2], abs=2e-6 * scale)
    elastic = x.corrector.problem.joint_tangents(x.response, x.floor)[0]
    assert (elastic @ x.du)[M2] == pytest.approx(x.kbar[M2] * x.du[M2], rel=1e-6)


def _collapse(model: Model) -> float:
    h = pushover(model, StaticSettings(kink_rounds=1))
    assert h.status == "collapse", h.reason
    return h.collapse_multiplier


def test_a_block_tilts_at_s_over_a_withkink_tangents():
    a, s = 0.2, 0.1
    blocks, base = add_base(single_block(a, 0.25, s, 20e3))
    assert _collapse(tilted(blocks, base)) == pytest.approx(s / a, rel=1e-6)


def test_a_squat_block_slides_at_mu_withkink_tangents():
    blocks, base = add_base(single_block(0.05, 0.25, 0.2, 20e3))  # s / a = 4 > mu
    material = InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.45)
    assert _collapse(tilted(blocks, base, material)) == pytest.approx(0.45, rel=1e-6)


def test_a_free_wall_tilts_at_t_over_h_withkink_tangents():
    a, s, courses = 0.081, 0.07, 9
    blocks, base = add_base(running_bond_wall(4, courses, a, 0.21, s, 20e3))
    lam = _collapse(tilted(blocks, base))
    assert lam == pytest.approx(s / (courses * a), rel=1e-6)


def test_a_bad_kink_rounds_is_named():
    with pytest.raises(ValueError, match="kink_rounds"):
        StaticSettings(kink_rounds=-1)
    assert StaticSettings().kink_rounds == 0  # off by default


def test_a_search_with_no_descent_stops_on_a_kink():
    """Each work search of the panel that fails with "no correction lowers the residual" is
    run again from its state (``benchmarks/newton_basin.py`` takes them apart). At the state
    where it stops, along the controlled Newton direction of its tangent, the merit does
    not fall at the full step, falls at some step of 8^-3 of it or shorter (the linear model
    holds up to there: measured 8^-4 to 8^-10), and, on 18 of the 19 (at least 90 %
    asserted), at the next longer step, where it no longer falls, some joint's flags have
    changed: the search stopped next to a kink of the law that the direction crosses. (On
    the 19th the merit rises at 8^-2 and 8^-3 with no change of state: the curved return
    of a sliding joint.)"""
    model = tilted_panel()
    solver = StaticSolver(model, StaticSettings())
    plain = solver.equilibrate
    failed = []

    def recording(*args, **kw):
        state = (solver.q.copy(), solver.plastic.copy(), solver.cracked.copy())
        out = plain(*args, **kw)
        if kw.get("control") is not None and out.failure == Failure.NO_DESCENT:
            failed.append((out, kw["control"], state))
        return out

    solver.equilibrate = recording  # type: ignore[method-assign]
    assert solver.run().status == "collapse"
    assert len(failed) >= 10
    p = solver.problem
    free = p.asm.free_index
    on_a_kink = 0
    for out, (c, goal, size), (_, plastic, cracked) in failed:
        solver.plastic, solver.cracked = plastic, cracked  # the law state of that search
        q, lam = out.q, float(out.load_factor)
        residual, _, response = solver.residual(q, lam)

        def merit(qq, ll, c=c, goal=goal, size=size):
            return solver.residual(qq, ll)[1] + abs(float(c @ qq[free]) - goal) / size

        lu = p.factor(response)
        dq = lu.solve(residual)
        live = lu.solve(p.F_live)
        dlam = (goal - float(c @ q[free]) - float(c @ dq)) / float(c @ live)
        dq = dq + dlam * live
        start = merit(q, lam)
        falls, flags = [], []
        for k in range(11):
            t = 8.0**-k
            qt = q.copy()
            qt[free] += t * dq
            falls.append(merit(qt, lam + t * dlam) < (1.0 - 1e-4 * t) * start)
            flags.append(
                bool(np.any(solver.residual(qt, lam + t * dlam)[2].flags != response.flags))
            )
        assert not falls[0]
        first = falls.index(True)  # the longest step that lowers the merit
        assert first >= 3
        on_a_kink += flags[first - 1]  # beyond that step a joint has crossed a kink
    assert on_a_kink >= 0.9 * len(failed)
