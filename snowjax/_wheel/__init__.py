"""The rigid wheel: geometry, stress distributions, contact quadrature, equilibrium (chapter 4).

Private: the public API is `snowjax.X`.
"""
