"""Building the package also compiles its numba kernels (masonry_dem.jit), so that the first
analysis after ``pip install .`` loads them instead of compiling them. Everything else is in
pyproject.toml."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

# the kernels every analysis of a wall below 300 interfaces uses (their serial variants), into
# numba's cache in a temporary folder, then copied into the package. The parallel variants
# (larger walls) and the kernels most analyses never call would more than double the build's
# time: they compile on first use, announced, or with `masonry-dem warmup`.
_COMPILE = """
import sys
from pathlib import Path
from masonry_dem import jit
from masonry_dem.solvers.warmup import compile_kernels
compile_kernels(parallel=False)
print(jit.copy_compiled(Path(sys.argv[1])))
"""


class BuildWithKernels(build_py):
    """build_py, then the kernels compiled into the built package (not for an editable
    install, whose kernels compile into numba's cache on first use). A failure leaves the
    package without them: it works as before, compiling on first use."""

    def run(self) -> None:
        super().run()
        if self.editable_mode:
            return
        lib = Path(self.build_lib).resolve()
        target = lib / "masonry_dem" / "_compiled"
        shutil.rmtree(target, ignore_errors=True)  # a former build's, in a reused build folder
        with tempfile.TemporaryDirectory() as cache:
            # the build environment's packages (pip's build isolation) stay on the path; no
            # bytecode files written into the package built
            path = os.pathsep.join(p for p in (str(lib), os.environ.get("PYTHONPATH")) if p)
            env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=path)
            env["PYTHONDONTWRITEBYTECODE"] = "1"
            done = subprocess.run(
                [sys.executable, "-c", _COMPILE, str(target)],
                env=env,
                capture_output=True,
                text=True,
                check=False,
            )
        if done.returncode == 0:
            print(f"masonry_dem: {done.stdout.strip()} kernel files compiled into {target}")
        else:
            tail = done.stderr.strip().splitlines()[-1:]
            print(
                f"masonry_dem: kernels not compiled at build ({tail}); they compile on first use",
                file=sys.stderr,
            )


setup(cmdclass={"build_py": BuildWithKernels})
