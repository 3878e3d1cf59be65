"""The floor spectrum of Circolare 2019 C7.2.3 ([C7.2.5]-[C7.2.10], first mode only) against
values worked by hand for a stated building, and what it gives where the mechanism sits at
the foundation (Z = 0): derived from the clause, not assumed."""

from __future__ import annotations

import math

import pytest

from masonry_dem.assessment.checks import Building, ntc_linear_demand
from masonry_dem.assessment.spectra import (
    NTC2018Spectrum,
    floor_acceleration,
    floor_peak_factor,
    floor_spectrum,
)

G = 9.81
TOL = 1e-9

#: H = 9 m, N = 3 storeys, T1 = 0.3 s, the mechanism at Z = 6 m; soil A, ag 0.2 g, F0 2.4,
#: Tc* 0.35 s (TB 0.1167, TC 0.35, TD 2.4 s); xi1 = xi = 5 %
SITE = NTC2018Spectrum(0.2, 2.4, 0.35, "A")
T1, GAMMA, PSI = 0.3, 9 / 7, 6 / 9


def test_the_floor_acceleration_and_peak_by_hand():
    """Se(T1 = 0.3) on the plateau = 0.2 x 9.81 x 2.4 = 4.7088 m/s2; gamma1 = 3N/(2N+1) =
    9/7 [C7.2.10], psi1 = Z/H = 2/3; a_Z = 4.7088 x 6/7 x sqrt(1 + 0.0004 x 5^2) =
    4.0562446564 m/s2 [C7.2.7]; A = 1.1 x 0.05^-0.5 x eta(5 %) = 4.9193495505 [C7.2.9]."""
    assert Building(Z=6.0, H=9.0, storeys=3, T1=0.3).gamma == pytest.approx(GAMMA, rel=TOL)
    assert floor_acceleration(SITE, T1, GAMMA, PSI) == pytest.approx(4.0562446564057755, rel=TOL)
    assert floor_peak_factor(SITE) == pytest.approx(4.919349550499538, rel=TOL)


@pytest.mark.parametrize(
    ("period", "want"),
    [
        # the building's period, on the plateau [a T1, b T1] = [0.24, 0.33]: A a_Z
        (0.3, 19.954085327205906),
        # a short one: A a_Z / (1 + (A - 1) (1 - 0.12/0.24)^1.6), 0.5^1.6 = 0.3298769777
        (0.12, 8.702541591960726),
        # T = 0 gives back a_Z: the rigid mechanism's demand
        (0.0, 4.0562446564057755),
        # past b T1: A a_Z / (1 + (A - 1) (0.5/0.33 - 1)^1.2), above Se(0.5) = 3.29616
        (0.5, 7.208276363052645),
        # far past it the ground spectrum governs ([C7.2.5]): Se(2) = 4.7088 x 0.35/2 =
        # 0.82404 > 0.70181853810 of the falling branch
        (2.0, 0.82404),
    ],
)
def test_the_floor_spectrum_by_hand(period, want):
    got = float(floor_spectrum(SITE, period, T1, GAMMA, PSI)[()])
    assert got == pytest.approx(want, rel=TOL)


def test_at_the_foundation_it_is_not_the_ground_spectrum():
    """Z = 0: psi1 = 0, so a_Z = 0 [C7.2.7] and the floor spectrum is 0 up to T1; past T1 it
    is held at the ground spectrum ([C7.2.5]). The clause gives no limit to the ground
    spectrum at Z = 0 below T1: the check at ground level stays ag S / q."""
    assert float(floor_spectrum(SITE, 0.2, T1, GAMMA, 0.0)[()]) == 0.0
    assert float(floor_spectrum(SITE, 0.5, T1, GAMMA, 0.0)[()]) == pytest.approx(
        float(SITE.acceleration(0.5)), rel=TOL
    )
    assert float(SITE.acceleration(0.2)) > 0.0


def test_the_building_damping_changes_se_t1_and_the_peak():
    """xi1 = 10 %: eta(10) = sqrt(10/15) on Se(T1), sqrt(1 + 0.04) on a_Z, and the peak
    1.1 x 0.10^-0.5 x eta(xi = 5 %) = 3.4785054262."""
    a_Z = 4.7088 * math.sqrt(10 / 15) * (6 / 7) * math.sqrt(1.04)
    assert floor_acceleration(SITE, T1, GAMMA, PSI, 10.0) == pytest.approx(a_Z, rel=TOL)
    assert floor_peak_factor(SITE, 10.0) == pytest.approx(1.1 / math.sqrt(0.1), rel=TOL)


def test_the_linear_demand_at_height_by_form():
    building = Building(Z=6.0, H=9.0, storeys=3, T1=0.3)
    ground, height = ntc_linear_demand(SITE, building, 2.0)
    assert ground == pytest.approx(0.2 * G / 2, rel=TOL)
    assert height == pytest.approx(4.0562446564057755 / 2, rel=TOL)
    _, old = ntc_linear_demand(SITE, building, 2.0, "circolare_2009")
    assert old == pytest.approx(4.7088 * (2 / 3) * (9 / 7) / 2, rel=TOL)
    with pytest.raises(
        ValueError,
        match=r"^demand_at_height = 'floor': must be one of "
        r"floor_spectrum, circolare_2009$",
    ):
        ntc_linear_demand(SITE, building, 2.0, "floor")


@pytest.mark.parametrize("bad", [0.0, -1.0, 31.0, float("nan")])
def test_a_bad_building_damping_is_one_line(bad):
    with pytest.raises(ValueError, match=r"^building_damping = .*\(0, 30\] %$"):
        Building(Z=6.0, H=9.0, storeys=3, T1=0.3, damping=bad)
