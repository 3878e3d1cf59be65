"""The ``validate`` command's parallel runs: the same rows as one process, in case order."""

from __future__ import annotations

import pytest

from masonry_dem.cli import main
from masonry_dem.studies.validation import run_case, run_cases


@pytest.mark.slow
def test_cases_run_side_by_side_give_the_rows_of_one_process():
    names = ["S32", "OL2"]  # the two quickest cases, not in table order
    parallel = run_cases(names, None, render=False, jobs=2)
    assert [row["case"] for row in parallel] == names
    for row in parallel:
        alone = run_case(row["case"], None, render=False)
        assert row["status"] == alone["status"] == "collapse"
        assert row["ours"] == pytest.approx(alone["ours"], rel=1e-12)
        assert row["steps"] == alone["steps"] and row["iterations"] == alone["iterations"]


@pytest.mark.parametrize("jobs", ["0", "-1", "two"])
def test_jobs_must_be_a_whole_number_of_at_least_one(jobs, capsys):
    with pytest.raises(SystemExit):
        main(["validate", "OL2", "--jobs", jobs])
    assert f"--jobs must be a whole number >= 1, got '{jobs}'" in capsys.readouterr().err
