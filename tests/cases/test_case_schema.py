"""Every class of bad input in issue 24 ends with exit code 2 and one line naming the file,
the table path and the value as written (no traceback, no numpy repr); on 7022155 each of
these ran silently, raised a traceback, or named neither the field nor the value."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np
import pytest

from masonry_dem.cli import main

GOOD = """\
name = "block"
[geometry]
builder = "single_block"
a = 0.4
b = 0.3
s = 0.2
unit_weight = 20e3
base = true
[material]
kn = 2.4e9
kt = 1e9
friction = 0.7
[[supports]]
select = "base"
[[loads]]
type = "self_weight"
[[loads]]
type = "weight_proportional"
direction = [0, 0, 1]
"""

WALL = GOOD.replace(
    'builder = "single_block"',
    'builder = "running_bond_wall"\nblocks_along_length = 2\ncourses = 3',
)


def _edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


# (case text, what the one line must name): the table path and the value as written
CASES = {
    # silent misreadings on 7022155
    "live as text": (GOOD + 'live = "false"\n', '[loads][1].live = "false"'),
    "base as text": (_edit(GOOD, "base = true", 'base = "no"'), '[geometry].base = "no"'),
    "refine as text": (GOOD + '[analysis]\nrefine = "no"\n', '[analysis].refine = "no"'),
    "fractional index": (
        GOOD + "[[supports]]\nselect = [15.7]\n",
        "[supports][1].select = [15.7]",
    ),
    "size as text": (_edit(GOOD, "a = 0.4", 'a = "0.081"'), '[geometry].a = "0.081"'),
    # silent wrong answers on 7022155: refused at the input with the range and the unit
    "friction 1e10": (_edit(GOOD, "friction = 0.7", "friction = 1e10"), "[material].friction"),
    "kn 1e300": (_edit(GOOD, "kn = 2.4e9", "kn = 1e300"), "[material].kn = 1e300"),
    # a cohesion of its own: its range, and the tension cap ft <= c / mu
    "negative cohesion": (
        _edit(GOOD, "friction = 0.7", "friction = 0.7\ncohesion = -1.0"),
        "[material].cohesion = -1",
    ),
    "tension above c / mu": (
        _edit(GOOD, "friction = 0.7", "friction = 0.7\ntensile_strength = 2e5\ncohesion = 1e5"),
        "[material]: tensile_strength must be at most cohesion / friction = 142857 Pa",
    ),
    "negative max_load_factor": (
        GOOD + "[analysis]\nmax_load_factor = -1\n",
        "[analysis].max_load_factor = -1",
    ),
    "control target NaN": (
        GOOD + '[analysis]\ncontrol = { block = 0, dof = "u3", target = nan }\n',
        "[analysis].control.target = nan",
    ),
    # tracebacks on 7022155
    "kn as text": (_edit(GOOD, "kn = 2.4e9", 'kn = "1e9"'), '[material].kn = "1e9"'),
    "courses inf": (_edit(WALL, "courses = 3", "courses = inf"), "[geometry].courses = inf"),
    "dofs as a number": (
        GOOD.replace('select = "base"', 'select = "base"\ndofs = 5'),
        "[supports][0].dofs = 5",
    ),
    "growth as text": (GOOD + '[analysis]\ngrowth = "fast"\n', '[analysis].growth = "fast"'),
    "max_steps as text": (
        GOOD + '[analysis]\nmax_steps = "many"\n',
        '[analysis].max_steps = "many"',
    ),
    "loads as a table": (
        GOOD.split("[[loads]]")[0] + '[loads]\ntype = "self_weight"\n',
        "[loads] = a table",
    ),
    "incomplete control": (
        GOOD + "[analysis]\ncontrol = { block = 0 }\n",
        "[analysis].control.dof is missing",
    ),
    "incomplete monitor": (
        GOOD + '[analysis]\nmonitor = { dof = "u3" }\n',
        "[analysis].monitor.block is missing",
    ),
    # messages that named neither the field nor the cause on 7022155
    "count as a fraction": (
        _edit(WALL, "courses = 3", "courses = 2.5"),
        "[geometry].courses = 2.5",
    ),
    "openings as text": (
        GOOD.replace("base = true", 'base = true\nopenings = "cest"'),
        '[geometry].openings = "cest"',
    ),
    "negative size": (_edit(GOOD, "a = 0.4", "a = -0.081"), "[geometry].a = -0.081"),
    "misspelled key": (_edit(GOOD, "friction = 0.7", "frction = 0.7"), "did you mean friction?"),
    "unknown load type": (
        _edit(GOOD, 'type = "self_weight"', 'type = "wind"'),
        '[loads][0].type = "wind"',
    ),
    "zero direction": (
        _edit(GOOD, "direction = [0, 0, 1]", "direction = [0, 0, 0]"),
        "[loads][1].direction",
    ),
    "control block out of range": (
        GOOD + '[analysis]\ncontrol = { block = 7, dof = "u3", target = 0.01 }\n',
        "[analysis].control.block",
    ),
    "tension option": (
        GOOD + '[analysis]\ntension = "none"\n',
        "tension is a property of the interface law: [material] tension",
    ),
    "bool as a count": (_edit(WALL, "courses = 3", "courses = true"), "[geometry].courses = true"),
    "course selector": (
        _edit(GOOD, 'select = "base"', 'select = "course:x"'),
        "[supports][0].select",
    ),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_case_file_exits_2_naming_path_and_value(name, tmp_path, capsys):
    text, expected = CASES[name]
    case = tmp_path / "case.toml"
    case.write_text(text)
    rc = main(["run", str(case), "--out", str(tmp_path / "out"), "--no-render", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("masonry-dem: error: "), err
    assert str(case) in err and expected in err, err
    assert "np." not in err and "Traceback" not in err
    assert not (tmp_path / "out" / "summary.json").exists()  # refused before any run


def test_range_errors_name_the_range_and_the_unit(tmp_path, capsys):
    case = tmp_path / "case.toml"
    case.write_text(_edit(GOOD, "kn = 2.4e9", "kn = 1e300"))
    assert main(["run", str(case), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "from 1e5 to 1e14 N/m^3" in err


def test_friction_above_two_runs_with_a_warning(tmp_path, caplog):
    """mu = 3 is allowed (interlocking) but named: a dry block still tilts at s/a = 0.5."""
    case = tmp_path / "case.toml"
    case.write_text(_edit(GOOD, "friction = 0.7", "friction = 3.0"))
    with caplog.at_level(logging.WARNING):
        rc = main(["run", str(case), "--out", str(tmp_path / "o"), "--no-render", "--quiet"])
    assert rc == 0
    assert any("[material].friction = 3.0" in r.getMessage() for r in caplog.records)
    assert any("interlocking" in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize(
    "make, expected",
    [
        (lambda p: p.write_bytes(b'name = "w\xe4ll"\n'), "is not UTF-8 text"),
        (lambda p: p.mkdir(), "is a folder"),
        (lambda p: p.write_text("[geometry\n"), "is not valid TOML"),
    ],
    ids=["latin-1", "folder", "toml"],
)
def test_unreadable_case_files_are_named(make, expected, tmp_path, capsys):
    case = tmp_path / "case.toml"
    make(case)
    assert main(["run", str(case), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert expected in err and str(case) in err and len(err.strip().splitlines()) == 1


def test_debug_shows_the_traceback(tmp_path, capsys):
    case = tmp_path / "case.toml"
    case.write_text(_edit(GOOD, "kn = 2.4e9", 'kn = "1e9"'))
    assert main(["--debug", "run", str(case), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and "CaseError" in err


def test_schema_reads_the_builder_registry(monkeypatch):
    """A builder added to ``_BUILDERS`` is checked by its own signature, with no schema edit."""
    from masonry_dem.cases import casefile
    from masonry_dem.cases.schema import CaseError
    from masonry_dem.geometry import builders

    def tower(levels: int, a: float, b: float, s: float, unit_weight: float, hollow: bool = False):
        return builders.stack_bond_column(levels, a, b, s, unit_weight)

    monkeypatch.setitem(casefile._BUILDERS, "tower", tower)
    geometry = {"builder": "tower", "levels": 2, "a": 0.4, "b": 0.3, "s": 0.2, "unit_weight": 2e4}
    data = {
        "geometry": {**geometry, "base": True},
        "material": {"kn": 1e9, "kt": 1e9, "friction": 0.7},
        "supports": [{"select": "base"}],
    }
    assert casefile.case_from_dict(data).model.blocks.count == 3
    for key, value, text in [
        ("levels", 2.5, "[geometry].levels = 2.5"),
        ("hollow", "no", '[geometry].hollow = "no"'),
        ("a", float("inf"), "[geometry].a = inf"),
        ("roof", 1, "[geometry].roof: unknown key"),
    ]:
        bad = {**data, "geometry": {**data["geometry"], key: value}}
        with pytest.raises(CaseError, match=re.escape(text)):
            casefile.case_from_dict(bad, "t.toml")


@pytest.mark.parametrize(
    "doc, after", [("README.md", "## Modelling your wall"), ("docs/case_files.md", "## The schema")]
)
def test_the_printed_case_files_pass_the_schema(doc, after):
    """The case file of the README (a wall of 3 x 13 blocks on a base, held by a return wall
    on the left, on a tilt table out of plane) and the full template of docs/case_files.md,
    as printed, are read (the optional opening commented out)."""
    text = (Path(__file__).resolve().parents[2] / doc).read_text()
    block = text.split(after)[1].split("```toml")[1].split("```")[0]
    block = block.replace("openings = [[0.2, 0.3, 0.4, 0.6]]", "# openings")
    from masonry_dem._toml import tomllib
    from masonry_dem.cases.casefile import case_from_dict

    case = case_from_dict(tomllib.loads(block), doc)
    model = case.model
    assert model.name == "my wall" and case.method == "pushover"
    assert model.blocks.count == 3 * 13 + 6 + 1  # 6 courses of 2 halves and 2 whole; the base
    live = np.asarray(model.live).reshape(-1, 6)
    assert np.abs(live[:, 2]).sum() > 0 and np.abs(live[:, [0, 1]]).sum() == 0  # along e3


def test_law_options_belong_to_the_material(tmp_path, capsys):
    """tension, memory and projection are [material] fields that reach the interface law;
    given in [analysis], the error says where they belong, and a bad value names the field
    and the allowed values."""
    from masonry_dem.cases.casefile import load_case
    from masonry_dem.solvers.static.problem import DiscreteProblem

    path = tmp_path / "law.toml"
    law_fields = 'tension = "plastic"\nmemory = "slip"\nprojection = "radial"\n'
    path.write_text(_edit(GOOD, "friction = 0.7\n", "friction = 0.7\n" + law_fields))
    law = DiscreteProblem(load_case(str(path)).model).law
    assert (law.tension, law.memory, law.projection) == ("plastic", "slip", "radial")

    path.write_text(GOOD + '[analysis]\nmemory = "slip"\n')
    with pytest.raises(
        ValueError, match=r"memory is a property of the interface law: \[material\] memory"
    ):
        load_case(str(path))

    path.write_text(_edit(GOOD, "friction = 0.7\n", 'friction = 0.7\ntension = "elastic"\n'))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert '[material].tension = "elastic"' in err and "brittle" in err and "plastic" in err


def test_the_schema_and_the_case_file_know_the_same_load_types():
    """A ``[[loads]]`` type the schema accepts is one the case file can build, and its keys are
    the load's fields (``select`` for ``blocks``)."""
    from dataclasses import fields

    from masonry_dem.cases.schema import LOAD_TABLES
    from masonry_dem.model import LOAD_TYPES

    assert set(LOAD_TABLES) == set(LOAD_TYPES)
    for kind, load in LOAD_TYPES.items():
        keys = {"select" if f.name == "blocks" else f.name for f in fields(load)} | {"type"}
        assert set(LOAD_TABLES[kind].model_fields) == keys, kind


def test_a_cohesion_of_its_own_reaches_the_model(tmp_path):
    from masonry_dem.cases.casefile import load_case

    case = tmp_path / "case.toml"
    case.write_text(
        _edit(
            GOOD, "friction = 0.7", "friction = 0.75\ntensile_strength = 0.16e6\ncohesion = 0.224e6"
        )
    )
    model = load_case(case).model
    np.testing.assert_array_equal(model.cohesion, 0.224e6)
    case.write_text(_edit(GOOD, "friction = 0.7", "friction = 0.75\ntensile_strength = 0.16e6"))
    np.testing.assert_array_equal(load_case(case).model.cohesion, 0.75 * 0.16e6)
