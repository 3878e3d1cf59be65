"""The limit analysis with a cohesion of its own (c > mu ft): closed forms on every backend.

The strength domain of a joint: ``|shear| <= c A - mu fn`` (fn tension-positive), capped by
``fn <= ft A``. Sliding with no rocking possible costs ``c A + mu N``; rocking opens the joint
at its tension cap, which a cohesion does not raise; the pushover stays within the bound.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from helpers.walls import JOINT_HEIGHT, JOINT_LENGTH, JOINT_LOAD, JOINT_WIDTH, pushed_joint
from masonry_dem.export.analyses import pushover
from masonry_dem.geometry.builders import add_base, single_block
from masonry_dem.model import (
    InterfaceMaterial,
    Model,
    PointLoad,
    SelfWeight,
    Support,
    WeightProportional,
)
from masonry_dem.solvers.limit_analysis import backends, dem_upper_bound, limit_analysis
from masonry_dem.solvers.limit_analysis.backends import _static_clarabel
from masonry_dem.solvers.limit_analysis.formulation import Problem, associative_columns

#: every backend and form: HiGHS's pyramid and Clarabel's exact cone, associative or not
#: (HiGHS's non-associative both by column generation and in full)
EVERY = [
    dict(backend="highs"),
    dict(backend="clarabel"),
    dict(backend="highs", associative=False),
    dict(backend="highs", associative=False, column_generation=False),
    dict(backend="clarabel", associative=False),
]
#: a wide flat block (0.1 high on a 0.4 x 0.2 joint) under a dead load N, pushed along x
A_, B, S, N = JOINT_HEIGHT, JOINT_LENGTH, JOINT_WIDTH, JOINT_LOAD


_pushed = pushed_joint


def _lam(model: Model, **kw) -> float:
    r = limit_analysis(model, **kw)
    assert r.status == "collapse", r.reason
    return r.load_factor


@pytest.mark.parametrize("kw", EVERY)
def test_a_cohesive_block_slides_at_c_a_plus_mu_n(kw):
    """Lourenco's joint (mu 0.75, ft 0.16 MPa, c 0.224 MPa > mu ft = 0.12 MPa): rocking needs
    lambda (a/2) = (N + ft A) l/2, far above sliding (the block is four times wider than
    high), so it slides at lambda = c A + mu N = 17 920 + 15 000 N (the pushover's 32 920 N,
    ``test_cohesive_sliding``)."""
    mu, ft, c = 0.75, 0.16e6, 0.224e6
    expected = c * B * S + mu * N
    assert (N + ft * B * S) * B / A_ > expected  # rocking costs more
    assert _lam(_pushed(mu, ft, c), **kw) == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("kw", EVERY)
@pytest.mark.parametrize("ft", [0.0, 0.05e6])
def test_pure_cohesion_slides_at_c_a(kw, ft):
    """mu = 0: the shear strength is the cohesion alone, c A = 8 000 N whatever the
    compression (and whatever the tensile strength: ft <= c / mu holds for any)."""
    c = 0.1e6
    assert _lam(_pushed(0.0, ft, c), **kw) == pytest.approx(c * B * S, rel=1e-6)


@pytest.mark.parametrize("kw", EVERY)
def test_the_papers_cohesion_given_is_the_default(kw):
    """c = mu ft given: the paper's cone, the same multiplier (bit for bit: no cohesive
    term is built where c - mu ft is zero)."""
    paper = _pushed(0.75, 0.16e6, None)
    given = replace(paper, cohesion=np.full(paper.interfaces.count, 0.75 * 0.16e6))
    assert _lam(given, **kw) == _lam(paper, **kw)
    assert _lam(paper, **kw) == pytest.approx(0.75 * (0.16e6 * B * S + N), rel=1e-6)


def _rocking() -> tuple[Model, float, float]:
    """A block a high, s thick, on a base with ft 2 kPa and c 20 kPa (mu ft = 1.2 kPa),
    tilted out of plane: it turns about its front edge, the joint open at its tension cap
    over the whole area, when lambda W a/2 = (W + ft A) s/2: lambda = s (W + ft A) / (W a)
    = 0.3125 (W = 240 N, ft A = 60 N). Sliding would need (c A + mu W) / W = 3.1. A shifted
    cone with no cap (tension up to c / mu) would give s (W + (c / mu) A) / (W a) = 1.29."""
    a, b, s, mu, ft, c = 0.4, 0.3, 0.1, 0.6, 2e3, 2e4
    blocks, base = add_base(single_block(a, b, s, 2e4))
    material = InterfaceMaterial(kn=1e9, kt=4e8, friction=mu, tensile_strength=ft, cohesion=c)
    model = Model.build(
        blocks, material, [Support([base])], [SelfWeight(), WeightProportional((0.0, 0.0, 1.0))]
    )
    W, A = float(model.blocks.weights[0]), b * s
    assert (c * A + mu * W) / W > 3.0
    return model, s * (W + ft * A) / (W * a), s * (W + c / mu * A) / (W * a)


@pytest.mark.parametrize("kw", EVERY)
def test_rocking_opens_the_joint_at_its_tension_cap(kw):
    model, expected, uncapped = _rocking()
    lam = _lam(model, **kw)
    assert lam == pytest.approx(expected, rel=1e-6)
    assert uncapped > 4 * lam


def test_the_static_clarabel_form_agrees():
    """The static SOCP (Clarabel's fallback where its kinematic form stalls) carries the
    cohesive shear as an offset of each point's cone: the same closed forms."""
    for model, expected in [
        (_pushed(0.75, 0.16e6, 0.224e6), 0.224e6 * B * S + 0.75 * N),
        (_pushed(0.0, 0.05e6, 0.1e6), 0.1e6 * B * S),
        (_rocking()[0], _rocking()[1]),
    ]:
        problem = Problem.of(model)
        R, K = associative_columns(model, 2, None)
        sol = _static_clarabel(problem, R, K, 2, "forced")
        assert sol.status == "optimal", sol.detail
        assert sol.lam == pytest.approx(expected, rel=1e-6)


def test_the_normal_equations_leave_a_cohesive_model_to_clarabel(monkeypatch):
    """The normal-equation interior point method has one cone per point, the slip's: a
    model with a cohesion of its own goes to Clarabel's kinematic form at any size."""
    calls = []
    monkeypatch.setattr(backends, "NORMAL_EQUATIONS_FROM", 0)
    monkeypatch.setattr(backends, "solve_kinematic_normal", lambda *a, **k: calls.append(1) or None)
    mu, ft, c = 0.75, 0.16e6, 0.224e6
    lam = _lam(_pushed(mu, ft, c), backend="clarabel")
    assert lam == pytest.approx(c * B * S + mu * N, rel=1e-6)
    assert calls == []
    _lam(_pushed(mu, ft, None), backend="clarabel")
    assert calls == [1]  # the paper's cohesion: the normal equations are tried


def test_the_statics_carry_the_cohesive_shear():
    """At collapse the joint's actions balance the load: shear c A + mu N, normal -N (the
    kinematic form's duals, the cohesive cones' included)."""
    mu, ft, c = 0.75, 0.16e6, 0.224e6
    for kw in EVERY[:2]:
        r = limit_analysis(_pushed(mu, ft, c), **kw)
        f = r.interface_actions[0]
        shear = float(np.hypot(f[0], f[1]))
        assert shear == pytest.approx(c * B * S + mu * N, rel=1e-6)
        assert f[2] == pytest.approx(-N, rel=1e-6)


@pytest.mark.parametrize("case", ["sliding", "rocking"])
def test_the_pushover_stays_within_the_bound(case):
    """The pushover of a cohesive model collapses within the associative bound (the exact
    cone, the friction enlarged to hold the DEM's domain): the certificate's "within"."""
    model = _pushed(0.75, 0.16e6, 0.224e6) if case == "sliding" else _rocking()[0]
    bound = dem_upper_bound(model)
    assert bound.status == "collapse", bound.reason
    history = pushover(model, bound=bound.load_factor)
    assert history.status == "collapse"
    assert history.certificate.bound_status == "within"
    expected = (0.224e6 * B * S + 0.75 * N) if case == "sliding" else _rocking()[1]
    assert history.collapse_multiplier == pytest.approx(expected, rel=0.02)


def test_a_twist_dissipates_the_cohesion_by_the_mean_distance():
    """A square block (0.3 x 0.3 joint, mu = 0, ft = 0, cohesion c) turned about the joint's
    normal by a live couple: the pure cohesion resists the twist with c A times the mean
    distance from the centre, cT (``torsion_constant``), lambda = c A cT. The cohesion's
    own grid (8 x 8, whatever the friction's: ``cohesive_grid``) is within 1 % of it, on the
    safe side for a bound (above); the corners alone would take the corner distance, 85 %
    above."""
    from masonry_dem.constitutive import torsion_constant

    l, c = 0.3, 1.0e4
    blocks, base = add_base(single_block(0.2, l, l, 2e4))
    material = InterfaceMaterial(kn=1e9, kt=4e8, friction=0.0, tensile_strength=0.0, cohesion=c)
    model = Model.build(
        blocks,
        material,
        [Support([base])],
        [  # a unit couple about the vertical: +-x forces 0.5 m either side along z
            SelfWeight(),
            PointLoad([0], (1.0, 0.0, 0.0), (0.0, 0.0, 0.5), live=True),
            PointLoad([0], (-1.0, 0.0, 0.0), (0.0, 0.0, -0.5), live=True),
        ],
    )
    exact = c * l * l * float(torsion_constant(l, l))
    # the circumscribed pyramid's section reaches 1 / cos(pi / 8) beyond the circle between
    # its face normals (a twist slides every way)
    for kw, over in [(EVERY[0], 1 / np.cos(np.pi / 8)), (EVERY[1], 1.0)]:
        r = limit_analysis(model, **kw)
        assert r.status == "collapse", r.reason
        assert r.grid == 2  # the friction's: its corners are exact
        assert exact <= r.load_factor <= 1.01 * over * exact
        # a finer friction grid: the same cohesive points, the same multiplier
        assert _lam(model, grid=4, **kw) == pytest.approx(r.load_factor, rel=1e-6)


def test_without_dilatancy_a_cohesive_joint_twists_at_c_a_plus_mu_n_times_ct():
    """The same twist with friction (mu 0.5, ft 1 kPa, c 10 kPa > mu ft): zero dilatancy
    keeps the compression the weight W, spread uniformly (Figure 10), and the rest of the
    joint at its cap carries (c - mu ft) A over the whole joint, so the twist costs
    (mu (W + ft A) + (c - mu ft) A) cT = (c A + mu W) cT = 123.96 N m: the 8 x 8 rule within
    1 % above (124.18); the pyramid by up to 1 / cos(pi / 8) more (130.43)."""
    from masonry_dem.constitutive import torsion_constant

    l, mu, ft, c = 0.3, 0.5, 1e3, 1.0e4
    blocks, base = add_base(single_block(0.2, l, l, 2e4))
    material = InterfaceMaterial(kn=1e9, kt=4e8, friction=mu, tensile_strength=ft, cohesion=c)
    model = Model.build(
        blocks,
        material,
        [Support([base])],
        [
            SelfWeight(),
            PointLoad([0], (1.0, 0.0, 0.0), (0.0, 0.0, 0.5), live=True),
            PointLoad([0], (-1.0, 0.0, 0.0), (0.0, 0.0, -0.5), live=True),
        ],
    )
    W = float(model.blocks.weights[0])
    exact = (c * l * l + mu * W) * float(torsion_constant(l, l))
    clarabel = _lam(model, backend="clarabel", associative=False)
    assert exact <= clarabel <= 1.01 * exact
    for kw in EVERY[2:4]:
        assert exact <= _lam(model, **kw) <= 1.01 * exact / np.cos(np.pi / 8)


def test_with_no_backend_given_a_cohesion_of_its_own_chooses_clarabel():
    """A small model goes to HiGHS, unless its joints have a cohesion above mu ft: their
    cohesive points cost the pyramid columns and rows, Clarabel's cone one each."""
    from masonry_dem.solvers.limit_analysis.analysis import choose_backend

    dry, cohesive = _pushed(0.75, 0.0, None), _pushed(0.75, 0.0, 2e3)
    assert choose_backend(dry) == "highs"
    assert choose_backend(cohesive) == "clarabel"
    assert choose_backend(cohesive, "inscribed") == "highs"  # a cone named is obeyed
