"""The size ladder: the methods on the same wall, limit analysis against the static answer."""

from __future__ import annotations

import pytest

from masonry_dem.studies.runs import Method
from masonry_dem.studies.size_ladder import ladder_text, ladder_wall, size_ladder


def test_limit_analysis_bounds_the_pushover_on_the_smallest_wall():
    """Radenkovic: an associative multiplier whose domain contains the DEM's is an upper
    bound of the non-associative DEM's. The ladder's plain exact cone contains it only for
    joints with alpha = 1 (solvers.limit_analysis.dem_domain), so its row is labelled an
    estimate; on this wall it still lies above the pushover (``ratio_to_static`` >= 1 within
    the static bracket, 0.5 %)."""
    rows = size_ladder([9], [Method.STATIC, Method.LIMIT_ANALYSIS])
    static, la = rows
    assert static["method"] == "static" and la["method"] == "limit_analysis"
    assert static["blocks"] == la["blocks"] == ladder_wall(9).blocks.count
    assert static["status"] == la["status"] == "collapse"
    assert static["ratio_to_static"] == pytest.approx(1.0)
    assert la["ratio_to_static"] >= 1.0 - 0.005
    assert la["bound"] == "estimate"
    assert "x static" in ladder_text(rows)


def test_a_method_skips_walls_above_its_limit():
    rows = size_ladder([9], [Method.STATIC, Method.LIMIT_ANALYSIS], up_to={Method.STATIC: 4})
    assert [r["method"] for r in rows] == ["limit_analysis"]
    assert rows[0]["ratio_to_static"] is None


@pytest.mark.parametrize("blocks", [0, 3, 2.5, True])
def test_bad_size_names_the_field(blocks):
    with pytest.raises(ValueError, match="blocks must be a whole number >= 4"):
        ladder_wall(blocks)


def test_ladder_command_prints_each_run_then_the_table(capsys):
    from masonry_dem.cli import main

    code = main(["study", "ladder", "--sizes", "9", "--methods", "limit_analysis"])
    assert code == 0
    out = capsys.readouterr().out
    assert "blocks, limit_analysis: collapse" in out  # the progress line
    assert "x static lambda" in out and " LA " in out
