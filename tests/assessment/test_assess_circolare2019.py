"""The nonlinear kinematic check of Circolare 2019 (C8.7.1.2.1.6, C8.7.1.2.1.8), the default
of ``--code ntc2018``, on one rigid block b x h rocking on its toe, worked by hand; the
Circolare 2009 check kept selectable; the option's refusals in one line.

The block of ``SINGLE_BLOCK``: h = 0.4 m high, t = 0.2 m thick along the load. Turning by
theta about its toe, its centroid moves d(theta) = (t/2)(1 - cos theta) + (h/2) sin theta and
alpha(theta) = tan(atan(t/h) - theta) (tests/assessment/test_kinematics.py); alpha0 = t/h,
e* = 1, so d* = d and a*(d) = alpha g / FC, d0* = t/2 = 0.1 m.

With R = sqrt(h^2 + t^2) / 2 and phi = atan(t/h), d(theta) = t/2 + R sin(theta - phi); at
d = t/2 - c t, beta = phi - theta = asin(c t / R) = asin(2 c t / sqrt(h^2 + t^2)), and
a(d) = tan(beta) g / FC = 2 c t g / (FC sqrt(h^2 + (1 - 4 c^2) t^2)).

* SLV: d_SLV = 0.4 d0* = 0.04 m (c = 0.3), a(d_SLV) = 0.6 t g / (FC sqrt(h^2 + 0.64 t^2)) =
  0.12 x 9.81 / (1.35 sqrt(0.1856)) = 2.024079186 m/s2 (FC 1.35), T_SLV = 1.68 pi
  sqrt(d_SLV / a(d_SLV)) [C8.7.1.10] = 0.7419513008 s.
* SLC: d_SLC = 0.6 d0* = 0.06 m (c = 0.2), a(d_SLC) = 0.4 t g / (FC sqrt(h^2 + 0.84 t^2)) =
  0.08 g / (1.35 x 0.44) = 2 g / 14.85 = 1.321212121 m/s2, T_SLC = 1.56 pi sqrt(d_SLC /
  a(d_SLC)) [C8.7.1.11] = 1.044392686 s.

The site: NTC 2018, soil A (S = 1, TC = Tc* = 0.35 s), F0 2.4, TD = 4 ag + 1.6 >= 2.4 s: both
periods on the 1/T branch, Se = ag g eta F0 TC / T, S_De(T) = Se T^2 / 4 pi^2 =
ag g eta F0 TC T / 4 pi^2 [3.2.10], with the mechanism's damping of C8.7.1.2.1.8 (8 % SLV,
eta = sqrt(10/13) = 0.8770580193; 10 % SLC, eta = sqrt(10/15)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from helpers.case_files import SINGLE_BLOCK
from masonry_dem.assessment.checks import Building, assess
from masonry_dem.assessment.kinematics import Mechanism
from masonry_dem.assessment.spectra import NTC2018Spectrum
from masonry_dem.cases.casefile import case_from_dict

G = 9.81
TOL = 1e-9
H, T = 0.4, 0.2
FC = 1.35
T_SLV = 1.68 * math.pi * math.sqrt(0.04 * FC * math.sqrt(0.1856) / (0.12 * G))
ETA8 = math.sqrt(10 / 13)


@pytest.fixture(scope="module")
def mechanism():
    """The block turning about its toe (y = 0, z = t)."""
    model = case_from_dict(SINGLE_BLOCK).model
    b = int(np.flatnonzero(~model.fixed.any(axis=1))[0])
    assert tuple(model.blocks.sizes[b, 1:]) == pytest.approx((H, T), rel=TOL)
    mode = np.zeros((model.blocks.count, 6))
    w = np.array([1.0, 0.0, 0.0])
    mode[b, :3] = np.cross(w, model.blocks.centres[b] - np.array([0.0, 0.0, T]))
    mode[b, 3:] = w
    return Mechanism.of(model, mode)


def _sde(ag: float, eta: float, period: float) -> float:
    return ag * G * eta * 2.4 * 0.35 * period / (4 * math.pi**2)


def test_the_hand_worked_values_are_what_the_docstring_says():
    """The literals of the module's docstring from its closed forms (these do not use the
    package: a slip in the derivation shows here)."""
    assert T_SLV == pytest.approx(0.7419513008, rel=1e-10)
    assert 0.12 * G / (FC * math.sqrt(0.1856)) == pytest.approx(2.024079186, rel=1e-9)
    assert _sde(0.2, ETA8, T_SLV) == pytest.approx(0.027165786102, rel=1e-10)


def test_slv_of_a_block_at_ground_level(mechanism):
    """ag = 0.2 g: S_De(T_SLV) at 8 % = 0.2 x 9.81 x 0.8770580 x 2.4 x 0.35 x 0.7419513 / 4
    pi^2 = 0.027165786102 m, d_SLV = 0.04 m: passes (ratio 1.4724)."""
    spectrum = NTC2018Spectrum(0.2, 2.4, 0.35)
    out, _ = assess(mechanism, "ntc2018", spectrum, FC=FC)
    assert out.nonlinear_check == "circolare_2019" and out.limit_state == "SLV"
    assert out.d0_star == pytest.approx(0.1, rel=TOL)
    assert out.d_SLV == pytest.approx(0.04, rel=TOL)
    assert out.a_SLV == pytest.approx(0.12 * G / (FC * math.sqrt(0.1856)), rel=TOL)
    assert out.T_SLV == pytest.approx(T_SLV, rel=TOL)
    assert out.nonlinear_damping == 8.0
    assert out.displacement_demand == pytest.approx(0.027165786102205446, rel=TOL)
    assert out.displacement_demand == pytest.approx(_sde(0.2, ETA8, T_SLV), rel=TOL)
    assert out.displacement_capacity == out.d_SLV and out.nonlinear_period == out.T_SLV
    assert out.displacement_ratio == pytest.approx(0.04 / 0.027165786102205446, rel=TOL)
    assert out.passes_nonlinear is True
    # the curve's secant period (the 2009 check's, EC8's T*) reported beside it, by hand:
    # d_u* = 0.04 m, d_s* = 0.016 m = t/2 - c t with c = 0.42, a_s* = 2 c t g / (FC sqrt(h^2
    # + (1 - 4 c^2) t^2)) = 2.9455 m/s2, Ts = 2 pi sqrt(d_s* / a_s*) = 0.4631 s
    a_s = 2 * 0.42 * 0.2 * G / (FC * math.sqrt(0.4**2 + (1 - 4 * 0.42**2) * 0.2**2))
    assert out.du_star == pytest.approx(0.04, rel=TOL) and out.ds_star == pytest.approx(0.016)
    assert out.as_star == pytest.approx(a_s, rel=TOL)
    assert out.Ts == pytest.approx(2 * math.pi * math.sqrt(0.016 / a_s), rel=TOL)
    assert out.d_SLC is None and out.T_SLC is None
    assert "T_SLV = 1.68 pi" in out.nonlinear_summary and "xi = 8 %" in out.nonlinear_summary


def test_a_damping_given_replaces_the_clauses_8_percent(mechanism):
    """C8.7.1.2.1.8's 8 % holds "in assenza di valutazioni più accurate": xi = 5 % given, eta = 1, S_De(T_SLV) =
    0.2 x 9.81 x 2.4 x 0.35 x 0.7419513 / 4 pi^2 = 0.030973762 m."""
    out, _ = assess(
        mechanism, "ntc2018", NTC2018Spectrum(0.2, 2.4, 0.35), FC=FC, nonlinear_damping=5.0
    )
    assert out.nonlinear_damping == 5.0
    assert out.displacement_demand == pytest.approx(_sde(0.2, 1.0, T_SLV), rel=TOL)
    assert out.displacement_demand == pytest.approx(0.030973761717234347, rel=TOL)


@pytest.mark.parametrize(
    ("ag", "demand", "passes"),
    [
        # 0.35 g: S_De = 0.047540126 m > d_SLV = 0.04 m, but a0* = 0.5 g / 1.35 = 3.6333 m/s2
        # >= ag S = 3.4335 m/s2 (activation ratio 1.0582): a_g,SLD >= a_g, it passes
        (0.35, 0.04754012567885953, True),
        # 0.45 g: S_De = 0.061123019 m > 0.04 m and a0* < 0.45 g (0.8230): it fails
        (0.45, 0.06112301872996225, False),
    ],
)
def test_slv_takes_the_activation_acceleration_when_larger(mechanism, ag, demand, passes):
    """C8.7.1.2.1.8: a_g,SLV below a_g,SLD "si assume quest'ultima anche per lo SLV"."""
    out, _ = assess(mechanism, "ntc2018", NTC2018Spectrum(ag, 2.4, 0.35), FC=FC)
    assert out.displacement_demand == pytest.approx(demand, rel=TOL)
    assert out.displacement_ratio < 1.0
    assert out.activation_ratio == pytest.approx(0.5 / FC / ag, rel=TOL)
    assert out.passes_nonlinear is passes


def test_slc_of_a_block(mechanism):
    """SLC: d_SLC = 0.06 m, a(d_SLC) = 1.321212121 m/s2, T_SLC = 1.044392686 s, xi = 10 %:
    S_De = 0.2 x 9.81 x sqrt(2/3) x 2.4 x 0.35 x 1.0443927 / 4 pi^2 = 0.035598914 m."""
    out, _ = assess(mechanism, "ntc2018", NTC2018Spectrum(0.2, 2.4, 0.35), FC=FC, limit_state="SLC")
    T_SLC = 1.56 * math.pi * math.sqrt(0.06 * 11 * FC / (2 * G))
    assert T_SLC == pytest.approx(1.044392686, rel=1e-9)
    assert out.limit_state == "SLC" and out.d_SLV is None and out.T_SLV is None
    assert out.d_SLC == pytest.approx(0.06, rel=TOL)
    assert out.a_SLC == pytest.approx(2 * G / 14.85, rel=TOL)
    assert out.T_SLC == pytest.approx(T_SLC, rel=TOL)
    assert out.nonlinear_damping == 10.0
    assert out.displacement_demand == pytest.approx(0.035598913594871176, rel=TOL)
    assert out.displacement_demand == pytest.approx(_sde(0.2, math.sqrt(10 / 15), T_SLC), rel=TOL)
    assert out.passes_nonlinear is True


def test_slv_at_height_on_the_floor_spectrum_at_t_slv(mechanism):
    """Z = 6 m of H = 9 m, N = 3, T1 = 0.3 s, xi1 = 5 %, ag 0.2 g: a_Z = 4.7088 x 6/7 x
    sqrt(1.01) = 4.0562446564 m/s2 [C7.2.7] (xi1's spectrum), the plateau A = 1.1 x
    0.05^-0.5 x eta(8 %) = 4.3145549730 [C7.2.6] (the mechanism's damping). T_SLV = 0.742 s
    > b T1 = 0.33 s: the falling branch A a_Z / (1 + (A - 1)(T_SLV/0.33 - 1)^1.2) =
    3.2863221 m/s2 (above Se(T_SLV, 8 %) = 1.9481896), in displacement 0.045824865 m; the
    bound of [C8.7.1.12], A a_Z 0.33^2 / 4 pi^2 = 0.048275668 m, governs."""
    out, _ = assess(
        mechanism,
        "ntc2018",
        NTC2018Spectrum(0.2, 2.4, 0.35),
        Building(Z=6.0, H=9.0, storeys=3, T1=0.3),
        FC=FC,
    )
    a_Z = 0.2 * G * 2.4 * (6 / 7) * math.sqrt(1.01)
    A = 1.1 / math.sqrt(0.05) * ETA8
    fall = A * a_Z / (1 + (A - 1) * (T_SLV / 0.33 - 1) ** 1.2)
    height = fall * T_SLV**2 / (4 * math.pi**2)
    bound = A * a_Z * 0.33**2 / (4 * math.pi**2)
    assert height == pytest.approx(0.045824864678794375, rel=1e-9)
    assert bound == pytest.approx(0.04827566799784691, rel=1e-9)
    assert out.T_SLV == pytest.approx(T_SLV, rel=TOL)
    assert out.displacement_demand == pytest.approx(bound, rel=TOL)


def test_the_2009_check_is_kept(mechanism):
    """nonlinear_check = circolare_2009: d_u* = 0.04 m and the secant Ts, no T_SLV; the
    spectrum's own damping (5 %)."""
    out, _ = assess(
        mechanism,
        "ntc2018",
        NTC2018Spectrum(0.2, 2.4, 0.35),
        FC=FC,
        nonlinear_check="circolare_2009",
    )
    assert out.nonlinear_check == "circolare_2009" and out.limit_state is None
    assert out.T_SLV is None and out.d_SLV is None and out.nonlinear_damping is None
    assert out.du_star == pytest.approx(0.04, rel=TOL)
    assert out.displacement_demand == pytest.approx(_sde(0.2, 1.0, out.Ts), rel=TOL)
    assert out.Ts != pytest.approx(T_SLV, rel=1e-3)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"nonlinear_check": "circolare_2018"},
            "nonlinear_check = 'circolare_2018': must be one of circolare_2019, circolare_2009",
        ),
        ({"limit_state": "SLD"}, "limit_state = 'SLD': must be one of SLV, SLC"),
        (
            {"limit_state": "SLC", "nonlinear_check": "circolare_2009"},
            "limit_state = 'SLC': must be SLV with nonlinear_check = circolare_2009",
        ),
        ({"nonlinear_damping": 40.0}, "damping = 40.0 out of range: must be in [0, 30] %"),
    ],
)
def test_bad_options_are_refused_in_one_line(mechanism, kwargs, message):
    with pytest.raises(ValueError) as err:
        assess(mechanism, "ntc2018", NTC2018Spectrum(0.2, 2.4, 0.35), **kwargs)
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("check", "words"),
    [
        (
            "circolare_2019",
            [
                "xi = 8 %",
                "T_SLV = 1.68 pi sqrt(d_SLV/a(d_SLV)) = 0.742 s",
                "d_SLV = 0.4 d0* = 40 mm",
                "S_De(T_SLV), xi = 8 % = 27.2 mm",
                "Circolare 2019 SLV",
            ],
        ),
        ("circolare_2009", ["xi = 5 %", "secant period Ts", "d_u* = 0.4 d0* = 40 mm", "2009"]),
    ],
)
def test_the_adrs_figure_names_the_check(mechanism, check, words):
    """adrs.png's legend and title: the period, the capacity and the demand of the check made,
    with their units."""
    from masonry_dem.export.assessment_files import adrs_figure

    spectrum = NTC2018Spectrum(0.2, 2.4, 0.35)
    out, curve = assess(mechanism, "ntc2018", spectrum, FC=FC, nonlinear_check=check)
    fig = adrs_figure(out, curve, spectrum)
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()] + [ax.get_title()]
    for w in words:
        assert any(w in t for t in texts), (w, texts)
    other = "secant period" if check == "circolare_2019" else "T_SLV"
    assert not any(other in t for t in texts)
