"""The ``run`` command and case files: outputs, schema errors, the README's Python example."""

from __future__ import annotations

import json
import runpy
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from helpers.case_files import write_case as _write_case
from masonry_dem.cases.casefile import case_from_dict, load_case
from masonry_dem.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_run_single_block_case_writes_every_output(tmp_path):
    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "res"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    for key in ("status", "steps", "lambda", "seconds", "blocks", "interfaces"):
        assert key in summary
    assert summary["status"] == "collapse"
    # a dry block 0.4 high and 0.2 thick tilts over at s/a = 0.5 (mu = 0.7 is higher)
    assert summary["lambda"] == pytest.approx(0.5, rel=0.005)
    assert summary["blocks"] == 2 and summary["interfaces"] == 1
    entries = ET.parse(out / "blocks.pvd").getroot().findall(".//DataSet")
    assert len(entries) == summary["steps"]
    times = [float(e.get("timestep")) for e in entries]
    assert times == sorted(times)
    last = meshio.read(out / entries[-1].get("file"))
    assert last.cells[0].type == "hexahedron"
    assert np.isfinite(last.point_data["displacement"]).all()
    rows = np.loadtxt(out / "pushover.csv", delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[0] == summary["steps"]
    assert rows[-1, 1] == pytest.approx(summary["lambda"])


def test_default_case_loads_and_is_a_supported_wall():
    case = load_case(None)
    assert case.model.blocks.count == 3 * 7 + 4 * 6 + 1  # 13 courses, half blocks, base
    assert case.model.fixed[-1].all()


@pytest.mark.parametrize(
    "patch, message",
    [
        ({"geometry": {"builder": "pyramid"}}, "builder"),
        ({"material": {"kn": 1e9, "kt": 1e9, "friction": 0.7, "colour": "red"}}, "colour"),
        ({"material": {"kn": -1.0, "kt": 1e9, "friction": 0.7}}, "kn"),
        ({"material": {"kn": 1e9, "kt": 1e9, "friction": float("nan")}}, "friction"),
        ({"supports": [{"select": "column:middle"}]}, "column"),
        ({"supports": []}, "mechanism"),
        ({"loads": [{"type": "wind"}]}, "type"),
        ({"analysis": {"bracket_tolerance": 0.0}}, "bracket_tolerance"),
        ({"analysis": {"step": 0.1}}, "step"),
    ],
)
def test_bad_case_files_name_the_field(patch, message):
    data = {**SINGLE_BLOCK, **patch}
    with pytest.raises(ValueError, match=message):
        case_from_dict(data)


def test_missing_case_file_is_a_clear_cli_error(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "r")]) == 2
    assert "case file not found" in capsys.readouterr().err


def test_console_script_help_lists_commands():
    out = subprocess.run(
        [sys.executable, "-m", "masonry_dem.cli", "--help"], capture_output=True, text=True
    )
    assert out.returncode == 0 and "run" in out.stdout


def test_quickstart_example_runs(tmp_path, capsys):
    summary = runpy.run_path(str(ROOT / "examples" / "quickstart.py"), run_name="not_main")["main"](
        ["--out", str(tmp_path / "q"), "--courses", "5"]
    )
    assert summary["status"] == "collapse"
    assert (tmp_path / "q" / "summary.json").exists()


def test_the_readme_python_example_runs(tmp_path, capsys, monkeypatch):
    """The README's Python example, as printed, builds the default wall and its pushover
    ends in a certified collapse at the bundled case's lambda."""
    readme = (ROOT / "README.md").read_text()
    code = readme.split("### In Python")[1].split("```python")[1].split("```")[0]
    monkeypatch.chdir(tmp_path)  # its results folder, results/ol1, lands here
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    history = namespace["history"]
    assert history.status == "collapse" and history.certificate.holds
    default = json.loads((tmp_path / "results" / "ol1" / "summary.json").read_text())
    assert default["status"] == "collapse"
    assert history.collapse_multiplier == pytest.approx(0.2826, rel=0.01)
    assert "collapse" in capsys.readouterr().out
    # the next block: every method through md.analyze on the same model
    compare = readme.split("### In Python")[1].split("```python")[2].split("```")[0]
    exec(compile(compare, "README.md", "exec"), namespace)
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in lines] == [
        ["pushover", "collapse"],
        ["relaxation", "collapse"],
        ["limit", "collapse"],
    ]


def test_run_renders_the_last_step_and_the_collapse_mechanism(tmp_path, capsys):
    """The PNGs are written, named in the summary and in the run's last line (the block
    tilting over along e3 is drawn from the side, where its motion shows); the folder keeps
    no lock file once the run is over."""
    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "res"
    assert main(["run", str(case), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert (out / summary["png"]).is_file()
    assert summary["mechanism_png"] == "mechanism_side.png"
    assert (out / summary["mechanism_png"]).is_file()
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert summary["png"] in last and summary["mechanism_png"] in last
    assert not (out / ".masonry-dem.lock").exists()


def test_the_limit_analysis_bound_is_computed_only_to_certify_a_collapse(tmp_path, monkeypatch):
    """``run`` computes the associative bound when a collapse is to be certified, and only
    then: a run that ends ``completed`` (max_load_factor 0.2, below the block's s/a = 0.5)
    does no limit analysis; a collapse carries the bound (0.5, the block's s/a) checked
    within it; ``--no-bound`` leaves the certificate's bound unchecked."""
    import masonry_dem.run_case as run_module

    calls: list[int] = []
    original = run_module.limit_analysis_bound

    def counting(model):
        calls.append(model.blocks.count)
        return original(model)

    monkeypatch.setattr(run_module, "limit_analysis_bound", counting)
    capped = _write_case(tmp_path, dict(SINGLE_BLOCK, analysis={"max_load_factor": 0.2}))
    out = tmp_path / "capped"
    assert main(["run", str(capped), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and calls == []
    assert summary["limit_analysis_bound"] is None
    assert summary["limit_analysis_status"] == "not computed (no collapse to certify)"
    case = _write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "collapse"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "collapse" and len(calls) == 1
    assert summary["limit_analysis_bound"] == pytest.approx(0.5, rel=1e-6)
    assert summary["certificate"]["bound_status"] == "within"
    out = tmp_path / "no_bound"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet", "--no-bound"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "collapse" and len(calls) == 1
    assert summary["certificate"]["bound_status"] == "not checked"
    assert summary["limit_analysis_status"] == "not computed (--no-bound)"


def test_run_goes_through_analyze_and_shows_the_newton_progress(tmp_path, monkeypatch):
    """``run_case`` (``masonry-dem run``) runs its pushover through ``md.analyze``: the steps
    its progress sees are those of the results folder and its lambda is ``analyze``'s on the
    same model to the last digit; within the steps it is told the solver's Newton iterations
    and factorizations (every tick here, the interval set to 0), which only grow."""
    import masonry_dem.analysis as analysis_module
    import masonry_dem.run_case as run_module

    class Recorder(run_module.Progress):
        def __init__(self) -> None:
            self.steps: list[float] = []
            self.ticks: list[tuple[int, int]] = []

        def step(self, step):
            self.steps.append(step.load_factor)

        def tick(self, iterations, factorizations):
            self.ticks.append((iterations, factorizations))

    calls: list[str] = []
    original = analysis_module.analyze

    def counting(model, method="pushover", *args, **kwargs):
        calls.append(method)
        return original(model, method, *args, **kwargs)

    monkeypatch.setattr(analysis_module, "analyze", counting)
    monkeypatch.setattr(run_module, "TICK_SECONDS", 0.0)
    case = load_case(_write_case(tmp_path, SINGLE_BLOCK))
    shown = Recorder()
    summary = run_module.run_case(case, tmp_path / "res", render=False, progress=shown)
    assert calls == ["pushover"]
    rows = np.loadtxt(tmp_path / "res" / "pushover.csv", delimiter=",", skiprows=1, ndmin=2)
    assert shown.steps == pytest.approx(rows[:, 1].tolist(), rel=1e-9)  # the CSV: 10 digits
    alone = original(case.model, "pushover", case.settings, monitor=case.monitor)
    assert summary["lambda"] == alone.load_factor
    assert shown.ticks and shown.ticks == sorted(shown.ticks)
    assert shown.ticks[-1][0] <= summary["iterations"]


def test_a_case_with_a_cohesion_of_its_own_runs_with_its_bound(tmp_path):
    """A run whose joints have a cohesion of their own collapses (the block tilts at s/a =
    0.5: no tension, so no rocking strength from the cohesion) within the limit analysis's
    bound, computed with the cohesion: the same 0.5 (rocking opens the joint, no slip)."""
    material = dict(SINGLE_BLOCK["material"], cohesion=5e3)
    case = _write_case(tmp_path, dict(SINGLE_BLOCK, material=material))
    out = tmp_path / "cohesive"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "collapse"
    assert summary["lambda"] == pytest.approx(0.5, rel=0.01)
    assert summary["limit_analysis_status"] == "collapse"
    assert summary["limit_analysis_bound"] == pytest.approx(0.5, rel=1e-6)
    assert summary["lambda"] <= summary["limit_analysis_bound"] * (1 + 1e-6)
