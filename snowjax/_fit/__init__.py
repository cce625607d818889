"""Calibration: least-squares fits of plate, wheel and tyre models.

`core` is the one least-squares machinery (solver, `FitResult`, standard errors and
identifiability diagnostics); `plate`, `tire` and `wheel` are the models on it, `data` the
shipped tables and input checks.  Private: the public API is `snowjax.X`.
"""
