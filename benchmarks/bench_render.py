"""Rendering speed: a PNG of a 10^4-block wall, and an animation of 100 steps.

    python benchmarks/bench_render.py [--blocks 10000] [--steps 100] [--anim-blocks 1000]

Prints a table. "cold" runs ``masonry-dem render`` (or one ``render_step`` call) in a fresh process: Python
start-up, the imports and the OpenGL context included, what a user waits for; "warm" calls
``render_step`` again in this process. Writing the results folders is not timed. The load
average is printed: on a shared machine the seconds scale with it.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _machine import arguments, print_machine

from masonry_dem.export.writer import ResultsWriter
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.linear import solve_linear


def wall_results(folder: Path, n_blocks: int, n_steps: int) -> Model:
    """A square-ish running-bond wall of about ``n_blocks`` blocks; ``n_steps`` steps of a
    linear solution with damage spreading from the base."""
    side = max(2, int(round(np.sqrt(n_blocks))))
    blocks = running_bond_wall(side, side, a=0.1, b=0.2, s=0.1, unit_weight=20e3)
    blocks, base = add_base(blocks)
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2e9, kt=8e8, friction=0.6),
        supports=[Support(np.array([base]))],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name=f"bench {blocks.count} blocks",
    )
    lin = solve_linear(model)
    height = model.interfaces.centre[:, 1]
    rank = (height - height.min()) / (np.ptp(height) or 1.0)
    code = np.arange(model.interfaces.count) % 4 + 1
    writer = ResultsWriter(folder, model)
    hist = History(status="completed")
    for k in range(n_steps):
        frac = (k + 1) / n_steps
        step = StepResult(
            k,
            frac,
            lin.q * frac,
            lin.actions * frac,
            np.where(rank < frac * 0.6, code, 0).astype(np.int32),
            np.full(model.interfaces.count, frac),
        )
        hist.steps.append(step)
        writer(step)
    writer.finish(hist)
    return model


def main() -> None:
    ap = arguments(__doc__)
    ap.add_argument("--blocks", type=int, default=10_000)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--anim-blocks", type=int, default=1_000)
    args = ap.parse_args()
    print_machine()

    from masonry_dem.export import render

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        big = Path(tmp) / "big"
        model = wall_results(big, args.blocks, 1)
        nb, ni = model.blocks.count, model.interfaces.count

        t = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "masonry_dem.cli", "render", str(big), "--view", "oblique"],
            check=True,
            capture_output=True,
        )
        rows.append(
            (f"PNG 1200x900, {nb} blocks / {ni} interfaces, cold CLI", time.perf_counter() - t)
        )
        t = time.perf_counter()
        code = (
            "from masonry_dem.export.render import render_step; "
            f"render_step({str(big)!r}, view='front', out={str(Path(tmp) / 'lib.png')!r})"
        )
        subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
        rows.append((f"PNG 1200x900, {nb} blocks, cold library call", time.perf_counter() - t))
        t = time.perf_counter()
        subprocess.run(
            [
                sys.executable,
                "-c",
                "import masonry_dem.export.scene as s; s.pyvista_offscreen().Plotter",
            ],
            check=True,
            capture_output=True,
        )
        rows.append(
            ("  of which: Python + import masonry_dem, pyvista, vtk", time.perf_counter() - t)
        )
        render.render_step(big, view="front", out=Path(tmp) / "warmup.png")
        for view in ("oblique", "front"):
            t = time.perf_counter()
            render.render_step(big, view=view, out=Path(tmp) / f"{view}.png")
            rows.append((f"PNG 1200x900, {nb} blocks, warm, {view}", time.perf_counter() - t))

        for n_blocks, size in ((args.anim_blocks, (800, 600)), (args.blocks, (800, 600))):
            anim = Path(tmp) / f"anim{n_blocks}"
            m = wall_results(anim, n_blocks, args.steps)
            t = time.perf_counter()
            out = render.render_animation(anim, window_size=size)
            dt = time.perf_counter() - t
            rows.append(
                (
                    f"GIF {size[0]}x{size[1]}, {args.steps} steps, {m.blocks.count} blocks "
                    f"({out.stat().st_size / 1e6:.1f} MB)",
                    dt,
                )
            )

    import os

    rows.append(("load average (1 min) after the runs", os.getloadavg()[0]))
    width = max(len(r[0]) for r in rows)
    print(f"{'case':<{width}}  seconds")
    for name, sec in rows:
        print(f"{name:<{width}}  {sec:7.2f}")


if __name__ == "__main__":
    main()
