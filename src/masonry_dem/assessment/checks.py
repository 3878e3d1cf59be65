"""The codes' checks of a mechanism (docs/assessment.md gives every formula and its clause):

* NTC 2018 with the Circolare 2019, C8.7.1.2.1: the linear kinematic check a0* >= demand (the
  mechanism at ground level, and at height Z in a building of height H, N storeys, first
  period T1 and damping xi1: the floor spectrum of C7.2.3, or the older Circolare 2009 form
  with ``demand_at_height="circolare_2009"``), and the nonlinear one d_u* >= SDe(Ts) (and its
  form at height);
* EN 1998-1: the same capacity against its elastic spectrum: the linear check with the
  amplification of section 4.3.5.2 at height, and the N2 target displacement of Annex B.

:func:`assess` runs both checks of one code and returns an :class:`Assessment`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np

from masonry_dem.assessment.kinematics import (
    KINEMATICS,
    MOVING,
    CapacityCurve,
    Mechanism,
    interpenetration,
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
)
from masonry_dem.model import Model

Code = Literal["ntc2018", "ec8"]
CODES: tuple[str, ...] = ("ntc2018", "ec8")
#: the NTC 2018 demand on a mechanism at height: Circolare 2019 C7.2.3's floor spectrum
#: (default) or the Circolare 2009 form Se(T1) psi gamma / q
DEMANDS_AT_HEIGHT: tuple[str, ...] = ("floor_spectrum", "circolare_2009")
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
    """Circolare nonlinear check: SDe(Ts) at ground level (C8.7.1.2.1.8, with the Circolare
    2009 secant period Ts, not 2019's T_SLV [C8.7.1.10]); at height the larger of it
    and, with ``"floor_spectrum"``, the floor's displacement spectrum of Circolare 2019
    C8.7.1.2.1.8: S_eZ(Ts, xi, Z) Ts^2 / 4 pi^2, at least S_eZ(T1, xi, Z) b^2 T1^2 / 4 pi^2
    when Ts > b T1 ([C8.7.1.12]); with ``"circolare_2009"``, SDe(T1) psi gamma (Ts/T1)^2 /
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
) -> tuple[Assessment, CapacityCurve]:
    """The linear and nonlinear kinematic checks of ``mechanism`` under ``code``.

    ``alpha0`` the multiplier that activates the mechanism (None: the virtual work of the
    loads alone, :attr:`Mechanism.alpha_rigid`); ``q`` the behaviour factor of the linear
    check (2.0 in the Circolare), ``FC`` the confidence factor; ``demand_at_height`` the NTC
    2018 demand on a mechanism at height (:data:`DEMANDS_AT_HEIGHT`). Returns the assessment
    and the capacity curve (its a* with FC = 1)."""
    building = building or Building()
    check_demand_at_height(demand_at_height)
    q = check_range("q", q, 1.0, 10.0, "(dimensionless)")
    FC = check_range("FC", FC, 1.0, 3.0, "(dimensionless)")
    if code not in CODES:
        raise ValueError(f"code = {code!r}: must be one of {', '.join(CODES)}")
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
    Ts = None
    if curve.complete:
        du = 0.4 * curve.d0_star
        ds = 0.4 * du
        s_s = mechanism.configuration_at(ds * e_star, float(curve.s[-1]))
        as_star = float(mechanism.alpha(s_s, alpha0)[0]) * G / (e_star * FC)
        Ts = 2.0 * math.pi * math.sqrt(ds / as_star)
        nonlinear.update(
            d_k0=curve.d_k0, d0_star=curve.d0_star, du_star=du, ds_star=ds, as_star=as_star, Ts=Ts
        )

    if code == "ntc2018":
        ground, height = ntc_linear_demand(spectrum, building, q, demand_at_height)
        disp = (
            None
            if Ts is None
            else ntc_displacement_demand(spectrum, building, Ts, demand_at_height)
        )
    else:
        ground = spectrum.pga() / q
        # Ta = Ts; with no Ts (no alpha = 0), Ta = T1: the resonant, largest amplification
        amp = (
            ec8_amplification(building, Ts if Ts is not None else building.period)
            if building.at_height
            else 1.0
        )
        height = ground * amp if building.at_height else None
        disp = None if Ts is None else n2_target(spectrum, Ts, a0_star) * amp
    if disp is not None:
        du = nonlinear["du_star"]
        nonlinear.update(
            displacement_demand=disp,
            displacement_ratio=du / disp,
            passes_nonlinear=bool(du >= disp),
        )
    demand = max(ground, height or 0.0)
    ratio = a0_star / demand
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
    )
    return assessment, curve


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
) -> tuple[Assessment, CapacityCurve, Mechanism, dict[str, Any]]:
    """:func:`assess` of a rigid-block mode (n, 6) on ``model``: alpha0 the analysis's
    ``load_factor`` in the codes' terms (None: the virtual work of the loads).

    ``kinematics`` ``"chain"`` or ``"independent"`` (:meth:`Mechanism.of`), or ``"auto"``:
    both, and the one whose finite motion overlaps the least across the joints at d_u*
    (:func:`~masonry_dem.assessment.kinematics.interpenetration`; a curve with no alpha = 0
    counts as no check at all); ``demand_at_height`` as :func:`assess` takes it. Returns the
    assessment, its curve, its mechanism and what
    chose it: ``kinematics``, ``overlap_at_du`` [m] and ``overlaps`` of each candidate."""
    if kinematics != "auto" and kinematics not in KINEMATICS:
        raise ValueError(f"kinematics = {kinematics!r}: must be auto, chain or independent")
    candidates = KINEMATICS if kinematics == "auto" else (kinematics,)
    found: dict[str, tuple[Assessment, CapacityCurve, Mechanism, float]] = {}
    for name in candidates:
        mech = Mechanism.of(model, mode, moving, name)
        alpha0 = None if load_factor is None else load_factor * mech.scale
        out, curve = assess(mech, code, spectrum, building, q, FC, alpha0, demand_at_height)
        if out.du_star is None:
            overlap = math.inf
        else:
            s_du = mech.configuration_at(out.du_star * out.e_star, float(curve.s[-1]))
            overlap = interpenetration(mech, model, s_du)
        found[name] = (out, curve, mech, overlap)
    best = min(candidates, key=lambda k: found[k][3])  # ties: the chain, listed first
    out, curve, mech, overlap = found[best]
    info = {
        "kinematics": best,
        "overlap_at_du": overlap,
        "overlaps": {k: v[3] for k, v in found.items()},
    }
    return out, curve, mech, info
