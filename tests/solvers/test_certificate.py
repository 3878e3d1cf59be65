"""A collapse is a certified result, and the solver never calls its own failure a collapse.

Proves: every reported collapse carries a certificate whose three conditions a test
re-checks on its own (the residual of the state re-evaluated by a fresh discrete problem,
the tangent's Rayleigh quotient along K_t^-1 F_L from a dense solve, the live load's work);
a stop the certificate refuses ends ``failed`` with every step kept; the outcome is typed
(Status, StopReason) and written to summary.json. And the defects of issue 18, each failing
on 7022155: the displacement-control budget reported as "completed", elastic shortening of a
tall column taken for a mechanism, a displacement limit taken for a collapse, and absurd
friction or stiffness giving a "collapse" at lambda ~ 1e-8.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import masonry_dem as md
from helpers.certificate_checks import recheck, tilted_wall
from masonry_dem.export.analyses import pushover
from masonry_dem.geometry.builders import (
    add_base,
    running_bond_wall,
    single_block,
    stack_bond_column,
)
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import (
    DisplacementControl,
    StaticSettings,
    Status,
    StopReason,
)


# ------------------------------------------------------------------ certified collapses
def test_a_tilting_block_collapse_is_certified_at_s_over_a():
    """A block on a base tilts at s/a; the certificate holds and re-checks: the tangent of
    its last state has almost nothing left along the rotation the load drives."""
    a, s = 0.2, 0.1
    blocks, base = add_base(single_block(a, 0.25, s, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
    )
    settings = StaticSettings()
    hist = pushover(model, settings)
    assert hist.collapse_multiplier == pytest.approx(s / a, rel=0.005)
    recheck(model, hist, settings)
    assert hist.certificate.bound_status == "not checked"  # no bound given: never a pass
    assert hist.certificate.within_bound is None


def test_panel_collapse_is_certified_and_written_to_the_summary(tmp_path):
    model = tilted_wall(3, 5)
    settings = StaticSettings()
    hist = pushover(model, settings, out=tmp_path)
    recheck(model, hist, settings)
    assert isinstance(hist.status, Status) and isinstance(hist.stop, StopReason)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "collapse"
    assert summary["stop"] == str(hist.stop)
    cert = summary["certificate"]
    assert cert["holds"] and cert["mode"] in ("singular tangent", "flat curve")
    assert cert["bound_status"] == "not checked"
    assert cert["live_work"] > 0 and cert["step"] == hist.certificate.step


def test_a_collapse_under_the_incremental_law_rechecks_with_its_slip():
    """The held 3 x 5 panel with ``memory = "slip"``: its certified collapse rechecks with
    the plastic slip stored at the step before it (evaluated without it, the state is out of
    balance by 6 % of the load), within 1 % of the holonomic answer (the two laws give the
    same actions under a monotonic, proportional load)."""
    slip = InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7, memory="slip")
    model = tilted_wall(3, 5, slip)
    settings = StaticSettings()
    hist = pushover(model, settings)
    recheck(model, hist, settings)
    none = InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7, memory="none")
    holonomic = pushover(tilted_wall(3, 5, none)).collapse_multiplier
    assert hist.collapse_multiplier == pytest.approx(holonomic, rel=0.01)


def test_a_bound_below_lambda_refuses_the_collapse():
    """Condition (c): a collapse multiplier above the (injected) associative bound is no
    certified collapse: the run ends failed and says which bound it exceeds."""
    model = tilted_wall(3, 5)
    found = pushover(model)
    lam = found.collapse_multiplier
    above = pushover(model, bound=1.5 * lam)
    assert above.status == "collapse" and above.certificate.bound_status == "within"
    below = pushover(model, bound=lambda m: 0.5 * lam)
    assert below.status == "failed" and below.certificate.bound_status == "exceeded"
    assert "limit-analysis bound" in below.reason
    assert len(below.steps) == len(found.steps)  # every step kept


# ------------------------------------------------------------------ the defects of issue 18
def test_displacement_control_that_spends_its_budget_fails():
    """On 7022155 the ``while ... else`` reported "completed, control displacement reached"
    when max_steps ran out at 15 % of the target."""
    model = tilted_wall(3, 5)
    top = int(np.argmax(model.blocks.centres[:, 1] * 100 + model.blocks.centres[:, 0]))
    target = 0.02
    hist = pushover(
        model, StaticSettings(max_steps=10), control=DisplacementControl(top, "u3", target, 50)
    )
    assert hist.status == "failed"
    assert hist.stop is StopReason.CONTROL_BUDGET
    reached = hist.last.q[top, 2]
    assert reached < 0.5 * target and f"{reached:.6g}" in hist.reason
    # with the budget it needs, the same control reaches its target
    done = pushover(model, control=DisplacementControl(top, "u3", 2e-3, 10))
    assert done.status == "completed" and done.stop is StopReason.CONTROL_REACHED
    assert done.last.q[top, 2] == pytest.approx(2e-3, rel=1e-9)


def test_elastic_shortening_of_a_tall_column_is_no_mechanism():
    """A stack of 200 blocks 0.1 m high, 0.05 m square (20 m) shortens elastically under its
    weight by w / (kn A) x n (n + 1) / 2 = 0.0402 m (the joint under course i carries the
    n - i + 1 blocks above it), more than the displacement limit (half the smallest block
    size, 0.025 m). On 7022155 the dead load failed as "a mechanism"."""
    n, a, b = 200, 0.1, 0.05
    blocks, base = add_base(stack_bond_column(n, a, b, b, 20e3))
    kn = 1e9
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=kn, kt=0.4e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight()],
    )
    hist = pushover(model)
    assert hist.status == "completed", hist.reason
    weight = 20e3 * a * b * b
    expected = weight / (kn * b * b) * n * (n + 1) / 2
    assert expected > 0.025
    assert -hist.last.q[:, 1].min() == pytest.approx(expected, rel=1e-6)


def test_a_displacement_limit_alone_is_not_a_collapse():
    """A limit the elastic wall passes long before anything yields (1e-5 m): the path stops
    where the wall has moved that far from its dead-load state (lambda 0.093), while its
    curve still rises and its tangent keeps most of its stiffness along the load. That is
    no collapse: the run ends ``failed``, saying the wall left the small-displacement range
    before its curve stopped rising, with every step kept."""
    model = tilted_wall(3, 5)
    hist = pushover(model, StaticSettings(displacement_limit=1e-5))
    assert hist.status == "failed" and hist.stop is StopReason.DISPLACEMENT_LIMIT
    assert "left the small-displacement range before its curve stopped rising" in hist.reason
    assert hist.collapse_multiplier is None and len(hist.steps) > 1


@pytest.mark.parametrize(
    "material",
    [
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=1e10),
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=10.0),
    ],
    ids=["friction 1e10", "friction 10"],
)
def test_high_friction_never_collapses_near_zero(material):
    """With friction that cannot slide, the held 3 x 5 panel still rocks: a certified
    collapse well above zero, or failed; on 7022155 friction 1e10 gave "collapse" at
    lambda = 1.6e-8. The rocking panel with friction 0.7 bounds it from below (more friction
    can only hold more)."""
    model = tilted_wall(3, 5, material)
    hist = pushover(model)
    reference = pushover(tilted_wall(3, 5)).collapse_multiplier
    if hist.status == "collapse":
        assert hist.collapse_multiplier >= 0.99 * reference
        recheck(model, hist, StaticSettings())
    else:
        assert hist.status == "failed"


def test_certify_false_reports_the_stop_unchecked():
    """``certify=False`` keeps the stop of the path as the answer (no certificate)."""
    model = tilted_wall(3, 5)
    unchecked = StaticSettings(displacement_limit=1e-5, certify=False)
    hist = pushover(model, unchecked)
    assert hist.status == "collapse" and hist.certificate is None


def test_settings_name_the_bad_field():
    for field, value in [("mode_stiffness", 0.0), ("max_iterations", 0), ("bound_tolerance", -1)]:
        with pytest.raises(ValueError, match=field):
            replace(StaticSettings(), **{field: value})


def test_an_in_plane_wall_never_collapses_at_the_residual_tolerance():
    """A held 9 x 3 wall tilted in its plane, friction 29, kn 1.1e8 (found by the property
    sweep): Newton stalls from the dead-load state for every lambda above 1e-8, and on
    7022155 that was a collapse at lambda 1.04e-8. The instability rule finds rest there and
    the load goes on to the wall's collapse, within 1 % of the reference analysis's 0.9271."""
    model = tilted_wall(9, 3, InterfaceMaterial(kn=1.1e8, kt=0.44e8, friction=29.0), (1, 0, 0))
    hist = pushover(model)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(0.9271, rel=0.01)


def test_a_frictionless_block_collapses_at_zero_load_certified():
    """No friction: the block slides under any lateral load. The multiplier (<= 1e-8) is
    below what the residual resolves, so the certificate asks for a mechanism of the
    dead-load state that dynamic relaxation confirms by finding no rest: it does."""
    blocks, base = add_base(single_block(0.2, 0.3, 0.3, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.0),
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
    )
    hist = pushover(model)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier <= 1e-8
    cert = hist.certificate
    assert cert.near_zero and cert.zero_load_check == "no rest"
    assert cert.mode == "mechanism of the dead-load state" and cert.live_work > 0


def test_load_and_displacement_control_reach_the_same_peak():
    """The held 3 x 5 panel: the top right block's u3 driven to 3x its displacement at the
    load-controlled collapse reaches the same peak within 1 % (0.3191 against 0.3187)."""
    from masonry_dem.solvers.static.branches import compare_controls

    model = tilted_wall(3, 5)
    top = int(np.argmax(model.blocks.centres[:, 1] * 100 + model.blocks.centres[:, 0]))
    result = compare_controls(
        model, DisplacementControl(top, "u3", 0.0057, 60), StaticSettings(max_steps=400)
    )
    assert result.same_peak and result.verdict == "same peak", result.reason
    assert result.displacement_peak == pytest.approx(result.load_peak, rel=0.01)


def test_a_displacement_control_stopped_short_says_so():
    """Driven to a fifth of the displacement at collapse, the path ends on a rising curve:
    the comparison says it stopped before the peak, not that it took another branch."""
    from masonry_dem.solvers.static.branches import compare_controls

    model = tilted_wall(3, 5)
    top = int(np.argmax(model.blocks.centres[:, 1] * 100 + model.blocks.centres[:, 0]))
    result = compare_controls(model, DisplacementControl(top, "u3", 0.0004, 10))
    assert not result.same_peak
    assert result.verdict == "displacement control stopped before the peak", result.reason
    assert result.displacement_peak < result.load_peak


def test_displacement_control_passes_the_folds_of_its_path_to_the_load_controlled_peak():
    """Issue 18: a dry running-bond wall on a fixed base tilted in its own plane (3 x 5
    blocks of 0.4 x 0.2 x 0.2 m, friction 0.6, kn 1e9, kt 0.4e9) slides at lambda = mu =
    0.6 under load control. Driving the top left block's u1 instead, the path folds where a
    joint starts to slide: at lambda 0.5077 (u1 = 0.186 mm) no equilibrium with a larger u1
    lies near the last state and halved steps only close in on it; on 5133bd5 the run
    stopped there ("displacement control stuck"), 15.4 % below the load-controlled peak, and
    the comparison called it a path "stopped before the peak" by its target or budget. The
    instability rule's damped motion to a lambda a bracket higher goes round each fold (the controlled
    displacement turns back at some: the reason counts them) and the two controls reach the
    same peak. Past it every bed joint slides at mu at once, so under the incremental law
    the controlled displacement does not say which: the run may end on that plateau, at the
    peak (its status is not the claim)."""
    from masonry_dem.solvers.static.branches import compare_controls

    wall = running_bond_wall(3, 5, a=0.2, b=0.4, s=0.2, unit_weight=2000 * 9.81)
    blocks, base = add_base(wall)
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.6),
        [Support([base])],
        [SelfWeight(), WeightProportional(direction=(1.0, 0.0, 0.0))],
    )
    c = wall.centres
    top = np.flatnonzero(np.isclose(c[:, 1], c[:, 1].max()))
    left = int(top[np.argmin(c[top, 0])])
    result = compare_controls(model, DisplacementControl(left, "u1", 0.05, 50))
    assert result.load_peak == pytest.approx(0.6, rel=1e-6)  # sliding at mu
    assert result.verdict == "same peak", result.reason
    assert result.displacement_peak == pytest.approx(0.6, rel=0.01)
    assert "damped motion(s) past folds" in result.displacement.reason


@pytest.mark.slow
def test_a_stop_at_a_corner_is_checked_whatever_its_tangent():
    """S23 (two openings): work control stops where Newton finds no correction, at a state
    whose tangent is singular along the load (rho 0.013 <= mode_stiffness), while its curve
    still rose at 0.1 of its elastic slope over its last steps: a corner, where the branch
    the path followed ends, which a fold of the path shares with a peak (d01d26a certified
    0.084721 there). The instability rule finds the wall at rest above it, and the path
    passes one more fold (0.1108) to a certified collapse near 0.112 (the test gave 0.144,
    the paper's DEM 0.130)."""
    from masonry_dem.cases.paper import build_case
    from masonry_dem.solvers.incremental import StaticSolver

    case = build_case("S23")
    hist = StaticSolver(case.model, case.settings).run(monitor=case.monitor)
    assert hist.status == "collapse", hist.reason
    assert 0.1108 < hist.collapse_multiplier < 1.02 * 0.1126


def test_a_soft_panel_past_the_small_displacement_range_keeps_its_multiplier():
    """A held 10 x 15 panel (friction 11.3) with kn 1.5e9 passes the displacement limit (half
    a block from the dead-load state) at 0.20 while its curve still rises. The instability
    rule finds it at rest above, so the path goes on (its displacements measured from that
    rest) to a collapse within 2 % of the stiff panel's, and the reason says that the
    collapse state lies past the small-displacement range. The same panel with kn 1.5e11
    (ef802c5 certified 0.256 there, 26 % low) reaches its collapse within 1 % of the
    reference analysis's 0.3438 (``md.quasi_static`` on the stiff panel): the multiplier
    does not depend on the scale of kn and kt."""
    soft = pushover(tilted_wall(10, 15, InterfaceMaterial(kn=1.5e9, kt=0.6e9, friction=11.3)))
    stiff = pushover(tilted_wall(10, 15, InterfaceMaterial(kn=1.5e11, kt=0.6e11, friction=11.3)))
    assert stiff.status == "collapse", stiff.reason
    assert stiff.collapse_multiplier == pytest.approx(0.3438, rel=0.01)
    assert soft.status == "collapse", soft.reason
    assert soft.collapse_multiplier == pytest.approx(stiff.collapse_multiplier, rel=0.02)
    assert "past the small-displacement range" in soft.reason


def test_work_control_stops_at_max_load_factor_and_a_completed_run_has_no_collapse():
    """A block jammed between a fixed base and a fixed top plate (joints in 4 x 4 pieces,
    friction 10) carries far more than its free-standing b/h = 0.5: the run must end
    ``completed`` exactly at ``max_load_factor`` (work control leaves lambda free, so a step
    may pass the cap and is found again at the cap), and a completed run reports no collapse
    multiplier (on 7022155: lambda 1.82 > 1.5 and a collapse multiplier of 0.1625 left from
    load control's first failure)."""
    blocks = md.boxes(
        [[0, -0.1, 0], [0, 0, 0], [0, 0.4, 0]],
        [[0.2, 0, 0.2], [0.2, 0.4, 0.2], [0.2, 0.5, 0.2]],
        20e3,
    )
    interfaces = md.subdivide_interfaces(md.detect_interfaces(blocks), 4, 4)
    model = md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=10.0),
        [md.Support([0, 2])],
        [md.SelfWeight(), md.WeightProportional((1, 0, 0), blocks=[1])],
        interfaces=interfaces,
    )
    hist = md.pushover(model, settings=md.StaticSettings(max_load_factor=1.5))
    assert hist.status == "completed"
    assert hist.final_load_factor == pytest.approx(1.5, rel=1e-12)
    assert hist.collapse_multiplier is None
    assert hist.summary()["lambda_bracket"] is None


def test_the_certificate_of_a_wall_does_not_move_with_its_joint_stiffness():
    """A 9 x 3 in-plane wall, left column held, friction 29: with kn and kt scaled together
    by f, every displacement of the path scales by 1 / f and its lambdas agree to 1e-15, so
    rho = F_L.v / v.K_0 v, a ratio of two stiffnesses along the same mode, must agree too.
    The metric K_0 is the dead-load state's tangent, where the head joints carry nothing:
    round-off set their flags, and the raw law tangent gave each its elastic shear stiffness
    or none (on 878b2f7 rho was 0.48 at f = 1, 0.29 at f = 10 and 0.31 at f = 1000). The
    wall stops at 0.928 with its tangent's stiffness along the load almost whole, yet the
    damped motion at 0.5 % more runs off (the reference analysis: no rest above 0.9271):
    a collapse at every f, the same lambda."""
    rhos, statuses, lambdas = [], [], []
    for f in (1.0, 10.0, 1000.0):
        kn = 108894312.318539 * f  # the wall of benchmarks/certificate_sweep.py, seed 18
        material = InterfaceMaterial(kn=kn, kt=0.4 * kn, friction=29.03076327893564)
        hist = pushover(tilted_wall(9, 3, material, direction=(1.0, 0.0, 0.0)))
        rhos.append(hist.certificate.mode_rayleigh)
        statuses.append(hist.status)
        lambdas.append(hist.collapse_multiplier)
    assert rhos == pytest.approx([rhos[0]] * 3, rel=1e-9)
    assert statuses == ["collapse"] * 3
    assert lambdas == pytest.approx([0.9271] * 3, rel=0.005)


@pytest.mark.parametrize("flat_slope", [0.0, 1e-3], ids=["tail off", "tail 1e-3"])
def test_a_head_joint_at_round_off_does_not_move_the_rechecked_rayleigh_quotient(
    flat_slope,
):
    """One block by two courses tilted in plane, free, friction 2.0, kn 1e8: the wall tilts
    about its toe at B/H = 0.21/0.162. The head joint of the top course carries nothing at
    the peak (normal force 1e-9 N), so the law reads it as sliding (shear coupled to the gap
    by friction x kn) or detached by the sign of round-off; the dense recheck of rho must
    reduce it to its normal stiffness, as the tangent Newton factors does (it got -5e-11
    against the certificate's 1.06e-9 from the raw tangent)."""
    material = InterfaceMaterial(kn=1e8, kt=0.4e8, friction=2.0)
    model = tilted_wall(1, 2, material, direction=(1.0, 0.0, 0.0), held=False)
    settings = StaticSettings(flat_slope=flat_slope)
    hist = pushover(model, settings)
    assert hist.status == "collapse", hist.reason
    assert hist.collapse_multiplier == pytest.approx(0.21 / (2 * 0.081), rel=1e-6)
    assert hist.certificate.mode.startswith("singular tangent")
    recheck(model, hist, settings)
