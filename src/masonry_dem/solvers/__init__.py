"""Solvers: linear, static incremental, dynamic relaxation, limit analysis, 3-DOF reduction."""
