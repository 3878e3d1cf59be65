"""One way in (issue 42, item 1): ``md.analyze`` runs the three analyses with their own settings
and returns the same core fields; through it each method gives its own function's answer to
the last digit, and every method finds the closed forms of a tilted block and wall."""

from __future__ import annotations

import json
import re
from dataclasses import replace

import numpy as np
import pytest

import masonry_dem as md
from helpers.walls import tilted_block, tilted_wall


@pytest.fixture(scope="module")
def wall():
    return md.load_case().model


@pytest.mark.parametrize("method", ["pushover", "relaxation", "limit"])
def test_each_method_through_analyze_is_its_own_function(wall, method):
    """The same lambda, status and reason as ``pushover``, ``relax`` and ``limit_analysis``
    called directly on the bundled wall, bit for bit; the core fields filled as documented."""
    own = {"pushover": md.pushover, "relaxation": md.relax, "limit": md.limit_analysis}[method]
    direct = own(wall)
    result = md.analyze(wall, method)
    assert result.method == method and result.details is not None
    if method == "limit":
        assert result.load_factor == direct.load_factor
        assert result.bound in ("upper", "estimate") and result.bound_reason
        assert result.history is None and result.stop is None
    else:
        assert result.load_factor == direct.collapse_multiplier
        assert result.bracket == direct.collapse_bracket
        assert result.stop == str(direct.stop)
        assert (result.certificate is not None) == (method == "pushover")  # the pushover's
        assert len(result.history.steps) == len(direct.steps)
    assert result.status == str(direct.status) == "collapse"
    assert result.reason == direct.reason
    assert result.mechanism.shape == (wall.blocks.count, 6)
    assert np.abs(result.mechanism[:, :3]).max() == pytest.approx(1.0)
    summary = result.summary()
    assert json.loads(json.dumps(summary)) == summary  # JSON-ready, no NaN
    assert summary["lambda"] == result.load_factor


@pytest.mark.parametrize("method", ["pushover", "relaxation", "limit"])
@pytest.mark.parametrize("scene", [tilted_block, tilted_wall])
def test_every_method_finds_the_tilt_of_a_block_and_a_free_standing_wall(method, scene):
    """A block tilts at s/a and a free-standing wall at t/H: rigid blocks exactly (the limit
    analysis's certified bracket), the elastic-joint methods within 1 %."""
    model, exact = scene()
    result = md.analyze(model, method)
    assert result.status == "collapse", result.reason
    tolerance = 1e-6 if method == "limit" else 1e-2
    assert result.load_factor == pytest.approx(exact, rel=tolerance)


def test_bad_arguments_name_what_is_allowed(wall):
    with pytest.raises(ValueError, match="method = 'fem': must be one of pushover, relaxation"):
        md.analyze(wall, "fem")
    with pytest.raises(TypeError, match="settings of method 'pushover' must be a StaticSettings"):
        md.analyze(wall, "pushover", md.DRSettings())
    with pytest.raises(ValueError, match="control is a setting of the pushover"):
        md.analyze(wall, "limit", control=md.DisplacementControl(0, "u3", 0.01))
    with pytest.raises(ValueError, match=r"settings\['tolerence'\] is not a setting of limit"):
        md.analyze(wall, "limit", {"tolerence": 1e-3})
    with pytest.raises(ValueError, match="model must be a Model"):
        md.analyze("wall.toml", "limit")


def test_aliases_and_settings_reach_the_method(wall):
    """The studies' names of the methods are the same methods; a setting changes the run
    (a pushover stopped by max_load_factor below its collapse completes there)."""
    assert md.analyze(wall, "limit_analysis").load_factor == md.analyze(wall, "limit").load_factor
    capped = md.analyze(wall, "static", replace(md.StaticSettings(), max_load_factor=0.1))
    assert capped.status == "completed" and capped.load_factor is None
    assert capped.mechanism is None


def test_out_writes_a_results_folder_for_every_method(wall, tmp_path):
    for method in ("pushover", "limit"):
        result = md.analyze(wall, method, out=tmp_path / method)
        summary = json.loads((tmp_path / method / "summary.json").read_text())
        assert summary["status"] == result.status == "collapse"
        assert summary["lambda"] == pytest.approx(result.load_factor, rel=1e-12)
        assert (tmp_path / method / "mechanism_blocks.vtu").exists() or method == "pushover"


def test_limit_settings_are_an_object_as_the_others_are(wall):
    """``LimitSettings`` holds limit_analysis's keyword arguments: through analyze it is the
    same analysis as the keywords (non-associative, grid 4), and a value out of range is
    named when the settings are made, not when the analysis runs."""
    settings = md.LimitSettings(associative=False, grid=4)
    via_object = md.analyze(wall, "limit", settings)
    via_keywords = md.limit_analysis(wall, associative=False, grid=4)
    assert via_object.load_factor == via_keywords.load_factor
    assert via_object.details.method == "non-associative"
    assert md.analyze(wall, "limit", {"associative": False, "grid": 4}).load_factor == (
        via_object.load_factor
    )
    for field, value, words in [
        ("tolerance", 2.0, "tolerance must be in (0, 1), got 2.0"),
        ("backend", "gurobi", "backend must be one of ('highs', 'clarabel')"),
        ("start", "plastic", "start must be one of ('elastic', 'associative')"),
        ("friction_sides", 2, "friction_sides must be an integer >= 3"),
        ("time_limit", 0, "time_limit must be a finite number of seconds > 0"),
    ]:
        with pytest.raises(ValueError, match=re.escape(words)):
            md.LimitSettings(**{field: value})
    with pytest.raises(TypeError, match="settings of method 'limit' must be a LimitSettings"):
        md.analyze(wall, "limit", md.StaticSettings())
