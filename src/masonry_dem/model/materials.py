"""Interface materials: the joints' stiffness and strength (kn, kt, friction, tensile
strength, cohesion, alpha) and the options of the interface law (tension, memory,
projection), each checked when made.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

from masonry_dem._validation import (
    check_choice,
    positive_scalar,
)

#: the interface law's options (one definition: the law, the settings and the schema use these)
Tension = Literal["brittle", "plastic"]
Memory = Literal["none", "slip"]


@dataclass(frozen=True)
class InterfaceMaterial:
    """Joint properties: stiffness, strength and the interface law's options.

    The interface law's behaviour beyond the strength domain is one for the whole model (the
    ``material`` of :meth:`Model.build`; see :mod:`masonry_dem.constitutive.law`).

    Parameters
    ----------
    kn, kt : float
        Normal and shear stiffness per unit area [N/m^3], each > 0.
    friction : float
        mu = tan(phi), >= 0.
    tensile_strength : float, default 0.0
        ft [Pa], >= 0: the tension cap of the Mohr-Coulomb domain, at most ``cohesion /
        friction``.
    alpha : float, optional
        Torsion-shear exponent of Eq. (A5), > 0 (None: 1.5, the paper's value for
        running-bond masonry).
    tension : {"brittle", "plastic"}, default "brittle"
        ``"brittle"``: a joint that opens loses its tensile strength for good.
    memory : {"slip", "none"}, default "slip"
        ``"slip"``: the paper's incremental law, sliding keeps its plastic slip; ``"none"``:
        holonomic.
    projection : {"energy", "radial"}, default "energy"
        The shear-torsion return: ``"energy"`` (closest point) or ``"radial"``.
    cohesion : float, optional
        c [Pa], >= 0: the shear strength at zero normal stress, ``|tau| <= c - mu sigma``
        (sigma tension positive) up to the tension cap ``sigma <= ft``. None (default):
        ``c = mu * ft``, the paper's reading of Eq. (10), whose domain closes at the cap. A
        larger c leaves the joint a shear strength ``c - mu ft`` at the cap (Lourenco's
        joint: ft = 0.16 MPa, c = 0.224 MPa, mu = 0.75). It needs ``mu * ft <= c`` (``ft <=
        c / mu``; with mu = 0 any ft). A joint that cracks (``tension="brittle"``) loses
        its cohesion with its tensile strength and becomes a dry Coulomb joint.

    Raises
    ------
    ValueError
        If a stiffness is not positive, ``friction``, ``tensile_strength`` or ``cohesion`` is
        negative (or any is not finite), ``alpha`` is not positive, ``tensile_strength``
        exceeds ``cohesion / friction``, or an option is not one of its values.

    Examples
    --------
    >>> import masonry_dem as md
    >>> md.InterfaceMaterial(kn=1e9, kt=4e8, friction=0.7).alpha is None
    True
    """

    kn: float
    kt: float
    friction: float
    tensile_strength: float = 0.0
    alpha: float | None = None
    tension: Tension = "brittle"
    memory: Memory = "slip"
    projection: str = "energy"
    cohesion: float | None = None

    def __post_init__(self) -> None:
        for name in ("kn", "kt", "friction", "tensile_strength", "alpha", "cohesion"):
            value = getattr(self, name)
            if value is not None or name not in ("alpha", "cohesion"):
                strict = name in ("kn", "kt", "alpha")
                object.__setattr__(self, name, positive_scalar(name, value, strict=strict))
        if self.cohesion is not None:
            check_tension_cap(self.friction, self.tensile_strength, self.cohesion)
        for name, allowed in LAW_OPTIONS.items():
            check_choice(name, getattr(self, name), allowed)


#: the round-off allowed on ``mu * ft <= c`` (a cap given as c / mu in decimal)
CAP_TOLERANCE = 1e-12


def check_tension_cap(friction: float, tensile_strength: float, cohesion: float) -> None:
    """Refuse a tension cap above the Mohr-Coulomb vertex: ``mu * ft <= c`` (``ft <= c /
    mu``), to a relative :data:`CAP_TOLERANCE`.

    Parameters
    ----------
    friction, tensile_strength, cohesion : float
        mu, ft [Pa] and c [Pa], each finite and >= 0.

    Raises
    ------
    ValueError
        If ``friction * tensile_strength > cohesion``, naming the three and the allowed range.
    """
    if friction * tensile_strength > cohesion * (1.0 + CAP_TOLERANCE):
        raise ValueError(
            f"tensile_strength must be at most cohesion / friction = {cohesion / friction:g} Pa "
            f"(the tension cap of the Mohr-Coulomb domain, ft <= c / mu), got tensile_strength "
            f"= {tensile_strength:g} Pa with cohesion = {cohesion:g} Pa and friction = "
            f"{friction:g}; raise the cohesion to at least {friction * tensile_strength:g} Pa "
            "or lower the tensile strength"
        )


#: ways back onto the shear-torsion boundary (see ``constitutive.strength.check_strength``)
PROJECTIONS: tuple[str, ...] = ("energy", "radial")

#: the interface law's options of :class:`InterfaceMaterial` and their allowed values
LAW_OPTIONS: dict[str, tuple[str, ...]] = {
    "tension": get_args(Tension),
    "memory": get_args(Memory),
    "projection": PROJECTIONS,
}
