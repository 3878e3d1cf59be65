"""Seismic assessment of a collapse mechanism: the kinematic analysis of NTC 2018 and its
Circolare 2019 (C8.7.1.2.1, the floor spectrum of C7.2.3), a large-displacement capacity curve, and the EN 1998-1 (N2)
format. It reads a model and a mode (the stages before it) and never the exports: the
results folder is read and written by ``export/assessment_files.py``.

* :mod:`.spectra` - the elastic spectra of NTC 2018 section 3.2 and EN 1998-1 section 3.2.2.2;
* :mod:`.kinematics` - the mechanism: alpha0, M*, e*, the capacity curve in finite rotations;
* :mod:`.checks` - the codes' checks (linear and nonlinear) and :func:`~.checks.assess`.
"""

from masonry_dem.assessment.checks import Assessment, Building, assess, assess_mode
from masonry_dem.assessment.kinematics import CapacityCurve, Mechanism, hinged_mode
from masonry_dem.assessment.sources import history_mechanism, limit_mechanism
from masonry_dem.assessment.spectra import EC8Spectrum, NTC2018Spectrum

__all__ = [
    "Assessment",
    "Building",
    "CapacityCurve",
    "EC8Spectrum",
    "Mechanism",
    "NTC2018Spectrum",
    "assess",
    "assess_mode",
    "hinged_mode",
    "history_mechanism",
    "limit_mechanism",
]
