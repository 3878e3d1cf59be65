"""Studies: many analyses of one scene (parameter sweeps, speed against accuracy, ...)."""
