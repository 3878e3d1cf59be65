"""``masonry-dem fragility SWEEP [--code ntc2018|ec8] [site flags]``: the fragility curve of a
mechanism from a sampled sweep (``masonry-dem sweep --sample``): each run's capacity as a
peak ground acceleration (the linear check of a mechanism at ground level), a lognormal fit
(median, beta) by maximum likelihood with a bootstrap band, and the curve; written into the
sweep's folder (fragility.json, fragility.csv, fragility.png; docs/assessment.md)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from masonry_dem.cli.assess import _number, add_site

#: the site's keys (flags, or a --config TOML of the same names)
SITE = ("code", "F0", "Tc", "soil", "topography", "spectrum_type", "q", "FC")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "fragility",
        help="fragility curve from a sampled sweep: capacities as ground accelerations, "
        "lognormal fit",
        description=__doc__,
    )
    p.add_argument("sweep", help="the folder of a masonry-dem sweep (its sweep.csv)")
    add_site(p, ("F0", "Tc", "q", "FC"))
    p.add_argument("--bootstrap", type=int, default=1000, help="bootstrap resamples (default 1000)")
    p.add_argument(
        "--confidence",
        type=_number("confidence"),
        default=0.90,
        help="level of the band and intervals (default 0.90)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    p.add_argument("--no-render", action="store_true", help="skip fragility.png")
    p.set_defaults(func=fragility_command)


def site_parameters(args: argparse.Namespace) -> dict[str, Any]:
    from masonry_dem.cli.options import parameter_file

    params = parameter_file(args.config, SITE, "fragility file")
    for name in SITE:
        value = getattr(args, name, None)
        if value is not None:
            params[name] = value
    return params


def fragility_command(args: argparse.Namespace) -> int:
    from masonry_dem.export.fragility_files import sweep_fragility

    params = site_parameters(args)
    code = str(params.pop("code", "ntc2018"))
    if code not in ("ntc2018", "ec8"):
        raise ValueError(f"code = {code!r}: must be ntc2018 or ec8")
    q = params.pop("q", 2.0)
    FC = params.pop("FC", 1.35)
    spectrum_keys = {"soil"} | (
        {"F0", "Tc", "topography"} if code == "ntc2018" else {"spectrum_type"}
    )
    given = sorted(set(params) - spectrum_keys)
    if given:
        raise ValueError(f"{given[0]}: not a parameter of the {code} spectrum")
    if "Tc" in params:
        params["Tc_star"] = params.pop("Tc")
    if args.bootstrap < 10:
        raise ValueError(f"--bootstrap {args.bootstrap}: must be at least 10")
    if not 0 < args.confidence < 1:
        raise ValueError(f"--confidence {args.confidence}: must be in (0, 1)")
    result = sweep_fragility(
        Path(args.sweep),
        code,
        params,
        q=q,
        FC=FC,
        bootstrap=args.bootstrap,
        confidence=args.confidence,
        seed=args.seed,
        render=not args.no_render,
    )
    fit = result.fit
    print(
        json.dumps(
            {
                "median": fit.median,
                "beta": fit.beta,
                "median_interval": fit.median_interval,
                "beta_interval": fit.beta_interval,
                "used": result.used,
                "censored": fit.censored,
                "runs": len(result.rows),
                "left_out": result.left_out,
            }
        )
    )
    pct = round(100 * fit.confidence)
    print(
        f"fragility: median {fit.median:.4g} g ({pct} %: {fit.median_interval[0]:.4g} to "
        f"{fit.median_interval[1]:.4g}), beta {fit.beta:.3g} ({fit.beta_interval[0]:.3g} to "
        f"{fit.beta_interval[1]:.3g}), from {result.used} of {len(result.rows)} runs, "
        f"{fit.censored} censored (did not collapse)"
    )
    print(f"results in {args.sweep}/ ({', '.join(result.files)})")
    return 0
