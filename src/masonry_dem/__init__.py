"""masonry_dem: nonlinear 3D discrete element analysis of masonry walls (Baraldi & Cecchi)."""

__version__ = "0.1.0"
