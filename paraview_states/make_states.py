"""Regenerate the ParaView state files of masonry_dem.

    python paraview_states/make_states.py            # needs pvbatch and xvfb-run

With the project's Python this script writes a small sample results folder, runs itself under
``xvfb-run -a pvbatch`` to build the states from it, replaces the sample folder's path in them by
the placeholder ``/path/to/your/results`` and writes each state twice: here
(``paraview_states/*.pvsm``, the copy users open) and in ``src/masonry_dem/paraview_states/``
(the identical copy the package ships; a test checks they are the same).

States (all time-aware: the PVD readers give ParaView every step, the animation snaps to them):

* ``damage_map.pvsm``: front elevation; blocks light with grey outlines, every interface drawn
  as lines coloured by ``state`` through a categorical lookup table with the colours of the
  pyvista renders (green elastic, red sliding, magenta rocking, orange sliding+rocking, blue
  detached); lambda annotated.
* ``deformed_shape.pvsm``: oblique view; blocks and interfaces through Warp By Vector on
  ``displacement`` (sources ``warp blocks`` and ``warp interfaces``; set their ScaleFactor),
  interface lines coloured by state.
* ``force_view.pvsm``: two front views side by side: interface ``normal_force`` (diverging map,
  compression blue) and ``utilisation`` (0..1).
* ``mechanism.pvsm``: oblique view of the collapse mechanism (``mechanism_blocks.vtu`` and
  ``mechanism_interfaces.vtu``, one mode, no time steps): blocks and interfaces through Warp By
  Vector on ``displacement`` (the mode; sources ``warp blocks`` and ``warp interfaces``), blocks
  plain, interface lines coloured by ``joint_motion`` through a 4-colour step lookup table equal
  to the pyvista mechanism picture's bins and colours (``MECHANISM_BINS``/``MECHANISM_COLOURS``).

Every state also holds ``frame_wall.py`` (up to its main block; the one file of it is the
package's, ``src/masonry_dem/paraview_states/frame_wall.py``) as a Python animation cue, so
that it frames the wall it is loaded against (warp scale from the data, cameras reset) when the
animation first moves.

Under pvbatch (internal use): ``pvbatch make_states.py --build DATA OUTDIR COLOURS_JSON``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

PLACEHOLDER = "/path/to/your/results"
#: the title's first line in the shipped states: the case's name replaces it (frame_wall.py when
#: the state frames itself, copy_state when it copies one)
CASE_PLACEHOLDER = "masonry_dem: the case's name is read from summary.json"  # = paraview_state's
STATES = ("damage_map", "deformed_shape", "force_view", "mechanism")
#: width of the ramp before each bin edge of the mechanism lookup table (a colour transfer
#: function cannot hold two colours at one value): joint_motion >= edge gets the upper colour
STEP = 1e-6
HERE = Path(__file__).resolve().parent
PACKAGE_COPY = HERE.parent / "src" / "masonry_dem" / "paraview_states"


# =========================================================================== pvbatch side
def _build(data: str, outdir: str, colours_json: str) -> None:  # pragma: no cover - pvbatch
    import paraview.simple as pvs

    spec = json.loads(colours_json)
    names, colours = spec["names"], spec["colours"]
    block_rgb = [c / 255 for c in spec["block"]]
    support_rgb = [c / 255 for c in spec["support"]]

    def state_lut():
        lut = pvs.GetColorTransferFunction("state")
        lut.InterpretValuesAsCategories = 1
        lut.AnnotationsInitialized = 1
        ann, rgb = [], []
        for code, (name, col) in enumerate(zip(names, colours, strict=True)):
            ann += [str(code), name]
            rgb += [c / 255 for c in col]
        lut.Annotations = ann
        lut.IndexedColors = rgb
        lut.IndexedOpacities = [1.0] * len(names)
        return lut

    def fixed_lut():
        lut = pvs.GetColorTransferFunction("fixed")
        lut.InterpretValuesAsCategories = 1
        lut.AnnotationsInitialized = 1
        lut.Annotations = ["0", "block", "1", "support"]
        lut.IndexedColors = block_rgb + support_rgb
        lut.IndexedOpacities = [1.0, 1.0]
        return lut

    def new_view(size=(1200, 900), axes=False):
        view = pvs.CreateView("RenderView")
        view.ViewSize = list(size)
        view.UseColorPaletteForBackground = 0
        view.Background = [1.0, 1.0, 1.0]
        view.OrientationAxesVisibility = 1 if axes else 0
        view.OrientationAxesLabelColor = [0.0, 0.0, 0.0]
        return view

    def front(view):
        view.CameraPosition = [0.0, 0.0, 10.0]
        view.CameraFocalPoint = [0.0, 0.0, 0.0]
        view.CameraViewUp = [0.0, 1.0, 0.0]
        view.CameraParallelProjection = 1
        view.ResetCamera(False)

    def oblique(view):
        view.CameraPosition = [7.5, 5.5, 10.0]
        view.CameraFocalPoint = [0.0, 0.0, 0.0]
        view.CameraViewUp = [0.0, 1.0, 0.0]
        view.CameraParallelProjection = 0
        view.ResetCamera(False)

    def blocks_display(src, view, outlines=True):
        d = pvs.Show(src, view)
        d.Representation = "Surface With Edges" if outlines else "Surface"
        pvs.ColorBy(d, ("CELLS", "fixed"))
        d.LookupTable = fixed_lut()
        d.SetScalarBarVisibility(view, False)
        d.EdgeColor = [0.45, 0.45, 0.45]
        d.Ambient = 0.3
        d.Diffuse = 0.7
        return d

    def lines_display(src, view, array, lut, width=4.0):
        """Interfaces as lines: an interface seen edge-on (head and bed joints in a front
        view) is still visible, and flat colours (no lighting) keep the legend's colours."""
        d = pvs.Show(src, view)
        d.Representation = "Wireframe"
        pvs.ColorBy(d, ("CELLS", array))
        d.LookupTable = lut
        d.LineWidth = width
        d.Ambient = 1.0
        d.Diffuse = 0.0
        d.Specular = 0.0
        d.SetScalarBarVisibility(view, True)
        return d

    def scalar_bar(lut, view, title):
        bar = pvs.GetScalarBar(lut, view)
        bar.Title = title
        bar.ComponentTitle = ""
        bar.TitleColor = [0.0, 0.0, 0.0]
        bar.LabelColor = [0.0, 0.0, 0.0]
        bar.WindowLocation = "Upper Right Corner"
        bar.TitleFontSize = 12
        bar.LabelFontSize = 11
        bar.ScalarBarLength = 0.3
        return bar

    def annotate(view, text):
        """The title: the case's name (its first line, filled in from summary.json by
        frame_wall.py and by copy_state) over what the state shows."""
        src = pvs.Text(registrationName="title: " + text[:20])
        src.Text = f"{spec['case_placeholder']}\n{text}"
        d = pvs.Show(src, view)
        d.WindowLocation = "Upper Left Corner"
        d.Color = [0.0, 0.0, 0.0]
        d.FontSize = 12
        return d

    def step_labels(source, view, prefix=""):
        """lambda and the step as two named quantities (the files' field data): the PVD's
        time is lambda only while lambda rises, the step number after."""
        for array, label, fmt, where in (
            ("lambda", "lambda = ", "%.4g", "Lower Left Corner"),
            ("step", "step ", "%d", "Lower Right Corner"),
        ):
            src = pvs.AnnotateGlobalData(registrationName=prefix + array, Input=source)
            src.SelectArrays = array
            src.Prefix = label
            src.Format = fmt
            d = pvs.Show(src, view)
            d.WindowLocation = where
            d.Color = [0.0, 0.0, 0.0]
            d.FontSize = 12

    def length_scale(view):
        """Axes with ticks in metres along the wall: the picture's length scale."""
        grid = view.AxesGrid
        grid.Visibility = 1
        grid.AxesToLabel = 1 | 2  # the left and the bottom edge: the title keeps the top
        grid.XTitle, grid.YTitle, grid.ZTitle = "e1 [m]", "e2 [m]", "e3 [m]"
        for axis in ("X", "Y", "Z"):
            setattr(grid, f"{axis}TitleColor", [0.0, 0.0, 0.0])
            setattr(grid, f"{axis}LabelColor", [0.0, 0.0, 0.0])
        grid.GridColor = [0.3, 0.3, 0.3]

    def readers():
        blocks = pvs.PVDReader(registrationName="blocks.pvd", FileName=f"{data}/blocks.pvd")
        interfaces = pvs.PVDReader(
            registrationName="interfaces.pvd", FileName=f"{data}/interfaces.pvd"
        )
        blocks.CellArrays = ["block_id", "translation", "rotation", "fixed"]
        blocks.PointArrays = ["displacement"]
        return blocks, interfaces

    def warped(blocks, interfaces, scale):
        """Warp By Vector on ``displacement`` of both meshes, by ``scale``."""
        out = []
        for name, src in (("warp blocks", blocks), ("warp interfaces", interfaces)):
            warp = pvs.WarpByVector(registrationName=name, Input=src)
            warp.Vectors = ["POINTS", "displacement"]
            warp.ScaleFactor = scale
            out.append(warp)
        return out

    def time_aware():
        scene = pvs.GetAnimationScene()
        scene.UpdateAnimationUsingDataTimeSteps()
        scene.PlayMode = "Snap To TimeSteps"
        scene.GoToLast()

    def reset():
        pvs.ResetSession()

    def framing_cue():
        """A Python animation cue running frame_wall.py's frame() when the animation starts:
        the state frames whatever wall it is loaded against (warp scale, cameras)."""
        cue = pvs.PythonAnimationCue()
        cue.Script = spec["frame_script"]
        pvs.GetAnimationScene().Cues.append(cue)
        return cue

    def save(name):
        framing_cue()
        pvs.SaveState(os.path.join(outdir, name))

    # ------------------------------------------------------------------ damage map
    reset()
    blocks, interfaces = readers()
    layout = pvs.CreateLayout("damage map")
    view = new_view()
    pvs.AssignViewToLayout(view=view, layout=layout, hint=0)
    blocks_display(blocks, view)
    lut = state_lut()
    lines_display(interfaces, view, "state", lut)
    scalar_bar(lut, view, "interface state")
    annotate(view, "damage map: interface states")
    step_labels(blocks, view)
    length_scale(view)
    front(view)
    time_aware()
    save("damage_map.pvsm")

    # ------------------------------------------------------------------ deformed shape
    reset()
    blocks, interfaces = readers()
    layout = pvs.CreateLayout("deformed shape")
    view = new_view(axes=True)
    pvs.AssignViewToLayout(view=view, layout=layout, hint=0)
    wb, wi = warped(blocks, interfaces, float(spec["scale"]))
    blocks_display(wb, view, outlines=True)
    lut = state_lut()
    lines_display(wi, view, "state", lut, width=3.0)
    scalar_bar(lut, view, "interface state")
    annotate(view, "deformed shape (Warp By Vector: displacement)")
    step_labels(blocks, view)
    oblique(view)
    time_aware()
    save("deformed_shape.pvsm")

    # ------------------------------------------------------------------ forces
    reset()
    blocks, interfaces = readers()
    layout = pvs.CreateLayout("forces")
    left, right = new_view((1200, 450)), new_view((1200, 450))
    pvs.AssignViewToLayout(view=left, layout=layout, hint=0)
    layout.SplitVertical(0, 0.5)
    pvs.AssignViewToLayout(view=right, layout=layout, hint=2)
    for view, array, title, preset in (
        (left, "normal_force", "normal force [N]", "Cool to Warm"),
        (right, "utilisation", "utilisation", "Inferno (matplotlib)"),
    ):
        d = pvs.Show(blocks, view)
        d.Representation = "Wireframe"
        d.ColorArrayName = ["POINTS", ""]
        d.AmbientColor = [0.8, 0.8, 0.8]
        d.DiffuseColor = [0.8, 0.8, 0.8]
        lut = pvs.GetColorTransferFunction(array)
        lut.ApplyPreset(preset, True)
        lines_display(interfaces, view, array, lut)
        if array == "utilisation":
            lut.RescaleTransferFunction(0.0, 1.0)
            lut.AutomaticRescaleRangeMode = "Never"
        else:
            lut.AutomaticRescaleRangeMode = "Grow and update every timestep"
        scalar_bar(lut, view, title)
        annotate(view, f"interface {title}")
        step_labels(blocks, view, prefix=f"{array}: ")
        front(view)
    pvs.AddCameraLink(left, right, "forces camera")
    time_aware()
    save("force_view.pvsm")
    pvs.RemoveCameraLink("forces camera")  # links outlive ResetSession: keep it out of the next

    # ------------------------------------------------------------------ mechanism
    reset()
    mblocks = pvs.XMLUnstructuredGridReader(
        registrationName="mechanism_blocks.vtu", FileName=[f"{data}/mechanism_blocks.vtu"]
    )
    minterfaces = pvs.XMLUnstructuredGridReader(
        registrationName="mechanism_interfaces.vtu",
        FileName=[f"{data}/mechanism_interfaces.vtu"],
    )
    layout = pvs.CreateLayout("mechanism")
    view = new_view(axes=True)
    pvs.AssignViewToLayout(view=view, layout=layout, hint=0)
    wb, wi = warped(mblocks, minterfaces, float(spec["mechanism_scale"]))
    blocks_display(wb, view, outlines=True)
    lut = pvs.GetColorTransferFunction("joint_motion")
    lines_display(wi, view, "joint_motion", lut, width=4.0)
    # a step function: bin k (edges 0, *bins, 1) in colour k, as render_mechanism's
    # searchsorted(bins, motion, side="right"); fixed range 0..1 (joint_motion / largest)
    edges = [0.0, *spec["mechanism_bins"], 1.0]
    points = []
    for k, col in enumerate(spec["mechanism_colours"]):
        rgb = [c / 255 for c in col]
        upper = edges[k + 1] - (STEP if k + 2 < len(edges) else 0.0)
        points += [edges[k], *rgb, upper, *rgb]
    lut.Discretize = 0
    lut.ColorSpace = "RGB"
    lut.RGBPoints = points
    lut.ScalarRangeInitialized = 1.0
    lut.AutomaticRescaleRangeMode = "Never"
    bar = scalar_bar(lut, view, "joint motion / largest")
    bar.AutomaticLabelFormat = 0
    bar.LabelFormat = "%-#.2f"
    bar.RangeLabelFormat = "%-#.2f"
    bar.UseCustomLabels = 1
    bar.CustomLabels = list(spec["mechanism_bins"])
    bar.AddRangeLabels = 1
    annotate(view, "collapse mechanism: joints by relative motion in the mode")
    step_labels(mblocks, view)
    oblique(view)
    save("mechanism.pvsm")


# =========================================================================== driver side
def _sample_results(folder: Path) -> tuple[float, float]:
    """A 6 x 6 running-bond wall, 4 steps, every damage state present, and a collapse
    mechanism (the wall overturning out of plane about its base, its top three courses
    turning further about the joint below them); returns the warp scales of the last step
    and of the mechanism."""
    import numpy as np

    from masonry_dem.export.render import auto_scale
    from masonry_dem.export.vtu import rigid_motion, write_mechanism_vtu
    from masonry_dem.export.writer import ResultsWriter
    from masonry_dem.geometry.builders import add_base, running_bond_wall
    from masonry_dem.model import InterfaceMaterial, Model, SelfWeight, Support, WeightProportional
    from masonry_dem.results import History, StepResult
    from masonry_dem.solvers.linear import solve_linear

    blocks = running_bond_wall(6, 6, a=0.1, b=0.2, s=0.1, unit_weight=20e3)
    blocks, base = add_base(blocks)
    model = Model.build(
        blocks,
        InterfaceMaterial(kn=2e9, kt=8e8, friction=0.6),
        supports=[Support(np.array([base]))],
        loads=[SelfWeight(), WeightProportional((0.0, 0.0, 1.0))],
        name="sample",
    )
    lin = solve_linear(model)
    code = np.arange(model.interfaces.count) % 5
    hist = History(status="completed")
    writer = ResultsWriter(folder, model)
    for k in range(4):
        lam = 0.1 * (k + 1)
        step = StepResult(
            k,
            lam,
            lin.q * lam,
            lin.actions * lam,
            np.where(code <= k, code, 0).astype(np.int32),
            np.full(model.interfaces.count, 0.25 * (k + 1)),
        )
        hist.steps.append(step)
        writer(step)
    writer.finish(hist)
    corners = model.blocks.corner_points()
    disp = rigid_motion(hist.last.q, model.blocks.centres, corners)
    size = float(np.max(model.blocks.upper.max(axis=0) - model.blocks.lower.min(axis=0)))
    scale = auto_scale(float(np.linalg.norm(disp, axis=2).max()), size)

    # the mechanism: rotations about e1 (out of plane) about the base's and mid-height's front
    centres, lower, upper = model.blocks.centres, model.blocks.lower, model.blocks.upper
    moving = ~model.fixed.all(axis=1)
    y_base = float(upper[~moving, 1].max())
    y_mid = float(np.median(lower[moving, 1]))
    z_front = float(upper[:, 2].max())
    mode = np.zeros((model.blocks.count, 6))
    for pivot_y, turn, sel in (
        (y_base, 1.0, moving),
        (y_mid, 0.6, moving & (lower[:, 1] >= y_mid - 1e-9)),
    ):
        w = np.array([-turn, 0.0, 0.0])
        arm = centres[sel] - np.array([0.0, pivot_y, z_front])
        mode[sel, :3] += np.cross(w, arm)
        mode[sel, 3:] += w
    mode /= np.linalg.norm(mode[:, :3], axis=1).max()
    write_mechanism_vtu(folder, model, hist.last, mode, None)
    mdisp = rigid_motion(mode, centres, corners)
    return scale, auto_scale(float(np.linalg.norm(mdisp, axis=2).max()), size)


def frame_script() -> str:
    """frame_wall.py up to its main block: frame() and the cue's callbacks."""
    text = (PACKAGE_COPY / "frame_wall.py").read_text()
    return text.split('\nif __name__ == "__main__":')[0] + "\n"


def main() -> int:
    from masonry_dem.export.render import (
        BLOCK_COLOUR,
        MECHANISM_BINS,
        MECHANISM_COLOURS,
        STATE_COLOURS,
        SUPPORT_COLOUR,
    )
    from masonry_dem.results import STATE_NAMES

    for tool in ("pvbatch", "xvfb-run"):
        if shutil.which(tool) is None:
            print(f"make_states: {tool} not found (apt-get install paraview xvfb)", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "sample"
        scale, mechanism_scale = _sample_results(data)
        out = Path(tmp) / "states"
        out.mkdir()
        spec = json.dumps(
            {
                "names": list(STATE_NAMES),
                "colours": [list(c) for c in STATE_COLOURS],
                "block": list(BLOCK_COLOUR),
                "support": list(SUPPORT_COLOUR),
                "scale": scale,
                "mechanism_bins": list(MECHANISM_BINS),
                "mechanism_colours": [list(c) for c in MECHANISM_COLOURS],
                "mechanism_scale": mechanism_scale,
                "frame_script": frame_script(),
                "case_placeholder": CASE_PLACEHOLDER,
            }
        )
        proc = subprocess.run(
            [
                "xvfb-run",
                "-a",
                "pvbatch",
                str(Path(__file__).resolve()),
                "--build",
                str(data),
                str(out),
                spec,
            ],
            capture_output=True,
            text=True,
        )
        if proc.returncode != 0:
            print(proc.stdout, proc.stderr, sep="\n", file=sys.stderr)
            return proc.returncode
        for name in STATES:
            text = (out / f"{name}.pvsm").read_text()
            text = text.replace(str(data), PLACEHOLDER)
            for target in (HERE / f"{name}.pvsm", PACKAGE_COPY / f"{name}.pvsm"):
                target.write_text(text)
                print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "--build":
        _build(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        sys.exit(main())
