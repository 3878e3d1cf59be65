"""``masonry-dem assess`` (issue 38, item 5): a run's mechanism checked against a code's
spectrum, written into its results folder only; bad spectrum parameters refused in one line
naming the field, its range and unit, with the exit code of the other input errors (2)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK, write_case
from masonry_dem.cli import main

G = 9.81
TOL = 1e-9
FILES = {"assessment.json", "capacity_curve.csv", "adrs.png"}
NTC = ["--ag", "0.2", "--F0", "2.4", "--Tc", "0.35", "--soil", "A"]


@pytest.fixture(scope="module")
def block_run(tmp_path_factory):
    """The single block (h 0.4, t 0.2, b 0.3 m, 20 kN/m3) run to its collapse."""
    root = tmp_path_factory.mktemp("block")
    case = write_case(root, SINGLE_BLOCK)
    out = root / "res"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    return out


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    """The bundled default wall run to its collapse."""
    out = tmp_path_factory.mktemp("default") / "res"
    assert main(["run", "--out", str(out), "--no-render", "--quiet"]) == 0
    return out


def _read(out: Path) -> dict:
    return json.loads((out / "assessment.json").read_text(), parse_constant=_refuse)


def _refuse(text: str) -> float:
    raise AssertionError(f"assessment.json holds {text}")


def test_block_from_its_run(block_run, capsys):
    """The pushover's mode of the block (rotation about its joint's centre) hinged at its
    toe: alpha0 = t/h = 0.5, e* = 1, M* = W/g, d0* = t/2; a0* = 0.5 g / 1.35 against
    0.2 g / 2; the control point the block's centroid. The nonlinear check is Circolare
    2019's SLV: d_SLV = 0.4 d0* = 0.04 m, T_SLV = 1.68 pi sqrt(0.04 x 1.35 sqrt(0.1856) /
    (0.12 g)) = 0.7419513008 s, S_De(T_SLV) at 8 % = 0.027165786102 m
    (tests/assessment/test_assess_circolare2019.py derives them)."""
    before = {p.name for p in block_run.parent.iterdir()}
    code = main(["assess", str(block_run), *NTC, "--alpha0", "mechanism"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "linear: a0* =" in printed and "passes" in printed
    assert {p.name for p in block_run.parent.iterdir()} == before  # the folder only
    assert FILES <= {p.name for p in block_run.iterdir()}
    a = _read(block_run)
    W = 20e3 * 0.4 * 0.3 * 0.2
    assert a["code"] == "ntc2018"
    assert a["alpha0"] == pytest.approx(0.5, rel=TOL)
    assert a["e_star"] == pytest.approx(1.0, rel=TOL)
    assert a["M_star"] == pytest.approx(W / G, rel=TOL)
    assert a["a0_star"] == pytest.approx(0.5 * G / 1.35, rel=TOL)
    assert a["demand"] == pytest.approx(0.2 * G / 2.0, rel=TOL)
    assert a["ratio"] == pytest.approx(a["a0_star"] / a["demand"], rel=TOL)
    assert a["passes"] is True
    assert a["d0_star"] == pytest.approx(0.1, rel=TOL)
    assert a["nonlinear_check"] == "circolare_2019" and a["limit_state"] == "SLV"
    assert a["d_SLV"] == pytest.approx(0.04, rel=TOL) and a["du_star"] == pytest.approx(
        0.04, rel=TOL
    )
    assert a["T_SLV"] == pytest.approx(0.7419513008172157, rel=TOL)
    assert a["nonlinear_damping"] == 8.0
    assert a["displacement_demand"] == pytest.approx(0.027165786102205446, rel=TOL)
    assert a["passes_nonlinear"] is True
    assert "T_SLV = 1.68 pi" in a["nonlinear_summary"] and " s," in a["nonlinear_summary"]
    assert "T_SLV = 1.68 pi sqrt" in printed
    np.testing.assert_allclose(a["control_point"], [0.15, 0.2, 0.1], atol=TOL)
    assert a["lambda"] == pytest.approx(0.5, rel=0.005)  # the run's own multiplier
    assert a["kinematics"] == "chain" and a["overlap_at_du"] < TOL  # one body: both exact
    assert a["motion_note"] == "" and "warning" not in printed
    curve = np.loadtxt(block_run / "capacity_curve.csv", delimiter=",", skiprows=1)
    assert curve[0, 1] == pytest.approx(0.5, rel=TOL) and curve[-1, 1] == 0.0
    assert curve[-1, 3] == pytest.approx(0.1, rel=TOL)
    assert curve[0, 4] == pytest.approx(a["a0_star"], rel=TOL)
    assert (block_run / "adrs.png").stat().st_size > 10_000


def test_alpha0_of_the_run_by_default(block_run):
    assert main(["assess", str(block_run), *NTC, "--no-render"]) == 0
    a = _read(block_run)
    assert a["alpha0"] == a["lambda"]
    assert a["alpha0_source"] == "the analysis's multiplier"
    assert a["alpha_rigid"] == pytest.approx(0.5, rel=TOL)


@pytest.mark.parametrize("code", ["ntc2018", "ec8"])
def test_default_wall(default_run, code, capsys):
    """The bundled wall: every number finite, the verdicts those of the ratios. Its
    pushover's mode is no finite mechanism of rigid blocks (docs/assessment.md): the motion
    chosen overlaps, and the command says by how much, against the blocks' least size (70 mm
    thick), and why the incremental path was not taken."""
    extra = ["--F0", "2.4", "--Tc", "0.3"] if code == "ntc2018" else ["--spectrum-type", "1"]
    args = ["assess", str(default_run), "--code", code, "--ag", "0.25", "--soil", "B", *extra]
    assert main(args) == 0
    a = _read(default_run)
    out = capsys.readouterr().out
    assert a["overlap_at_du"] > 1e-9 and a["least_block_size"] == pytest.approx(0.07, rel=TOL)
    worst = max(a["overlap_at_du"], a["drift_at_du"])
    assert f"its blocks overlap by {1e3 * a['overlap_at_du']:.3g} mm" in a["motion_note"]
    share = f"{100 * worst / a['least_block_size']:.2g} % of the moving blocks' least size (70 mm)"
    assert share in a["motion_note"]
    assert (
        "the incremental path, which keeps the contacts, reaches no alpha = 0" in a["motion_note"]
    )
    assert f"warning: {a['motion_note']}; a limit analysis of the same case" in out
    assert a["code"] == code
    assert a["passes"] == (a["a0_star"] >= a["demand"])
    assert 0 < a["e_star"] <= 1 and a["M_star"] > 0
    assert a["a0_star"] == pytest.approx(a["alpha0"] * G / (a["e_star"] * a["FC"]), rel=TOL)
    # the kinematics chosen overlaps least at d_u*; the chain's has no alpha = 0 here
    assert a["kinematics"] in ("chain", "independent")
    assert a["overlap_at_du"] == min(v for v in a["overlaps"].values() if v is not None)
    if code == "ec8":  # the secant period as T*
        assert a["passes_nonlinear"] == (a["du_star"] >= a["displacement_demand"])
        Ts = 2 * math.pi * math.sqrt(a["ds_star"] / a["as_star"])
        assert a["Ts"] == pytest.approx(Ts, rel=TOL)
        assert a["du_star"] == pytest.approx(0.4 * a["d0_star"], rel=TOL)
        assert a["nonlinear_check"] is None
    else:  # Circolare 2019, SLV
        assert a["d_SLV"] == pytest.approx(0.4 * a["d0_star"], rel=TOL)
        T_SLV = 1.68 * math.pi * math.sqrt(a["d_SLV"] / a["a_SLV"])
        assert a["T_SLV"] == pytest.approx(T_SLV, rel=TOL)
        assert a["passes_nonlinear"] == (
            a["d_SLV"] >= a["displacement_demand"] or a["activation_ratio"] >= 1
        )
    assert a["analysis"] == "pushover" and a["case"].startswith("bundled:")


def test_config_file_and_flags_over_it(default_run, tmp_path):
    cfg = tmp_path / "site.toml"
    cfg.write_text('code = "ntc2018"\nag = 0.3\nF0 = 2.5\nTc = 0.4\nsoil = "C"\nZ = 0\n')
    assert main(["assess", str(default_run), "--config", str(cfg), "--no-render"]) == 0
    assert _read(default_run)["spectrum"]["ag"] == 0.3
    assert (
        main(["assess", str(default_run), "--config", str(cfg), "--ag", "0.1", "--no-render"]) == 0
    )
    a = _read(default_run)
    assert a["spectrum"]["ag"] == 0.1 and a["spectrum"]["soil"] == "C"


@pytest.mark.parametrize(
    ("flags", "words"),
    [
        (["--ag", "2"], ["ag = 2.0", "(0, 1.5] g"]),
        (["--ag", "0.2", "--F0", "7"], ["F0 = 7.0", "[1, 5]"]),
        (["--ag", "0.2", "--Tc", "0"], ["Tc = 0.0", "(0, 2] s"]),
        (["--ag", "0.2", "--soil", "F"], ["soil = 'F'", "A, B, C, D, E"]),
        (["--ag", "0.2", "--FC", "0.5"], ["FC = 0.5", "[1, 3]"]),
        (["--ag", "0.2", "--Z", "3"], ["Z = 3", "H"]),
        (["--ag", "0.2", "--Z", "12", "--H", "9"], ["Z = 12", "[0, H = 9] m"]),
        (["--code", "ec8", "--ag", "0.2", "--F0", "2.4"], ["F0", "ec8"]),
        (["--soil", "A"], ["ag", "[g]"]),
        (
            ["--ag", "0.2", "--demand-at-height", "floor"],
            ["demand_at_height = 'floor'", "floor_spectrum, circolare_2009"],
        ),
        (["--ag", "0.2", "--building-damping", "0"], ["building_damping = 0.0", "(0, 30] %"]),
        (
            ["--code", "ec8", "--ag", "0.2", "--demand-at-height", "floor_spectrum"],
            ["demand_at_height", "ntc2018 code only", "ec8"],
        ),
        (
            ["--ag", "0.2", "--nonlinear-check", "2019"],
            ["nonlinear_check = '2019'", "circolare_2019, circolare_2009"],
        ),
        (["--ag", "0.2", "--limit-state", "slv"], ["limit_state = 'slv'", "SLV, SLC"]),
        (
            ["--ag", "0.2", "--limit-state", "SLC", "--nonlinear-check", "circolare_2009"],
            ["limit_state = 'SLC'", "must be SLV with nonlinear_check = circolare_2009"],
        ),
        (
            ["--code", "ec8", "--ag", "0.2", "--nonlinear-check", "circolare_2009"],
            ["nonlinear_check", "ntc2018 code only", "ec8"],
        ),
    ],
)
def test_bad_parameters_one_line_exit_2(block_run, capsys, flags, words):
    assert main(["assess", str(block_run), "--no-render", *flags]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("masonry-dem: error:")
    for w in words:
        assert w in err


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ('ag = 0.2\nsoil = "B"\nF0 = 12\n', ["F0 = 12", "[1, 5]"]),
        ('ag = "0.2"\n', ["ag = '0.2'", "without quotes", "(0, 1.5] g"]),
        ("ag = 0.2\nZ = 4.0\nH = 3.0\n", ["Z = 4", "[0, H = 3] m"]),
        (
            'ag = 0.2\ndemand_at_height = "2009"\n',
            ["demand_at_height = '2009'", "floor_spectrum, circolare_2009"],
        ),
        (
            'ag = 0.2\nnonlinear_check = "T_SLV"\n',
            ["nonlinear_check = 'T_SLV'", "must be one of circolare_2019, circolare_2009"],
        ),
    ],
)
def test_a_bad_value_of_the_config_file_names_the_file(block_run, tmp_path, capsys, text, words):
    cfg = tmp_path / "site.toml"
    cfg.write_text(text)
    assert main(["assess", str(block_run), "--config", str(cfg), "--no-render"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"assessment file {cfg}: " in err
    for w in words:
        assert w in err


def test_demand_at_height_floor_spectrum_by_default_and_2009_on_request(block_run, tmp_path):
    """At Z = 6 m of H = 9 m, N = 3, T1 = 0.3 s (soil A, ag 0.2, F0 2.4, Tc* 0.35, q 2): the
    default is the floor's peak acceleration of Circolare 2019 over q, 4.0562446564 / 2;
    ``demand_at_height = "circolare_2009"`` in the file gives Se(T1) psi gamma / q."""
    site = [*NTC, "--Z", "6", "--H", "9", "--storeys", "3", "--T1", "0.3", "--no-render"]
    assert main(["assess", str(block_run), *site]) == 0
    a = _read(block_run)
    assert a["demand_at_height"] == "floor_spectrum" and a["building_damping"] == 5.0
    assert a["demand_height"] == pytest.approx(4.0562446564057755 / 2, rel=TOL)
    cfg = tmp_path / "old.toml"
    cfg.write_text('demand_at_height = "circolare_2009"\n')
    assert main(["assess", str(block_run), *site, "--config", str(cfg)]) == 0
    a = _read(block_run)
    assert a["demand_at_height"] == "circolare_2009"
    assert a["demand_height"] == pytest.approx(0.2 * G * 2.4 * (2 / 3) * (9 / 7) / 2, rel=TOL)


def test_the_circolare_2009_check_on_request(block_run, tmp_path, capsys):
    """``nonlinear_check = "circolare_2009"`` (file or flag): d_u* = 0.04 m and the secant
    period Ts at d_s* = 0.4 d_u* (the values of test_kinematics.py's closed form), no T_SLV;
    ``--limit-state SLC`` with the 2019 check: d_SLC = 0.6 d0* = 0.06 m, T_SLC = 1.56 pi
    sqrt(0.06 x 11 x 1.35 / 2g) = 1.044392686 s."""
    from scipy.optimize import brentq

    cfg = tmp_path / "old.toml"
    cfg.write_text('nonlinear_check = "circolare_2009"\n')
    assert main(["assess", str(block_run), *NTC, "--config", str(cfg), "--no-render"]) == 0
    assert "Circolare 2009 C8A.4.2.2: d_u* = 0.4 d0* = 40 mm" in capsys.readouterr().out
    a = _read(block_run)
    h, t, ds = 0.4, 0.2, 0.016
    theta_s = brentq(
        lambda th: (t / 2) * (1 - math.cos(th)) + (h / 2) * math.sin(th) - ds, 0, 1, xtol=1e-15
    )
    Ts = 2 * math.pi * math.sqrt(ds / (math.tan(math.atan(t / h) - theta_s) * G / 1.35))
    assert a["nonlinear_check"] == "circolare_2009" and a["T_SLV"] is None
    assert a["du_star"] == pytest.approx(0.04, rel=TOL)
    assert a["Ts"] == pytest.approx(Ts, rel=TOL)
    assert a["displacement_demand"] == pytest.approx(
        0.2 * G * 2.4 * 0.35 * Ts / (4 * math.pi**2), rel=TOL
    )
    assert main(["assess", str(block_run), *NTC, "--limit-state", "SLC", "--no-render"]) == 0
    a = _read(block_run)
    assert a["limit_state"] == "SLC" and a["d_SLV"] is None
    assert a["d_SLC"] == pytest.approx(0.06, rel=TOL)
    assert a["T_SLC"] == pytest.approx(1.56 * math.pi * math.sqrt(0.06 * 11 * 1.35 / (2 * G)))
    assert a["nonlinear_damping"] == 10.0
    # a damping given is the mechanism's (C8.7.1.2.1.8 "in assenza di valutazioni più
    # accurate"): 5 % gives eta = 1, S_De(T_SLV) = 0.030973762 m (test_assess_circolare2019.py)
    assert main(["assess", str(block_run), *NTC, "--damping", "5", "--no-render"]) == 0
    a = _read(block_run)
    assert a["nonlinear_damping"] == 5.0 and a["limit_state"] == "SLV"
    assert a["displacement_demand"] == pytest.approx(0.030973761717234347, rel=TOL)


def test_unknown_config_key(block_run, tmp_path, capsys):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("ag = 0.2\npga = 0.3\n")
    assert main(["assess", str(block_run), "--config", str(cfg)]) == 2
    assert "unknown key 'pga'" in capsys.readouterr().err


def test_chain_kinematics_without_alpha_zero_leaves_the_nonlinear_check_out(default_run):
    """The default wall's pushover mechanism composed as a chain keeps alpha > 0 until its
    blocks turn away from the load: the linear check is made, the nonlinear one is None with
    the reason, and the picture says so."""
    args = ["assess", str(default_run), *NTC, "--kinematics", "chain"]
    assert main(args) == 0
    a = _read(default_run)
    assert a["d0_star"] is None and a["passes_nonlinear"] is None and a["T_SLV"] is None
    assert "no d_k0" in a["nonlinear_reason"]
    assert a["ratio"] == pytest.approx(a["a0_star"] / a["demand"], rel=TOL)


def test_a_folder_without_collapse(tmp_path, capsys):
    (tmp_path / "summary.json").write_text('{"status": "completed"}')
    assert main(["assess", str(tmp_path), "--ag", "0.2"]) == 2
    assert "not in a collapse" in capsys.readouterr().err


def test_in_a_child_process_as_a_shell_runs_it(block_run):
    """``python -m masonry_dem.cli assess`` with a bad value: one line, exit code 2, as the
    other commands' input errors; with good ones, exit 0 and the files."""
    from helpers.cli_process import run_cli

    bad = run_cli("assess", block_run, "--ag", "0.2", "--soil", "Z", "--no-render")
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == [
        "masonry-dem: error: soil = 'Z': must be one of A, B, C, D, E (ground category)"
    ]
    good = run_cli("assess", block_run, "--code", "ec8", "--ag", "0.2", "--soil", "C")
    assert good.returncode == 0, good.stderr
    assert f"results in {block_run}/" in good.stdout
    assert _read(block_run)["code"] == "ec8"


def test_overwrite_removes_the_assessment(tmp_path):
    """A run with --overwrite into a folder that was assessed leaves no stale assessment."""
    case = write_case(tmp_path, SINGLE_BLOCK)
    out = tmp_path / "res"
    assert main(["run", str(case), "--out", str(out), "--no-render", "--quiet"]) == 0
    assert main(["assess", str(out), *NTC]) == 0
    assert FILES <= {p.name for p in out.iterdir()}
    args = ["run", str(case), "--out", str(out), "--no-render", "--quiet", "--overwrite"]
    assert main(args) == 0
    assert not FILES & {p.name for p in out.iterdir()}


def test_the_incremental_path_shows_its_steps_unless_quiet(block_run, capsys):
    """The incremental kinematics reports each step; ``assess`` shows them on one progress
    line on stderr, and nothing with ``--quiet``."""
    args = ["assess", str(block_run), *NTC, "--kinematics", "incremental", "--no-render"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "incremental kinematics" in err and "a block turned" in err
    assert main([*args, "--quiet"]) == 0
    assert "incremental kinematics" not in capsys.readouterr().err
