"""The load-path fields the static and the dynamic-relaxation settings share are refused by
name in both, with the same message (one base, ``solvers.load_path.LoadPathSettings``)."""

from __future__ import annotations

import math
from dataclasses import fields

import pytest

from masonry_dem.solvers.dynamic_relaxation import DRSettings
from masonry_dem.solvers.incremental import StaticSettings

BAD = [
    ("initial_step", 0.0, "initial_step must be a positive number"),
    ("max_step", math.inf, "max_step must be a positive number"),
    ("bracket_tolerance", -0.01, "bracket_tolerance must be a positive number"),
    ("max_steps", 0, "max_steps must be an integer from 1 to 1e8"),
    ("max_steps", 2.0, "max_steps must be an integer from 1 to 1e8"),
    ("growth", 0.5, "growth must be a number >= 1"),
    ("growth", math.nan, "growth must be a number >= 1"),
    ("growth", "fast", "growth must be a number >= 1"),
    ("max_load_factor", -1.0, "max_load_factor must be a number > 0"),
    ("max_load_factor", math.nan, "max_load_factor must be a number > 0"),
    ("max_load_factor", True, "max_load_factor must be a number > 0"),
    ("displacement_limit", -0.01, "displacement_limit must be a number > 0 or None"),
    ("displacement_limit", math.nan, "displacement_limit must be a number > 0 or None"),
    ("displacement_limit", "half a block", "displacement_limit must be a number > 0 or None"),
]


@pytest.mark.parametrize("settings", [StaticSettings, DRSettings])
@pytest.mark.parametrize("field, value, message", BAD)
def test_both_settings_refuse_a_bad_load_path_field_by_name(settings, field, value, message):
    with pytest.raises(ValueError, match=message):
        settings(**{field: value})


@pytest.mark.parametrize("settings", [StaticSettings, DRSettings])
def test_both_settings_take_the_load_path_fields_at_their_limits(settings):
    """growth 1 keeps the step, an infinite max_load_factor is no cap, displacement_limit None
    is the solver's own, and an infinite one no limit."""
    s = settings(growth=1, max_load_factor=math.inf, displacement_limit=None, max_steps=1)
    assert (s.growth, s.max_load_factor, s.displacement_limit) == (1, math.inf, None)
    assert settings(displacement_limit=math.inf).displacement_limit == math.inf


@pytest.mark.parametrize("settings", [StaticSettings, DRSettings])
def test_every_checked_field_refuses_nan_by_its_name(settings):
    """Each field that declares a range (``positive``, ``count``, ``choice``, ...) refuses a
    NaN, naming itself: no range of a number, a count or a choice holds NaN."""
    checked = [f.name for f in fields(settings) if "test" in f.metadata]
    # every field but the switches (bool) and the optional limit declares its range
    assert set(checked) >= {
        f.name for f in fields(settings) if f.type != "bool" and f.name != "displacement_limit"
    }
    for name in checked:
        with pytest.raises(ValueError, match=f"^{name} must be"):
            settings(**{name: math.nan})


@pytest.mark.parametrize("settings_class", ["StaticSettings", "LoadPathSettings", "DRSettings"])
def test_every_documented_setting_is_a_field_and_every_field_is_documented(settings_class):
    """The class docstring's numpydoc Parameters section lists each setting as
    ``    name : type`` (or ``    a, b : type``), the base's fields too. A documented name that
    is not a field means a declaration went missing (a line put inside the docstring once
    dropped a field, and only a fuzz test saw it); a field that is not documented has no
    stated meaning."""
    import dataclasses
    import re

    from masonry_dem.solvers.load_path import LoadPathSettings
    from masonry_dem.solvers.static.settings import StaticSettings

    cls = {
        "StaticSettings": StaticSettings,
        "LoadPathSettings": LoadPathSettings,
        "DRSettings": DRSettings,
    }[settings_class]
    doc = cls.__doc__ or ""
    section = doc.split("    Parameters\n    ----------\n", 1)[-1].split("\n\n    Raises", 1)[0]
    documented: list[str] = []
    for line in section.splitlines():
        match = re.match(r"^    ([a-z_][a-z0-9_]*(?:, [a-z_][a-z0-9_]*)*) : ", line)
        if match:
            documented += match.group(1).split(", ")
    fields = [f.name for f in dataclasses.fields(cls)]
    assert documented == fields
