"""Calibration: least-squares fits of plate, wheel and tyre models.

Private: the public API is `snowjax.X`.
"""
