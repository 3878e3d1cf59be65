"""Small models run their compiled kernels on one thread; the answer does not change."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import masonry_dem as md
from masonry_dem import _threads, jit


def test_a_small_model_runs_its_kernels_on_one_thread_and_restores_the_setting():
    before = numba.get_num_threads()
    with _threads.kernel_threads_for(_threads.SERIAL_BELOW - 1):
        assert numba.get_num_threads() == 1
    assert numba.get_num_threads() == before
    with _threads.kernel_threads_for(_threads.SERIAL_BELOW):
        assert numba.get_num_threads() == before


def test_the_setting_is_restored_when_the_analysis_raises():
    before = numba.get_num_threads()
    with pytest.raises(RuntimeError), _threads.kernel_threads_for(1):
        raise RuntimeError("a failed analysis")
    assert numba.get_num_threads() == before


def _wall():
    wall = md.running_bond_wall(3, 5, 0.081, 0.21, 0.07, 20e3)
    blocks, base = md.add_base(wall)
    return md.Model.build(
        blocks,
        md.InterfaceMaterial(kn=2.4e9, kt=1e9, friction=0.7),
        supports=[md.Support([base]), md.Support(md.select.column(wall, "left"), ["u1", "u3"])],
        loads=[md.SelfWeight(), md.WeightProportional((0.0, 0.0, 1.0))],
    )


def test_one_kernel_thread_gives_the_same_bits(monkeypatch):
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one core: nothing to compare")
    model = _wall()
    serial = md.pushover(model)
    monkeypatch.setattr(_threads, "SERIAL_BELOW", 0)  # every model on all threads
    monkeypatch.setattr(jit, "_PARALLEL_FROM", [0])  # with the parallel variants
    parallel = md.pushover(model)
    assert serial.collapse_multiplier == parallel.collapse_multiplier
    assert np.array_equal(serial.steps[-1].q, parallel.steps[-1].q)
    assert serial.iterations == parallel.iterations
