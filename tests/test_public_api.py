"""The public namespace: every exported name exists, heavy names load on first use, and
importing the package changes no environment variable (the entry points set the thread wait
policy)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import masonry_dem as md

SRC = Path(md.__file__).resolve().parents[1]


def _python(code: str, **env: str) -> str:
    base = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    base.update(env, PYTHONPATH=str(SRC))
    out = subprocess.run(
        [sys.executable, "-c", code], env=base, capture_output=True, text=True, check=True
    )
    return out.stdout.strip()


def test_every_exported_name_resolves_and_no_internal_leaks():
    for name in md.__all__:
        assert getattr(md, name) is not None, name
    assert not {"replace", "os", "import_module"} & set(md.__all__)
    # the names the README and docs use
    for name in ("History", "relax", "load_case", "collapse_mode", "limit_analysis", "Status"):
        assert name in md.__all__
    from masonry_dem.solvers.limit_analysis import limit_analysis

    assert md.limit_analysis is limit_analysis


def test_the_package_ships_its_type_information():
    assert (Path(md.__file__).parent / "py.typed").is_file()


def test_importing_the_package_sets_no_thread_policy_and_the_cli_does():
    assert _python("import os, masonry_dem; print(os.environ.get('OMP_WAIT_POLICY'))") == "None"
    code = (
        "import os, contextlib, io\n"
        "from masonry_dem.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()): main([])\n"
        "print(os.environ.get('OMP_WAIT_POLICY'))"
    )
    assert _python(code) == "PASSIVE"
    # a value the user set is kept
    assert _python(code, OMP_WAIT_POLICY="ACTIVE") == "ACTIVE"


def test_the_thread_policy_helper_refuses_an_unknown_policy_by_name():
    with pytest.raises(ValueError, match="policy must be 'PASSIVE' or 'ACTIVE', got 'SPIN'"):
        md.set_thread_wait_policy("SPIN")  # type: ignore[arg-type]


def test_status_is_an_enum_that_compares_and_serialises_as_its_text():
    history = md.History()
    assert history.status is md.Status.RUNNING
    history.end(md.Status.COMPLETED, md.StopReason.MAX_STEPS, "done")
    assert history.status == "completed" and isinstance(history.status, md.Status)
    summary = json.loads(json.dumps(history.summary()))
    assert summary["status"] == "completed" and summary["stop"] == "max_steps reached"


@pytest.mark.parametrize(
    "build",
    [
        lambda **k: md.running_bond_wall(3, 4, unit_weight=20e3, **k),
        lambda **k: md.running_bond_wall_of_size(0.9, 0.4, unit_weight=20e3, **k),
        lambda **k: md.stack_bond_column(3, unit_weight=20e3, **k),
        lambda **k: md.single_block(unit_weight=20e3, **k),
        lambda **k: md.l_wall(4, 3, unit_weight=20e3, **k),
        lambda **k: md.box_wall(4, 3, unit_weight=20e3, **k),
    ],
)
def test_builders_take_descriptive_names_or_the_papers_letters(build):
    named = build(block_height=0.081, block_length=0.21, thickness=0.07)
    letters = build(a=0.081, b=0.21, s=0.07)
    assert np.array_equal(named.centres, letters.centres)
    assert np.array_equal(named.sizes, letters.sizes)
    with pytest.raises(ValueError, match="give block_height or a .*not both"):
        build(block_height=0.081, a=0.081, block_length=0.21, thickness=0.07)
    with pytest.raises(ValueError, match="thickness is required"):
        build(block_height=0.081, block_length=0.21)


def test_the_thread_policy_set_after_the_threads_started_says_it_comes_too_late(
    monkeypatch, caplog
):
    import numba

    numba.get_num_threads()  # starts the threading layer, as a first analysis does
    monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    with caplog.at_level("WARNING", logger="masonry_dem._threads"):
        assert md.set_thread_wait_policy() == "PASSIVE"
    assert "after the kernels' threads started" in caplog.text


def test_heavy_names_load_on_first_use_and_once():
    """Importing the package leaves limit analysis, dynamic relaxation and the case files
    unloaded; the first access imports the defining module and keeps the name."""
    code = (
        "import sys, masonry_dem as md\n"
        "heavy = ('masonry_dem.solvers.limit_analysis', 'masonry_dem.solvers.dynamic_relaxation',"
        " 'masonry_dem.cases.casefile')\n"
        "print(any(m in sys.modules for m in heavy))\n"
        "f = md.limit_analysis\n"
        "print('masonry_dem.solvers.limit_analysis' in sys.modules, 'limit_analysis' in vars(md))"
    )
    assert _python(code).split("\n") == ["False", "True True"]


def test_the_lazy_names_of_the_static_solver_package_are_its_modules_names():
    import masonry_dem.solvers.static as static
    from masonry_dem.solvers.static import certificate, settings, solver

    assert static.pushover is solver.pushover and static.StaticSettings is settings.StaticSettings
    assert static.certify is certificate.certify
    for package in (md, static):
        with pytest.raises(AttributeError, match=f"module '{package.__name__}' has no attribute"):
            package.no_such_name  # noqa: B018
