"""The tyre shear-force model of chapter 3.

Private: the public API is `snowjax.X`.
"""
