"""Loose blocks solved apart (``StaticSettings.loose_blocks``; docs/solvers.md, "Loose blocks
solved apart (session 20)").

Proves:

* the detector's measure is the smallest eigenvalue of a block's own tangent block relative
  to its elastic block: exactly 1 for a block on an elastic bed joint, and below the
  threshold (the block is found) for a block on a joint rocking about y2, which keeps no
  bending stiffness; no block of an elastic wall under its dead load is loose;
* the local solve puts such a block back in equilibrium: the block at 1.5 x its rocking
  capacity under its own weight alone (lambda 0) returns to rest, its residual at the
  tolerance, every other DOF held; past its tilting load factor (no equilibrium: a local
  mechanism) it is left where it was;
* with either mode on, a converged state is still an exact equilibrium of the law, so the
  closed forms hold within 1e-6 (a block tilts at s / a, a squat block slides at mu, a free
  wall tilts at t / H);
* replayed from the same states, the rescue and the fallback converge every search of a
  3 x 13 panel with a free edge that the default converges, and more;
* a bad value is named, and the option is off by default.
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers.walls import tilted, tilted_panel, tilted_wall
from masonry_dem.geometry.builders import add_base, running_bond_wall, single_block
from masonry_dem.model import InterfaceMaterial
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.solvers.static.corrector import Corrector
from masonry_dem.solvers.static.solver import StaticSolver

M2 = 4  # bending about y2 among the local actions [f1, f2, fn, m1, m2, m3]
A, S = 0.2, 0.1  # the block's height and thickness: it tilts at S / A


def _block_at(over: float, mode: str = "rescue") -> tuple[Corrector, np.ndarray]:
    """A corrector of one block on its base and the block's DOFs q that put the bed joint's
    bending about y2 at ``over`` times its rocking capacity, under a compression of the
    block's weight."""
    blocks, base = add_base(single_block(A, 0.25, S, 20e3))
    corrector = Corrector(tilted(blocks, base), StaticSettings(loose_blocks=mode))
    p = corrector.problem
    kbar = p.law.kbar[0]
    weight = 20e3 * A * 0.25 * S
    rel = np.zeros(6)
    rel[2] = -weight / kbar[2]  # fn = -W
    capacity = weight * p.model.interfaces.l1[0] / 2.0  # |m2| <= (ft - fn) l1 / 2
    rel[M2] = over * capacity / kbar[M2]
    q = np.zeros(p.model.n_dofs)
    q[p.asm.free_index] = np.linalg.solve(p.asm.H_free.toarray(), rel)
    return corrector, q


def test_a_block_on_an_elastic_joint_keeps_all_its_stiffness():
    corrector, q = _block_at(0.5)
    response = corrector.residual(q, 0.0)[2]
    assert response.flags[0] == 0
    weakest = corrector.loose.weakest(response)
    assert weakest[0] == pytest.approx(1.0, rel=1e-12)
    assert np.isinf(weakest[1])  # the base: held
    assert corrector.loose.detect(response).size == 0


def test_a_block_on_a_rocking_joint_is_loose():
    corrector, q = _block_at(1.5)
    response = corrector.residual(q, 0.0)[2]
    assert response.flags[0] != 0  # rocking
    assert corrector.loose.weakest(response)[0] < corrector.settings.loose_stiffness
    assert list(corrector.loose.detect(response)) == [0]


def test_no_block_of_an_elastic_wall_is_loose():
    model, _ = tilted_wall()
    corrector = Corrector(model, StaticSettings(loose_blocks="rescue"))
    out = corrector.equilibrate(0.0)
    assert out.ok
    assert corrector.loose.detect(out.response).size == 0
    assert corrector.loose.weakest(out.response).min() > 0.1


def test_the_local_solve_puts_a_rocking_block_back_at_rest():
    corrector, q = _block_at(1.5)
    response = corrector.residual(q, 0.0)[2]
    before = corrector.residual(q, 0.0)[1]
    done = corrector.eliminate(q, 0.0, 1.0, response, corrector.settings.residual_stiffness)
    assert done is not None
    assert list(done.blocks) == [0]
    assert before > 0.1
    assert done.rnorm <= corrector.settings.tolerance
    assert (done.solved, done.improved, done.left) == (1, 0, 0)
    assert done.response.flags[0] == 0  # back in the elastic range
    assert corrector.local_factorizations <= corrector.settings.loose_iterations


def test_a_block_with_no_local_equilibrium_is_left_where_it_was():
    corrector, q = _block_at(1.5)
    lam = 1.2 * S / A  # past the tilt: the block falls
    response = corrector.residual(q, lam)[2]
    done = corrector.eliminate(q, lam, 1.0, response, corrector.settings.residual_stiffness)
    assert done is not None
    assert (done.solved, done.left) == (0, 1)
    assert np.array_equal(done.q, q)


def _collapse(model, mode: str) -> float:
    h = pushover(model, StaticSettings(loose_blocks=mode))
    assert h.status == "collapse", h.reason
    return h.collapse_multiplier


@pytest.mark.parametrize("mode", ["rescue", "iterate", "fallback"])
def test_a_block_tilts_at_s_over_a_with_loose_blocks_solved_apart(mode):
    blocks, base = add_base(single_block(A, 0.25, S, 20e3))
    assert _collapse(tilted(blocks, base), mode) == pytest.approx(S / A, rel=1e-6)


@pytest.mark.parametrize("mode", ["rescue", "iterate", "fallback"])
def test_a_squat_block_slides_at_mu_with_loose_blocks_solved_apart(mode):
    blocks, base = add_base(single_block(0.05, 0.25, 0.2, 20e3))  # s / a = 4 > mu
    material = InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.45)
    assert _collapse(tilted(blocks, base, material), mode) == pytest.approx(0.45, rel=1e-6)


@pytest.mark.parametrize("mode", ["rescue", "iterate", "fallback"])
def test_a_free_wall_tilts_at_t_over_h_with_loose_blocks_solved_apart(mode):
    a, s, courses = 0.081, 0.07, 9
    blocks, base = add_base(running_bond_wall(4, courses, a, 0.21, s, 20e3))
    lam = _collapse(tilted(blocks, base), mode)
    assert lam == pytest.approx(s / (courses * a), rel=1e-6)


def test_a_bad_loose_blocks_setting_is_named():
    with pytest.raises(ValueError, match="loose_blocks"):
        StaticSettings(loose_blocks="always")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="loose_stiffness"):
        StaticSettings(loose_stiffness=0.0)
    with pytest.raises(ValueError, match="loose_iterations"):
        StaticSettings(loose_iterations=0)
    assert StaticSettings().loose_blocks == "off"


def _recorded(model, settings: StaticSettings) -> list:
    """Every Newton search of the pushover of ``model``: (args, kwargs, the state before
    it: q, plastic part, cracked joints, last increment; converged?)."""
    solver = StaticSolver(model, settings)
    plain = solver.equilibrate
    calls = []

    def recording(*args, **kw):
        state = (solver.q.copy(), solver.plastic.copy(), solver.cracked.copy())
        state += (solver.last_increment,)
        out = plain(*args, **kw)
        calls.append((args, kw, state, out.ok))
        return out

    solver.equilibrate = recording  # type: ignore[method-assign]
    assert solver.run().status == "collapse"
    return calls


def _replayed(model, settings: StaticSettings, calls: list) -> list[bool]:
    """Each recorded search run again from its state with ``settings``: converged?"""
    solver = StaticSolver(model, StaticSettings())
    solver.run()  # the path's scales and limits, as the recorded run set them
    solver.settings = settings
    done = []
    for args, kw, (q, plastic, cracked, last), _ in calls:
        solver.q, solver.plastic, solver.cracked = q.copy(), plastic.copy(), cracked.copy()
        solver.last_increment = last
        out = solver.equilibrate(*args, **kw)
        if out.ok:  # an exact equilibrium of the law
            assert solver.residual(out.q, out.load_factor)[1] <= solver.settings.tolerance
        done.append(out.ok)
    return done


def test_the_rescue_converges_searches_that_fail_by_default():
    """The 3 x 13 panel with a free edge (46 searches, 22 failed by default): replayed from
    the same states, the rescue and the fallback converge each search the default
    converged, and more (measured: 24 -> 25 with the rescue, 27 with the fallback)."""
    model = tilted_panel()
    calls = _recorded(model, StaticSettings())
    default = [ok for *_, ok in calls]
    assert not all(default)
    for mode in ("rescue", "fallback"):
        rescued = _replayed(model, StaticSettings(loose_blocks=mode), calls)
        assert all(r for r, d in zip(rescued, default, strict=True) if d)
        assert sum(rescued) > sum(default)
