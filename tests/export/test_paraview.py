"""ParaView state files, tested in a real ParaView (``xvfb-run -a pvbatch``) against a results
folder that is not the one the states were made from (other wall, other number of steps); the
mechanism state against a free-standing wall that collapsed by tilting about its base (its mode
moves only the base joints: the crack colour must show there and nowhere else).

Without pvbatch or xvfb-run the ParaView tests skip, saying so (they fail instead when
MASONRY_DEM_REQUIRE_PARAVIEW=1, for CI); the tests of copy_state and of the shipped files run
everywhere.
"""

from __future__ import annotations

import filecmp
import json
import os
import shutil
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from helpers.damage_pattern import build_model, states_at, write_results
from masonry_dem.export import paraview_state
from masonry_dem.export.pvd import read_pvd
from masonry_dem.export.render import (
    MECHANISM_BINS,
    MECHANISM_COLOURS,
    STATE_COLOURS,
    auto_scale,
)
from masonry_dem.export.vtu import MECHANISM_FILES
from masonry_dem.results import STATE_NAMES

REPO = Path(__file__).resolve().parents[2]
USER_STATES = REPO / "paraview_states"
CHECK = Path(__file__).with_name("pvbatch_check.py")
PVBATCH_TIMEOUT = 300
#: the time-aware states (blocks.pvd, interfaces.pvd); the mechanism state reads one mode
STEP_STATES = tuple(n for n in paraview_state.STATES if n != "mechanism")
TILT_COURSES = 6


# --------------------------------------------------------------------------- helpers
@pytest.fixture(scope="module")
def pvbatch() -> list[str]:
    missing = [tool for tool in ("pvbatch", "xvfb-run") if shutil.which(tool) is None]
    if missing and os.environ.get("MASONRY_DEM_REQUIRE_PARAVIEW") == "1":
        pytest.fail(f"MASONRY_DEM_REQUIRE_PARAVIEW=1 but {' and '.join(missing)} not on PATH")
    if missing:
        pytest.skip(
            f"ParaView tests need {' and '.join(missing)} on PATH "
            "(Debian/Ubuntu: apt-get install paraview xvfb); CI installs them"
        )
    return ["xvfb-run", "-a", "pvbatch"]


def run_pvbatch(cmd: list[str], *args) -> dict:
    for attempt in range(4):
        if attempt:
            time.sleep(1.0)
        proc = subprocess.run(
            [*cmd, str(CHECK), *map(str, args)],
            capture_output=True,
            text=True,
            timeout=PVBATCH_TIMEOUT,
        )
        # a busy machine sometimes gives xvfb-run a display that the X window then cannot
        # open (pvbatch aborts in CreateAWindow before loading anything, twice in a row at a
        # load of 3 on 2 cores): start it again
        if not (proc.returncode != 0 and "CreateAWindow" in proc.stdout + proc.stderr):
            break
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, (
        f"pvbatch failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    )
    return json.loads(lines[-1][len("RESULT ") :])


def damage_codes(img: np.ndarray, tol: float = 40.0) -> np.ndarray:
    """State code of pixels drawn in a damage colour (-1 elsewhere), with the scalar bar
    (upper right) and the orientation axes (lower left) masked."""
    rgb = img[..., :3].astype(float)
    ref = np.array(STATE_COLOURS, dtype=float)
    dist = np.linalg.norm(rgb[:, :, None, :] - ref[None, None], axis=-1)
    code = np.where(dist.min(axis=-1) < tol, dist.argmin(axis=-1), -1)
    h, w = code.shape
    code[: int(0.4 * h), int(0.85 * w) :] = -1
    code[int(0.75 * h) :, : int(0.2 * w)] = -1
    return code


def assert_not_blank(img: np.ndarray) -> None:
    rgb = img[..., :3].astype(int)
    background = np.all(rgb == rgb[0, 0], axis=-1)
    assert background.mean() < 0.97, "screenshot is (almost) blank"
    packed = (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]
    assert np.unique(packed).size > 20, "screenshot has hardly any colour"


def expected_fractions(model, state) -> np.ndarray:
    q = model.interfaces.corner_points()
    length = np.ptp(q[:, :, 0], axis=1) + np.ptp(q[:, :, 1], axis=1)
    w = np.bincount(state, weights=length, minlength=len(STATE_NAMES))
    return w / w.sum()


@pytest.fixture(scope="module")
def pv_results(tmp_path_factory):
    """12 courses x 10 blocks, 5 steps: not the sample the states were made from."""
    model = build_model()
    folder = tmp_path_factory.mktemp("pv") / "wall"
    write_results(folder, model)
    return model, folder


@pytest.fixture(scope="module")
def mech_results(tmp_path_factory):
    """A free-standing 3 x 6 running-bond wall pushed out of plane: it tilts about its base
    (lambda = s/H), the mode moves the base joints only (as in test_mechanism_render)."""
    from masonry_dem.export.analyses import pushover
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import (
        InterfaceMaterial,
        Model,
        SelfWeight,
        Support,
        WeightProportional,
    )

    blocks, base = add_base(running_bond_wall(3, TILT_COURSES, 0.081, 0.21, 0.07, 20e3))
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2.4e9, kt=1.0e9, friction=0.7),
        supports=[Support([base])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name="tilting wall",
    )
    folder = tmp_path_factory.mktemp("pv_mech") / "wall"
    hist = pushover(model, out=folder)
    assert hist.status == "collapse", hist.reason
    return model, folder


@pytest.fixture
def mech_copy(tmp_path, mech_results) -> Path:
    dst = tmp_path / "mech"
    shutil.copytree(mech_results[1], dst)
    return dst


def colour_mask(img: np.ndarray, colour, tol: float = 40.0, inside: bool = False) -> np.ndarray:
    """Pixels within ``tol`` of ``colour``, with the scalar bar (upper right) and the
    orientation axes (lower left) masked, as in damage_codes. ``inside``: only pixels at least
    3 pixels from the white background (a grey of the anti-aliased wall outline, white fading
    into the support's dark grey, is no joint)."""
    rgb = img[..., :3].astype(float)
    mask = np.linalg.norm(rgb - np.asarray(colour, dtype=float), axis=-1) < tol
    if inside:
        white = np.all(rgb >= 250, axis=-1)
        near = white.copy()
        for dr in range(-3, 4):
            for dc in range(-3, 4):
                near |= np.roll(np.roll(white, dr, axis=0), dc, axis=1)
        mask &= ~near
    h, w = mask.shape
    mask[: int(0.4 * h), int(0.85 * w) :] = False
    mask[int(0.75 * h) :, : int(0.2 * w)] = False
    return mask


# --------------------------------------------------------------------------- shipped files
def test_user_copies_are_identical_to_the_shipped_states():
    for name in paraview_state.STATES:
        shipped = paraview_state.state_path(name)
        user = USER_STATES / f"{name}.pvsm"
        assert user.is_file(), f"{user} missing: run python paraview_states/make_states.py"
        assert filecmp.cmp(shipped, user, shallow=False), (
            f"{user} differs from {shipped}: regenerate both with paraview_states/make_states.py"
        )


@pytest.mark.parametrize("name", paraview_state.STATES)
def test_shipped_states_point_only_at_the_placeholder(name):
    root = ET.parse(paraview_state.state_path(name)).getroot()
    files = [
        e.get("value")
        for p in root.iter("Property")
        if p.get("name") == "FileName"
        for e in p.findall("Element")
    ]
    assert sorted(set(files)) == sorted(
        f"{paraview_state.PLACEHOLDER}/{f}" for f in paraview_state.DATA_FILES[name]
    )
    text = paraview_state.state_path(name).read_text()
    assert "/tmp/" not in text and str(REPO) not in text


def test_mechanism_state_reads_the_mechanism_files():
    assert paraview_state.DATA_FILES["mechanism"] == MECHANISM_FILES
    assert set(paraview_state.DATA_FILES) == set(paraview_state.STATES)


def _lut_points(name: str, array: str) -> np.ndarray:
    root = ET.parse(paraview_state.state_path(name)).getroot()
    for proxy in root.iter("Proxy"):
        if proxy.get("group") != "lookup_tables":
            continue
        props = {p.get("name"): p for p in proxy.findall("Property")}
        # the LUT the joints are coloured with: the one holding the mechanism colours
        values = [float(e.get("value")) for e in props["RGBPoints"].findall("Element")]
        pts = np.array(values).reshape(-1, 4)
        if len(pts) == 2 * len(MECHANISM_COLOURS):
            discretize = props["Discretize"].find("Element").get("value")
            assert discretize == "0", "a discretized LUT would move the bin edges"
            return pts
    raise AssertionError(f"no {array} lookup table with {len(MECHANISM_COLOURS)} bins")


def test_mechanism_lookup_table_matches_the_pyvista_bins():
    """The ParaView picture and render_mechanism colour every joint alike."""
    pts = _lut_points("mechanism", "joint_motion")
    assert pts[0, 0] == 0.0 and pts[-1, 0] == 1.0
    motion = np.array(
        [0.0, 0.01, 0.0499, 0.05, 0.1, 0.2499, 0.25, 0.3, 0.4999, 0.5, 0.7, 0.99, 1.0]
    )
    want = np.searchsorted(np.asarray(MECHANISM_BINS), motion, side="right")
    rgb = np.stack([np.interp(motion, pts[:, 0], pts[:, c]) for c in (1, 2, 3)], axis=1)
    np.testing.assert_allclose(
        rgb * 255, np.asarray(MECHANISM_COLOURS, dtype=float)[want], atol=0.01
    )
    text = paraview_state.state_path("mechanism").read_text()
    assert 'value="joint motion / largest"' in text
    assert 'value="joint_motion"' in text


def test_state_names():
    assert paraview_state.state_path("damage-map.pvsm") == paraview_state.state_path("damage_map")
    with pytest.raises(ValueError, match="unknown ParaView state 'damage'.*damage_map"):
        paraview_state.state_path("damage")


# --------------------------------------------------------------------------- copy_state
def _file_names(root: ET.Element) -> list[str]:
    """Every FileName value of a state, sorted."""
    return sorted(
        e.get("value")
        for p in root.iter("Property")
        if p.get("name") == "FileName"
        for e in p.findall("Element")
    )


def _warp_scales(root: ET.Element) -> list[float]:
    """The ScaleFactor of every Warp By Vector of a state, in order."""
    return [
        float(p.find("Element").get("value"))
        for proxy in root.iter("Proxy")
        if proxy.get("type") == "WarpVector"
        for p in proxy.findall("Property")
        if p.get("name") == "ScaleFactor"
    ]


def test_copy_state_fills_in_the_folder(results_copy):
    out = paraview_state.copy_state("deformed_shape", results_copy, scale=12.5)
    assert out == results_copy / "deformed_shape.pvsm"
    root = ET.parse(out).getroot()
    files = _file_names(root)
    assert files == [str((results_copy / f).resolve()) for f in ("blocks.pvd", "interfaces.pvd")]
    scales = _warp_scales(root)
    assert scales == [12.5, 12.5]


@pytest.mark.parametrize("name", STEP_STATES)
def test_copy_state_names_the_case_and_its_method(results_copy, name):
    """The copy's titles start with the case's name and the method (the shipped states hold a
    placeholder there), wrapped to lines a Text source shows whole."""
    summary = json.loads((results_copy / "summary.json").read_text())
    summary["name"] = "a wall" + " with a long name" * 10
    (results_copy / "summary.json").write_text(json.dumps(summary))
    root = ET.parse(paraview_state.copy_state(name, results_copy)).getroot()
    titles = [
        el.get("value", "")
        for proxy in root.iter("Proxy")
        if proxy.get("type") == "TextSource"
        for prop in proxy.findall("Property")
        if prop.get("name") == "Text"
        for el in prop.findall("Element")
    ]
    assert titles
    for title in titles:
        assert paraview_state.CASE_PLACEHOLDER not in title
        flat = " ".join(title.split("\n")[:-1])
        assert flat == f"{summary['name']}: static pushover (Newton, load/displacement control)"
        assert max(len(line) for line in title.split("\n")) <= paraview_state.TITLE_WIDTH


def test_copy_state_mechanism(mech_copy):
    out = paraview_state.copy_state("mechanism", mech_copy)
    assert out == mech_copy / "mechanism.pvsm"
    root = ET.parse(out).getroot()
    files = sorted(set(_file_names(root)))
    assert files == [str((mech_copy / f).resolve()) for f in MECHANISM_FILES]
    scales = _warp_scales(root)
    # the mode's scale (largest translation 1): its largest point motion ~6.5 % of the wall
    points, disp = paraview_state._read_points(mech_copy / MECHANISM_FILES[0])
    size = float(np.max(np.ptp(points, axis=0)))
    dmax = float(np.linalg.norm(disp, axis=1).max())
    assert scales == [auto_scale(dmax, size)] * 2
    assert 0.03 < scales[0] * dmax / size <= 0.065
    assert scales[0] == paraview_state.warp_scale(mech_copy, mechanism=True)
    assert scales[0] != paraview_state.warp_scale(mech_copy)  # not the last step's
    out = paraview_state.copy_state("mechanism", mech_copy, scale=0.5, overwrite=True)
    assert 'value="0.5"' in out.read_text()


def test_copy_state_mechanism_needs_the_mechanism_files(results_copy, mech_copy):
    """A run that did not collapse has no mechanism: the error names the missing file."""
    with pytest.raises(FileNotFoundError, match="no collapse mechanism.*mechanism_blocks.vtu"):
        paraview_state.copy_state("mechanism", results_copy)
    assert not (results_copy / "mechanism.pvsm").exists()
    (mech_copy / MECHANISM_FILES[1]).unlink()
    with pytest.raises(FileNotFoundError, match="mechanism_interfaces.vtu is missing"):
        paraview_state.copy_state("mechanism", mech_copy)
    with pytest.raises(FileNotFoundError, match="not found"):
        paraview_state.copy_state("mechanism", mech_copy / "missing")


def test_copy_state_refuses_to_overwrite(results_copy):
    out = paraview_state.copy_state("damage_map", results_copy)
    out.write_text("edited by the user")
    with pytest.raises(FileExistsError, match="overwrite"):
        paraview_state.copy_state("damage_map", results_copy)
    assert out.read_text() == "edited by the user"
    paraview_state.copy_state("damage_map", results_copy, overwrite=True)
    assert out.read_text() != "edited by the user"


def test_copy_state_bad_input(results_copy, tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        paraview_state.copy_state("damage_map", tmp_path / "missing")
    with pytest.raises(ValueError, match="unknown ParaView state"):
        paraview_state.copy_state("nope", results_copy)
    with pytest.raises(ValueError, match=r"\.pvsm"):
        paraview_state.copy_state("damage_map", results_copy, out=results_copy / "blocks.pvd")
    (results_copy / "interfaces.pvd").unlink()
    for f in (results_copy / "steps").glob("interfaces_*.vtu"):
        f.unlink()
    with pytest.raises(FileNotFoundError, match="interfaces.pvd"):
        paraview_state.copy_state("damage_map", results_copy)


def test_cli_paraview_state(results_copy, capsys):
    from masonry_dem.cli import main

    assert main(["paraview-state", "all", str(results_copy)]) == 0
    for name in STEP_STATES:
        assert (results_copy / f"{name}.pvsm").is_file()
    # no collapse, no mechanism: 'all' skips it and says so
    assert not (results_copy / "mechanism.pvsm").exists()
    assert "mechanism state skipped" in capsys.readouterr().err
    assert main(["paraview-state", "damage_map", str(results_copy)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["paraview-state", "damage_map", str(results_copy), "--force"]) == 0
    with pytest.raises(SystemExit):
        main(["paraview-state", "nope", str(results_copy)])


def test_cli_paraview_state_mechanism(results_copy, mech_copy, capsys):
    from masonry_dem.cli import main

    assert main(["paraview-state", "mechanism", str(results_copy)]) == 2
    err = capsys.readouterr().err
    assert "no collapse mechanism" in err and "mechanism_blocks.vtu is missing" in err
    assert main(["paraview-state", "mechanism", str(mech_copy)]) == 0
    assert (mech_copy / "mechanism.pvsm").is_file()
    assert main(["paraview-state", "all", str(mech_copy), "--force"]) == 0
    for name in paraview_state.STATES:
        assert (mech_copy / f"{name}.pvsm").is_file()
    assert "skipped" not in capsys.readouterr().err


# --------------------------------------------------------------------------- in ParaView
@pytest.mark.paraview
def test_pvd_opens_in_paraview_with_every_time_step(pvbatch, pv_results):
    model, folder = pv_results
    files = {
        "blocks.pvd": (model.blocks.count, "fixed"),
        "interfaces.pvd": (model.interfaces.count, "state"),
    }
    got = run_pvbatch(pvbatch, "pvd", *(folder / f for f in files))
    for pvd, (cells, array) in files.items():
        want = [t for t, _ in read_pvd(folder / pvd)]
        info = got[str(folder / pvd)]
        assert len(want) == 5 and info["timesteps"] == pytest.approx(want)
        assert info["cells"] == cells
        assert array in info["cell_arrays"] and "displacement" in info["point_arrays"]


@pytest.mark.paraview
def test_pvd_with_falling_lambda_opens_with_step_numbers(pvbatch, tmp_path):
    """Past the peak lambda falls; the writer then indexes by step number."""
    from masonry_dem.export.writer import ResultsWriter
    from masonry_dem.results import StepResult
    from masonry_dem.solvers.linear import solve_linear

    model = build_model(4, 3)
    lin = solve_linear(model)
    writer = ResultsWriter(tmp_path / "peak", model)
    for k, lam in enumerate((0.2, 0.4, 0.3)):
        writer(
            StepResult(
                k,
                lam,
                lin.q * lam,
                lin.actions * lam,
                np.zeros(model.interfaces.count, dtype=np.int32),
                np.zeros(model.interfaces.count),
            )
        )
    path = tmp_path / "peak" / "interfaces.pvd"
    assert run_pvbatch(pvbatch, "pvd", path)[str(path)]["timesteps"] == [0.0, 1.0, 2.0]


@pytest.fixture(scope="module")
def state_folders(pv_results, mech_results) -> dict[str, Path]:
    """The results folder each state is loaded against."""
    return {
        name: mech_results[1] if name == "mechanism" else pv_results[1]
        for name in paraview_state.STATES
    }


@pytest.fixture(scope="module")
def screenshots(pvbatch, state_folders, tmp_path_factory):
    """Every state loaded twice: LoadState(data_directory=folder) (then Reset Camera, as a user
    would for a wall of another size), and the copy_state copy loaded as is."""
    import imageio.v3 as iio

    out_dir = tmp_path_factory.mktemp("pv_shots")
    jobs, keys = [], []
    for name in paraview_state.STATES:
        folder = state_folders[name]
        jobs.append(
            [
                str(paraview_state.state_path(name)),
                str(folder),
                str(out_dir / f"{name}_search.png"),
                "reset",
            ]
        )
        copy = paraview_state.copy_state(name, folder, out=out_dir / f"{name}.pvsm")
        jobs.append([str(copy), "-", str(out_dir / f"{name}_copy.png"), ""])
        keys += [(name, "search"), (name, "copy")]
    (out_dir / "jobs.json").write_text(json.dumps(jobs))
    infos = run_pvbatch(pvbatch, "states", out_dir / "jobs.json")
    return {
        key: (info, iio.imread(job[2])) for key, info, job in zip(keys, infos, jobs, strict=True)
    }


@pytest.mark.paraview
@pytest.mark.parametrize("how", ["search", "copy"])
@pytest.mark.parametrize("name", paraview_state.STATES)
def test_state_loads_against_a_results_folder(screenshots, state_folders, name, how):
    folder = state_folders[name]
    info, img = screenshots[name, how]
    assert info["files"] == {
        f: str((folder / f).resolve()) for f in paraview_state.DATA_FILES[name]
    }
    if name == "mechanism":  # one mode, no time steps
        assert info["timesteps"] == [] and info["views"] == 1
        assert {"warp blocks", "warp interfaces"} <= set(info["sources"])
        assert_not_blank(img)
        return
    times = [t for t, _ in read_pvd(folder / "blocks.pvd")]
    # time-aware: ParaView knows every step of this folder (5, the states were made with 4)
    assert info["timesteps"] == pytest.approx(times)
    assert info["end_time"] == pytest.approx(times[-1])
    assert info["time"] == pytest.approx(times[-1])
    assert_not_blank(img)


@pytest.mark.paraview
@pytest.mark.parametrize("how", ["search", "copy"])
@pytest.mark.parametrize("name", paraview_state.STATES)
def test_labels_name_the_case_its_method_lambda_and_the_step(screenshots, state_folders, name, how):
    """Every state, loaded by the README's recipe or as a copy, shows lambda and the step as
    two named quantities (not "lambda (or step) = 38" once lambda stops rising), and a title
    naming the case and the method; the damage map draws a length scale (axes in metres)."""
    info, _ = screenshots[name, how]
    summary = json.loads((state_folders[name] / "summary.json").read_text())
    labels = info["labels"]
    titles = [text for key, text in labels.items() if key.startswith("title: ")]
    assert titles and all(t.startswith(f"{summary['name']}: static pushover") for t in titles), (
        titles
    )
    lambdas = sorted(text for key, text in labels.items() if key.endswith("lambda"))
    steps = sorted(text for key, text in labels.items() if key.endswith("step"))
    if name == "mechanism":  # the collapse step's
        last = summary["steps"] - 1
        lam = float(
            np.loadtxt(state_folders[name] / "pushover.csv", delimiter=",", skiprows=1)[-1, 1]
        )
    else:
        last, lam = 4, 0.5  # write_results: 5 steps up to lambda 0.5
    assert lambdas and set(lambdas) == {f"lambda = {lam:.4g}"}, labels
    assert steps and set(steps) == {f"step {last}"}, labels
    if name == "damage_map":
        assert info["axes_grids"] == [1]


@pytest.mark.paraview
@pytest.mark.parametrize("how", ["search", "copy"])
@pytest.mark.parametrize("name", ["damage_map", "deformed_shape"])
def test_damage_colours_where_interfaces_failed(screenshots, pv_results, name, how):
    model, _ = pv_results
    _, img = screenshots[name, how]
    code = damage_codes(img)
    counts = np.bincount(code[code >= 0], minlength=len(STATE_NAMES))
    assert np.all(counts > 200), (
        f"damage colours missing: {dict(zip(STATE_NAMES, counts, strict=True))}"
    )
    # bands 0..4 lie left to right in both the front and the oblique (from the right) view
    cols = np.nonzero(code >= 0)[1]
    centre = [np.median(cols[code[code >= 0] == k]) for k in range(len(STATE_NAMES))]
    assert np.all(np.diff(centre) > 0), centre
    if name == "damage_map":  # front elevation: shares as the analysis says
        got = counts / counts.sum()
        np.testing.assert_allclose(got, expected_fractions(model, states_at(model, 4)), atol=0.03)


@pytest.mark.paraview
def test_force_view_shows_both_fields(screenshots):
    for how in ("search", "copy"):
        _, img = screenshots["force_view", how]
        h = img.shape[0]
        for half in (img[: h // 2], img[h // 2 :]):  # normal force above, utilisation below
            assert_not_blank(half)


@pytest.mark.paraview
@pytest.mark.parametrize("how", ["search", "copy"])
def test_mechanism_crack_colour_along_the_base_only(screenshots, how):
    """The wall tilts about its base: the base joints move the most (joint_motion 1, dark red),
    every other joint < 5 % (light grey); the picture shows exactly that."""
    _, img = screenshots["mechanism", how]
    crack = colour_mask(img, MECHANISM_COLOURS[-1])
    shut = colour_mask(img, MECHANISM_COLOURS[0], tol=12.0, inside=True)
    assert crack.sum() > 150, f"crack colour missing ({crack.sum()} pixels)"
    assert shut.sum() > 1000, f"the shut joints above the base are missing ({shut.sum()} pixels)"
    for colour in MECHANISM_COLOURS[1:3]:  # no joint between 5 and 50 %
        assert colour_mask(img, colour, tol=30.0).sum() < 20
    rows, cols = np.nonzero(crack)
    # the crack is the lowest joint line in every column it crosses (image rows grow down) ...
    for c in np.unique(cols):
        above = np.nonzero(shut[:, c])[0]
        if above.size:
            assert rows[cols == c].min() >= above.max() - 4, f"crack above a shut joint, x={c}"
    # ... and it runs along the wall's length, below the shut joints of the wall above
    shut_rows, shut_cols = np.nonzero(shut)
    span = np.ptp(shut_cols)
    assert np.ptp(cols) > 0.7 * span
    assert np.median(rows) > np.percentile(shut_rows, 90)


# --------------------------------------------------------------------------- framing any wall
FRAME_WALL = paraview_state.frame_script_path()
#: the wall's share of the frame (along its longer side on screen) that "fills most of it"
FILL_SHARE = 0.6
#: pixels at the image's edge that must stay background (nothing cut off)
EDGE = 2


def default_wall_model(factor: float):
    """The bundled default wall (default_wall.toml: 3 x 13 running bond, a = 0.081, b = 0.21,
    s = 0.07 m, base slab, left column held in u1 and u3) with every length times
    ``factor``."""
    from masonry_dem.geometry import selectors
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import (
        InterfaceMaterial,
        Model,
        SelfWeight,
        Support,
        WeightProportional,
    )

    wall = running_bond_wall(3, 13, 0.081 * factor, 0.21 * factor, 0.07 * factor, 20e3)
    blocks, base = add_base(wall)
    return Model.build(
        blocks,
        InterfaceMaterial(kn=1e9, kt=0.4e9, friction=0.7),
        supports=[Support([base]), Support(selectors.column(wall, "left"), ["u1", "u3"])],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name=f"default wall x{factor:g}",
    )


def write_with_mechanism(folder: Path, model) -> None:
    """Steps with known damage (damage_pattern) and a collapse mode: the wall turning out of
    plane about its base's front edge (largest translation 1)."""
    from masonry_dem.export.vtu import write_mechanism_vtu

    hist = write_results(folder, model)
    centres, upper = model.blocks.centres, model.blocks.upper
    moving = ~model.fixed.all(axis=1)
    pivot = np.array([0.0, float(upper[~moving, 1].max()), float(upper[:, 2].max())])
    w = np.array([-1.0, 0.0, 0.0])
    mode = np.zeros((model.blocks.count, 6))
    mode[moving, :3] = np.cross(w, centres[moving] - pivot)
    mode[moving, 3:] = w
    mode /= np.linalg.norm(mode[:, :3], axis=1).max()
    write_mechanism_vtu(folder, model, hist.last, mode, None)


def test_frame_wall_script_is_shipped_once():
    # one file, the package's: no copy beside the user-facing states to drift from it
    assert not (USER_STATES / "frame_wall.py").exists()
    assert FRAME_WALL.is_file()
    text = FRAME_WALL.read_text()
    # the same amplification rule as the package's pictures
    from masonry_dem.export.scene import AUTO_SCALE_TARGET

    assert f"AUTO_SCALE_TARGET = {AUTO_SCALE_TARGET}" in text


@pytest.fixture(scope="module")
def framed(pvbatch, tmp_path_factory):
    """Every state loaded against the default wall and against the same wall 4x larger, by
    the README's recipe alone and by frame_wall.py; screenshots without the 2D overlays."""
    import imageio.v3 as iio

    root = tmp_path_factory.mktemp("frame")
    jobs, keys = [], []
    for factor in (1.0, 4.0):
        folder = root / f"wall_x{factor:g}"
        write_with_mechanism(folder, default_wall_model(factor))
        for name in paraview_state.STATES:
            for how in ("recipe", "macro"):
                prefix = str(root / f"{name}_{factor:g}_{how}")
                jobs.append([str(paraview_state.state_path(name)), str(folder), prefix, how])
                keys.append((name, factor, how, folder))
    (root / "jobs.json").write_text(json.dumps(jobs))
    infos = run_pvbatch(pvbatch, "frame", FRAME_WALL, root / "jobs.json")
    return {
        (name, factor, how): (
            folder,
            info["scales"],
            [iio.imread(f)[..., :3] for f in info["images"]],
        )
        for (name, factor, how, folder), info in zip(keys, infos, strict=True)
    }


@pytest.mark.paraview
@pytest.mark.parametrize("how", ["recipe", "macro"])
@pytest.mark.parametrize("factor", [1.0, 4.0])
@pytest.mark.parametrize("name", paraview_state.STATES)
def test_state_frames_any_wall(framed, name, factor, how):
    """Loaded by the README's recipe (LoadState with data_directory, then the last time
    step: the state's cue frames it) or framed by frame_wall.py: the wall fills most of
    every view and no part touches the frame's edge; the warp scale is the package's
    automatic one for this folder."""
    folder, scales, images = framed[name, factor, how]
    for img in images:
        wall = np.any(img < 245, axis=-1)  # anything drawn on the white background
        rows, cols = np.nonzero(wall)
        assert rows.size, f"{name}: nothing drawn"
        h, w = wall.shape
        assert not wall[:EDGE].any() and not wall[-EDGE:].any(), f"{name} x{factor}: cut off"
        assert not wall[:, :EDGE].any() and not wall[:, -EDGE:].any(), f"{name} x{factor}: cut off"
        fill = max(np.ptp(rows) / h, np.ptp(cols) / w)
        assert fill >= FILL_SHARE, f"{name} x{factor}: the wall fills {fill:.0%} of the frame"
    if name in ("deformed_shape", "mechanism"):
        want = paraview_state.warp_scale(folder, mechanism=name == "mechanism")
        assert scales == pytest.approx([want, want])


@pytest.mark.paraview
def test_a_front_view_of_walls_that_meet_turns_oblique(pvbatch, tmp_path):
    """S5 with return walls (a U wall, 0.32 m deep for 1.4 m wide): the damage map's and the
    force view's front elevations would hide the returns behind the facade, so the framing
    turns them to the oblique view; the flat default wall keeps its front elevation."""
    import imageio.v3 as iio

    from masonry_dem.cases.paper import build_case

    folders = {"u": tmp_path / "u", "flat": tmp_path / "flat"}
    write_with_mechanism(folders["u"], build_case("S5", restraint="return-walls").model)
    write_with_mechanism(folders["flat"], default_wall_model(1.0))
    jobs = [
        [str(paraview_state.state_path(name)), str(folder), str(tmp_path / f"{key}_{name}"), how]
        for key, folder in folders.items()
        for name in ("damage_map", "force_view")
        for how in ("recipe", "macro")
    ]
    (tmp_path / "jobs.json").write_text(json.dumps(jobs))
    infos = run_pvbatch(pvbatch, "frame", FRAME_WALL, tmp_path / "jobs.json")
    for (_, folder, _, _), info in zip(jobs, infos, strict=True):
        for direction, image in zip(info["directions"], info["images"], strict=True):
            if folder.endswith("flat"):
                assert direction == pytest.approx([0.0, 0.0, 1.0], abs=1e-9)
            else:
                assert abs(direction[0]) > 0.3 and abs(direction[2]) < 0.9, direction
                wall = np.any(iio.imread(image)[..., :3] < 245, axis=-1)
                assert not wall[:EDGE].any() and not wall[-EDGE:].any()


@pytest.mark.parametrize("name", paraview_state.STATES)
def test_every_state_frames_itself_with_frame_wall(name):
    """Each shipped state holds frame_wall.py (up to its main block) as a Python animation
    cue: the code the framing test runs in ParaView is the code in the file."""
    root = ET.parse(paraview_state.state_path(name)).getroot()
    scripts = [
        p.find("Element").get("value")
        for proxy in root.iter("Proxy")
        if proxy.get("type") == "PythonAnimationCue"
        for p in proxy.findall("Property")
        if p.get("name") == "Script"
    ]
    head = FRAME_WALL.read_text().split('\nif __name__ == "__main__":')[0] + "\n"
    assert scripts == [head]
