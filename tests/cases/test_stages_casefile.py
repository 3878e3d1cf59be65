"""``[[stages]]`` in a case file (issue 41, item 4): the loading stages of the pushover, each
with its own loads, supports and control; a loading beam by ``[geometry].top_beam`` and
``select = "beam"``."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.cases.schema import CaseError

P = 1500.0  # the precompression on the beam [N]

WALL = {
    "name": "shear wall",
    "geometry": {
        "builder": "running_bond_wall",
        "blocks_along_length": 3,
        "courses": 3,
        "block_height": 0.1,
        "block_length": 0.2,
        "thickness": 0.1,
        "unit_weight": 18e3,
        "base": True,
        "top_beam": 0.1,
    },
    "material": {"kn": 1e9, "kt": 0.4e9, "friction": 0.6},
    "supports": [{"select": "base"}],
    "loads": [{"type": "self_weight"}],
}

STAGED = {
    **WALL,
    "stages": [
        {
            "name": "precompression",
            "loads": [{"type": "point", "select": "beam", "force": [0, -P, 0]}],
        },
        {
            "name": "push",
            "supports": [{"select": "beam", "dofs": ["u2", "w3"]}],
            "loads": [{"type": "point", "select": "beam", "force": [1, 0, 0], "live": True}],
            "control": {"block": 11, "dof": "u1", "target": 0.001, "steps": 10},
        },
    ],
}


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def test_a_two_stage_case_file_ends_stage_one_at_the_dead_load_state():
    case = case_from_dict(copy.deepcopy(STAGED))
    beam = case.model.blocks.count - 1
    assert beam == 11 and case.stages is not None and len(case.stages) == 2
    assert case.stages[1].control == md.DisplacementControl(
        block=11, dof="u1", target=0.001, steps=10
    )
    history = md.pushover(case.model, case.settings, stages=case.stages)
    assert history.status == "completed", history.reason
    first = [s for s in history.steps if s.stage == 0][-1]
    single = copy.deepcopy(WALL)
    single["loads"].append({"type": "point", "select": [beam], "force": [0, -P, 0]})
    dead = md.pushover(case_from_dict(single).model)
    assert dead.stop is md.StopReason.NO_LIVE_LOAD
    assert _relative(first.q, dead.last.q) <= 1e-9
    assert _relative(first.actions, dead.last.actions) <= 1e-9
    pushed = history.steps[-1]
    assert pushed.stage == 1 and pushed.q[beam, 1] == first.q[beam, 1]


def test_a_case_file_with_no_stages_has_none():
    case = case_from_dict(copy.deepcopy(WALL))
    assert case.stages is None


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (lambda d: d["stages"][0].update(load_factor=2), "[stages][0].load_factor: unknown key"),
        (lambda d: d["stages"][1]["control"].update(dof="u4"), "[stages][1].control.dof"),
        (
            lambda d: d["stages"][1]["control"].update(dof="u2"),
            "stages[1] (push).control: dof 'u2' of block 11 is held",
        ),
        (lambda d: d["stages"][0]["loads"][0].update(type="wind"), "[stages][0].loads[0].type"),
        (lambda d: d.update(stages=[]), "at least one Stage"),
        (
            lambda d: d.update(analysis={"control": {"block": 11, "dof": "u1", "target": 0.01}}),
            "each stage names its own control",
        ),
        (lambda d: d["geometry"].pop("top_beam"), 'select = "beam" but the geometry has no'),
        (lambda d: d["geometry"].update(top_beam=-0.1), "[geometry].top_beam = -0.1"),
    ],
)
def test_a_bad_stage_table_is_named(change, words):
    data = copy.deepcopy(STAGED)
    change(data)
    with pytest.raises(CaseError) as err:
        case_from_dict(data)
    assert words in str(err.value)


def test_masonry_dem_run_runs_the_stages_and_limit_refuses_them(tmp_path, capsys):
    """``masonry-dem run`` of the two-stage file: its pushover is the staged one (the stage
    column in pushover.csv; the beam pushed by displacement reaches mu (P + the beam's
    weight, 0 here) = 0.6 x 1500 N = 900 N, 1 %), not the model's own loads alone (which push
    nothing); ``masonry-dem limit`` refuses the file, named."""
    import json

    from helpers.case_files import write_case
    from masonry_dem.cli import main

    path = write_case(tmp_path, copy.deepcopy(STAGED))
    out = tmp_path / "res"
    assert main(["run", str(path), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    rows = np.loadtxt(out / "pushover.csv", delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[1] == 4 and set(rows[:, 3]) == {0.0, 1.0}
    assert summary["status"] == "completed"
    assert rows[:, 1].max() == pytest.approx(0.6 * P, rel=0.01)
    capsys.readouterr()
    assert main(["limit", str(path), "--out", str(tmp_path / "la")]) == 2
    assert "loading stages" in capsys.readouterr().err


def test_an_idle_load_of_a_stage_is_named_once_per_run(tmp_path, caplog):
    """A stage's live load on held DOFs alone (a push on the base) is named when the stages
    are planned to run, once: loading the file checks the stages without warning."""
    import logging

    from helpers.case_files import write_case
    from masonry_dem.cli import main

    data = copy.deepcopy(STAGED)
    data["stages"][1]["loads"].append(
        {"type": "point", "select": "base", "force": [1, 0, 0], "live": True}
    )
    path = write_case(tmp_path, data)
    with caplog.at_level(logging.WARNING):
        assert (
            main(["run", str(path), "--out", str(tmp_path / "res"), "--no-render", "--quiet"]) == 0
        )
    named = [r for r in caplog.records if "acts only on held DOFs" in r.getMessage()]
    assert len(named) == 1 and "loads[1] (PointLoad, live)" in named[0].getMessage()


def test_a_builder_that_builds_its_own_slabs_refuses_another_named():
    """The shear wall declares its beams (``base``, then ``beam``): ``select = "base"`` is
    its bottom beam and ``"beam"`` its top one; ``base`` or ``top_beam`` given besides is
    refused, named."""
    wall = {
        "builder": "shear_wall",
        "length": 0.6,
        "courses": 3,
        "a": 0.1,
        "b": 0.2,
        "s": 0.1,
        "unit_weight": 18e3,
    }
    data = {**WALL, "geometry": wall}
    case = case_from_dict(copy.deepcopy(data))
    blocks = case.model.blocks
    base, beam = blocks.count - 2, blocks.count - 1
    assert case.model.fixed[base].all() and not case.model.fixed[beam].any()
    assert blocks.centres[beam, 1] == blocks.centres[:, 1].max()
    for key, value in (("base", True), ("top_beam", 0.1)):
        bad = copy.deepcopy(data)
        bad["geometry"][key] = value
        with pytest.raises(ValueError, match=f"{key}: builder 'shear_wall' builds its own slabs"):
            case_from_dict(bad)
