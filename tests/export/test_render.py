"""Off-screen renders with pyvista: image tests (pytest-pyvista for the 3D pictures, pytest-mpl
for the pushover plot), damage colours on screen, animation, pushover plot, bad input, and the
promise that ``import masonry_dem`` does not import pyvista.

Image tolerance: a 3D picture matches its cached image (tests/export/image_cache, 600 x 450)
when ``pyvista.compare_images`` (vtkImageDifference, mean error) is at most 500, pytest-pyvista's
and pyvista's own threshold: one damage band changing colour (about 2 % of the pixels) fails
it. The pushover plot matches its baseline (tests/export/baseline) within an RMS difference of
2 (of 255) with pytest-mpl (``--mpl`` is in the pytest options of pyproject.toml). Regenerate
with ``pytest tests/export --reset_image_cache`` and ``--mpl-generate-path=tests/export/baseline``,
then look at the images before committing them.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyvista")
import imageio.v3 as iio  # noqa: E402

from masonry_dem.export import render  # noqa: E402
from masonry_dem.results import STATE_NAMES  # noqa: E402

SMALL = (600, 450)


# --------------------------------------------------------------------------- helpers
def classify(img: np.ndarray, tol: float = 40.0) -> np.ndarray:
    """(h, w) state code of each pixel drawn in a damage colour, -1 elsewhere; the column of
    the legend and the triad is masked out."""
    rgb = img[..., :3].astype(float)
    ref = np.array(render.STATE_COLOURS, dtype=float)
    dist = np.linalg.norm(rgb[:, :, None, :] - ref[None, None], axis=-1)
    code = np.where(dist.min(axis=-1) < tol, dist.argmin(axis=-1), -1)
    h, w = code.shape
    x0 = render.LEGEND_BOX[0]
    code[:, int(w * x0) - 2 :] = -1  # the column of the legend and the axes triad
    return code


def fractions(code: np.ndarray) -> np.ndarray:
    counts = np.bincount(code[code >= 0], minlength=len(STATE_NAMES)).astype(float)
    return counts / counts.sum()


def expected_front_fractions(model, state) -> np.ndarray:
    """Share of each state in the joints' visible front area: every joint shows a strip
    of the same thickness and of its length in the wall plane."""
    q = model.interfaces.corner_points()
    length = np.ptp(q[:, :, 0], axis=1) + np.ptp(q[:, :, 1], axis=1)
    w = np.bincount(state, weights=length, minlength=len(STATE_NAMES))
    return w / w.sum()


# --------------------------------------------------------------------------- imports
def test_import_masonry_dem_does_not_import_pyvista():
    code = (
        "import sys\n"
        "import masonry_dem, masonry_dem.export.vtu, masonry_dem.export.writer\n"
        "import masonry_dem.export.render, masonry_dem.export.paraview_state\n"
        "from masonry_dem.cli import build_parser\n"
        "build_parser()\n"
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('pyvista', 'vtk', 'vtkmodules'))\n"
        "assert not bad, bad\n"
    )
    env = dict(os.environ)
    src = str(Path(render.__file__).resolve().parents[2])
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr


# --------------------------------------------------------------------------- image tests
#: pytest-pyvista's threshold on pyvista.compare_images (stated here, its default)
IMAGE_ERROR = 500.0


@pytest.mark.slow
@pytest.mark.parametrize("view", list(render.VIEWS))
def test_render_image(results, tmp_path, view, verify_image_cache):
    """The picture of the last step in every view, with its caption, triad, length scale,
    load arrow, support marks and legend, against the cached image."""
    verify_image_cache.error_value = IMAGE_ERROR
    out = render.render_step(results, view=view, out=tmp_path / f"{view}.png", window_size=SMALL)
    assert out == tmp_path / f"{view}.png"
    assert iio.imread(out).shape[:2] == (SMALL[1], SMALL[0])


@pytest.mark.slow
@pytest.mark.mpl_image_compare(baseline_dir="baseline", tolerance=2, style="default")
def test_pushover_plot_image(results):
    """The pushover curve: lambda [-] against the named displacement in mm."""
    from masonry_dem.export.plots import pushover_figure

    return pushover_figure(results)


# --------------------------------------------------------------------------- content
@pytest.mark.slow
def test_front_view_damage_colours_in_proportion(results, model, tmp_path):
    from helpers.damage_pattern import states_at

    img = iio.imread(render.render_step(results, view="front", out=tmp_path / "f.png"))
    got = fractions(classify(img))
    want = expected_front_fractions(model, states_at(model, 4))
    assert np.all(want > 0.05)  # every state is on screen
    np.testing.assert_allclose(got, want, atol=0.015)


@pytest.mark.slow
def test_damage_colours_where_interfaces_failed(results, tmp_path):
    """Bands 0..4 from left to right in the front view, right to left in the back view."""
    centres = {}
    for view in ("front", "back"):
        code = classify(
            iio.imread(render.render_step(results, view=view, out=tmp_path / f"{view}.png"))
        )
        cols = np.nonzero(code >= 0)[1]
        centres[view] = [np.median(cols[code[code >= 0] == k]) for k in range(len(STATE_NAMES))]
    assert np.all(np.diff(centres["front"]) > 0)
    assert np.all(np.diff(centres["back"]) < 0)


def test_earlier_step_shows_its_own_states(results, model, tmp_path):
    from helpers.damage_pattern import states_at

    img = iio.imread(render.render_step(results, step=1, view="front", out=tmp_path / "s1.png"))
    got = fractions(classify(img))
    want = expected_front_fractions(model, states_at(model, 1))
    assert got[2:].sum() == 0  # no rocking, sliding+rocking or detached yet
    np.testing.assert_allclose(got, want, atol=0.015)


@pytest.mark.slow
def test_oblique_and_side_views_show_damage(results, tmp_path):
    for view in ("oblique", "side"):
        code = classify(
            iio.imread(render.render_step(results, view=view, out=tmp_path / f"{view}.png"))
        )
        assert (code >= 0).sum() > 500, view


def test_auto_scale_makes_displacements_a_few_percent_of_the_wall():
    for disp in (1e-6, 3.3e-4, 0.02, 1.7):
        s = render.auto_scale(disp, 2.0)
        assert 0.05 <= s * disp / 2.0 <= 0.08
        assert float(f"{s:.2g}") == s  # a round number, as printed in the title
    assert render.auto_scale(0.0, 2.0) == 1.0


def test_scale_changes_the_picture(results, tmp_path):
    a = iio.imread(render.render_step(results, view="side", out=tmp_path / "a.png", scale=0.0))
    b = iio.imread(render.render_step(results, view="side", out=tmp_path / "b.png"))
    assert np.abs(a.astype(int) - b.astype(int)).max(axis=-1).astype(bool).mean() > 0.01


# --------------------------------------------------------------------------- animation
def test_animation_has_one_frame_per_step(results, tmp_path):
    out = render.render_animation(results, out=tmp_path / "anim.gif", window_size=(320, 240))
    frames = iio.imread(out, index=None)
    assert frames.shape[0] == 5
    assert frames.shape[1:3] == (240, 320)
    # the damage spreads: more non-green damage colour in the last frame than the first
    first, last = classify(frames[0]), classify(frames[-1])
    assert (first > 0).sum() == 0 and (last > 0).sum() > 100


def test_default_outputs_go_next_to_the_results_and_touch_nothing_else(results_copy):
    before = {p: p.stat().st_mtime_ns for p in results_copy.rglob("*")}
    png = render.render_step(results_copy, window_size=SMALL)
    gif = render.render_animation(results_copy, window_size=(200, 150))
    plot = render.plot_pushover(results_copy)
    assert png == results_copy / "render_oblique_0004.png"
    assert gif == results_copy / "animation_oblique.gif"
    assert plot == results_copy / "pushover.png"
    after = {p: p.stat().st_mtime_ns for p in results_copy.rglob("*")}
    assert set(after) - set(before) == {png, gif, plot}
    assert all(after[p] == t for p, t in before.items())


# --------------------------------------------------------------------------- bad input
def _listing(folder: Path) -> dict:
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")}


def test_missing_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        render.render_step(tmp_path / "nope")
    with pytest.raises(FileNotFoundError, match="not found"):
        render.plot_pushover(tmp_path / "nope")


def test_incomplete_folder(results_copy):
    (results_copy / "steps" / "blocks_0003.vtu").unlink()
    before = _listing(results_copy)
    with pytest.raises(FileNotFoundError, match="blocks_0003.vtu"):
        render.render_step(results_copy)
    (results_copy / "blocks.pvd").unlink()
    with pytest.raises(FileNotFoundError, match="blocks.pvd"):
        render.render_animation(results_copy)
    (results_copy / "pushover.csv").unlink()
    with pytest.raises(FileNotFoundError, match="pushover.csv"):
        render.plot_pushover(results_copy)
    del before[results_copy / "blocks.pvd"], before[results_copy / "pushover.csv"]
    assert _listing(results_copy) == before


def test_step_that_does_not_exist(results_copy):
    before = _listing(results_copy)
    for bad in (99, -1, "99", "latest", 2.5):
        with pytest.raises(ValueError, match="step"):
            render.render_step(results_copy, step=bad)
    assert _listing(results_copy) == before


def test_unknown_view_and_bad_arguments(results_copy, tmp_path):
    before = _listing(results_copy)
    with pytest.raises(ValueError, match="unknown view 'top'.*front, back, oblique, side"):
        render.render_step(results_copy, view="top")
    with pytest.raises(ValueError, match="unknown view"):
        render.render_animation(results_copy, view="top")
    with pytest.raises(ValueError, match="scale"):
        render.render_step(results_copy, scale=-2)
    with pytest.raises(ValueError, match="window_size"):
        render.render_step(results_copy, window_size=(10, 10))
    with pytest.raises(ValueError, match="fps"):
        render.render_animation(results_copy, fps=0)
    # an output that is not an image is refused, and the file it names is left alone
    target = results_copy / "steps" / "blocks_0000.vtu"
    with pytest.raises(ValueError, match=r"\.png"):
        render.render_step(results_copy, out=target)
    with pytest.raises(ValueError, match=r"\.gif"):
        render.render_animation(results_copy, out=results_copy / "summary.json")
    with pytest.raises(ValueError, match=r"\.png"):
        render.plot_pushover(results_copy, out=results_copy / "pushover.csv")
    assert _listing(results_copy) == before


# --------------------------------------------------------------------------- command line
def test_cli_render(results_copy):
    from masonry_dem.cli import main

    assert (
        main(
            [
                "render",
                str(results_copy),
                "--step",
                "2",
                "--view",
                "front",
                "--pushover",
                "--size",
                "300x200",
            ]
        )
        == 0
    )
    assert (results_copy / "render_front_0002.png").is_file()
    assert (results_copy / "pushover.png").is_file()
    assert (
        main(
            [
                "render",
                str(results_copy),
                "--animate",
                "--view",
                "side",
                "--size",
                "160x120",
                "--scale",
                "0",
            ]
        )
        == 0
    )
    assert (results_copy / "render_side_0004.png").is_file()
    assert iio.imread(results_copy / "animation_side.gif", index=None).shape[0] == 5


def test_cli_view_choices_are_the_presets():
    from masonry_dem.cli import render as cli_render

    assert cli_render.VIEW_CHOICES == tuple(render.VIEWS)


def test_cli_render_errors(results_copy, tmp_path, capsys):
    from masonry_dem.cli import main

    assert main(["render", str(tmp_path / "missing")]) == 2
    assert "not found" in capsys.readouterr().err
    assert main(["render", str(results_copy), "--step", "12"]) == 2
    assert "step 12 is not in" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["render", str(results_copy), "--view", "top"])


def test_side_by_side(results, tmp_path):
    out = render.render_side_by_side(
        [results, results, results],
        tmp_path / "sheet.png",
        view=["front", "side", "oblique"],
        columns=2,
        window_size=(200, 150),
    )
    img = iio.imread(out)
    assert img.shape[:2] == (300, 400)
    assert (classify(img[:150, :200]) >= 0).sum() > 100  # the front panel shows the damage
    assert np.all(img[150:, 200:] == 255)  # the empty fourth panel stays white
    with pytest.raises(ValueError, match="views"):
        render.render_side_by_side([results], tmp_path / "x.png", view=["front", "side"])
    with pytest.raises(ValueError, match=r"\.png"):
        render.render_side_by_side([results], tmp_path / "x.gif")
