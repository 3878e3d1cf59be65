"""``masonry-dem limit`` never hangs: its time limit (``--time-limit``, ``[analysis]
time_limit``) ends a run "failed" with no lambda, and SIGTERM or Ctrl-C during a solve leaves
``interrupted`` in summary.json within 2 s."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest

from helpers.case_files import write_case
from helpers.cli_process import start_cli
from masonry_dem.cli import main

ROOT = Path(__file__).resolve().parents[2]


def held_wall(n: int, courses: int, **analysis) -> dict:
    """The issue's kind of wall as a case: running bond of 0.081 x 0.21 x 0.07 m blocks on a
    base, out of plane, its left column held in u1 and u3."""
    case: dict = {
        "name": "held",
        "geometry": {
            "builder": "running_bond_wall",
            "blocks_along_length": n,
            "courses": courses,
            "block_height": 0.081,
            "block_length": 0.21,
            "thickness": 0.07,
            "unit_weight": 20e3,
            "base": True,
        },
        "material": {"kn": 1e9, "kt": 4e8, "friction": 0.7},
        "supports": [{"select": "base"}, {"select": "column:left", "dofs": ["u1", "u3"]}],
        "loads": [
            {"type": "self_weight"},
            {"type": "weight_proportional", "direction": [0, 0, 1]},
        ],
    }
    if analysis:
        case["analysis"] = analysis
    return case


def test_a_run_out_of_time_exits_1_with_no_lambda(tmp_path, capsys):
    """HiGHS's LP on 331 blocks takes seconds; given a millisecond it stops, and so does the
    run: status failed, lambda null, the limit named, exit 1."""
    case = write_case(tmp_path, held_wall(16, 20))
    out = tmp_path / "la"
    argv = ["limit", str(case), "--out", str(out), "--no-render", "--backend", "highs"]
    assert main([*argv, "--time-limit", "0.001"]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["lambda"] is None
    assert "stopped by the solver's time or iteration limit" in summary["reason"]
    assert "Time limit reached" in summary["reason"]
    assert "time or iteration limit" in capsys.readouterr().out


def test_the_case_file_time_limit(tmp_path):
    """``[analysis] time_limit`` with ``method = "limit"``: the same stop."""
    case = write_case(
        tmp_path, held_wall(16, 20, method="limit", backend="highs", time_limit=0.001)
    )
    out = tmp_path / "la"
    assert main(["limit", str(case), "--out", str(out), "--no-render"]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "Time limit reached" in summary["reason"]


@pytest.mark.parametrize("text", ["0", "-5", "inf", "nan", "soon"])
def test_a_time_limit_out_of_range_is_named(tmp_path, capsys, text):
    case = write_case(tmp_path, held_wall(2, 3))
    with pytest.raises(SystemExit) as exc:
        main(["limit", str(case), "--out", str(tmp_path / "la"), "--time-limit", text])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"--time-limit must be a finite number of seconds > 0, got '{text}'" in err


@pytest.mark.parametrize("value", [0, -1.0])
def test_a_case_file_time_limit_out_of_range_is_named(tmp_path, capsys, value):
    case = write_case(tmp_path, held_wall(2, 3, method="limit", time_limit=value))
    assert main(["limit", str(case), "--out", str(tmp_path / "la"), "--no-render"]) == 2
    err = capsys.readouterr().err
    assert f"[analysis].time_limit = {value}" in err
    assert "above 0" in err


def test_a_time_limit_needs_the_limit_method(tmp_path, capsys):
    case = write_case(tmp_path, held_wall(2, 3, time_limit=10))
    assert main(["run", str(case), "--out", str(tmp_path / "r"), "--no-render"]) == 2
    assert "[analysis].time_limit = 10" in capsys.readouterr().err


@pytest.mark.parametrize(
    "signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)], ids=["SIGTERM", "Ctrl-C"]
)
def test_a_signal_during_the_solve_is_obeyed_within_2_s(tmp_path, signum, code):
    """HiGHS's LP on 586 blocks runs for tens of seconds (36 s of CPU measured); the signal
    comes a second into it. summary.json says "interrupted" within 2 s (measured: 0.01 to
    0.12 s), and the process exits with 128 + the signal's number."""
    case, out = write_case(tmp_path, held_wall(22, 26)), tmp_path / "out"
    proc = start_cli("limit", case, "--out", out, "--backend", "highs", "--no-render")
    try:
        while not (out / "summary.json").exists():
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.01)
        time.sleep(1.0)  # the model is built in 0.1 s: inside HiGHS's solve now
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(signum)
        sent = time.monotonic()
        status = None
        while time.monotonic() - sent < 2.0:
            status = json.loads((out / "summary.json").read_text())["status"]
            if status == "interrupted":
                break
            time.sleep(0.01)
        assert status == "interrupted"
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == code, err
    assert err.strip() == f"masonry-dem: interrupted by {signal.Signals(signum).name}"
