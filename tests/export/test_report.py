"""``masonry-dem report RESULTS`` (issue 38, item 5): one self-contained HTML page of a results
folder, written there and nowhere else, opened in real headless Chromium (Debian's): it loads
with no error and asks for nothing but itself, and its screenshot shows the mechanism picture
and the verdict."""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import numpy as np
import pytest

from helpers.chromium import open_page
from masonry_dem.cli import main
from masonry_dem.export.report import (
    REPORT,
    certificate_in_words,
    lambda_in_words,
    verdict,
    write_report,
)

NTC = ["--ag", "0.25", "--F0", "2.4", "--Tc", "0.3", "--soil", "B"]


def _files(root: Path) -> dict[str, int]:
    """Every file under ``root`` with its modification time."""
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}


@pytest.fixture(scope="module")
def assessed(tmp_path_factory):
    """The bundled default wall run to collapse (with its mechanism picture), assessed."""
    root = tmp_path_factory.mktemp("report")
    out = root / "res"
    assert main(["run", "--out", str(out), "--quiet"]) == 0
    assert main(["assess", str(out), *NTC]) == 0
    return out


@pytest.fixture(scope="module")
def reported(assessed):
    """The report of ``assessed``; what the folder's parent held before and after."""
    before = _files(assessed.parent)
    assert main(["report", str(assessed)]) == 0
    return assessed, before, _files(assessed.parent)


def test_lambda_in_words():
    """The issue's example: lambda 0.2826 of a weight-proportional load is a horizontal
    acceleration of 0.28 g and a tilt of atan(0.2826) = 15.8 degrees."""
    text = lambda_in_words(0.2826)
    assert "a horizontal acceleration of 0.28 g, a tilt of 15.8 degrees" in text
    assert math.isclose(math.degrees(math.atan(0.2826)), 15.78, abs_tol=5e-3)
    scaled = lambda_in_words(0.1, scale=2.0)  # alpha = c lambda
    assert "0.20 g" in scaled and f"{math.degrees(math.atan(0.2)):.1f} degrees" in scaled
    assert "no acceleration" in lambda_in_words(3.0, scale=None)


def test_words_of_a_limit_analysis_and_of_a_failed_run():
    limit = {"analysis": "limit", "status": "collapse", "lambda": 0.45, "bound": "estimate"}
    words = " ".join(certificate_in_words({**limit, "bound_reason": "the DEM's torsion"}))
    assert "no certificate" in words and "an estimate, not a bound" in words
    words = " ".join(certificate_in_words({**limit, "bound": "upper"}))
    assert "upper bound" in words
    failed = {"status": "failed", "reason": "not a certified collapse: rho 0.3"}
    assert "no certified collapse" in " ".join(certificate_in_words(failed))
    assert verdict(failed, None)[0] == "none"


def test_the_page_holds_it_all_and_only_the_page_is_written(reported, capsys):
    """report.html is the one file added, in the results folder; every picture is
    embedded; lambda, the certificate, the bound and the assessment are in words."""
    folder, before, after = reported
    added = set(after) - set(before)
    assert added == {f"{folder.name}/{REPORT}"}
    assert {k: v for k, v in after.items() if k in before} == before  # nothing else touched
    text = (folder / REPORT).read_text()
    assert "a horizontal acceleration of 0.28 g, a tilt of 15.8 degrees" in text
    assert "PASSES the check of NTC 2018" in text
    assert "T_SLV = 1.68 pi" in text and "Ts, the secant period" not in text  # the 2019 rows
    # the pushover's mode moved by screws that overlap: the verdict says so
    assert "Note: The finite motion of the nonlinear check (independent kinematics) is not" in text
    assert "is certified" in text and "upper bound of the pushover" in text
    assert "Design with the certified lambda" in text
    sources = re.findall(r"src='([^']*)'", text)
    assert len(sources) == 4  # mechanism, wall, pushover curve, ADRS
    assert all(s.startswith("data:image/png;base64,") for s in sources)
    assert "http://" not in text and "https://" not in text
    # the library logs and never prints
    capsys.readouterr()
    write_report(folder)
    assert capsys.readouterr().out == ""


def test_a_folder_without_assessment_nor_pictures(tmp_path):
    """A limit analysis run without pictures: the mechanism rendered in memory (nothing
    written but the page), the verdict says no assessment, the certificate that there is
    none."""
    out = tmp_path / "limit"
    assert main(["limit", "--out", str(out), "--no-render"]) == 0
    before = _files(tmp_path)
    path = write_report(out)
    assert set(_files(tmp_path)) - set(before) == {f"limit/{REPORT}"}
    text = path.read_text()
    assert "No seismic assessment in this folder" in text
    assert "gives no certificate" in text
    assert "id='mechanism' src='data:image/png;base64," in text
    assert "id='wall-missing'" in text  # a limit analysis has no steps


def test_a_folder_that_is_not_one(tmp_path, capsys):
    assert main(["report", str(tmp_path / "nowhere")]) == 2
    assert "results folder not found" in capsys.readouterr().err
    assert main(["report", str(tmp_path)]) == 2
    assert "no summary.json" in capsys.readouterr().err


def test_in_headless_chromium(reported, tmp_path):
    """Chromium loads the page with no console error, warning, exception or failed load, asks
    for no URL but the page's own and its data: pictures, and its screenshot shows the
    mechanism picture (a drawing, not a blank box) and the verdict (its green box; its text in
    the DOM)."""
    import imageio.v3 as iio

    folder = reported[0]
    page = open_page(folder / REPORT)
    assert page.errors == []
    own = (folder / REPORT).resolve().as_uri()
    others = [u[:60] for u in page.requests if u != own and not u.startswith("data:")]
    assert others == []
    assert "The mechanism PASSES the check of NTC 2018" in page.text
    assert "a horizontal acceleration of 0.28 g, a tilt of 15.8 degrees" in page.text
    images = {i["id"]: i for i in page.images}
    assert set(images) == {"mechanism", "wall", "pushover", "adrs"}
    assert all(i["complete"] and i["width"] > 100 and i["height"] > 100 for i in images.values())

    shot = iio.imread(io.BytesIO(page.screenshot), extension=".png")[..., :3].astype(float)
    (tmp_path / "report.png").write_bytes(page.screenshot)  # to look at when it fails
    assert shot.shape[0] > 1000 and shot.shape[1] >= 1000
    assert shot.std() > 20  # not blank

    def region(element: str) -> np.ndarray:
        x, y, w, h = (int(round(v)) for v in page.rects[element])
        assert w > 50 and h > 50, f"{element} is not shown ({w} x {h} px)"
        assert y + h <= shot.shape[0] and x + w <= shot.shape[1], f"{element} is off the page"
        return shot[y : y + h, x : x + w]

    mechanism = region("mechanism")
    dark = (mechanism.mean(axis=2) < 200).mean()
    assert mechanism.std() > 20 and 0.01 < dark < 0.6  # drawn blocks on a light background
    box = region("verdict")
    green = np.array([0xE8, 0xF6, 0xEC], dtype=float)  # the verdict's "passes" background
    assert (np.abs(box - green).max(axis=2) < 8).mean() > 0.5
    assert (box.mean(axis=2) < 100).mean() > 0.005  # with text in it


def test_the_readme_reads_lambda_the_bound_and_their_gap_as_the_run_does(assessed):
    """Issue 38, item 6: the README's paragraph near the top says what lambda means (its
    example as the report words it) and gives the bundled wall's lambda, bound and gap as a
    run of it finds them."""
    import json

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    top = readme[: readme.index("## Modelling your wall")]
    assert "## What lambda means, and which number to design with" in top
    assert "Design with the pushover's certified lambda" in top
    assert "Reading the certificate" in top and "Reading their gap" in top
    words = lambda_in_words(0.283)
    assert "a horizontal acceleration of 0.28 g, a tilt of 15.8 degrees" in words
    assert "horizontal acceleration of 0.28 g, a tilt of atan(0.283) = 15.8 degrees" in top
    summary = json.loads((assessed / "summary.json").read_text())
    lam, bound = summary["lambda"], summary["limit_analysis_bound"]
    gap = round(100 * (bound - lam) / lam)
    assert f"lambda {lam:.3f} under a bound of {bound:.3f}, a gap of {gap} %" in top
