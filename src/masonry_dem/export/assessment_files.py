"""The seismic assessment of a results folder (``masonry-dem assess``): its mechanism read
back, and what the assessment writes into the same folder:

    assessment.json         the checks (keys of :class:`~masonry_dem.assessment.checks.Assessment`)
    capacity_curve.csv      s, alpha, d_k [m], d* [m], a* [m/s2] of the mechanism in large displacements
    adrs.png                the capacity curve against the code's elastic spectrum (ADRS)

The mechanism is the collapse mode of ``mechanism_blocks.vtu`` (the pushover's or the limit
analysis's), on the model of the case the run names in ``summary.json`` (the bundled wall,
or the case file, which must still describe the same blocks), turned into a rigid-block
mechanism with hinges at the joints' edges (:func:`~masonry_dem.assessment.kinematics.hinged_mode`).
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.assessment.checks import Assessment
from masonry_dem.assessment.kinematics import MOVING, CapacityCurve, Mechanism, hinged_mode
from masonry_dem.assessment.spectra import Spectrum, with_damping
from masonry_dem.export.limit_results import finite_json
from masonry_dem.export.picture_files import write_atomically
from masonry_dem.export.results_folder import MECHANISM_FILES, read_summary, write_atomic
from masonry_dem.model import Model

log = logging.getLogger(__name__)

ASSESSMENT = "assessment.json"
CAPACITY_CURVE = "capacity_curve.csv"
ADRS = "adrs.png"
ASSESSMENT_FILES = (ASSESSMENT, CAPACITY_CURVE, ADRS)
#: how far (m) a block's corners may lie from the run's for the case to be the run's
SAME_GEOMETRY = 1e-9


@dataclass(frozen=True)
class FolderMechanism:
    """The mechanism of a results folder: the model, the rigid-block mode, the multiplier
    of the run (None: none recorded), the analysis (``pushover``, ``limit``), the case, and
    the relative residual of the hinged fit."""

    model: Model
    mode: np.ndarray
    load_factor: float | None
    analysis: str
    case: str
    residual: float

    def mechanism(self, moving: float = MOVING, kinematics: str = "chain") -> Mechanism:
        return Mechanism.of(self.model, self.mode, moving, kinematics)


def load_run_model(source: str, folder: Path, case: str | Path | None) -> tuple[Model, str]:
    """The model of the run in ``folder`` and where it came from: the case file ``case`` when
    given, else the ``source`` its summary names (``bundled:...``, or a path looked up from
    here, in the folder and beside it); a ValueError or FileNotFoundError when none is found."""
    from masonry_dem.cases.casefile import load_case

    if case is not None:
        return load_case(case).model, str(case)
    if not source:
        raise ValueError(f"{folder / 'summary.json'} names no case: give it with --case")
    if source.startswith("bundled:"):
        return load_case(None).model, source
    path = Path(source)
    for candidate in (path, folder / path, folder.parent / path):
        if candidate.is_file():
            return load_case(candidate).model, str(candidate)
    raise FileNotFoundError(
        f"the case of {folder}, {source}, is not found (from here or the folder): give it "
        "with --case"
    )


def read_mechanism(folder: Path | str, case: str | Path | None = None) -> FolderMechanism:
    """The mechanism of a results folder whose run ended in collapse; ``case`` overrides the
    case file ``summary.json`` names. Raises ValueError (no collapse, another geometry) or
    FileNotFoundError naming the folder."""
    import meshio

    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"results folder not found: {folder}")
    summary = read_summary(folder)
    if summary.get("status") != "collapse":
        raise ValueError(
            f"results folder {folder}: its run ended {summary.get('status', 'without a summary')!r}, "
            "not in a collapse: there is no mechanism to assess"
        )
    path = folder / MECHANISM_FILES[0]
    if not path.is_file():
        raise FileNotFoundError(f"results folder {folder}: {path.name} is missing")
    model, source = load_run_model(str(summary.get("case", "")), folder, case)
    mesh = meshio.read(path)
    cells = mesh.cell_data
    mode = np.hstack([np.asarray(cells["translation"][0]), np.asarray(cells["rotation"][0])])
    if mode.shape[0] != model.blocks.count:
        raise ValueError(
            f"the case {source} has {model.blocks.count} blocks, the run in {folder} "
            f"{mode.shape[0]}: not the same wall"
        )
    corners = np.asarray(mesh.points, dtype=float).reshape(-1, 8, 3)
    if np.abs(corners - model.blocks.corner_points()).max() > SAME_GEOMETRY:
        raise ValueError(f"the case {source} does not describe the blocks of the run in {folder}")
    hinged, residual = hinged_mode(model, mode)
    lam = summary.get("lambda")
    return FolderMechanism(
        model=model,
        mode=hinged,
        load_factor=float(lam) if isinstance(lam, (int, float)) else None,
        analysis=str(summary.get("analysis", "pushover")),
        case=source,
        residual=residual,
    )


def write_assessment(
    folder: Path | str,
    assessment: Assessment,
    curve: CapacityCurve,
    spectrum: Spectrum,
    extra: dict[str, Any] | None = None,
    render: bool = True,
) -> list[str]:
    """``assessment.json``, ``capacity_curve.csv`` and (``render``) ``adrs.png`` in
    ``folder``; returns the names written."""
    folder = Path(folder)
    data = finite_json({**assessment.as_dict(), **(extra or {})})
    text = json.dumps(data, indent=2)
    write_atomic(folder / ASSESSMENT, lambda tmp: tmp.write_text(text + "\n"))
    fc = assessment.FC
    rows = np.column_stack([curve.s, curve.alpha, curve.d_k, curve.d_star, curve.a_star / fc])
    header = "s,alpha,d_k [m],d_star [m],a_star [m/s2]"
    write_atomic(
        folder / CAPACITY_CURVE,
        lambda tmp: np.savetxt(tmp, rows, delimiter=",", header=header, comments="", fmt="%.10g"),
    )
    names = [ASSESSMENT, CAPACITY_CURVE]
    if render:
        fig = adrs_figure(assessment, curve, spectrum)
        write_atomically(folder / ADRS, lambda tmp: fig.savefig(tmp, dpi=150))
        names.append(ADRS)
    return names


def adrs_figure(assessment: Assessment, curve: CapacityCurve, spectrum: Spectrum) -> Any:
    """The capacity curve (d*, a*) against the elastic spectrum in ADRS (SDe(T), Se(T)), the
    nonlinear check's period (Circolare 2019: T_SLV or T_SLC with d and a(d), the spectrum at
    the mechanism's damping; Circolare 2009 and EN 1998-1: the secant period Ts with d_s*,
    a_s*), its displacement capacity and the displacement demand; a matplotlib Figure (Agg)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 4.8), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    a = assessment
    # the Circolare 2019 demand is read on the spectrum at the mechanism's damping
    shown = spectrum if a.nonlinear_damping is None else with_damping(spectrum, a.nonlinear_damping)
    T = np.linspace(1e-3, 4.0, 600)
    ax.plot(
        1e3 * shown.displacement(T),
        shown.acceleration(T),
        color="#7f8c8d",
        lw=1.4,
        label=f"elastic spectrum ({a.code}, soil {getattr(spectrum, 'soil', '?')}, "
        f"xi = {shown.damping:g} %)",
    )
    ax.plot(
        1e3 * curve.d_star,
        curve.a_star / a.FC,
        color="#1f4e9c",
        lw=2.0,
        label="capacity curve a*(d*)",
    )
    period = a.nonlinear_period
    capacity = a.displacement_capacity
    nonlinear = period is not None and capacity is not None and a.displacement_demand is not None
    d_end = float(curve.d_star[-1]) * 1.05
    if nonlinear:
        assert period is not None and capacity is not None and a.displacement_demand is not None
        state = a.limit_state
        if state is not None:  # Circolare 2019
            factor = "1.68" if state == "SLV" else "1.56"
            period_label = f"T_{state} = {factor} pi sqrt(d_{state}/a(d_{state})) = {period:.3g} s"
            a_point = getattr(a, f"a_{state}")
            point_label = f"d_{state}, a(d_{state}) = {a_point:.3g} m/s$^2$"
            d_point = capacity
            share = "0.4" if state == "SLV" else "0.6"
            capacity_label = f"d_{state} = {share} d0* = {1e3 * capacity:.3g} mm"
            demand_label = (
                f"S_De(T_{state}), xi = {a.nonlinear_damping:g} % = "
                f"{1e3 * a.displacement_demand:.3g} mm"
            )
        else:
            assert a.ds_star is not None and a.as_star is not None
            period_label = f"secant period Ts = {period:.3g} s"
            a_point = a.as_star
            point_label = f"d_s* = 0.4 d_u*, a_s* = {a.as_star:.3g} m/s$^2$"
            d_point = a.ds_star
            capacity_label = f"d_u* = 0.4 d0* = {1e3 * capacity:.3g} mm"
            demand_label = f"displacement demand = {1e3 * a.displacement_demand:.3g} mm"
        d_end = max(a.displacement_demand, d_end)
        # the radial line of the period meets the spectrum at its demand
        omega2 = (2.0 * math.pi / period) ** 2
        ax.plot(
            [0.0, 1e3 * d_end],
            [0.0, omega2 * d_end],
            ls=":",
            color="#1f4e9c",
            lw=1,
            label=period_label,
        )
        ax.plot([1e3 * d_point], [a_point], "o", color="#1f4e9c", ms=5, label=point_label)
        ax.axvline(1e3 * capacity, color="#27ae60", ls="--", lw=1.2, label=capacity_label)
        ax.axvline(
            1e3 * a.displacement_demand, color="#c0392b", ls="--", lw=1.2, label=demand_label
        )
    ax.axhline(
        a.demand,
        color="#c0392b",
        ls="-.",
        lw=1,
        label=f"linear demand = {a.demand:.3g} m/s$^2$ (a0* = {a.a0_star:.3g})",
    )
    top = max(a.a0_star, float(np.max(spectrum.acceleration(T))), a.demand) * 1.1
    ax.set_xlim(0.0, 1e3 * d_end * 1.3)
    ax.set_ylim(0.0, top)
    ax.set_xlabel("spectral displacement d* [mm]")
    ax.set_ylabel("spectral acceleration a* [m/s$^2$]")
    check = {
        "circolare_2019": f"Circolare 2019 {a.limit_state}",
        "circolare_2009": "Circolare 2009",
    }.get(str(a.nonlinear_check), "N2")
    ratios = f"ratio {a.displacement_ratio}"
    if nonlinear:
        ratios = f"ratio {a.displacement_ratio:.3g}"
        if a.passes_nonlinear and a.displacement_ratio is not None and a.displacement_ratio < 1:
            # passed by C8.7.1.2.1.8's floor a_g,SLV >= a_g,SLD, not by the displacement
            ratios += f"; by a_g,SLD / a_g = {a.activation_ratio:.3g}"
    verdict = f"linear: {'passes' if a.passes else 'fails'} (ratio {a.ratio:.3g});\n" + (
        f"nonlinear ({check}): {'passes' if a.passes_nonlinear else 'fails'} ({ratios})"
        if nonlinear
        else "nonlinear: no alpha = 0 (see assessment.json)"
    )
    ax.set_title(verdict, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig
