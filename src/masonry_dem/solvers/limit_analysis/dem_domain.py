"""Which limit-analysis domain contains the DEM's: the friction enlargement kappa(alpha) that
makes the associative multiplier a theorem-backed upper bound of the pushover's.

Radenkovic's theorem bounds the non-associative (DEM) multiplier by the associative one when
the DEM's strength domain lies inside the LA's. The LA's joint (four corners, exact cone, or
any grid: the corners are exact, ``interface``) carries anything a pressure distribution on
the rectangle with the local cone ``|t| <= mu p`` carries. The DEM reads a rocking joint as a
uniform compression N on the reduced rectangle centred on the resultant, with the
shear-torsion interaction of Eq. (A5), ``(m3 / (cT mu N))^alpha + (f / (mu N))^2 <= 1``.

The worst joint is the one rocking on an edge (the reduced rectangle a line of length l),
shearing across it. Its LA capacity is that of the two end points, N/2 each, with friction
``kappa mu``: their forces across the line add to the shear, ``t_a + t_b = s mu N``, and
``|t_a|, |t_b| <= kappa mu N / 2``, so the torsion ``(l/2)(t_a - t_b)`` is at most
``(l/2)(kappa - s) mu N``, i.e. ``tau = 2 (kappa - s)`` in units of the line's
``cT mu N = (l/4) mu N``. The DEM allows ``tau = (1 - s^2)^(1/alpha)``. So the LA with friction
``kappa mu`` contains the DEM's line joint if and only if

    kappa >= kappa(alpha) = max over s in [0, 1] of  s + (1 - s^2)^(1/alpha) / 2,

which is 1 for alpha = 1 (the linear interaction: the plain LA is a bound), 1.0655 for the
package's default alpha = 1.5, sqrt(5)/2 = 1.118 for alpha = 2 and 1.161 for Table A1's
largest 2.56. Rectangles of aspect 0.1 to 1 and other shear directions need less (a bisection
on the corner SOCP over aspects 0, 0.1, 0.25, 0.5, 1 and shear angles 0-90 degrees:
the line across its length is the maximum; ``tests/solvers/test_limit_analysis.py`` checks
both the containment at kappa(alpha) and its failure just below). The tensile strength
enters both laws through ``N = ft - fn`` alike, so kappa covers it.
"""

from __future__ import annotations

import numpy as np

from masonry_dem.constitutive import DEFAULT_ALPHA
from masonry_dem.model import Model


def dem_friction_scale(alpha: float | np.ndarray) -> float:
    """kappa(alpha): the smallest factor on the LA's friction whose domain contains the DEM's
    for every joint (module docstring); the largest over ``alpha`` when it is an array."""
    a = np.atleast_1d(np.asarray(alpha, dtype=float))
    # one value per distinct alpha: a model passes one per interface, and 20 001 powers of
    # each took 14 s of the 10^4-block ladder wall's limit analysis
    a = np.unique(a)
    if a.size == 0:
        return 1.0
    if not np.all(np.isfinite(a)) or np.any(a < 1.0):
        raise ValueError(f"alpha must be finite and >= 1 (a convex domain), got {alpha!r}")
    s = np.linspace(0.0, 1.0, 20001)
    # the maximum over s of a smooth concave function: the grid is within 1e-8 of it
    values = s[None, :] + 0.5 * (1.0 - s[None, :] ** 2) ** (1.0 / a[:, None])
    return float(max(values.max(), 1.0))


def model_friction_scale(model: Model) -> float:
    """kappa of the model's largest alpha (nan in the model: the package's ``DEFAULT_ALPHA``)."""
    alpha = np.where(np.isnan(model.alpha), DEFAULT_ALPHA, model.alpha)
    return dem_friction_scale(alpha)
