"""Run under ``xvfb-run -a pvbatch`` by test_paraview.py (ParaView's own Python).

pvbatch pvbatch_check.py state STATE.pvsm DATA_DIR|- OUT.png [reset]
    LoadState (with data_directory=DATA_DIR, or the file names stored in the state when
    DATA_DIR is "-"), go to the last time step, optionally reset the cameras, save a
    screenshot of the layout; print a JSON line with the time steps, the sources, the text
    every label shows and whether each view draws its axes grid.
pvbatch pvbatch_check.py states JOBS.json
    the same for a list of jobs [[state, data_dir, out, reset], ...] in one ParaView
    session (reset between jobs); prints a JSON list.
pvbatch pvbatch_check.py frame FRAME_WALL.py JOBS.json
    for each job [state, data_dir, out_prefix, how]: load the state by the README's recipe
    (LoadState with data_directory, then the last time step: the state's own cue frames it;
    how = "recipe") or by the package's frame_wall.py (how = "macro"), hide the 2D overlays (titles, time, scalar
    bars, orientation axes: they do not move with the camera), save one screenshot per
    render view (out_prefix_<k>.png); prints a JSON list of {scales, images, directions} (each
    view's unit vector from its focal point to the camera).
pvbatch pvbatch_check.py pvd FILE.pvd [FILE.pvd ...]
    open each PVD and print a JSON line {file: {timesteps, cells, arrays}}.
"""

import json
import sys

import paraview.simple as pvs


def state(path, data_dir, out, reset):
    print("RESULT " + json.dumps(_state(path, data_dir, out, reset)))


def states(jobs_file):
    with open(jobs_file) as fh:
        jobs = json.load(fh)
    results = []
    for path, data_dir, out, reset in jobs:
        pvs.ResetSession()
        results.append(_state(path, data_dir, out, reset))
    print("RESULT " + json.dumps(results))


def _state(path, data_dir, out, reset):
    if data_dir == "-":
        pvs.LoadState(path)
    else:
        pvs.LoadState(path, data_directory=data_dir, restrict_to_data_directory=True)
    scene = pvs.GetAnimationScene()
    scene.GoToLast()
    layout = pvs.GetLayouts()
    layout = list(layout.values())[0]
    views = [v for v in pvs.GetViews() if v.GetXMLName() == "RenderView"]
    if reset:
        for v in views:
            v.ResetCamera(False)
    files = {}
    for (name, _), src in pvs.GetSources().items():
        if hasattr(src, "FileName"):
            name_ = src.FileName  # a string (PVD reader) or a list (XML VTU reader)
            if not isinstance(name_, str):
                name_ = [str(f) for f in name_]
                name_ = name_[0] if len(name_) == 1 else name_
            files[name] = name_
    pvs.SaveScreenshot(out, layout, ImageResolution=[1200, 900])
    return {
        "labels": _labels(),
        "axes_grids": [int(v.AxesGrid.Visibility) for v in views],
        "timesteps": list(pvs.GetTimeKeeper().TimestepValues),
        "time": views[0].ViewTime if views else None,
        "end_time": scene.EndTime,
        "files": files,
        "views": len(views),
        "sources": sorted(name for (name, _) in pvs.GetSources()),
    }


def _labels():
    """The text every text source shows now: {registration name: text} (a Text source's own
    text; an Annotate Global Data filter's output at the current time)."""
    from paraview import servermanager

    out = {}
    for (name, _), src in pvs.GetSources().items():
        kind = src.GetXMLName()
        if kind == "TextSource":
            out[name] = src.Text
        elif kind == "AnnotateGlobalData":
            table = servermanager.Fetch(src)
            out[name] = table.GetValue(0, 0).ToString() if table.GetNumberOfRows() else ""
    return out


def frame(frame_wall_py, jobs_file):
    import importlib.util

    spec = importlib.util.spec_from_file_location("frame_wall", frame_wall_py)
    frame_wall = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(frame_wall)
    with open(jobs_file) as fh:
        jobs = json.load(fh)
    results = []
    for path, data_dir, prefix, how in jobs:
        pvs.ResetSession()
        if how == "macro":
            scales = frame_wall.load(path, data_dir)
        else:  # the README's recipe alone: the state's own cue frames it
            pvs.LoadState(path, data_directory=data_dir, restrict_to_data_directory=True)
            pvs.GetAnimationScene().GoToLast()
            scales = [
                float(s.ScaleFactor)
                for s in pvs.GetSources().values()
                if s.GetXMLName() == "WarpVector"
            ]
        images = []
        views = [v for v in pvs.GetViews() if v.GetXMLName() == "RenderView"]
        for k, view in enumerate(views):
            view.OrientationAxesVisibility = 0
            for rep in view.Representations:
                if "WindowLocation" in rep.ListProperties():  # text and scalar bars
                    rep.Visibility = 0
            out = f"{prefix}_{k}.png"
            pvs.SaveScreenshot(out, view)
            images.append(out)
        directions = []
        for view in views:
            d = [p - f for p, f in zip(view.CameraPosition, view.CameraFocalPoint, strict=True)]
            norm = sum(x * x for x in d) ** 0.5 or 1.0
            directions.append([x / norm for x in d])
        results.append({"scales": scales, "images": images, "directions": directions})
    print("RESULT " + json.dumps(results))


def pvd(paths):
    out = {}
    for path in paths:
        reader = pvs.PVDReader(FileName=path)
        reader.UpdatePipelineInformation()
        times = list(reader.TimestepValues)
        reader.UpdatePipeline(times[-1] if times else 0.0)
        out[path] = {
            "timesteps": times,
            "cells": reader.GetDataInformation().GetNumberOfCells(),
            "cell_arrays": sorted(reader.CellData.keys()),
            "point_arrays": sorted(reader.PointData.keys()),
        }
    print("RESULT " + json.dumps(out))


if __name__ == "__main__":
    if sys.argv[1] == "state":
        state(sys.argv[2], sys.argv[3], sys.argv[4], len(sys.argv) > 5 and sys.argv[5] == "reset")
    elif sys.argv[1] == "states":
        states(sys.argv[2])
    elif sys.argv[1] == "frame":
        frame(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "pvd":
        pvd(sys.argv[2:])
    else:
        sys.exit(f"unknown mode {sys.argv[1]!r}")
