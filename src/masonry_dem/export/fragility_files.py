"""The fragility of a sampled sweep (``masonry-dem fragility SWEEP``): each run's capacity as
a peak ground acceleration from the sweep's rows (``alpha0``, ``e_star``), the lognormal fit,
and what is written into the sweep's folder, and nowhere else:

    fragility.json   the fit (median, beta, their bootstrap intervals), the site, the relation
    fragility.csv    run, status, lambda, alpha0, e_star, a0_star [m/s2], ag_capacity [g]
    fragility.png    the fragility curve with its band and the runs' empirical distribution
"""

from __future__ import annotations

import csv
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from masonry_dem.assessment.fragility import (
    BOOTSTRAP,
    CONFIDENCE,
    LognormalFit,
    ag_capacity,
    fit_lognormal,
    fragility_figure,
)
from masonry_dem.assessment.spectra import G
from masonry_dem.export.limit_results import finite_json
from masonry_dem.export.picture_files import write_atomically
from masonry_dem.export.results_folder import write_atomic

log = logging.getLogger(__name__)

SWEEP_CSV = "sweep.csv"
FRAGILITY_JSON = "fragility.json"
FRAGILITY_CSV = "fragility.csv"
FRAGILITY_PNG = "fragility.png"
RELATION = (
    "ag_capacity: the smallest ag [g] with ag S(ag) / q >= a0* / g, a0* = alpha0 g / (e* FC) "
    "(the linear check of a mechanism at ground level, Circolare 2019 C8.7.1.2.1.7, [C8.7.1.8]; "
    "Circolare 2009 [C8A.4.9], [C8A.4.4]); "
    "a0* q / (g S) where S does not depend on ag"
)


@dataclass(frozen=True)
class Fragility:
    fit: LognormalFit
    rows: list[dict[str, Any]]
    used: int
    left_out: dict[str, int]
    files: list[str]


def _float(text: str | None) -> float | None:
    if text is None or text == "":
        return None
    try:
        return float(text)
    except ValueError:
        return None


def read_sweep_rows(folder: Path) -> list[dict[str, str]]:
    path = folder / SWEEP_CSV
    if not folder.is_dir():
        raise FileNotFoundError(f"sweep folder not found: {folder}")
    if not path.is_file():
        raise FileNotFoundError(f"{folder}: no {SWEEP_CSV} (the folder of a masonry-dem sweep)")
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        fields = reader.fieldnames or []
        missing = [c for c in ("run", "status", "lambda", "alpha0", "e_star") if c not in fields]
        if missing:
            raise ValueError(
                f"{path}: no {', '.join(missing)} column: a sweep of an older version; run it "
                "again (--overwrite) to have the seismic mechanism of each run"
            )
        return list(reader)


def sweep_fragility(
    folder: Path | str,
    code: str,
    site: dict[str, Any],
    q: float = 2.0,
    FC: float = 1.35,
    bootstrap: int = BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int | None = 0,
    render: bool = True,
) -> Fragility:
    """The fragility of the runs of a sweep folder against ``code``'s spectrum at the site
    ``site`` (its parameters but ag); writes the files and returns them with the fit."""
    from masonry_dem.assessment.checks import spectrum_of
    from masonry_dem.assessment.spectra import check_range

    folder = Path(folder)
    q = check_range("q", q, 1.0, 10.0, "(dimensionless)")
    FC = check_range("FC", FC, 1.0, 3.0, "(dimensionless)")
    spectrum_of(code, ag=0.1, **site)  # the site's values checked before anything is read
    rows = []
    left_out: dict[str, int] = {}
    for raw in read_sweep_rows(folder):
        lam, alpha0, e_star = (_float(raw.get(k)) for k in ("lambda", "alpha0", "e_star"))
        status = raw.get("status", "")
        row: dict[str, Any] = {
            "run": int(raw["run"]),
            "status": status,
            "lambda": lam,
            "alpha0": alpha0,
            "e_star": e_star,
            "a0_star": None,
            "ag_capacity": None,
        }
        why = (
            f"status {status}"
            if status != "collapse"
            else "no seismic mechanism (the live load is not c P_i d, or no mode)"
            if alpha0 is None or e_star is None or e_star <= 0
            else "alpha0 <= 0"
            if alpha0 <= 0
            else ""
        )
        if why:
            left_out[why] = left_out.get(why, 0) + 1
        else:
            assert alpha0 is not None and e_star is not None
            row["a0_star"] = alpha0 * G / (e_star * FC)
            row["ag_capacity"] = ag_capacity(row["a0_star"], code, site, q)
        rows.append(row)
    capacities = np.array([r["ag_capacity"] for r in rows if r["ag_capacity"] is not None])
    if capacities.size < 2:
        raise ValueError(
            f"{folder}: {capacities.size} run(s) with a capacity ({left_out or 'none left out'}): "
            "a fit needs at least 2"
        )
    fit, resamples = fit_lognormal(capacities, bootstrap, confidence, seed)
    data = {
        "median": fit.median,
        "beta": fit.beta,
        **fit.as_dict(),
        "runs": len(rows),
        "used": int(capacities.size),
        "left_out": left_out,
        "capacity_min": float(capacities.min()),
        "capacity_max": float(capacities.max()),
        "code": code,
        "site": site,
        "q": q,
        "FC": FC,
        "relation": RELATION,
        "units": "ag, median in g; a0_star in m/s2",
    }
    text = json.dumps(finite_json(data), indent=2)
    write_atomic(folder / FRAGILITY_JSON, lambda tmp: tmp.write_text(text + "\n"))
    columns = ["run", "status", "lambda", "alpha0", "e_star", "a0_star", "ag_capacity"]

    def write_csv(tmp: Path) -> None:
        with tmp.open("w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow([*columns[:5], "a0_star [m/s2]", "ag_capacity [g]"])
            for r in rows:
                writer.writerow(["" if r[c] is None else r[c] for c in columns])

    write_atomic(folder / FRAGILITY_CSV, write_csv)
    files = [FRAGILITY_JSON, FRAGILITY_CSV]
    if render:
        soil = site.get("soil", "A")
        title = (
            f"{folder.name}: {code}, soil {soil}, q {q:g}, FC {FC:g}; "
            f"{capacities.size} of {len(rows)} runs"
        )
        fig = fragility_figure(fit, resamples, capacities, title)
        write_atomically(folder / FRAGILITY_PNG, lambda tmp: fig.savefig(tmp, dpi=150))
        files.append(FRAGILITY_PNG)
    log.info("fragility of %s: median %.4g g, beta %.4g", folder, fit.median, fit.beta)
    return Fragility(fit, rows, int(capacities.size), left_out, files)
