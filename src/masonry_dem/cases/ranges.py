"""The allowed values of a case file's numbers: each physical or numerical key's range, its
unit and the reason for its bounds (:data:`RANGES`), which :mod:`masonry_dem.cases.schema`
checks and its errors quote."""

from __future__ import annotations

import math
from dataclasses import dataclass

from pydantic_core import PydanticCustomError

from masonry_dem._validation import GRID_MOST, plain

__all__ = ["RANGES", "Range"]


@dataclass(frozen=True)
class Range:
    """Allowed values of a number: ``lo`` <= x <= ``hi`` (``lo`` excluded when ``open_lo``),
    always finite; ``warn_above``: allowed, but logged with ``warn`` as the reason."""

    lo: float
    hi: float
    unit: str
    reason: str
    integer: bool = False
    open_lo: bool = False
    warn_above: float | None = None
    warn: str = ""

    def text(self) -> str:
        lo, hi = _bound(self.lo), _bound(self.hi)
        span = f"above {lo} up to {hi}" if self.open_lo else f"from {lo} to {hi}"
        unit = f" {self.unit}" if self.unit else ""
        kind = "a whole number" if self.integer else "a finite number"
        return f"{kind} {span}{unit} ({self.reason})"

    def check(self, value: float) -> float:
        ok = math.isfinite(value) and (value > self.lo if self.open_lo else value >= self.lo)
        if not (ok and value <= self.hi):
            raise PydanticCustomError("range", "must be {range}", {"range": self.text()})
        return value


def _bound(x: float) -> str:
    """1e14 rather than 100000000000000.0; 0.5 as it is."""
    if x != 0 and (abs(x) >= 1e5 or abs(x) < 1e-3):
        mantissa, exponent = f"{x:.3g}".split("e")
        return f"{mantissa}e{int(exponent)}"
    return plain(int(x)) if float(x).is_integer() else plain(float(x))


_SIZE = Range(
    0.0,
    1e3,
    "m",
    "sizes are in metres; larger values are millimetres typed as metres",
    open_lo=True,
)
_COUNT = Range(
    1, 10_000, "", "10^4 blocks along one direction already make 10^8 blocks", integer=True
)
COORDINATE = Range(-1e4, 1e4, "m", "a coordinate of a wall, in metres")
_STIFFNESS = Range(
    1e5,
    1e14,
    "N/m^3",
    "below 1e5 a joint under 1 m of masonry closes by more than 0.2 m, outside small "
    "displacements; above 1e14 the elastic displacements under the self weight fall below "
    "the solver's resolution and steps fail at once (kn = 1e300 gave a false collapse)",
)

#: Ranges of the physical and numerical values, by key (the same key means the same thing in
#: every table that has it). A key not here is typed by its builder's annotation only.
RANGES: dict[str, Range] = {
    # geometry
    "blocks_along_length": _COUNT,
    "courses": _COUNT,
    "block_height": _SIZE,
    "block_length": _SIZE,
    "thickness": _SIZE,
    "a": _SIZE,  # the paper's letters for the three above
    "b": _SIZE,
    "s": _SIZE,
    "length": _SIZE,
    "height": _SIZE,
    "depth": _SIZE,
    "joint": Range(0.0, 1.0, "m", "a mortar joint thicker than 1 m is no joint"),
    "overhang": Range(0.0, 1e3, "m", "sizes are in metres"),
    "unit_weight": Range(
        0.0,
        1e5,
        "N/m^3",
        "0 for weightless blocks; steel, the densest building material, is 78.5e3",
    ),
    # material
    "kn": _STIFFNESS,
    "kt": _STIFFNESS,
    "friction": Range(
        0.0,
        100.0,
        "",
        "mu = tan(phi): 0 is frictionless, 100 is phi = 89.4 degrees, a joint that cannot slide; "
        "larger values (friction 1e10 gave a false collapse) only spoil the conditioning",
        warn_above=2.0,
        warn="a friction coefficient above 2 (phi > 63 degrees) stands for interlocking (shear "
        "keys, toothed joints), not for friction between masonry units",
    ),
    "tensile_strength": Range(
        0.0, 1e8, "Pa", "0 for dry joints; 100 MPa is ten times the tensile strength of granite"
    ),
    "cohesion": Range(
        0.0,
        1e8,
        "Pa",
        "leave it out for friction x tensile_strength (the paper's reading); 100 MPa is ten "
        "times the shear strength of granite",
    ),
    "alpha": Range(0.0, 10.0, "", "exponent of Eq. (A5); the paper's value is 1.5", open_lo=True),
    # loads
    "value": Range(
        -1e9, 1e9, "Pa", "a pressure; 1e9 Pa is over ten times the crushing strength of masonry"
    ),
    "axis": Range(0, 2, "", "0: e1 along the wall, 1: e2 up, 2: e3 out of plane", integer=True),
    # analysis (fields of StaticSettings)
    "initial_step": Range(0.0, 1e3, "load scales", "a lambda increment", open_lo=True),
    "max_step": Range(0.0, 1e3, "load scales", "a lambda increment", open_lo=True),
    "growth": Range(1.0, 10.0, "", "factor on the step after an easy step; 1 keeps it"),
    "bracket_tolerance": Range(
        0.0, 0.5, "", "relative width of the collapse bracket", open_lo=True
    ),
    "tolerance": Range(
        0.0, 1e-2, "", "relative residual of an equilibrium; above 1 % it is none", open_lo=True
    ),
    "max_iterations": Range(1, 10**5, "", "Newton iterations per attempt", integer=True),
    "max_steps": Range(1, 10**7, "", "converged steps of one run", integer=True),
    "max_load_factor": Range(
        0.0,
        1e12,
        "",
        "lambda at which a run stops as completed; leave it out for no limit "
        "(-1 gave a collapse at 0)",
        open_lo=True,
    ),
    "displacement_limit": Range(
        0.0,
        1e3,
        "m",
        "largest translation still small; leave it out for half a block",
        open_lo=True,
    ),
    "residual_stiffness": Range(
        0.0, 1.0, "", "fraction of the elastic stiffness kept in the tangent", open_lo=True
    ),
    # [analysis] control and monitor
    "block": Range(0, 10**9, "", "a block index, counted from 0", integer=True),
    "target": Range(-1e3, 1e3, "m or rad", "a displacement to reach; not 0"),
    "steps": Range(1, 10**6, "", "steps to the target", integer=True),
    # plans (walls that meet)
    "return_blocks": _COUNT,
    "blocks_along_depth": _COUNT,
    # [analysis] of the limit analysis
    "grid": Range(
        2,
        GRID_MOST,
        "",
        "contact points along each side of an interface, grid x grid per interface",
        integer=True,
    ),
    "time_limit": Range(
        0, 1e6, "s", "the limit analysis's wall-clock budget; it stops there", open_lo=True
    ),
}
