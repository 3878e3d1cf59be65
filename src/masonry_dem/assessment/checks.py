"""The codes' checks of a mechanism (docs/assessment.md gives every formula and its clause):

* NTC 2018 with the Circolare 2019, C8.7.1.2.1: the linear kinematic check a0* >= demand (the
  mechanism at ground level, and at height Z in a building of height H, N storeys, first
  period T1 and damping xi1: the floor spectrum of C7.2.3, or the older Circolare 2009 form
  with ``demand_at_height="circolare_2009"``), and the nonlinear one: by default Circolare
  2019's, d_SLV >= S_De(T_SLV) at the mechanism's damping (C8.7.1.2.1.6, C8.7.1.2.1.8), or
  (``nonlinear_check="circolare_2009"``) the older d_u* >= SDe(Ts) with the secant period;
  both with their forms at height;
* EN 1998-1: the same capacity against its elastic spectrum: the linear check with the
  amplification of section 4.3.5.2 at height, and the N2 target displacement of Annex B.

:func:`assess` runs both checks of one code and returns an :class:`Assessment`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np

from masonry_dem.assessment.incremental import CONTACT_GAP
from masonry_dem.assessment.kinematics import (
    KINEMATICS,
    MOVING,
    CapacityCurve,
    Mechanism,
    interpenetration,
    support_drift,
)
from masonry_dem.assessment.spectra import (
    FLOOR_B,
    EC8Spectrum,
    G,
    NTC2018Spectrum,
    Spectrum,
    check_range,
    floor_acceleration,
    floor_spectrum,
    with_damping,
)
from masonry_dem.model import Model

Code = Literal["ntc2018", "ec8"]
CODES: tuple[str, ...] = ("ntc2018", "ec8")
#: the NTC 2018 demand on a mechanism at height: Circolare 2019 C7.2.3's floor spectrum
#: (default) or the Circolare 2009 form Se(T1) psi gamma / q
DEMANDS_AT_HEIGHT: tuple[str, ...] = ("floor_spectrum", "circolare_2009")
#: the NTC 2018 nonlinear kinematic check: Circolare 2019 C8.7.1.2.1.6/.8 (T_SLV [C8.7.1.10],
#: default) or the Circolare 2009 secant period Ts at d_s* = 0.4 d_u* (C8A.4.2.2)
NONLINEAR_CHECKS: tuple[str, ...] = ("circolare_2019", "circolare_2009")
#: the ultimate limit states of Circolare 2019 C8.7.1.2.1.6 ("con riferimento ad uno dei due")
LIMIT_STATES: tuple[str, ...] = ("SLV", "SLC")
#: C8.7.1.2.1.6: d_SLV is "il 40% dello spostamento d_0", d_SLC "il 60%" (each the smaller of it
#: and a displacement the package cannot compute: a broken tie, a beam pulled out, a vault)
LIMIT_SHARE: dict[str, float] = {"SLV": 0.4, "SLC": 0.6}
#: C8.7.1.2.1.8: T_SLV = 1.68 pi sqrt(d_SLV / a(d_SLV)) [C8.7.1.10], T_SLC = 1.56 pi ... [C8.7.1.11]
PERIOD_FACTOR: dict[str, float] = {"SLV": 1.68, "SLC": 1.56}
#: an overlap [m] at d_u* at or below which ``kinematics = "auto"`` counts a finite motion as
#: admissible: the closed-form motions are then kept (in KINEMATICS' order) and the
#: incremental path, which costs a factorization or two per step, is not integrated (round
#: off leaves 1e-17 m on a hinged chain, the incremental path 1e-11 to 1e-8 m on closed loops)
OVERLAP_FLOOR = 1e-9
#: C8.7.1.2.1.8: the mechanism's equivalent viscous damping "in assenza di valutazioni più
#: accurate ... pari all'8% per lo SLV e al 10% per lo SLC" [%]
LIMIT_DAMPING: dict[str, float] = {"SLV": 8.0, "SLC": 10.0}
#: C1 of T1 = C1 H^(3/4) for masonry buildings (NTC 2018 [7.3.6] of section 7.3.3.2, as
#: Circolare 2019 C7.2.3 names it; the value 0.050 is not checked against a text)
C1_MASONRY = 0.050


@dataclass(frozen=True)
class Building:
    """Where the mechanism sits: ``Z`` [m] the height of the hinge of the mechanism above the
    foundation (0: at ground level), ``H`` [m] the building's height, ``storeys`` N, ``T1``
    [s] its first period (None: C1 H^(3/4), C1 = 0.050), ``damping`` xi1 [%] the equivalent
    viscous damping of its first mode (the floor spectrum's, Circolare 2019 C7.2.3)."""

    Z: float = 0.0
    H: float | None = None
    storeys: int = 1
    T1: float | None = None
    damping: float = 5.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "Z", check_range("Z", self.Z, 0.0, 500.0, "m"))
        if self.H is not None:
            set_(self, "H", check_range("H", self.H, 0.0, 500.0, "m", low_open=True))
        if isinstance(self.storeys, bool) or not isinstance(self.storeys, (int, np.integer)):
            raise ValueError(f"storeys = {self.storeys!r}: must be a whole number in [1, 100]")
        check_range("storeys", self.storeys, 1, 100, "")
        if self.T1 is not None:
            set_(self, "T1", check_range("T1", self.T1, 0.0, 10.0, "s", low_open=True))
        set_(
            self,
            "damping",
            check_range("building_damping", self.damping, 0.0, 30.0, "%", low_open=True),
        )
        if self.Z > 0 and self.H is None:
            raise ValueError(
                f"Z = {self.Z:g} m: a mechanism at height needs H, the building's height [m]"
            )
        if self.H is not None and self.Z > self.H:
            raise ValueError(f"Z = {self.Z:g} out of range: must be in [0, H = {self.H:g}] m")

    @property
    def at_height(self) -> bool:
        return self.Z > 0

    @property
    def psi(self) -> float:
        """psi(Z) = Z / H, the first mode's shape."""
        return self.Z / self.H if self.H else 0.0

    @property
    def gamma(self) -> float:
        """gamma = 3N / (2N + 1), the first mode's participation factor (Circolare 2019
        [C7.2.10], for masses even along the height and a linear first mode)."""
        return 3.0 * self.storeys / (2.0 * self.storeys + 1.0)

    @property
    def period(self) -> float:
        """T1 given, or C1 H^(3/4)."""
        if self.T1 is not None:
            return self.T1
        if self.H is None:
            raise ValueError("T1: give the first period or H, the building's height")
        return C1_MASONRY * self.H**0.75


@dataclass(frozen=True)
class Assessment:
    """What ``assessment.json`` holds (SI units: m, s, m/s2, kg, N)."""

    code: str
    alpha0: float
    alpha0_source: str
    alpha_rigid: float
    M_star: float
    e_star: float
    total_weight: float
    moving_blocks: int
    FC: float
    q: float
    a0_star: float
    demand: float
    demand_ground: float
    demand_height: float | None
    ratio: float
    passes: bool
    d_k0: float | None
    d0_star: float | None
    du_star: float | None
    ds_star: float | None
    as_star: float | None
    Ts: float | None
    displacement_demand: float | None
    displacement_ratio: float | None
    passes_nonlinear: bool | None
    nonlinear_reason: str
    rotation_at_end_deg: float
    control_point: list[float]
    direction: list[float]
    Z: float
    H: float | None
    storeys: int
    T1: float | None
    spectrum: dict[str, Any]
    demand_at_height: str = "floor_spectrum"
    building_damping: float = 5.0
    #: NTC 2018: which nonlinear check was made (:data:`NONLINEAR_CHECKS`); None with ec8
    nonlinear_check: str | None = None
    #: Circolare 2019: the limit state checked, SLV or SLC (None otherwise)
    limit_state: str | None = None
    #: Circolare 2019 SLV: d_SLV [m], a(d_SLV) [m/s2], T_SLV [s] (None otherwise)
    d_SLV: float | None = None
    a_SLV: float | None = None
    T_SLV: float | None = None
    #: Circolare 2019 SLC: d_SLC [m], a(d_SLC) [m/s2], T_SLC [s] (None otherwise)
    d_SLC: float | None = None
    a_SLC: float | None = None
    T_SLC: float | None = None
    #: Circolare 2019: the mechanism's damping xi of the displacement demand [%]
    nonlinear_damping: float | None = None
    #: the displacement the demand is checked against [m]: d_SLV, d_SLC or d_u*
    displacement_capacity: float | None = None
    #: the period of the displacement demand [s]: T_SLV, T_SLC or Ts
    nonlinear_period: float | None = None
    #: Circolare 2019: a0* over the linear demand without q, a_g,SLD / a_g in the package's
    #: reading (C8.7.1.2.1.8: a_g,SLV is at least a_g,SLD)
    activation_ratio: float | None = None
    #: the nonlinear check in words, with its numbers and units
    nonlinear_summary: str = ""

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def spectrum_of(code: str, **params: Any) -> Spectrum:
    """The elastic spectrum of ``code`` from its parameters (others are refused by name)."""
    if code == "ntc2018":
        return NTC2018Spectrum(**params)
    if code == "ec8":
        return EC8Spectrum(**params)
    raise ValueError(f"code = {code!r}: must be one of {', '.join(CODES)}")


def spectrum_summary(spectrum: Spectrum) -> dict[str, Any]:
    """The spectrum's parameters and derived values (S, eta, TB, TC, TD) for the report."""
    out: dict[str, Any] = {k: v for k, v in vars(spectrum).items()}
    out.update(
        S=spectrum.S,
        eta=spectrum.eta,
        TB=spectrum.TB,
        TC=spectrum.TC,
        TD=spectrum.TD,
        pga=spectrum.pga(),
    )
    if isinstance(spectrum, NTC2018Spectrum):
        out.update(S_S=spectrum.S_S, S_T=spectrum.S_T, C_C=spectrum.C_C)
    return out


def check_demand_at_height(value: object) -> str:
    """``value`` as one of :data:`DEMANDS_AT_HEIGHT`, else a one-line ValueError naming it."""
    if value not in DEMANDS_AT_HEIGHT:
        raise ValueError(
            f"demand_at_height = {value!r}: must be one of {', '.join(DEMANDS_AT_HEIGHT)}"
        )
    return str(value)


def check_nonlinear_check(value: object) -> str:
    """``value`` as one of :data:`NONLINEAR_CHECKS`, else a one-line ValueError naming it."""
    if value not in NONLINEAR_CHECKS:
        raise ValueError(
            f"nonlinear_check = {value!r}: must be one of {', '.join(NONLINEAR_CHECKS)}"
        )
    return str(value)


def check_limit_state(value: object, nonlinear_check: str = "circolare_2019") -> str:
    """``value`` as one of :data:`LIMIT_STATES` (SLC with the Circolare 2019 check only), else
    a one-line ValueError naming it."""
    if value not in LIMIT_STATES:
        raise ValueError(f"limit_state = {value!r}: must be one of {', '.join(LIMIT_STATES)}")
    if value != "SLV" and nonlinear_check != "circolare_2019":
        raise ValueError(
            f"limit_state = {value!r}: must be SLV with nonlinear_check = {nonlinear_check} "
            "(SLC is a check of circolare_2019 only)"
        )
    return str(value)


def ntc_linear_demand(
    spectrum: Spectrum, building: Building, q: float, demand_at_height: str = "floor_spectrum"
) -> tuple[float, float | None]:
    """NTC 2018 / Circolare: the spectral acceleration a0* must reach [m/s2]: at ground level
    ag S / q; at height also a_Z(Z) / q, the floor's peak acceleration of Circolare 2019
    [C7.2.7]-[C7.2.8] (``"floor_spectrum"``: C8.7.1.2.1.5 [C8.7.1.8] and C8.7.1.2.1.7), or
    Se(T1) psi(Z) gamma / q (``"circolare_2009"``). Returns (ground, height or None)."""
    check_demand_at_height(demand_at_height)
    ground = spectrum.pga() / q
    if not building.at_height:
        return ground, None
    T1 = building.period
    if demand_at_height == "floor_spectrum":
        a_Z = floor_acceleration(spectrum, T1, building.gamma, building.psi, building.damping)
        return ground, a_Z / q
    height = float(spectrum.acceleration(T1)) * building.psi * building.gamma / q
    return ground, height


def ec8_amplification(building: Building, Ta: float) -> float:
    """EN 1998-1 (4.25) over alpha S: 3 (1 + z/H) / (1 + (1 - Ta/T1)^2) - 0.5, at least 1."""
    if not building.at_height:
        return 1.0
    T1 = building.period
    return max(3.0 * (1.0 + building.psi) / (1.0 + (1.0 - Ta / T1) ** 2) - 0.5, 1.0)


def ntc_displacement_demand(
    spectrum: Spectrum, building: Building, Ts: float, demand_at_height: str = "floor_spectrum"
) -> float:
    """Circolare nonlinear check, the displacement demand [m] at the period ``Ts`` (Circolare
    2019's T_SLV or T_SLC [C8.7.1.10]-[C8.7.1.11], or the 2009 secant period) on
    ``spectrum`` (at the mechanism's damping xi): SDe(Ts) at ground level (C8.7.1.2.1.8,
    S_De of NTC 2018 section 3.2.3.2.3); at height the larger of it and, with
    ``"floor_spectrum"``, the floor's displacement spectrum of Circolare 2019 C8.7.1.2.1.8:
    S_eZ(Ts, xi, Z) Ts^2 / 4 pi^2, at least S_eZ(T1, xi, Z) b^2 T1^2 / 4 pi^2 when Ts > b T1
    ([C8.7.1.12]); with ``"circolare_2009"``, SDe(T1) psi gamma (Ts/T1)^2 /
    sqrt((1 - Ts/T1)^2 + 0.02 Ts/T1)."""
    check_demand_at_height(demand_at_height)
    ground = float(spectrum.displacement(Ts))
    if not building.at_height:
        return ground
    T1 = building.period
    if demand_at_height == "floor_spectrum":
        args = (T1, building.gamma, building.psi, building.damping)
        height = float(floor_spectrum(spectrum, Ts, *args)[()]) * Ts**2 / (4.0 * math.pi**2)
        if Ts > FLOOR_B * T1:
            bound = float(floor_spectrum(spectrum, T1, *args)[()]) * (FLOOR_B * T1) ** 2
            height = max(height, bound / (4.0 * math.pi**2))
        return max(ground, height)
    r = Ts / T1
    height = (
        float(spectrum.displacement(T1))
        * building.psi
        * building.gamma
        * r**2
        / math.sqrt((1.0 - r) ** 2 + 0.02 * r)
    )
    return max(ground, height)


def n2_target(spectrum: Spectrum, T_star: float, a_y: float) -> float:
    """EN 1998-1 Annex B target displacement d_t* [m] of an SDOF of period ``T_star`` and
    yield acceleration ``a_y`` [m/s2]: d_et* = Se(T*) (T*/2pi)^2 (B.8); T* >= TC: d_et*
    (B.9); T* < TC: d_et* if a_y >= Se(T*), else d_et*/q_u (1 + (q_u - 1) TC/T*) >= d_et*,
    q_u = Se(T*) / a_y (B.10)-(B.11)."""
    Se = float(spectrum.acceleration(T_star))
    d_et = Se * (T_star / (2.0 * math.pi)) ** 2
    if T_star >= spectrum.TC or a_y >= Se:
        return d_et
    q_u = Se / a_y
    return max(d_et / q_u * (1.0 + (q_u - 1.0) * spectrum.TC / T_star), d_et)


def assess(
    mechanism: Mechanism,
    code: str,
    spectrum: Spectrum,
    building: Building | None = None,
    q: float = 2.0,
    FC: float = 1.35,
    alpha0: float | None = None,
    demand_at_height: str = "floor_spectrum",
    nonlinear_check: str = "circolare_2019",
    limit_state: str = "SLV",
    nonlinear_damping: float | None = None,
) -> tuple[Assessment, CapacityCurve]:
    """The linear and nonlinear kinematic checks of ``mechanism`` under ``code``.

    ``alpha0`` the multiplier that activates the mechanism (None: the virtual work of the
    loads alone, :attr:`Mechanism.alpha_rigid`); ``q`` the behaviour factor of the linear
    check (2.0 in the Circolare), ``FC`` the confidence factor; ``demand_at_height`` the NTC
    2018 demand on a mechanism at height (:data:`DEMANDS_AT_HEIGHT`).

    NTC 2018's nonlinear check, ``nonlinear_check`` (:data:`NONLINEAR_CHECKS`):
    ``"circolare_2019"`` checks ``limit_state`` (SLV or SLC) by Circolare 2019 C8.7.1.2.1.6
    and .8 with the mechanism's damping ``nonlinear_damping`` [%] (None: the clause's 8 % for
    the SLV, 10 % for the SLC; the spectrum's own damping is not used for it);
    ``"circolare_2009"`` the secant period Ts on the spectrum as given. EN 1998-1 takes the
    secant period as its T* whatever these say. Returns the assessment and the capacity curve
    (its a* with FC = 1)."""
    building = building or Building()
    check_demand_at_height(demand_at_height)
    nonlinear_check = check_nonlinear_check(nonlinear_check)
    limit_state = check_limit_state(limit_state, nonlinear_check)
    q = check_range("q", q, 1.0, 10.0, "(dimensionless)")
    FC = check_range("FC", FC, 1.0, 3.0, "(dimensionless)")
    if code not in CODES:
        raise ValueError(f"code = {code!r}: must be one of {', '.join(CODES)}")
    circ2019 = code == "ntc2018" and nonlinear_check == "circolare_2019"
    if nonlinear_damping is not None:
        if not circ2019:
            raise ValueError(
                f"nonlinear_damping = {nonlinear_damping!r}: a parameter of the ntc2018 "
                "nonlinear_check circolare_2019 only"
            )
        nonlinear_damping = check_range("damping", nonlinear_damping, 0.0, 30.0, "%")
    source = "virtual work of the loads" if alpha0 is None else "the analysis's multiplier"
    alpha_rigid = mechanism.alpha_rigid
    a0 = alpha_rigid if alpha0 is None else float(alpha0)
    m_star, e_star = mechanism.participating_mass()
    a0_star = a0 * G / (e_star * FC)

    curve = mechanism.capacity_curve(alpha0)
    nonlinear: dict[str, Any] = dict.fromkeys(
        (
            "d_k0",
            "d0_star",
            "du_star",
            "ds_star",
            "as_star",
            "Ts",
            "displacement_demand",
            "displacement_ratio",
            "passes_nonlinear",
        )
    )
    states: dict[str, Any] = {}
    period = capacity = None
    xi = None
    if circ2019:
        xi = LIMIT_DAMPING[limit_state] if nonlinear_damping is None else nonlinear_damping
    if curve.complete:
        nonlinear.update(d_k0=curve.d_k0, d0_star=curve.d0_star)
        s_end = float(curve.s[-1])
        # the curve's secant period, Circolare 2009 C8A.4.2.2: d_u* = 0.4 d0*, Ts = 2 pi
        # sqrt(d_s*/a_s*) at d_s* = 0.4 d_u* (EN 1998-1's T* here); the 2009 check's and
        # EC8's, and reported beside the 2019 check (which reads T_SLV or T_SLC)
        du = 0.4 * curve.d0_star
        ds = 0.4 * du
        s_s = mechanism.configuration_at(ds * e_star, s_end)
        as_star = float(mechanism.alpha(s_s, alpha0)[0]) * G / (e_star * FC)
        secant = 2.0 * math.pi * math.sqrt(ds / as_star)
        nonlinear.update(du_star=du, ds_star=ds, as_star=as_star, Ts=secant)
        if circ2019:
            # C8.7.1.2.1.6: d_SLV = 0.4 d0 (d_SLC = 0.6 d0), d0 where a(d) = 0
            capacity = LIMIT_SHARE[limit_state] * curve.d0_star
            s_ls = mechanism.configuration_at(capacity * e_star, s_end)
            # a(d) of the curve with FC, as a0* takes it ([C8.7.1.3], [C8.7.1.8])
            a_ls = float(mechanism.alpha(s_ls, alpha0)[0]) * G / (e_star * FC)
            # [C8.7.1.10] / [C8.7.1.11]: T = 1.68 (1.56) pi sqrt(d / a(d))
            period = PERIOD_FACTOR[limit_state] * math.pi * math.sqrt(capacity / a_ls)
            states = {
                f"d_{limit_state}": capacity,
                f"a_{limit_state}": a_ls,
                f"T_{limit_state}": period,
            }
        else:
            capacity, period = du, secant

    if code == "ntc2018":
        ground, height = ntc_linear_demand(spectrum, building, q, demand_at_height)
        # C8.7.1.2.1.8: the demand spectrum at the mechanism's damping xi (8 % SLV, 10 % SLC)
        demand_spectrum = spectrum if xi is None else with_damping(spectrum, xi)
        disp = (
            None
            if period is None
            else ntc_displacement_demand(demand_spectrum, building, period, demand_at_height)
        )
    else:
        Ts = nonlinear["Ts"]
        ground = spectrum.pga() / q
        # Ta = Ts; with no Ts (no alpha = 0), Ta = T1: the resonant, largest amplification
        amp = (
            ec8_amplification(building, Ts if Ts is not None else building.period)
            if building.at_height
            else 1.0
        )
        height = ground * amp if building.at_height else None
        disp = None if Ts is None else n2_target(spectrum, Ts, a0_star) * amp
    demand = max(ground, height or 0.0)
    ratio = a0_star / demand
    # a0* against the linear demand without q: the mechanism not activated at the site's ag
    activation = ratio / q if circ2019 else None
    summary = "no nonlinear check: " + curve.reason if disp is None else ""
    if disp is not None:
        assert capacity is not None and period is not None
        passes_nl = capacity >= disp
        if circ2019 and limit_state == "SLV" and activation is not None and activation >= 1.0:
            # C8.7.1.2.1.8: "nel caso in cui [a_g,SLV] risulti minore di a_g,SLD ... si assume
            # quest'ultima anche per lo SLV": a_g,SLD >= a_g passes the SLV check too
            passes_nl = True
        nonlinear.update(
            displacement_demand=disp,
            displacement_ratio=capacity / disp,
            passes_nonlinear=bool(passes_nl),
        )
        summary = _nonlinear_summary(
            code,
            nonlinear_check if code == "ntc2018" else None,
            limit_state,
            capacity,
            period,
            disp,
            xi,
            activation,
            spectrum.damping,
            building.at_height,
        )
    assessment = Assessment(
        code=code,
        alpha0=a0,
        alpha0_source=source,
        alpha_rigid=alpha_rigid,
        M_star=m_star,
        e_star=e_star,
        total_weight=mechanism.total_weight,
        moving_blocks=int(mechanism.moving.sum()),
        FC=FC,
        q=q,
        a0_star=a0_star,
        demand=demand,
        demand_ground=ground,
        demand_height=height,
        ratio=ratio,
        passes=bool(ratio >= 1.0),
        **nonlinear,
        nonlinear_reason=curve.reason,
        rotation_at_end_deg=math.degrees(curve.rotation),
        control_point=mechanism.control_point().tolist(),
        direction=mechanism.direction.tolist(),
        Z=building.Z,
        H=building.H,
        storeys=building.storeys,
        T1=building.period if building.at_height else building.T1,
        spectrum=spectrum_summary(spectrum),
        demand_at_height=demand_at_height,
        building_damping=building.damping,
        nonlinear_check=nonlinear_check if code == "ntc2018" else None,
        limit_state=limit_state if circ2019 else None,
        **states,
        nonlinear_damping=xi,
        displacement_capacity=capacity,
        nonlinear_period=period,
        activation_ratio=activation,
        nonlinear_summary=summary,
    )
    return assessment, curve


def _nonlinear_summary(
    code: str,
    check: str | None,
    state: str,
    capacity: float,
    period: float,
    demand: float,
    xi: float | None,
    activation: float | None,
    spectrum_damping: float,
    at_height: bool,
) -> str:
    """The nonlinear check in one line, its clauses, numbers and units."""
    where = "S_De and the floor spectrum at Z" if at_height else "S_De at ground level"
    if check == "circolare_2019":
        factor = PERIOD_FACTOR[state]
        share = LIMIT_SHARE[state]
        text = (
            f"Circolare 2019 C8.7.1.2.1.6/.8, {state}: d_{state} = {share:g} d0* = "
            f"{1e3 * capacity:.4g} mm, T_{state} = {factor:g} pi sqrt(d_{state} / "
            f"a(d_{state})) = {period:.4g} s, demand ({where}, xi = {xi:g} %) = "
            f"{1e3 * demand:.4g} mm"
        )
        if state == "SLV" and activation is not None:
            text += (
                f"; a0* over the linear demand without q = {activation:.3g} (a_g,SLD / a_g"
                + (", which passes the SLV" if activation >= 1.0 else "")
                + ")"
            )
        return text
    if check == "circolare_2009":
        return (
            f"Circolare 2009 C8A.4.2.2: d_u* = 0.4 d0* = {1e3 * capacity:.4g} mm, secant "
            f"period Ts = {period:.4g} s at d_s* = 0.4 d_u*, demand ({where}, xi = "
            f"{spectrum_damping:g} %) = {1e3 * demand:.4g} mm"
        )
    return (
        f"EN 1998-1 Annex B (N2): d_u* = 0.4 d0* = {1e3 * capacity:.4g} mm, T* = Ts = "
        f"{period:.4g} s, target displacement = {1e3 * demand:.4g} mm"
    )


def assess_mode(
    model: Model,
    mode: Any,
    code: str,
    spectrum: Spectrum,
    building: Building | None = None,
    q: float = 2.0,
    FC: float = 1.35,
    load_factor: float | None = None,
    moving: float = MOVING,
    kinematics: str = "auto",
    demand_at_height: str = "floor_spectrum",
    nonlinear_check: str = "circolare_2019",
    limit_state: str = "SLV",
    nonlinear_damping: float | None = None,
) -> tuple[Assessment, CapacityCurve, Mechanism, dict[str, Any]]:
    """:func:`assess` of a rigid-block mode (n, 6) on ``model``: alpha0 the analysis's
    ``load_factor`` in the codes' terms (None: the virtual work of the loads).

    ``kinematics`` ``"chain"``, ``"independent"`` or ``"incremental"`` (:meth:`Mechanism.of`),
    or ``"auto"``: the one whose finite motion overlaps the least across the joints at d_u*
    (:func:`~masonry_dem.assessment.kinematics.interpenetration`; a curve with no alpha = 0
    counts as no check at all; overlaps up to :data:`OVERLAP_FLOOR` count as none, ties go
    to the first of KINEMATICS), the incremental path tried only when neither closed-form
    motion is admissible; ``demand_at_height``, ``nonlinear_check``, ``limit_state``
    and ``nonlinear_damping`` as :func:`assess` takes them. Returns the assessment, its
    curve, its mechanism and what chose it: ``kinematics``, ``overlap_at_du`` [m] (at the
    displacement capacity: d_SLV, d_SLC or d_u*) and ``overlaps`` of each candidate."""
    if kinematics != "auto" and kinematics not in KINEMATICS:
        raise ValueError(
            f"kinematics = {kinematics!r}: must be auto, chain, independent or incremental"
        )
    candidates = KINEMATICS if kinematics == "auto" else (kinematics,)
    found: dict[str, tuple[Assessment, CapacityCurve, Mechanism, float, float]] = {}
    for name in candidates:
        if (
            kinematics == "auto"
            and name == "incremental"
            and min(max(v[3], v[4]) for v in found.values()) <= OVERLAP_FLOOR
        ):
            continue
        mech = Mechanism.of(model, mode, moving, name)
        alpha0 = None if load_factor is None else load_factor * mech.scale
        out, curve = assess(
            mech,
            code,
            spectrum,
            building,
            q,
            FC,
            alpha0,
            demand_at_height,
            nonlinear_check,
            limit_state,
            nonlinear_damping,
        )
        if out.displacement_capacity is None:
            overlap = drift = math.inf
        else:
            s_du = mech.configuration_at(out.displacement_capacity * out.e_star, float(curve.s[-1]))
            overlap = interpenetration(mech, model, s_du)
            drift = support_drift(mech, model, s_du)
        found[name] = (out, curve, mech, overlap, drift)

    def error(name: str) -> float:
        """How far a finite motion is from admissible at d_u*: its overlap or its held
        blocks' drift, whichever is larger (up to the floor: none)."""
        worst = max(found[name][3], found[name][4])
        return worst if worst > OVERLAP_FLOOR else 0.0

    # ties (up to the floor among them): the first listed, the chain first
    best = min(found, key=error)
    out, curve, mech, overlap, drift = found[best]
    least = float(np.asarray(model.blocks.sizes, dtype=float)[mech.moving].min())
    info = {
        "kinematics": best,
        "overlap_at_du": overlap,
        "overlaps": {k: v[3] for k, v in found.items()},
        "drift_at_du": drift,
        "drifts": {k: v[4] for k, v in found.items()},
        "least_block_size": least,
        "motion_note": motion_note(best, overlap, drift, least, found),
    }
    return out, curve, mech, info


def motion_note(
    best: str,
    overlap: float,
    drift: float,
    least: float,
    found: Mapping[str, tuple[Assessment, CapacityCurve, Mechanism, float, float]],
) -> str:
    """What an engineer must know of the finite motion the nonlinear check rests on, when it
    is not admissible: its blocks overlap, or a held block drifts, at the displacement
    capacity by more than :data:`~masonry_dem.assessment.incremental.CONTACT_GAP` of the
    moving blocks' least size ``least`` (the gap at which the incremental path takes two
    blocks as in contact): by how much, against ``least``, and whether the incremental path
    was tried in vain. Empty when the motion is admissible or was not checked."""
    worst = max(overlap, drift)
    if not math.isfinite(worst) or worst <= CONTACT_GAP * least:
        return ""
    parts = []
    if overlap > CONTACT_GAP * least:
        parts.append(f"its blocks overlap by {1e3 * overlap:.3g} mm")
    if drift > CONTACT_GAP * least:
        parts.append(f"a held block drifts by {1e3 * drift:.3g} mm")
    text = (
        f"the finite motion of the nonlinear check ({best} kinematics) is not admissible at "
        f"the displacement capacity: {' and '.join(parts)}, {100 * worst / least:.2g} % of "
        f"the moving blocks' least size ({1e3 * least:.3g} mm)"
    )
    incremental = found.get("incremental")
    if incremental is not None and incremental[1].reason:
        # its reason in full is the incremental run's nonlinear_reason (--kinematics)
        text += "; the incremental path, which keeps the contacts, reaches no alpha = 0"
    return text
