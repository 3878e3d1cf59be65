"""The fragility of a sampled sweep (``masonry-dem fragility SWEEP``): each run's capacity as
a peak ground acceleration from the sweep's rows (``alpha0``, ``e_star``), the lognormal fit,
and what is written into the sweep's folder, and nowhere else:

    fragility.json   the fit (median, beta, their bootstrap intervals), the site, the relation
    fragility.csv    run, status, lambda, alpha0, e_star, a0_star [m/s2], ag_capacity [g],
                     censored (True: the capacity is a lower bound, the run did not collapse)
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
    AG_MAX,
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
CENSORING = (
    "censored: the capacity is a lower bound only; a run that ended 'completed' (still standing "
    "at its last lambda, e.g. max_load_factor reached), its a0* from alpha0 = c lambda and "
    "e* <= 1, or one whose capacity reached AG_MAX; fitted by the likelihood of right-censored "
    "data, sum ln f(exact) + sum ln(1 - F(censored))"
)


@dataclass(frozen=True)
class Fragility:
    fit: LognormalFit
    rows: list[dict[str, Any]]
    used: int  # exact and censored capacities
    left_out: dict[str, int]
    files: list[str]


def _float(text: str | None) -> float | None:
    if text is None or text == "":
        return None
    try:
        return float(text)
    except ValueError:
        return None


def _counts_text(fit: LognormalFit) -> str:
    return f"{fit.n} runs, {fit.censored} censored (did not collapse)"


def _live_load_scale(rows: list[dict[str, str]]) -> float | None:
    """c of the live load c P_i d, alpha0 / lambda of the runs that collapsed, when they all
    share it (to 1e-9): a sweep that does not vary the live load; None otherwise. A completed
    run of a sweep written before its row carried alpha0 takes its alpha0 = c lambda from it."""
    ratios = []
    for raw in rows:
        lam, alpha0 = _float(raw.get("lambda")), _float(raw.get("alpha0"))
        if raw.get("status") == "collapse" and lam and alpha0 is not None and lam > 0:
            ratios.append(alpha0 / lam)
    if not ratios or max(ratios) - min(ratios) > 1e-9 * max(abs(r) for r in ratios):
        return None
    return float(np.mean(ratios))


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
    raw_rows = read_sweep_rows(folder)
    scale = _live_load_scale(raw_rows)
    rows = []
    left_out: dict[str, int] = {}
    for raw in raw_rows:
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
            "censored": None,
        }
        standing = status == "completed"
        if standing and alpha0 is None and lam is not None and scale is not None:
            alpha0 = row["alpha0"] = lam * scale  # c lambda, c read off the collapses
        if standing and (e_star is None or not 0 < e_star <= 1):
            # no collapse mode, so no e*: it is at most 1 (the participating mass is a share
            # of the total), and a0* = alpha0 g / (e* FC) is at least alpha0 g / FC; the
            # capacity rises with a0*, so the bound stays a lower bound
            e_star = 1.0
        why = (
            f"status {status}"
            if status not in ("collapse", "completed")
            else "completed with no lambda above 0 (no live load)"
            if standing and (lam is None or lam <= 0)
            else "completed, no alpha0 (the live load is not c P_i d, or c differs between runs)"
            if standing and alpha0 is None
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
            # a run still standing at the end of its path, or one stronger than the largest
            # capacity sought (reported at AG_MAX), bounds its capacity from below only
            row["censored"] = standing or row["ag_capacity"] >= AG_MAX
        rows.append(row)
    used = [r for r in rows if r["ag_capacity"] is not None]
    capacities = np.array([r["ag_capacity"] for r in used], dtype=float)
    censored = np.array([r["censored"] for r in used], dtype=bool)
    exact = int((~censored).sum())
    if exact < 2:
        raise ValueError(
            f"{folder}: {exact} run(s) with a capacity from a collapse"
            + (f" and {int(censored.sum())} censored (did not collapse)" if censored.any() else "")
            + f" ({left_out or 'none left out'}): a fit needs at least 2 that collapsed"
        )
    fit, resamples = fit_lognormal(capacities, bootstrap, confidence, seed, censored)
    data = {
        "median": fit.median,
        "beta": fit.beta,
        **fit.as_dict(),
        "runs": len(rows),
        "used": int(capacities.size),
        "left_out": left_out,
        "capacity_min": float(capacities.min()),
        "capacity_max": float(capacities.max()),
        "counts": _counts_text(fit),
        "censoring": CENSORING,
        "code": code,
        "site": site,
        "q": q,
        "FC": FC,
        "relation": RELATION,
        "units": "ag, median in g; a0_star in m/s2",
    }
    text = json.dumps(finite_json(data), indent=2)
    write_atomic(folder / FRAGILITY_JSON, lambda tmp: tmp.write_text(text + "\n"))
    columns = ["run", "status", "lambda", "alpha0", "e_star", "a0_star", "ag_capacity", "censored"]

    def write_csv(tmp: Path) -> None:
        with tmp.open("w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow([*columns[:5], "a0_star [m/s2]", "ag_capacity [g]", "censored"])
            for r in rows:
                writer.writerow(["" if r[c] is None else r[c] for c in columns])

    write_atomic(folder / FRAGILITY_CSV, write_csv)
    files = [FRAGILITY_JSON, FRAGILITY_CSV]
    if render:
        soil = site.get("soil", "A")
        title = (
            f"{folder.name}: {code}, soil {soil}, q {q:g}, FC {FC:g}; "
            f"{_counts_text(fit)}, of {len(rows)}"
        )
        fig = fragility_figure(fit, resamples, capacities, title, censored)
        write_atomically(folder / FRAGILITY_PNG, lambda tmp: fig.savefig(tmp, dpi=150))
        files.append(FRAGILITY_PNG)
    log.info(
        "fragility of %s: median %.4g g, beta %.4g (%s)",
        folder,
        fit.median,
        fit.beta,
        _counts_text(fit),
    )
    return Fragility(fit, rows, int(capacities.size), left_out, files)
