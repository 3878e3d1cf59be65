"""A Ctrl-C while the background writer finishes the steps the solver has handed over, and
while ``--overwrite`` clears the previous run.

The writer may lag the solver by hundreds of steps (a run of 1 000 short steps of a wall
pushed downwards, where no collapse exists, wrote for seconds after its last step); a SIGINT
then came while ``ResultsWriter.__exit__`` waited for those writes, outside the solver's
signal handling, and left ``summary.json`` saying ``running`` for a process that had exited
with code 130 (found by the new-user sweep, docs/new_user_sweep.md)."""

from __future__ import annotations

import json
import os
import signal

import pytest

from masonry_dem.export import results_folder as rf
from masonry_dem.export.analyses import pushover
from masonry_dem.export.writer import ResultsWriter
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.solvers.incremental import StaticSettings


def _wall_model() -> Model:
    wall = running_bond_wall(2, 3, 0.081, 0.21, 0.07, 20e3)
    blocks, base = add_base(wall)
    return Model.build(
        blocks,
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        [Support([base])],
        [SelfWeight(), WeightProportional((0, 0, 1))],
    )


def test_a_ctrl_c_during_the_last_writes_is_recorded_as_interrupted(tmp_path, monkeypatch):
    model = _wall_model()
    history = pushover(model, StaticSettings(max_steps=4))
    writer = ResultsWriter(tmp_path / "out", model, background=True)
    flush = writer.flush

    def flush_then_ctrl_c() -> None:
        flush()  # every step handed over is on disk, then the signal arrives
        raise KeyboardInterrupt

    monkeypatch.setattr(writer, "flush", flush_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt), writer:
        for step in history.steps:
            writer(step)
    summary = json.loads((tmp_path / "out" / rf.SUMMARY).read_text())
    assert summary["status"] == rf.INTERRUPTED
    assert summary["steps"] == summary["steps_written"] == len(history.steps)
    assert (tmp_path / "out" / rf.PUSHOVER).is_file()
    assert rf.state(tmp_path / "out").kind != "unfinished"


def test_a_ctrl_c_while_overwrite_clears_the_old_run_leaves_no_half_folder(tmp_path, monkeypatch):
    """``run --overwrite`` interrupted while it removed the previous run's files left part
    of them (463 step files of 2 002) and no summary.json at all. The removal and the new
    summary now finish first; the signal then stops the run, and the summary says it was
    interrupted before its first step."""
    model = _wall_model()
    out = tmp_path / "out"
    pushover(model, StaticSettings(max_steps=3), out=out)
    assert len(list((out / "steps").glob("*.vtu"))) > 0
    remove = rf.remove_own_files

    def remove_after_ctrl_c(folder):
        os.kill(os.getpid(), signal.SIGINT)  # arrives while the files go
        return remove(folder)

    monkeypatch.setattr(rf, "remove_own_files", remove_after_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        ResultsWriter(out, model, overwrite=True)
    assert not list((out / "steps").glob("*.vtu"))
    assert json.loads((out / rf.SUMMARY).read_text())["status"] == "interrupted"
    assert rf.state(out).kind == "interrupted"
