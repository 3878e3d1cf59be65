"""Fragility of a mechanism over uncertain inputs (issue 38, item 4): the capacity of each run
of a sampled sweep as a peak ground acceleration, a lognormal fitted to them by maximum
likelihood (runs that did not collapse as right-censored: their capacity only exceeds a
value) with a bootstrap confidence band, and the fragility curve
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

import logging
import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from masonry_dem.assessment.checks import spectrum_of
from masonry_dem.assessment.spectra import G

log = logging.getLogger(__name__)

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
    ``confidence`` interval of ``bootstrap`` resamples (percentiles), over ``n`` values of
    which ``censored`` are lower bounds only (runs that did not collapse, see
    :func:`censored_lognormal_mle`)."""

    median: float
    beta: float
    median_interval: tuple[float, float]
    beta_interval: tuple[float, float]
    n: int
    bootstrap: int
    confidence: float
    seed: int | None
    censored: int = 0

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


def _censoring(values: ArrayLike, censored: ArrayLike | None) -> tuple[NDArray, NDArray]:
    """``values`` as floats and ``censored`` as booleans of the same shape (all False when
    None), checked: finite positive values, at least 2 of them exact."""
    x = np.asarray(values, dtype=float)
    c = np.zeros(x.shape, bool) if censored is None else np.asarray(censored, dtype=bool)
    if x.ndim != 1 or c.shape != x.shape:
        raise ValueError(
            f"values {x.shape} and censored {c.shape}: must be two 1-D arrays of one length"
        )
    if not np.all(np.isfinite(x)) or np.any(x <= 0):
        raise ValueError("a lognormal fit needs finite positive values")
    exact = int((~c).sum())
    if x.size and exact == 0:
        raise ValueError(
            f"all {x.size} values are censored (no run collapsed): the capacities are lower "
            "bounds only and fix no lognormal"
        )
    if exact < 2:
        raise ValueError(
            f"a lognormal fit needs at least 2 exact values (runs that collapsed), got {exact} "
            f"of {x.size} ({x.size - exact} censored)"
        )
    return x, c


def _censored_terms(
    logs: NDArray, censored: NDArray, a: NDArray, b: NDArray
) -> tuple[NDArray, NDArray, NDArray]:
    """The log-likelihood, its gradient and its Hessian in (a, b) = (mu / beta, 1 / beta),
    in which it is concave (z = b ln x - a is linear in them and the normal's log pdf and log
    survival are concave in z): one row per sample of ``logs`` (k, n); ``a``, ``b`` (k,).
    Constants (ln sqrt(2 pi), ln x) are dropped."""
    from scipy.stats import norm

    z = b[:, None] * logs - a[:, None]
    exact = ~censored
    # the censored terms' derivatives go through the hazard h = phi / (1 - Phi), computed
    # from the logs so that it stays finite far in the upper tail
    log_sf = norm.logsf(z)
    h = np.where(censored, np.exp(norm.logpdf(z) - log_sf), 0.0)
    dh = h * (h - z)  # -d2/dz2 ln(1 - Phi), in (0, 1)
    m = exact.sum(axis=1)
    ll = np.where(exact, -0.5 * z**2, log_sf).sum(axis=1) + m * np.log(b)
    # d/da, d/db of the exact terms (-z^2 / 2 + ln b) and of the censored ones (ln(1 - Phi))
    ga = np.where(exact, z, h).sum(axis=1)
    gb = np.where(exact, -z * logs, -h * logs).sum(axis=1) + m / b
    haa = -np.where(exact, 1.0, dh).sum(axis=1)
    hab = np.where(exact, logs, dh * logs).sum(axis=1)
    hbb = -np.where(exact, logs**2, dh * logs**2).sum(axis=1) - m / b**2
    return ll, np.stack([ga, gb], axis=1), np.stack([haa, hab, hab, hbb], axis=1).reshape(-1, 2, 2)


def censored_lognormal_mle(
    values: ArrayLike, censored: ArrayLike | None = None
) -> tuple[float, float]:
    """(median, beta) of the lognormal of largest likelihood for ``values`` (> 0) of which
    those flagged ``censored`` are right-censored: the capacity is known only to exceed them
    (a run that did not collapse). The likelihood of survival analysis (Lawless, *Statistical
    Models and Methods for Lifetime Data*, 2nd ed. 2003, ch. 5; for fragility functions
    Porter, Kennedy & Bachman, Earthquake Spectra 23(2) 2007, the bounding-EDP method):

        ln L = sum_exact ln phi(z_i) / (beta x_i) + sum_censored ln(1 - Phi(z_j)),
        z = ln(x / median) / beta,

    maximised by ``scipy.optimize.minimize`` from the closed form of the exact values alone.
    Without censored values it is the closed form (:func:`lognormal_mle`). A ValueError when
    fewer than 2 values are exact, or all are censored."""
    x, c = _censoring(values, censored)
    if not c.any():
        return lognormal_mle(x)
    from scipy.optimize import minimize

    logs = np.log(x)[None, :]
    mu0 = float(logs[0, ~c].mean())
    beta0 = float(np.sqrt(np.mean((logs[0, ~c] - mu0) ** 2)))
    if beta0 <= 0:
        raise ValueError(
            "the exact values are all equal: with censored values their lognormal has no "
            "finite beta"
        )

    def cost(theta: NDArray) -> tuple[float, NDArray]:
        ll, g, _ = _censored_terms(logs, c[None, :], theta[:1], theta[1:])
        return -float(ll[0]), -g[0]

    def hess(theta: NDArray) -> NDArray:
        return -_censored_terms(logs, c[None, :], theta[:1], theta[1:])[2][0]

    # (a, b) = (mu / beta, 1 / beta): the negative log-likelihood is convex in them, so
    # the trust-region Newton method with the exact Hessian finds the one minimum
    start = np.array([mu0 / beta0, 1.0 / beta0])
    # the gradient is a sum over the values: its rounding grows with their number, and a
    # tolerance below it ends in "failure to predict improvement" at the optimum
    res = minimize(
        cost, start, jac=True, hess=hess, method="trust-exact", options={"gtol": 1e-9 * x.size}
    )
    a, b = (float(v) for v in res.x)
    at_rounding = bool(np.abs(res.jac).max() <= 1e-6 * x.size)
    if not ((res.success or at_rounding) and math.isfinite(a) and math.isfinite(b) and b > 0):
        raise ValueError(f"the censored lognormal fit did not converge: {res.message}")
    return math.exp(a / b), 1.0 / b


def _censored_mle_rows(
    logs: NDArray, censored: NDArray, iterations: int = 60
) -> NDArray[np.float64]:
    """The censored maximum-likelihood (median, beta) of each row of ``logs`` (k, n) at once
    (the bootstrap's resamples): Newton's method in (a, b) with step halving, vectorised
    over the rows, from each row's closed form of its exact values; a row with fewer than 2
    distinct exact values, or that does not converge, is NaN."""
    exact = ~censored
    m = exact.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu = np.where(exact, logs, 0.0).sum(axis=1) / m
        var = np.where(exact, (logs - mu[:, None]) ** 2, 0.0).sum(axis=1) / m
    ok = (m >= 2) & (var > 0)
    out = np.full((logs.shape[0], 2), np.nan)
    if not ok.any():
        return out
    logs, censored = logs[ok], censored[ok]
    beta = np.sqrt(var[ok])
    a, b = mu[ok] / beta, 1.0 / beta
    ll, g, h = _censored_terms(logs, censored, a, b)
    done = np.zeros(a.size, bool)
    for _ in range(iterations):
        step = -np.linalg.solve(h, g[:, :, None])[:, :, 0]
        step[done] = 0.0
        # near the maximum Newton's step is quadratically small: one below 1e-12 of (a, b)
        # leaves them at their rounding, taken whole and the row done
        small = np.abs(step).max(axis=1) <= 1e-12 * (np.abs(a) + np.abs(b))
        a, b = a + np.where(small, step[:, 0], 0.0), b + np.where(small, step[:, 1], 0.0)
        done |= small
        if done.all():
            break
        t = np.where(done, 0.0, 1.0)
        for _ in range(30):
            na, nb = a + t * step[:, 0], b + t * step[:, 1]
            bad = nb <= 0
            nll, ng, nh = _censored_terms(logs, censored, na, np.where(bad, b, nb))
            worse = bad | ~(nll >= ll - 1e-12 * np.abs(ll))
            if not (worse & (t > 0)).any():
                break
            t = np.where(worse, 0.5 * t, t)
        moved = t > 0
        a, b = np.where(moved, na, a), np.where(moved, nb, b)
        ll = np.where(moved, nll, ll)
        g = np.where(moved[:, None], ng, g)
        h = np.where(moved[:, None, None], nh, h)
    fits = np.column_stack([np.exp(a / b), 1.0 / b])
    fits[~done] = np.nan
    out[ok] = fits
    return out


def fit_lognormal(
    values: ArrayLike,
    bootstrap: int = BOOTSTRAP,
    confidence: float = CONFIDENCE,
    seed: int | None = 0,
    censored: ArrayLike | None = None,
) -> tuple[LognormalFit, NDArray[np.float64]]:
    """The maximum-likelihood lognormal of ``values`` and its bootstrap: ``bootstrap``
    resamples with replacement (``seed``), each refitted; returns the fit (with the
    percentile intervals at ``confidence``) and the resamples' (median, beta), (bootstrap, 2).

    ``censored`` flags the values that are lower bounds only (right-censored: a run that did
    not collapse); the fit is then :func:`censored_lognormal_mle`, and the bootstrap draws
    (value, censored) pairs together and refits each resample with the same likelihood. A
    resample with fewer than 2 distinct exact values fixes no lognormal and is left out of
    the intervals (logged)."""
    if not 0 < confidence < 1:
        raise ValueError(f"confidence = {confidence!r}: must be in (0, 1)")
    if bootstrap < 10:
        raise ValueError(f"bootstrap = {bootstrap!r}: must be at least 10 resamples")
    x, c = _censoring(values, censored)
    median, beta = censored_lognormal_mle(x, c)
    rng = np.random.default_rng(seed)
    logs = np.log(x)
    picks = rng.integers(0, x.size, size=(bootstrap, x.size))
    sample = logs[picks]
    if c.any():
        resamples = _censored_mle_rows(sample, c[picks])
        bad = ~np.all(np.isfinite(resamples), axis=1)
        if bad.any():
            log.info(
                "%d of %d bootstrap resamples fix no lognormal (fewer than 2 distinct exact "
                "values, or no convergence): left out of the intervals",
                int(bad.sum()),
                bootstrap,
            )
            resamples = resamples[~bad]
        if resamples.shape[0] < 10:
            raise ValueError(
                f"only {resamples.shape[0]} of {bootstrap} bootstrap resamples have 2 distinct "
                "exact values: too few runs collapsed for intervals"
            )
    else:
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
        censored=int(c.sum()),
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


def empirical_fragility(
    values: ArrayLike, censored: ArrayLike | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The runs' empirical P(capacity <= x) at their exact values (sorted), by the
    Kaplan-Meier product (Lawless 2003, ch. 3): the plain share of runs below x when none is
    censored; with censored runs the share would count a run still standing as failing at
    its bound, so each exact value takes the share of the runs still at risk there."""
    x = np.asarray(values, dtype=float)
    c = np.zeros(x.shape, bool) if censored is None else np.asarray(censored, dtype=bool)
    # at a tie an exact value comes first: a run censored at x is known to stand at x
    order = np.lexsort((c, x))
    x, c = x[order], c[order]
    at_risk = x.size - np.arange(x.size)
    survival = np.cumprod(np.where(c, 1.0, 1.0 - 1.0 / at_risk))
    return x[~c], 1.0 - survival[~c]


def fragility_figure(
    fit: LognormalFit,
    resamples: NDArray[np.float64],
    capacities: ArrayLike,
    title: str = "",
    censored: ArrayLike | None = None,
) -> Any:
    """The fragility curve with its band and the runs' empirical distribution (Kaplan-Meier
    when some are ``censored``, those drawn as ticks at their lower bounds); a matplotlib
    Figure (Agg)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    values = np.asarray(capacities, dtype=float)
    flags = np.zeros(values.shape, bool) if censored is None else np.asarray(censored, dtype=bool)
    # the axis spans the exact capacities and the curve: a bound at AG_MAX would squash it
    x = np.sort(values[~flags])
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
    k = int(flags.sum())
    steps_x, steps_p = empirical_fragility(values, flags)
    ax.step(
        steps_x,
        steps_p,
        where="post",
        color="#c0392b",
        lw=1,
        label=f"the {values.size} runs, {k} censored (did not collapse)"
        + (" (Kaplan-Meier)" if k else ""),
    )
    if k:
        ax.plot(
            values[flags],
            np.full(k, 0.98),
            "|",
            color="#c0392b",
            ms=8,
            label="censored: capacity above",
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
