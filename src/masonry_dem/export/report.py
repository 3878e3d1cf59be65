"""``masonry-dem report RESULTS``: one self-contained HTML page of a results folder, for an
engineer to read and file (issue 38, item 5).

The page holds, in words and pictures: the verdict (the assessment's checks when
``assessment.json`` is there, else the run's status), lambda in words (for a
weight-proportional load: the horizontal acceleration in g and the tilt angle atan(lambda)),
the certificate and the limit analysis's bound with their gap, the mechanism, the wall and its
supports, the pushover curve and the assessment with its ADRS plot. Every picture is embedded
as base64 (``data:`` URLs): the page loads nothing from a disk or a network. It is written as
``report.html`` into the results folder, and nothing else is written anywhere: the pictures
the folder lacks are rendered in memory.
"""

from __future__ import annotations

import base64
import html
import io
import json
import logging
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.export import results_folder as rf
from masonry_dem.export.figure_text import method_of

log = logging.getLogger(__name__)

REPORT = "report.html"
ASSESSMENT = "assessment.json"
ADRS = "adrs.png"
#: the pictures rendered in memory when the folder has none (pixels)
PICTURE_SIZE = (1000, 750)
CODE_NAMES = {
    "ntc2018": "NTC 2018 (Circolare 2019, C8.7.1)",
    "ec8": "EN 1998-1 (N2 format)",
}


# --------------------------------------------------------------------------- words
def lambda_in_words(lam: float, scale: float | None = 1.0) -> str:
    """lambda in words. ``scale`` c of a weight-proportional live load c P_i d (horizontal, d
    a unit vector; None: the live load is of another kind): alpha = c lambda is the horizontal
    acceleration in g that the wall carries, and atan(alpha) the angle of a tilt table that
    loads it the same way."""
    if scale is None:
        return (
            f"lambda = {lam:.4g}: the factor on the live load of the case at which the wall "
            "collapses (the live load is not proportional to the weights: lambda is no "
            "acceleration)"
        )
    alpha = scale * lam
    g = f"{alpha:.2f}" if abs(alpha) >= 0.1 else f"{alpha:.2g}"
    tilt = math.degrees(math.atan(alpha))
    factor = "" if abs(scale - 1.0) < 1e-12 else f" (alpha = c lambda, c = {scale:.4g})"
    return (
        f"lambda = {lam:.4g}{factor}: a horizontal acceleration of {g} g, a tilt of "
        f"{tilt:.1f} degrees. The wall carries its own weight and horizontal forces of "
        f"{alpha:.3g} times its weight (the equivalent static earthquake), as it would on a "
        f"table tilted by {tilt:.1f} degrees."
    )


def certificate_in_words(summary: dict[str, Any]) -> list[str]:
    """The certificate and the bound of a run's summary, in sentences."""
    analysis = str(summary.get("analysis", "pushover"))
    lam = summary.get("lambda")
    status = summary.get("status")
    if analysis == "limit":
        kind = summary.get("bound")
        lines = [
            "A limit analysis gives no certificate: it is one convex solve on rigid blocks, "
            "a fast first answer, not the number to design with."
        ]
        if kind == "upper":
            lines.append(
                f"Its multiplier {_num(lam)} is an upper bound of the pushover's: the wall "
                "collapses at this load or below it."
            )
        else:
            lines.append(
                f"Its multiplier {_num(lam)} is an estimate, not a bound: "
                f"{summary.get('bound_reason', 'see summary.json')}."
            )
        lines.append(
            "Run the pushover of the same case (masonry-dem run) for the certified multiplier."
        )
        return lines
    cert = summary.get("certificate") or {}
    lines = []
    if status == "collapse" and cert.get("holds"):
        lines.append(
            f"The collapse at lambda = {_num(lam)} is certified: the last state is an "
            f"equilibrium (residual {_num(cert.get('residual'), '.2g')} within "
            f"{_num(cert.get('tolerance'), '.2g')}, every joint's action in its strength "
            f"domain); the live load drives a collapse mode ({cert.get('mode', 'found')}); "
            "a damped motion finds no rest 0.5 % above it"
            + (f" ({cert['instability']})" if cert.get("instability") else "")
            + "."
        )
    elif status == "collapse":
        lines.append(f"The run reports a collapse at lambda = {_num(lam)} without a certificate.")
    else:
        lines.append(
            f"The run ended {status!r}: no certified collapse. {summary.get('reason', '')}".strip()
        )
    bound = summary.get("limit_analysis_bound", cert.get("bound"))
    if isinstance(bound, (int, float)) and isinstance(lam, (int, float)) and lam > 0:
        gap = (bound - lam) / lam
        lines.append(
            f"The bound: the associative limit analysis of the same blocks gives "
            f"{_num(bound)}, an upper bound of the pushover's multiplier; the gap between "
            f"them is {100 * gap:.0f} % of lambda"
            + (
                " (lambda within the bound, as it must be)"
                if cert.get("within_bound")
                else f" (the certificate's bound check: {cert.get('bound_status', 'n/a')})"
            )
            + ". A small gap (a few %, a mechanism that rocks) means rigid blocks and the "
            "DEM describe the same collapse; a large one that joints slide or twist (an "
            "associative joint dilates as it slides and carries more) or that the wall arches "
            "between held edges (rigid blocks never flatten an arch): the bound is loose, the "
            "pushover is not wrong. Design with the certified lambda, never with the bound."
        )
    elif status == "collapse":
        lines.append(
            "No limit-analysis bound was computed (run without --no-bound to have one): "
            "the certificate's fourth condition was not checked."
        )
    return lines


def verdict(summary: dict[str, Any], assessment: dict[str, Any] | None) -> tuple[str, str]:
    """(class, sentence): the page's verdict. ``class`` is ``pass``, ``fail`` or ``none``."""
    if assessment is not None:
        code = CODE_NAMES.get(str(assessment.get("code")), str(assessment.get("code")))
        linear = (
            f"the linear check {'passes' if assessment.get('passes') else 'fails'} "
            f"(a0* = {_num(assessment.get('a0_star'), '.3g')} m/s2 against a demand of "
            f"{_num(assessment.get('demand'), '.3g')} m/s2, ratio "
            f"{_num(assessment.get('ratio'), '.3g')})"
        )
        nonlinear_ok = assessment.get("passes_nonlinear")
        if nonlinear_ok is None:
            nonlinear = (
                "the nonlinear check was not made ("
                + str(assessment.get("nonlinear_reason") or "no alpha = 0")
                + ")"
            )
        else:
            # an assessment.json older than the Circolare 2019 check has du_star alone
            state = assessment.get("limit_state")
            du = assessment.get("displacement_capacity", assessment.get("du_star"))
            name = f"d_{state}" if state else "d_u*"
            dd = assessment.get("displacement_demand")
            nonlinear = (
                f"the nonlinear check {'passes' if nonlinear_ok else 'fails'} "
                f"({name} = {_mm(du)} mm against a demand of {_mm(dd)} mm"
            )
            ratio = assessment.get("displacement_ratio")
            if nonlinear_ok and isinstance(ratio, (int, float)) and ratio < 1:
                # Circolare 2019 C8.7.1.2.1.8: a_g,SLV is at least a_g,SLD
                nonlinear += (
                    ", but the mechanism is not activated at this ag: a_g,SLD / a_g = "
                    f"{_num(assessment.get('activation_ratio'), '.3g')}"
                )
            nonlinear += ")"
        ok = bool(assessment.get("passes")) and nonlinear_ok is not False
        word = "PASSES" if ok else "FAILS"
        note = str(assessment.get("motion_note") or "")
        return (
            "pass" if ok else "fail",
            f"The mechanism {word} the check of {code} at ag = "
            f"{_num(assessment.get('spectrum', {}).get('ag'), '.3g')} g: {linear}; {nonlinear}."
            + (f" Note: {note[0].upper()}{note[1:]}." if note else ""),
        )
    status = summary.get("status")
    if status == "collapse":
        return (
            "none",
            f"Collapse at lambda = {_num(summary.get('lambda'))}. No seismic assessment in "
            "this folder: masonry-dem assess RESULTS --code ntc2018|ec8 --ag G ... adds one.",
        )
    return "none", f"No collapse: the run ended {status!r}."


def _num(value: Any, fmt: str = ".4g") -> str:
    return format(float(value), fmt) if isinstance(value, (int, float)) else "n/a"


def _mm(value: Any) -> str:
    return format(1e3 * float(value), ".3g") if isinstance(value, (int, float)) else "n/a"


# --------------------------------------------------------------------------- pictures
def data_url(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _png_of_array(image: np.ndarray) -> bytes:
    import imageio.v3 as iio

    return bytes(iio.imwrite("<bytes>", np.ascontiguousarray(image[..., :3]), extension=".png"))


def _png_of_figure(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def _scene_png(make: Callable[[], Any]) -> bytes:
    scene = make()
    try:
        return _png_of_array(np.asarray(scene.image()))
    finally:
        scene.close()


def mechanism_png(folder: Path, render: bool) -> tuple[bytes | None, str]:
    """The mechanism picture of the folder (``mechanism_<view>.png`` of the run), else
    rendered in memory; (None, why) when there is none."""
    if not (folder / rf.MECHANISM_FILES[0]).is_file():
        return None, "no collapse mechanism in this folder (written when a run ends in collapse)"
    for view in ("side", "front", "oblique", "back"):
        path = folder / f"mechanism_{view}.png"
        if path.is_file():
            return path.read_bytes(), f"the collapse mode, {view} view ({path.name})"
    if not render:
        return None, "no mechanism picture in the folder (rendering off)"
    from masonry_dem.export import render as rd

    data = rd._read_mechanism(folder, False)
    view = rd.view_of_motion(data)
    png = _scene_png(lambda: rd._mechanism_scene(folder, view, None, PICTURE_SIZE, False, data))
    return png, f"the collapse mode, {view} view"


def wall_png(folder: Path, render: bool) -> tuple[bytes | None, str]:
    """The wall and its supports at the first step (the dead-load state), rendered in
    memory; (None, why) when the folder has no steps (a limit analysis) or rendering is off."""
    if not render:
        return None, "rendering off"
    from masonry_dem.export import render as rd

    try:
        series = rd.open_results(folder)
    except (FileNotFoundError, ValueError) as exc:
        return None, f"no steps to draw the wall from ({exc})"
    if len(series.steps) == 0:
        return None, "no steps to draw the wall from"
    png = _scene_png(lambda: rd._step_scene(series, 0, "oblique", 1.0, PICTURE_SIZE)[0])
    return png, (
        "the wall under its dead load (first step), oblique view: supports dark grey and "
        "marked, the live load's direction drawn"
    )


def pushover_png(folder: Path) -> bytes | None:
    if not (folder / "pushover.csv").is_file():
        return None
    from masonry_dem.export.plots import pushover_figure

    try:
        return _png_of_figure(pushover_figure(folder))
    except ValueError as exc:  # a pushover.csv with no step
        log.warning("no pushover curve in the report: %s", exc)
        return None


# --------------------------------------------------------------------------- the page
def live_scale(folder: Path, summary: dict[str, Any]) -> float | None:
    """c of the run's weight-proportional live load c P_i d (from assessment.json, else the
    case's model); None when the live load is of another kind or the case is not found."""
    from masonry_dem.assessment.kinematics import live_load_scale
    from masonry_dem.export.assessment_files import load_run_model

    try:
        model, _ = load_run_model(str(summary.get("case", "")), folder, None)
    except (OSError, ValueError) as exc:
        log.info("lambda in general words: the case of %s is not loaded (%s)", folder, exc)
        return None
    try:
        return float(live_load_scale(model))
    except ValueError:
        return None


ASSESSMENT_ROWS = (
    ("alpha0", "alpha0, the collapse multiplier of the mechanism", "", ".4g", 1.0),
    ("alpha_rigid", "alpha0 of the loads alone on the rigid-block mechanism", "", ".4g", 1.0),
    ("M_star", "M*, the participating mass", "kg", ".4g", 1.0),
    ("e_star", "e*, its fraction of the moving weight", "", ".3g", 1.0),
    ("FC", "FC, the confidence factor", "", ".3g", 1.0),
    ("q", "q, the behaviour factor", "", ".3g", 1.0),
    (
        "a0_star",
        "a0* = alpha0 g / (e* FC), the spectral acceleration of activation",
        "m/s2",
        ".4g",
        1.0,
    ),
    ("demand", "linear demand", "m/s2", ".4g", 1.0),
    ("ratio", "capacity / demand (linear)", "", ".3g", 1.0),
    ("d0_star", "d0*, the displacement at which alpha = 0", "mm", ".4g", 1e3),
    ("nonlinear_check", "the nonlinear check (NTC 2018)", "", "s", 1.0),
    ("d_SLV", "d_SLV = 0.4 d0* (Circolare 2019 C8.7.1.2.1.6)", "mm", ".4g", 1e3),
    ("T_SLV", "T_SLV = 1.68 pi sqrt(d_SLV / a(d_SLV)) [C8.7.1.10]", "s", ".3g", 1.0),
    ("d_SLC", "d_SLC = 0.6 d0* (Circolare 2019 C8.7.1.2.1.6)", "mm", ".4g", 1e3),
    ("T_SLC", "T_SLC = 1.56 pi sqrt(d_SLC / a(d_SLC)) [C8.7.1.11]", "s", ".3g", 1.0),
    ("nonlinear_damping", "xi, the mechanism's damping of the demand", "%", ".3g", 1.0),
    ("du_star", "d_u* = 0.4 d0*, the ultimate displacement (Circolare 2009)", "mm", ".4g", 1e3),
    ("Ts", "Ts, the secant period (Circolare 2009)", "s", ".3g", 1.0),
    ("displacement_demand", "displacement demand", "mm", ".4g", 1e3),
    ("displacement_ratio", "capacity / demand (nonlinear)", "", ".3g", 1.0),
)


#: rows of one nonlinear check only (Circolare 2019 SLV or SLC, Circolare 2009): left out
#: when the check made was another
ONE_CHECK_ROWS = frozenset(
    ("nonlinear_check", "d_SLV", "T_SLV", "d_SLC", "T_SLC", "nonlinear_damping", "du_star", "Ts")
)
#: the secant period's rows: assessment.json reports them beside the Circolare 2019 check,
#: the page only for the check that reads them
SECANT_ROWS = frozenset(("du_star", "Ts"))


def _assessment_table(a: dict[str, Any]) -> str:
    rows = []
    for key, label, unit, fmt, factor in ASSESSMENT_ROWS:
        value = a.get(key)
        if key in ONE_CHECK_ROWS and (
            value is None or (key in SECANT_ROWS and a.get("nonlinear_check") == "circolare_2019")
        ):
            continue
        if isinstance(value, str):
            text = html.escape(value)
        else:
            text = format(factor * value, fmt) if isinstance(value, (int, float)) else "n/a"
        rows.append(
            f"<tr><td>{html.escape(label)}</td><td class='num'>{text}</td>"
            f"<td>{html.escape(unit)}</td></tr>"
        )
    spec = a.get("spectrum") or {}
    site = ", ".join(
        f"{k} = {format(v, '.4g') if isinstance(v, float) else v}"
        for k, v in spec.items()
        if not isinstance(v, (dict, list))
    )
    return (
        "<table><thead><tr><th>quantity</th><th>value</th><th>unit</th></tr></thead><tbody>"
        + "".join(rows)
        + "</tbody></table>"
        + f"<p class='small'>Spectrum: {html.escape(site)}. Mechanism at Z = "
        f"{html.escape(str(a.get('Z', 0)))} m; kinematics {html.escape(str(a.get('kinematics')))}"
        f"; {html.escape(str(a.get('moving_blocks')))} moving blocks. Every formula and clause: "
        "docs/assessment.md.</p>"
    )


def _figure(png: bytes | None, element_id: str, caption: str) -> str:
    if png is None:
        return f"<p class='small' id='{element_id}-missing'>Not drawn: {html.escape(caption)}.</p>"
    return (
        f"<figure><img id='{element_id}' src='{data_url(png)}' alt='{html.escape(caption)}'>"
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


STYLE = """
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 24px auto; max-width: 1100px;
       color: #222; line-height: 1.45; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; }
h2 { font-size: 1.15em; border-bottom: 1px solid #ccc; padding-bottom: 2px; margin-top: 1.4em; }
.small { font-size: 0.9em; color: #555; }
#verdict { padding: 12px 16px; border-radius: 6px; font-size: 1.1em; border: 2px solid; }
#verdict.pass { background: #e8f6ec; border-color: #27ae60; }
#verdict.fail { background: #fdecea; border-color: #c0392b; }
#verdict.none { background: #f1f3f5; border-color: #7f8c8d; }
figure { margin: 0.8em 0; }
img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #555; }
table { border-collapse: collapse; font-size: 0.95em; }
td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
"""


def report_html(folder: Path | str, render: bool = True) -> str:
    """The page of a results folder, as text (see the module's doc)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder not found: {folder}")
    summary = rf.read_summary(folder)
    if not summary:
        raise ValueError(f"{folder} holds no summary.json: not a results folder")
    assessment = None
    if (folder / ASSESSMENT).is_file():
        assessment = json.loads((folder / ASSESSMENT).read_text())
    name = str(summary.get("name", folder.name))
    lam = summary.get("lambda")
    klass, sentence = verdict(summary, assessment)
    scale = live_scale(folder, summary)
    mech, mech_caption = mechanism_png(folder, render)
    wall, wall_caption = wall_png(folder, render)
    curve = pushover_png(folder)
    e = html.escape
    parts = [
        "<!DOCTYPE html>",
        "<html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        "<link rel='icon' href='data:,'>",
        f"<title>{e(name)}: masonry_dem report</title>",
        f"<style>{STYLE}</style></head><body>",
        f"<h1>{e(name)}</h1>",
        f"<p class='small'>{e(method_of(summary))}; case {e(str(summary.get('case', '?')))}; "
        f"{e(str(summary.get('blocks', '?')))} blocks, "
        f"{e(str(summary.get('interfaces', '?')))} joints; status "
        f"{e(str(summary.get('status')))}.</p>",
        f"<section><h2>Verdict</h2><p id='verdict' class='{klass}'>{e(sentence)}</p></section>",
        "<section><h2>The mechanism</h2>",
        _figure(mech, "mechanism", mech_caption),
        "</section>",
        "<section><h2>What lambda means here</h2><p id='lambda-words'>",
        e(lambda_in_words(float(lam), scale))
        if isinstance(lam, (int, float))
        else "No multiplier: the run gave none.",
        "</p><p class='small'>Loads are F = F_D + lambda F_L: the dead load (self weight) and "
        "the live load scaled by lambda.</p></section>",
        "<section><h2>The certificate and the bound</h2>",
        *(f"<p>{e(line)}</p>" for line in certificate_in_words(summary)),
        "</section>",
        "<section><h2>The wall and its supports</h2>",
        _figure(wall, "wall", wall_caption),
        "</section>",
        "<section><h2>The pushover curve</h2>",
        _figure(curve, "pushover", "lambda against the displacement the run recorded")
        if curve is not None
        else "<p class='small'>No pushover curve: this folder holds no pushover.csv.</p>",
        "</section>",
        "<section id='assessment'><h2>Seismic assessment</h2>",
    ]
    if assessment is None:
        parts.append(
            "<p>None yet: <code>masonry-dem assess RESULTS --code ntc2018 --ag G ...</code> "
            "writes assessment.json, and the report then shows it.</p>"
        )
    else:
        parts.append(_assessment_table(assessment))
        adrs = folder / ADRS
        parts.append(
            _figure(
                adrs.read_bytes() if adrs.is_file() else None,
                "adrs",
                "the capacity curve against the elastic spectrum (ADRS)"
                if adrs.is_file()
                else "no adrs.png in the folder",
            )
        )
    from masonry_dem._version import version

    parts += [
        "</section>",
        f"<p class='small'>Written by masonry_dem {e(version())} from {e(folder.name)}/. "
        "Pictures are embedded: the page needs no other file.</p>",
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"


def write_report(folder: Path | str, render: bool = True) -> Path:
    """``report.html`` in ``folder`` (atomically); returns its path."""
    folder = Path(folder)
    text = report_html(folder, render)
    path = folder / REPORT
    rf.write_atomic(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    log.info("report of %s written to %s (%d kB)", folder, path, len(text) // 1024)
    return path
