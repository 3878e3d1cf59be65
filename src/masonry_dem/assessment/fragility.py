"""Fragility of a mechanism over uncertain inputs (issue 38, item 4): the capacity of each run
of a sampled sweep as a peak ground acceleration, a lognormal fitted to them by maximum
likelihood with a bootstrap confidence band, and the fragility curve
P(collapse | ag) = Phi(ln(ag / median) / beta).

The capacity of a run is the ground acceleration at which its mechanism, at ground level,
just fails the linear kinematic check of NTC 2018 / Circolare 2019 C8.7.1.2.1.7 (the
Circolare 2009's [C8A.4.9]), a0* = ag S / q, with a0* = alpha0 g / (e* FC) (2019 [C8.7.1.8]):

    ag_capacity = the smallest ag with ag S(ag) / q >= a0* / g   [g]

which for a constant S (EN 1998-1, NTC soil A) is ag_capacity = a0* q / (g S). NTC's S_S of
soils B-E falls with ag (Tab. 3.2.IV), so there the root is found numerically (ag S(ag) is
not monotonic on soil D). ``ag`` is on rock (EN 1998-1: gamma_I agR), as ``assess`` takes it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem.assessment.checks import spectrum_of
from masonry_dem.assessment.spectra import G

#: the spectra take ag up to this [g]; above it S is at its bound on every soil (S_S is
#: constant once F0 ag >= 1 on NTC soils, constant on EN 1998-1 ground types)
AG_SPECTRUM_MAX = 1.5
#: the largest capacity sought [g]: a run stronger than this is reported at it
AG_MAX = 50.0
#: the grid on which the first crossing of the demand is bracketed before Brent's method
#: (every 0.005 g: S_S of NTC soil D falls faster than ag rises over 0.08 g at F0 = 2.4)
SCAN_POINTS = 301
#: bootstrap resamples and the confidence level of the band
BOOTSTRAP = 1000
CONFIDENCE = 0.90


def ground_demand_factor(ag: float, code: str, site: dict[str, Any]) -> float:
    """ag S(ag) [g]: the peak ground acceleration of the elastic spectrum at ``ag``."""
    capped = min(ag, AG_SPECTRUM_MAX)
    spectrum = spectrum_of(code, ag=capped, **site)
    return ag * spectrum.S


def ag_capacity(a0_star: float, code: str, site: dict[str, Any], q: float) -> float:
    """The peak ground acceleration [g] at which a mechanism at ground level whose spectral
    acceleration of activation is ``a0_star`` [m/s2] just fails the linear check
    a0* >= ag S / q: the smallest ag with ag S(ag) / q >= a0* / g."""
    if not (math.isfinite(a0_star) and a0_star > 0):
        raise ValueError(f"a0* = {a0_star!r}: must be a positive number [m/s2]")
    target = a0_star * q / G

    def excess(ag: float) -> float:
        return ground_demand_factor(ag, code, site) - target

    # S is constant from AG_SPECTRUM_MAX on, and on EN 1998-1 ground types and NTC soil A
    # everywhere: the crossing is linear there
    top = ground_demand_factor(AG_SPECTRUM_MAX, code, site)
    if code == "ec8" or str(site.get("soil", "A")).upper() == "A":
        return min(target / (top / AG_SPECTRUM_MAX), AG_MAX)
    if target > top:
        return min(target / (top / AG_SPECTRUM_MAX), AG_MAX)
    grid = np.linspace(0.0, AG_SPECTRUM_MAX, SCAN_POINTS)[1:]
    values = np.array([excess(float(a)) for a in grid])
    k = int(np.argmax(values >= 0.0))
    if k == 0:
        lo = 1e-12
    else:
        lo = float(grid[k - 1])
    from scipy.optimize import brentq

    return float(brentq(excess, lo, float(grid[k]), xtol=1e-12, rtol=1e-12))


@dataclass(frozen=True)
class LognormalFit:
    """A lognormal fitted by maximum likelihood: ``median`` (exp of the mean of ln x) and
    ``beta`` (the standard deviation of ln x, the MLE's 1/n form), each with the
    ``confidence`` interval of ``bootstrap`` resamples (percentiles), over ``n`` values."""

    median: float
    beta: float
    median_interval: tuple[float, float]
    beta_interval: tuple[float, float]
    n: int
    bootstrap: int
    confidence: float
    seed: int | None

    def probability(self, x: ArrayLike) -> NDArray[np.float64]:
        """P(capacity <= x) = Phi(ln(x / median) / beta)."""
        from scipy.stats import norm

        x = np.asarray(x, dtype=float)
        with np.errstate(divide="ignore"):
            return np.asarray(norm.cdf(np.log(x / self.median) / self.beta), dtype=float)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def lognormal_mle(values: ArrayLike) -> tuple[float, float]:
    """(median, beta) of the lognormal of largest likelihood for ``values`` (> 0)."""
    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ValueError(f"a lognormal fit needs at least 2 values, got {x.size}")
    if not np.all(np.isfinite(x)) or np.any(x <= 0):
        raise ValueError("a lognormal fit needs finite positive values")
    logs = np.log(x)
    mu = float(logs.mean())
    return math.exp(mu), float(np.sqrt(np.mean((logs - mu) ** 2)))


def fit_lognormal(
    values: ArrayLike,
    bootstrap: int = BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int | None = 0,
) -> tuple[LognormalFit, NDArray[np.float64]]:
    """The maximum-likelihood lognormal of ``values`` and its bootstrap: ``bootstrap``
    resamples with replacement (``seed``), each refitted; returns the fit (with the
    percentile intervals at ``confidence``) and the resamples' (median, beta), (bootstrap, 2)."""
    if not 0 < confidence < 1:
        raise ValueError(f"confidence = {confidence!r}: must be in (0, 1)")
    if bootstrap < 10:
        raise ValueError(f"bootstrap = {bootstrap!r}: must be at least 10 resamples")
    x = np.asarray(values, dtype=float)
    median, beta = lognormal_mle(x)
    rng = np.random.default_rng(seed)
    logs = np.log(x)
    picks = rng.integers(0, x.size, size=(bootstrap, x.size))
    sample = logs[picks]
    mus = sample.mean(axis=1)
    betas = np.sqrt(((sample - mus[:, None]) ** 2).mean(axis=1))
    resamples = np.column_stack([np.exp(mus), betas])
    tail = 100 * (1 - confidence) / 2
    lo, hi = np.percentile(resamples, [tail, 100 - tail], axis=0)
    fit = LognormalFit(
        median=median,
        beta=beta,
        median_interval=(float(lo[0]), float(hi[0])),
        beta_interval=(float(lo[1]), float(hi[1])),
        n=int(x.size),
        bootstrap=int(bootstrap),
        confidence=float(confidence),
        seed=seed,
    )
    return fit, resamples


def fragility_band(
    fit: LognormalFit, resamples: NDArray[np.float64], ag: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The confidence band of the fragility curve at ``ag``: at each ag the percentiles of
    the resamples' curves."""
    from scipy.stats import norm

    a = np.asarray(ag, dtype=float)
    with np.errstate(divide="ignore"):
        curves = norm.cdf(np.log(a[None, :] / resamples[:, :1]) / resamples[:, 1:])
    tail = 100 * (1 - fit.confidence) / 2
    lo, hi = np.percentile(curves, [tail, 100 - tail], axis=0)
    return np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)


def fragility_figure(
    fit: LognormalFit,
    resamples: NDArray[np.float64],
    capacities: ArrayLike,
    title: str = "",
) -> Any:
    """The fragility curve with its band and the runs' empirical distribution; a matplotlib
    Figure (Agg)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    x = np.sort(np.asarray(capacities, dtype=float))
    top = max(float(x.max()), fit.median * math.exp(3 * fit.beta)) * 1.05
    # from zero, unless the curve rises far from it (a small beta): then around its rise
    low = min(float(x.min()), fit.median * math.exp(-3 * fit.beta)) * 0.95
    left = 0.0 if low < 0.4 * fit.median else low
    ag = np.linspace(max(left, top / 2000), top, 400)
    lo, hi = fragility_band(fit, resamples, ag)
    fig = Figure(figsize=(7.0, 4.6), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    pct = round(100 * fit.confidence)
    ax.fill_between(
        ag, lo, hi, color="#1f4e9c", alpha=0.18, lw=0, label=f"{pct} % band (bootstrap)"
    )
    ax.plot(
        ag,
        fit.probability(ag),
        color="#1f4e9c",
        lw=2,
        label=f"lognormal: median {fit.median:.3g} g, beta {fit.beta:.3g}",
    )
    ax.step(
        x,
        np.arange(1, x.size + 1) / x.size,
        where="post",
        color="#c0392b",
        lw=1,
        label=f"the {x.size} runs",
    )
    ax.axvline(fit.median, color="#7f8c8d", ls=":", lw=1)
    ax.set_xlim(left, top)
    ax.set_ylim(0, 1)
    ax.set_xlabel("peak ground acceleration ag [g]")
    ax.set_ylabel("probability of failing the check")
    ax.set_title(title or "fragility of the mechanism", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    return fig
