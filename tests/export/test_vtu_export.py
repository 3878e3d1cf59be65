"""VTU and PVD export.

Proves: the block and interface VTU files of a step round-trip through meshio with the same
points, cells, point data and cell data (bit for bit); block corners move by their block's
exact rigid motion; interface quads lie on the contact planes with the right areas; the PVD
index lists every written step with a path relative to its own folder (the folder can be
moved) and lambda as the time value; the writer keeps the last step and a summary.
(The check that ParaView's pvbatch opens the PVD lives in the ParaView tests.)
"""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path, PurePosixPath

import meshio
import numpy as np
import pytest

from masonry_dem.export.pvd import read_pvd, write_pvd
from masonry_dem.export.vtu import blocks_mesh, interfaces_mesh, rigid_motion, write_step_vtu
from masonry_dem.export.writer import ResultsWriter
from masonry_dem.geometry.builders import add_base, running_bond_wall
from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
from masonry_dem.results import History, StepResult
from masonry_dem.solvers.linear import solve_linear

A, B, S, GAMMA = 0.1, 0.25, 0.12, 18_000.0


@pytest.fixture(scope="module")
def vtu_model() -> Model:
    blocks, ib = add_base(running_bond_wall(4, 3, A, B, S, GAMMA))
    return Model.build(
        blocks,
        InterfaceMaterial(kn=1e8, kt=4e7, friction=0.6),
        [Support([ib])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name="vtu wall",
    )


def _step(model: Model, k: int, lam: float) -> StepResult:
    sol = solve_linear(model, lam)
    m = model.interfaces.count
    rng = np.random.default_rng(k)
    return StepResult(
        step=k,
        load_factor=lam,
        q=sol.q,
        actions=sol.actions,
        state=rng.integers(0, 5, m).astype(np.int32),
        utilisation=rng.uniform(0, 1, m),
        flags=rng.integers(0, 8, m).astype(np.int32),
        control_displacement=float(sol.q[:, 2].max()),
    )


def _assert_same_mesh(read: meshio.Mesh, written: meshio.Mesh) -> None:
    np.testing.assert_array_equal(read.points, written.points)
    assert len(read.cells) == len(written.cells) == 1
    assert read.cells[0].type == written.cells[0].type
    np.testing.assert_array_equal(read.cells[0].data, written.cells[0].data)
    assert set(read.point_data) == set(written.point_data)
    for key, val in written.point_data.items():
        np.testing.assert_array_equal(read.point_data[key], val, err_msg=key)
    assert set(read.cell_data) == set(written.cell_data)
    for key, val in written.cell_data.items():
        got = read.cell_data[key][0]
        assert got.shape == np.asarray(val[0]).shape, key
        np.testing.assert_array_equal(got, val[0], err_msg=key)


def test_vtu_files_round_trip_through_meshio(tmp_path, vtu_model):
    step = _step(vtu_model, 3, 0.25)
    bfile, ifile = write_step_vtu(tmp_path, vtu_model, step)
    assert (bfile, ifile) == ("steps/blocks_0003.vtu", "steps/interfaces_0003.vtu")
    _assert_same_mesh(meshio.read(tmp_path / bfile), blocks_mesh(vtu_model, step))
    _assert_same_mesh(meshio.read(tmp_path / ifile), interfaces_mesh(vtu_model, step))
    blocks = meshio.read(tmp_path / bfile)
    n, m = vtu_model.blocks.count, vtu_model.interfaces.count
    assert blocks.cells[0].type == "hexahedron" and blocks.cells[0].data.shape == (n, 8)
    np.testing.assert_array_equal(blocks.cell_data["translation"][0], step.q[:, :3])
    np.testing.assert_array_equal(blocks.cell_data["rotation"][0], step.q[:, 3:])
    np.testing.assert_array_equal(blocks.cell_data["block_id"][0], np.arange(n))
    np.testing.assert_array_equal(blocks.cell_data["fixed"][0], vtu_model.fixed.all(axis=1))
    joints = meshio.read(tmp_path / ifile)
    assert joints.cells[0].type == "quad" and joints.cells[0].data.shape == (m, 4)
    cd = {k: v[0] for k, v in joints.cell_data.items()}
    np.testing.assert_array_equal(cd["actions"], step.actions)
    np.testing.assert_array_equal(cd["normal_force"], step.actions[:, 2])
    np.testing.assert_array_equal(cd["shear_force"], np.hypot(*step.actions[:, :2].T))
    np.testing.assert_array_equal(cd["bending_moment"], np.hypot(*step.actions[:, 3:5].T))
    np.testing.assert_array_equal(cd["torsion"], step.actions[:, 5])
    np.testing.assert_array_equal(cd["state"], step.state)
    np.testing.assert_array_equal(cd["flags"], step.flags)
    np.testing.assert_array_equal(cd["utilisation"], step.utilisation)
    np.testing.assert_array_equal(cd["block_i"], vtu_model.interfaces.block_i)
    np.testing.assert_array_equal(cd["block_j"], vtu_model.interfaces.block_j)
    np.testing.assert_array_equal(cd["normal_axis"], vtu_model.interfaces.axis)
    np.testing.assert_array_equal(cd["area"], vtu_model.interfaces.area)


def test_block_corners_move_rigidly_and_hexahedra_are_valid(vtu_model):
    blocks = vtu_model.blocks
    q = np.zeros((blocks.count, 6))
    q[:, :3] = [1e-3, 2e-3, -1e-3]
    q[:, 3:] = [0.01, -0.02, 0.03]
    step = StepResult(
        0, 0.0, q, np.zeros((vtu_model.interfaces.count, 6)), np.zeros(0), np.zeros(0)
    )
    mesh = blocks_mesh(vtu_model, step)
    pts = mesh.points.reshape(-1, 8, 3)
    disp = mesh.point_data["displacement"].reshape(-1, 8, 3)
    arm = pts - blocks.centres[:, None, :]
    np.testing.assert_allclose(disp, q[:, None, :3] + np.cross(q[:, None, 3:], arm), rtol=1e-14)
    np.testing.assert_allclose(rigid_motion(q, blocks.centres, pts), disp, rtol=1e-15)
    # VTK hexahedron: the volume from the corner ordering is positive and equals the block's
    p = pts
    vol = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 3] - p[:, 0], p[:, 4] - p[:, 0]))
    np.testing.assert_allclose(vol, blocks.volumes, rtol=1e-12)


def test_interface_quads_lie_on_the_contact_planes(vtu_model):
    its = vtu_model.interfaces
    step = StepResult(
        0, 0.0, np.zeros((vtu_model.blocks.count, 6)), np.zeros((its.count, 6)),
        np.zeros(its.count), np.zeros(its.count),
    )  # fmt: skip
    mesh = interfaces_mesh(vtu_model, step)
    quads = mesh.points[mesh.cells[0].data]  # (m, 4, 3)
    rows = np.arange(its.count)
    normal_coord = quads[rows[:, None], np.arange(4)[None, :], its.axis[:, None]]  # (m, 4)
    np.testing.assert_allclose(normal_coord, np.repeat(its.centre[rows, its.axis][:, None], 4, 1))
    # quad area (shoelace in 3D) equals l1 l2
    cross = np.cross(quads[:, 1] - quads[:, 0], quads[:, 3] - quads[:, 0])
    np.testing.assert_allclose(np.linalg.norm(cross, axis=1), its.area, rtol=1e-12)
    np.testing.assert_allclose(quads.mean(axis=1), its.centre, rtol=1e-12, atol=1e-15)
    assert not mesh.point_data["displacement"].any()
    assert "flags" in mesh.cell_data and not mesh.cell_data["flags"][0].any()


def _run(
    folder: Path, model: Model, lams, every: int = 1, background: bool = False
) -> tuple[ResultsWriter, History]:
    writer = ResultsWriter(folder, model, every=every, background=background)
    hist = History()
    for k, lam in enumerate(lams):
        step = _step(model, k, lam)
        hist.steps.append(step)
        writer(step)
    hist.status = "completed"
    writer.finish(hist)
    return writer, hist


def test_pvd_lists_every_step_with_relative_paths_and_lambda(tmp_path, vtu_model):
    lams = [0.0, 0.1, 0.25, 0.3, 0.45]
    folder = tmp_path / "out"
    _run(folder, vtu_model, lams)
    for name, prefix in (("blocks.pvd", "blocks"), ("interfaces.pvd", "interfaces")):
        entries = read_pvd(folder / name)
        assert [t for t, _ in entries] == lams
        files = [f for _, f in entries]
        assert files == [f"steps/{prefix}_{k:04d}.vtu" for k in range(len(lams))]
        for f in files:
            assert not PurePosixPath(f).is_absolute() and ".." not in PurePosixPath(f).parts
        # the XML is a VTK Collection with one DataSet per step
        root = ET.parse(folder / name).getroot()
        assert root.tag == "VTKFile" and root.get("type") == "Collection"
        assert len(root.findall("./Collection/DataSet")) == len(lams)
    # the folder can move: every path resolves relative to the PVD's new location
    moved = tmp_path / "elsewhere" / "copy"
    shutil.copytree(folder, moved)
    shutil.rmtree(folder)
    for k, (lam, f) in enumerate(read_pvd(moved / "blocks.pvd")):
        mesh = meshio.read(moved / f)
        np.testing.assert_array_equal(
            mesh.cell_data["translation"][0], _step(vtu_model, k, lam).q[:, :3]
        )
    summary = json.loads((moved / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["steps"] == len(lams) and summary["steps_written"] == len(lams)
    assert summary["blocks"] == vtu_model.blocks.count
    assert summary["interfaces"] == vtu_model.interfaces.count
    assert summary["lambda"] == pytest.approx(lams[-1])
    csv = np.loadtxt(moved / "pushover.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(csv[:, 1], lams)


def test_writer_every_n_keeps_the_last_step(tmp_path, vtu_model):
    lams = [0.1 * k for k in range(7)]
    writer, _ = _run(tmp_path, vtu_model, lams, every=3)
    entries = read_pvd(tmp_path / "blocks.pvd")
    assert writer.steps_written == [0, 3, 6]
    np.testing.assert_allclose([t for t, _ in entries], [lams[0], lams[3], lams[6]])
    writer2, _ = _run(tmp_path / "b", vtu_model, lams[:6], every=4)
    assert writer2.steps_written == [0, 4, 5]  # the last step is written by finish()


def test_non_increasing_lambda_falls_back_to_step_numbers(tmp_path, vtu_model):
    # past a load peak lambda falls; ParaView needs increasing times, so steps are used
    _run(tmp_path, vtu_model, [0.1, 0.3, 0.2])
    assert [t for t, _ in read_pvd(tmp_path / "blocks.pvd")] == [0.0, 1.0, 2.0]


def test_write_pvd_checks_lengths_and_is_atomic(tmp_path):
    with pytest.raises(ValueError, match="2 files but 1 times"):
        write_pvd(tmp_path / "x.pvd", ["a.vtu", "b.vtu"], [0.0])
    write_pvd(tmp_path / "x.pvd", ["a.vtu", "sub/b.vtu"], [0.5, 1.5])
    assert read_pvd(tmp_path / "x.pvd") == [(0.5, "a.vtu"), (1.5, "sub/b.vtu")]
    assert not list(tmp_path.glob("*.tmp"))


def test_background_writer_writes_the_same_files(tmp_path, vtu_model):
    """Steps written by the background thread are the synchronous writer's, byte for byte,
    in the same order, and every one is on disk once finish() returns."""
    lams = [0.0, 0.1, 0.25, 0.3, 0.45]
    _run(tmp_path / "sync", vtu_model, lams)
    writer, _ = _run(tmp_path / "thread", vtu_model, lams, background=True)
    assert writer.steps_written == list(range(len(lams)))
    names = sorted(p.relative_to(tmp_path / "sync") for p in (tmp_path / "sync").rglob("*"))
    assert names == sorted(
        p.relative_to(tmp_path / "thread") for p in (tmp_path / "thread").rglob("*")
    )
    for name in names:
        if (tmp_path / "sync" / name).is_file() and name.name != "summary.json":
            assert (tmp_path / "sync" / name).read_bytes() == (
                tmp_path / "thread" / name
            ).read_bytes(), name


def test_background_writer_keeps_the_steps_of_a_run_that_raises(tmp_path, vtu_model):
    """A solver that raises after three steps inside ``with writer:``: all three are on disk
    when the error comes out."""
    writer = ResultsWriter(tmp_path, vtu_model, background=True)
    with pytest.raises(RuntimeError, match="solver broke"), writer:
        for k in range(3):
            writer(_step(vtu_model, k, 0.1 * k))
        raise RuntimeError("solver broke")
    assert [f for _, f in read_pvd(tmp_path / "blocks.pvd")] == [
        f"steps/blocks_{k:04d}.vtu" for k in range(3)
    ]
    for k in range(3):
        assert meshio.read(tmp_path / f"steps/interfaces_{k:04d}.vtu").cells
