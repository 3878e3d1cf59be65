"""``masonry-dem validate --restraint return-walls``: one JSON row per case and return-wall
length, each saying which reading it is; the fixed-column rows say theirs."""

from __future__ import annotations

import json

import pytest

from masonry_dem.cli import main


@pytest.mark.slow
def test_return_wall_rows_carry_their_restraint(tmp_path, capsys):
    code = main(
        [
            "validate",
            "S15",
            "--restraint",
            "return-walls",
            "--return-blocks",
            "2",
            "3",
            "--json",
            "--no-render",
            "--out",
            str(tmp_path),
        ]
    )
    rows = json.loads(capsys.readouterr().out)
    assert [(r["case"], r["restraint"], r["return_blocks"]) for r in rows] == [
        ("S15", "return-walls", 2),
        ("S15", "return-walls", 3),
    ]
    assert code == 0 and all(r["status"] == "collapse" for r in rows)
    assert (tmp_path / "S15_return2" / "summary.json").is_file()
    # a longer return holds the facade better (2 blocks: the return turns over with it)
    assert rows[0]["ours"] < rows[1]["ours"]


def test_fixed_column_rows_say_so(tmp_path, capsys):
    main(["validate", "S15", "--json", "--no-render", "--out", str(tmp_path)])
    (row,) = json.loads(capsys.readouterr().out)
    assert row["restraint"] == "columns" and "return_blocks" not in row


def test_cases_without_a_return_wall_reading_are_refused(tmp_path, capsys):
    code = main(["validate", "S32", "--restraint", "return-walls", "--out", str(tmp_path)])
    assert code == 2
    assert "unknown case 'S32' for --restraint return-walls" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["validate", "S15", "--restraint", "return-walls", "--return-blocks", "1"])
