"""Loading stages (solvers/static/stages.py): the state carried from one stage to the next, a
DOF held anew at its current displacement, the reactions at the held DOFs, and the checks of
a bad stage (issue 41, items 1-3)."""

from __future__ import annotations

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.export.results_series import read_pushover
from masonry_dem.geometry.builders import boxes
from masonry_dem.model import InterfaceMaterial, Model, PointLoad, SelfWeight, Support
from masonry_dem.results import STATE_NAMES
from masonry_dem.solvers.static.settings import DisplacementControl
from masonry_dem.solvers.static.stages import Stage, run_stages

MU = 0.6
DRY = InterfaceMaterial(kn=1e9, kt=4e8, friction=MU)  # no tension, no cohesion
P = 500.0  # the precompression on the beam [N]
BASE, WALL, BEAM = 0, 1, 2


def _specimen() -> Model:
    """A wall block (0.4 x 0.2 x 0.1 m) between a fixed base and a loading beam (0.1 m
    tall) on top, under their weights: the shear-wall test in one block."""
    blocks = boxes(
        [[0, -0.1, 0], [0, 0, 0], [0, 0.2, 0]],
        [[0.4, 0, 0.1], [0.4, 0.2, 0.1], [0.4, 0.3, 0.1]],
        20e3,
    )
    return Model.build(blocks, DRY, supports=[Support([BASE])], loads=[SelfWeight()])


PRECOMPRESSION = Stage(loads=[PointLoad([BEAM], (0.0, -P, 0.0))], name="precompression")


def _push(target: float = 0.002, held=("u2", "w3")) -> Stage:
    """The beam held at its height and against rotation, pushed along e1 by displacement."""
    return Stage(
        loads=[PointLoad([BEAM], (1.0, 0.0, 0.0), live=True)],
        supports=[Support([BEAM], list(held))],
        control=DisplacementControl(block=BEAM, dof="u1", target=target, steps=20),
        name="push",
    )


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def test_stage_one_ends_in_the_state_of_a_dead_load_analysis():
    """(a) precompression then push: the last state of stage 1 is the equilibrium of one
    analysis with the precompression a dead load (q and the joints' actions to 1e-9)."""
    model = _specimen()
    history = run_stages(model, [PRECOMPRESSION, _push()])
    assert history.status == "completed", history.reason
    first = [s for s in history.steps if s.stage == 0][-1]
    single = Model.build(
        model.blocks,
        DRY,
        supports=[Support([BASE])],
        loads=[SelfWeight(), PointLoad([BEAM], (0.0, -P, 0.0))],
    )
    dead = md.pushover(single)
    assert dead.stop is md.StopReason.NO_LIVE_LOAD
    assert _relative(first.q, dead.last.q) <= 1e-9
    assert _relative(first.actions, dead.last.actions) <= 1e-9
    assert set(history.stages.tolist()) == {0, 1}
    assert [s.step for s in history.steps] == list(range(len(history.steps)))


def test_one_stage_is_the_analysis_with_no_stages():
    """The model's own loads and supports are the first stage's: one empty stage runs the
    same path, bit for bit."""
    model = _specimen()
    tilted = Model.build(
        model.blocks,
        DRY,
        supports=[Support([BASE])],
        loads=[SelfWeight(), md.WeightProportional((1.0, 0.0, 0.0))],
    )
    plain = md.pushover(tilted)
    staged = md.pushover(tilted, stages=[Stage()])
    assert staged.status == plain.status and staged.stop == plain.stop
    assert np.array_equal(staged.load_factors, plain.load_factors)
    assert all(np.array_equal(a.q, b.q) for a, b in zip(staged.steps, plain.steps, strict=True))
    assert staged.collapse_multiplier == plain.collapse_multiplier


def test_pushed_beam_held_at_its_height_slides_at_mu_n():
    """(b) closed form. The beam held at its height and against rotation and pushed along
    e1: with no dilatancy the joints' normal forces stay those of the precompression stage,
    N = P + W_beam in the joint under the beam and N + W_wall in the bed joint, and the
    wall block (b / h = 2 > mu) slides before it rocks. The joint under the beam (the smaller
    N, the same mu) slides first: the horizontal force lambda x 1 N tops at H = mu N."""
    model = _specimen()
    history = md.pushover(model, stages=[PRECOMPRESSION, _push()])
    assert history.status == "completed", history.reason
    w_beam = float(model.blocks.weights[BEAM])
    expected = MU * (P + w_beam)
    pushed = history.load_factors[history.stages == 1]
    assert pushed.max() == pytest.approx(expected, rel=0.01)
    assert pushed[-1] == pytest.approx(expected, rel=0.01)  # a plateau: sliding
    last = history.last
    assert last.control_displacement == pytest.approx(0.002)
    touches_beam = (model.interfaces.block_i == BEAM) | (model.interfaces.block_j == BEAM)
    names = [STATE_NAMES[code] for code in last.state]
    assert [n for n, top in zip(names, touches_beam, strict=True) if top] == ["sliding"]
    assert "sliding" not in [n for n, top in zip(names, touches_beam, strict=True) if not top]
    # the horizontal reaction of the base balances the push
    assert last.reactions is not None
    assert last.reactions[BASE, 0] == pytest.approx(-last.load_factor, rel=1e-9)


@pytest.mark.parametrize("cohesion", [0.0, 2.0e3])
def test_pushed_beam_slides_at_c_a_plus_mu_n_on_cohesive_joints(cohesion):
    """(b) with a cohesion of its own: joints with c (tension 0, so the cap ft <= c / mu
    holds) under the same stages; the joint under the beam (area 0.4 x 0.1 m, the smaller
    N = P + W_beam) slides first, at H = c A + mu N, worked by hand: c = 2 kPa gives
    80 N + 0.6 x (500 N + 80 N) = 428 N (1 %)."""
    material = InterfaceMaterial(kn=1e9, kt=4e8, friction=MU, cohesion=cohesion)
    model = _specimen()
    cohesive = Model.build(model.blocks, material, supports=[Support([BASE])], loads=[SelfWeight()])
    history = md.pushover(cohesive, stages=[PRECOMPRESSION, _push()])
    assert history.status == "completed", history.reason
    w_beam = float(model.blocks.weights[BEAM])
    expected = cohesion * 0.4 * 0.1 + MU * (P + w_beam)
    pushed = history.load_factors[history.stages == 1]
    assert pushed.max() == pytest.approx(expected, rel=0.01)


def test_a_dof_held_anew_stays_at_its_current_value_and_its_reaction_balances_it():
    """(c) the beam sinks under the precompression (u2 < 0); held in stage 2, u2 keeps that
    value through every step, the joint under it keeps its compression (it would open, were
    the held value taken as zero), and the reactions with the loads balance the joints'
    forces on every held DOF and the whole wall (to 1e-9)."""
    model = _specimen()
    history = md.pushover(model, stages=[PRECOMPRESSION, _push()])
    steps = list(history.steps)
    sunk = [s for s in steps if s.stage == 0][-1].q[BEAM, 1]
    assert sunk < -1e-6
    w_beam = float(model.blocks.weights[BEAM])
    under_beam = np.flatnonzero(
        (model.interfaces.block_i == BEAM) | (model.interfaces.block_j == BEAM)
    )
    assert under_beam.size == 1
    asm = Assembly.of(model)
    dead = model.dead + np.array([0.0, -P, 0, 0, 0, 0]) * (np.arange(3) == BEAM)[:, None]
    live = np.zeros_like(dead)
    live[BEAM, 0] = 1.0
    for step in (s for s in steps if s.stage == 1):
        assert step.q[BEAM, 1] == sunk  # held where it was, exactly
        assert step.q[BEAM, 5] == steps[0].q[BEAM, 5]
        normal = step.actions[under_beam[0], 2]
        assert normal == pytest.approx(-(P + w_beam), rel=1e-6)
        applied = dead + step.load_factor * live
        joints = asm.internal_forces(step.actions).reshape(-1, 6)
        scale = P + w_beam
        # each held DOF: applied load + reaction = the joints' force on it
        held = model.fixed | (np.arange(3) == BEAM)[:, None] & np.isin(np.arange(6), [1, 5])
        balance = (applied + step.reactions - joints)[held]
        assert np.abs(balance).max() <= 1e-9 * scale
        assert np.all(step.reactions[~held] == 0.0)
        # the whole wall: the loads and the reactions have no resultant
        total = (applied + step.reactions)[:, :3].sum(axis=0)
        assert np.abs(total).max() <= 1e-9 * scale


@pytest.mark.parametrize(
    ("stages", "words"),
    [
        ([], "at least one Stage"),
        ("push", "must be a list of Stage"),
        ([{"loads": [], "load_factor": 2.0}], "unknown field 'load_factor' = 2.0"),
        ([{"loads": "self_weight"}], "Stage.loads must be a list"),
        ([Stage(control=DisplacementControl(block=BASE, dof="u1", target=0.01))], "held"),
        ([PRECOMPRESSION, _push(held=("u1", "u2"))], "stages[1] (push).control: dof 'u1'"),
        ([Stage(control=DisplacementControl(block=9, dof="u1", target=0.01))], "block must"),
        ([Stage(supports=[Support([WALL, BEAM])])], "every DOF of the model is held"),
        ([Stage(loads=[PointLoad([7], (1.0, 0, 0))])], "stages[0]"),
        ([3], "stages[0] must be a Stage"),
    ],
)
def test_a_bad_stage_is_named(stages, words):
    """(d) a bad stage is refused before any solve, by a ValueError naming the field and
    the value."""
    with pytest.raises(ValueError) as err:
        md.pushover(_specimen(), stages=stages)
    assert words in str(err.value)


def test_stages_and_control_are_not_both_given():
    with pytest.raises(ValueError, match="give control or stages, not both"):
        md.pushover(
            _specimen(),
            control=DisplacementControl(block=BEAM, dof="u1", target=0.01),
            stages=[PRECOMPRESSION],
        )


def test_stage_fields_are_checked():
    with pytest.raises(ValueError, match=r"Stage.supports\[0\] must be a Support"):
        Stage(supports=[PRECOMPRESSION])
    with pytest.raises(ValueError, match="Stage.control must be a DisplacementControl"):
        Stage(control=("u1", 0.01))
    with pytest.raises(ValueError, match="Stage.name must be a string"):
        Stage(name=3)


def test_analyze_runs_stages_of_the_pushover_only(tmp_path):
    """md.analyze(stages=...) is the pushover's; the results folder and a streamed History
    keep the stage of each step and its reactions."""
    model = _specimen()
    result = md.analyze(model, stages=[PRECOMPRESSION, _push(steps_target := 0.001)], out=tmp_path)
    assert result.status == "completed"
    assert result.history is not None and set(result.history.stages.tolist()) == {0, 1}
    table = read_pushover(tmp_path)
    assert np.array_equal(table["stage"], result.history.stages)
    assert np.allclose(table["lambda"], result.history.load_factors, rtol=1e-9, atol=0)
    assert "stage" not in read_pushover(_plain_folder(tmp_path / "plain"))
    with pytest.raises(ValueError, match="stages is a setting of the pushover"):
        md.analyze(model, "limit", stages=[PRECOMPRESSION])
    streamed = md.pushover(model, stages=[PRECOMPRESSION, _push(steps_target)], stream=True)
    assert np.array_equal(streamed.stages, result.history.stages)
    late = streamed.steps[len(streamed.steps) // 2]  # read back from disk
    assert late.stage == 1 and late.reactions is not None
    assert np.array_equal(late.reactions, result.history.steps[len(streamed.steps) // 2].reactions)


def test_shear_wall_test_of_a_running_bond_wall():
    """Item 2: a dry running-bond wall between a fixed base and a loading beam
    (``add_top_beam``), precompressed through the beam, then the beam held at its height and
    rotation and pushed by displacement. The horizontal force is lambda x the live 1 N on
    the beam against its u1; every bed joint slides at mu x its normal force, the smallest
    in the joint under the beam (N = P + W_beam), so the curve tops at mu (P + W_beam) and
    stays there while the wall slides under the beam."""
    wall = md.running_bond_wall(4, 4, 0.1, 0.2, 0.1, 18e3)
    blocks, base = md.add_base(wall)
    blocks, beam = md.add_top_beam(blocks, depth=0.1, unit_weight=20e3)
    model = Model.build(blocks, DRY, supports=[Support([base])], loads=[SelfWeight()])
    precompression = 2000.0
    history = md.pushover(
        model,
        stages=[
            Stage(loads=[PointLoad([beam], (0.0, -precompression, 0.0))]),
            Stage(
                loads=[PointLoad([beam], (1.0, 0.0, 0.0), live=True)],
                supports=[Support([beam], ["u2", "w3"])],
                control=DisplacementControl(block=beam, dof="u1", target=0.003, steps=30),
            ),
        ],
    )
    assert history.status == "completed", history.reason
    pushed = history.stages == 1
    expected = MU * (precompression + float(blocks.weights[beam]))
    assert history.load_factors[pushed].max() == pytest.approx(expected, rel=0.01)
    assert history.load_factors[-1] == pytest.approx(expected, rel=0.01)
    assert history.control_displacements[-1] == pytest.approx(0.003)


def _plain_folder(folder):
    """The results folder of a run with no stages (its pushover.csv has no stage column)."""
    model = _specimen()
    tilted = Model.build(
        model.blocks,
        DRY,
        supports=[Support([BASE])],
        loads=[SelfWeight(), md.WeightProportional((1.0, 0.0, 0.0))],
    )
    md.pushover(tilted, out=folder)
    return folder


def test_a_later_stage_under_load_control_collapses_certified_and_carries_its_load():
    """A later stage's collapse is certified with the law state it started from: pushed
    under load control the held beam's joint slides at mu N (a certified collapse); pushed
    past sliding by displacement in stage 2, then back under load control in stage 3, the
    stage-2 force mu N stays on (a dead load of stage 3) and the joint slides back when
    lambda x 1 N against it reaches 2 mu N."""
    model = _specimen()
    expected = MU * (P + float(model.blocks.weights[BEAM]))
    hold = [Support([BEAM], ["u2", "w3"])]
    push = Stage(loads=[PointLoad([BEAM], (1.0, 0.0, 0.0), live=True)], supports=hold)
    history = md.pushover(model, stages=[PRECOMPRESSION, push])
    assert history.status == "collapse", history.reason
    assert history.certificate is not None and history.certificate.holds
    assert history.collapse_multiplier == pytest.approx(expected, rel=0.01)
    back = Stage(loads=[PointLoad([BEAM], (-1.0, 0.0, 0.0), live=True)], name="back")
    history = md.pushover(model, stages=[PRECOMPRESSION, _push(target=0.0005), back])
    assert history.status == "collapse", history.reason
    assert history.reason.startswith("stage 3 of 3 (back)")
    assert history.certificate is not None and history.certificate.holds
    assert history.collapse_multiplier == pytest.approx(2 * expected, rel=0.01)
