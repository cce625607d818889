"""Chunked, resumable, sharded sweeps of the wheel equilibrium to disk.

Private: the public API is `snowjax.X`.
"""
