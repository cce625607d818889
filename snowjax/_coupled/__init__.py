"""Models that couple the thesis's two halves: the chapter-3 tyre shear forces on the
chapter-4 wheel–snow equilibrium.

Private: the public API is `snowjax.X`.
"""
