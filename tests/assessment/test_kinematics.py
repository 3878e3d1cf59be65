"""The kinematic analysis of a mechanism against closed forms (issue 38, items 1 and 2): a
rigid block b x h rocking about its toe, a free-standing wall, a two-block chain worked by
hand. Every expected value below is written from the mechanics, never from the package."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from helpers.case_files import SINGLE_BLOCK
from masonry_dem.assessment.checks import Building, assess
from masonry_dem.assessment.kinematics import Mechanism, hinged_mode, support_drift
from masonry_dem.assessment.spectra import NTC2018Spectrum
from masonry_dem.cases.casefile import case_from_dict

G = 9.81
TOL = 1e-9


def _model(geometry: dict, supports=None):
    data = {
        **SINGLE_BLOCK,
        "geometry": {**SINGLE_BLOCK["geometry"], **geometry},
        "supports": supports or [{"select": "base"}],
    }
    return case_from_dict(data).model


def _rotation_about(centres, axis_point, theta=1.0):
    """Mode (n, 6): every block turning by theta about the line along e1 through
    ``axis_point`` (y, z), the top moving towards +e3."""
    w = np.array([theta, 0.0, 0.0])
    arm = centres - np.array([0.0, *axis_point])
    u = np.cross(w, arm)
    return np.hstack([u, np.tile(w, (len(centres), 1))])


# ----------------------------------------------------------------------------- one block
@pytest.fixture(scope="module")
def block():
    model = _model({})
    wall = np.flatnonzero(~model.fixed.any(axis=1))
    assert wall.size == 1
    b = int(wall[0])
    h, t = model.blocks.sizes[b, 1], model.blocks.sizes[b, 2]
    # the DEM's mode: the block turning about the centre line of its base joint (y = 0, z = t/2)
    mode = np.zeros((model.blocks.count, 6))
    mode[b] = _rotation_about(model.blocks.centres[[b]], (0.0, t / 2), 0.37)[0]
    hinged, residual = hinged_mode(model, mode)
    return model, b, h, t, mode, hinged, residual


def test_hinged_mode_turns_the_block_about_its_toe(block):
    model, b, h, t, mode, hinged, residual = block
    toe = _rotation_about(model.blocks.centres[[b]], (0.0, t), 0.37)[0]
    assert residual < TOL
    assert np.abs(hinged[b] - toe).max() < TOL


def test_block_alpha0_mass_and_participation(block):
    model, b, h, t, _, hinged, _ = block
    mech = Mechanism.of(model, hinged)
    W = t * h * model.blocks.sizes[b, 0] * 20e3
    assert mech.alpha_rigid == pytest.approx(t / h, rel=TOL, abs=0)
    m_star, e_star = mech.participating_mass()
    assert m_star == pytest.approx(W / G, rel=TOL)
    assert e_star == pytest.approx(1.0, rel=TOL)
    assert mech.total_weight == pytest.approx(W, rel=TOL)


def test_block_alpha_in_finite_rotation(block):
    """alpha(theta) = (t cos th - h sin th) / (h cos th + t sin th) = tan(atan(t/h) - th):
    the moments of W and alpha W about the toe with the centroid turned by th."""
    model, b, h, t, _, hinged, _ = block
    mech = Mechanism.of(model, hinged)
    curve = mech.capacity_curve()
    theta = 0.37 * curve.s
    closed = (t * np.cos(theta) - h * np.sin(theta)) / (h * np.cos(theta) + t * np.sin(theta))
    assert np.abs(curve.alpha - closed).max() < TOL
    # alpha = 0 when the centroid is above the toe: theta0 = atan(t/h), the centroid moved t/2
    assert 0.37 * curve.s[-1] == pytest.approx(math.atan(t / h), rel=TOL)
    assert curve.d_k0 == pytest.approx(t / 2, rel=TOL)
    assert curve.d0_star == pytest.approx(t / 2, rel=TOL)  # e* = 1
    # the top of the block (its face's centre, at z = t/2, y = h) at theta0:
    # (-t/2)(cos th0 - 1) + h sin th0 = t/2 + t h / (2 sqrt(t^2 + h^2))
    top = model.blocks.centres[b] + np.array([0.0, h / 2, 0.0])
    moved = mech.positions(top[None], [b], curve.s[-1])[0, 0]
    assert moved[2] - top[2] == pytest.approx(t / 2 + t * h / (2 * math.hypot(t, h)), rel=TOL)
    assert moved[1] - top[1] == pytest.approx(
        -(-t / 2) * math.sin(math.atan(t / h)) + h * (math.cos(math.atan(t / h)) - 1), rel=TOL
    )


def test_block_checks_in_closed_form(block):
    """a0* = (t/h) g / FC; d_u* = 0.4 t/2, d_s* = 0.4 d_u*, Ts = 2 pi sqrt(d_s*/a_s*) with
    a_s* = alpha(theta_s) g / FC, theta_s where the centroid moved d_s*; NTC soil A: the
    demand ag g / q and SDe(Ts) on the 1/T branch."""
    model, b, h, t, _, hinged, _ = block
    FC, q, ag, F0, Tc = 1.35, 2.0, 0.2, 2.4, 0.35
    out, _ = assess(
        Mechanism.of(model, hinged),
        "ntc2018",
        NTC2018Spectrum(ag, F0, Tc),
        q=q,
        FC=FC,
        nonlinear_check="circolare_2009",  # the 2009 form (2019's: test_assess_circolare2019.py)
    )
    assert out.a0_star == pytest.approx(t / h * G / FC, rel=TOL)
    assert out.demand == pytest.approx(ag * G / q, rel=TOL)
    assert out.ratio == pytest.approx(t / h / FC / (ag / q), rel=TOL)
    du, ds = 0.4 * t / 2, 0.16 * t / 2
    theta_s = brentq(
        lambda th: (t / 2) * (1 - math.cos(th)) + (h / 2) * math.sin(th) - ds, 0, 1, xtol=1e-15
    )
    a_s = math.tan(math.atan(t / h) - theta_s) * G / FC
    Ts = 2 * math.pi * math.sqrt(ds / a_s)
    assert out.du_star == pytest.approx(du, rel=TOL)
    assert out.Ts == pytest.approx(Ts, rel=TOL)
    assert 0.35 < Ts < 2.4 + 4 * ag  # Tc < Ts < TD: Se = ag g F0 Tc / Ts
    SDe = ag * G * F0 * Tc / Ts * (Ts / (2 * math.pi)) ** 2
    assert out.displacement_demand == pytest.approx(SDe, rel=TOL)
    assert out.passes_nonlinear == (du >= SDe)
    np.testing.assert_allclose(out.control_point, model.blocks.centres[b], atol=TOL)


# ----------------------------------------------------------------------------- free-standing wall
@pytest.mark.parametrize("courses", [3, 8])
def test_free_standing_wall(courses):
    """A running-bond wall of N courses on a base, tipping as one body about its toe:
    alpha0 = t/H, e* = 3N^2 / (4N^2 - 1) (courses of equal weight at heights (k + 1/2) a),
    alpha(theta) = tan(atan(t/H) - theta), d_k0 = t/2 at the centroid."""
    model = _model(
        {
            "builder": "running_bond_wall",
            "blocks_along_length": 3,
            "courses": courses,
            "a": 0.081,
            "b": 0.21,
            "s": 0.07,
        }
    )
    t, a = 0.07, 0.081
    H = courses * a
    wall = ~model.fixed.any(axis=1)
    mode = np.zeros((model.blocks.count, 6))
    mode[wall] = _rotation_about(model.blocks.centres[wall], (0.0, t / 2))  # the DEM's
    hinged, residual = hinged_mode(model, mode)
    assert residual < TOL
    toe = _rotation_about(model.blocks.centres[wall], (0.0, t))
    assert np.abs(hinged[wall] - toe).max() < TOL
    mech = Mechanism.of(model, hinged)
    assert mech.moving.sum() == wall.sum()
    assert mech.alpha_rigid == pytest.approx(t / H, rel=TOL)
    m_star, e_star = mech.participating_mass()
    W = float(model.blocks.weights[wall].sum())
    assert e_star == pytest.approx(3 * courses**2 / (4 * courses**2 - 1), rel=TOL)
    assert m_star == pytest.approx(e_star * W / G, rel=TOL)
    curve = mech.capacity_curve()
    assert np.abs(curve.alpha - np.tan(math.atan(t / H) - curve.s)).max() < TOL
    assert curve.d_k0 == pytest.approx(t / 2, rel=TOL)
    assert curve.d0_star == pytest.approx(t / 2 / e_star, rel=TOL)


# ----------------------------------------------------------------------------- two blocks
def _two_block_chain():
    model = _model({"builder": "stack_bond_column", "courses": 2})
    c = model.blocks.centres
    lower, upper = (int(np.flatnonzero(np.isclose(c[:, 1], y))[0]) for y in (0.2, 0.6))
    mode = np.zeros((model.blocks.count, 6))
    mode[lower] = [0, 0.1, 0.2, 1, 0, 0]
    mode[upper] = [0, 0.2, 0.8, 2, 0, 0]
    return model, mode, (lower, upper)


def test_two_block_chain_by_hand():
    """Two blocks t = 0.2, h = 0.4, b = 0.3 stacked: the lower turns by th1 = 1 about its
    toe (y = 0, z = t), the upper by th2 = 2 about the front edge of their joint (y = 0.4,
    z = t), which moves with the lower block. Centroids' virtual displacements:
    lower dx = th1 h/2 = 0.2, dy = th1 t/2 = 0.1; upper dx = th1 h + th2 h/2 = 0.8,
    dy = th2 t/2 = 0.2. With W = 20e3 x 0.3 x 0.4 x 0.2 = 480 N each:
    alpha0 = (0.1 + 0.2) / (0.2 + 0.8) = 0.3; M* = W (0.2 + 0.8)^2 / (g (0.04 + 0.64))
    = W / (0.68 g); e* = g M* / 2W = 1 / 1.36; a0* = 0.3 g / (e* FC) = 0.408 g / FC."""
    model, mode, _ = _two_block_chain()
    hinged, residual = hinged_mode(model, mode)  # a compatible chain: left as it is
    assert residual < TOL
    assert np.abs(hinged - mode).max() < TOL
    mech = Mechanism.of(model, mode)
    W = 480.0
    assert mech.alpha_rigid == pytest.approx(0.3, rel=TOL)
    m_star, e_star = mech.participating_mass()
    assert m_star == pytest.approx(W / (0.68 * G), rel=TOL)
    assert e_star == pytest.approx(1 / 1.36, rel=TOL)
    FC = 1.35
    out, _ = assess(mech, "ntc2018", NTC2018Spectrum(0.1), FC=FC)
    assert out.a0_star == pytest.approx(0.408 * G / FC, rel=TOL)
    assert out.M_star == pytest.approx(W / (0.68 * G), rel=TOL)
    # the control point: the centroid of the two weights, at y = 0.4
    np.testing.assert_allclose(out.control_point, [0.15, 0.4, 0.1], atol=TOL)


def test_alpha0_of_the_analysis_keeps_the_joints_work():
    """With alpha0 above the loads' own (the joints did work at collapse), alpha(s) is
    alpha_rigid(s) + (alpha0 - alpha_rigid(0)) W_live(0) / W_live(s); for the block,
    W_live(s) = W (h cos th + t sin th)/2 th' and so the shift goes as h / (h cos + t sin)."""
    model = _model({})
    b = int(np.flatnonzero(~model.fixed.any(axis=1))[0])
    h, t = 0.4, 0.2
    mode = np.zeros((model.blocks.count, 6))
    mode[b] = _rotation_about(model.blocks.centres[[b]], (0.0, t))[0]
    mech = Mechanism.of(model, mode)
    s = np.linspace(0, 0.3, 7)
    got = mech.alpha(s, alpha0=0.6)
    rigid = np.tan(math.atan(t / h) - s)
    shift = 0.1 * h / (h * np.cos(s) + t * np.sin(s))
    assert np.abs(got - (rigid + shift)).max() < TOL


def test_a_load_not_proportional_to_the_weights_is_refused():
    """A live point force on one of two blocks is no seismic load: refused by name."""
    data = {
        **SINGLE_BLOCK,
        "geometry": {**SINGLE_BLOCK["geometry"], "builder": "stack_bond_column", "courses": 2},
        "loads": [
            {"type": "self_weight"},
            {"type": "point", "select": "course:1", "force": [0, 0, 5.0], "live": True},
        ],
    }
    model = case_from_dict(data).model
    mode = np.zeros((model.blocks.count, 6))
    mode[:, 2] = 1.0
    with pytest.raises(ValueError, match="proportional to the weights"):
        Mechanism.of(model, mode)


def _one_block_at_height(**options):
    """The first free block of the test wall rocking, assessed at Z = 6 m of a 9 m, 3-storey
    building (T1 = 0.3 s) on NTC soil A (ag 0.2, F0 2.4, Tc* 0.35), q = 2."""
    model = _model({})
    b = int(np.flatnonzero(~model.fixed.any(axis=1))[0])
    mode = np.zeros((model.blocks.count, 6))
    mode[b] = _rotation_about(model.blocks.centres[[b]], (0.0, 0.2))[0]
    out, _ = assess(
        Mechanism.of(model, mode),
        "ntc2018",
        NTC2018Spectrum(0.2, 2.4, 0.35),
        Building(Z=6.0, H=9.0, storeys=3, T1=0.3),
        q=2.0,
        **options,
    )
    return out


def test_a_mechanism_at_height_takes_the_larger_demand():
    """NTC, the Circolare 2009 form: at Z = 6 m of H = 9 m, N = 3, T1 = 0.3 s on soil A (ag
    0.2, F0 2.4, Tc* 0.35): Se(T1) on the plateau = 0.2 g 2.4; psi = 2/3, gamma = 9/7;
    demand Se psi gamma / q."""
    out = _one_block_at_height(demand_at_height="circolare_2009", nonlinear_check="circolare_2009")
    assert out.demand_at_height == "circolare_2009"
    assert out.demand_ground == pytest.approx(0.2 * G / 2, rel=TOL)
    assert out.demand_height == pytest.approx(0.2 * G * 2.4 * (2 / 3) * (9 / 7) / 2, rel=TOL)
    assert out.demand == out.demand_height
    # nonlinear at height: max(SDe(Ts), SDe(T1) psi gamma r^2 / sqrt((1 - r)^2 + 0.02 r)),
    # r = Ts/T1, Ts on the 1/T branch, T1 on the plateau
    Ts = out.Ts
    assert 0.35 < Ts < 2.4
    ground = 0.2 * G * 2.4 * 0.35 / Ts * (Ts / (2 * math.pi)) ** 2
    r = Ts / 0.3
    height = (
        0.2
        * G
        * 2.4
        * (0.3 / (2 * math.pi)) ** 2
        * (2 / 3)
        * (9 / 7)
        * r**2
        / math.sqrt((1 - r) ** 2 + 0.02 * r)
    )
    assert out.displacement_demand == pytest.approx(max(ground, height), rel=TOL)


def test_a_mechanism_at_height_against_the_floor_spectrum_by_default():
    """NTC, Circolare 2019 (the default): the same building, xi1 = 5 %. Linear: the floor's
    peak acceleration a_Z = Se(T1) gamma psi sqrt(1 + 0.0004 x 25) = 4.7088 x 6/7 x
    sqrt(1.01) = 4.056244656 m/s2 [C7.2.7], over q = 2. Nonlinear: Ts > b T1 = 0.33 s, on
    the falling branch of [C7.2.6] or the ground spectrum, whichever is larger, in
    displacement, and at least the plateau's at b T1 ([C8.7.1.12])."""
    # Ts at 5 %; T_SLV at 8 %: test_assess_circolare2019.py
    out = _one_block_at_height(nonlinear_check="circolare_2009")
    assert out.demand_at_height == "floor_spectrum" and out.building_damping == 5.0
    a_Z = 0.2 * G * 2.4 * (6 / 7) * math.sqrt(1.01)
    assert out.demand_height == pytest.approx(a_Z / 2, rel=TOL)
    assert out.demand_height == pytest.approx(2.028122328, rel=1e-9)
    Ts = out.Ts
    assert 0.35 < Ts < 2.4
    A = 1.1 / math.sqrt(0.05)
    fall = A * a_Z / (1 + (A - 1) * (Ts / 0.33 - 1) ** 1.2)
    ground_Se = 0.2 * G * 2.4 * 0.35 / Ts
    height = max(fall, ground_Se) * Ts**2 / (4 * math.pi**2)
    bound = A * a_Z * 0.33**2 / (4 * math.pi**2)
    ground = ground_Se * Ts**2 / (4 * math.pi**2)
    assert out.displacement_demand == pytest.approx(max(ground, height, bound), rel=TOL)


# ----------------------------------------------------------------------------- from the analyses
@pytest.fixture(scope="module")
def free_wall():
    return _model(
        {"builder": "running_bond_wall", "blocks_along_length": 3, "courses": 8}
    )  # a = 0.4, t = 0.2: H = 3.2 m


def test_free_standing_wall_from_the_limit_analysis(free_wall):
    """The limit analysis's mechanism of the free wall: alpha0 = t/H = 0.0625 and
    e* = 3 x 64 / 255, to the solver's precision (its velocities are exact at a vertex)."""
    import masonry_dem as md
    from masonry_dem.assessment.sources import limit_mechanism

    mech, alpha0 = limit_mechanism(free_wall, md.limit_analysis(free_wall))
    assert alpha0 == pytest.approx(0.0625, rel=TOL)
    assert mech.alpha_rigid == pytest.approx(0.0625, rel=TOL)
    assert mech.participating_mass()[1] == pytest.approx(3 * 64 / 255, rel=TOL)


def test_free_standing_wall_from_the_pushover(free_wall):
    """The pushover's collapse mode (joints turning about their centres, the elastic floor
    of its damaged stiffness) hinged at the toe: alpha0 and e* of the rigid wall to 1e-8
    (measured 3e-10: the mode's elastic part)."""
    import masonry_dem as md
    from masonry_dem.assessment.sources import history_mechanism

    history = md.pushover(free_wall)
    mech, alpha0 = history_mechanism(free_wall, history)
    assert alpha0 == pytest.approx(0.0625, rel=1e-3)  # the pushover's own bracket
    assert mech.alpha_rigid == pytest.approx(0.0625, rel=1e-8)
    assert mech.participating_mass()[1] == pytest.approx(3 * 64 / 255, rel=1e-8)


def test_two_block_chain_in_finite_rotation():
    """The chain of ``test_two_block_chain_by_hand`` turned by theta: the lower block by theta
    about its toe A = (y 0, z 0.2), the upper by theta more about the hinge C = (0.4, 0.2),
    which turns with the lower block (the hinge stays closed):
    c1 = A + Rot(th)(c1_0 - A), C = A + Rot(th)(C_0 - A), c2 = C + Rot(2 th)(c2_0 - C_0),
    Rot(th) (y, z) = (y cos - z sin, y sin + z cos). The weights are equal, so
    alpha(th) = (c1' + c2')_y / (c1' + c2')_z with Rot'(th) r = Rot(th + pi/2) r."""
    model, mode, (lower, upper) = _two_block_chain()
    mech = Mechanism.of(model, mode)
    curve = mech.capacity_curve()

    def rot(r, th):
        return np.array(
            [r[0] * np.cos(th) - r[1] * np.sin(th), r[0] * np.sin(th) + r[1] * np.cos(th)]
        )

    A, C0 = np.array([0.0, 0.2]), np.array([0.4, 0.2])
    r1, rC, r2 = np.array([0.2, 0.1]) - A, C0 - A, np.array([0.6, 0.1]) - C0

    def alpha(th):
        v1 = rot(r1, th + np.pi / 2)
        v2 = rot(rC, th + np.pi / 2) + 2 * rot(r2, 2 * th + np.pi / 2)
        return (v1[0] + v2[0]) / (v1[1] + v2[1])

    exact = np.array([alpha(th) for th in curve.s])
    assert np.abs(curve.alpha - exact).max() < TOL
    theta0 = brentq(alpha, 0.01, 0.5, xtol=1e-15)
    assert curve.s[-1] == pytest.approx(theta0, rel=TOL)
    # the control point, the centroid of the two, moved along z: the mean of c1 and c2
    c1 = A + rot(r1, theta0)
    c2 = A + rot(rC, theta0) + rot(r2, 2 * theta0)
    assert curve.d_k0 == pytest.approx(0.5 * (c1[1] + c2[1]) - 0.1, rel=TOL)
    # the hinge C, as a point of either block, at theta0
    on_lower = mech.positions([0.15, 0.4, 0.2], [lower], theta0)[0, 0]
    on_upper = mech.positions([0.15, 0.4, 0.2], [upper], theta0)[0, 0]
    assert np.abs(on_lower - on_upper).max() < TOL


def test_overlap_tells_the_chain_from_independent_screws():
    """At the chain's theta0 the two blocks of the chain still meet at the hinge with no
    overlap; moved each by its own screw, the upper one turns about a fixed point instead
    of the moving hinge and overlaps the lower one; ``assess_mode`` picks the chain."""
    from masonry_dem.assessment.checks import assess_mode
    from masonry_dem.assessment.kinematics import interpenetration

    model, mode, _ = _two_block_chain()
    chain = Mechanism.of(model, mode, kinematics="chain")
    screws = Mechanism.of(model, mode, kinematics="independent")
    s0 = chain.capacity_curve().s[-1]
    assert interpenetration(chain, model, s0) < TOL
    assert interpenetration(screws, model, s0) > 1e-3
    _, _, _, info = assess_mode(model, mode, "ntc2018", NTC2018Spectrum(0.1))
    assert info["kinematics"] == "chain"
    assert info["overlaps"]["chain"] < info["overlaps"]["independent"]


# ----------------------------------------------------------------------------- incremental
# The explicit midpoint rule of the incremental path errs by O(step^2) over a path: on the
# two-block chain at step = 0.005 rad (of the fastest block) alpha is off by 2.8e-7, at 0.01
# by 1.1e-6 (a ratio of 4.0: second order), so 1e-6 at 0.005 holds with a margin of 3.5.
STEP_TOL = 1e-6


def test_incremental_block_rocks_about_its_toe_exactly(block):
    """One block turning about its toe: the twist about a fixed hinge keeps its toe corners
    closed, so the projection returns it unchanged and each step's screw motion is the exact
    rotation; no step error at all (round-off: measured 2e-15)."""
    model, b, h, t, _, hinged, _ = block
    mech = Mechanism.of(model, hinged, kinematics="incremental")
    curve = mech.capacity_curve()
    theta = 0.37 * curve.s
    closed = (t * np.cos(theta) - h * np.sin(theta)) / (h * np.cos(theta) + t * np.sin(theta))
    assert np.abs(curve.alpha - closed).max() < 1e-12
    assert 0.37 * curve.s[-1] == pytest.approx(math.atan(t / h), rel=1e-12)
    assert curve.d_k0 == pytest.approx(t / 2, rel=1e-12)


def test_incremental_steps_by_the_projected_mode(block):
    """A mode that pushes the block's toe into its base (the rocking about the toe, 0.37,
    plus a turn of 0.2 about the heel) is projected onto the rocking about the toe, which
    turns the block more slowly than the mode given: the path's step is ``step`` radians
    of the projected mode's rotation (exactly), and the block still rocks about its toe
    exactly."""
    model, b, h, t, _, _, _ = block
    centre = model.blocks.centres[[b]]
    mode = np.zeros((model.blocks.count, 6))
    mode[b] = (
        _rotation_about(centre, (0.0, t), 0.37)[0] + _rotation_about(centre, (0.0, 0.0), 0.2)[0]
    )
    mech = Mechanism.of(model, mode, kinematics="incremental")
    assert mech.path is not None
    turn = float(np.linalg.norm(mech.w[b]))
    assert turn < 0.57 - 0.05  # the projection took the push into the base away
    assert mech.path.ds * turn == pytest.approx(0.005, rel=1e-12)
    about_toe = _rotation_about(centre, (0.0, t), turn)[0]
    moved = np.hstack([mech.v0[b] + np.cross(mech.w[b], centre[0]), mech.w[b]])
    assert np.abs(moved - about_toe).max() < 1e-12 * turn
    curve = mech.capacity_curve()
    theta = turn * curve.s
    closed = (t * np.cos(theta) - h * np.sin(theta)) / (h * np.cos(theta) + t * np.sin(theta))
    assert np.abs(curve.alpha - closed).max() < 1e-12


def _hinged_pair_alpha(A, C0, r1, r2, W1, W2):
    """alpha(th) of a lower body turning by th about the toe A and an upper one by 2 th
    about the hinge C (turning with the lower body), their centroids at A + r1 and C0 + r2
    (y, z), from the work rates of the weights and of the horizontal loads."""
    rC = np.asarray(C0) - np.asarray(A)

    def rot(r, th):
        return np.array(
            [r[0] * np.cos(th) - r[1] * np.sin(th), r[0] * np.sin(th) + r[1] * np.cos(th)]
        )

    def alpha(th):
        v1 = rot(r1, th + np.pi / 2)
        v2 = rot(rC, th + np.pi / 2) + 2 * rot(r2, 2 * th + np.pi / 2)
        return (W1 * v1[0] + W2 * v2[0]) / (W1 * v1[1] + W2 * v2[1])

    return alpha


def test_incremental_two_block_chain_against_the_closed_form():
    """The chain of ``test_two_block_chain_in_finite_rotation`` integrated in steps: alpha(th),
    th0 and d_k0 of the closed form within STEP_TOL at step 0.005, and the error falling by
    about 4 when the step halves (the midpoint rule's second order: it could fail both ways)."""
    model, mode, _ = _two_block_chain()
    alpha = _hinged_pair_alpha([0.0, 0.2], [0.4, 0.2], [0.2, -0.1], [0.2, -0.1], 1.0, 1.0)
    theta0 = brentq(alpha, 0.01, 0.5, xtol=1e-15)
    errors = []
    for step in (0.01, 0.005):
        mech = Mechanism.of(model, mode, kinematics="incremental", step=step)
        curve = mech.capacity_curve()
        errors.append(np.abs(curve.alpha - np.array([alpha(th) for th in curve.s])).max())
    assert errors[1] < STEP_TOL
    assert 3.0 < errors[0] / errors[1] < 5.0
    assert curve.s[-1] == pytest.approx(theta0, abs=STEP_TOL)
    # the centroids at th0, by hand: Rot(th) (y, z) = (y cos - z sin, y sin + z cos)
    A = np.array([0.0, 0.2])
    c1 = A + np.array(
        [0.2 * np.cos(theta0) + 0.1 * np.sin(theta0), 0.2 * np.sin(theta0) - 0.1 * np.cos(theta0)]
    )
    C = A + np.array([0.4 * np.cos(theta0), 0.4 * np.sin(theta0)])
    c2 = C + np.array(
        [
            0.2 * np.cos(2 * theta0) + 0.1 * np.sin(2 * theta0),
            0.2 * np.sin(2 * theta0) - 0.1 * np.cos(2 * theta0),
        ]
    )
    assert curve.d_k0 == pytest.approx(0.5 * (c1[1] + c2[1]) - 0.1, abs=STEP_TOL)


def test_incremental_keeps_a_running_bond_wall_closed_where_screws_overlap():
    """A running-bond wall of 4 courses (t = 0.2, course a = 0.4) in two bodies: courses 1-2
    turning by th about the toe (y 0, z t), courses 3-4 by 2 th about the front edge of the
    bed joint between them (y 2a, z t), which turns with the lower body. Every block touches
    two below it, so the joints close loops, within each body and across the hinge (several
    joints of the one hinge line). alpha(th) is the two-block chain's with the bodies'
    centroids and weights (from the blocks), to the step's STEP_TOL; at d_u* the independent
    screws overlap the bodies at the hinge by 0.44 mm, the incremental path by round-off
    (3e-15 m): asserted below 1e-6 of the screws'."""
    from masonry_dem.assessment.checks import assess_mode
    from masonry_dem.assessment.kinematics import interpenetration

    model = _model({"builder": "running_bond_wall", "blocks_along_length": 3, "courses": 4})
    t, a = 0.2, 0.4
    c = model.blocks.centres
    wall = ~model.fixed.any(axis=1)
    low, up = wall & (c[:, 1] < 2 * a), wall & (c[:, 1] > 2 * a)
    assert low.sum() >= 5 and up.sum() >= 5  # a loop needs more than one joint per block
    A, C0 = np.array([0.0, t]), np.array([2 * a, t])
    mode = np.zeros((model.blocks.count, 6))
    mode[low] = _rotation_about(c[low], A)
    w2 = np.array([2.0, 0.0, 0.0])
    hinge_velocity = np.cross([1.0, 0.0, 0.0], [0.0, *(C0 - A)])
    mode[up, :3] = hinge_velocity + np.cross(w2, c[up] - np.array([0.0, *C0]))
    mode[up, 3:] = w2
    W = model.blocks.weights
    W1, W2 = float(W[low].sum()), float(W[up].sum())
    g1 = (W[low] @ c[low][:, 1:]) / W1
    g2 = (W[up] @ c[up][:, 1:]) / W2
    alpha = _hinged_pair_alpha(A, C0, g1 - A, g2 - C0, W1, W2)
    mech = Mechanism.of(model, mode, kinematics="incremental")
    curve = mech.capacity_curve()
    assert np.abs(curve.alpha - np.array([alpha(th) for th in curve.s])).max() < STEP_TOL
    assert curve.s[-1] == pytest.approx(brentq(alpha, 0.01, 0.5, xtol=1e-15), abs=STEP_TOL)
    spectrum = NTC2018Spectrum(0.1)
    runs = {
        k: assess_mode(model, mode, "ntc2018", spectrum, kinematics=k)
        for k in ("independent", "incremental")
    }
    screws, steps = (runs[k][3]["overlap_at_du"] for k in ("independent", "incremental"))
    assert screws > 1e-4  # 0.1 mm: the screws turn the upper body about a fixed hinge
    assert steps < 1e-6 * screws
    # the overlap of the path's own d_u*, measured again
    out, curve, mech, _ = runs["incremental"]
    s_du = mech.configuration_at(out.displacement_capacity * out.e_star, float(curve.s[-1]))
    assert interpenetration(mech, model, s_du) == pytest.approx(steps, abs=1e-12)


def test_incremental_follows_a_three_hinge_loop_the_screws_break():
    """Three blocks (a = 0.4, t = 0.2) on a base, the top one held horizontally at its
    centre (u1, u3 fixed: a floor that lets it rise), the limit analysis's mechanism: the
    lower two turn by th about the toe A = (y 0, z t), the top one about the back hinge
    C = (0.8, 0) that moves with them, its centre kept at z = t/2 (a closed loop through the
    ground: one degree of freedom). By hand: C(th) = A + Rot(th)(C0 - A), the top block's
    turn phi from C_z + 0.2 sin phi + 0.1 cos phi = 0.1, alpha = sum dy / sum dz of the three
    centroids (equal weights; the held one takes no horizontal load's work). The
    incremental path follows it (alpha within 1e-5 at step 0.0025, measured 1.2e-6; theta0
    and d_k0 within 1e-6), where the closed-form motions move the held centre by 0.13 m and
    end at d_k0 21 % too far."""
    import masonry_dem as md

    geometry = {"builder": "stack_bond_column", "courses": 3}
    top = int(np.argmax(_model(geometry).blocks.centres[:, 1]))
    model = _model(geometry, supports=[{"select": "base"}, {"select": [top], "dofs": ["u1", "u3"]}])
    mode, residual = hinged_mode(model, np.asarray(md.limit_analysis(model).block_velocities))
    assert residual < TOL
    A, C0, r = np.array([0.0, 0.2]), np.array([0.8, 0.0]), np.array([0.2, 0.1])

    def rot(v, th):
        return np.array(
            [v[0] * np.cos(th) - v[1] * np.sin(th), v[0] * np.sin(th) + v[1] * np.cos(th)]
        )

    def centroids(th):
        C = A + rot(C0 - A, th)
        phi = brentq(lambda f: (C + rot(r, f))[1] - 0.1, -1.5, 0.5, xtol=1e-15)
        return np.array(
            [
                A + rot(np.array([0.2, 0.1]) - A, th),
                A + rot(np.array([0.6, 0.1]) - A, th),
                C + rot(r, phi),
            ]
        )

    def alpha(th, h=1e-6):
        v = (centroids(th + h) - centroids(th - h)) / (2 * h)
        return v[:, 0].sum() / v[:, 1].sum()

    theta0 = brentq(alpha, 0.01, 0.3, xtol=1e-14)
    d_k0 = float(np.mean(centroids(theta0)[:, 1] - 0.1))
    mech = Mechanism.of(model, mode, kinematics="incremental", step=0.0025)
    curve = mech.capacity_curve()
    lower = int(np.argmin(np.abs(model.blocks.centres[:, 1] - 0.2)))
    R = mech.motion(curve.s)[0][:, lower]
    turn = np.arctan2(R[:, 2, 1], R[:, 1, 1])  # the lower blocks' turn about e1
    assert max(abs(a - alpha(th)) for a, th in zip(curve.alpha[:-1], turn[:-1], strict=True)) < 1e-5
    assert turn[-1] == pytest.approx(theta0, abs=1e-6)
    assert curve.d_k0 == pytest.approx(d_k0, abs=1e-6)
    held = mech.positions(model.blocks.centres[[top]], [top], curve.s[-1])[0, 0]
    assert abs(held[2] - model.blocks.centres[top, 2]) < 1e-5
    screws = Mechanism.of(model, mode, kinematics="independent")
    assert screws.capacity_curve().d_k0 > 1.1 * d_k0  # what the incremental path corrects
    # the held centre's drift: 0.13 m for the screws at theta0, none along the path
    s0 = float(screws.capacity_curve().s[-1])
    assert support_drift(screws, model, s0) > 0.1
    assert support_drift(mech, model, float(curve.s[-1])) < 1e-5


def test_auto_takes_the_motion_that_keeps_a_held_block_still():
    """On the three-hinge loop of ``test_incremental_follows_a_three_hinge_loop_the_screws_
    break`` the chain and the screws overlap nothing but move the held top block: ``auto``
    weighs that drift as it weighs an overlap, and takes the incremental path."""
    import masonry_dem as md
    from masonry_dem.assessment.checks import assess_mode

    geometry = {"builder": "stack_bond_column", "courses": 3}
    top = int(np.argmax(_model(geometry).blocks.centres[:, 1]))
    model = _model(geometry, supports=[{"select": "base"}, {"select": [top], "dofs": ["u1", "u3"]}])
    mode, _ = hinged_mode(model, np.asarray(md.limit_analysis(model).block_velocities))
    _, _, _, info = assess_mode(model, mode, "ntc2018", NTC2018Spectrum(0.1))
    assert info["kinematics"] == "incremental"
    assert min(info["drifts"]["chain"], info["drifts"]["independent"]) > 1e-3
    assert info["drift_at_du"] < 1e-6
    assert info["overlap_at_du"] < 1e-6


def test_incremental_bad_input_and_auto_spares_it_on_a_chain():
    """A step out of (0, 0.1] and an unknown kinematics are refused in one line naming the
    field, the value and what is allowed; on the two-block chain the chain's motion has no
    overlap, so ``auto`` keeps it and never integrates the incremental path."""
    from masonry_dem.assessment.checks import assess_mode

    model, mode, _ = _two_block_chain()
    with pytest.raises(ValueError, match=r"step = 0\.0 out of range: must be in \(0, 0\.1\]"):
        Mechanism.of(model, mode, kinematics="incremental", step=0.0)
    with pytest.raises(ValueError, match="kinematics = 'spiral': must be one of .*incremental"):
        Mechanism.of(model, mode, kinematics="spiral")
    with pytest.raises(ValueError, match="must be auto, chain, independent or incremental"):
        assess_mode(model, mode, "ntc2018", NTC2018Spectrum(0.1), kinematics="spiral")
    _, _, mech, info = assess_mode(model, mode, "ntc2018", NTC2018Spectrum(0.1))
    assert info["kinematics"] == "chain"
    assert set(info["overlaps"]) == {"chain", "independent"}
    assert mech.path is None


def test_the_motion_note_names_an_overlap_beyond_the_contact_gap():
    """The note of an inadmissible motion starts past the incremental path's contact gap
    (1e-3 of the moving blocks' least size: 70 micrometres for 70 mm blocks), says the
    overlap against that size, and where the incremental path ended."""
    from masonry_dem.assessment.checks import motion_note
    from masonry_dem.assessment.incremental import CONTACT_GAP

    least = 0.07
    assert motion_note("independent", 0.999 * CONTACT_GAP * least, 0.0, least, {}) == ""
    assert motion_note("chain", math.inf, math.inf, least, {}) == ""  # no alpha = 0: no check
    note = motion_note("independent", 0.004, 0.0, least, {})
    assert note.endswith(
        "its blocks overlap by 4 mm, 5.7 % of the moving blocks' least size (70 mm)"
    )
    assert "drifts" not in note
    note = motion_note("chain", 0.0, 1.01 * CONTACT_GAP * least, least, {})
    assert "a held block drifts by 0.0707 mm, 0.1 %" in note
