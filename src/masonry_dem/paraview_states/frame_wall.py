"""Frame a masonry_dem ParaView state to the wall it shows: every Warp By Vector scaled from the
data, every render view's camera reset to the data (a front view of walls that meet turned
oblique, so the returns show), the title naming the case and its method (from the folder's
summary.json).

The shipped states (``*.pvsm``) were made from a sample wall. Each holds this file's
:func:`frame` in a Python animation cue: the first time the animation moves
(*Last Frame* in the GUI, ``GetAnimationScene().GoToLast()`` in a script, or *Play*) it frames
the state to the wall loaded. To frame at any other moment, or a state without the cue, run
this file:

* GUI: *Macros > Import new macro...*, choose this file (once); after *File > Load State*, click
  ``frame_wall`` in the Macros toolbar;
* pvpython / pvbatch: ``pvbatch frame_wall.py STATE.pvsm RESULTS_FOLDER [OUT.png]`` loads the
  state against the folder, frames it and optionally saves a screenshot; or, in a script after
  ``LoadState``: ``exec(open("src/masonry_dem/paraview_states/frame_wall.py").read())``.

The warp scale is the one of the package's own pictures (``masonry_dem.export.scene
.auto_scale``): a round number (two significant figures, rounded down) making the largest
displacement of the last time step about 6.5 % of the wall's largest dimension.
"""

import json
import math
import os
import sys
import textwrap

import paraview.simple as pvs

#: largest displacement / largest wall dimension (masonry_dem.export.scene.AUTO_SCALE_TARGET)
AUTO_SCALE_TARGET = 0.065
#: a wall at least this deep (e3) for its width or height has walls that meet (returns, a
#: U or L plan): a view along e3 hides them, so it turns to the oblique view
DEEP_SHARE = 0.25
#: the states' oblique view: from the front right, above (make_states.py)
OBLIQUE = (7.5, 5.5, 10.0)


def auto_scale(max_displacement, wall_size):
    """The package's automatic amplification; 1 when nothing moves."""
    if not (max_displacement > 0 and math.isfinite(max_displacement)) or wall_size <= 0:
        return 1.0
    raw = AUTO_SCALE_TARGET * wall_size / max_displacement
    mag = 10.0 ** (math.floor(math.log10(raw)) - 1)
    return float(math.floor(raw / mag) * mag)


def _last_time():
    times = list(pvs.GetTimeKeeper().TimestepValues)
    return max(times) if times else 0.0


def _warp_filters():
    return [src for src in pvs.GetSources().values() if src.GetXMLName() == "WarpVector"]


def _data_bounds(t):
    """(xmin, xmax, ymin, ymax, zmin, zmax) of everything the state reads, at time ``t``."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for src in pvs.GetSources().values():
        if getattr(src, "FileName", None) is None:
            continue
        src.UpdatePipeline(t)
        b = src.GetDataInformation().GetBounds()
        for k in range(3):
            if b[2 * k] <= b[2 * k + 1]:
                lo[k], hi[k] = min(lo[k], b[2 * k]), max(hi[k], b[2 * k + 1])
    return None if lo[0] == math.inf else (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])


def _turn_oblique_where_walls_meet(view, bounds):
    """A view along e3 of walls that meet (deeper than :data:`DEEP_SHARE` of their width or
    height) turns to the oblique view, in perspective: the front elevation hides the returns
    behind the facade."""
    if bounds is None:
        return
    width, height, depth = (bounds[2 * k + 1] - bounds[2 * k] for k in range(3))
    if depth < DEEP_SHARE * max(width, height):
        return
    pos, focal = list(view.CameraPosition), list(view.CameraFocalPoint)
    direction = [p - f for p, f in zip(pos, focal, strict=True)]
    norm = math.sqrt(sum(d * d for d in direction)) or 1.0
    if abs(direction[2]) < 0.99 * norm:  # not along e3: already shows the depth
        return
    side = 1.0 if direction[2] > 0 else -1.0
    dx, dy, dz = OBLIQUE
    view.CameraPosition = [focal[0] + dx, focal[1] + dy, focal[2] + side * dz]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelProjection = 0


def frame(time=None, set_time=True):
    """Set every Warp By Vector's scale from the data at ``time`` (default: the last time
    step), then reset every render view's camera to what it shows (at that time when
    ``set_time``, else at the view's own time: the animation cue, which must not move the
    time). One scale for the whole state, from the largest displacement and the largest
    dimension of all the warped inputs (the blocks), so blocks and joints move together.
    Returns the scales set."""
    t = _last_time() if time is None else time
    warps = _warp_filters()
    size = dmax = 0.0
    for warp in warps:
        source = warp.Input
        source.UpdatePipeline(t)
        b = source.GetDataInformation().GetBounds()
        size = max(size, b[1] - b[0], b[3] - b[2], b[5] - b[4])
        array = source.PointData.GetArray("displacement")
        if array is not None:
            dmax = max(dmax, array.GetRange(-1)[1])
    scale = auto_scale(dmax, size)
    for warp in warps:
        warp.ScaleFactor = scale
    name_case()
    bounds = _data_bounds(t)
    for view in pvs.GetViews():
        if view.GetXMLName() != "RenderView":
            continue
        if set_time:
            view.ViewTime = t
        _turn_oblique_where_walls_meet(view, bounds)
        view.ResetCamera(False)
        pvs.Render(view)
    return [scale] * len(warps)


def _results_folder():
    """The folder of the data the state reads (its first reader's file), or None."""
    for src in pvs.GetSources().values():
        name = getattr(src, "FileName", None)
        if name is None:
            continue
        name = name if isinstance(name, str) else (list(name) or [""])[0]
        if name:
            return os.path.dirname(str(name))
    return None


def case_title():
    """The title's first line: the case's name and the method that made the results, from
    the folder's summary.json (as the package's own pictures name them); None without one."""
    folder = _results_folder()
    try:
        with open(os.path.join(folder or "", "summary.json")) as fh:
            summary = json.load(fh)
    except (OSError, ValueError):
        return None
    name = str(summary.get("name") or os.path.basename(folder or ""))
    method = summary.get("method")
    # the names of masonry_dem.export.figure_text.method_of (ParaView's Python may not
    # import the package)
    if summary.get("analysis") == "limit":
        made = (
            f"limit analysis ({method}, rigid blocks)"
            if method
            else "limit analysis (rigid blocks)"
        )
    elif method == "dynamic_relaxation":
        made = "pushover by dynamic relaxation"
    else:
        made = "static pushover (Newton, load/displacement control)"
    # wrapped as masonry_dem.export.paraview_state.TITLE_WIDTH: a Text source does not wrap
    return textwrap.fill(f"{name}: {made}", 100)


def name_case():
    """Put :func:`case_title` on the first line of every title (the states' Text sources)."""
    title = case_title()
    if title is None:
        return
    for (name, _), src in pvs.GetSources().items():
        if name.startswith("title: "):
            what = src.Text.split("\n")[-1]
            src.Text = f"{title}\n{what}"


def load(state, results_folder):
    """LoadState against ``results_folder`` (the README's recipe), go to the last time step,
    frame."""
    pvs.LoadState(state, data_directory=results_folder, restrict_to_data_directory=True)
    scene = pvs.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.GoToLast()
    return frame()


#: the animation cue's callbacks (make_states.py embeds this file, up to the main block, in
#: every state): frame once when the animation starts, keeping the time it is at
def start_cue(self):
    frame(set_time=False)


def tick(self):
    pass


def end_cue(self):
    pass


if __name__ == "__main__":
    if len(sys.argv) >= 3:  # pvbatch frame_wall.py STATE RESULTS [OUT.png]
        load(sys.argv[1], sys.argv[2])
        if len(sys.argv) >= 4:
            pvs.SaveScreenshot(sys.argv[3], pvs.GetLayout(), ImageResolution=[1200, 900])
    else:  # a GUI macro, or exec() after LoadState
        frame()
