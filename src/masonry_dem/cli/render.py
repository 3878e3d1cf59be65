"""``masonry-dem render RESULTS``: PNG of a step (and optionally the animation and the pushover
curve) written next to the results.

Renders off-screen. Interfaces coloured by state: green elastic, red sliding, magenta rocking,
orange sliding+rocking, blue detached. Files are written next to the results:
render_<view>_<step>.png, animation_<view>.gif, pushover.png, mechanism_<view>.png.
"""

from __future__ import annotations

import argparse
import re

from masonry_dem.cli.options import add_results

VIEW_CHOICES = ("front", "back", "oblique", "side")  # keep in step with export.render.VIEWS


def _step(text: str) -> int | str:
    t = text.strip().lower()
    if t in ("last", "first"):
        return t
    if re.fullmatch(r"\d+", t):
        return int(t)
    raise argparse.ArgumentTypeError(f"expected a step number, 'first' or 'last', got {text!r}")


#: the range of a picture's width and height in pixels (8192 x 8192: 0.27 GB of RGBA before
#: the PNG; a size of 10^5 would ask VTK for 40 GB before failing)
PIXELS = (16, 8192)


def _size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not m:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, got {text!r}")
    width, height = int(m.group(1)), int(m.group(2))
    if not (PIXELS[0] <= width <= PIXELS[1] and PIXELS[0] <= height <= PIXELS[1]):
        raise argparse.ArgumentTypeError(
            f"width and height must be whole numbers of pixels from {PIXELS[0]} to "
            f"{PIXELS[1]}, got {text!r}"
        )
    return width, height


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "render",
        help="render a results folder: a step's PNG, an animation, the pushover curve",
        description=__doc__,
    )
    add_results(p)
    p.add_argument(
        "--step", type=_step, default="last", help="step number, or 'last' (default) / 'first'"
    )
    p.add_argument(
        "--view",
        action="append",
        choices=VIEW_CHOICES + ("all",),
        help="camera preset (default oblique; the mechanism: the view in which its mode moves "
        "most); repeat it or give 'all' for several",
    )
    p.add_argument(
        "--scale",
        type=float,
        default=None,
        help="displacement amplification (default: automatic, ~6%% of the wall size)",
    )
    p.add_argument(
        "--animate", action="store_true", help="also write an animation (GIF) of every step"
    )
    p.add_argument("--pushover", action="store_true", help="also plot the pushover curve")
    p.add_argument(
        "--mechanism",
        action="store_true",
        help="also render the collapse mechanism (mechanism_<view>.png: the collapse mode, "
        "joints coloured by the relative motion across them; without --view, from the side "
        "for a wall overturning out of its plane, from the front for an in-plane mechanism)",
    )
    p.add_argument(
        "--size",
        type=_size,
        default=(1200, 900),
        metavar="WxH",
        help="picture size in pixels (default 1200x900; animation: 800x600 unless set)",
    )
    p.add_argument("--fps", type=float, default=8.0, help="animation frames per second (8)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from masonry_dem._signals import run_interruptible

    # in a worker thread: a Ctrl-C stops the main thread at once, and the scene's VTK objects
    # stay with the worker to the process's end; raised in the thread that built them, it
    # unwound their frames, most likely freeing a render window VTK was still setting up
    # (SIGSEGV in 4 of 14 interrupted renders; docs/reliability.md)
    return run_interruptible(lambda: _render(args))


def _render(args: argparse.Namespace) -> int:
    from masonry_dem.export import render  # imports pyvista lazily, only when rendering
    from masonry_dem.export.results_folder import warn_if_unfinished

    views = args.view or ["oblique"]
    if "all" in views:
        views = list(VIEW_CHOICES)
    views = list(dict.fromkeys(views))
    written = []
    # check the folder, step and views before writing anything
    warn_if_unfinished(args.results)  # a killed or running run: named, its steps still drawn
    series = render.open_results(args.results)
    series.index_of(args.step)
    for view in views:
        written.append(
            render.render_step(
                args.results, step=args.step, view=view, scale=args.scale, window_size=args.size
            )
        )
    if args.animate:
        size = args.size if args.size != (1200, 900) else (800, 600)
        anim_view = "oblique" if "oblique" in views else views[0]
        written.append(
            render.render_animation(
                args.results, fps=args.fps, view=anim_view, scale=args.scale, window_size=size
            )
        )
    if args.mechanism:
        # no --view: the view in which the collapse mode moves the most
        for view in views if args.view else [None]:
            written.append(
                render.render_mechanism(
                    args.results, view=view, scale=args.scale, window_size=args.size
                )
            )
    if args.pushover:
        written.append(render.plot_pushover(args.results))
    for path in written:
        print(path)
    return 0
