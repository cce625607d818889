"""`snowjax reproduce`: the thesis's figures and tables.

Private: the public API is `snowjax.X`.
"""
