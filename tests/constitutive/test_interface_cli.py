"""``masonry-dem interface``: closed form vs spring model and Table A1, text and JSON."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from masonry_dem.cli import main


def _json(capsys, *args: str) -> dict:
    assert main(["interface", "--json", *args]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_reference_interface(capsys, ref_interface, table_a1, alpha_columns):
    out = _json(capsys)
    for key in ("shear_strength", "torsion_strength", "spring_shear_strength",
                "spring_torsion_strength", "alpha_table"):  # fmt: skip
        assert key in out
    assert out["shear_strength"] == pytest.approx(ref_interface["shear_strength"], rel=5e-3)
    assert out["spring_shear_strength"] == pytest.approx(ref_interface["shear_strength"], rel=5e-3)
    assert out["torsion_strength"] == pytest.approx(ref_interface["torsion_strength"], rel=1e-2)
    assert out["spring_torsion_strength"] == pytest.approx(
        ref_interface["torsion_strength"], rel=1e-2
    )
    assert out["interface"]["springs_per_side"] == ref_interface["springs_per_side"]
    errors = [abs(row["relative_error"]) for row in out["torsion_convergence"]]
    assert [row["n"] for row in out["torsion_convergence"]] == [4, 8, 16, 32, 64]
    assert errors == sorted(errors, reverse=True) and errors[-1] < 1e-3
    rows = out["alpha_table"]
    assert len(rows) == 3 * len(table_a1["aspect_l1_over_l2"])
    for row in rows:
        assert set(row) >= {"aspect", "direction", "alpha_fitted", "alpha_paper"}
        i = table_a1["aspect_l1_over_l2"].index(row["aspect"])
        assert row["alpha_paper"] == alpha_columns[row["direction"]][i]
        assert abs(row["alpha_fitted"] - row["alpha_paper"]) < 0.125


def test_text_output_and_custom_interface(capsys):
    args = ["--l1", "0.2", "--l2", "0.2", "--fn", "-100", "--friction", "0.5", "--n", "16"]
    assert main(["interface", *args, "--no-alpha-table"]) == 0
    text = capsys.readouterr().out
    assert "shear strength [N]" in text and "torsion strength [N m]" in text
    assert "50.000" in text  # mu * |fn|
    out = _json(capsys, *args, "--no-alpha-table", "--tensile-strength", "1000")
    assert out["shear_strength"] == pytest.approx(0.5 * (100 + 1000 * 0.04))
    assert out["alpha_table"] == []


def test_a_cohesion_of_its_own(capsys):
    """Lourenco's joint (ft 0.16 MPa, c 0.224 MPa, mu 0.75): fsu = c A - mu fn, the spring
    model's too."""
    args = ["--l1", "0.2", "--l2", "0.1", "--fn", "-100", "--friction", "0.75", "--n", "8"]
    more = ["--tensile-strength", "0.16e6", "--cohesion", "0.224e6", "--no-alpha-table"]
    out = _json(capsys, *args, *more)
    assert out["interface"]["cohesion"] == 0.224e6
    assert out["shear_strength"] == pytest.approx(0.224e6 * 0.02 + 0.75 * 100, rel=1e-12)
    assert out["spring_shear_strength"] == pytest.approx(out["shear_strength"], rel=1e-9)
    assert main(["interface", *args, *more]) == 0
    assert "cohesion = 224000 Pa" in capsys.readouterr().out
    assert main(["interface", *args, "--tensile-strength", "0.16e6", "--cohesion", "1e4"]) == 2
    assert "tensile_strength must be at most cohesion / friction" in capsys.readouterr().err


def test_text_table(capsys):
    assert main(["interface", "--alpha-n", "8", "--n", "8"]) == 0
    text = capsys.readouterr().out
    assert "Table A1" in text and "f1=f2" in text


@pytest.mark.parametrize(
    "args",
    [["--friction", "-0.7"], ["--l1", "0"], ["--n", "0"], ["--fn", "10"], ["--directions", "0"]],
)
def test_bad_input_exits_2(capsys, args):
    assert main(["interface", "--no-alpha-table", *args]) == 2
    assert "error" in capsys.readouterr().err


def test_module_entry_point():
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run(
        [sys.executable, "-m", "masonry_dem.cli", "interface", "--json", "--no-alpha-table"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["torsion_strength"] > 0
