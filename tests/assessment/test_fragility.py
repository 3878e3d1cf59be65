"""Fragility from a sampled sweep (issue 38, item 4): each run's capacity as a peak ground
acceleration (the linear check at ground level solved for ag), a lognormal fitted by maximum
likelihood with a bootstrap band, the curve; ``masonry-dem fragility SWEEP``."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from masonry_dem.assessment.fragility import (
    ag_capacity,
    fit_lognormal,
    fragility_band,
    lognormal_mle,
)
from masonry_dem.assessment.spectra import G, NTC2018Spectrum
from masonry_dem.cli import main
from masonry_dem.studies.sweep_point import RESULT_COLUMNS

MEDIAN, BETA = 0.30, 0.35
SAMPLES = 400
#: the tolerance of the recovery, relative, for a sample of 400: the standard errors of the
#: MLE are beta / sqrt(n) on ln(median) (1.75 %) and beta / sqrt(2 n) on beta (1.2 %); four
#: of them
TOLERANCE = 0.07


def _lognormal_sample(n: int = SAMPLES, seed: int = 5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return MEDIAN * np.exp(BETA * rng.standard_normal(n))


def test_a_synthetic_lognormal_sample_gives_back_its_median_and_beta():
    x = _lognormal_sample()
    fit, resamples = fit_lognormal(x, bootstrap=1000, confidence=0.90, seed=1)
    assert fit.median == pytest.approx(MEDIAN, rel=TOLERANCE)
    assert fit.beta == pytest.approx(BETA, rel=TOLERANCE)
    # the intervals hold the estimate and the truth, and are about the standard errors wide
    lo, hi = fit.median_interval
    assert lo < fit.median < hi and lo < MEDIAN < hi
    assert hi / lo == pytest.approx(math.exp(2 * 1.645 * BETA / math.sqrt(SAMPLES)), rel=0.25)
    lo, hi = fit.beta_interval
    assert lo < fit.beta < hi and lo < BETA < hi
    assert resamples.shape == (1000, 2)
    # the curve is the lognormal's CDF: 1/2 at the median, its band around it
    assert float(fit.probability(fit.median)) == pytest.approx(0.5, abs=1e-12)
    ag = np.array([0.1, 0.3, 0.6])
    low, high = fragility_band(fit, resamples, ag)
    assert np.all(low <= fit.probability(ag) + 1e-12) and np.all(
        fit.probability(ag) <= high + 1e-12
    )


def test_the_mle_in_closed_form():
    """median = exp(mean ln x), beta = sqrt(mean (ln x - mu)^2)."""
    x = np.array([0.2, 0.4, 0.8])
    median, beta = lognormal_mle(x)
    assert median == pytest.approx(0.4, rel=1e-12)
    assert beta == pytest.approx(math.log(2) * math.sqrt(2 / 3), rel=1e-12)
    with pytest.raises(ValueError, match="positive"):
        lognormal_mle([0.1, -0.2])


@pytest.mark.parametrize("soil", ["A", "B", "D"])
def test_the_capacity_just_fails_the_linear_check(soil):
    """ag_capacity: a0* = ag S(ag) / q at the capacity, and below it the check passes; on
    soil A (S = 1) it is a0* q / g."""
    site = {"F0": 2.4, "Tc_star": 0.3, "soil": soil}
    for a0 in (0.5, 2.0, 3.7, 9.0):
        ag = ag_capacity(a0, "ntc2018", site, q=2.0)
        # past the spectra's range of ag (1.5 g) S stays at its bound (F0 ag >= 1)
        S = NTC2018Spectrum(min(ag, 1.5), **site).S
        assert ag * G * S / 2.0 == pytest.approx(a0, rel=1e-9)
        below = 0.999 * ag
        assert below * G * NTC2018Spectrum(min(below, 1.5), **site).S / 2.0 < a0
        if soil == "A":
            assert ag == pytest.approx(a0 * 2.0 / G, rel=1e-12)
    # past the spectra's range of ag (1.5 g) S stays at its bound: linear
    ec8 = ag_capacity(30.0, "ec8", {"soil": "B"}, q=2.0)
    assert ec8 == pytest.approx(30.0 * 2.0 / (G * 1.2), rel=1e-12)


def _write_sweep(folder, rows):
    folder.mkdir()
    columns = ["run", "material.friction", *RESULT_COLUMNS]
    with (folder / "sweep.csv").open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(columns)
        for r in rows:
            writer.writerow(["" if r.get(c) is None else r[c] for c in columns])


def test_the_command_on_a_synthetic_sweep(tmp_path, capsys):
    """A sweep table whose capacities are a lognormal sample (alpha0 from each, e* 0.5): the
    command recovers median and beta; a run without collapse or without a seismic mechanism is
    left out and counted; the files go into the sweep's folder only."""
    capacities = _lognormal_sample(200, seed=9)
    q, FC, e_star = 2.0, 1.35, 0.5
    rows = [
        # soil A: ag = a0* q / g = alpha0 q / (e* FC)
        {
            "run": k,
            "status": "collapse",
            "lambda": a,
            "alpha0": a * e_star * FC / q,
            "e_star": e_star,
        }
        for k, a in enumerate(capacities)
    ]
    rows.append({"run": len(rows), "status": "failed", "lambda": None})
    rows.append({"run": len(rows), "status": "collapse", "lambda": 0.3})  # no alpha0, e*
    folder = tmp_path / "sweep"
    _write_sweep(folder, rows)
    code = main(["fragility", str(folder), "--soil", "A", "--seed", "3", "--bootstrap", "400"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "fragility: median" in printed
    data = json.loads((folder / "fragility.json").read_text())
    median, beta = lognormal_mle(capacities)
    assert data["median"] == pytest.approx(median, rel=1e-9)
    assert data["beta"] == pytest.approx(beta, rel=1e-9)
    assert data["median"] == pytest.approx(MEDIAN, rel=0.1) and data["beta"] == pytest.approx(
        BETA, rel=0.15
    )
    assert data["used"] == 200 and data["runs"] == 202
    assert sum(data["left_out"].values()) == 2
    assert {p.name for p in folder.iterdir()} == {
        "sweep.csv",
        "fragility.json",
        "fragility.csv",
        "fragility.png",
    }
    with (folder / "fragility.csv").open(newline="") as fh:
        table = list(csv.DictReader(fh))
    assert float(table[0]["ag_capacity [g]"]) == pytest.approx(capacities[0], rel=1e-9)


@pytest.mark.parametrize(
    "flags, words",
    [
        (["--soil", "Z"], "soil = 'Z'"),
        (["--F0", "9"], "F0 = 9.0 out of range"),
        (["--q", "0.5"], "q = 0.5 out of range"),
        (["--code", "ec8", "--F0", "2.4"], "F0: not a parameter of the ec8 spectrum"),
    ],
)
def test_bad_site_values_one_line(tmp_path, capsys, flags, words):
    folder = tmp_path / "sweep"
    _write_sweep(
        folder, [{"run": 0, "status": "collapse", "lambda": 0.3, "alpha0": 0.3, "e_star": 0.5}] * 3
    )
    assert main(["fragility", str(folder), *flags]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1


def test_a_table_of_an_older_version_is_named(tmp_path, capsys):
    folder = tmp_path / "old"
    folder.mkdir()
    (folder / "sweep.csv").write_text("run,status,lambda\n0,collapse,0.3\n")
    assert main(["fragility", str(folder)]) == 2
    assert "an older version" in capsys.readouterr().err


def test_a_sweep_row_carries_the_seismic_mechanism():
    """A run of a sweep (the bundled wall, as a worker runs it) gives alpha0 = c lambda and
    the e* that ``masonry-dem assess`` finds for the same pushover (docs/assessment.md: 0.553)."""
    from masonry_dem.cases.casefile import read_case_data
    from masonry_dem.studies.sweep_point import run_point

    data, source = read_case_data(None)
    row = run_point(data, source)
    assert row["status"] == "collapse"
    assert row["alpha0"] == pytest.approx(row["lambda"], rel=1e-12)  # c = 1
    assert row["e_star"] == pytest.approx(0.5528, abs=5e-4)


def test_a_sweep_table_of_an_older_version_still_resumes(tmp_path):
    """A sweep.csv written before the alpha0 and e_star columns reads back, those empty."""
    from masonry_dem.studies.sweep_plan import make_plan
    from masonry_dem.studies.sweep_table import read_rows

    plan = make_plan(None, vary={"material.friction": "0.5,0.6"})
    old = [c for c in RESULT_COLUMNS if c not in ("alpha0", "e_star")]
    (tmp_path / "sweep.csv").write_text(
        ",".join(["run", "material.friction", *old])
        + "\n"
        + ",".join(["0", "0.5", "collapse", "", "0.25", *[""] * (len(old) - 3)])
        + "\n"
    )
    rows = read_rows(tmp_path, plan)
    assert list(rows) == [0]
    assert rows[0]["lambda"] == 0.25 and rows[0]["alpha0"] is None and rows[0]["e_star"] is None
