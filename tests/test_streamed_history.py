"""The History streamed to disk (masonry_dem.streamed_history) against the one in memory.

Proves: a pushover whose steps go to disk gives the same History, read back: every step's
arrays equal bit for bit, the same lambdas, status, stop and summary; the streamed list keeps
only the dead-load state and the last ``keep`` steps in memory; indexing and slicing behave
as a list's; the automatic choice streams exactly when the History would not fit in a
quarter of the available memory.
"""

from __future__ import annotations

import numpy as np
import pytest

import masonry_dem as md
from masonry_dem.results import StepResult
from masonry_dem.solvers.incremental import StaticSettings, pushover
from masonry_dem.solvers.resources import should_stream, step_bytes
from masonry_dem.streamed_history import StreamedSteps

ARRAYS = ("q", "actions", "state", "utilisation", "flags")


def _wall() -> md.Model:
    wall = md.running_bond_wall(3, 5, 0.081, 0.210, 0.070, 20e3)
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        supports=[md.Support([base]), md.Support(md.select.column(wall, "left"), ["u1", "u3"])],
        loads=[md.SelfWeight(), md.WeightProportional(direction=(0, 0, 1))],
    )


def test_the_streamed_history_read_back_equals_the_one_in_memory(tmp_path):
    model = _wall()
    memory = pushover(model, StaticSettings(), stream=False)
    streamed = pushover(model, StaticSettings(), stream=tmp_path / "steps")
    assert isinstance(streamed.steps, StreamedSteps)
    assert isinstance(memory.steps, list)
    assert len(memory.steps) > 5
    assert len(streamed.steps) == len(memory.steps)
    assert len(list((tmp_path / "steps").glob("step_*.npz"))) == len(memory.steps)
    for a, b in zip(memory.steps, streamed.steps, strict=True):
        assert (a.step, a.load_factor, a.control_displacement, a.iterations) == (
            b.step,
            b.load_factor,
            b.control_displacement,
            b.iterations,
        )
        for name in ARRAYS:
            x, y = getattr(a, name), getattr(b, name)
            assert x.dtype == y.dtype and np.array_equal(x, y), name
    # read back from the files, not from what the list keeps in memory
    fresh = StreamedSteps.__new__(StreamedSteps)
    fresh.folder = tmp_path / "steps"
    middle = len(memory.steps) // 2
    again = StreamedSteps._read(fresh, middle)
    for name in ARRAYS:
        assert np.array_equal(getattr(again, name), getattr(memory.steps[middle], name))
    assert np.array_equal(streamed.load_factors, memory.load_factors)
    assert np.array_equal(streamed.control_displacements, memory.control_displacements)
    assert streamed.status == memory.status and streamed.stop == memory.stop
    keys = ("status", "stop", "steps", "lambda", "lambda_bracket", "iterations", "reason")
    s1, s2 = memory.summary(), streamed.summary()
    assert {k: s1[k] for k in keys} == {k: s2[k] for k in keys}
    assert s1["certificate"] == s2["certificate"]


def _step(i: int, n: int = 4, m: int = 3) -> StepResult:
    rng = np.random.default_rng(i)
    return StepResult(
        step=i,
        load_factor=0.1 * i,
        q=rng.normal(size=(n, 6)),
        actions=rng.normal(size=(m, 6)),
        state=rng.integers(0, 5, m).astype(np.int32),
        utilisation=rng.random(m),
        flags=None if i % 2 else rng.integers(0, 9, m).astype(np.int32),
        control_displacement=0.01 * i,
        iterations=i + 1,
    )


def test_the_streamed_list_keeps_the_first_and_the_last_steps_only(tmp_path):
    steps = StreamedSteps(tmp_path, keep=2)
    made = [_step(i) for i in range(7)]
    for st in made:
        steps.append(st)
    assert len(steps) == 7
    assert sorted(steps._recent) == [5, 6]
    assert steps[0] is made[0] and steps[-1] is made[6]
    assert steps[3] is not made[3]  # read back from its file
    assert np.array_equal(steps[3].q, made[3].q) and steps[3].flags is None
    assert np.array_equal(steps[2].flags, made[2].flags)
    assert [s.step for s in steps[2:5]] == [2, 3, 4]
    assert [s.step for s in steps] == list(range(7))
    assert steps.load_factors == [0.1 * i for i in range(7)]
    with pytest.raises(IndexError, match="step 7 of a History of 7 steps"):
        steps[7]
    with pytest.raises(ValueError, match="keep"):
        StreamedSteps(tmp_path, keep=0)


def test_a_temporary_folder_goes_with_the_list():
    steps = StreamedSteps()
    steps.append(_step(0))
    folder = steps.folder
    assert (folder / "step_000000.npz").is_file()
    del steps
    import gc

    gc.collect()
    assert not folder.exists()


def test_the_history_streams_when_it_would_not_fit_in_a_quarter_of_the_memory():
    from masonry_dem.solvers.resources import STEPS

    blocks, interfaces = 100_000, 300_000
    need = STEPS * step_bytes(blocks, interfaces)
    assert should_stream(blocks, interfaces, available=3.9 * need)
    assert not should_stream(blocks, interfaces, available=4.1 * need)
    assert not should_stream(1_000, 3_000, available=16e9)  # 10^3 blocks stay in memory
