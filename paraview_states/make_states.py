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
STATES = ("damage_map", "deformed_shape", "force_view")
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

    def annotate(view, text, time=False):
        if time:
            src = pvs.AnnotateTime(registrationName="lambda")
            src.Format = "lambda (or step) = {time:.4g}"
        else:
            src = pvs.Text(registrationName="title: " + text[:20])
            src.Text = text
        d = pvs.Show(src, view)
        d.WindowLocation = "Lower Left Corner" if time else "Upper Left Corner"
        d.Color = [0.0, 0.0, 0.0]
        d.FontSize = 12
        return d

    def readers():
        blocks = pvs.PVDReader(registrationName="blocks.pvd", FileName=f"{data}/blocks.pvd")
        interfaces = pvs.PVDReader(
            registrationName="interfaces.pvd", FileName=f"{data}/interfaces.pvd"
        )
        blocks.CellArrays = ["block_id", "translation", "rotation", "fixed"]
        blocks.PointArrays = ["displacement"]
        return blocks, interfaces

    def time_aware():
        scene = pvs.GetAnimationScene()
        scene.UpdateAnimationUsingDataTimeSteps()
        scene.PlayMode = "Snap To TimeSteps"
        scene.GoToLast()

    def reset():
        pvs.ResetSession()

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
    annotate(view, "masonry_dem damage map: interface states")
    annotate(view, "", time=True)
    front(view)
    time_aware()
    pvs.SaveState(os.path.join(outdir, "damage_map.pvsm"))

    # ------------------------------------------------------------------ deformed shape
    reset()
    blocks, interfaces = readers()
    layout = pvs.CreateLayout("deformed shape")
    view = new_view(axes=True)
    pvs.AssignViewToLayout(view=view, layout=layout, hint=0)
    wb = pvs.WarpByVector(registrationName="warp blocks", Input=blocks)
    wb.Vectors = ["POINTS", "displacement"]
    wb.ScaleFactor = float(spec["scale"])
    wi = pvs.WarpByVector(registrationName="warp interfaces", Input=interfaces)
    wi.Vectors = ["POINTS", "displacement"]
    wi.ScaleFactor = float(spec["scale"])
    blocks_display(wb, view, outlines=True)
    lut = state_lut()
    lines_display(wi, view, "state", lut, width=3.0)
    scalar_bar(lut, view, "interface state")
    annotate(view, "masonry_dem deformed shape (Warp By Vector: displacement)")
    annotate(view, "", time=True)
    oblique(view)
    time_aware()
    pvs.SaveState(os.path.join(outdir, "deformed_shape.pvsm"))

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
        annotate(view, f"masonry_dem interface {title}")
        annotate(view, "", time=True)
        front(view)
    pvs.AddCameraLink(left, right, "forces camera")
    time_aware()
    pvs.SaveState(os.path.join(outdir, "force_view.pvsm"))


# =========================================================================== driver side
def _sample_results(folder: Path) -> float:
    """A 6 x 6 running-bond wall, 4 steps, every damage state present; returns a warp scale."""
    import numpy as np

    from masonry_dem.export.render import auto_scale
    from masonry_dem.export.vtu import rigid_motion
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
    disp = rigid_motion(hist.last.q, model.blocks.centres, model.blocks.corner_points())
    size = float(np.max(model.blocks.upper.max(axis=0) - model.blocks.lower.min(axis=0)))
    return auto_scale(float(np.linalg.norm(disp, axis=2).max()), size)


def main() -> int:
    from masonry_dem.export.render import BLOCK_COLOUR, STATE_COLOURS, SUPPORT_COLOUR
    from masonry_dem.results import STATE_NAMES

    for tool in ("pvbatch", "xvfb-run"):
        if shutil.which(tool) is None:
            print(f"make_states: {tool} not found (apt-get install paraview xvfb)", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "sample"
        scale = _sample_results(data)
        out = Path(tmp) / "states"
        out.mkdir()
        spec = json.dumps(
            {
                "names": list(STATE_NAMES),
                "colours": [list(c) for c in STATE_COLOURS],
                "block": list(BLOCK_COLOUR),
                "support": list(SUPPORT_COLOUR),
                "scale": scale,
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
        PACKAGE_COPY.mkdir(parents=True, exist_ok=True)
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
