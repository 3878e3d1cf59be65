"""Interface constitutive law, one module per role.

* :mod:`~masonry_dem.constitutive.states` - the joint states and flags (one definition for the
  law, the export and the renderer);
* :mod:`~masonry_dem.constitutive.strength` - the closed-form strength domain of Section 2.1
  (numpy API: strengths, torsion constant, the batched check);
* :mod:`~masonry_dem.constitutive.check_kernels`, :mod:`~masonry_dem.constitutive.law_kernels`
  - the compiled (numba) kernels of the check and of the law;
* :mod:`~masonry_dem.constitutive.law` - :class:`InterfaceLaw`, the elastic-perfectly-plastic
  law of the solvers;
* :mod:`~masonry_dem.constitutive.springs` - the spring (fibre) model the closed forms are
  checked against.
"""

from masonry_dem.constitutive.springs import (
    REFERENCE_INTERFACE,
    ReferenceInterface,
    SpringInterface,
    SpringResponse,
    fit_alpha,
    shear_strength_numeric,
    torsion_shear_domain,
    torsion_strength_numeric,
)
from masonry_dem.constitutive.states import (
    FLAG_DETACHED,
    FLAG_ROCKING_1,
    FLAG_ROCKING_2,
    FLAG_SHEAR_TORSION,
    STATE_DETACHED,
    STATE_ELASTIC,
    STATE_NAMES,
    STATE_ROCKING,
    STATE_SLIDING,
    STATE_SLIDING_ROCKING,
    JointFlag,
    JointState,
)
from masonry_dem.constitutive.strength import (
    ALPHA_TABLE_A1,
    DEFAULT_ALPHA,
    StrengthCheck,
    alpha_from_table,
    check_strength,
    shear_strength,
    torsion_constant,
    torsion_strength,
)

__all__ = [
    "ALPHA_TABLE_A1",
    "DEFAULT_ALPHA",
    "FLAG_DETACHED",
    "FLAG_ROCKING_1",
    "FLAG_ROCKING_2",
    "FLAG_SHEAR_TORSION",
    "REFERENCE_INTERFACE",
    "STATE_DETACHED",
    "STATE_ELASTIC",
    "STATE_NAMES",
    "STATE_ROCKING",
    "STATE_SLIDING",
    "STATE_SLIDING_ROCKING",
    "JointFlag",
    "JointState",
    "ReferenceInterface",
    "SpringInterface",
    "SpringResponse",
    "StrengthCheck",
    "alpha_from_table",
    "check_strength",
    "fit_alpha",
    "shear_strength",
    "shear_strength_numeric",
    "torsion_constant",
    "torsion_shear_domain",
    "torsion_strength",
    "torsion_strength_numeric",
]
