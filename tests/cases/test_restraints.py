"""What a held column means under the dead load: a column with u2 fixed does not settle and
the wall hangs on it; a column that ``settles_with_wall`` sinks course by course exactly as
the wall does, as the corner of an L wall with its return wall as blocks does."""

from __future__ import annotations

import numpy as np
import pytest

from masonry_dem.assembly.stiffness import Assembly
from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.geometry import selectors as sel
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.geometry.plans import l_wall
from masonry_dem.model import DOF_NAMES, InterfaceMaterial, Model, SelfWeight, Support
from masonry_dem.solvers.incremental import pushover

A, B, S, GAMMA, NC = 0.081, 0.21, 0.07, 20e3, 8
KN = 2.4e9
DRY = InterfaceMaterial(kn=KN, kt=1.0e9, friction=0.7)


def _settlement(k):
    """Closed form: course k sinks by (gamma a / kn) sum_{j <= k} (nc - j) (each bed joint j
    uniformly compressed by the nc - j courses above it)."""
    return GAMMA * A / KN * np.cumsum(NC - np.arange(NC))[k]


def _dead_state(wall, supports, base):
    blocks = add_base(wall)[0]
    model = Model.build(blocks, DRY, [Support([base]), *supports], [SelfWeight()])
    h = pushover(model)
    assert h.status == "completed", h.reason
    asm = Assembly.of(model)
    reactions = (asm.internal_forces(h.last.actions) - model.dead.reshape(-1)).reshape(-1, 6)
    reactions[~model.fixed] = 0.0
    return model, h.last, reactions


def _course_of(wall):
    return np.rint(wall.centres[:, 1] / A - 0.5).astype(int)


@pytest.mark.parametrize(
    ("dofs", "fixed"),
    [
        (["u1", "u3"], ["u1", "u3"]),
        ("all", ["u1", "u3", "w1", "w2", "w3"]),
        ("translations", ["u1", "u3"]),
        (["u2"], []),
    ],
)
def test_settles_with_wall_frees_only_u2(dofs, fixed):
    plain = Support([0, 2], dofs).mask(3)
    settling = Support([0, 2], dofs, settles_with_wall=True).mask(3)
    np.testing.assert_array_equal(settling[1], False)
    assert [DOF_NAMES[d] for d in np.flatnonzero(settling[0])] == fixed
    np.testing.assert_array_equal(settling[:, [0, 2, 3, 4, 5]], plain[:, [0, 2, 3, 4, 5]])
    with pytest.raises(ValueError, match="settles_with_wall must be true or false, got 'yes'"):
        Support([0], dofs, settles_with_wall="yes").mask(3)  # type: ignore[arg-type]


def test_a_column_held_in_u2_does_not_settle_and_the_wall_hangs_on_it():
    """u2 fixed: the column stays at zero while the wall beside it sinks, its head joints
    shear, and its support carries part of the wall's weight (the base the rest)."""
    wall = running_bond_wall(3, NC, A, B, S, GAMMA)
    column = sel.column(wall, "left")
    _, state, reactions = _dead_state(wall, [Support(column, "all")], wall.count)
    assert np.abs(state.q[column, 1]).max() == 0.0
    far = sel.column(wall, "right")
    assert state.q[far, 1].min() < -0.5 * _settlement(NC - 1)
    hung = reactions[column, 1].sum()
    base = reactions[wall.count, 1]
    assert hung + base == pytest.approx(wall.weights.sum(), rel=1e-6)
    # the column carries its own weight and more: the wall beside it hangs on it
    assert hung > 1.2 * wall.weights[column].sum()


def test_a_column_that_settles_with_the_wall_sinks_as_its_course_does():
    """settles_with_wall: every block of course k, the column's included, sinks by the
    closed-form delta_k; the column's support carries no weight, the head joints nothing."""
    wall = running_bond_wall(3, NC, A, B, S, GAMMA)
    column = sel.column(wall, "left")
    model, state, reactions = _dead_state(
        wall, [Support(column, "all", settles_with_wall=True)], wall.count
    )
    k = _course_of(wall)
    np.testing.assert_allclose(state.q[: wall.count, 1], -_settlement(k), rtol=1e-6)
    assert np.abs(reactions[column]).max() <= 1e-6 * wall.weights.sum()
    assert reactions[wall.count, 1] == pytest.approx(wall.weights.sum(), rel=1e-6)
    head = model.interfaces.axis != 1
    assert np.abs(state.actions[head]).max() <= 1e-6 * wall.weights.max()


def test_a_return_wall_as_blocks_settles_as_a_column_that_settles_with_the_wall():
    """The corner of an L wall (its return wall as blocks) sinks with the facade under the
    dead load, exactly as the held column that settles with the wall: the facade's dead-load
    state is the same in both readings, and not in the u2-fixed one."""
    n = 3
    wall = l_wall(n, NC, A, B, S, GAMMA, return_blocks=3)
    _, state, _ = _dead_state(wall, [], wall.count)
    corner = sel.part(wall, "corner:left")
    k = _course_of(wall)
    np.testing.assert_allclose(state.q[corner, 1], -_settlement(k[corner]), rtol=1e-6)
    flat = running_bond_wall(n, NC, A, B, S, GAMMA)
    held = Support(sel.column(flat, "left"), "all", settles_with_wall=True)
    _, flat_state, _ = _dead_state(flat, [held], flat.count)
    np.testing.assert_allclose(
        np.sort(flat_state.q[: flat.count, 1]),
        np.sort(-_settlement(_course_of(flat))),
        rtol=1e-6,
    )


def test_case_file_takes_settles_with_wall():
    data = {
        "geometry": {
            "builder": "running_bond_wall",
            "blocks_along_length": 3,
            "courses": 4,
            "a": A,
            "b": B,
            "s": S,
            "unit_weight": GAMMA,
            "base": True,
        },
        "material": {"kn": KN, "kt": 1e9, "friction": 0.7},
        "supports": [
            {"select": "base"},
            {"select": "column:left", "dofs": "all", "settles_with_wall": True},
        ],
    }
    model = case_from_dict(data).model
    column = sel.column(model.blocks, "left", among=np.arange(model.blocks.count - 1))
    np.testing.assert_array_equal(model.fixed[column, 1], False)
    assert model.fixed[column][:, [0, 2, 3, 4, 5]].all()


def test_table_2_columns_are_read_as_settling_with_the_wall():
    """The paper's fixed columns of Table 2 ("translations and rotations") are read as held
    columns that settle with the wall: the same fixed DOFs as
    Support(column, "all", settles_with_wall=True); Table 1's keep u1, u3 (free to turn)."""
    from masonry_dem.cases.paper import Assumptions, build_case

    case = build_case("S13")
    wall = case.model.blocks.subset(case.wall)
    column = sel.column(wall, "left")
    held = Support(column, "all", settles_with_wall=True).mask(case.model.blocks.count)
    np.testing.assert_array_equal(case.model.fixed[column], held[column])
    assert "u2" not in Assumptions().column_dofs_table1
