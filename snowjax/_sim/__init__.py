"""Longitudinal vehicle simulation on snow.

Private: the public API is `snowjax.X`.
"""
