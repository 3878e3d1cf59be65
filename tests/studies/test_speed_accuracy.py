"""The speed-accuracy study (``masonry_dem.studies``): its Pareto front and equal-accuracy
ratio, its grids, and the command on a one-block case where every method has the closed-form
answer s / a (the block tilts over its base edge before it slides, mu 0.7 > s / a = 0.5)."""

from __future__ import annotations

import json

import pytest

from helpers.walls import A, B, S, on_base
from masonry_dem.geometry import builders
from masonry_dem.solvers.incremental import StaticSettings
from masonry_dem.studies import speed_accuracy as sa
from masonry_dem.studies.runs import Method, StudyCase, settings_for, with_changes


@pytest.fixture(scope="module")
def tilting_block():
    return on_base(builders.single_block(A, B, S, 20e3))


def test_pareto_front_and_equal_accuracy():
    rows = [
        {"method": "static", "label": "a", "seconds": 1.0, "error_vs_converged": 0.05},
        {"method": "static", "label": "b", "seconds": 2.0, "error_vs_converged": 0.001},
        {"method": "static", "label": "c", "seconds": 3.0, "error_vs_converged": 0.002},
        {"method": "dynamic_relaxation", "label": "d", "seconds": 40.0, "error_vs_converged": 0.0},
        {"method": "dynamic_relaxation", "label": "e", "seconds": 5.0, "error_vs_converged": None},
        {"method": "limit_analysis", "label": "f", "seconds": 2.5, "error_vs_converged": 0.5},
    ]
    sa.mark_pareto(rows)
    assert [r["pareto"] for r in rows] == [True, True, False, True, False, False]
    eq = sa.equal_accuracy(rows, 0.01)
    assert eq["static_label"] == "b" and eq["dynamic_relaxation_label"] == "d"
    assert eq["time_ratio_dr_over_static"] == pytest.approx(20.0)


@pytest.mark.parametrize("method", list(Method))
def test_every_setting_on_the_chart_is_a_knob_of_its_method(method):
    """A knob the solver no longer has is an error, not a row silently run with defaults."""
    base = settings_for(method, StaticSettings())
    for label, changes in sa.GRIDS[method]:
        settings = with_changes(base, changes)
        for key, value in changes.items():
            got = settings[key] if isinstance(settings, dict) else getattr(settings, key)
            assert got == value, (label, key)
    assert set(sa.QUICK[method]) <= {label for label, _ in sa.GRIDS[method]}
    assert set(sa.FULL_ONLY[method]) <= {label for label, _ in sa.GRIDS[method]}
    with pytest.raises((TypeError, ValueError)):
        with_changes(settings_for(Method.STATIC, StaticSettings()), {"iteration": "modified"})


def test_an_unknown_method_is_named_with_the_allowed_ones():
    with pytest.raises(ValueError, match="static, dynamic_relaxation, limit_analysis"):
        Method.parse("newton")


def test_study_command_json_table_and_chart(tmp_path, monkeypatch, capsys, tilting_block):
    """``masonry-dem study speed-accuracy --json`` on one block, all three methods: every
    lambda is s / a (the static and DR brackets within 2 %, limit analysis exact: the
    tilting mechanism has no sliding, so no cone or flow rule enters), and the limit
    analysis is reported against the static answer."""
    from masonry_dem.cli import main

    case = StudyCase("block", tilting_block, S / A, StaticSettings())
    monkeypatch.setattr(sa, "load_study_case", lambda name: case)
    grids = {
        Method.STATIC: sa.GRIDS[Method.STATIC][:2],
        Method.DYNAMIC_RELAXATION: (("bracket 2%", {"bracket_tolerance": 0.02}),),
        Method.LIMIT_ANALYSIS: sa.GRIDS[Method.LIMIT_ANALYSIS],
    }
    monkeypatch.setattr(sa, "GRIDS", grids)
    monkeypatch.setattr(sa, "FULL_ONLY", {m: () for m in Method})
    code = main(["study", "speed-accuracy", "--cases", "block", "--json", "--out", str(tmp_path)])
    assert code == 0
    runs = json.loads(capsys.readouterr().out)
    assert [r["method"] for r in runs] == ["static"] * 2 + ["dynamic_relaxation"] + [
        "limit_analysis"
    ] * 3
    for r in runs:
        for key in ("case", "settings", "seconds", "lambda", "error_vs_converged", "error_vs_test"):
            assert key in r
        rel = 1e-6 if r["method"] == "limit_analysis" else 0.02
        assert r["lambda"] == pytest.approx(S / A, rel=rel)
        assert r["error_vs_test"] <= rel
    for r in runs[3:]:
        assert not r["verified"]  # another model: never the converged lambda of the case
        assert r["ratio_to_static"] == pytest.approx(1.0, rel=0.02)
    # plain associative (default alpha: its domain does not hold the DEM's) and
    # non-associative multipliers are both estimates; only dem_upper_bound is certified
    assert runs[3]["bound"] == "estimate" and runs[5]["bound"] == "estimate"
    saved = json.loads((tmp_path / "speed_accuracy.json").read_text())
    summary = saved["summary"]["block"]
    assert summary["lambda_converged"] == pytest.approx(S / A, rel=1e-3)
    assert [r["label"] for r in summary["limit_analysis"]] == [
        label for label, _ in sa.GRIDS[Method.LIMIT_ANALYSIS]
    ]
    assert (tmp_path / "speed_accuracy.png").stat().st_size > 10_000
    text = (tmp_path / "speed_accuracy.txt").read_text()
    assert "Pareto" in text and "limit analysis against the static answer" in text
    # the chart and table are regenerated from the saved runs without running anything
    (tmp_path / "speed_accuracy.png").unlink()
    again = tmp_path / "again"
    code = main(
        ["study", "speed-accuracy", "--from-json", str(tmp_path / "speed_accuracy.json")]
        + ["--out", str(again)]
    )
    assert code == 0 and (again / "speed_accuracy.png").is_file()
    assert "DR / static" in capsys.readouterr().out


def test_the_methods_of_a_study_are_chosen(tmp_path, monkeypatch, capsys, tilting_block):
    """``--methods static limit_analysis``: no dynamic relaxation is run."""
    case = StudyCase("block", tilting_block, S / A, StaticSettings())
    monkeypatch.setattr(sa, "load_study_case", lambda name: case)
    res = sa.speed_accuracy(["block"], quick=True, methods=["static", "limit_analysis"])
    assert {r["method"] for r in res["rows"]} == {"static", "limit_analysis"}
    assert len([r for r in res["rows"] if r["method"] == "limit_analysis"]) == 1


def test_rows_saved_by_an_older_version_are_refused_with_the_file(tmp_path):
    saved = tmp_path / "speed_accuracy.json"
    row = {"case": "S15", "method": "static", "label": "default", "lambda": 0.27}
    saved.write_text(json.dumps({"rows": [row], "summary": {}}))
    with pytest.raises(ValueError, match="speed_accuracy.json: 1 rows .* older version"):
        sa.from_saved(saved)
