"""What ``masonry-dem limit`` writes is clear (issue 37, item 5): only finite numbers in every
file, the bound's kind with a reason, a "no mechanism" that names the supports, and a case
file with ``method = "limit"`` that refuses the pushover's keys."""

from __future__ import annotations

import json
from dataclasses import replace
from importlib import resources
from pathlib import Path
from types import SimpleNamespace

import meshio
import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from helpers.case_files import write_case as _write_case
from masonry_dem.cases.casefile import DEFAULT_CASE, case_from_dict
from masonry_dem.cases.paper import build_case
from masonry_dem.cases.schema import CaseError
from masonry_dem.cli import main
from masonry_dem.cli.limit import run_limit
from masonry_dem.export.limit_results import UTILISATION_CAP, ZERO_CAPACITY

#: validation cases the associative analysis runs in about a second each: the wall of OL2
#: is held on both edges (no collapse), S15 collapses, S5 has a return wall (no collapse)
QUICK_CASES = ("OL2", "S15", "S5")


def _refuse_constant(text: str) -> float:
    raise AssertionError(f"summary.json holds the non-JSON constant {text}")


def _assert_finite_files(folder: Path) -> dict:
    """Every VTU array and every JSON number in ``folder`` finite; returns the summary."""
    vtus = sorted(folder.glob("*.vtu"))
    for path in vtus:
        mesh = meshio.read(path)
        arrays = {**mesh.point_data, **{k: v[0] for k, v in mesh.cell_data.items()}}
        for name, values in arrays.items():
            assert np.isfinite(np.asarray(values, dtype=float)).all(), (path.name, name)
    with open(folder / "summary.json") as f:
        summary = json.load(f, parse_constant=_refuse_constant)
    return {**summary, "_vtus": [p.name for p in vtus]}


@pytest.mark.parametrize(
    "options", [[], ["--non-associative"], ["--backend", "clarabel", "--dem-bound"]]
)
def test_limit_of_the_default_wall_writes_only_finite_values(tmp_path, options):
    """The default wall's collapse puts whole joint compressions at one corner, where the DEM's
    capacity is zero (utilisation inf on 24 of its 107 joints with HiGHS, 65 non-associative,
    before): the VTU caps them and says so in ``utilisation_capped``."""
    out = tmp_path / "la"
    assert main(["limit", "--out", str(out), "--no-render", *options]) == 0
    summary = _assert_finite_files(out)
    assert summary["status"] == "collapse"
    assert "mechanism_interfaces.vtu" in summary["_vtus"]
    cells = meshio.read(out / "mechanism_interfaces.vtu").cell_data
    util, why = cells["utilisation"][0], cells["utilisation_capped"][0]
    if "--backend" not in options:  # the exact cone's actions leave no joint at zero capacity
        assert (why == ZERO_CAPACITY).any()
    assert np.all(util[why != 0] == UTILISATION_CAP) and np.all(util <= UTILISATION_CAP)


@pytest.mark.parametrize("name", QUICK_CASES)
def test_limit_of_validation_cases_writes_only_finite_values(tmp_path, name):
    """A "no collapse" once wrote ``"load_factors": [NaN]`` into summary.json."""
    paper = build_case(name)
    case = SimpleNamespace(model=paper.model, source=f"paper:{name}")
    summary = run_limit(case, tmp_path / name, {}, render=False)
    written = _assert_finite_files(tmp_path / name)
    assert written["status"] == summary["status"]
    if summary["status"] == "no collapse":
        assert written["lambda"] is None and written["bound"] == "none"
        # the solver knows no finer cause than "the supports hold it": it names them
        assert "held in" in written["reason"], written["reason"]
        # and says that rigid blocks carrying the load prove nothing of the real wall
        assert "no proof that the wall stands" in written["reason"], written["reason"]
    else:
        assert written["_vtus"] == ["mechanism_blocks.vtu", "mechanism_interfaces.vtu"]


def test_method_limit_in_run_writes_only_finite_values(tmp_path, capsys):
    """``run`` on the default wall with ``method = "limit"``: its pushover key
    (``bracket_tolerance``) refused with one line, then, without it, finite files."""
    text = resources.files("masonry_dem.cases").joinpath("data", DEFAULT_CASE).read_text()
    assert "[analysis]\nbracket_tolerance" in text
    case = tmp_path / "wall.toml"
    case.write_text(text.replace("[analysis]\n", '[analysis]\nmethod = "limit"\n'))
    out = tmp_path / "run_la"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert any("[analysis].bracket_tolerance = 0.005: not used by" in line for line in err), err
    case.write_text(
        text.replace("[analysis]\nbracket_tolerance", '[analysis]\nmethod = "limit"\n#')
    )
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = _assert_finite_files(out)
    assert summary["analysis"] == "limit" and summary["status"] == "collapse"


def test_summary_names_the_bound_and_why(tmp_path, capsys):
    """upper with --dem-bound; an estimate for alpha 1.5 without it (saying alpha and the
    cure) and for the non-associative analysis (saying why); none without a multiplier."""
    case = _write_case(tmp_path, SINGLE_BLOCK)

    def limit(*options: str) -> dict:
        out = tmp_path / f"la{len(list(tmp_path.iterdir()))}"
        code = main(["limit", str(case), "--out", str(out), "--no-render", *options])
        summary = json.loads((out / "summary.json").read_text())
        assert code == 0 and summary["status"] == "collapse", summary["reason"]
        return summary

    plain = limit()
    assert plain["bound_reason"] in capsys.readouterr().out  # said on the terminal too
    assert plain["bound"] == "estimate"
    assert "alpha = 1.5 > 1" in plain["bound_reason"] and "--dem-bound" in plain["bound_reason"]
    upper = limit("--dem-bound")
    assert upper["bound"] == "upper" and "upper bound" in upper["bound_reason"]
    non = limit("--non-associative", "--grid", "4")
    assert non["bound"] == "estimate" and "non-associative" in non["bound_reason"]
    for summary in (plain, upper, non):
        assert "\n" not in summary["bound_reason"]
    none = tmp_path / "none"
    no_live = dict(SINGLE_BLOCK, loads=[{"type": "self_weight"}])
    main(["limit", str(_write_case(tmp_path, no_live)), "--out", str(none), "--no-render"])
    summary = json.loads((none / "summary.json").read_text())
    assert summary["bound"] == "none" and summary["lambda"] is None
    assert "no collapse" in summary["bound_reason"]


@pytest.mark.parametrize(
    ("key", "value"),
    [("control", {"block": 0, "dof": "u3", "target": 0.01}), ("tolerance", 1e-5)],
)
def test_method_limit_refuses_the_pushover_keys(key, value):
    """They were silently ignored: the user believed the control acted."""
    data = dict(SINGLE_BLOCK, analysis={"method": "limit", key: value})
    with pytest.raises(CaseError, match=rf'\[analysis\]\.{key} = .*not used by method = "limit"'):
        case_from_dict(data)
    # the options of the limit analysis stay allowed
    ok = dict(SINGLE_BLOCK, analysis={"method": "limit", "grid": 4, "associative": False})
    assert case_from_dict(ok).limit_options == {"grid": 4, "associative": False}


def test_estimate_reasons_name_the_gap_they_can_prove(tmp_path):
    """``bound_reason`` of an estimate says what is proven, specific to its kind (it was one
    generic sentence): the non-associative one the associative multiplier above it and the
    gap in per cent, the alpha > 1 one the joints and the kappa that makes it a bound, the
    inscribed pyramid its side of the exact cone."""
    from masonry_dem.export.limit_results import bound_of
    from masonry_dem.solvers.limit_analysis import limit_analysis

    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "non"
    assert main(["limit", str(case), "--out", str(out), "--no-render", "--non-associative"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    la = summary["limit_analysis"]
    upper, lam = la["associative_lambda"], summary["lambda"]
    assert la["start"] == "elastic" and upper >= lam > 0
    reason = summary["bound_reason"]
    assert f"{upper:.6g}" in reason and "from the elastic state" in reason
    if lam < upper * (1 - 1e-9):
        assert f"{upper / lam - 1:+.1%} above this estimate" in reason
    else:  # the single block tips with no sliding: the iteration reaches the associative
        assert "proven gap above is 0" in reason
    model = case_from_dict(SINGLE_BLOCK).model
    plain = limit_analysis(model, backend="highs")
    kind, reason = bound_of(model, plain)
    assert kind == "estimate" and "on 1 of 1 joints" in reason and "x 1.065" in reason
    inscribed = limit_analysis(model, backend="highs", cone="inscribed", friction_sides=8)
    kind, reason = bound_of(model, inscribed)
    assert kind == "estimate" and "inscribed 8-face" in reason and "x 1.082" in reason
    # a non-associative result without its associative multiplier still says why
    kind, reason = bound_of(model, replace(inscribed, method="non-associative", info={}))
    assert kind == "estimate" and "either side" in reason


def test_start_of_the_non_associative_analysis_from_the_cli_and_the_case_file(tmp_path, capsys):
    """``--start`` and ``[analysis] start`` reach the analysis (the summary names it); a start
    for the associative analysis, which has none, or outside the allowed values is refused
    with one line."""
    case = _write_case(tmp_path, SINGLE_BLOCK)

    def limit(*options: str) -> tuple[int, dict | None]:
        out = tmp_path / f"s{len(list(tmp_path.iterdir()))}"
        code = main(["limit", str(case), "--out", str(out), "--no-render", *options])
        path = out / "summary.json"
        return code, json.loads(path.read_text()) if path.exists() else None

    code, summary = limit("--non-associative", "--start", "associative")
    assert code == 0 and summary is not None
    assert summary["limit_analysis"]["start"] == "associative"
    assert "from the associative state" in summary["bound_reason"]
    capsys.readouterr()
    code, summary = limit("--start", "associative")  # associative: no starting state
    assert code == 2 and summary is None
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "add --non-associative" in err[0], err
    with pytest.raises(SystemExit):
        main(["limit", str(case), "--non-associative", "--start", "magic"])
    # the case file: checked like the other keys, and only with associative = false
    ok = dict(
        SINGLE_BLOCK, analysis={"method": "limit", "associative": False, "start": "associative"}
    )
    assert case_from_dict(ok).limit_options == {"associative": False, "start": "associative"}
    (tmp_path / "file").mkdir()
    from_file = _write_case(tmp_path / "file", ok)
    out = tmp_path / "from_file"
    assert main(["limit", str(from_file), "--out", str(out), "--no-render"]) == 0
    written = json.loads((out / "summary.json").read_text())
    assert written["method"] == "non-associative"
    assert written["limit_analysis"]["start"] == "associative"
    # --associative overrides the file's method: its start goes with it
    out2 = tmp_path / "overridden"
    assert main(["limit", str(from_file), "--associative", "--out", str(out2), "--no-render"]) == 0
    assert json.loads((out2 / "summary.json").read_text())["method"] == "associative"
    bad = [
        ({"method": "limit", "associative": False, "start": "magic"}, "must be one of elastic"),
        ({"method": "limit", "start": "elastic"}, "needs associative = false"),
        ({"start": "elastic"}, 'needs method = "limit"'),
    ]
    for analysis, message in bad:
        with pytest.raises(CaseError, match=message):
            case_from_dict(dict(SINGLE_BLOCK, analysis=analysis))


def test_the_schema_allows_the_solver_starts():
    from masonry_dem.cases.schema import LIMIT_STARTS
    from masonry_dem.solvers.limit_analysis.settings import STARTS

    assert LIMIT_STARTS == STARTS


def test_limit_shows_its_iterations_unless_quiet(tmp_path, capsys):
    """A wall the normal equations solve (a 30 x 33 default wall, 1 007 blocks) shows its
    interior point iterations on stderr; ``--quiet`` shows nothing there."""
    pytest.importorskip("pypardiso")
    text = (resources.files("masonry_dem.cases.data") / "default_wall.toml").read_text()
    text = text.replace("blocks_along_length = 3", "blocks_along_length = 30")
    case = tmp_path / "big.toml"
    case.write_text(text.replace("courses = 13", "courses = 33"))
    assert main(["limit", str(case), "--out", str(tmp_path / "a"), "--no-render"]) == 0
    assert "interior point" in capsys.readouterr().err
    assert main(["limit", str(case), "--out", str(tmp_path / "b"), "--no-render", "--quiet"]) == 0
    assert capsys.readouterr().err == ""
