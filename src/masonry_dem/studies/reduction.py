"""The in-plane reduction study: in-plane scenes solved with the full 6-DOF model and with the
3-DOF in-plane model (lambda, time, DOFs), and what the never-assembled fixed-block DOFs and the
closed-form interface domain save on validation cases."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from masonry_dem.model import Model
from masonry_dem.studies.runs import load_study_case
from masonry_dem.studies.text import fmt

log = logging.getLogger(__name__)

#: (scene, blocks along, courses, (a, b, s) [m], unit weight [N/m^3], (kn, kt, mu, ft))
SCENES = (
    ("shear wall 6x13", 6, 13, (0.081, 0.210, 0.070), 20e3, (2.4e9, 1.0e9, 0.7, 0.0)),
    ("shear wall 12x26", 12, 26, (0.081, 0.210, 0.070), 20e3, (2.4e9, 1.0e9, 0.7, 0.0)),
    ("mortar wall 20x40", 20, 40, (0.046, 0.122, 0.053), 18e3, (25e9, 105e9, 0.57, 0.35e6)),
)


def in_plane_scenes() -> list[tuple[str, Model]]:
    """Running-bond shear walls on a rigid base pushed along e1 by lambda x their weight (the
    Orduna-Lourenco block and a Chee Liang-sized brick wall)."""
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import InterfaceMaterial, SelfWeight, Support, WeightProportional

    out = []
    for name, nx, nc, dims, gamma, mat in SCENES:
        wall = running_bond_wall(nx, nc, *dims, gamma)
        blocks, base = add_base(wall)
        model = Model.build(
            blocks,
            InterfaceMaterial(*mat),
            [Support(np.array([base]))],
            [SelfWeight(), WeightProportional((1.0, 0.0, 0.0))],
            name=name,
        )
        out.append((name, model))
    return out


def reduction_study(repeats: int = 3) -> dict[str, Any]:
    """Both reductions measured (best of ``repeats`` timings)."""
    from masonry_dem.solvers import reduction

    scenes = []
    for name, model in in_plane_scenes():
        r = reduction.measure_reduction(model, repeats=repeats)
        r["scene"] = name
        scenes.append(r)
    fixed = []
    for name in ("S15", "14-15"):
        try:
            case = load_study_case(name)
        except (ImportError, ValueError) as exc:
            log.warning("case %s unavailable: %s", name, exc)
            continue
        f = reduction.measure_fixed_dofs(case.model, repeats=repeats)
        f["case"] = name
        s = reduction.measure_strength_model(case.model, repeats=repeats)
        fixed.append({**f, "strength": s})
    return {"in_plane": scenes, "fixed_dofs": fixed}


def reduction_text(res: dict[str, Any]) -> str:
    lines = ["in-plane scenes: full 6-DOF model against the 3-DOF (u1, u2, w3) model (static)"]
    lines.append(
        f"  {'scene':<18} {'free DOFs':>11} {'nnz K':>13} {'lambda 6-DOF':>13} "
        f"{'lambda 3-DOF':>13} {'rel diff':>9} {'t6 [s]':>7} {'t3 [s]':>7} {'t6/t3':>6}"
    )
    for r in res["in_plane"]:
        f, p = r["full"], r["in_plane"]
        lines.append(
            f"  {r['scene']:<18} {f['free_dofs']:>5}/{p['free_dofs']:<5} "
            f"{f['nnz_K']:>6}/{p['nnz_K']:<6} {fmt(f['lambda'], '13.6g')} "
            f"{fmt(p['lambda'], '13.6g')} {fmt(r['lambda_relative_difference'], '9.1e')} "
            f"{f['seconds']:7.2f} {p['seconds']:7.2f} {r['time_ratio']:6.2f}"
        )
    if res["fixed_dofs"]:
        lines.append("fixed-block DOFs never assembled, and the closed-form interface domain:")
        for f in res["fixed_dofs"]:
            s = f["strength"]
            lines.append(
                f"  {f['case']:<8} DOFs {f['dofs_all']} -> {f['dofs_free']} free "
                f"(nnz K {f['nnz_K_all']} -> {f['nnz_K_free']}); factorisation "
                f"{1e3 * f['seconds_factor_all_penalty']:.2f} ms (all DOFs + penalty) -> "
                f"{1e3 * f['seconds_factor_free']:.2f} ms ({f['time_ratio']:.1f}x); "
                f"law for {s['interfaces']} interfaces: closed form "
                f"{1e3 * s['seconds_closed_form']:.2f} ms, {s['springs_per_interface']}-spring "
                f"model {1e3 * s['seconds_spring_model']:.1f} ms ({s['time_ratio']:.0f}x)"
            )
    return "\n".join(lines)
