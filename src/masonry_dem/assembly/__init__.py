"""Assembly: the compatibility matrix H (:mod:`.compatibility`) and the interface stiffness
Kbar with K = H^T Kbar H on the free DOFs, internal forces and reactions (:mod:`.stiffness`)."""
