"""Elastic response spectra of the codes: NTC 2018 section 3.2.3.2 and EN 1998-1 section
3.2.2.2, as frozen dataclasses of their parameters, each checked where it is given: a value
out of range is one line naming the field, the value, the range and the unit; and the floor
spectrum of Circolare 2019 C7.2.3 (:func:`floor_spectrum`) for a mechanism at height.

Accelerations are returned in m/s2 (the parameters ``ag`` are in g), displacements in m,
periods in s. Every formula and its clause is in docs/assessment.md.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: the acceleration of gravity of the codes' examples [m/s2]
G = 9.81

Soil = Literal["A", "B", "C", "D", "E"]
SOILS: tuple[str, ...] = ("A", "B", "C", "D", "E")
TOPOGRAPHY: dict[str, float] = {"T1": 1.0, "T2": 1.2, "T3": 1.2, "T4": 1.4}  # NTC Tab. 3.2.V


def check_range(
    name: str, value: object, low: float, high: float, unit: str, low_open: bool = False
) -> float:
    """``value`` as a finite float in [low, high] (``(low, high]`` if ``low_open``), else a
    ValueError naming ``name``, the value, the range and the unit."""
    opening = "(" if low_open else "["
    bracket = f"{opening}{low:g}, {high:g}] {unit}".rstrip()
    if isinstance(value, (str, bytes)):  # a quoted number in a file is text, as case files say
        raise ValueError(f"{name} = {value!r}: must be a number (without quotes) in {bracket}")
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r}: must be a number in {bracket}") from None
    if isinstance(value, bool) or not math.isfinite(number):
        raise ValueError(f"{name} = {value!r}: must be a number in {bracket}")
    if number < low or number > high or (low_open and number == low):
        raise ValueError(f"{name} = {value!r} out of range: must be in {bracket}")
    return number


def check_choice(name: str, value: object, allowed: tuple[str, ...], what: str) -> str:
    """``value`` as one of ``allowed``, else a ValueError naming ``name`` and ``what`` it is."""
    if not isinstance(value, str) or value.upper() not in allowed:
        raise ValueError(f"{name} = {value!r}: must be one of {', '.join(allowed)} ({what})")
    return value.upper()


def damping_correction(damping: float) -> float:
    """eta = sqrt(10 / (5 + xi)) >= 0.55, xi the viscous damping in percent (NTC 2018
    [3.2.4], EN 1998-1 (3.6))."""
    return max(math.sqrt(10.0 / (5.0 + damping)), 0.55)


class Spectrum:
    """What both codes' spectra give: S, eta, the corner periods and Se(T), SDe(T)."""

    ag: float
    damping: float

    @property
    def S(self) -> float:
        """The soil factor S."""
        raise NotImplementedError

    @property
    def eta(self) -> float:
        """The damping correction eta."""
        raise NotImplementedError

    @property
    def TB(self) -> float:
        raise NotImplementedError

    @property
    def TC(self) -> float:
        raise NotImplementedError

    @property
    def TD(self) -> float:
        raise NotImplementedError

    @property
    def plateau(self) -> float:
        """The plateau's amplification over ag S eta (F0 for NTC 2018, 2.5 for EN 1998-1)."""
        raise NotImplementedError

    def acceleration(self, period: ArrayLike) -> NDArray[np.float64]:
        """Se(T) [m/s2] of the horizontal elastic spectrum (NTC 2018 [3.2.2]; EN 1998-1
        (3.2)-(3.5): the same four branches)."""
        T = np.asarray(period, dtype=float)
        if np.any(T < 0) or not np.all(np.isfinite(T)):
            raise ValueError("a period must be a finite number of seconds >= 0")
        top = self.ag * G * self.S * self.eta * self.plateau
        Tp = np.where(T > 0, T, 1.0)  # the 1/T branches are never taken at T = 0
        rise = self.ag * G * self.S * (1.0 + T / self.TB * (self.eta * self.plateau - 1.0))
        out = np.where(
            T < self.TB,
            rise,
            np.where(
                T < self.TC,
                top,
                np.where(
                    T < self.TD,
                    top * self.TC / Tp,
                    top * self.TC * self.TD / Tp**2,
                ),
            ),
        )
        return np.asarray(out, dtype=float)

    def displacement(self, period: ArrayLike) -> NDArray[np.float64]:
        """SDe(T) = Se(T) (T / 2 pi)^2 [m] (NTC 2018 [3.2.10] of section 3.2.3.2.3, which holds
        up to T_E of its Tab. 3.2.VII, beyond which [3.2.11] is not implemented; EN 1998-1
        (3.7))."""
        T = np.asarray(period, dtype=float)
        return self.acceleration(T) * (T / (2.0 * math.pi)) ** 2

    def pga(self) -> float:
        """ag S [m/s2]: the spectrum at T = 0."""
        return self.ag * G * self.S


@dataclass(frozen=True)
class NTC2018Spectrum(Spectrum):
    """The horizontal elastic spectrum of NTC 2018 section 3.2.3.2.1: ``ag`` [g] on rock
    (site A, flat), ``F0`` the plateau's amplification, ``Tc_star`` [s] Tc*, ``soil`` A-E
    (Tab. 3.2.IV: S_S, C_C), ``topography`` T1-T4 (Tab. 3.2.V: S_T), ``damping`` xi [%]."""

    ag: float
    F0: float = 2.5
    Tc_star: float = 0.3
    soil: str = "A"
    topography: str = "T1"
    damping: float = 5.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "ag", check_range("ag", self.ag, 0.0, 1.5, "g", low_open=True))
        set_(self, "F0", check_range("F0", self.F0, 1.0, 5.0, "(dimensionless)"))
        set_(self, "Tc_star", check_range("Tc", self.Tc_star, 0.0, 2.0, "s", low_open=True))
        set_(self, "soil", check_choice("soil", self.soil, SOILS, "ground category"))
        set_(
            self,
            "topography",
            check_choice("topography", self.topography, tuple(TOPOGRAPHY), "topographic category"),
        )
        set_(self, "damping", check_range("damping", self.damping, 0.0, 30.0, "%"))

    @property
    def S_S(self) -> float:
        """Stratigraphic amplification (Tab. 3.2.IV), with its bounds."""
        x = self.F0 * self.ag
        low, value, high = {
            "A": (1.0, 1.0, 1.0),
            "B": (1.0, 1.40 - 0.40 * x, 1.20),
            "C": (1.0, 1.70 - 0.60 * x, 1.50),
            "D": (0.90, 2.40 - 1.50 * x, 1.80),
            "E": (1.0, 2.00 - 1.10 * x, 1.60),
        }[self.soil]
        return min(max(value, low), high)

    @property
    def C_C(self) -> float:
        """C_C of Tab. 3.2.IV: Tc = C_C Tc*."""
        coefficient, power = {
            "A": (1.0, 0.0),
            "B": (1.10, -0.20),
            "C": (1.05, -0.33),
            "D": (1.25, -0.50),
            "E": (1.15, -0.40),
        }[self.soil]
        return coefficient * self.Tc_star**power

    @property
    def S_T(self) -> float:
        return TOPOGRAPHY[self.topography]

    @property
    def S(self) -> float:
        """S = S_S S_T ([3.2.3])."""
        return self.S_S * self.S_T

    @property
    def eta(self) -> float:
        return damping_correction(self.damping)

    @property
    def plateau(self) -> float:
        return self.F0

    @property
    def TC(self) -> float:
        """Tc = C_C Tc* ([3.2.5])."""
        return self.C_C * self.Tc_star

    @property
    def TB(self) -> float:
        """TB = Tc / 3 ([3.2.6])."""
        return self.TC / 3.0

    @property
    def TD(self) -> float:
        """TD = 4.0 ag/g + 1.6 ([3.2.7])."""
        return 4.0 * self.ag + 1.6


#: EN 1998-1 Tables 3.2 (type 1) and 3.3 (type 2): S, TB, TC, TD by ground type, checked
#: against libraries' transcriptions (docs/assessment.md "Sources"). They are EN 1998-1's own:
#: a national annex may set others (type 1 TD = 2.5 in the Greek one), so a site under one
#: is not assessed by these
EC8_TABLES: dict[int, dict[str, tuple[float, float, float, float]]] = {
    1: {
        "A": (1.00, 0.15, 0.40, 2.0),
        "B": (1.20, 0.15, 0.50, 2.0),
        "C": (1.15, 0.20, 0.60, 2.0),
        "D": (1.35, 0.20, 0.80, 2.0),
        "E": (1.40, 0.15, 0.50, 2.0),
    },
    2: {
        "A": (1.00, 0.05, 0.25, 1.2),
        "B": (1.35, 0.05, 0.25, 1.2),
        "C": (1.50, 0.10, 0.25, 1.2),
        "D": (1.80, 0.10, 0.30, 1.2),
        "E": (1.60, 0.05, 0.25, 1.2),
    },
}


@dataclass(frozen=True)
class EC8Spectrum(Spectrum):
    """The horizontal elastic spectrum of EN 1998-1 section 3.2.2.2: ``ag`` [g] the design
    ground acceleration on type A ground (gamma_I agR), ``soil`` the ground type A-E,
    ``spectrum_type`` 1 (Ms > 5.5) or 2, ``damping`` xi [%]."""

    ag: float
    soil: str = "A"
    spectrum_type: int = 1
    damping: float = 5.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "ag", check_range("ag", self.ag, 0.0, 1.5, "g", low_open=True))
        set_(self, "soil", check_choice("soil", self.soil, SOILS, "ground type"))
        if self.spectrum_type not in (1, 2) or isinstance(self.spectrum_type, bool):
            raise ValueError(
                f"spectrum_type = {self.spectrum_type!r}: must be 1 or 2 (EN 1998-1 type 1 "
                "or type 2 spectrum)"
            )
        set_(self, "damping", check_range("damping", self.damping, 0.0, 30.0, "%"))

    @property
    def _row(self) -> tuple[float, float, float, float]:
        return EC8_TABLES[int(self.spectrum_type)][self.soil]

    @property
    def S(self) -> float:
        return self._row[0]

    @property
    def TB(self) -> float:
        return self._row[1]

    @property
    def TC(self) -> float:
        return self._row[2]

    @property
    def TD(self) -> float:
        return self._row[3]

    @property
    def eta(self) -> float:
        return damping_correction(self.damping)

    @property
    def plateau(self) -> float:
        return 2.5


#: Circolare 2019 C7.2.3: a, b bound the floor spectrum's plateau [a T1, b T1] ("possono
#: essere assunti pari a 0,8 e 1,1")
FLOOR_A = 0.8
FLOOR_B = 1.1


def with_damping(spectrum: Spectrum, damping: float) -> Spectrum:
    """The same spectrum at another viscous damping xi [%] (its eta changes, nothing else)."""
    return dataclasses.replace(spectrum, damping=damping)  # type: ignore[type-var]


def floor_acceleration(
    spectrum: Spectrum, T1: float, gamma: float, psi: float, building_damping: float = 5.0
) -> float:
    """a_Z(z) [m/s2], the peak acceleration of the floor at height z from the building's first
    mode alone (Circolare 2019 C7.2.3: "sufficiente riferirsi al solo primo modo"):
    a_Z,1 = Se(T1, xi1) |gamma1 psi1(z)| sqrt(1 + 0.0004 xi1^2) [C7.2.7], a_Z = a_Z,1 [C7.2.8];
    ``building_damping`` xi1 in percent, as the clause defines it."""
    xi1 = check_range("building_damping", building_damping, 0.0, 30.0, "%", low_open=True)
    Se_T1 = float(with_damping(spectrum, xi1).acceleration(T1))
    return Se_T1 * abs(gamma * psi) * math.sqrt(1.0 + 0.0004 * xi1**2)


def floor_peak_factor(spectrum: Spectrum, building_damping: float = 5.0) -> float:
    """The plateau of the floor spectrum over a_Z: 1.1 xi1^-0.5 eta(xi) [C7.2.6], [C7.2.9],
    eta of the mechanism's damping (the spectrum's own). xi1 is taken here as a fraction
    (xi1 / 100): the clause says "in percentuale", but with xi1 = 5 the factor would be
    0.49, a floor spectrum below the floor's own acceleration at the building's period,
    against the clause's "forte amplificazione in corrispondenza del periodo fondamentale"
    and the a_p = 2.5-5 of its Tab. C7.2.II; as a fraction it is 4.92 (docs/assessment.md)."""
    xi1 = check_range("building_damping", building_damping, 0.0, 30.0, "%", low_open=True)
    return 1.1 * (xi1 / 100.0) ** -0.5 * spectrum.eta


def floor_spectrum(
    spectrum: Spectrum,
    period: ArrayLike,
    T1: float,
    gamma: float,
    psi: float,
    building_damping: float = 5.0,
) -> NDArray[np.float64]:
    """S_eZ(T, xi, z) [m/s2], the Circolare 2019 floor spectrum at height z of a building of
    first period ``T1``, participation ``gamma`` and mode shape ``psi`` = psi1(z), from its
    first mode (C7.2.3, [C7.2.5]-[C7.2.9]); xi, the mechanism's damping, is the spectrum's:

        T <  a T1:        A a_Z / (1 + (A - 1) (1 - T / (a T1))^1.6)
        a T1 <= T < b T1: A a_Z
        T >= b T1:        A a_Z / (1 + (A - 1) (T / (b T1) - 1)^1.2)

    A = :func:`floor_peak_factor`, a_Z = :func:`floor_acceleration`, a = 0.8, b = 1.1; and
    not below the ground spectrum Se(T, xi) for T > T1 ([C7.2.5])."""
    T = np.asarray(period, dtype=float)
    if np.any(T < 0) or not np.all(np.isfinite(T)):
        raise ValueError("a period must be a finite number of seconds >= 0")
    T1 = check_range("T1", T1, 0.0, 10.0, "s", low_open=True)
    a_Z = floor_acceleration(spectrum, T1, gamma, psi, building_damping)
    A = floor_peak_factor(spectrum, building_damping)
    low, high = FLOOR_A * T1, FLOOR_B * T1
    rise = A * a_Z / (1.0 + (A - 1.0) * np.clip(1.0 - T / low, 0.0, None) ** 1.6)
    fall = A * a_Z / (1.0 + (A - 1.0) * np.clip(T / high - 1.0, 0.0, None) ** 1.2)
    out = np.where(T < low, rise, np.where(T < high, A * a_Z, fall))
    out = np.where(T > T1, np.maximum(out, spectrum.acceleration(T)), out)
    return np.asarray(out, dtype=float)
