"""Inputs a new user gives the static solver (found by the new-user sweep, session 17):
each ends in a status or a named error, never a traceback from inside the solver."""

from __future__ import annotations

import math

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.solvers.static.outcome import Status, StopReason
from masonry_dem.solvers.static.settings import DisplacementControl


def _wall(kn: float, kt: float, loads: list) -> md.Model:
    wall = md.running_bond_wall(
        2, 3, block_height=0.081, block_length=0.21, thickness=0.07, unit_weight=20e3
    )
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=kn, kt=kt, friction=0.7),
        supports=[md.Support([base])],
        loads=loads,
    )


@pytest.mark.parametrize(
    ("args", "field"),
    [
        ((0, "u3", math.nan), "target"),
        ((0, "u3", 0.0), "target"),
        ((0, "u3", math.inf), "target"),
        ((0, "u7", 1e-3), "dof"),
        ((-1, "u3", 1e-3), "block"),
        ((0.5, "u3", 1e-3), "block"),
        ((0, "u3", 1e-3, 0), "steps"),
    ],
)
def test_displacement_control_names_the_field_it_refuses(args: tuple, field: str) -> None:
    with pytest.raises(ValueError, match=f"^{field} must be"):
        DisplacementControl(*args)


def test_displacement_control_takes_numpy_integers() -> None:
    control = DisplacementControl(np.int64(3), "u3", 1e-3, np.int64(5))
    assert (control.block, control.steps) == (3, 5)


def test_settings_given_as_a_dict_are_named() -> None:
    model = _wall(1e9, 0.4e9, [md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))])
    with pytest.raises(TypeError, match="settings must be a StaticSettings"):
        md.pushover(model, {"max_steps": 5})  # type: ignore[arg-type]


def test_max_steps_counts_converged_steps_not_the_attempts_of_a_bracket() -> None:
    """A live tilt with no dead load: dry joints carry no normal force, so no equilibrium
    exists above lambda = 0, and load control refines its bracket down to zero load (about
    45 failed attempts). ``max_steps`` counts converged steps, so 40 leaves the answer of the
    default settings: a collapse at 0, not 'max_steps reached'."""
    model = _wall(1e9, 0.4e9, [md.WeightProportional(direction=(0, 0, 1))])
    default = md.pushover(model)
    capped = md.pushover(model, md.StaticSettings(max_steps=40))
    assert default.status == capped.status == Status.COLLAPSE
    assert capped.stop == StopReason.LOAD_BRACKET
    assert capped.final_load_factor == default.final_load_factor == 0.0


def test_a_tangent_that_cannot_be_factored_ends_failed_with_its_reason() -> None:
    """kn = 1e300 beside kt = 1e9: 291 decades apart, no factorization of the tangent is
    regular even with the stiffened floor. The run ends ``failed`` and says why."""
    loads = [md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))]
    history = md.pushover(_wall(1e300, 1e9, loads))
    assert history.status == Status.FAILED
    assert history.stop == StopReason.SINGULAR_TANGENT
    assert "cannot be factored" in history.reason
