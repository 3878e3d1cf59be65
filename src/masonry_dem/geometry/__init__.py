"""Geometry: box blocks, builders of walls and plans, selectors, contact detection."""
