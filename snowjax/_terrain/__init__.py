"""Terrain laws: the abstract Terrain, one file per pressure–sinkage law family, shear laws.

Private: the public API is `snowjax.X`.
"""
