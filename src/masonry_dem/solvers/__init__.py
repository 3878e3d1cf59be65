"""Solvers: linear (:mod:`.linear`), static incremental (:mod:`.static`, entry points in
:mod:`.incremental`), dynamic relaxation (:mod:`.dynamic_relaxation`), limit analysis
(:mod:`.limit_analysis`), the in-plane reduction (:mod:`.reduction`), the sparse
factorizations (:mod:`.factorization`) and the memory estimate of a run (:mod:`.resources`)."""
