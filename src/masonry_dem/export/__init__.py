"""Export: the results folder (:mod:`.results_folder`: layout, lock, atomic writes) and what
writes into it (:mod:`.writer`, :mod:`.vtu`, :mod:`.pvd`, :mod:`.limit_results`), one case run
into it (:mod:`.run_case`), renders (:mod:`.render`, :mod:`.scene`, :mod:`.annotations`), the
pushover plot (:mod:`.plots`) and ParaView states (:mod:`.paraview_state`)."""
