"""Empirical wheel and vehicle models of chapter 2 and the CRREL shallow-snow model.

Private: the public API is `snowjax.X`.
"""
