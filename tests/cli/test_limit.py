"""The ``limit`` command, ``[analysis] method = "limit"`` and the bound in every pushover
summary."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from helpers.case_files import write_case as _write_case
from masonry_dem.cases.casefile import case_from_dict
from masonry_dem.cli import main


def test_limit_command_writes_summary_and_mechanism(tmp_path):
    """A block 0.4 high, 0.2 thick (mu 0.7) tilts over at s/a = 0.5; the summary has the
    keys of a pushover's plus method and bound; the mechanism VTU turns the block."""
    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "la"
    assert main(["limit", str(case), "--out", str(out), "--no-render"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    pushover_keys = {"status", "reason", "steps", "lambda", "lambda_bracket", "iterations"}
    pushover_keys |= {"factorizations", "seconds", "blocks", "interfaces", "name", "case"}
    assert pushover_keys <= set(summary)
    # the default alpha 1.5 is covered only with the friction enlarged by kappa (--dem-bound)
    assert summary["method"] == "associative" and summary["bound"] == "estimate"
    assert summary["lambda"] == pytest.approx(0.5, rel=1e-6)
    out_b = tmp_path / "la_bound"
    assert main(["limit", str(case), "--out", str(out_b), "--no-render", "--dem-bound"]) == 0
    bound = json.loads((out_b / "summary.json").read_text())
    assert bound["bound"] == "upper" and bound["lambda"] == pytest.approx(0.5, rel=1e-6)
    mesh = meshio.read(out / "mechanism_blocks.vtu")
    assert np.abs(mesh.point_data["displacement"]).max() > 0
    assert (out / "mechanism_interfaces.vtu").is_file()
    out2 = tmp_path / "la2"
    assert (
        main(
            [
                "limit",
                str(case),
                "--non-associative",
                "--grid",
                "4",
                "--out",
                str(out2),
                "--no-render",
            ]
        )
        == 0
    )
    summary2 = json.loads((out2 / "summary.json").read_text())
    assert summary2["method"] == "non-associative" and summary2["bound"] == "estimate"
    assert summary2["lambda"] == pytest.approx(0.5, rel=1e-6)


def test_case_file_method_limit_and_the_pushover_bound(tmp_path):
    """``[analysis] method = "limit"`` makes ``run`` a limit analysis; a pushover's summary
    carries the associative multiplier as ``limit_analysis_bound``, never below its lambda."""
    data = dict(SINGLE_BLOCK, analysis={"method": "limit", "backend": "clarabel"})
    case = _write_case(tmp_path, data)
    assert case_from_dict(data).method == "limit"
    out = tmp_path / "run_la"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["analysis"] == "limit" and summary["limit_analysis"]["backend"] == "clarabel"
    push = tmp_path / "push"
    case2 = _write_case(tmp_path, SINGLE_BLOCK)
    assert main(["run", str(case2), "--out", str(push), "--no-render", "--quiet"]) == 0
    summary = json.loads((push / "summary.json").read_text())
    assert summary["limit_analysis_bound"] == pytest.approx(0.5, rel=1e-6)
    assert summary["limit_analysis_bound"] >= summary["lambda"] * (1 - 1e-6)
    with pytest.raises(ValueError, match="method"):
        case_from_dict(dict(SINGLE_BLOCK, analysis={"method": "magic"}))
    with pytest.raises(ValueError, match="grid"):
        case_from_dict(dict(SINGLE_BLOCK, analysis={"grid": 4}))


def test_limit_command_claims_its_folder_as_run_does(tmp_path, capsys):
    """A results folder belongs to one run: a second limit analysis into the same --out is
    refused (exit 2, naming the folder) unless --overwrite, which replaces it."""
    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "la"
    assert main(["limit", str(case), "--out", str(out), "--no-render"]) == 0
    capsys.readouterr()
    assert main(["limit", str(case), "--out", str(out), "--no-render"]) == 2
    assert str(out) in capsys.readouterr().err
    assert main(["limit", str(case), "--out", str(out), "--no-render", "--overwrite"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "collapse" and summary["analysis"] == "limit"


def test_limit_command_names_its_picture_and_leaves_no_lock(tmp_path, capsys, monkeypatch):
    """The last line lists the files the analysis left, the mechanism picture among them
    (which names the limit analysis in its title and is drawn from the side, where the
    block's tilt along e3 shows), and nothing it did not write."""
    from masonry_dem.export import render

    titles = []

    def caption(*args):
        titles.append(original(*args))
        return titles[-1]

    original = render.caption
    monkeypatch.setattr(render, "caption", caption)
    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "la"
    assert main(["limit", str(case), "--out", str(out)]) == 0
    assert len(titles) == 1 and "mechanism (collapse mode), limit analysis (" in titles[0]
    summary = json.loads((out / "summary.json").read_text())
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == (
        f"results in {out}/ (mechanism_blocks.vtu, mechanism_interfaces.vtu, "
        f"{summary['mechanism_png']}, summary.json)"
    )
    assert summary["mechanism_png"] == "mechanism_side.png"
    assert not (out / ".masonry-dem.lock").exists()
