"""Results folders with known damage patterns for the render and ParaView tests.

The displacements come from a linear solve (scaled by lambda per step) and the interface
states are assigned by position, so the share of each damage colour on screen is known:
the wall is cut into five vertical bands of equal width and, at the last step, the interfaces
whose centre lies in band k carry state k (0 elastic ... 4 detached). Step j (0-based) shows
the bands k <= j damaged and the others elastic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from masonry_dem.export.writer import ResultsWriter
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.linear import solve_linear

N_BANDS = 5


def build_model(nx: int = 10, ny: int = 12) -> Model:
    blocks = running_bond_wall(nx, ny, a=0.1, b=0.2, s=0.1, unit_weight=20e3)
    blocks, base = add_base(blocks)
    return Model.build(
        blocks,
        InterfaceMaterial(kn=2e9, kt=8e8, friction=0.6),
        supports=[Support(np.array([base]))],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name="test wall",
    )


def band_of(model: Model) -> np.ndarray:
    """(m,) band index 0..4 of every interface (by its centre along e1)."""
    x = model.interfaces.centre[:, 0]
    lo, hi = model.blocks.lower[:, 0].min(), model.blocks.upper[:, 0].max()
    return np.clip(((x - lo) / (hi - lo) * N_BANDS).astype(int), 0, N_BANDS - 1)


def states_at(model: Model, step: int) -> np.ndarray:
    band = band_of(model)
    return np.where(band <= step, band, 0).astype(np.int32)


def write_results(
    folder: Path, model: Model, n_steps: int = 5, lam_max: float = 0.5, amplify: float = 1.0
) -> History:
    lin = solve_linear(model, 1.0)
    hist = History()
    writer = ResultsWriter(folder, model)
    for k in range(n_steps):
        lam = lam_max * (k + 1) / n_steps
        step = StepResult(
            step=k,
            load_factor=lam,
            q=lin.q * lam * amplify,
            actions=lin.actions * lam,
            state=states_at(model, k),
            utilisation=np.clip(np.abs(lin.actions[:, 2]) * lam / 500.0, 0, 1),
            control_displacement=float(lin.q[:, 2].max() * lam * amplify),
        )
        hist.steps.append(step)
        writer(step)
    hist.status = "completed"
    writer.finish(hist)
    return hist
