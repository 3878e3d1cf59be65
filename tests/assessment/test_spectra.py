"""The elastic spectra of NTC 2018 (section 3.2.3.2.1, Tab. 3.2.IV-V) and EN 1998-1
(section 3.2.2.2, Tables 3.2-3.3) against values computed by hand at the corner periods,
for two ground categories each; and the one-line refusals of bad parameters."""

from __future__ import annotations

import pytest

from masonry_dem.assessment.spectra import EC8Spectrum, NTC2018Spectrum

G = 9.81
TOL = 1e-9


def _at(spectrum, periods):
    return [float(spectrum.acceleration(T)) for T in periods]


def test_ntc_soil_a():
    """ag 0.2 g, F0 2.4, Tc* 0.35 s, soil A, T1: S = 1, Tc = 0.35, TB = 0.35/3, TD = 2.4;
    Se(0) = 1.962, plateau 4.7088, Se(TD) = 4.7088 x 0.35 / 2.4 = 0.6867,
    Se(4) = 4.7088 x 0.35 x 2.4 / 16 = 0.247212 m/s2."""
    sp = NTC2018Spectrum(0.2, 2.4, 0.35, "A")
    assert (sp.S, sp.TC, sp.TB, sp.TD) == pytest.approx((1.0, 0.35, 0.35 / 3, 2.4), rel=TOL)
    got = _at(sp, [0.0, 0.35 / 3, 0.35, 2.4, 4.0])
    assert got == pytest.approx([1.962, 4.7088, 4.7088, 0.6867, 0.247212], rel=TOL)
    # the first branch halfway: ag S eta F0 (T/TB + (1 - T/TB)/(eta F0)) = 1.962 (1.2 + 0.5/1)
    assert float(sp.acceleration(0.35 / 6)) == pytest.approx(1.962 * (1.2 + 0.5), rel=TOL)
    # the displacement spectrum: Se (T / 2 pi)^2
    assert float(sp.displacement(1.0)) == pytest.approx(
        4.7088 * 0.35 / 1.0 / (4 * 3.141592653589793**2), rel=TOL
    )


def test_ntc_soil_c_and_topography():
    """ag 0.25 g, F0 2.5, Tc* 0.4 s, soil C, T2: S_S = 1.70 - 0.60 x 2.5 x 0.25 = 1.325,
    C_C = 1.05 x 0.4^-0.33, S_T = 1.2, S = 1.59, TD = 4 x 0.25 + 1.6 = 2.6."""
    sp = NTC2018Spectrum(0.25, 2.5, 0.4, "C", "T2")
    Cc = 1.05 * 0.4**-0.33
    Tc = Cc * 0.4
    assert sp.S_S == pytest.approx(1.325, rel=TOL)
    assert sp.S == pytest.approx(1.59, rel=TOL)
    assert sp.TC == pytest.approx(Tc, rel=TOL)
    assert sp.TD == pytest.approx(2.6, rel=TOL)
    top = 0.25 * G * 1.59 * 2.5  # 9.7494375
    got = _at(sp, [0.0, Tc / 3, Tc, 2.6, 3.0])
    want = [0.25 * G * 1.59, top, top, top * Tc / 2.6, top * Tc * 2.6 / 9.0]
    assert got == pytest.approx(want, rel=TOL)


def test_ntc_soil_factor_bounds():
    """Soil D with ag F0 = 1.3: 2.40 - 1.50 x 1.3 = 0.45, raised to the bound 0.90; soil B
    with ag F0 = 0.1: 1.40 - 0.04 = 1.36, cut to 1.20."""
    assert NTC2018Spectrum(0.5, 2.6, 0.3, "D").S_S == pytest.approx(0.90, rel=TOL)
    assert NTC2018Spectrum(0.05, 2.0, 0.3, "B").S_S == pytest.approx(1.20, rel=TOL)


def test_ec8_type_1_ground_b():
    """ag 0.3 g: S 1.2, TB 0.15, TC 0.5, TD 2.0: Se(0) = 3.5316, plateau 8.829,
    Se(TD) = 8.829 x 0.5 / 2 = 2.20725, Se(3 s) = 8.829 x 0.5 x 2 / 9 = 0.981 m/s2."""
    sp = EC8Spectrum(0.3, "B", 1)
    got = _at(sp, [0.0, 0.15, 0.5, 2.0, 3.0])
    assert got == pytest.approx([3.5316, 8.829, 8.829, 2.20725, 0.981], rel=TOL)


def test_ec8_type_2_ground_d():
    """ag 0.1 g: S 1.8, TB 0.1, TC 0.3, TD 1.2: Se(0) = 1.7658, plateau 4.4145,
    Se(TD) = 1.103625, Se(2.4 s) = 4.4145 x 0.36 / 5.76 = 0.27590625 m/s2; at TB/2 the
    rising line: 1.7658 (1 + 0.5 x 1.5) = 3.09015."""
    sp = EC8Spectrum(0.1, "D", 2)
    got = _at(sp, [0.0, 0.05, 0.1, 0.3, 1.2, 2.4])
    assert got == pytest.approx([1.7658, 3.09015, 4.4145, 4.4145, 1.103625, 0.27590625], rel=TOL)


#: EN 1998-1 Tables 3.2 (type 1) and 3.3 (type 2), S, TB, TC, TD, as transcribed by
#: ROB-Seismology/rshalib siteresponse/refspec.py (both types) and, type 1,
#: GeorgePapazafeiropoulos/ArtifSeismoMatlab paramEC8.m (docs/assessment.md, "Sources"):
#: written out here, not read from EC8_TABLES, so that a changed table value fails
TRANSCRIBED = {
    (1, "A"): (1.0, 0.15, 0.4, 2.0),
    (1, "B"): (1.2, 0.15, 0.5, 2.0),
    (1, "C"): (1.15, 0.2, 0.6, 2.0),
    (1, "D"): (1.35, 0.2, 0.8, 2.0),
    (1, "E"): (1.4, 0.15, 0.5, 2.0),
    (2, "A"): (1.0, 0.05, 0.25, 1.2),
    (2, "B"): (1.35, 0.05, 0.25, 1.2),
    (2, "C"): (1.5, 0.1, 0.25, 1.2),
    (2, "D"): (1.8, 0.1, 0.30, 1.2),
    (2, "E"): (1.6, 0.05, 0.25, 1.2),
}


@pytest.mark.parametrize(("spectrum_type", "soil"), sorted(TRANSCRIBED))
def test_ec8_tables_as_transcribed(spectrum_type, soil):
    sp = EC8Spectrum(0.2, soil, spectrum_type)
    got = (sp.S, sp.TB, sp.TC, sp.TD)
    assert got == pytest.approx(TRANSCRIBED[(spectrum_type, soil)], rel=TOL)


def test_ec8_type_1_ground_c_corners():
    """ag 0.2 g, Table 3.2 C: S 1.15, TB 0.2, TC 0.6, TD 2.0: Se(0) = 0.2 x 9.81 x 1.15 =
    2.2563, plateau 5.64075 at TB and TC, Se(TD) = 5.64075 x 0.6 / 2 = 1.692225,
    Se(4 s) = 5.64075 x 0.6 x 2 / 16 = 0.42305625 m/s2, one on each of the four branches."""
    sp = EC8Spectrum(0.2, "C", 1)
    got = _at(sp, [0.0, 0.2, 0.6, 2.0, 4.0])
    assert got == pytest.approx([2.2563, 5.64075, 5.64075, 1.692225, 0.42305625], rel=TOL)


def test_ec8_type_2_ground_e_corners_and_damping():
    """ag 0.1 g, Table 3.3 E: S 1.6, TB 0.05, TC 0.25, TD 1.2: Se(0) = 1.5696, plateau
    3.924, Se(TD) = 3.924 x 0.25 / 1.2 = 0.8175, Se(2.4 s) = 3.924 x 0.3 / 5.76 =
    0.204375 m/s2. At xi = 10 %, eta = sqrt(2/3): the plateau is 3.924 eta and the rising
    line at TB/2 is ag S (1 + 0.5 (2.5 eta - 1)), not ag S eta (1 + ...)."""
    sp = EC8Spectrum(0.1, "E", 2)
    got = _at(sp, [0.0, 0.05, 0.25, 1.2, 2.4])
    assert got == pytest.approx([1.5696, 3.924, 3.924, 0.8175, 0.204375], rel=TOL)
    eta = (2 / 3) ** 0.5
    damped = EC8Spectrum(0.1, "E", 2, damping=10)
    assert _at(damped, [0.025, 0.1]) == pytest.approx(
        [1.5696 * (1 + 0.5 * (2.5 * eta - 1)), 3.924 * eta], rel=TOL
    )


def test_damping_correction():
    """eta = sqrt(10 / (5 + xi)) >= 0.55: 10 % -> sqrt(2/3); 40 % would be 0.471, but the
    range of xi stops at 30 % (0.5345 -> 0.55)."""
    assert EC8Spectrum(0.1, "A", 1, damping=10).eta == pytest.approx((2 / 3) ** 0.5, rel=TOL)
    assert EC8Spectrum(0.1, "A", 1, damping=30).eta == pytest.approx(0.55, rel=TOL)


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: NTC2018Spectrum(2.0), ["ag = 2.0", "(0, 1.5] g"]),
        (lambda: NTC2018Spectrum(0.0), ["ag = 0.0", "(0, 1.5] g"]),
        (lambda: NTC2018Spectrum(0.2, F0=9), ["F0 = 9", "[1, 5]"]),
        (lambda: NTC2018Spectrum(0.2, Tc_star=-1), ["Tc = -1", "(0, 2] s"]),
        (lambda: NTC2018Spectrum(0.2, soil="F"), ["soil = 'F'", "A, B, C, D, E"]),
        (lambda: NTC2018Spectrum(0.2, topography="T5"), ["topography = 'T5'", "T1, T2, T3, T4"]),
        (lambda: EC8Spectrum(0.2, spectrum_type=3), ["spectrum_type = 3", "1 or 2"]),
        (lambda: EC8Spectrum(float("nan")), ["ag = nan", "g"]),
    ],
)
def test_bad_parameters_are_named_with_range_and_unit(make, words):
    with pytest.raises(ValueError) as err:
        make()
    text = str(err.value)
    assert "\n" not in text
    for w in words:
        assert w in text


def test_n2_target_displacement_by_hand():
    """EN 1998-1 Annex B on type 1 ground B, ag 0.3 g (plateau 8.829 m/s2, TC 0.5 s):
    T* = 0.4 s < TC: d_et* = 8.829 (0.4 / 2 pi)^2; with a_y = 4.4145, q_u = 2 and
    d_t* = d_et* / 2 (1 + 1 x 0.5 / 0.4) = 1.125 d_et*; with a_y = 9 >= Se: d_et*.
    T* = 1.0 s >= TC: d_t* = d_et* = 4.4145 (1 / 2 pi)^2."""
    from masonry_dem.assessment.checks import n2_target

    sp = EC8Spectrum(0.3, "B", 1)
    d_et = 8.829 * (0.4 / (2 * 3.141592653589793)) ** 2
    assert n2_target(sp, 0.4, 4.4145) == pytest.approx(1.125 * d_et, rel=TOL)
    assert n2_target(sp, 0.4, 9.0) == pytest.approx(d_et, rel=TOL)
    assert n2_target(sp, 1.0, 1.0) == pytest.approx(4.4145 / (4 * 3.141592653589793**2), rel=TOL)


def test_ec8_amplification_at_height_by_hand():
    """EN 1998-1 (4.25) over alpha S: z/H = 0.5, Ta/T1 = 0.5: 3 x 1.5 / 1.25 - 0.5 = 3.1;
    Ta = T1 at the top: 3 x 2 - 0.5 = 5.5; Ta >> T1 at the base: below 1, so 1."""
    from masonry_dem.assessment.checks import Building, ec8_amplification

    assert ec8_amplification(Building(Z=5, H=10, T1=0.4), 0.2) == pytest.approx(3.1, rel=TOL)
    assert ec8_amplification(Building(Z=10, H=10, T1=0.4), 0.4) == pytest.approx(5.5, rel=TOL)
    assert ec8_amplification(Building(Z=0.0, H=10, T1=0.4), 4.0) == 1.0
