"""The joint states: ONE definition, used by the interface law, the export and the renderer.

A joint's strength check sets bit flags (:class:`JointFlag`), one per violated criterion of
Section 2.1; its damage state (:class:`JointState`, the ``state`` field of the VTU files and the
colour of the renders) and its stiffness factors of Eqs. (13)-(14) follow from the flags by the
tables :data:`STATE_OF_FLAGS` and :data:`FACTORS_OF_FLAGS`.
"""

from __future__ import annotations

from enum import IntEnum, IntFlag
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "FACTORS_OF_FLAGS",
    "FLAG_DETACHED",
    "FLAG_ROCKING_1",
    "FLAG_ROCKING_2",
    "FLAG_SHEAR_TORSION",
    "SLIDE_COLUMNS",
    "STATE_DETACHED",
    "STATE_ELASTIC",
    "STATE_NAMES",
    "STATE_OF_FLAGS",
    "STATE_ROCKING",
    "STATE_SLIDING",
    "STATE_SLIDING_ROCKING",
    "JointFlag",
    "JointState",
    "stiffness_factors_of_flags",
]


class JointState(IntEnum):
    """Damage state of a joint (the ``state`` cell field of the VTU files)."""

    ELASTIC = 0
    SLIDING = 1  # shear and/or torsion
    ROCKING = 2  # bending about y1 and/or y2
    SLIDING_ROCKING = 3
    DETACHED = 4  # fn > ft

    @property
    def label(self) -> str:
        """The name the exports and legends show ("sliding+rocking", ...)."""
        return STATE_NAMES[self]


class JointFlag(IntFlag):
    """Violated criteria of a joint's strength check (the ``flags`` cell field)."""

    SHEAR_TORSION = 1  # Eq. (A5)
    ROCKING_1 = 2  # bending about y1
    ROCKING_2 = 4  # bending about y2
    DETACHED = 8  # a detached joint carries only this flag


#: :class:`JointState` names, index = code
STATE_NAMES: Final[tuple[str, ...]] = (
    "elastic",
    "sliding",
    "rocking",
    "sliding+rocking",
    "detached",
)

# plain ints for the compiled kernels and the array arithmetic
STATE_ELASTIC: Final[int] = int(JointState.ELASTIC)
STATE_SLIDING: Final[int] = int(JointState.SLIDING)
STATE_ROCKING: Final[int] = int(JointState.ROCKING)
STATE_SLIDING_ROCKING: Final[int] = int(JointState.SLIDING_ROCKING)
STATE_DETACHED: Final[int] = int(JointState.DETACHED)
FLAG_SHEAR_TORSION: Final[int] = int(JointFlag.SHEAR_TORSION)
FLAG_ROCKING_1: Final[int] = int(JointFlag.ROCKING_1)
FLAG_ROCKING_2: Final[int] = int(JointFlag.ROCKING_2)
FLAG_DETACHED: Final[int] = int(JointFlag.DETACHED)

#: f1, f2, m3: the components that sliding scales (and that keep plastic slip)
SLIDE_COLUMNS: Final = np.array([0, 1, 5])


def _flag_tables() -> tuple[NDArray[np.int8], NDArray[np.float64]]:
    """State code and stiffness factors of every combination of the bit flags."""
    flags = np.arange(16)
    sliding = (flags & FLAG_SHEAR_TORSION) > 0
    rock1 = (flags & FLAG_ROCKING_1) > 0
    rock2 = (flags & FLAG_ROCKING_2) > 0
    detached = (flags & FLAG_DETACHED) > 0
    state = sliding * STATE_SLIDING + (rock1 | rock2) * STATE_ROCKING
    state[detached] = STATE_DETACHED
    factors = np.ones((16, 6))
    factors[np.ix_(sliding, SLIDE_COLUMNS)] = 0.0
    factors[rock1, 3] = 0.0
    factors[rock2, 4] = 0.0
    factors[detached] = 0.0
    return state.astype(np.int8), factors


#: (16,) int8 state code and (16, 6) stiffness factors of Eqs. (13)-(14), index = flags
STATE_OF_FLAGS, FACTORS_OF_FLAGS = _flag_tables()


def stiffness_factors_of_flags(flags: ArrayLike) -> NDArray[np.float64]:
    """(m, 6) stiffness factors of Eqs. (13)-(14) (0 or 1) for the bit flags of m interfaces."""
    return FACTORS_OF_FLAGS[np.asarray(flags, dtype=np.int64)]
