"""Parameter sweeps on a 2-worker Dask LocalCluster (``masonry_dem.sweep``, ``masonry-dem sweep``).

The wall: two courses of two running-bond blocks (0.4 m long, 0.05 m high) on a rigid base,
dry joints, tilted in its plane (lambda x weight along e1). Every bed joint is Coulomb with
no cohesion and no tension, so a course slides on the one below (or on the base) when the
horizontal force it carries reaches mu times the weight above the joint: lambda W_above =
mu W_above, i.e. lambda = mu for every joint at once, independent of the weights. Overturning
needs lambda = L/H = 0.8/0.1 = 8 for the wall, 8 for a block: far above any mu of the grid,
so sliding governs and lambda_c = mu exactly; it must rise with friction, by 0.05 a step.
The solver's collapse bracket is 0.5 % wide (its default tolerance): lambda is checked
against mu to that tolerance, and against the single runs of the same cases exactly.
"""

from __future__ import annotations

import csv
import json
from importlib.metadata import version
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
pq = pytest.importorskip("pyarrow.parquet")
tomli_w = pytest.importorskip("tomli_w")

from masonry_dem.cases.schema import CaseError  # noqa: E402
from masonry_dem.cli import main  # noqa: E402
from masonry_dem.constitutive import DEFAULT_ALPHA  # noqa: E402
from masonry_dem.solvers.limit_analysis import dem_friction_scale  # noqa: E402
from masonry_dem.studies.sweep import (  # noqa: E402
    Distribution,
    make_plan,
    parse_values,
    run_point,
    set_path,
    sweep,
)

TOL = 0.005  # the solver's default bracket tolerance
SLIDING_WALL = {
    "name": "sliding wall",
    "geometry": {
        "builder": "running_bond_wall",
        "blocks_along_length": 2,
        "courses": 2,
        "a": 0.05,
        "b": 0.4,
        "s": 0.1,
        "unit_weight": 20e3,
        "base": True,
    },
    "material": {"kn": 1e9, "kt": 0.4e9, "friction": 0.7},
    "supports": [{"select": "base"}],
    "loads": [
        {"type": "self_weight"},
        {"type": "weight_proportional", "direction": [1.0, 0.0, 0.0]},
    ],
}


@pytest.fixture(scope="module")
def client():
    # one run here first: the compiled kernels are cached before two workers look for them
    assert run_point(SLIDING_WALL, "warm-up")["status"] == "collapse"
    with (
        distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            env={"NUMBA_NUM_THREADS": "1"},
        ) as cluster,
        distributed.Client(cluster) as c,
    ):
        yield c


@pytest.mark.slow
def test_friction_grid_rises_with_mu_and_matches_single_runs(client, tmp_path):
    result = sweep(
        SLIDING_WALL, vary={"material.friction": "0.5:0.9:9"}, out=tmp_path, scheduler=client
    )
    rows = result.rows
    kappa = dem_friction_scale(DEFAULT_ALPHA)
    mu = np.array([r["material.friction"] for r in rows])
    lam = result.lambdas
    assert [r["run"] for r in rows] == list(range(9))
    np.testing.assert_allclose(mu, np.linspace(0.5, 0.9, 9), rtol=0, atol=1e-15)
    assert all(r["status"] == "collapse" for r in rows), [r["reason"] for r in rows]
    np.testing.assert_allclose(lam, mu, rtol=TOL)  # lambda_c = mu (module docstring)
    assert np.all(np.diff(lam) > 0.04)  # rises by about 0.05 a step
    for r in rows:  # the collapse mode slides: the cracks move along the joints
        assert r["mechanism_sliding_share"] > 0.99 and r["mechanism_cracks"] >= 1
        # the certified bound of the summaries: the LA with friction x kappa(alpha), whose
        # domain holds the DEM's (solvers.limit_analysis.dem_domain); sliding at kappa mu
        assert r["limit_analysis_bound"] == pytest.approx(kappa * r["material.friction"], rel=1e-6)
    # exactly the single run of the same case, in this process
    for r in rows:
        single = run_point(set_path(SLIDING_WALL, "material.friction", r["material.friction"]), "x")
        assert r["lambda"] == single["lambda"]
        assert r["steps"] == single["steps"]
    # the Parquet table and the CSV hold the same rows
    table = pq.read_table(result.parquet).to_pylist()
    assert [t["lambda"] for t in table] == list(lam)
    with result.csv.open() as f:
        assert sorted(float(c["lambda"]) for c in csv.DictReader(f)) == sorted(lam)
    assert (tmp_path / "lambda_vs_material.friction.png").stat().st_size > 10_000
    plan = json.loads((tmp_path / "sweep.json").read_text())
    assert plan["vary"]["material.friction"] == list(mu)


def test_a_failing_run_is_a_row_and_the_sweep_goes_on(client, tmp_path):
    # without the base the support "base" names no block: the run raises, the other runs on
    result = sweep(
        SLIDING_WALL,
        vary={"geometry.base": [True, False], "material.friction": [0.6]},
        out=tmp_path,
        scheduler=client,
        keep="all",
    )
    ok, failed = result.rows
    assert ok["status"] == "collapse" and ok["lambda"] == pytest.approx(0.6, rel=TOL)
    assert failed["status"] == "error" and failed["lambda"] is None
    assert "base" in failed["reason"] and "[supports][0]" in failed["reason"]
    assert (Path(ok["folder"]) / "blocks.pvd").is_file()  # keep="all": the whole folder
    assert (Path(ok["folder"]) / "mechanism_blocks.vtu").is_file()
    table = pq.read_table(result.parquet).to_pylist()
    assert [t["status"] for t in table] == ["collapse", "error"]


def test_resume_runs_only_the_missing_rows(client, tmp_path):
    vary = {"material.friction": "0.5,0.7,0.9"}
    first = sweep(SLIDING_WALL, vary=vary, out=tmp_path, scheduler=client, keep="summary")
    assert first.ran == 3 and all(Path(r["folder"], "summary.json").is_file() for r in first.rows)
    # an interrupted sweep: the row of run 1 never written, a torn line at the end
    lines = first.csv.read_text().splitlines(keepends=True)
    kept = [line for line in lines if not line.startswith("1,")]
    first.csv.write_text("".join(kept) + "1,0.7,coll")
    second = sweep(SLIDING_WALL, vary=vary, out=tmp_path, scheduler=client, resume=True)
    assert (second.ran, second.resumed) == (1, 2)
    for a, b in zip(first.rows, second.rows, strict=True):
        if a["run"] != 1:  # the rows kept, as they were (same worker, same seconds)
            assert a == b
        else:
            assert b["lambda"] == a["lambda"] and b["worker"] is not None
    assert len(pq.read_table(second.parquet)) == 3
    with pytest.raises(ValueError, match="resume continues it"):
        sweep(SLIDING_WALL, vary=vary, out=tmp_path, scheduler=client)
    with pytest.raises(ValueError, match="another plan"):
        sweep(SLIDING_WALL, vary={"material.friction": "0.5,0.8"}, out=tmp_path, resume=True)


def test_samples_give_the_histogram_and_cdf_and_command_line_runs_on_a_scheduler(
    client, tmp_path, capsys
):
    case = tmp_path / "wall.toml"
    case.write_text(tomli_w.dumps(SLIDING_WALL))
    out = tmp_path / "out"
    args = ["sweep", str(case), "--sample", "material.friction=uniform(0.5,0.9)"]
    args += ["--samples", "4", "--scheduler", client.scheduler.address, "--out", str(out)]
    assert main([*args, "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out.splitlines()[0])
    assert summary["runs"] == 4 and summary["status"] == {"collapse": 4}
    rows = pq.read_table(out / "sweep.parquet").to_pylist()
    seed = json.loads((out / "sweep.json").read_text())["seed"]  # drawn and recorded
    mu = np.random.default_rng(seed).uniform(0.5, 0.9, 4)
    assert [r["material.friction"] for r in rows] == list(mu)
    np.testing.assert_allclose([r["lambda"] for r in rows], mu, rtol=TOL)
    for png in ("lambda_histogram.png", "lambda_cdf.png", "lambda_vs_material.friction.png"):
        assert (out / png).stat().st_size > 10_000
    # resumed without --seed: the recorded one, so every row is found done
    assert main([*args, "--quiet", "--resume"]) == 0
    summary = json.loads(capsys.readouterr().out.splitlines()[0])
    assert (summary["ran"], summary["resumed"]) == (0, 4)


# --------------------------------------------------------------------- plans and errors
def test_grids_lists_and_distributions_parse_as_written():
    assert parse_values("0.5:0.9:5") == pytest.approx([0.5, 0.6, 0.7, 0.8, 0.9])
    assert parse_values("0.5,6,true,column:left,[0,0,1]") == [
        0.5,
        6,
        True,
        "column:left",
        [0, 0, 1],
    ]
    plan = make_plan(SLIDING_WALL, vary={"geometry.courses": "2:4:3"})
    assert plan.vary["geometry.courses"] == [2, 3, 4]  # whole numbers where the schema wants
    d = Distribution.parse("lognormal(1e9,0.3)")
    draws = d.draw(np.random.default_rng(0), 20_000)
    assert np.median(draws) == pytest.approx(1e9, rel=0.02)
    assert np.std(np.log(draws)) == pytest.approx(0.3, rel=0.02)
    plan = make_plan(
        SLIDING_WALL,
        vary={"material.friction": [0.5, 0.6]},
        sample={"material.kn": "lognormal(1e9,0.3)"},
        samples=3,
        seed=7,
    )
    points = plan.points()  # the grid crossed with the same three draws
    assert len(points) == 6
    assert [p["material.kn"] for p in points[:3]] == [p["material.kn"] for p in points[3:]]
    with pytest.raises(ValueError, match="no sampled parameter"):
        make_plan(SLIDING_WALL, vary={"material.friction": [0.5]}, samples=3)


@pytest.mark.parametrize(
    "vary, sample, words",
    [
        ({"material.friction": "0.5:150:3"}, {}, ["[material].friction = 150", "from 0 to 100"]),
        ({"material.frction": "0.5,0.6"}, {}, ["material.frction", "did you mean friction"]),
        ({"geometry.courses": "2:3:3"}, {}, ["[geometry].courses = 2.5", "whole number"]),
        ({}, {"material.kn": "lognormal(1e9,30)"}, ["[material].kn", "1e5 to 1e14 N/m^3"]),
        ({}, {"material.kn": "gamma(1,2)"}, ["lognormal(median, sigma_log)"]),
        ({"material.friction": "0.5:0.9"}, {}, ["a grid is lo:hi:n"]),
    ],
)
def test_a_bad_path_or_value_is_one_line_naming_it(vary, sample, words, tmp_path):
    with pytest.raises(ValueError) as err:
        make_plan(SLIDING_WALL, vary=vary, sample=sample, samples=50 if sample else 0, seed=1)
    text = str(err.value)
    assert "\n" not in text and all(w in text for w in words), text
    if sample == {} and "grid" not in words[0]:
        assert isinstance(err.value, CaseError)


def test_command_line_refuses_a_value_out_of_range_with_exit_2(tmp_path, capsys):
    code = main(["sweep", "--vary", "material.friction=-1,0.5", "--out", str(tmp_path / "s")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "material.friction = -1" in err and "from 0 to 100" in err
    assert not (tmp_path / "s").exists()  # refused before anything ran


def test_version_is_the_installed_one(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"masonry-dem {version('masonry_dem')}"


def test_runs_are_handed_to_dask_a_few_per_worker_at_a_time(client, tmp_path, monkeypatch):
    """10^6 tasks submitted at once filled the scheduler until it dropped its workers: at
    most WINDOW_PER_WORKER x workers runs are in flight, the next one handed on as one
    ends; every run still gets its row, in order."""
    import masonry_dem.studies.sweep as sweep_module

    monkeypatch.setattr(sweep_module, "WINDOW_PER_WORKER", 1)
    submitted, ended, in_flight = [0], [0], []

    class Counting:
        def __init__(self, inner):
            self.inner = inner

        def __getattr__(self, name):
            return getattr(self.inner, name)

        def submit(self, *args, **kwargs):
            submitted[0] += 1
            in_flight.append(submitted[0] - ended[0])
            return self.inner.submit(*args, **kwargs)

    appended = sweep_module.Journal.append

    def append(self, row):
        ended[0] += 1
        return appended(self, row)

    monkeypatch.setattr(sweep_module.Journal, "append", append)
    result = sweep(
        SLIDING_WALL,
        vary={"material.friction": "0.5:0.8:12"},
        out=tmp_path / "sweep",
        scheduler=Counting(client),
        plots=False,
    )
    assert submitted[0] == 12 and [r["run"] for r in result.rows] == list(range(12))
    assert max(in_flight) <= 8  # the window: max(8, 1 x 2 workers)
