"""VTU meshes of one analysis step, written with meshio.

blocks: one hexahedron per block at its undeformed position (8 own points per block so each
block's rigid motion is exact), point data ``displacement``; cell data ``block_id``,
``translation``, ``rotation``, ``fixed`` (every DOF held), ``restrained`` (which DOFs a support
holds, u1 u2 u3 w1 w2 w3), ``live_load`` (the live force on the block at lambda = 1, N).
Warp By Vector on ``displacement`` shows the motion at any scale.

interfaces: one quad per interface at its mid-plane; point data ``displacement`` (mean of the
two blocks' motion there); cell data ``interface_id``, ``block_i``, ``block_j``,
``normal_axis``, ``area``, ``actions`` (local [f1, f2, fn, m1, m2, m3]), ``normal_force``,
``shear_force`` (|f1, f2|), ``bending_moment`` (|m1, m2|), ``torsion``, ``state`` (:class:`~masonry_dem.constitutive.states.JointState`: 0 elastic,
1 sliding, 2 rocking, 3 sliding and rocking, 4 detached), ``flags``, ``utilisation``.

mechanism (``mechanism_blocks.vtu``, ``mechanism_interfaces.vtu``, once per run that ends in
collapse): the same meshes with the collapse mode as ``displacement`` (largest translation 1)
and ``joint_motion``, the relative motion across each joint in that mode over its largest
value: the crack pattern of the mechanism, which the states do not show (an unloaded dry head
joint is "detached" from the first step). A limit analysis's mechanism adds
``utilisation_capped`` (``export.limit_results``: its utilisation is capped, never inf).

Every file carries field data ``lambda`` and ``step`` (of the mechanism: the collapse step).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np

from masonry_dem.export.results_folder import MECHANISM_FILES, STEPS, write_atomic
from masonry_dem.model import Model
from masonry_dem.results import StepResult


def rigid_motion(q: np.ndarray, centres: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Displacement u + w x (p - c) of points (k, p, 3) of blocks with DOFs q (k, 6)."""
    arm = points - centres[:, None, :]
    return q[:, None, :3] + np.cross(q[:, None, 3:], arm)


def blocks_mesh(model: Model, step: StepResult) -> meshio.Mesh:
    blocks = model.blocks
    corners = blocks.corner_points()  # (n, 8, 3)
    disp = rigid_motion(step.q, blocks.centres, corners)
    n = blocks.count
    cells = np.arange(8 * n, dtype=np.int64).reshape(n, 8)
    return meshio.Mesh(
        corners.reshape(-1, 3),
        [("hexahedron", cells)],
        point_data={"displacement": disp.reshape(-1, 3)},
        cell_data={
            "block_id": [np.arange(n, dtype=np.int32)],
            "translation": [np.ascontiguousarray(step.q[:, :3])],
            "rotation": [np.ascontiguousarray(step.q[:, 3:])],
            "fixed": [model.fixed.all(axis=1).astype(np.int32)],
            # which of u1 u2 u3 w1 w2 w3 a support holds (1), and the live load at
            # lambda = 1 (force at the centre, N): the pictures' support marks and load arrow
            "restrained": [model.fixed.astype(np.int32)],
            "live_load": [np.ascontiguousarray(model.live[:, :3])],
        },
    )


def _interface_corner_motion(model: Model, q: np.ndarray):
    """Corners (m, 4, 3) of the interfaces and the motion there of block i and of block j."""
    its = model.interfaces
    corners = its.corner_points()
    centres = model.blocks.centres
    d_i = rigid_motion(q[its.block_i], centres[its.block_i], corners)
    d_j = rigid_motion(q[its.block_j], centres[its.block_j], corners)
    return corners, d_i, d_j


def interfaces_mesh(model: Model, step: StepResult) -> meshio.Mesh:
    its = model.interfaces
    m = its.count
    corners, d_i, d_j = _interface_corner_motion(model, step.q)
    a = step.actions
    flags = step.flags if step.flags is not None else np.zeros(m, dtype=np.int32)
    return meshio.Mesh(
        corners.reshape(-1, 3),
        [("quad", np.arange(4 * m, dtype=np.int64).reshape(m, 4))],
        point_data={"displacement": (0.5 * (d_i + d_j)).reshape(-1, 3)},
        cell_data={
            "interface_id": [np.arange(m, dtype=np.int32)],
            "block_i": [its.block_i.astype(np.int32)],
            "block_j": [its.block_j.astype(np.int32)],
            "normal_axis": [its.axis.astype(np.int32)],
            "area": [its.area],
            "actions": [np.ascontiguousarray(a)],
            "normal_force": [a[:, 2].copy()],
            "shear_force": [np.hypot(a[:, 0], a[:, 1])],
            "bending_moment": [np.hypot(a[:, 3], a[:, 4])],
            "torsion": [a[:, 5].copy()],
            "state": [np.asarray(step.state, dtype=np.int32)],
            "flags": [np.asarray(flags, dtype=np.int32)],
            "utilisation": [np.asarray(step.utilisation, dtype=float)],
        },
    )


def write_step_vtu(folder: Path, model: Model, step: StepResult) -> tuple[str, str]:
    """Write ``steps/blocks_NNNN.vtu`` and ``steps/interfaces_NNNN.vtu``; returns both
    paths relative to ``folder``."""
    sub = Path(folder) / STEPS
    sub.mkdir(parents=True, exist_ok=True)
    names = (f"{STEPS}/blocks_{step.step:04d}.vtu", f"{STEPS}/interfaces_{step.step:04d}.vtu")
    fields = step_fields(step)
    _write_vtu(Path(folder) / names[0], blocks_mesh(model, step), fields)
    if model.interfaces.count:
        _write_vtu(Path(folder) / names[1], interfaces_mesh(model, step), fields)
    return names


def step_fields(step: StepResult) -> dict[str, np.ndarray]:
    """The field data of a step's meshes: ``lambda`` and ``step``, each one value, so that a
    viewer shows them as two named quantities (a PVD's time is lambda only while lambda
    rises, and the step number after)."""
    return {
        "lambda": np.array([float(step.load_factor)]),
        "step": np.array([int(step.step)], dtype=np.int64),
    }


def _field_data_xml(fields: dict[str, np.ndarray]) -> bytes:
    arrays = "".join(
        f'<DataArray type="{"Int64" if v.dtype.kind in "iu" else "Float64"}" Name="{k}" '
        f'NumberOfTuples="{v.size}" format="ascii">{" ".join(repr(x) for x in v.tolist())}'
        "</DataArray>"
        for k, v in fields.items()
    )
    return f"<FieldData>{arrays}</FieldData>".encode()


def _write_vtu(path: Path, mesh: meshio.Mesh, fields: dict[str, np.ndarray] | None = None) -> None:
    """A whole VTU file or none: written under a temporary name, renamed into place.
    ``fields``: field data (one record of the whole mesh), which meshio does not write to a
    VTU: put into the grid's XML element after meshio wrote the file."""

    def write(tmp: Path) -> None:
        meshio.write(tmp, mesh, file_format="vtu", binary=True)
        if fields:
            text = tmp.read_bytes()
            tag = b"<UnstructuredGrid>"
            tmp.write_bytes(text.replace(tag, tag + _field_data_xml(fields), 1))

    write_atomic(path, write)


def joint_relative_motion(model: Model, dq: np.ndarray) -> np.ndarray:
    """(m,) largest relative displacement between the two faces of each interface, over its
    corners, for the block motion ``dq`` (n, 6): how much the joint opens, slides or turns."""
    _, d_i, d_j = _interface_corner_motion(model, dq)
    return np.linalg.norm(d_j - d_i, axis=2).max(axis=1)


def write_mechanism_vtu(
    folder: Path,
    model: Model,
    step: StepResult,
    mode: np.ndarray,
    increment: np.ndarray | None,
    interface_cells: dict[str, np.ndarray] | None = None,
) -> tuple[str, str | None]:
    """Write the collapse mechanism at ``step``: blocks moved by ``mode`` (n, 6) (point data
    ``displacement``; ``last_increment`` too when given) and the interfaces with
    ``joint_motion`` (relative displacement across the joint in the mode, divided by its
    largest value) and, when given, ``joint_motion_last_increment``; ``interface_cells``:
    more cell data of the interfaces, (m,) arrays by name (the limit analysis's
    ``utilisation_capped``)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    moved = replace(step, q=mode)
    bmesh = blocks_mesh(model, moved)
    imesh = interfaces_mesh(model, moved) if model.interfaces.count else None
    fields = {"joint_motion": mode}
    if increment is not None:
        fields["joint_motion_last_increment"] = increment
        blocks = model.blocks
        moved_corners = rigid_motion(increment, blocks.centres, blocks.corner_points())
        bmesh.point_data["last_increment"] = moved_corners.reshape(-1, 3)
        if imesh is not None:
            _, d_i, d_j = _interface_corner_motion(model, increment)
            imesh.point_data["last_increment"] = (0.5 * (d_i + d_j)).reshape(-1, 3)
    _write_vtu(folder / MECHANISM_FILES[0], bmesh, step_fields(step))
    if imesh is None:
        return MECHANISM_FILES[0], None
    for name, field in fields.items():
        motion = joint_relative_motion(model, field)
        peak = float(motion.max(initial=0.0))
        imesh.cell_data[name] = [motion / peak if peak > 0 else motion]
    for name, values in (interface_cells or {}).items():
        imesh.cell_data[name] = [np.asarray(values)]
    _write_vtu(folder / MECHANISM_FILES[1], imesh, step_fields(step))
    return MECHANISM_FILES
