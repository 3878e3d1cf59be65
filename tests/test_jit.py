"""The compiled kernels: serial and parallel variants give the same bits, their disk cache is
keyed on every kernel file, and a compilation is announced before it happens."""

from __future__ import annotations

import hashlib
import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from masonry_dem import jit
from masonry_dem.constitutive.law import InterfaceLaw, _unsigned
from masonry_dem.constitutive.law_kernels import forces
from masonry_dem.constitutive.states import (
    FLAG_DETACHED,
    FLAG_ROCKING_1,
    FLAG_SHEAR_TORSION,
    STATE_DETACHED,
    STATE_NAMES,
    STATE_OF_FLAGS,
    STATE_SLIDING_ROCKING,
    JointFlag,
    JointState,
)


def test_one_definition_of_the_joint_states():
    """The law's flag table, the export's names and the renderer's colours agree."""
    from masonry_dem.export.render import STATE_COLOURS
    from masonry_dem.results import STATE_NAMES as RESULT_STATE_NAMES

    assert [s.label for s in JointState] == list(STATE_NAMES) and len(STATE_COLOURS) == 5
    assert RESULT_STATE_NAMES is STATE_NAMES
    assert STATE_OF_FLAGS[FLAG_SHEAR_TORSION | FLAG_ROCKING_1] == JointState.SLIDING_ROCKING
    assert STATE_SLIDING_ROCKING == JointState.SLIDING_ROCKING
    assert STATE_OF_FLAGS[JointFlag.DETACHED] == STATE_DETACHED
    # a flag set with the detached bit is detached whatever else it holds
    assert (STATE_OF_FLAGS[np.arange(16) | FLAG_DETACHED] == JointState.DETACHED).all()


def test_the_two_variants_give_the_same_bits():
    """Each row of the parallel loop is worked out alone: the parallel variant of the law's
    forces (all rows yielding in some way, half of them with a cohesion beyond mu ft) is the
    serial one, bit for bit."""
    rng = np.random.default_rng(3)
    m = 64
    kbar = np.tile([1e9, 1e9, 2e9, 1e6, 2e6, 5e5], (m, 1))
    law = InterfaceLaw(
        kbar, rng.uniform(0.1, 0.4, m), rng.uniform(0.1, 0.3, m), np.full(m, 0.6),
        np.where(rng.random(m) < 0.5, 0.0, 500.0), np.full(m, 1.5),
    )  # fmt: skip
    n = 40
    from scipy import sparse

    H = sparse.random(6 * m, n, density=0.1, random_state=4, format="csr") * 1e-6
    H_T = H.T.tocsr()
    x = rng.normal(size=n)
    dom = law._domain
    args = (
        x, _unsigned(H.indptr), _unsigned(H.indices), H.data, law.kbar, np.zeros((m, 6)),
        np.zeros(m, dtype=bool), np.ascontiguousarray(law.tensile_force),
        np.where(rng.random(m) < 0.5, 0.0, 100.0), *dom.kernel_arrays,
        dom.row_constants, True, True, _unsigned(H_T.indptr), _unsigned(H_T.indices),
        H_T.data, n,
    )  # fmt: skip
    one = forces.serial(*args)
    two = forces.parallel(*args)
    assert one[4].any()  # some joints yield
    for a, b in zip(one, two, strict=True):
        assert np.asarray(a).tobytes() == np.asarray(b).tobytes()


def test_the_cache_key_holds_every_kernel_file():
    """A change of a callee's file (the check's rows) renews the law kernels' cache."""
    key = forces.serial._cache._index_key(
        forces.serial.signatures[0], forces.serial.targetctx.codegen()
    )
    assert key[-1] == jit._sources_hash()
    assert {p.name for p in jit.KERNEL_SOURCES} >= {"check_kernels.py", "law_kernels.py"}
    # a cache file is fresh by these hashes and its own file's (the callees there), not by
    # the file's time, which an installation changes
    from masonry_dem.solvers.static import problem

    own = hashlib.sha256(Path(problem.__file__).read_bytes()).hexdigest()
    assert problem._assemble_tangent.serial._cache._stamp == (jit._sources_hash(), own)


def test_a_compilation_is_announced_before_it_happens(monkeypatch, caplog):
    monkeypatch.setattr(jit, "_cached", lambda disp: False)
    with caplog.at_level(logging.WARNING, logger="masonry_dem.jit"):
        seconds = jit.announce_compilation(10)
    assert seconds == pytest.approx(jit.COMPILE_SECONDS["serial"])
    assert "compiling kernels, once per machine, about" in caplog.text
    assert "(parallel)" not in caplog.text  # a small wall compiles no parallel variant
    monkeypatch.setattr(jit, "_cached", lambda disp: True)
    assert jit.announce_compilation(10**6) == 0.0


def test_warmup_command_leaves_nothing_to_compile(capsys):
    """``masonry-dem warmup`` fills the cache: afterwards no serial kernel is pending."""
    from masonry_dem.cli import main

    assert main(["warmup", "--variant", "serial", "--processes", "1"]) == 0
    assert "serial kernels:" in capsys.readouterr().out
    assert jit.compile_pending(parallel=False, lazy=True) == []


def test_a_lazy_kernel_is_announced_on_its_first_call(monkeypatch, caplog):
    """The forward difference, which most analyses never call, is compiled on its first call
    (not before every analysis), and says so then, once per process and variant."""
    from masonry_dem.constitutive.law_kernels import fd_tangent_rows

    monkeypatch.setattr(jit, "_cached", lambda disp: False)
    assert not any("fd_tangent_rows" in p for p in jit.compile_pending(parallel=True))
    assert any("fd_tangent_rows" in p for p in jit.compile_pending(parallel=True, lazy=True))
    announced = set(fd_tangent_rows._announced)
    fd_tangent_rows._announced.clear()
    with caplog.at_level(logging.WARNING, logger="masonry_dem.jit"):
        assert fd_tangent_rows.for_rows(10) is fd_tangent_rows.serial
        fd_tangent_rows.for_rows(10)
    fd_tangent_rows._announced.update(announced)
    assert caplog.text.count("compiling kernel fd_tangent_rows (serial), once per machine") == 1


def test_the_warm_up_compiles_the_zero_capacity_reduction():
    """Newton's joint tangents pass through a compiled reduction of the joints of no strength
    at zero compression (``problem._reduce_zero_capacity``); the warm-up's tangent group builds
    them the same way, so that kernel is compiled (or loaded) before the analysis, not on its
    first Newton iteration. A fresh interpreter: in this one other tests may have called it."""
    code = (
        "from masonry_dem.solvers.warmup import _run_group; "
        "from masonry_dem.solvers.static import problem; "
        "_run_group('tangent', False); "
        "print(len(problem._reduce_zero_capacity.serial.signatures))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=600
    )
    assert int(out.stdout.split()[-1]) >= 1


def test_kernels_compiled_at_build_are_loaded_not_compiled(tmp_path):
    """What setup.py does: the cache files of compiled kernels copied into a folder
    (``jit.copy_compiled``) are found there by a process whose numba cache is empty, where
    the package is installed elsewhere and its files have other times: it loads the kernel
    and compiles nothing."""
    from masonry_dem.constitutive.energy_return import row_constants

    row_constants.serial(np.ones(2), np.ones(2), np.full(2, 1.5), np.ones(2))
    shipped = tmp_path / "compiled"
    assert jit.copy_compiled(shipped) >= 2  # at least this kernel's index and code
    code = (
        "import sys; from pathlib import Path; import numpy as np; "
        "from masonry_dem import jit; jit.INSTALLED = Path(sys.argv[1]); "
        "from masonry_dem.constitutive.energy_return import row_constants as k; "
        "cached = jit._cached(k.serial); "
        "k.serial(np.ones(2), np.ones(2), np.full(2, 1.5), np.ones(2)); "
        "print(cached, sum(k.serial.stats.cache_hits.values()), "
        "sum(k.serial.stats.cache_misses.values()))"
    )
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "empty"))
    out = subprocess.run(
        [sys.executable, "-c", code, str(shipped)],
        capture_output=True, text=True, check=True, timeout=600, env=env,
    )  # fmt: skip
    assert out.stdout.split() == ["True", "1", "0"]
