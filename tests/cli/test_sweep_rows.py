"""What a new user reads in ``sweep.csv``: the rows in the order of the runs (not in the order
they ended on the workers) and the grid's values as written (0.85, not linspace's
0.8500000000000001)."""

from __future__ import annotations

import csv
import time

import pytest

from helpers.case_files import SINGLE_BLOCK
from masonry_dem.studies import sweep as sweep_module
from masonry_dem.studies.sweep_plan import parse_values
from masonry_dem.studies.sweep_point import RESULT_COLUMNS

distributed = pytest.importorskip("distributed")

GRID = "0.5:0.9:9"


def test_a_grid_holds_its_values_as_written():
    assert parse_values(GRID) == [0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9]
    assert [repr(v) for v in parse_values("0.1:0.7:7")] == [
        "0.1",
        "0.2",
        "0.3",
        "0.4",
        "0.5",
        "0.6",
        "0.7",
    ]


def test_the_table_lists_the_runs_in_their_order(tmp_path, monkeypatch):
    """Runs that end in reverse order (the first sleeps longest) on two threads: the table
    still lists run 0 first."""
    mus = parse_values(GRID)

    def late_first(data, source, keep, folder):
        mu = data["material"]["friction"]
        time.sleep(0.04 * (len(mus) - mus.index(mu)))
        row = dict.fromkeys(RESULT_COLUMNS)
        row.update(status="collapse", reason="stub", **{"lambda": mu})
        return row

    monkeypatch.setattr(sweep_module, "run_point", late_first)
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=2) as client:
        done = sweep_module.sweep(
            SINGLE_BLOCK,
            vary={"material.friction": GRID},
            out=tmp_path / "s",
            scheduler=client,
            plots=False,
        )
    with (done.folder / "sweep.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [int(r["run"]) for r in rows] == list(range(len(mus)))
    assert [r["material.friction"] for r in rows] == [repr(m) for m in mus]
    assert "0.85" in {r["material.friction"] for r in rows}
