"""Assembly: the compatibility matrix H (Eqs. A1-A3), interface stiffness Kbar, K = H^T Kbar H."""
