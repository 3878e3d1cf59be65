"""Load control against displacement control on one model: the same peak, or which branch
the displacement-controlled path took, at which lambda, and why.

Both followers trace equilibria of the same discrete problem, but a path of an
elastic-perfectly-plastic assembly can branch where joints change state: driven by one DOF,
the wall may unload other joints and settle on a plateau that the load-controlled path (which
raises every load together) never visits. :func:`compare_controls` runs both with the same
settings, monitors the controlled DOF on both curves, and reports the peaks and, where they
differ by more than ``tolerance``, where the curves part (the first displacement at which
lambda differs by more than ``tolerance`` x the higher peak) and how many joints are then in
different states.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from masonry_dem.model import Model
from masonry_dem.results import History
from masonry_dem.solvers.static.settings import DisplacementControl, StaticSettings
from masonry_dem.solvers.static.solver import pushover


@dataclass(frozen=True)
class BranchComparison:
    """Peaks of both controls and, when they differ, where and why."""

    load_peak: float | None  # None: load control found no collapse
    displacement_peak: float
    relative_difference: float  # |displacement - load| / load
    same_peak: bool
    # "same peak", "displacement control stopped before the peak", "another branch"
    verdict: str
    parting_lambda: float | None  # lambda where the curves part (another branch)
    parting_displacement: float | None
    differing_joints: int  # joints in different states where the curves part
    reason: str
    load: History
    displacement: History


def compare_controls(
    model: Model,
    control: DisplacementControl,
    settings: StaticSettings | None = None,
    tolerance: float = 0.01,
) -> BranchComparison:
    """Run load control (monitoring ``control``'s DOF) and displacement control; compare."""
    settings = settings or StaticSettings()
    monitor = (control.block, control.dof)
    load = pushover(model, settings, monitor=monitor)
    disp = pushover(model, settings, control=control)
    load_peak = load.collapse_multiplier
    lam_d = disp.load_factors
    u_d = disp.control_displacements
    disp_peak = float(lam_d.max())
    reference = load_peak if load_peak is not None else float(load.load_factors.max())
    difference = abs(disp_peak - reference) / max(abs(reference), 1e-300)
    if difference <= tolerance:
        return BranchComparison(
            load_peak, disp_peak, difference, True, "same peak", None, None, 0,
            f"the same peak within {tolerance:.0%}: load {reference:.6g}, "
            f"displacement {disp_peak:.6g} ({difference:.2%})",
            load, disp,
        )  # fmt: skip
    falling = int(np.argmax(lam_d)) < lam_d.size - 1 and lam_d[-1] < disp_peak
    if disp_peak < reference and not falling:
        return BranchComparison(
            load_peak, disp_peak, difference, False,
            "displacement control stopped before the peak", None, None, 0,
            f"displacement control ended ({disp.stop}: {disp.reason}) at lambda "
            f"{lam_d[-1]:.6g} on a rising curve, below the load-controlled peak "
            f"{reference:.6g}: its target or budget ended the path before the peak",
            load, disp,
        )  # fmt: skip
    # another branch: where the two curves (lambda against the controlled DOF) part
    u_l = load.control_displacements
    lam_l = load.load_factors
    order = np.argsort(u_l, kind="stable")
    inside = (u_d >= u_l.min()) & (u_d <= u_l.max())
    on_load = np.interp(u_d, u_l[order], lam_l[order])
    parted = np.flatnonzero(
        inside & (np.abs(lam_d - on_load) > tolerance * max(disp_peak, reference))
    )
    if parted.size:
        k = int(parted[0])
        parting_u, parting_lam = float(u_d[k]), float(lam_d[k])
    else:  # the displacement-controlled path leaves the load-controlled range
        k = int(np.flatnonzero(inside)[-1]) if inside.any() else 0
        parting_u, parting_lam = float(u_d[k]), float(lam_d[k])
    j = int(np.argmin(np.abs(u_l - parting_u)))
    differing = int(np.count_nonzero(disp.steps[k].state != load.steps[j].state))
    return BranchComparison(
        load_peak, disp_peak, difference, False, "another branch", parting_lam, parting_u,
        differing,
        f"another branch: the curves part at lambda {parting_lam:.6g} (controlled "
        f"displacement {parting_u:.4g}), where {differing} joints are in different states; "
        f"displacement control peaks at {disp_peak:.6g}, load control at {reference:.6g} "
        f"({difference:.1%})",
        load, disp,
    )  # fmt: skip
