"""Validation of the models against measured snow data.

Private: the public API is `snowjax.X`.
"""
