"""A run that knows its size (solvers/resources.py, ``masonry-dem run --max-memory``): the
blocks of a case counted without building it, the model's part of the memory estimate
against the memory the model and the solver's set-up really allocate, and the refusal of a
1000 x 1000 wall with the estimate in the message and exit code 2, before anything is built."""

from __future__ import annotations

import os
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.cases.casefile import build_blocks
from masonry_dem.cli import main
from masonry_dem.model import Model
from masonry_dem.solvers import resources
from masonry_dem.solvers.incremental import StaticSolver

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = (ROOT / "src/masonry_dem/cases/data/default_wall.toml").read_text()


def _case(tmp_path: Path, along: int, courses: int) -> Path:
    text = DEFAULT.replace("blocks_along_length = 3\n", f"blocks_along_length = {along}\n")
    text = text.replace("courses = 13\n", f"courses = {courses}\n")
    assert f"courses = {courses}" in text and f"blocks_along_length = {along}" in text
    path = tmp_path / f"wall_{along}x{courses}.toml"
    path.write_text(text)
    return path


GEOMETRIES = [
    dict(builder="running_bond_wall", blocks_along_length=7, courses=5, base=True),
    dict(builder="running_bond_wall", blocks_along_length=3, courses=6, start_with_half=True),
    dict(builder="running_bond_wall_of_size", length=2.0, height=1.5, joint=0.01, base=True),
    dict(builder="stack_bond_column", courses=9),
    dict(builder="single_block", base=True),
]


@pytest.mark.parametrize("geometry", GEOMETRIES, ids=lambda g: g["builder"])
def test_blocks_are_counted_exactly_without_building_them(geometry):
    geometry = {"a": 0.081, "b": 0.21, "s": 0.07, "unit_weight": 20e3, **geometry}
    assert resources.blocks_of_geometry(geometry) == build_blocks(geometry)[0].count


def test_an_unknown_builder_is_not_guessed():
    assert resources.blocks_of_geometry({"builder": "dome"}) is None
    assert resources.blocks_of_geometry({"builder": "running_bond_wall"}) is None


def test_the_model_part_of_the_estimate_is_what_the_model_and_the_solver_allocate():
    """tracemalloc's peak while a 20 x 20 wall is built and its solver set up (the tangent
    assembler's sort is the peak) against the estimate's ``model`` part: within a factor 1.6
    either way (the constants come from 10^3 and 10^4 blocks). The compiled kernels are
    loaded first: loading them from numba's cache is no part of the model's memory."""
    tiny, tiny_base = md.add_base(md.running_bond_wall(2, 2, 0.081, 0.21, 0.07, 20e3))
    tiny_model = Model.build(tiny, md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
                             [md.Support([tiny_base])])  # fmt: skip
    StaticSolver(tiny_model).problem.tangent_assembler.data(
        np.tile(np.eye(6), (tiny_model.interfaces.count, 1, 1))
    )
    tracemalloc.start()
    wall = md.running_bond_wall(20, 20, 0.081, 0.21, 0.07, 20e3)
    blocks, base = md.add_base(wall)
    model = Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        [md.Support([base])],
        [md.SelfWeight(), md.WeightProportional((0.0, 0.0, 1.0))],
    )
    solver = StaticSolver(model)
    solver.problem.tangent_assembler.data(np.tile(np.eye(6), (model.interfaces.count, 1, 1)))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    est = resources.estimate(model.blocks.count, model.interfaces.count, model.n_dofs)
    assert est.parts["model"] / 1.6 <= peak <= 1.6 * est.parts["model"]
    assert est.memory == pytest.approx(sum(est.parts.values()))


def test_the_kept_part_of_the_estimate_is_what_the_tangents_update_keeps():
    """tracemalloc's memory still held after the first ``TangentAssembler.update`` of a 20 x
    20 wall (the store it keeps for the next tangents: each joint's tangent and block, the
    entries and the joint index; the entries it returns are dropped) against the estimate's
    ``kept`` part: within 1.25x either way."""
    wall = md.running_bond_wall(20, 20, 0.081, 0.21, 0.07, 20e3)
    blocks, base = md.add_base(wall)
    model = Model.build(blocks, md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
                        [md.Support([base])])  # fmt: skip
    tangents = StaticSolver(model).problem.tangent_assembler
    T = np.tile(np.eye(6), (model.interfaces.count, 1, 1))
    tangents.update(T)  # the kernel compiled or loaded before the count
    tangents._kept = None
    tracemalloc.start()
    tangents.update(T)
    held = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    est = resources.estimate(model.blocks.count, model.interfaces.count, model.n_dofs)
    assert est.parts["kept"] / 1.25 <= held <= 1.25 * est.parts["kept"]


def test_the_estimate_grows_faster_than_the_wall():
    """Factors of a planar wall grow like n log n: ten times the blocks, more than ten
    times the factors' memory, and more time."""
    small, large = resources.estimate(10_000), resources.estimate(100_000)
    assert large.parts["factors"] > 10 * small.parts["factors"]
    assert large.seconds > 10 * small.seconds
    with pytest.raises(ValueError, match="blocks must be >= 0, got -1"):
        resources.estimate(-1)


@pytest.mark.parametrize(
    "text, value",
    [("16G", 16e9), ("500M", 500e6), ("2.5GB", 2.5e9), ("1e9", 1e9), ("64k", 64e3)],
)
def test_memory_sizes_parse(text, value):
    assert resources.parse_memory(text) == pytest.approx(value)


@pytest.mark.parametrize("text", ["lots", "-1G", "0"])
def test_a_bad_memory_size_names_the_option(text):
    with pytest.raises(ValueError, match="--max-memory"):
        resources.parse_memory(text)


def test_a_1000_by_1000_wall_is_refused_before_it_is_built(tmp_path, capsys, monkeypatch):
    def no_build(*args, **kwargs):
        raise AssertionError("the model was built before the refusal")

    monkeypatch.setattr(Model, "build", no_build)
    out = tmp_path / "out"
    code = main(["run", str(_case(tmp_path, 1000, 1000)), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert "refused" in err and "1000501 blocks" in err
    est = resources.estimate(1000501)
    assert f"{est.memory / 1e9:.1f} GB of memory" in err
    assert not out.exists()  # nothing written


def test_max_memory_refuses_a_small_wall_and_lets_it_run_when_raised(tmp_path, capsys):
    case = _case(tmp_path, 2, 3)
    assert main(["run", str(case), "--out", str(tmp_path / "a"), "--max-memory", "1M"]) == 2
    assert "over 1 MB (--max-memory)" in capsys.readouterr().err
    code = main(
        ["run", str(case), "--out", str(tmp_path / "b"), "--max-memory", "64G", "--no-render"]
    )
    assert code in (0, 1)  # it ran (the status of the tiny wall is not the point)
    assert (tmp_path / "b" / "summary.json").is_file()


def test_the_command_exits_with_code_2(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "masonry_dem.cli", "run", str(_case(tmp_path, 1000, 1000))],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert proc.returncode == 2
    assert "refused: the run would need 1000501 blocks" in proc.stderr


def test_a_cold_kernel_cache_adds_the_compilation_to_the_time_said(monkeypatch):
    """The time said before a run is the whole run's: on an empty or stale numba cache
    (every kernel reported uncached) it holds the compilation, jit.COMPILE_SECONDS of the
    serial kernels (x SIDE_BY_SIDE on two cores) for a small wall, and says it happens once
    per machine; on a warm cache only the loading of the compiled kernels. The pictures
    count when the run renders."""
    from masonry_dem import jit
    from masonry_dem.run_case import estimate_run

    model = md.load_case().model
    monkeypatch.setattr(jit, "_cached", lambda disp: False)
    cold = estimate_run(model)
    side_by_side = jit.SIDE_BY_SIDE if (os.cpu_count() or 1) >= 2 else 1.0
    compiling = "compiling the kernels (once per machine)"
    assert cold.times[compiling] == pytest.approx(jit.COMPILE_SECONDS["serial"] * side_by_side)
    assert cold.total_seconds >= cold.times[compiling] + cold.seconds
    assert compiling in cold.describe()
    monkeypatch.setattr(jit, "_cached", lambda disp: True)
    warm = estimate_run(model)
    assert compiling not in warm.times
    assert warm.times["loading the compiled kernels"] == resources.KERNEL_LOAD_SECONDS
    assert cold.total_seconds - warm.total_seconds > 5.0
    assert "pictures" in warm.times and "pictures" not in estimate_run(model, render=False).times


def test_the_time_said_is_a_range_that_widens_on_a_busy_machine():
    """From half to twice the idle estimate while a core is free; on 2 cores at load 3.9
    the top of the range grows by (3.9 + 1) / 2 and the message says why."""
    est = resources.estimate(46, 107, 276)
    idle = resources.run_time(est, compile_seconds=9.0, pictures=2, load=0.5, cores=2)
    lo, hi = idle.time_range()
    assert lo == pytest.approx(idle.total_seconds / 2) and hi == pytest.approx(
        2 * idle.total_seconds
    )
    assert "busy" not in idle.describe()
    busy = resources.run_time(est, compile_seconds=9.0, pictures=2, load=3.9, cores=2)
    assert busy.busy == pytest.approx(2.45)
    assert busy.time_range()[1] == pytest.approx(2.45 * hi)
    text = busy.describe()
    assert "expect" in text and "the machine is busy: load 3.9 on 2 cores" in text
    # the default wall's analysis (0.52 s measured, idle) is not said to take "0 s": the
    # fixed part of every Newton iteration counts
    assert 0.25 < est.seconds < 1.0
