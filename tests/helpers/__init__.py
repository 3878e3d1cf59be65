"""What several test modules share, imported as ``helpers.<module>`` (``pytest`` puts
``tests/`` on the path: ``pythonpath`` in pyproject.toml), so that no test module imports
from a sibling test module.

* :mod:`.walls` - the one-block and small walls on a rigid base of the solver tests;
* :mod:`.case_files` - a case file written from a dict, and the one-block case;
* :mod:`.paper_runs` - each validation case run once per session;
* :mod:`.mechanism_checks` - what a collapse mode must look like;
* :mod:`.certificate_checks` - an independent re-check of a collapse certificate;
* :mod:`.damage_pattern` - results folders with a known damage pattern (export tests);
* :mod:`.numpy_reference` - the interface law in plain numpy (kernel tests).
"""
