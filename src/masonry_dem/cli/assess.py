"""``masonry-dem assess RESULTS --code ntc2018|ec8 --ag G [...]``: the seismic assessment of
the collapse mechanism of a results folder (the linear and nonlinear kinematic checks of NTC
2018 / Circolare 2019 C8.7.1, or the EN 1998-1 spectrum with the N2 target displacement),
written into that folder: ``assessment.json``, ``capacity_curve.csv``, ``adrs.png``.

The spectrum and the building are given as flags or as a TOML file (``--config``) of the
same names; a flag overrides the file. A value out of range is one line naming it, its
range and unit, exit code 2."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from masonry_dem._progress import reporting
from masonry_dem.cli.options import EventLine, add_results

if TYPE_CHECKING:
    from masonry_dem.assessment.incremental import IncrementalProgress

#: the keys of a --config file: its name, the parameter it sets, its help
FIELDS: dict[str, str] = {
    "code": "the code: ntc2018 (default) or ec8",
    "ag": "peak ground acceleration on rock ag [g] (EC8: gamma_I agR)",
    "F0": "NTC 2018: the plateau's amplification F0 (default 2.5)",
    "Tc": "NTC 2018: Tc* [s], the start of the constant-velocity branch on rock (default 0.3)",
    "soil": "ground category A-E (default A)",
    "topography": "NTC 2018: topographic category T1-T4 (default T1)",
    "spectrum_type": "EN 1998-1: spectrum type 1 or 2 (default 1)",
    "damping": "viscous damping [%] (default 5; NTC 2018 with the circolare_2019 nonlinear "
    "check: the mechanism's, default 8 for the SLV, 10 for the SLC)",
    "q": "behaviour factor of the linear check (default 2.0)",
    "FC": "confidence factor (default 1.35)",
    "Z": "height of the mechanism's base hinge above the foundation [m] (default 0)",
    "H": "height of the building [m] (needed when Z > 0)",
    "storeys": "number of storeys N (default 1)",
    "T1": "first period of the building [s] (default 0.050 H^(3/4))",
    "building_damping": "NTC 2018: damping xi1 of the building's first mode [%] (default 5)",
    "demand_at_height": "NTC 2018: the demand at height Z > 0: floor_spectrum (Circolare "
    "2019 C7.2.3, default) or circolare_2009 (Se(T1) psi gamma)",
    "nonlinear_check": "NTC 2018: the nonlinear kinematic check: circolare_2019 (T_SLV = 1.68 "
    "pi sqrt(d_SLV/a(d_SLV)), C8.7.1.2.1.8, default) or circolare_2009 (the secant period Ts)",
    "limit_state": "NTC 2018, circolare_2019: the ultimate limit state checked, SLV (default) "
    "or SLC (give the ag of the SLC)",
}
#: the keys of the NTC 2018 demand at height, refused with --code ec8
NTC_HEIGHT_KEYS = ("building_damping", "demand_at_height", "nonlinear_check", "limit_state")
NUMBERS = ("ag", "F0", "Tc", "damping", "q", "FC", "Z", "H", "T1")


def add_site(p: argparse.ArgumentParser, numbers: tuple[str, ...]) -> None:
    """The code, the site and spectrum flags (``numbers``: those of :data:`NUMBERS` the
    command takes) and ``--config``, a TOML file of the same keys; shared with fragility."""
    p.add_argument("--code", choices=("ntc2018", "ec8"), default=None, help=FIELDS["code"])
    p.add_argument("--config", default=None, metavar="TOML", help="a TOML file of these keys")
    for name in numbers:
        p.add_argument(f"--{name}", type=_number(name), default=None, help=FIELDS[name])
    p.add_argument("--soil", default=None, help=FIELDS["soil"])
    p.add_argument("--topography", default=None, help=FIELDS["topography"])
    p.add_argument(
        "--spectrum-type",
        dest="spectrum_type",
        type=int,
        default=None,
        choices=(1, 2),
        help=FIELDS["spectrum_type"],
    )


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "assess",
        help="seismic assessment of a run's collapse mechanism (NTC 2018 C8.7.1 or EN 1998-1)",
        description=(
            "The kinematic checks of the collapse mechanism of a results folder: alpha0, M*, "
            "e*, a0* against the demand of the elastic spectrum (linear), and the capacity "
            "curve of the mechanism in large displacements against the displacement demand "
            "(nonlinear). Writes assessment.json, capacity_curve.csv and adrs.png into "
            "RESULTS (docs/assessment.md)."
        ),
    )
    add_results(p)
    add_site(p, NUMBERS)
    p.add_argument("--storeys", type=int, default=None, help=FIELDS["storeys"])
    p.add_argument(
        "--building-damping",
        dest="building_damping",
        type=_number("building-damping"),
        default=None,
        help=FIELDS["building_damping"],
    )
    # no argparse choices: a bad value is the one line naming the key, as in the TOML file
    for flag, metavar in (
        ("demand-at-height", "FORM"),
        ("nonlinear-check", "FORM"),
        ("limit-state", "STATE"),
    ):
        dest = flag.replace("-", "_")
        p.add_argument(f"--{flag}", dest=dest, default=None, metavar=metavar, help=FIELDS[dest])
    p.add_argument(
        "--alpha0",
        choices=("analysis", "mechanism"),
        default="analysis",
        help="alpha0: the run's collapse multiplier (default; the joints' work held constant "
        "in large displacements) or the virtual work of the loads on the rigid-block mechanism",
    )
    p.add_argument(
        "--moving",
        type=_number("moving"),
        default=None,
        help="a block belongs to the mechanism when it moves at least this share of the "
        "largest motion (default 0.05): its weight counts in e* and the control point",
    )
    p.add_argument(
        "--kinematics",
        choices=("auto", "chain", "independent", "incremental"),
        default="auto",
        help="the finite motion: each block's mode composed along the joints' spanning tree "
        "(chain: hinges stay closed), each block by its own screw motion (independent), "
        "integrated in steps with the twists projected onto the joints' contacts at each step "
        "(incremental: slower, closed loops stay closed), or (default) the one whose blocks "
        "overlap least across the joints at d_u* (incremental only when neither of the other "
        "two is free of overlap)",
    )
    p.add_argument(
        "--case", default=None, help="the run's case file, if summary.json's is not found"
    )
    p.add_argument("--no-render", action="store_true", help="skip adrs.png")
    p.add_argument(
        "--quiet", action="store_true", help="no progress line while the incremental path runs"
    )
    p.set_defaults(func=assess_command)


class IncrementalBar(EventLine):
    """The progress line of the incremental kinematics: its steps, the largest rotation of a
    block and the kinetic norm the lock test reads (``IncrementalProgress``). An assessment
    that integrates no path shows nothing."""

    def __init__(self, quiet: bool) -> None:
        super().__init__("incremental kinematics", "step", quiet)

    def __call__(self, event: IncrementalProgress) -> None:
        self.tick(
            f"a block turned {math.degrees(event.rotation):.1f} deg, kinetic norm "
            f"{event.kinetic:.2f} of the mode's"
        )


def _number(name: str):
    def parse(text: str) -> float:
        try:
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"--{name} must be a number, got {text!r}") from None

    return parse


def parameters(args: argparse.Namespace) -> tuple[dict[str, Any], set[str]]:
    """The parameters: the --config file's, overridden by the flags given; and the keys
    that come from the file."""
    from masonry_dem.cli.options import parameter_file

    params = parameter_file(args.config, FIELDS, "assessment file")
    from_file = set(params)
    for name in FIELDS:
        value = getattr(args, name, None)
        if value is not None:
            params[name] = value
            from_file.discard(name)
    return params, from_file


def run_assessment(
    folder: Path,
    params: dict[str, Any],
    alpha0_from: str = "analysis",
    case: str | None = None,
    render: bool = True,
    moving: float | None = None,
    kinematics: str = "auto",
) -> dict[str, Any]:
    """Assess the mechanism of ``folder`` with ``params`` (the keys of :data:`FIELDS`) and
    write the files; returns what assessment.json holds."""
    from masonry_dem.assessment.checks import (
        Building,
        assess_mode,
        check_demand_at_height,
        check_limit_state,
        check_nonlinear_check,
        spectrum_of,
    )
    from masonry_dem.assessment.kinematics import MOVING
    from masonry_dem.export.assessment_files import read_mechanism, write_assessment

    params = dict(params)
    code = str(params.pop("code", "ntc2018"))
    if code not in ("ntc2018", "ec8"):
        raise ValueError(f"code = {code!r}: must be ntc2018 or ec8")
    if "ag" not in params:
        raise ValueError("ag: the peak ground acceleration [g] is needed (--ag)")
    spectrum_keys = {"ag", "soil", "damping"} | (
        {"F0", "Tc", "topography"} if code == "ntc2018" else {"spectrum_type"}
    )
    other = {"F0", "Tc", "topography", "spectrum_type"} - spectrum_keys
    given = sorted(other & set(params))
    if given:
        raise ValueError(f"{given[0]}: not a parameter of the {code} spectrum")
    if code != "ntc2018":
        given = sorted(set(NTC_HEIGHT_KEYS) & set(params))
        if given:
            raise ValueError(f"{given[0]}: a parameter of the ntc2018 code only, not of {code}")
    demand_at_height = check_demand_at_height(params.pop("demand_at_height", "floor_spectrum"))
    nonlinear_check = check_nonlinear_check(params.pop("nonlinear_check", "circolare_2019"))
    limit_state = check_limit_state(params.pop("limit_state", "SLV"), nonlinear_check)
    # a damping given is the mechanism's "valutazione più accurata" of C8.7.1.2.1.8; not
    # given, the Circolare 2019 check takes the clause's 8 % (SLV) or 10 % (SLC)
    nonlinear_damping = (
        params.get("damping") if code == "ntc2018" and nonlinear_check == "circolare_2019" else None
    )
    spec = {k: params.pop(k) for k in list(params) if k in spectrum_keys}
    if "Tc" in spec:
        spec["Tc_star"] = spec.pop("Tc")
    spectrum = spectrum_of(code, **spec)
    building = Building(
        Z=params.pop("Z", 0.0),
        H=params.pop("H", None),
        storeys=params.pop("storeys", 1),
        T1=params.pop("T1", None),
        damping=params.pop("building_damping", 5.0),
    )
    found = read_mechanism(folder, case)
    if alpha0_from == "analysis" and found.load_factor is None:
        raise ValueError(f"results folder {folder}: its summary gives no collapse multiplier")
    assessment, curve, _, chosen = assess_mode(
        found.model,
        found.mode,
        code,
        spectrum,
        building,
        q=params.pop("q", 2.0),
        FC=params.pop("FC", 1.35),
        load_factor=found.load_factor if alpha0_from == "analysis" else None,
        moving=MOVING if moving is None else moving,
        kinematics=kinematics,
        demand_at_height=demand_at_height,
        nonlinear_check=nonlinear_check,
        limit_state=limit_state,
        nonlinear_damping=nonlinear_damping,
    )
    extra = {
        **chosen,
        "analysis": found.analysis,
        "case": found.case,
        "lambda": found.load_factor,
        "hinged_fit_residual": found.residual,
        "moving_share": MOVING if moving is None else moving,
        "units": "m, s, m/s2, kg, N; ag in g",
    }
    names = write_assessment(folder, assessment, curve, spectrum, extra, render)
    return {**assessment.as_dict(), **extra, "files": names}


def assess_command(args: argparse.Namespace) -> int:
    folder = Path(args.results)
    params, from_file = parameters(args)
    try:
        with IncrementalBar(args.quiet) as bar, reporting(bar):
            data = run_assessment(
                folder,
                params,
                args.alpha0,
                args.case,
                not args.no_render,
                args.moving,
                args.kinematics,
            )
    except ValueError as exc:  # a value of the file is named with the file, as case files are
        key = str(exc).split(" ", 1)[0].rstrip(":")
        if key in from_file:
            raise ValueError(f"assessment file {args.config}: {exc}") from exc
        raise
    keys = (
        "code",
        "alpha0",
        "M_star",
        "e_star",
        "a0_star",
        "demand",
        "ratio",
        "passes",
        "nonlinear_check",
        "limit_state",
        "d0_star",
        "displacement_capacity",
        "nonlinear_period",
        "displacement_demand",
        "passes_nonlinear",
    )
    print(json.dumps({k: data[k] for k in keys}))
    linear = (
        f"linear: a0* = {data['a0_star']:.4g} m/s2 against {data['demand']:.4g} m/s2: "
        f"{'passes' if data['passes'] else 'fails'}"
    )
    if data["passes_nonlinear"] is None:
        print(f"{linear}; nonlinear: not checked, {data['nonlinear_reason']}")
    else:
        print(
            f"{linear}; nonlinear: {'passes' if data['passes_nonlinear'] else 'fails'} "
            f"({data['nonlinear_summary']})"
        )
    if data["motion_note"]:
        note = f"warning: {data['motion_note']}"
        if data["analysis"] != "limit":
            note += (
                "; a limit analysis of the same case (masonry-dem limit) gives a mechanism of "
                "rigid blocks to assess beside it"
            )
        print(note)
    print(f"results in {folder}/ ({', '.join(data['files'])})")
    return 0
