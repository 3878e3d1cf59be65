"""Studies: library functions that run the package's solvers on sets of models and return
JSON-ready rows (the command line only parses arguments and prints them).

* :mod:`.runs` - the three methods (:class:`~.runs.Method`: static, dynamic relaxation, limit
  analysis) run and timed the same way, the study cases, the warm-up of the compiled law;
* :mod:`.speed_accuracy` - every setting of every method on validation cases: time against
  error in lambda, the Pareto front, the time ratio at equal accuracy; :mod:`.chart` draws it;
* :mod:`.size_ladder` - the methods on walls of 10^2 to 10^4 blocks;
* :mod:`.reduction` - the 3-DOF in-plane model against the 6-DOF model;
* :mod:`.kn_sweep` - lambda as the dry-joint stiffness grows;
* :mod:`.validation` - the paper's validation cases (Tables 1-3) against the paper and the tests;
* :mod:`.interface` - the closed-form interface strength against the spring model (Table A1);
* :mod:`.sweep` - one case over grids, lists and seeded samples of its case-file values, on Dask;
  :mod:`.sweep_plan` reads the values, :mod:`.sweep_point` runs one, :mod:`.sweep_table` and
  :mod:`.sweep_plots` write the rows and draw them.

Submodules are imported on use, not here, so that ``import masonry_dem.studies`` is cheap.
"""
